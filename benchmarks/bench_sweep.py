"""Cage-angle sweep benchmark: bearingsim.sweep (all angles as one batched Newton, warm started
from the first angle) vs a warm-started loop of the plain scipy reference over the same angles.

Harris 218 at 10 000 rpm, Fa = 10 kN + Fr = 3 kN, rectangular spall (centre 0, 6 deg, 0.3 mm),
360 cage angles over one ball pitch; and the demo case (cases/demo.toml: 3 deg spall, 3 kN radial).
Target (issue 8): <= 100 ms for the demo case's 360-angle sweep after compile.  Usage: python benchmarks/bench_sweep.py [--n-ref 24]
"""
from __future__ import annotations

import argparse
import importlib.util
import pathlib
import sys
import time

import numpy as np

_HERE = pathlib.Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("reference_scipy", _HERE / "reference_scipy.py")
ref = importlib.util.module_from_spec(_spec)
sys.modules.setdefault("reference_scipy", ref)
_spec.loader.exec_module(ref)

import jax  # noqa: E402

import bearingsim as bs  # noqa: E402
from bearingsim.physics.sweep import sweep  # noqa: E402

DEG = np.pi / 180


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n-ref", type=int, default=24, help="scipy-loop angles timed (scaled to 360)")
    args = ap.parse_args()
    b = bs.Bearing(16, 22.225e-3, 125.26e-3, 0.5232, 0.5232, 40 * DEG)
    geom = ref.Geometry(Z=16, D=22.225e-3, dm=125.26e-3, fi=0.5232, fo=0.5232, alpha0=40 * DEG)
    op = bs.Operation.from_rpm(10000.0)
    loads = np.array([3000.0, 0.0, 10000.0, 0.0, 0.0])
    sp = bs.Spall(0.0, 6 * DEG, 0.3e-3, "rectangular")
    spd = dict(center=0.0, extent=6 * DEG, depth=0.3e-3, profile="rectangular")
    angles = np.linspace(-np.pi / 16, np.pi / 16, 360)

    rows = []
    demo = bs.Spall(0.0, 3 * DEG, 0.3e-3, "rectangular")
    demo_angles = np.linspace(-11.25 * DEG, 11.25 * DEG, 360)
    for name, spall, ang in (("6 deg spall", sp, angles), ("demo case", demo, demo_angles)):
        t = time.perf_counter()
        s = sweep(b, op, loads, spall, angles=ang)
        jax.block_until_ready(s.result)
        compile_s = time.perf_counter() - t
        ts = []
        for _ in range(5):
            t = time.perf_counter()
            s = sweep(b, op, loads, spall, angles=ang)
            jax.block_until_ready(s.result)
            ts.append(time.perf_counter() - t)
        rows.append((name, compile_s, min(ts), int(np.sum(np.asarray(s.result) != 0))))
        if spall is sp:
            sol = s

    sub = angles[: args.n_ref]
    t = time.perf_counter()
    r = ref.solve_sweep(geom, loads, sub, speed_rpm=10000.0, spall=spd)
    t_ref = (time.perf_counter() - t) / len(sub) * 360
    ok = np.all([x["converged"] for x in r]) if isinstance(r, list) else True
    # agreement on the timed angles
    Qo_ref = np.array([x["Q_o"] for x in r]) if isinstance(r, list) else np.asarray(r["Q_o"])
    dQ = np.max(np.abs(Qo_ref - np.asarray(sol.Q_outer)[: len(sub)])) / np.max(Qo_ref)

    print(f"{'':24}{'1st call s':>11}{'360 angles s':>14}{'per angle ms':>14}{'failed':>8}")
    for m, c, w, f in rows:
        print(f"bearingsim {m:<13}{c:11.1f}{w:14.3f}{w / 360 * 1e3:14.3f}{f:8d}")
    print(f"scipy loop (warm){'':7}{'':11}{t_ref:14.3f}{t_ref / 360 * 1e3:14.3f}   (from {len(sub)} angles, converged={ok})")
    w6, wd = rows[0][2], rows[1][2]
    print(f"\nspeed-up over the scipy loop (6 deg spall): {t_ref / w6:.0f}x; demo case 360 angles in "
          f"{wd * 1e3:.0f} ms (target <= 100 ms: {'met' if wd <= 0.1 else 'NOT met'})")
    print(f"max |Q_o| difference to the reference on the timed angles: {dQ:.2e} of max Q_o")


if __name__ == "__main__":
    main()
