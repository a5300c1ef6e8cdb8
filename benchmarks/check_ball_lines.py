"""Ball-fault lines, simulated against the CWRU ball records, line by line (issue 33, item 4).

    .venv/bin/python benchmarks/check_ball_lines.py [--count 12] [--duration-s 1.0] [--seed 0]
        [--spec dataset_cwru_4class] [--realdata ../shared/realdata] [--modes gate,kinematic]

Simulates ``--count`` ball items of ``--duration-s`` of the shipped CWRU four-class spec (the
CWRU rig's 12 kHz and its 1730-1797 rpm, the records' motor loads 0-3 hp; every other range of the
spec unchanged, every issue-26 ingredient on) once per ``[dataset] ball_exposure`` of
``--modes`` (``gate``: the drawn strikes and gate; ``kinematic``: the pit's exposure from the ball
kinematics, bearingsim.dynamics.exposure), the same seed, and reads the drive-end records 118-121
(0.007 in, 0-3 hp) and 222-223 (0.021 in, 0-1 hp) of ``../shared/realdata`` with their Smith &
Randall grades (:data:`bearingsim.realism.transfer.DEV_RECORDS`), and the normal record 97 as the
floor every line has without a fault.

Every signal is cut into windows of ``--duration-s`` (a record: its whole windows; an item: one),
and of every window the squared envelope in the three fixed bands of the plain features
(:data:`bearingsim.signals.plain_features.PLAIN_BANDS_HZ`: 1-2.5, 2.5-4, 4-5.4 kHz; Butterworth
order 4, zero phase, Hilbert, Hann, zero padded 4x) gives each line's strength in dB over the
local median (the largest bin within f0 +- max(1.5 %, half a bin of the window) over the median
between 0.5 f0 and 1.5 f0), the strongest of the three bands.  Lines: 2 BSF, 4 BSF, 2 BSF -+ FTF,
FTF, 1-3 x shaft, at the bearing's fault orders (free contact angle) times the shaft speed (a
record's nominal rpm, an item's label).  The table prints each record's and each mode's median
over its windows (items), and their spread (interquartile range) in brackets.  No score and no
classifier: what the lines of a simulated ball look like next to the real ones.  Nothing here is
fitted to a record.  A row of white Gaussian noise windows shows what the procedure reads without
any line (the max of a window's bins over the median, the strongest of three bands).  Last, the
kinematic exposure itself: 1000 draws of the default ranges at the spec's nominal point.
"""
from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.signal as ss

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from bearingsim.app.workflows import solve_case  # noqa: E402
from bearingsim.case import load_case  # noqa: E402
from bearingsim.dynamics.exposure import ball_track, draw_exposure, pass_exposure  # noqa: E402
from bearingsim.datasets import make_dataset  # noqa: E402
from bearingsim.datasets.mldata import load_dataset  # noqa: E402
from bearingsim.realism.records import read_record  # noqa: E402
from bearingsim.realism.transfer import DEV_RECORDS  # noqa: E402
from bearingsim.signals.features import fault_orders  # noqa: E402
from bearingsim.signals.nuisance import INGREDIENTS  # noqa: E402
from bearingsim.signals.plain_features import PLAIN_BANDS_HZ  # noqa: E402

#: the ball records compared (12 kHz drive end) and the normal record (the floor)
BALL_RECORDS = ("cwru_B007_0hp_12k", "cwru_B007_1hp_12k", "cwru_B007_2hp_12k", "cwru_B007_3hp_12k",
                "cwru_B021_0hp_12k", "cwru_B021_1hp_12k")
NORMAL = "cwru_normal_0hp_12k_decimated"
LINES = ("2BSF", "4BSF", "2BSF-FTF", "2BSF+FTF", "FTF", "1x", "2x", "3x")
_REL, _LOCAL = 0.015, 0.5


def line_orders(o):
    """The :data:`LINES` as multiples of the shaft frequency (``o``: fault orders)."""
    return np.array([o.two_bsf, 2 * o.two_bsf, o.two_bsf - o.ftf, o.two_bsf + o.ftf, o.ftf, 1.0, 2.0, 3.0])


