"""The CWRU ball records' lines after cepstral pre-whitening, by window length (issue 33, item 4).

    .venv/bin/python benchmarks/check_ball_whitened.py [--realdata ../shared/realdata]
        [--windows 10,5,2,1,0.2] [--simulated N] [--seed 0] [--exposure gate|kinematic]
        [--fault ball|inner|outer|healthy] [--ball-snr LO,HI] [--spec SPEC]

Smith & Randall (2015) graded 222 (method 2 only) and 223 diagnosable (Y2) as ball faults;
method 2 is cepstral pre-whitening: the spectrum's amplitude set to one (phase kept), the squared
envelope of the whitened signal over the whole band, its spectrum.  This script applies it to the
ball records, the normal record 97 and the rig's inner- and outer-race records (for the lines a
fault of another class makes), cut into windows of each ``--windows`` length (s; 10: the whole
record), and prints per record the mean over its windows of each line's strength: the peak within
f0 +- (1 % of f0 + 0.5 Hz, at least a bin) over the median within +-6 times that (dB).  Lines at the bearing's
fault orders (bearingsim.signals.features.fault_orders, contact angle 0) times the record's shaft
speed measured from its spectrum (bearingsim.realism.identify_bank.measured_shaft_speed near the
file's rpm).  No classifier: what a window of a real ball record carries.
A line of the normal record is the level a window shows without that fault.

``--simulated N``: beside the records, N items of 1 s of the CWRU rig's training spec
(:func:`bearingsim.realism.transfer.rig_spec` of the shipped four-class spec or ``--spec``; every item of
class ``--fault``, ball by default; data set seed ``--seed``; ``[dataset] ball_exposure``
``--exposure``; ``[dataset] ball_fault_snr_dB`` ``--ball-snr`` where given), measured the same
way at each item's own shaft speed (its label), one window per item (its start) of each
``--windows`` length up to 1 s: the mean over the items, the quartiles, and the means of the
items whose ball pit struck on most (>= 50 %) and on few (< 50 %) of its passes, line by line
against the records (docs/realism.md, "Simulated items, the same measure").
"""
from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np
from scipy.signal import hilbert

from bearingsim.case import load_case
from bearingsim import load_dataset
from bearingsim.datasets import make_dataset
from bearingsim.realism.calibration import find_realdata
from bearingsim.realism.identify_bank import measured_shaft_speed
from bearingsim.realism.transfer import RIGS, rig_spec
from bearingsim.signals.features import fault_orders

#: file stem, CWRU number, Smith & Randall grade (../shared/realdata/README.md)
RECORDS = [("cwru_B007_0hp_12k", 118, "N1"), ("cwru_B007_1hp_12k", 119, "N1"), ("cwru_B007_2hp_12k", 120, "N1"),
           ("cwru_B007_3hp_12k", 121, "Y2 (method 3)"), ("cwru_B021_0hp_12k", 222, "Y2 (method 2)"),
           ("cwru_B021_1hp_12k", 223, "Y2"), ("cwru_B021_2hp_12k", 224, "N1"), ("cwru_B021_3hp_12k", 225, "N1"),
           ("cwru_normal_0hp_12k_decimated", 97, "normal"), ("cwru_IR021_0hp_12k", 209, "Y1 inner"),
           ("cwru_OR021_6_0hp_12k", 234, "Y2 outer")]


def whitened_envelope_spectrum(x, fs):
    """(frequencies, |spectrum| of the squared envelope of the pre-whitened signal)."""
    X = np.fft.rfft(x - np.mean(x))
    y = np.fft.irfft(X / np.maximum(np.abs(X), 1e-30), len(x))
    e = np.abs(hilbert(y)) ** 2
    return np.fft.rfftfreq(len(e), 1.0 / fs), np.abs(np.fft.rfft(e - e.mean())) / len(e)


def line_db(f, E, f0):
    w = max(0.01 * f0 + 0.5, f[1] - f[0])       # at least one bin (a 0.2 s window resolves 5 Hz)
    peak = E[np.abs(f - f0) <= w].max()
    return 10.0 * np.log10(peak / np.median(E[np.abs(f - f0) <= 6.0 * w]))


