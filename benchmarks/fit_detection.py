"""Fit and check the constants of bearingsim.realism.detection (issue 34: `bearingsim spectrum`
verdicts with a measured false-alarm rate).  Healthy data only; never a fault record.

    .venv/bin/python benchmarks/fit_detection.py [--realdata ../shared/realdata] [--simulated H5]

1. The null model: white Gaussian noise records (12 kHz, 1 / 2 / 5 / 10 s), analysed as the command
   analyses a record (demodulation band from 4 x the highest fault line, envelope spectrum, the line
   statistic at pseudo-lines): NULL_BINS_PER_TRIAL is the value that makes the exceedance of the
   null quantile equal FALSE_ALARM over all of them (bisection); the rate per length is printed.
2. The healthy margin: healthy records cut into segments of 1 s, 2 s and the whole record (the
   lengths the command meets), the shaft found as the command finds it, pseudo-lines at
   non-integer orders 0.3-6.5 x the shaft (a geometric grid of ratio 1.04: the windows do not
   overlap), windows clear of shaft harmonics and inside the band's width; the excess of each
   line over the null quantile; HEALTHY_MARGIN_DB is the largest over the sources of the
   (1 - FALSE_ALARM) quantile of that excess, so each source keeps the rate.  Sources: CWRU 97
   (normal, DE, 48 kHz and its 12 kHz decimated copy), HIT-MFS normal 600 / 900 / 1200 rpm, and the
   simulated healthy items of cases/dataset_cwru_4class.toml (made with `bearingsim dataset` of a
   copy of that spec with healthy_fraction = 1.0 and the outer / inner / ball fractions 0.0,
   --count 8 --seed 7 --duration-s 2 --sample-rate-Hz 12000: 536 s on a loaded 2-core machine).
Prints the constants to paste into bearingsim/realism/detection.py and the rates measured.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from bearingsim.realism import detection as det
from bearingsim.realism.background_fit import shaft_speed
from bearingsim.realism.record_spectrum import demodulation_band
from bearingsim.signals.envelope import envelope_spectrum

#: the 6205's highest fault line (BPFI + f_r) in orders of the shaft: sets the band search
TOP_ORDER = 6.415
ORDERS = 0.3 * 1.04 ** np.arange(200)
ORDERS = ORDERS[ORDERS <= 6.5]


def pseudo_lines(x, fs, shaft_hz):
    """(strength dB, bins, ring bins, segment s) of the pseudo-lines of one segment, as the command
    measures a line."""
    band = demodulation_band(x, fs, TOP_ORDER * shaft_hz)
    env = envelope_spectrum(x, fs, band=band)
    f = np.asarray(env.freqs)
    df = f[1] - f[0]
    out = []
    for o in ORDERS:
        f0 = o * shaft_hz
        if det.shaft_harmonic(f0, shaft_hz, df) or f0 + det.FLOOR_RING * det.line_window(f0, df) > band[1] - band[0]:
            continue
        _, db, n, m, _ = det.line_strength(f, env.amplitude, f0)
        if n:
            out.append((db, n, m, x.size / fs))
    return out


def segments(x, fs, lengths=(1.0, 2.0, None)):
    for T in lengths:
        n = x.size if T is None else int(T * fs)
        for k in range(x.size // n):
            yield x[k * n:(k + 1) * n]


def rate(rows, margin=0.0):
    a = np.asarray(rows, float)
    thr = np.array([det.null_threshold_db(n, m) for _, n, m, _ in a]) + margin
    return float(np.mean(a[:, 0] > thr)), len(a)


def tail_rates(rows, levels=(0.01, 0.05, 0.1, 0.2)):
    """The fraction of lines whose null exceedance probability is below each level (= the level
    when the model holds)."""
    a = np.asarray(rows, float)
    p = det.null_exceedance(a[:, 0], a[:, 1], a[:, 2])
    return np.array([np.mean(p < q) for q in levels]), np.array(levels)


def null_rows(seed=2026):
    rng = np.random.default_rng(seed)
    rows = {}
    for T, count in ((1.0, 40), (2.0, 20), (5.0, 8), (10.0, 4)):
        rows[T] = [r for _ in range(count) for r in pseudo_lines(rng.standard_normal(int(12000 * T)), 12000.0, 29.9)]
    return rows


def fit_kappa(rows):
    """The bins per independent trial that make the noise's tail rates at 1, 5, 10 and 20 % equal
    the model's (least squares on log ratios over a grid of 0.05)."""
    allrows = [r for v in rows.values() for r in v]
    best = None
    for k in np.arange(1.0, 4.01, 0.05):
        det.NULL_BINS_PER_TRIAL = float(k)
        got, want = tail_rates(allrows)
        err = float(np.sum(np.log(np.maximum(got, 1e-4) / want) ** 2))
        if best is None or err < best[0]:
            best = (err, float(k))
    return best[1]


