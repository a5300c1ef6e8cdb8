"""Where the real healthy windows fall among the simulated healthy items (issue 33): no classifier.

    .venv/bin/python benchmarks/check_healthy_windows.py [--rig hit|cwru] [--windows 1,0.2]
        [--count 300] [--seed 0] [--realdata ../shared/realdata] [--spec dataset_cwru_4class]

For each window length: ``--count`` items of the rig's training spec
(:func:`bearingsim.realism.transfer.rig_spec` of the shipped four-class spec, items as long as the
window, data set seed ``--seed``) and the rig's real records
(:data:`bearingsim.realism.transfer.RIGS`, resampled to the rig's rate), both through the plain
features (:func:`bearingsim.signals.plain_features.plain_features`).  Per feature: the simulated
healthy items' 5th / 50th / 95th percentiles, the simulated outer and inner medians, the real
healthy windows' median (min..max) and the median percentile of a real healthy window among the
simulated healthy items, and the real outer and inner medians.  A real healthy window at the
100th percentile of a feature that is a fault class's hallmark is what a classifier trained on the
simulation will call faulty (docs/realism.md, "Why the healthy records are called faulty at 1 s").
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bearingsim.case import load_case  # noqa: E402
from bearingsim.datasets.runner import make_dataset  # noqa: E402
from bearingsim.realism import transfer as tr  # noqa: E402
from bearingsim.signals.features import fault_orders  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rig", default="hit", choices=sorted(tr.RIGS))
    ap.add_argument("--windows", default="1,0.2")
    ap.add_argument("--count", type=int, default=300)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--realdata", default=str(ROOT.parent / "shared" / "realdata"))
    ap.add_argument("--spec", default="dataset_cwru_4class")
    ap.add_argument("--ingredients", default=None, help="comma list: the spec's realism_ingredients instead of its own")
    a = ap.parse_args(argv)
    rig = tr.RIGS[a.rig]
    data_dir = tr.rig_data_dir(a.realdata, rig)
    if data_dir is None:
        print(f"skipped: the {a.rig} records are not under {a.realdata}")
        return 0
    spec = load_case(a.spec)
    orders = fault_orders(spec.bearing())
    with tempfile.TemporaryDirectory() as tmp:
        for win in (float(w) for w in a.windows.split(",")):
            path = Path(tmp) / f"{a.rig}_{win:g}.h5"
            rs = tr.rig_spec(spec, rig, win, a.count, a.seed)
            if a.ingredients is not None:
                rs = rs.with_value("dataset.realism_ingredients", [k for k in a.ingredients.split(",") if k])
            make_dataset(rs, path, progress=False)
            sim = tr.simulated_windows(path, orders, win, "plain")
            real = tr.real_windows(data_dir, orders, win, rig.records, features="plain",
                                   sample_rate_Hz=rig.sample_rate_Hz)
            H, O, I = (sim.features[sim.label == c] for c in (0, 1, 2))
            R, RO, RI = (real.features[real.label == c] for c in (0, 1, 2))
            print(f"{a.rig}, {win:g} s windows: {len(H)} simulated healthy items, {len(R)} real healthy windows "
                  f"({', '.join(sorted(set(real.group[real.label == 0])))})")
            print(f"{'feature':24s} {'sim healthy p5/p50/p95':>24s} {'sim O':>6s} {'sim I':>6s} | "
                  f"{'real healthy p50 (min..max)':>28s} {'pct':>5s} | {'real O':>6s} {'real I':>6s}")
            for j, n in enumerate(sim.feature_names):
                p5, p50, p95 = np.percentile(H[:, j], [5, 50, 95])
                pct = np.median(np.mean(H[:, j][None, :] <= R[:, j][:, None], axis=1)) * 100
                print(f"{n:24s} {p5:7.2f} {p50:7.2f} {p95:7.2f} {np.median(O[:, j]):6.2f} {np.median(I[:, j]):6.2f} | "
                      f"{np.median(R[:, j]):9.2f} ({R[:, j].min():7.2f}..{R[:, j].max():7.2f}) {pct:4.0f}% | "
                      f"{np.median(RO[:, j]):6.2f} {np.median(RI[:, j]):6.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
