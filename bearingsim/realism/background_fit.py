"""Fits of a machine's background vibration to a record (the inverse of
``background_signal`` of the NumPy oracle (tests/oracles/background_numpy.py); used by ``bearingsim calibrate``,
:mod:`bearingsim.realism.machine`, whose docstring states every method).  NumPy / SciPy on arrays in
m/s^2 and Hz; no files."""
from __future__ import annotations

import math

import numpy as np
import scipy.signal as ss

__all__ = ["SHAFT_HARMONICS", "LINE_HARMONICS", "MODULATION_HARMONICS", "PSD_POINTS", "KNOCK_SIGMA",
           "MAX_ANALYSIS_SAMPLES", "LSQ_BLOCK", "shaft_speed", "supply_lines", "fit_lines", "analysed_length",
           "fit_knocks", "broadband_shape", "modulation_depths", "psd_resonances"]

SHAFT_HARMONICS = 6
LINE_HARMONICS = 4
#: shaft-rate modulation of the broadband part fitted at k f_r, k = 1..MODULATION_HARMONICS
MODULATION_HARMONICS = 8
PSD_POINTS = 48
#: knock threshold: the band-passed envelope over this many robust standard deviations
KNOCK_SIGMA = 7.0
#: the machine fits analyse at most this many samples of a record (its first 2^22: 349.5 s at
#: 12 kHz, 87.4 s at 48 kHz; the CWRU records are 10 s): the memory stays bounded
MAX_ANALYSIS_SAMPLES = 1 << 22
#: samples per block of the least-squares line fit (:func:`fit_lines`)
LSQ_BLOCK = 1 << 16


def _amplitude_spectrum(x, fs, pad=4):
    n = x.size
    w = np.hanning(n)
    nfft = 1 << (int(np.ceil(np.log2(n))) + int(np.log2(pad)))
    A = 2.0 * np.abs(np.fft.rfft((x - x.mean()) * w, nfft)) / w.sum()
    return np.fft.rfftfreq(nfft, 1.0 / fs), A


def _excess_db(f, A, span_hz):
    """dB of A over its running median (window ``span_hz``)."""
    from scipy.ndimage import median_filter

    k = max(5, int(round(span_hz / (f[1] - f[0]))) | 1)
    med = median_filter(A, size=k, mode="nearest")
    return 20.0 * np.log10(np.maximum(A, 1e-300) / np.maximum(med, 1e-300))


def shaft_speed(x, fs, nominal_hz, harmonics=SHAFT_HARMONICS, search=0.10) -> float:
    """Shaft frequency (Hz) of a record: harmonic search within +-``search`` of ``nominal_hz``."""
    fmax = min((harmonics + 1) * nominal_hz * (1 + search), 0.45 * fs)
    f, A = _amplitude_spectrum(x, fs)
    m = f <= fmax + 10.0
    f, E = f[m], _excess_db(f[m], A[m], max(4.0, 0.3 * nominal_hz))
    df = f[1] - f[0]
    cand = np.arange(nominal_hz * (1 - search), nominal_hz * (1 + search), df / 16.0)
    ks = np.arange(1, harmonics + 1)
    tot = np.zeros(cand.size)
    for k in ks:
        tot += np.maximum(np.interp(k * cand, f, E), 0.0)
    return float(cand[int(np.argmax(tot))])


def supply_lines(x, fs, shaft_hz, T):
    """(line frequency, kept harmonic numbers, dB excess) of the better of 50 / 60 Hz."""
    f, A = _amplitude_spectrum(x, fs)
    E = _excess_db(f, A, 8.0)
    res = 1.0 / T
    best = (60.0, [], -np.inf)
    for F in (50.0, 60.0):
        kept, ex = [], []
        for l in range(1, LINE_HARMONICS + 1):
            fl = l * F
            if fl >= 0.45 * fs:
                break
            k = max(1, round(fl / shaft_hz))
            if abs(fl - k * shaft_hz) < 3.0 * res:
                continue
            kept.append(l)
            m = np.abs(f - fl) <= max(2.0 * res, 0.002 * fl)
            ex.append(float(E[m].max()))
        score = float(np.mean(ex)) if ex else -np.inf
        if score > best[2]:
            best = (F, kept, score)
    return best