def simulated_rows(n, seed, lines, window_s=1.0, exposure="gate", fault="ball", ball_snr=None,
                   spec_name="dataset_cwru_4class"):
    """(line strengths (n_ok, len(lines)), strike probabilities (n_ok,)) of ``n`` simulated
    1 s ball items of the CWRU rig spec, one window of ``window_s`` each (the item's start)."""
    import tempfile

    spec = rig_spec(load_case(spec_name), RIGS["cwru"], max(1.0, window_s), n, seed)
    with tempfile.TemporaryDirectory() as tmp:
        text = spec.text
        for k in ("healthy", "outer", "inner", "ball"):      # all at once: they sum to 1
            v = 1.0 if k == fault else 0.0
            text = re.sub(rf"(?m)^{k}_fraction\s*=.*$", f"{k}_fraction = {v}", text)
        (Path(tmp) / "ball.toml").write_text(text)
        spec = load_case(Path(tmp) / "ball.toml").with_value("dataset.ball_exposure", exposure)
        if ball_snr is not None:
            spec = spec.with_value("dataset.ball_fault_snr_dB", list(ball_snr))
        path = Path(tmp) / "ball.h5"
        make_dataset(spec, path)
        X, lab, meta = load_dataset(path)       # the items simulated (result 0) only
    fs = float(meta["sample_rate_Hz"])
    X = np.asarray(X, float)
    T = int(round(window_s * fs))
    rows = []
    for x, fr in zip(X[:, :T], lab["shaft_Hz"]):
        f, E = whitened_envelope_spectrum(x, fs)
        rows.append([line_db(f, E, v * fr) for v in lines.values()])
    strike = lab["strike_probability"]
    return np.asarray(rows), np.asarray(strike, float)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--realdata", default=None, help="the records' folder (default: ../shared/realdata)")
    ap.add_argument("--windows", default="10,5,2,1,0.2", help="window lengths in s (10: the whole record)")
    ap.add_argument("--simulated", type=int, default=0, help="also N simulated 1 s ball items (CWRU rig spec)")
    ap.add_argument("--seed", type=int, default=0, help="data set seed of the simulated items")
    ap.add_argument("--fault", default="ball", help="class of the simulated items: ball (default), inner, "
                    "outer or healthy (the same measure on the other classes: is a line's strength off for "
                    "one class or for all)")
    ap.add_argument("--spec", default="dataset_cwru_4class", help="the four-class spec the simulated items "
                    "derive from (a shipped name or a path; default: the shipped one)")
    ap.add_argument("--ball-snr", default=None, help="lo,hi: [dataset] ball_fault_snr_dB of the simulated ball "
                    "items (dB; default: the spec's)")
    ap.add_argument("--exposure", default="gate", help="[dataset] ball_exposure of the simulated items: gate "
                    "(the shipped spec's) or kinematic")
    a = ap.parse_args(argv)
    root = Path(a.realdata) if a.realdata else find_realdata(Path(__file__).resolve().parent.parent)
    if root is None or not Path(root).is_dir():
        print("skipped: the CWRU records (../shared/realdata) are not here")
        return 0
    o = fault_orders(load_case("cwru_6205").bearing())
    lines = {"2BSF": o.two_bsf, "4BSF": 2 * o.two_bsf, "2BSF+FTF": o.two_bsf + o.ftf, "BPFI": o.bpfi, "BPFO": o.bpfo,
             "FTF": o.ftf}
    lengths = [float(v) for v in a.windows.split(",")]
    print("lines (orders): " + ", ".join(f"{k} {v:.4f}" for k, v in lines.items()))
    print(f"{'record':>6} {'grade':>14} {'window s':>8} {'n':>3} " + " ".join(f"{k:>9}" for k in lines))
    for stem, no, grade in RECORDS:
        p = Path(root) / f"{stem}.npz"
        if not p.is_file():
            continue
        d = np.load(p)
        x, fs = np.asarray(d["DE"], float), float(d["fs"])
        fr = measured_shaft_speed(x, fs, float(d["rpm"]) / 60.0)
        for L in lengths:
            n = min(len(x), int(round(L * fs)))
            rows = []
            for k in range(len(x) // n):
                f, E = whitened_envelope_spectrum(x[k * n:(k + 1) * n], fs)
                rows.append([line_db(f, E, v * fr) for v in lines.values()])
            m = np.mean(rows, axis=0)
            print(f"{no:>6} {grade:>14} {n / fs:>8.2f} {len(rows):>3} " + " ".join(f"{v:>9.1f}" for v in m))
    if a.simulated > 0:
        for L in lengths:
            if L > 1.0:
                continue
            R, p = simulated_rows(a.simulated, a.seed, lines, L, a.exposure, a.fault,
                                  None if a.ball_snr is None else [float(v) for v in a.ball_snr.split(",")], a.spec)
            sel = {"sim mean": np.ones(len(R), bool), "sim p>=0.5": p >= 0.5, "sim p<0.5": p < 0.5}
            for name, m in sel.items():
                if m.any():
                    print(f"{'sim':>6} {name:>14} {L:>8.2f} {int(m.sum()):>3} "
                          + " ".join(f"{v:>9.1f}" for v in R[m].mean(axis=0)))
            for q in (25, 50, 75):
                print(f"{'sim':>6} {f'quartile {q}':>14} {L:>8.2f} {len(R):>3} "
                      + " ".join(f"{v:>9.1f}" for v in np.percentile(R, q, axis=0)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
