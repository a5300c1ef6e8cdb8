"""A plain, textbook feature set for fault classifiers: the second feature set of the transfer
benchmark (issue 33), next to :func:`bearingsim.signals.features.window_features` ("own").

What a vibration analyst without this project would compute, fixed before any result was seen
and never tuned on a real record:

Envelope-spectrum lines in three fixed bands
    The window (mean removed, divided by its RMS) is band-passed in :data:`PLAIN_BANDS_HZ`
    (1-2.5, 2.5-4 and 4-5.4 kHz: contiguous, covering the simulated sensor modes 1.5-5.5 kHz; the
    top is 0.45 x 12 kHz, the lowest sample rate of the benchmark; Butterworth order 4, zero
    phase); of each band the squared envelope (Hilbert, mean removed) is analysed with a Hann
    window, zero-padded to 4x the next power of two.  A line's strength is ``20 log10(peak /
    local median)``: the largest bin within ``f0 (1 +- 1.5 %)`` (at least half the window's
    resolution 1/T either side) over the median of the envelope spectrum between 0.5 f0 and
    1.5 f0 (the local floor).  Lines: BPFO, 2 BPFO; BPFI, 2 BPFI, BPFI - f_r, BPFI + f_r;
    2 BSF, 4 BSF, 2 BSF - FTF, 2 BSF + FTF (:data:`PLAIN_LINES`).  One feature per line and
    band (no maximum over bands: the classifier sees each band).
Statistics of the window
    Kurtosis, crest factor (peak / RMS) and skewness (signed, as textbooks define it).

The frequencies come from the fault orders (:func:`bearingsim.signals.features.fault_orders`, the
bearing at its free contact angle) times the window's shaft frequency (a real record's nominal
rpm; a simulated item's label).  Every feature is a ratio: none depends on the signal's level.
The signature is that of :func:`window_features`: ``plain_features(windows (N, T), fs,
shaft_hz, orders) -> (N, len(PLAIN_FEATURE_NAMES))``.
"""
from __future__ import annotations

import numpy as np
import scipy.signal as ss

from ..errors import InputError
from ..physics.kinematics import DefectFrequencies

__all__ = ["PLAIN_BANDS_HZ", "PLAIN_LINES", "PLAIN_FEATURE_NAMES", "plain_features", "line_orders"]

#: the three envelope bands (Hz), fixed: the top one ends at 0.45 x 12 kHz
PLAIN_BANDS_HZ = ((1000.0, 2500.0), (2500.0, 4000.0), (4000.0, 5400.0))
#: the lines of every band
PLAIN_LINES = ("BPFO", "2BPFO", "BPFI", "2BPFI", "BPFI-fr", "BPFI+fr", "2BSF", "4BSF", "2BSF-FTF", "2BSF+FTF")
#: feature names, in the column order of :func:`plain_features`
PLAIN_FEATURE_NAMES = tuple(f"{ln}@{lo / 1000:g}-{hi / 1000:g}kHz" for lo, hi in PLAIN_BANDS_HZ
                            for ln in PLAIN_LINES) + ("kurtosis", "crest", "skewness")

_REL = 0.015          # line window (relative)
_LOCAL = 0.5          # local floor: the median between (1 -+ _LOCAL) f0


def line_orders(orders: DefectFrequencies) -> np.ndarray:
    """The lines of :data:`PLAIN_LINES` as multiples of the shaft frequency."""
    o = orders
    return np.array([o.bpfo, 2 * o.bpfo, o.bpfi, 2 * o.bpfi, o.bpfi - 1.0, o.bpfi + 1.0,
                     o.two_bsf, 2 * o.two_bsf, o.two_bsf - o.ftf, o.two_bsf + o.ftf])


def _lines_db(f, S, f0, half):
    """20 log10(peak within f0 +- half / median within (1 -+ _LOCAL) f0), per row; f0, half (N,)."""
    a = np.searchsorted(f, f0 - half, "left")
    b = np.searchsorted(f, f0 + half, "right")
    c = np.searchsorted(f, (1.0 - _LOCAL) * f0, "left")
    d = np.searchsorted(f, (1.0 + _LOCAL) * f0, "right")
    out = np.empty(len(f0))
    for i in range(len(f0)):
        peak = S[i, a[i]:b[i]].max() if b[i] > a[i] else 0.0
        floor = np.median(S[i, c[i]:d[i]]) if d[i] > c[i] else 0.0
        out[i] = 20.0 * np.log10(max(peak, 1e-300) / max(floor, 1e-300))
    return out


def plain_features(windows, fs, shaft_hz, orders: DefectFrequencies) -> np.ndarray:
    """(N, len(PLAIN_FEATURE_NAMES)) features of ``windows`` (N, T) sampled at ``fs`` (at least
    12 kHz); ``shaft_hz`` scalar or (N,)."""
    X = np.atleast_2d(np.asarray(windows, float))
    N, T = X.shape
    fs = float(fs)
    if T < 64:
        raise InputError(f"windows of {T} samples are too short for envelope features (need >= 64)",
                         "cut windows of at least 64 samples (window_s >= 64 / fs)")
    if 0.5 * fs <= PLAIN_BANDS_HZ[-1][1]:
        raise InputError(f"sample rate fs = {fs:g} Hz: the plain features need more than "
                         f"{2 * PLAIN_BANDS_HZ[-1][1]:g} Hz (their top band ends at {PLAIN_BANDS_HZ[-1][1]:g} Hz)",
                         "use a record sampled at 12 kHz or more")
    if not np.all(np.isfinite(X)):
        raise InputError("windows hold NaN or infinite samples",
                         "remove or interpolate the non-finite samples before the features")
    fr = np.broadcast_to(np.asarray(shaft_hz, float), (N,)).copy()
    if np.any(~np.isfinite(fr)) or np.any(fr <= 0):
        raise InputError("shaft_hz (the shaft frequency of each window, Hz) must be finite and > 0",
                         "pass the record's shaft speed in Hz (rpm / 60)")
    return np.concatenate([_block(X[i:i + _BLOCK], fs, fr[i:i + _BLOCK], orders)
                           for i in range(0, N, _BLOCK)], axis=0)


_BLOCK = 256          # windows per block (memory: the spectra of a block)


def _block(X, fs, fr, orders):
    N, T = X.shape
    X = X - X.mean(axis=1, keepdims=True)
    rms = np.sqrt(np.mean(X * X, axis=1))
    Xn = X / np.where(rms > 0, rms, 1.0)[:, None]
    nfft = 1 << (int(np.ceil(np.log2(T))) + 2)
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    w = np.hanning(T)
    cols = []
    for lo, hi in PLAIN_BANDS_HZ:
        sos = ss.butter(4, [lo, hi], btype="bandpass", fs=fs, output="sos")
        y = ss.sosfiltfilt(sos, Xn, axis=1)
        e2 = np.abs(ss.hilbert(y, axis=1)) ** 2
        e2 -= e2.mean(axis=1, keepdims=True)
        S = np.abs(np.fft.rfft(e2 * w, nfft, axis=1))
        for k in line_orders(orders):
            f0 = k * fr
            cols.append(_lines_db(f, S, f0, np.maximum(_REL * f0, 0.5 * fs / T)))
    zero = rms <= 0
    stats = [np.where(zero, 0.0, v) for v in (np.mean(Xn ** 4, axis=1), np.max(np.abs(Xn), axis=1),
                                               np.mean(Xn ** 3, axis=1))]
    return np.column_stack(cols + stats)
