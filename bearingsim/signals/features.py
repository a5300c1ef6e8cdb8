"""Scale-free fault features of vibration windows, for classifiers that must work on any machine.

One documented extractor (:func:`window_features`), fixed on physical grounds before any
classifier met a real record and never tuned on one (docs/realism.md, "Transfer benchmark").
Every feature is independent of the signal's level and of the sensor's transfer path, so a
classifier trained on simulated records learns the *signature* of a fault, not one rig's gains:

Envelope lines (one set per band, then the largest over the bands)
    The window is band-passed in octave bands from 750 Hz up to 0.45 fs (Butterworth order 4,
    zero phase) and over the whole range 500 Hz - 0.45 fs; of each band the squared envelope
    (Hilbert) is analysed with a Hann window, zero-padded to 4x the next power of two.  A
    line's strength is ``20 log10(peak / floor)``: the largest bin within +-1.5 % of the line
    (at least two bins) over the median of the spectrum between 1 and 20 x the shaft
    frequency.  Lines: 1, 2, 3 x BPFO (outer race); 1, 2, 3 x BPFI and BPFI +- f_r (inner race:
    the load zone modulates it at the shaft rate); 1, 2 x (2 BSF) and 2 BSF +- FTF (a ball pit
    meets the raceways twice per ball turn and orbits with the cage) and the cage comb, the mean
    of the lines at k FTF, k = 1..8 (the pitted ball passes through the load zone once per cage
    turn: where its strikes are irregular, the 2 BSF line smears but the cage periodicity of
    their strength survives; an outer-race fault has lines only at multiples of 9 FTF = BPFO for
    Z = 9); f_r, 2 f_r and the strongest of 3..8 f_r (unbalance, misalignment, the machine's
    shaft-synchronous modulation: background, not a bearing fault); FTF.  Each feature is the
    largest over the bands (the fault's own resonance band is unknown on a new machine), as is
    the band kurtosis.
Family summaries
    The mean of each fault family's lines (outer; inner; ball with the cage comb) and the contrast of each family
    against the strongest of the other two (a fault shows one family above the others).
Impulsiveness of the raw window
    Kurtosis, crest factor and |skewness|.

The frequencies come from the bearing geometry at its free contact angle
(:func:`bearingsim.physics.kinematics.defect_frequencies`) and the shaft speed of the window (a
real record's nominal rpm; a simulated item's label).  All arrays are NumPy; windows are
processed together (N, T).
"""
from __future__ import annotations


import numpy as np
import scipy.signal as ss

from ..errors import InputError
from ..physics.defect import LOCATIONS
from ..physics.kinematics import DefectFrequencies, defect_frequencies

__all__ = ["fault_orders", "FEATURE_NAMES", "window_features", "cut_windows", "octave_bands"]


def fault_orders(bearing, alpha=None) -> DefectFrequencies:
    """The bearing's fault orders: its :class:`DefectFrequencies` per unit shaft frequency
    (shaft 1, FTF, BPFO, BPFI, BSF as multiples of the shaft frequency; ``two_bsf`` = 2 BSF),
    floats, at ``alpha`` (rad; default: its free contact angle; docs/model.md section 8)."""
    return DefectFrequencies(*(float(v) for v in defect_frequencies(bearing, 1.0, alpha)))


_LINES = ("O1", "O2", "O3", "I1", "I2", "I3", "Isb", "B1", "B2", "Bsb", "Ccomb", "R1", "R2", "Rcomb", "C")
#: feature names, in the column order of :func:`window_features`
FEATURE_NAMES = _LINES + ("band_kurtosis", "outer", "inner", "ball", "outer_contrast",
                          "inner_contrast", "ball_contrast", "kurtosis", "crest", "abs_skewness")

_REL = 0.015          # line window (relative)
_FLOOR = (1.0, 20.0)  # floor: median between these multiples of the shaft frequency


def octave_bands(fs) -> list:
    """The analysis bands (Hz) for a sample rate: octaves from 750 Hz up to 0.45 fs (the last
    one cut there, kept when at least half an octave wide) and the whole 500 Hz - 0.45 fs."""
    top = 0.45 * float(fs)
    if top <= 1000.0:
        raise InputError(f"sample rate fs = {fs:g} Hz: the features need at least 2.3 kHz "
                         "(bands from 500 Hz up to 0.45 fs)", "use a record sampled at 2.3 kHz or more")
    bands, lo = [], 750.0
    while lo * 1.41 < top:
        bands.append((lo, min(2.0 * lo, top)))
        lo *= 2.0
    return bands + [(500.0, top)]


def cut_windows(x, fs, window_s) -> np.ndarray:
    """Non-overlapping windows of ``window_s`` seconds of a 1-D record (N, T); the rest dropped."""
    x = np.asarray(x, float).ravel()
    T = int(round(float(window_s) * float(fs)))
    if T < 16 or x.size < T:
        raise InputError(f"a record of {x.size} samples has no window of window_s = {window_s:g} s at {fs:g} Hz",
                         "window_s must hold at least 16 samples and at most the whole record "
                         "(fs: the sample rate in Hz)")
    n = x.size // T
    return x[:n * T].reshape(n, T)


def _kurt(y):
    y = y - y.mean(axis=-1, keepdims=True)
    m2 = np.mean(y * y, axis=-1)
    return np.mean(y ** 4, axis=-1) / np.where(m2 > 0, m2 * m2, 1.0)


