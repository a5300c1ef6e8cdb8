"""Real CWRU records against simulated ones (issue 9): loading, equal-length metrics, the
targets, and the fits that calibrate the CWRU case (used by ``docs/calibrate_cwru.py``, the
notebook ``05_real_vs_simulated`` and ``tests/test_realdata.py``).

The real records live outside the project (``../shared/realdata``; never committed);
:func:`find_realdata` locates them and every caller skips cleanly when they are absent.

Equal length.  The BPFO line of a squared-envelope spectrum is coherent and its floor is not,
so "peak over median" grows with the record length (CWRU 130: 33 dB over 0.5 s, 41 dB over
1 s, 59 dB over the whole 10 s).  Simulated records are short (~1 s), so the real records are
measured on segments of the same length and the median over segments is the reference
(:func:`segment_metrics`); the whole-record figures of docs/reference-data.md are printed alongside.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.signal as ss

from ..errors import InputError
from ..signals.envelope import squared_envelope
from ..signals.lines import RecordMetrics, record_metrics

__all__ = [
    "G",
    "BPFO_ORDER",
    "RECORDS",
    "TARGETS",
    "find_realdata",
    "load_record",
    "segment_metrics",
    "compare_metrics",
    "smoothed_psd",
    "sensor_response",
    "fit_modes",
    "pass_interval_jitter",
]

#: standard gravity: the CWRU records are in g
G = 9.80665
#: published CWRU BPFO multiplier (docs/reference-data.md)
BPFO_ORDER = 3.5848

#: real outer-race records at 6:00, 0 hp: (spall diameter in, fs) -> file stem
RECORDS = {
    (0.007, 12000): "cwru_OR007_6_0hp_12k",
    (0.014, 12000): "cwru_OR014_6_0hp_12k",
    (0.021, 12000): "cwru_OR021_6_0hp_12k",
    (0.007, 48000): "cwru_OR007_6_0hp_48k",
    (0.014, 48000): "cwru_OR014_6_0hp_48k",
    (0.021, 48000): "cwru_OR021_6_0hp_48k",
}
NORMAL = {12000: "cwru_normal_0hp_12k_decimated", 48000: "cwru_normal_0hp_48k"}


@dataclass(frozen=True)
class Target:
    """One issue-9 target: ``kind`` "rel" (|sim/real - 1| <= tol), "abs" (|sim - real| <= tol)
    or "factor" (1/tol <= sim/real <= tol)."""

    field: str
    kind: str
    tol: float
    label: str

    def check(self, sim: float, real: float) -> bool:
        if not (np.isfinite(sim) and np.isfinite(real)):
            return False
        if self.kind == "rel":
            return abs(sim / real - 1.0) <= self.tol
        if self.kind == "abs":
            return abs(sim - real) <= self.tol
        r = sim / real
        return 1.0 / self.tol <= r <= self.tol


#: issue 9: BPFO order within 0.3 %, peak over median within +-8 dB, A2/A1 and A3/A1 within
#: +-0.15, kurtosis and RMS within a factor 2
TARGETS = (
    Target("peak_order", "rel", 0.003, "BPFO order ±0.3 %"),
    Target("peak_over_median_db", "abs", 8.0, "peak/median ±8 dB"),
    Target("a2_a1", "abs", 0.15, "A2/A1 ±0.15"),
    Target("a3_a1", "abs", 0.15, "A3/A1 ±0.15"),
    Target("kurtosis", "factor", 2.0, "kurtosis ×/÷2"),
    Target("rms", "factor", 2.0, "RMS ×/÷2"),
)


def find_realdata(start=None) -> Path | None:
    """The folder of the real CWRU records, or None when absent: ``$BEARINGSIM_REALDATA`` when
    set (only that folder), else ``../shared/realdata`` relative to ``start`` (default: the
    current directory), its parents, and the package's repository."""
    env = os.environ.get("BEARINGSIM_REALDATA")
    if env is not None:
        cands = [Path(env)]
    else:
        here = Path(start or os.getcwd()).resolve()
        cands = [p / ".." / "shared" / "realdata" for p in [here, *here.parents][:4]]
        cands.append(Path(__file__).resolve().parents[1] / ".." / "shared" / "realdata")
    for c in cands:
        if c.is_dir() and (c / "README.md").is_file() and any(c.glob("cwru_*.npz")):
            return c.resolve()
    return None


def load_record(data_dir, stem, channel="DE"):
    """(x in g, de-meaned float64; fs in Hz; shaft frequency in Hz from the file's rpm)."""
    d = np.load(Path(data_dir) / f"{stem}.npz")
    x = d[channel].astype(np.float64)
    return x - x.mean(), float(d["fs"]), float(d["rpm"]) / 60.0


def segment_metrics(x, fs, shaft_hz, duration, order=BPFO_ORDER, band=(2500.0, 5500.0)):
    """(median RecordMetrics over the non-overlapping ``duration``-long segments of ``x``,
    the list of per-segment metrics)."""
    n = int(round(duration * fs))
    if n < 1:
        raise InputError(f"duration must hold at least one sample, got {duration} s at {fs:g} Hz",
                         "duration is the length (s) of each segment, e.g. 1.0")
    k = len(x) // n
    if k < 1:
        raise InputError(f"record of {len(x) / fs:.2f} s is shorter than duration = {duration} s",
                         "pass a shorter duration or a longer record")
    ms = [record_metrics(x[i * n:(i + 1) * n], fs, shaft_hz, order, band) for i in range(k)]
    vals = np.array([list(m.as_dict().values()) for m in ms])
    med = RecordMetrics(*np.median(vals, axis=0))
    return med, ms