def fit_lines(x, fs, shaft_hz, line_hz=None, line_harmonics=(), block=LSQ_BLOCK):
    """Least-squares amplitudes (m/s^2 if ``x`` is) of the shaft harmonics k = 1..6 and the given
    supply harmonics; returns (shaft amplitudes, line amplitudes (one per harmonic 1..max,
    0 where left out), the fitted lines as a record).

    The normal equations (a constant, a cosine and a sine per line: at most 21 columns) are summed
    over blocks of ``block`` samples and the lines evaluated block by block, so the memory is that
    of the record and one block (the whole design matrix of a 1-hour 12 kHz record was 6.8 GiB);
    the columns are nearly orthogonal (the lines kept are >= 3 resolution bins apart), so the
    normal equations lose nothing against a QR of the whole matrix (tests/test_calibrate_memory.py)."""
    x = np.asarray(x, float)
    n = x.size
    freqs = [k * shaft_hz for k in range(1, SHAFT_HARMONICS + 1)]
    nl = max(line_harmonics, default=0)
    freqs += [l * line_hz for l in line_harmonics]
    use = [i for i, fk in enumerate(freqs) if fk < 0.45 * fs]
    w = 2 * np.pi * np.asarray([freqs[i] for i in use], float)
    block = max(1, int(block))

    def design(a, b):           # the transposed design matrix of samples a..b: (columns, samples)
        phase = np.outer(w, np.arange(a, b) / fs)
        D = np.empty((1 + 2 * w.size, b - a))
        D[0] = 1.0
        D[1::2] = np.cos(phase)
        D[2::2] = np.sin(phase)
        return D

    G = np.zeros((1 + 2 * w.size,) * 2)
    r = np.zeros(1 + 2 * w.size)
    for a in range(0, n, block):
        D = design(a, min(n, a + block))
        G += np.einsum("ij,kj->ik", D, D)      # einsum, not BLAS: a loaded machine's BLAS threads
        r += np.einsum("ij,j->i", D, x[a:a + block])    # were 10-50x slower here
    c, *_ = np.linalg.lstsq(G, r, rcond=None)
    amps = np.zeros(len(freqs))
    for j, i in enumerate(use):
        amps[i] = math.hypot(c[1 + 2 * j], c[2 + 2 * j])
    lines = np.empty(n)
    for a in range(0, n, block):
        b = min(n, a + block)
        lines[a:b] = np.einsum("i,ij->j", c[1:], design(a, b)[1:])
    shaft = amps[:SHAFT_HARMONICS]
    line = np.zeros(nl)
    for l, a in zip(line_harmonics, amps[SHAFT_HARMONICS:]):
        line[l - 1] = a
    return shaft, line, lines


def analysed_length(samples, max_samples=None) -> int:
    """How many samples of a record of ``samples`` samples the machine fits analyse: all of it, or
    the first :data:`MAX_ANALYSIS_SAMPLES` (``max_samples``), so that the memory of
    ``bearingsim calibrate`` is bounded whatever the record's length (the zero-padded spectra
    of :func:`shaft_speed` and :func:`supply_lines` and the envelopes: measured peak ~90 bytes
    per analysed sample, 378 MB for a 10-min 12 kHz record; a 1-hour 12 kHz record asked for
    6.8 GiB in :func:`fit_lines` alone before)."""
    cap = MAX_ANALYSIS_SAMPLES if max_samples is None else int(max_samples)
    return int(min(int(samples), cap))


def fit_knocks(r, fs, sigma=KNOCK_SIGMA):
    """(rate Hz, median peak amplitude, mask of the samples outside knock segments) of a residual."""
    sos = ss.butter(4, [1000.0, 0.45 * fs], btype="bandpass", fs=fs, output="sos")
    y = ss.sosfiltfilt(sos, r)
    s = 1.4826 * np.median(np.abs(y - np.median(y)))
    env = np.abs(ss.hilbert(y))
    over = np.flatnonzero(env > sigma * s)
    keep = np.ones(r.size, bool)
    if over.size == 0 or s == 0:
        return 0.0, 0.0, keep
    gap = int(0.005 * fs)
    starts = [over[0]] + [over[i + 1] for i in np.flatnonzero(np.diff(over) > gap)]
    ends = [over[i] for i in np.flatnonzero(np.diff(over) > gap)] + [over[-1]]
    peaks = []
    for a, b in zip(starts, ends):
        peaks.append(float(np.max(np.abs(y[a:b + 1]))))
        keep[max(0, a - int(0.002 * fs)):a + int(0.020 * fs)] = False
    return len(starts) / (r.size / fs), float(np.median(peaks)), keep