def line_db(x, fs, shaft_hz, orders) -> np.ndarray:
    """(len(LINES),) strength of each line in dB over its local median, the strongest band."""
    x = np.asarray(x, float)
    x = (x - x.mean()) / max(x.std(), 1e-300)
    T = x.size
    nfft = 1 << (int(np.ceil(np.log2(T))) + 2)
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    best = np.full(len(LINES), -np.inf)
    for lo, hi in PLAIN_BANDS_HZ:
        y = ss.sosfiltfilt(ss.butter(4, [lo, hi], btype="bandpass", fs=fs, output="sos"), x)
        e2 = np.abs(ss.hilbert(y)) ** 2
        S = np.abs(np.fft.rfft((e2 - e2.mean()) * np.hanning(T), nfft))
        for i, k in enumerate(line_orders(orders)):
            f0 = k * shaft_hz
            half = max(_REL * f0, 0.5 * fs / T)
            pk = S[(f >= f0 - half) & (f <= f0 + half)]
            fl = S[(f >= (1 - _LOCAL) * f0) & (f <= (1 + _LOCAL) * f0)]
            peak, floor = (pk.max() if pk.size else 0.0), (np.median(fl) if fl.size else 0.0)
            v = 20 * np.log10(max(peak, 1e-300) / max(floor, 1e-300))
            best[i] = max(best[i], v)
    return best


def record_lines(path, window_s, orders):
    x, fs, _, rpm, _ = read_record(path, default_unit="g")
    n = int(round(window_s * fs))
    wins = [x[i:i + n] for i in range(0, x.size - n + 1, n)]
    return np.array([line_db(w, fs, rpm / 60.0, orders) for w in wins]), rpm


def ball_only(spec, folder):
    """``spec`` with every item a ball item (the class fractions change together: one file)."""
    text = re.sub(r"(?m)^(healthy|outer|inner)_fraction\s*=.*$", r"\1_fraction = 0.0", spec.text)
    text = re.sub(r"(?m)^ball_fraction\s*=.*$", "ball_fraction = 1.0", text)
    p = Path(folder) / "ball_only.toml"
    p.write_text(text)
    return load_case(p)


def simulated_lines(spec, mode, count, duration_s, seed, orders, folder):
    case = (ball_only(spec, folder).with_value("dynamics.sample_rate_Hz", 12000.0)
            .with_value("dataset.speed_rpm", [1730.0, 1797.0]).with_value("operation.speed_rpm", 1763.5)
            .with_value("dataset.duration_s", float(duration_s)).with_value("dataset.count", int(count))
            .with_value("dataset.seed", int(seed)).with_value("dataset.realism_ingredients", list(INGREDIENTS))
            .with_value("dataset.ball_exposure", mode))
    path = Path(folder) / f"ball_{mode}.h5"
    t0 = time.perf_counter()
    make_dataset(case, path, progress=False)
    took = time.perf_counter() - t0
    X, lab, meta = load_dataset(path)
    fs = float(meta["sample_rate_Hz"])
    rows = np.array([line_db(X[i], fs, lab["speed_rpm"][i] / 60.0, orders) for i in range(len(X))])
    return rows, took


def noise_lines(n, fs, shaft_hz, duration_s, orders, seed):
    """The lines of ``n`` windows of white Gaussian noise: what the procedure reads with no line."""
    rng = np.random.default_rng(seed)
    T = int(round(duration_s * fs))
    return np.array([line_db(rng.standard_normal(T), fs, shaft_hz, orders) for _ in range(n)])