def _line_db(f, S, f0, floor, df):
    """20 log10(largest bin within f0 (1 +- _REL) / floor), per row; f0 (N,)."""
    half = np.maximum(_REL * f0, 2.0 * df)
    m = np.abs(f[None, :] - f0[:, None]) <= half[:, None]
    peak = np.max(np.where(m, S, 0.0), axis=1)
    return 20.0 * np.log10(np.maximum(peak, 1e-300) / floor)


def window_features(windows, fs, shaft_hz, orders: DefectFrequencies) -> np.ndarray:
    """(N, len(FEATURE_NAMES)) features of ``windows`` (N, T) sampled at ``fs``; ``shaft_hz``
    scalar or (N,) (the shaft frequency of each window)."""
    X = np.atleast_2d(np.asarray(windows, float))
    N, T = X.shape
    if T < 64:
        raise InputError(f"windows of {T} samples are too short for envelope features (need >= 64)",
                         "cut windows of at least 64 samples (window_s >= 64 / fs)")
    if not np.all(np.isfinite(X)):
        raise InputError(f"windows hold {int(np.sum(~np.isfinite(X)))} NaN or infinite samples",
                         "remove or interpolate the non-finite samples before the features")
    fs = float(fs)
    fr = np.broadcast_to(np.asarray(shaft_hz, float), (N,)).copy()
    bad = ~np.isfinite(fr) | (fr <= 0)
    if bad.any():
        raise InputError(f"shaft_hz must be finite and > 0 Hz: {int(bad.sum())} of {N} value(s) are not "
                         f"(first: {fr[np.argmax(bad)]:g})",
                         "shaft_hz is the shaft frequency in Hz (rpm / 60), a scalar or one per window")
    X = X - X.mean(axis=1, keepdims=True)
    rms = np.sqrt(np.mean(X * X, axis=1))
    Xn = X / np.where(rms > 0, rms, 1.0)[:, None]
    nfft = 1 << (int(np.ceil(np.log2(T))) + 2)
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    df = fs / nfft
    w = np.hanning(T)
    lines = {
        "O1": orders.bpfo, "O2": 2 * orders.bpfo, "O3": 3 * orders.bpfo,
        "I1": orders.bpfi, "I2": 2 * orders.bpfi, "I3": 3 * orders.bpfi,
        "B1": orders.two_bsf, "B2": 2 * orders.two_bsf, "R1": 1.0, "R2": 2.0, "C": orders.ftf,
    }
    per_band = []
    for lo, hi in octave_bands(fs):
        sos = ss.butter(4, [lo, hi], btype="bandpass", fs=fs, output="sos")
        y = ss.sosfiltfilt(sos, Xn, axis=1)
        e2 = np.abs(ss.hilbert(y, axis=1)) ** 2
        e2 -= e2.mean(axis=1, keepdims=True)
        S = np.abs(np.fft.rfft(e2 * w, nfft, axis=1))
        fm = (f[None, :] >= _FLOOR[0] * fr[:, None]) & (f[None, :] <= _FLOOR[1] * fr[:, None])
        floor = np.array([np.median(S[i, fm[i]]) for i in range(N)])
        floor = np.maximum(floor, 1e-300)
        v = {k: _line_db(f, S, o * fr, floor, df) for k, o in lines.items()}
        v["Isb"] = 0.5 * (_line_db(f, S, (orders.bpfi - 1.0) * fr, floor, df) +
                          _line_db(f, S, (orders.bpfi + 1.0) * fr, floor, df))
        v["Bsb"] = 0.5 * (_line_db(f, S, (orders.two_bsf - orders.ftf) * fr, floor, df) +
                          _line_db(f, S, (orders.two_bsf + orders.ftf) * fr, floor, df))
        v["Ccomb"] = np.mean([_line_db(f, S, k * orders.ftf * fr, floor, df) for k in range(1, 9)], axis=0)
        v["Rcomb"] = np.max([_line_db(f, S, k * fr, floor, df) for k in range(3, 9)], axis=0)
        v["band_kurtosis"] = _kurt(y)
        per_band.append(np.stack([v[k] for k in _LINES + ("band_kurtosis",)], axis=1))
    F = np.max(np.stack(per_band, axis=0), axis=0)          # (N, 14): largest over the bands
    col = {k: F[:, i] for i, k in enumerate(_LINES + ("band_kurtosis",))}
    fam = {"outer": (col["O1"] + col["O2"] + col["O3"]) / 3.0,
           "inner": (col["I1"] + col["I2"] + col["I3"] + col["Isb"]) / 4.0,
           "ball": (col["B1"] + col["B2"] + col["Bsb"] + col["Ccomb"]) / 4.0}
    names = LOCATIONS
    contrast = [fam[a] - np.maximum(*(fam[b] for b in names if b != a)) for a in names]
    m2 = rms * rms
    kurt = np.mean(X ** 4, axis=1) / np.where(m2 > 0, m2 * m2, 1.0)
    crest = np.max(np.abs(X), axis=1) / np.where(rms > 0, rms, 1.0)
    skew = np.abs(np.mean(X ** 3, axis=1)) / np.where(rms > 0, rms ** 3, 1.0)
    return np.column_stack([F, fam["outer"], fam["inner"], fam["ball"], *contrast, kurt, crest, skew])
