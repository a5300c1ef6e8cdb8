"""Vibration-signal processing: band-pass, squared envelope, envelope spectrum.

This stage sits after the JAX dynamics and works on plain NumPy arrays (SciPy
filters and FFTs).  It implements the classical envelope analysis of Randall &
Antoni (docs/model.md §8): band-pass the signal around a resonance excited by the
spall impacts, take the squared envelope ``|hilbert(x)|**2``, and look at its
spectrum for lines at BPFO and its harmonics.

Conventions
-----------
* All signals are 1-D, finite, real arrays sampled at ``fs`` (Hz).
* Amplitude spectra are one-sided and *amplitude*-normalised for the window
  (coherent gain): a sinusoid ``A cos(2 pi f t)`` whose frequency lies on a bin
  shows a line of height ``A`` (the DC bin is not doubled).  For a squared
  envelope of an acceleration in m/s² the unit is therefore (m/s²)².
* By default spectra are zero-padded by a factor 2 (``nfft = 2 * len(x)``).
  This does not improve the resolution (still ``fs / len(x)``) but halves the
  grid spacing, which makes the 3-point log-parabolic peak interpolation of
  :func:`peak_frequency` accurate to < 0.002 of a native bin for a Hann window
  (without padding its bias reaches 0.016 bin).
* ``scipy.signal`` is imported by the functions that filter, at their first call:
  the modules that import this one (the workflows, the figures) load no SciPy.
"""
from __future__ import annotations

from dataclasses import dataclass
from numbers import Integral

import numpy as np

from ..errors import InputError, InputTypeError
from .checks import check_band, check_fs, check_freq, check_signal, unpack_band

__all__ = [
    "Spectrum",
    "EnvelopeSpectrum",
    "bandpass",
    "squared_envelope",
    "amplitude_spectrum",
    "envelope_spectrum",
    "peak_frequency",
    "harmonic_peaks",
    "select_band",
]


# --------------------------------------------------------------------------- filters
def bandpass(x, fs, f_lo, f_hi, order: int = 4) -> np.ndarray:
    """Zero-phase Butterworth band-pass of ``x`` between ``f_lo`` and ``f_hi`` (Hz).

    Designed as second-order sections (``butter(order, ..., 'bandpass')``, i.e.
    ``2*order`` poles) and applied forward-backward with ``sosfiltfilt``, so the
    phase is zero and the magnitude response is squared.  Requires
    ``0 < f_lo < f_hi < fs/2``.
    """
    import scipy.signal as ss

    fs = check_fs(fs)
    f_lo, f_hi = check_band(f_lo, f_hi, fs)
    if isinstance(order, (bool, np.bool_)) or not isinstance(order, Integral) or order < 1:
        raise InputError(f"order must be an integer >= 1, got {order!r}",
                         "order is the Butterworth order of the band-pass, e.g. 4")
    x = check_signal(x)
    sos = ss.butter(int(order), [f_lo, f_hi], btype="bandpass", fs=fs, output="sos")
    # scipy's default padlen for sosfiltfilt; check it here for a clear message
    n_zeros = min(int((sos[:, 2] == 0).sum()), int((sos[:, 5] == 0).sum()))
    padlen = 3 * (2 * len(sos) + 1 - n_zeros)
    if x.size <= padlen:
        raise InputError(
            f"x is too short ({x.size} samples) for an order-{order} zero-phase band-pass; need > {padlen}",
            "pass a longer record or a lower order",
        )
    return ss.sosfiltfilt(sos, x)


def squared_envelope(x, fs, band=None) -> np.ndarray:
    """Squared envelope ``|hilbert(x_b)|**2`` minus its mean.

    ``x_b`` is ``x`` band-passed to ``band = (f_lo, f_hi)`` (Hz) when a band is
    given (see :func:`bandpass`), else ``x`` itself.  The mean (DC) is removed
    so the envelope spectrum has no line at 0 Hz whose leakage would mask the
    low-order defect lines.
    """
    import scipy.signal as ss

    fs = check_fs(fs)
    x = check_signal(x)
    b = unpack_band(band, fs)
    if b is not None:
        x = bandpass(x, fs, *b)
    se = np.abs(ss.hilbert(x)) ** 2
    return se - se.mean()


