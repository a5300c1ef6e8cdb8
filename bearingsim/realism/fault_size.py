"""Physics of an identified fault (the numeric core of :mod:`bearingsim.realism.identify`; NumPy/SciPy on
arrays, no files): the surface speed that maps an event spacing to a defect length, the contact
angle from a measured fault order, the measured fault line, and the path-robust features of a
ball's passage over a defect that the size estimator learns from.

Kinematics (docs/model.md section 8, g = D/d_m): the contact point travels over a defect at
    outer race   v = R_o 2 pi FTF              (R_o = (d_m + D cos a0)/2, the outer raceway radius)
    inner race   v = R_ir 2 pi (f_r - FTF)     (R_ir = (d_m - D cos a0)/2)
    ball pit     v = (D/2) 2 pi BSF            (BSF: ball turns per second)
so a ball that crosses a defect of length L takes L / v from its entry event (the ball leaves the
load-bearing surface: a step) to its exit event (it strikes the far edge: an impulse; Sawalhi &
Randall 2011).  The features of :func:`pass_features` are sampled on a grid of *lengths*: each
length L is looked up at the lag L / v of the record's own kinematics, so one estimator serves
every class and speed.

Contact angle from a fault order (f_line / f_r).  With a cage that lags its kinematic speed by a
mean fraction s (gross slip):
    outer:  BPFO/f_r = (Z/2)(1 - g cos a)(1 - s)
    inner:  BPFI/f_r = Z - (Z/2)(1 - g cos a)(1 - s)
so cos a = (1 - 2 order / (Z (1 - s))) / g (outer) and (1 - 2 (Z - order) / (Z (1 - s))) / g
(inner).  The order moves by (Z/2) g sin a per radian: 0.003 per degree at 10 deg on the CWRU 6205
against 0.036 for 1 % slip, so the angle is fixed by the order only where the mean slip is known.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.signal as ss

from ..errors import InputError

__all__ = ["SIZE_GRID_MM", "PASS_FEATURE_NAMES", "surface_speed", "angle_from_order", "order_of_angle",
           "line_frequency", "pass_times", "pass_features", "FaultLine"]

#: the lengths (mm) at which the pass features are sampled (lag = L / v)
SIZE_GRID_MM = np.array([0.08, 0.12, 0.16, 0.2, 0.25, 0.3, 0.36, 0.43, 0.5, 0.6, 0.7, 0.8, 0.95, 1.1, 1.3])
PASS_FEATURE_NAMES = tuple([f"env_{L:g}" for L in SIZE_GRID_MM] + [f"acf_{L:g}" for L in SIZE_GRID_MM] +
                           [f"cep_{L:g}" for L in SIZE_GRID_MM] +
                           ["centroid_kHz", "bandwidth_kHz", "decay_per_ms", "resolvable_mm"])
_PRE_MS, _POST_MS = 1.0, 3.0


def surface_speed(bearing, shaft_hz, location, ftf_hz, bsf_hz=None) -> float:
    """Speed (m/s) at which a ball's contact crosses a defect of ``location`` (outer/inner/ball)."""
    if location == "outer":
        return float(bearing.outer_raceway_radius) * 2.0 * np.pi * float(ftf_hz)
    if location == "inner":
        return float(bearing.inner_raceway_radius) * 2.0 * np.pi * (float(shaft_hz) - float(ftf_hz))
    if location == "ball":
        return 0.5 * float(bearing.ball_diameter) * 2.0 * np.pi * float(bsf_hz)
    raise InputError(f"location must be 'outer', 'inner' or 'ball', got {location!r}",
                     "the surface the defect lies on: the outer or inner raceway, or a ball")


def order_of_angle(bearing, location, alpha, slip=0.0):
    """The fault order (line / f_r) of ``location`` at contact angle ``alpha`` (rad), with the cage
    lagging by ``slip`` (fraction)."""
    Z = int(bearing.n_balls)
    c = 0.5 * Z * (1.0 - float(bearing.g) * np.cos(alpha)) * (1.0 - slip)
    if location == "outer":
        return c
    if location == "inner":
        return Z - c
    raise InputError(f"location must be 'outer' or 'inner' for a race order, got {location!r}",
                     "the contact angle is read from an outer- or inner-race line (BPFO or BPFI)")