def compare_metrics(sim: RecordMetrics, real: RecordMetrics, targets=TARGETS):
    """[(target, sim value, real value, passed)] for every target."""
    out = []
    for t in targets:
        s, r = getattr(sim, t.field), getattr(real, t.field)
        out.append((t, float(s), float(r), bool(t.check(s, r))))
    return out


# ------------------------------------------------------------------------------ mode fit
def smoothed_psd(x, fs, f_lo, f_hi, nperseg=None, smooth_hz=150.0):
    """(f, log10 PSD) of ``x`` over [f_lo, f_hi]: Welch (Hann, ~11.7 Hz bins), then a moving
    average of ``smooth_hz`` in log10 (it removes the comb of BPFO harmonics)."""
    nperseg = int(1024 * fs / 12000) if nperseg is None else nperseg
    f, P = ss.welch(x, fs=fs, nperseg=nperseg)
    L = np.log10(np.maximum(P, 1e-300))
    k = max(1, int(round(smooth_hz / (f[1] - f[0]))))
    Ls = np.convolve(L, np.ones(k) / k, mode="same")
    m = (f >= f_lo) & (f <= f_hi)
    return f[m], Ls[m]


def sensor_response(f, frequencies, damping_ratios, gains):
    """Transfer function of the sensor path (bearingsim.dynamics.sensor) from the housing acceleration:
    ``1 - sum_k g_k s^2 / (s^2 + 2 zeta_k w_k s + w_k^2)`` at ``s = 2 pi i f``."""
    s = 2j * np.pi * np.asarray(f, dtype=float)[:, None]
    w = 2 * np.pi * np.asarray(frequencies, dtype=float)[None, :]
    z = np.asarray(damping_ratios, dtype=float)[None, :]
    g = np.asarray(gains, dtype=float)[None, :]
    return 1.0 - np.sum(g * s * s / (s * s + 2 * z * w * s + w * w), axis=1)


def fit_modes(f, real_logpsd, excitation_logpsd, f0, zeta0=0.03, zeta_bounds=(0.005, 0.3)):
    """Least-squares fit of the sensor modes to the shape of real spectra.

    ``real_logpsd`` / ``excitation_logpsd``: lists (one per record) of smoothed log10 PSDs on
    the grid ``f`` of the real record and of the simulated housing acceleration.  The model is
    ``log10 |H(f)|^2 + excitation + c_r`` with a free level ``c_r`` per record (levels are fitted
    separately), H of :func:`sensor_response` with M = len(f0) modes (frequency, damping ratio,
    gain > 0).  Returns (frequencies, damping ratios, gains normalised to the largest = 1,
    rms residual in dB).
    """
    from scipy.optimize import least_squares

    f0 = np.asarray(f0, dtype=float)
    M = f0.size
    nrec = len(real_logpsd)

    def unpack(p):
        return p[:M], np.exp(p[M:2 * M]), np.exp(p[2 * M:3 * M])

    def resid(p):
        fk, zk, gk = unpack(p)
        H2 = np.log10(np.abs(sensor_response(f, fk, zk, gk)) ** 2)
        out = []
        for R, E in zip(real_logpsd, excitation_logpsd):
            d = H2 + E - R
            out.append(d - d.mean())                # free level per record
        return 10.0 * np.concatenate(out)           # dB

    p0 = np.concatenate([f0, np.log(np.full(M, zeta0)), np.log(np.full(M, 10.0))])
    lo = np.concatenate([f0 * 0.85, np.full(M, np.log(zeta_bounds[0])), np.full(M, np.log(1e-3))])
    hi = np.concatenate([f0 * 1.15, np.full(M, np.log(zeta_bounds[1])), np.full(M, np.log(1e4))])
    sol = least_squares(resid, p0, bounds=(lo, hi), x_scale="jac")
    fk, zk, gk = unpack(sol.x)
    rms = float(np.sqrt(np.mean(resid(sol.x) ** 2)))
    order = np.argsort(fk)
    del nrec
    return fk[order], zk[order], gk[order], rms


def pass_interval_jitter(x, fs, shaft_hz, order=BPFO_ORDER, band=(2500.0, 5500.0), strong=0.4):
    """Relative standard deviation of the interval between successive impacts of a record.

    Impacts are the peaks of the band-passed squared envelope (smoothed over 0.5 ms, at least
    0.7 pass intervals apart); only pairs of successive peaks both above the ``strong`` quantile
    of the peak heights and 0.85-1.15 nominal intervals apart count (weak passes drown in noise).
    Returns (std, robust std = 1.4826 MAD, number of intervals), as fractions of the interval.
    """
    e = squared_envelope(x, fs, band)
    k = max(1, int(0.0005 * fs))
    e = np.convolve(e, np.ones(k) / k, "same")
    T = 1.0 / (order * shaft_hz)
    pk, _ = ss.find_peaks(e, distance=int(0.7 * T * fs))
    h = e[pk]
    big = h > np.quantile(h, strong)
    d = np.diff(pk) / fs / T
    sel = big[:-1] & big[1:] & (d > 0.85) & (d < 1.15)
    r = d[sel]
    mad = 1.4826 * np.median(np.abs(r - np.median(r)))
    return float(np.std(r)), float(mad), int(r.size)