# --------------------------------------------------------------------------- spectra
@dataclass(frozen=True, eq=False)
class Spectrum:
    """One-sided, window-normalised amplitude spectrum.

    freqs      : bin frequencies (Hz), spacing ``fs / nfft``
    amplitude  : line amplitudes in the unit of the analysed signal (see module doc)
    band       : the (f_lo, f_hi) band-pass applied before demodulation, or None
    fs         : sampling frequency (Hz)
    window     : window name/spec passed to ``scipy.signal.get_window``
    n_samples  : record length; the true resolution is ``fs / n_samples``
    """

    freqs: np.ndarray
    amplitude: np.ndarray
    band: tuple[float, float] | None
    fs: float
    window: object = "hann"
    n_samples: int = 0

    @property
    def resolution(self) -> float:
        """Native frequency resolution fs / n_samples (Hz), independent of zero padding."""
        return self.fs / self.n_samples

    @property
    def df(self) -> float:
        """Grid spacing of ``freqs`` (Hz)."""
        return float(self.freqs[1] - self.freqs[0])


class EnvelopeSpectrum(Spectrum):
    """Spectrum of the squared envelope (see :func:`envelope_spectrum`)."""


def _spectrum(x, fs, window, nfft, band, cls):
    import scipy.signal as ss

    n = x.size
    if nfft is None:
        nfft = 2 * n
    if isinstance(nfft, (bool, np.bool_)) or not isinstance(nfft, Integral):
        raise InputError(f"nfft must be None or an integer >= len(x) = {n}, got {nfft!r}",
                         "leave nfft=None (2 x len(x)) or pass an integer >= len(x)")
    if nfft < n:
        raise InputError(f"nfft must be >= len(x) = {n} (no truncation), got {nfft}",
                         "leave nfft=None (2 x len(x)) or pass an integer >= len(x)")
    try:
        w = ss.get_window(window, n, fftbins=True)
    except (ValueError, TypeError) as exc:
        raise InputError(f"window {window!r} is not understood by scipy.signal.get_window: {exc}",
                         "a window name such as 'hann' (default), 'hamming' or 'boxcar', or a (name, "
                         "parameter) tuple such as ('kaiser', 8.0)") from exc
    amp = np.abs(np.fft.rfft(x * w, int(nfft))) * (2.0 / w.sum())
    amp[0] *= 0.5
    if nfft % 2 == 0:
        amp[-1] *= 0.5
    freqs = np.fft.rfftfreq(int(nfft), 1.0 / fs)
    return cls(freqs=freqs, amplitude=amp, band=band, fs=fs, window=window, n_samples=n)


def amplitude_spectrum(x, fs, window="hann", nfft=None) -> Spectrum:
    """Plain one-sided amplitude spectrum of ``x`` (no demodulation); ``band`` is None.

    Same normalisation and padding conventions as :func:`envelope_spectrum`; the
    mean of ``x`` is *not* removed.
    """
    fs = check_fs(fs)
    x = check_signal(x)
    return _spectrum(x, fs, window, nfft, None, Spectrum)


def envelope_spectrum(x, fs, band=None, window="hann", nfft=None) -> EnvelopeSpectrum:
    """Squared-envelope spectrum (Randall & Antoni).

    ``x`` is band-passed to ``band`` (if given), squared-enveloped (mean removed),
    windowed with ``window`` (periodic form) and transformed with ``nfft`` points
    (default ``2*len(x)``).  ``amplitude`` is the one-sided magnitude scaled by
    ``2 / sum(window)``, so a squared-envelope component ``a cos(2 pi f t)``
    shows a line of height ``a`` (e.g. for an AM carrier
    ``A (1 + m cos 2 pi f_m t) cos 2 pi f_c t`` the line at ``f_m`` is ``2 m A²``).
    """
    fs = check_fs(fs)
    x = check_signal(x)
    b = unpack_band(band, fs)
    se = squared_envelope(x, fs, b)
    return _spectrum(se, fs, window, nfft, b, EnvelopeSpectrum)


# --------------------------------------------------------------------------- peaks
def _check_spectrum(spectrum):
    if not isinstance(spectrum, Spectrum):
        raise InputTypeError(f"spectrum must be a Spectrum/EnvelopeSpectrum, got {type(spectrum).__name__}",
                             "pass the result of envelope_spectrum() or amplitude_spectrum()")