def angle_from_order(bearing, location, order, slip=0.0):
    """Contact angle (rad) whose ``location`` order with mean cage slip ``slip`` is ``order``; NaN
    where no angle in [0, 90) deg gives it (the order is outside the kinematic range)."""
    Z = int(bearing.n_balls)
    order = np.asarray(order, float)
    if location == "outer":
        c = (1.0 - 2.0 * order / (Z * (1.0 - slip))) / float(bearing.g)
    elif location == "inner":
        c = (1.0 - 2.0 * (Z - order) / (Z * (1.0 - slip))) / float(bearing.g)
    else:
        raise InputError(f"location must be 'outer' or 'inner' to read a contact angle, got {location!r}",
                         "the contact angle is read from an outer- or inner-race line (BPFO or BPFI)")
    c = np.where((c > 0.0) & (c <= 1.0 + 1e-12), np.minimum(c, 1.0), np.nan)
    return np.arccos(c)


class FaultLine(NamedTuple):
    """A line of the squared-envelope spectrum: frequency (Hz), its standard uncertainty (Hz),
    strength over the local floor (dB), the band it was found in (Hz)."""

    hz: float
    sd_hz: float
    db: float
    band: tuple


def _env_spectrum(x, fs, band, pad=4):
    sos = ss.butter(4, band, btype="bandpass", fs=fs, output="sos")
    e2 = np.abs(ss.hilbert(ss.sosfiltfilt(sos, x))) ** 2
    e2 = e2 - e2.mean()
    n = e2.size
    nfft = 1 << (int(np.ceil(np.log2(n))) + int(np.log2(pad)))
    S = np.abs(np.fft.rfft(e2 * np.hanning(n), nfft))
    return np.fft.rfftfreq(nfft, 1.0 / fs), S


def line_frequency(x, fs, f_expected, bands, rel=0.03, harmonics=3) -> FaultLine:
    """The fault line near ``f_expected`` in the squared-envelope spectrum of ``x``: in each band,
    the peak of the harmonic sum (k = 1..``harmonics``, candidates within +-``rel``), refined by
    a parabola through the log spectrum; the band with the strongest line wins.  ``sd_hz``: the
    Hann window's resolution (fs / n) over sqrt(strength ratio), the usual peak-location
    uncertainty, floored at 1 % of a bin (the window's own bias)."""
    n = x.size
    best = None
    for band in bands:
        f, S = _env_spectrum(x, fs, band)
        df = f[1] - f[0]
        cand = np.arange(f_expected * (1 - rel), f_expected * (1 + rel), df / 4.0)
        lS = np.log(np.maximum(S, 1e-300))
        tot = np.zeros(cand.size)
        for k in range(1, harmonics + 1):
            tot += np.interp(k * cand, f, lS) / k
        c = cand[int(np.argmax(tot))]
        i = int(np.argmin(np.abs(f - c)))
        lo, hi = max(i - 3, 1), min(i + 4, f.size - 1)
        i = lo + int(np.argmax(S[lo:hi]))
        y0, y1, y2 = lS[i - 1], lS[i], lS[i + 1]
        den = y0 - 2 * y1 + y2
        d = 0.5 * (y0 - y2) / den if den < 0 else 0.0
        fpk = f[i] + float(np.clip(d, -0.5, 0.5)) * df
        m = (f >= 0.5 * f_expected) & (f <= 1.5 * f_expected)
        floor = float(np.median(S[m])) if np.any(m) else 1e-300
        db = 20.0 * np.log10(max(S[i], 1e-300) / max(floor, 1e-300))
        ratio = max(S[i] / max(floor, 1e-300), 1.0)
        sd = max((fs / n) / np.sqrt(ratio), 0.01 * fs / n)
        if best is None or db > best.db:
            best = FaultLine(float(fpk), float(sd), float(db), tuple(band))
    return best


def pass_times(x, fs, period_s, band):
    """Sample indices of the passes of a defect of period ``period_s``: the largest squared-
    envelope sample (band ``band``) in each period, periods phased on the envelope's own
    fundamental."""
    sos = ss.butter(4, band, btype="bandpass", fs=fs, output="sos")
    e2 = np.abs(ss.hilbert(ss.sosfiltfilt(sos, x, axis=-1), axis=-1)) ** 2
    t = np.arange(e2.shape[-1]) / fs
    ph = np.angle(np.sum(e2 * np.exp(-2j * np.pi * t / period_s), axis=-1))
    t0 = (ph / (2 * np.pi)) % 1.0 * period_s           # phase of the peak of the fundamental
    P = int(round(period_s * fs))
    out = []
    for row, t00 in zip(np.atleast_2d(e2), np.atleast_1d(t0)):
        k = np.arange(-1, int(row.size / (period_s * fs)) + 1)
        starts = np.round((t00 + (k - 0.5) * period_s) * fs).astype(int)
        starts = starts[(starts >= 0) & (starts + P <= row.size)]
        idx = [s + int(np.argmax(row[s:s + P])) for s in starts]
        out.append(np.array(idx, int))
    return out, e2