def broadband_shape(r, fs, points=PSD_POINTS):
    """(frequencies Hz, levels dB) of the residual's Welch PSD averaged over ``points``
    log-spaced bands from 50 Hz to 0.45 fs."""
    nper = 1 << int(round(np.log2(fs / 10.0)))
    f, P = ss.welch(r, fs=fs, nperseg=min(nper, r.size))
    edges = np.geomspace(50.0 / 2 ** (1 / 8), 0.45 * fs, points + 1)
    centres = np.sqrt(edges[:-1] * edges[1:])
    lev = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (f >= lo) & (f < hi)
        v = P[m].mean() if m.any() else np.interp(np.sqrt(lo * hi), f, P)
        lev.append(10.0 * np.log10(max(v, 1e-300)))
    return centres, np.asarray(lev)


def modulation_depths(r, fs, shaft_hz, lo_hz, orders=(1, 2), keep=None):
    """Shaft-rate modulation depths of a broadband residual (see the module docstring); ``keep``:
    mask of the samples that count (outside knocks)."""
    sos = ss.butter(4, [lo_hz, 0.45 * fs], btype="bandpass", fs=fs, output="sos")
    e = np.abs(ss.hilbert(ss.sosfiltfilt(sos, r))) ** 2
    t = np.arange(e.size) / fs
    if keep is not None:
        e, t = e[keep], t[keep]
    mean = e.mean()
    ec = e - mean

    def proj(fq):
        return 2.0 * abs(np.mean(ec * np.exp(-2j * np.pi * fq * t)))

    out = []
    for k in orders:
        line = proj(k * shaft_hz)
        off = [proj((k + s * d) * shaft_hz) for d in (0.23, 0.31, 0.37) for s in (-1, 1)]
        a = math.sqrt(max(line ** 2 - float(np.mean(np.square(off))), 0.0))
        out.append(min(a / (2.0 * mean), 0.9) if mean > 0 else 0.0)
    return np.asarray(out)


def psd_resonances(r, fs, count, lo_hz=1000.0, smooth_hz=100.0):
    """[(frequency Hz, damping ratio, prominence dB)] of the strongest PSD peaks (at most
    ``count``) between ``lo_hz`` and 0.45 fs (see the module docstring)."""
    nper = 1 << int(round(np.log2(fs / 10.0)))
    f, P = ss.welch(r, fs=fs, nperseg=min(nper, r.size))
    from scipy.ndimage import median_filter

    df = f[1] - f[0]
    k = max(1, int(round(smooth_hz / df)))
    Pm = median_filter(P, size=max(3, int(round(1.5 * smooth_hz / df)) | 1), mode="nearest")
    Ps = np.convolve(Pm, np.ones(k) / k, mode="same")
    m = (f >= lo_hz) & (f <= 0.45 * fs)
    fb, Pb = f[m], Ps[m]
    L = 10.0 * np.log10(np.maximum(Pb, 1e-300))
    pk, prop = ss.find_peaks(L, prominence=3.0)
    if pk.size == 0:
        return []
    order = np.argsort(prop["prominences"])[::-1]
    widths = ss.peak_widths(Pb, pk[order], rel_height=0.5)[0] * df
    out = []
    for j, w in zip(order, widths):
        fn = float(fb[pk[j]])
        w_true = math.sqrt(max(w * w - (k * df) ** 2, 0.0))
        if w_true < 2.0 * df:         # no wider than the smoothing: a tone, not a resonance
            continue
        zeta = float(np.clip(w_true / (2.0 * fn), 0.005, 0.3))
        out.append((fn, zeta, float(prop["prominences"][j])))
        if len(out) == count:
            break
    return sorted(out)