def exposure_stats(case, n, duration_s, seed):
    """Quartiles of the kinematic exposure of ``n`` ball items of the spec's default ranges at
    its nominal operating point (its quasi-static state; pit diameters of the spec's
    ``ball_length_mm``): the mean exposure over an item's passes, the pass-to-pass coefficient
    of variation, and the fraction of items whose mean exposure is below 0.1 (no ball signal)."""
    sol = solve_case(case)
    track = np.asarray(ball_track(case.bearing(), sol, 0.0))
    R = track[5]
    ds = case.data["dataset"]
    ranges = dict(pit_latitude=tuple(np.radians(ds["ball_pit_latitude_deg"])),
                  wander_sd=tuple(np.radians(ds["ball_axis_wander_deg"])),
                  wander_correlation=tuple(ds["ball_axis_correlation_cage_rev"]))
    fr = float(case.data["operation"]["speed_rpm"]) / 60.0
    o = fault_orders(case.bearing())
    two_bsf, ftf = o.two_bsf * fr, o.ftf * fr
    tp = jnp.asarray(np.arange(int(two_bsf * duration_s)) / two_bsf)
    rng = np.random.default_rng(seed)
    lo, hi = (float(v) * 1e-3 / 2 for v in ds["ball_length_mm"])

    def one(key, spin0, pit_r):
        kd, kw = jax.random.split(key)
        lat, sd, corr = draw_exposure(kd, ranges)
        t = jnp.asarray(track).at[6].set(pit_r)
        return pass_exposure(kw, tp, ftf, spin0, t, lat, sd, corr)

    keys = jax.random.split(jax.random.PRNGKey(seed), n)
    E = np.asarray(jax.vmap(one)(keys, jnp.asarray(rng.uniform(0, 2 * np.pi, n)), jnp.asarray(rng.uniform(lo, hi, n))))
    m = E.mean(1)
    cv = E.std(1) / np.where(m > 0, m, np.inf)
    return dict(alpha_deg=np.degrees(track[1]), beta_deg=np.degrees(track[0]), a_mm=1e3 * track[3], R_mm=1e3 * R,
                mean=np.percentile(m, [25, 50, 75]), cv=np.percentile(cv, [25, 50, 75]), off=float(np.mean(m < 0.1)))


def _cell(v):
    q1, m, q3 = np.percentile(v, [25, 50, 75])
    return f"{m:5.1f} [{q1:4.1f},{q3:4.1f}]"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=12)
    ap.add_argument("--duration-s", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--spec", default="dataset_cwru_4class")
    ap.add_argument("--realdata", default=str(ROOT.parent / "shared" / "realdata"))
    ap.add_argument("--modes", default="gate,kinematic")
    a = ap.parse_args(argv)
    spec = load_case(a.spec)
    orders = fault_orders(spec.bearing())
    rows = []
    real = Path(a.realdata)
    for stem in (NORMAL,) + BALL_RECORDS:
        p = real / f"{stem}.npz"
        if not p.exists():
            print(f"({p} missing: skipped)")
            continue
        v, rpm = record_lines(p, a.duration_s, orders)
        cls, grade, no = DEV_RECORDS.get(stem, ("healthy", "-", 97))
        rows.append((f"{no} {cls} {rpm:.0f} rpm, S&R {grade}", v))
    rows.append(("white noise (60 windows)", noise_lines(60, 12000.0, 1763.5 / 60.0, a.duration_s, orders,
                                                               a.seed)))
    with tempfile.TemporaryDirectory() as tmp:
        for mode in [m for m in a.modes.split(",") if m]:
            v, took = simulated_lines(spec, mode, a.count, a.duration_s, a.seed, orders, tmp)
            rows.append((f"sim ball, ball_exposure={mode} ({len(v)} items, {took:.0f} s)", v))
    print(f"Ball-fault lines: dB over the local median, the strongest of the bands {PLAIN_BANDS_HZ} Hz; "
          f"median [IQR] over {a.duration_s:g} s windows (records) or items (simulated)")
    w = max(len(r[0]) for r in rows)
    print(" " * w + " | " + " | ".join(f"{n:^17}" for n in LINES))
    for name, v in rows:
        print(f"{name:<{w}} | " + " | ".join(_cell(v[:, j]) for j in range(len(LINES))))
    st = exposure_stats(spec, 1000, a.duration_s, a.seed)
    print(f"\nKinematic exposure of 1000 ball items of the default ranges at the spec's nominal point (alpha "
          f"{st['alpha_deg']:.2f} deg, beta {st['beta_deg']:.2f} deg, a {st['a_mm']:.3f} mm, R {st['R_mm']:.3f} mm), "
          f"{a.duration_s:g} s: mean exposure over the passes (quartiles) {np.round(st['mean'], 3).tolist()}, "
          f"pass-to-pass c.v. {np.round(st['cv'], 3).tolist()}, items with mean exposure < 0.1: {st['off']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