def _interp_rows(lags, v, q):
    """rows of v sampled at lags q (s) by linear interpolation over the lag axis ``lags``."""
    return np.stack([np.interp(q, lags, r) for r in v], axis=0)


def pass_features(windows, fs, period_s, speed_m_s, band=(500.0, None)) -> np.ndarray:
    """(N, len(PASS_FEATURE_NAMES)) features of each window's defect passes, path-robust by
    construction (every quantity a ratio or a shape), sampled at lags L / ``speed_m_s`` over
    :data:`SIZE_GRID_MM` (``speed_m_s`` scalar or (N,)):

    env_L  the passes' averaged squared envelope (aligned on its peak, normalised by it) at the lag
           before the peak (the entry event precedes the exit impulse by L / v);
    acf_L  the autocorrelation of the averaged band-passed pass waveform (normalised);
    cep_L  the real cepstrum of the averaged pass power spectrum (entry and exit events are an
           echo: a rahmonic at L / v);
    centroid, bandwidth (kHz) of the pass spectrum, the envelope decay rate (1/ms) after the peak
    (the path's damping), and the shortest length the sample rate resolves, v / (0.45 fs) in mm.
    """
    X = np.atleast_2d(np.asarray(windows, float))
    N, T = X.shape
    fs = float(fs)
    hi = 0.45 * fs if band[1] is None else float(band[1])
    v = np.broadcast_to(np.asarray(speed_m_s, float), (N,))
    per = np.broadcast_to(np.asarray(period_s, float), (N,))
    sos = ss.butter(4, [band[0], hi], btype="bandpass", fs=fs, output="sos")
    Y = ss.sosfiltfilt(sos, X - X.mean(axis=1, keepdims=True), axis=1)
    pre, post = int(round(_PRE_MS * 1e-3 * fs)), int(round(_POST_MS * 1e-3 * fs))
    W = pre + post
    nfft = 1 << (int(np.ceil(np.log2(W))) + 2)
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    fm = (f >= band[0]) & (f <= hi)
    lag = np.arange(W) / fs
    win = ss.windows.tukey(W, 0.2)
    feats = np.zeros((N, len(PASS_FEATURE_NAMES)))
    grid = SIZE_GRID_MM * 1e-3
    for i in range(N):
        idx, e2 = pass_times(Y[i], fs, per[i], (band[0], hi))
        idx = idx[0]
        idx = idx[(idx - pre >= 0) & (idx + post <= T)]
        if idx.size == 0:
            continue
        segs = np.stack([Y[i, k - pre:k + post] for k in idx])
        envs = np.stack([e2[k - pre:k + post] for k in idx])
        env = envs.mean(axis=0)
        env = env / max(env[pre], 1e-300)
        q = grid / v[i]
        feats[i, 0:15] = np.interp(lag[pre] - q, lag, env)
        # autocorrelation of each pass (pass-by-pass, then averaged: phases of the ringing differ)
        Fseg = np.fft.rfft(segs * win, nfft, axis=1)
        P = np.mean(np.abs(Fseg) ** 2, axis=0)
        ac = np.fft.irfft(P, nfft)[:W]
        ac = ac / max(ac[0], 1e-300)
        feats[i, 15:30] = np.interp(q, lag, ac)
        lp = np.log(np.maximum(P[fm], 1e-300 * P.max()))
        lp = lp - lp.mean()
        # cepstrum over the analysed band: cos transform at the lags q
        ff = f[fm]
        cq = np.array([np.mean(lp * np.cos(2 * np.pi * ff * qq)) for qq in q]) / max(lp.std(), 1e-12)
        feats[i, 30:45] = cq
        pn = P[fm] / P[fm].sum()
        cen = float(np.sum(ff * pn))
        feats[i, 45] = cen / 1e3
        feats[i, 46] = float(np.sqrt(np.sum((ff - cen) ** 2 * pn))) / 1e3
        tail = env[pre:pre + post]
        j = np.argmax(tail < np.exp(-1.0)) if np.any(tail < np.exp(-1.0)) else post - 1
        feats[i, 47] = 1.0 / max(j / fs * 1e3, 1e-3)
        feats[i, 48] = v[i] / (0.45 * fs) * 1e3
    return feats