def _peak(spectrum: Spectrum, f_expected: float, rel_window: float):
    """(f, amplitude) of the largest local maximum within f_expected*(1 ± rel_window); NaNs if none."""
    f = spectrum.freqs
    a = spectrum.amplitude
    df = f[1] - f[0]
    half = max(rel_window * f_expected, 1.5 * df)
    sel = np.flatnonzero((f >= f_expected - half) & (f <= f_expected + half))
    sel = sel[(sel > 0) & (sel < f.size - 1)]          # need both neighbours for interpolation
    if sel.size == 0:
        return np.nan, np.nan
    is_max = (a[sel] >= a[sel - 1]) & (a[sel] > a[sel + 1])
    cand = sel[is_max]
    if cand.size == 0:
        return np.nan, np.nan
    k = int(cand[np.argmax(a[cand])])
    y0, y1, y2 = a[k - 1], a[k], a[k + 1]
    if min(y0, y1, y2) > 0.0:                           # quadratic on log amplitude
        l0, l1, l2 = np.log(y0), np.log(y1), np.log(y2)
        den = l0 - 2.0 * l1 + l2
        p = 0.5 * (l0 - l2) / den if den < 0.0 else 0.0
        p = float(np.clip(p, -0.5, 0.5))
        amp = float(np.exp(l1 - 0.25 * (l0 - l2) * p))
    else:                                               # plain parabola fallback
        den = y0 - 2.0 * y1 + y2
        p = float(np.clip(0.5 * (y0 - y2) / den, -0.5, 0.5)) if den < 0.0 else 0.0
        amp = float(y1 - 0.25 * (y0 - y2) * p)
    return float(f[k] + p * df), amp


def peak_frequency(spectrum: Spectrum, f_expected, rel_window: float = 0.1) -> float:
    """Frequency (Hz) of the largest peak within ``f_expected * (1 ± rel_window)``.

    The peak is the largest local maximum of ``spectrum.amplitude`` in the
    window (at least ±1.5 grid bins wide); its position is refined by a
    parabola through the log amplitudes of the maximum bin and its two
    neighbours.  With the default 2x zero-padded Hann spectra the bias for a
    clean tone is < 0.002 of a native bin ``fs/len(x)``.
    Raises :class:`~bearingsim.errors.InputError` (a ValueError) if the window holds no local
    maximum.
    """
    _check_spectrum(spectrum)
    f_expected = check_freq(f_expected, "f_expected")
    if f_expected <= 0.0:
        raise InputError(f"f_expected must be > 0 Hz, got {f_expected:g}",
                         "f_expected is the frequency (Hz) of the line to look for, e.g. BPFO")
    if not (0.0 < rel_window < 1.0):
        raise InputError(f"rel_window must be in (0, 1), got {rel_window!r}",
                         "rel_window is the relative half width of the search window, e.g. 0.1 for +- 10 %")
    fp, _ = _peak(spectrum, f_expected, float(rel_window))
    if not np.isfinite(fp):
        raise InputError(
            f"no local maximum within f_expected = {f_expected:g} Hz ± {100 * rel_window:g} % "
            f"(spectrum covers 0–{spectrum.freqs[-1]:g} Hz)",
            "check that f_expected lies inside the spectrum, or widen rel_window",
        )
    return fp


def harmonic_peaks(spectrum: Spectrum, f0, n: int = 5, rel_window: float = 0.05):
    """Measured peaks at the harmonics ``k * f0``, ``k = 1..n``.

    Returns a list of ``(k, f_measured, amplitude)``; each harmonic is searched
    within ``k*f0*(1 ± rel_window)`` as in :func:`peak_frequency` (amplitude is the
    log-parabola vertex).  Harmonics without a local maximum in their window
    (e.g. above Nyquist) give ``(k, nan, nan)``.
    """
    _check_spectrum(spectrum)
    f0 = check_freq(f0, "f0")
    if f0 <= 0.0:
        raise InputError(f"f0 must be > 0 Hz, got {f0:g}", "f0 is the fundamental frequency (Hz) of the harmonics")
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, Integral) or n < 1:
        raise InputError(f"n must be an integer >= 1, got {n!r}", "n is the number of harmonics to measure, e.g. 5")
    if not (0.0 < rel_window < 1.0):
        raise InputError(f"rel_window must be in (0, 1), got {rel_window!r}",
                         "rel_window is the relative half width of each harmonic's window, e.g. 0.05 for +- 5 %")
    out = []
    for k in range(1, int(n) + 1):
        fk, ak = _peak(spectrum, k * f0, float(rel_window))
        out.append((k, fk, ak))
    return out


# --------------------------------------------------------------------------- band selection
def _band_kurtosis(x, fs, edges, trim):
    """Envelope kurtosis  E[e^4]/E[e^2]^2 - 2  (e = |analytic signal|) of each band."""
    import scipy.signal as ss

    k = np.empty(len(edges))
    for i, (lo, hi) in enumerate(edges):
        e2 = np.abs(ss.hilbert(bandpass(x, fs, lo, hi)))[trim: x.size - trim] ** 2
        m2 = e2.mean()
        k[i] = (np.mean(e2 * e2) / (m2 * m2) - 2.0) if m2 > 0.0 else -np.inf
    return k