def healthy_rows(realdata: Path, simulated: Path | None):
    import h5py

    src = {}
    cwru = []
    for name in ("cwru_normal_0hp_48k.npz", "cwru_normal_0hp_12k_decimated.npz"):
        z = np.load(realdata / name)
        x, fs = np.asarray(z["DE"], float), float(z["fs"])
        for seg in segments(x, fs):
            cwru += pseudo_lines(seg, fs, shaft_speed(seg, fs, float(z["rpm"]) / 60.0))
    src["CWRU 97 (48 kHz and 12 kHz decimated, DE)"] = cwru
    hit = []
    for rpm in (600, 900, 1200):
        z = np.load(realdata / "hit_mfs" / f"hit_mfs_normal_{rpm}rpm.npz")
        x, fs = np.asarray(z["DE"], float), float(z["fs"])
        for seg in segments(x, fs):
            hit += pseudo_lines(seg, fs, shaft_speed(seg, fs, rpm / 60.0))
    src["HIT-MFS normal 600/900/1200 rpm"] = hit
    if simulated is not None:
        sim = []
        with h5py.File(simulated, "r") as f:
            fs = float(f.attrs["sample_rate_Hz"])
            X, lab = f["signals"][()], f["labels"][()]
        for x, lb in zip(X, lab):
            if not bool(lb["healthy"]) or int(lb["result"]) != 0:
                continue
            for seg in segments(np.asarray(x, float), fs):
                sim += pseudo_lines(seg, fs, float(lb["shaft_Hz"]))
        src[f"simulated healthy ({simulated.name}, {len(X)} items)"] = sim
    return src


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--realdata", type=Path, default=Path(__file__).resolve().parents[1] / ".." / "shared" / "realdata")
    ap.add_argument("--simulated", type=Path, default=None)
    args = ap.parse_args()
    rows = null_rows()
    kappa = fit_kappa(rows)
    det.NULL_BINS_PER_TRIAL = kappa
    print(f"NULL_BINS_PER_TRIAL = {kappa:.3f}")
    for T, r in rows.items():
        n = np.asarray(r)[:, 1]
        print(f"  white noise {T:g} s: rate {100 * rate(r)[0]:.2f} % of {len(r)} lines (bins {n.min():.0f}-{n.max():.0f}); "
              f"tail rates at 1/5/10/20 %: {np.round(100 * tail_rates(r)[0], 2)} %")
    src = healthy_rows(args.realdata, args.simulated)
    margins = {}
    for name, r in src.items():
        a = np.asarray(r, float)
        excess = a[:, 0] - np.array([det.null_threshold_db(n, m) for _, n, m, _ in a])
        margins[name] = float(np.quantile(excess, 1.0 - det.FALSE_ALARM))
        print(f"  {name}: {len(r)} lines, rate at the null quantile {100 * rate(r)[0]:.2f} %, margin for "
              f"{100 * det.FALSE_ALARM:g} %: {margins[name]:+.2f} dB")
    margin = max(0.0, max(margins.values()))
    print(f"HEALTHY_MARGIN_DB = {margin:.2f}")
    for name, r in src.items():
        a = np.asarray(r, float)
        per = ", ".join(f"{T:.1f} s: {100 * rate(a[np.round(a[:, 3], 1) == T], margin)[0]:.2f} % of "
                        f"{int(np.sum(np.round(a[:, 3], 1) == T))}" for T in sorted(set(np.round(a[:, 3], 1))))
        print(f"  {name} at the threshold, by segment length: {per}")
    print("MEASURED_RATES = {" + ", ".join(f"{k!r}: ({rate(r, margin)[1]}, {rate(r, margin)[0]:.4f})"
                                          for k, r in src.items()) + "}")


if __name__ == "__main__":
    main()