def select_band(x, fs, resonance_hz=None, bandwidth_hz=None, *, f_min=None, return_kurtosis=False):
    """Demodulation band ``(f_lo, f_hi)`` in Hz.

    * Resonance known: ``resonance_hz ± bandwidth_hz/2`` with default
      ``bandwidth_hz = 0.25 * resonance_hz``, clipped to
      ``[1e-3 * fs/2, 0.98 * fs/2]`` so that it is a valid :func:`bandpass` band.
    * Otherwise (a deliberately simple heuristic, not the fast kurtogram): split
      ``[f_min, fs/2)`` into a 1/3-octave bank (centres ``1000 * 2**(j/3)`` Hz,
      edges ``centre * 2**(∓1/6)``), band-pass ``x`` into each band, take the
      envelope ``e = |hilbert|`` and its kurtosis ``E[e^4]/E[e^2]^2 - 2``
      (0 for Gaussian noise, -1 for a steady tone, > 0 for repetitive impacts;
      5 % of the record is dropped at each end against filter transients).  The
      band with the largest value is returned.  ``f_min`` defaults to ``fs/64``
      so the bands (23 % wide) are wide enough to carry the sidebands at typical
      defect frequencies and avoid low-frequency (shaft, mains) interference.

    With ``return_kurtosis=True`` the heuristic also returns
    ``(band, centres, kurtosis)`` for inspection (``centres``/``kurtosis`` are
    None when the resonance was given).
    """
    fs = check_fs(fs)
    x = check_signal(x)
    nyq = fs / 2.0
    if resonance_hz is not None:
        fr = check_freq(resonance_hz, "resonance_hz")
        if not (0.0 < fr < nyq):
            raise InputError(f"resonance_hz must be in (0, fs/2 = {nyq:g}) Hz, got {fr:g}",
                             "give a resonance below the Nyquist frequency, or None to pick the band by "
                             "envelope kurtosis")
        bw = 0.25 * fr if bandwidth_hz is None else check_freq(bandwidth_hz, "bandwidth_hz")
        if bw <= 0.0:
            raise InputError(f"bandwidth_hz must be > 0 Hz, got {bw:g}",
                             "give a bandwidth in Hz, or None for 0.25 x resonance_hz")
        lo = max(fr - 0.5 * bw, 1e-3 * nyq)
        hi = min(fr + 0.5 * bw, 0.98 * nyq)
        if lo >= hi:
            raise InputError(f"band resonance_hz ± bandwidth_hz/2 = {fr:g} ± {bw / 2:g} Hz is empty after "
                             f"clipping to [{1e-3 * nyq:g}, {0.98 * nyq:g}] Hz (inside fs/2 = {nyq:g} Hz)",
                             "move resonance_hz away from 0 and fs/2, or change bandwidth_hz")
        band = (float(lo), float(hi))
        return (band, None, None) if return_kurtosis else band

    if bandwidth_hz is not None:
        raise InputError(f"bandwidth_hz (= {bandwidth_hz!r}) only applies when resonance_hz is given",
                         "give resonance_hz too, or leave bandwidth_hz None")
    f_min = fs / 64.0 if f_min is None else check_freq(f_min, "f_min")
    if not (0.0 < f_min < nyq):
        raise InputError(f"f_min must be in (0, fs/2 = {nyq:g}) Hz, got {f_min:g}",
                         "f_min is the lowest band edge of the search (Hz); None for fs/64")
    r = 2.0 ** (1.0 / 6.0)
    j = np.arange(np.ceil(3 * np.log2(f_min * r / 1000.0)), np.floor(3 * np.log2(0.98 * nyq / r / 1000.0)) + 1)
    centres = 1000.0 * 2.0 ** (j / 3.0)
    if centres.size == 0:
        raise InputError(f"no 1/3-octave band fits between f_min = {f_min:g} Hz and fs/2 = {nyq:g} Hz",
                         "lower f_min, or analyse a record of a higher sample rate")
    edges = np.column_stack([centres / r, centres * r])
    trim = int(0.05 * x.size)
    kurt = _band_kurtosis(x, fs, edges, trim)
    i = int(np.argmax(kurt))
    band = (float(edges[i, 0]), float(edges[i, 1]))
    return (band, centres, kurt) if return_kurtosis else band


