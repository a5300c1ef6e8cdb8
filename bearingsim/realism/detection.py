"""Is a fault line there?  A detection verdict with a stated false-alarm rate for each fault line
of a squared-envelope spectrum (``bearingsim spectrum RECORD``; issue 34).

The statistic.  A line at ``f0`` is searched in the window ``|f - f0| <= w``, ``w = max(1.5 % f0,
2 bins)``; its strength is the largest bin of the envelope amplitude spectrum in that window over
the *local* floor, the median of the ring ``w < |f - f0| <= 6 w`` around it (dB, 20 log10 of the
amplitude ratio).  Level-free: a gain, a unit or a weak healthy record (the HIT normals are ~150x
weaker than their fault records) changes nothing.

Its null distribution.  Without a line, the bins of a long record's envelope spectrum are complex
Gaussian, their powers exponential.  With ``n`` bins in the window and ``m`` in the ring, of which
every ``k`` = :data:`NULL_BINS_PER_TRIAL` make one independent trial (Hann window, 2x zero padding:
neighbouring bins are correlated), the largest power of ``n / k`` exponentials exceeds ``r`` times
the median ``y`` of ``m / k`` others with probability ``E_y[1 - (1 - exp(-r y)) ** (n / k)]``, the
median's distribution that of the middle order statistic (:func:`null_exceedance`).  ``n`` and
``m`` grow with the record's length and the line's frequency (resolution), so the threshold does
too: a 1 s record's window holds ~5-12 bins, a 10 s record's up to ~120.  ``k`` is fitted on
white Gaussian noise analysed as the command analyses a record (the tail at 1-20 %).

The healthy margin.  Real healthy machines are not Gaussian noise: shaft-rate modulation, supply
lines, a line near a bearing order (the HIT rig at 1200 rpm).  :data:`HEALTHY_MARGIN_DB` is the dB
added to the null quantile so that at most :data:`FALSE_ALARM` of the lines at arbitrary non-integer
orders of the shaft (0.3-6.5 x, the 6205's fault lines' range, windows clear of shaft harmonics)
exceed it on each healthy source (the largest of their margins, so the rate is an upper bound on
each): :data:`HEALTHY_SOURCES`, the records the numbers came from
(fitted from healthy data only, never from a fault record: ``benchmarks/fit_detection.py`` refits
and prints them; the rates it measured are :data:`MEASURED_RATES`).

A line whose window holds a shaft harmonic gets no verdict (the shaft's own line is no bearing
fault), nor does one beyond the demodulation band's width (the envelope cannot carry it).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np
from scipy import optimize, special

from ..errors import InputError

__all__ = ["LINE_WINDOW", "FLOOR_RING", "FALSE_ALARM", "NULL_BINS_PER_TRIAL", "HEALTHY_MARGIN_DB",
           "HEALTHY_SOURCES", "MEASURED_RATES", "MEASURED_LENGTHS_S", "LineVerdict", "LineStrength",
           "line_window", "line_strength", "shaft_harmonic", "null_exceedance", "null_threshold_db",
           "detection_threshold_db", "line_verdicts", "provenance"]

#: a line's search half-window (relative; at least two bins), as in bearingsim.signals.features
LINE_WINDOW = 0.015
#: the local floor: the median over w < |f - f0| <= FLOOR_RING * w
FLOOR_RING = 6.0
#: the stated false-alarm rate per line
FALSE_ALARM = 0.01
#: bins per independent trial of the null model: fitted on white Gaussian noise (records of 1-10 s
#: at 12 kHz, seed 2026, 5176 lines) by benchmarks/fit_detection.py (its tail rates at 1/5/10/20 %:
#: 0.75/4.5/9.8/19.2 % over all)
NULL_BINS_PER_TRIAL = 2.1
#: dB added to the null quantile so that healthy machines keep the rate: the largest of the three
#: sources' margins (CWRU 97: +2.15 dB, HIT-MFS normals: +1.49 dB, simulated healthy: +4.43 dB; the
#: simulated background carries lines near bearing orders by design), benchmarks/fit_detection.py
HEALTHY_MARGIN_DB = 4.43
#: the record lengths (s) the rate was measured at (segments of 1 s, 2 s and whole records: no healthy
#: record is longer); the real rigs' rate grows with the length (HIT: 0.0 / 0.2 / 0.9 % at 1 / 2 /
#: 5.1 s; a healthy machine's own lines stand out more with a finer resolution)
MEASURED_LENGTHS_S = (1.0, 5.12)
#: where HEALTHY_MARGIN_DB came from (healthy data only)
HEALTHY_SOURCES = ("CWRU 97 (normal, DE, 48 kHz and its 12 kHz copy)", "HIT-MFS normal 600/900/1200 rpm",
                   "8 simulated healthy items of dataset_cwru_4class (seed 7, 2 s, 12 kHz)")
#: the false-alarm rate per line measured at the threshold on each source, in the order of
#: HEALTHY_SOURCES: (lines, rate)
MEASURED_RATES = {"CWRU 97": (1148, 0.0), "HIT-MFS normal": (1624, 0.0018), "simulated healthy": (2304, 0.0100)}


@dataclass(frozen=True)
class LineVerdict:
    """One fault line: where it was expected and found (Hz), its strength and the threshold (dB
    over the local floor), the bins searched, ``detected`` (True / False, None: no verdict), why
    there is none (``note``), the search window's half-width (Hz) and the local floor (the
    spectrum's amplitude unit: the threshold's level is ``floor * 10 ** (threshold_db / 20)``)."""

    name: str
    expected_hz: float
    peak_hz: float
    strength_db: float
    threshold_db: float
    bins: int
    detected: bool | None
    note: str = ""
    window_hz: float = float("nan")
    floor: float = float("nan")
    false_alarm: float = FALSE_ALARM

    @property
    def verdict(self) -> str:
        return {True: "detected", False: "not detected", None: "no verdict"}[self.detected]


def line_window(f0, df) -> float:
    """The half-width (Hz) of the search window of a line at ``f0`` in a spectrum of bin ``df``."""
    return max(LINE_WINDOW * float(f0), 2.0 * float(df))


class LineStrength(NamedTuple):
    """A line's strength: the peak (Hz), dB over the local floor, the bins of the window and of the
    floor's ring, the floor (the spectrum's amplitude unit)."""

    peak_hz: float
    strength_db: float
    bins: int
    ring_bins: int
    floor: float


def line_strength(freqs, amplitude, f0) -> LineStrength:
    """The :class:`LineStrength` of a line at ``f0`` Hz in a spectrum (``freqs`` evenly spaced from
    0, ``amplitude`` >= 0); NaNs and 0 bins when the window or the ring is outside the spectrum."""
    f, S = np.asarray(freqs, float), np.asarray(amplitude, float)
    df = f[1] - f[0]
    w = line_window(f0, df)
    d = np.abs(f - float(f0))
    win = np.flatnonzero(d <= w)
    ring = (d > w) & (d <= FLOOR_RING * w) & (f > 2.0 * df)
    if win.size == 0 or ring.sum() < 4 or float(f0) + FLOOR_RING * w > f[-1]:
        return LineStrength(float("nan"), float("nan"), 0, 0, float("nan"))
    k = win[int(np.argmax(S[win]))]
    floor = max(float(np.median(S[ring])), 1e-300)
    return LineStrength(float(f[k]), float(20.0 * np.log10(max(S[k], 1e-300) / floor)), int(win.size),
                        int(ring.sum()), floor)


#: quantile midpoints of the median's distribution (the expectation over it)
_GRID = (np.arange(64) + 0.5) / 64.0


def null_exceedance(strength_db, bins, ring_bins, bins_per_trial=None):
    """The probability that a window of ``bins`` bins of Gaussian noise's envelope spectrum shows a
    strength over ``strength_db`` against the median of ``ring_bins`` bins (the null model of the
    module's docstring; ``bins_per_trial``: default :data:`NULL_BINS_PER_TRIAL`).  Arrays broadcast."""
    k = NULL_BINS_PER_TRIAL if bins_per_trial is None else float(bins_per_trial)
    r = 10.0 ** (np.asarray(strength_db, float)[..., None] / 10.0)
    n = np.maximum(np.asarray(bins, float) / k, 1.0)[..., None]
    m = np.maximum(np.asarray(ring_bins, float) / k, 1.0)[..., None]
    half = 0.5 * (m + 1.0)
    u = special.betaincinv(half, m - half + 1.0, _GRID)      # F(median) of m exponentials, at its quantiles
    q = (1.0 - u) ** r                                       # exp(-r * median)
    p = np.mean(-np.expm1(n * np.log1p(-q)), axis=-1)
    return float(p) if p.ndim == 0 else p


def null_threshold_db(bins, ring_bins, false_alarm=FALSE_ALARM) -> float:
    """The strength (dB) that pure Gaussian noise exceeds with probability ``false_alarm`` in a
    window of ``bins`` bins against a ring of ``ring_bins`` (:func:`null_exceedance`)."""
    p = float(false_alarm)
    if not 0.0 < p < 1.0:
        raise InputError(f"false_alarm = {p!r}: a probability in (0, 1)", "e.g. 0.01 for 1 % per line")
    for name, v in (("bins", bins), ("ring_bins", ring_bins)):
        if not (np.isfinite(v) and v >= 1):
            raise InputError(f"{name} = {v!r}: a number of spectrum bins >= 1", "see line_strength")
    return _quantile(int(bins), int(ring_bins), p, float(NULL_BINS_PER_TRIAL))


@lru_cache(maxsize=4096)
def _quantile(bins, ring_bins, p, bins_per_trial):
    f = lambda db: null_exceedance(db, bins, ring_bins, bins_per_trial) - p      # noqa: E731
    return float(optimize.brentq(f, 0.0, 60.0, xtol=1e-4))


def detection_threshold_db(bins, ring_bins) -> float:
    """The detection threshold (dB over the local floor) of a window of ``bins`` bins against a
    ring of ``ring_bins``: the null quantile at :data:`FALSE_ALARM` plus :data:`HEALTHY_MARGIN_DB`."""
    return null_threshold_db(bins, ring_bins) + HEALTHY_MARGIN_DB


def shaft_harmonic(f0, shaft_hz, df) -> int:
    """The shaft harmonic k >= 1 within a bin of the window of a line at ``f0``, or 0."""
    w = line_window(f0, df)
    k = int(round(float(f0) / float(shaft_hz)))
    return k if k >= 1 and abs(k * shaft_hz - f0) <= w + df else 0


def line_verdicts(spectrum, lines: dict, shaft_hz, band_width_hz=None, reference=("shaft",)) -> dict:
    """name -> :class:`LineVerdict` of each line of ``lines`` (name -> Hz) in ``spectrum`` (an
    envelope spectrum: ``freqs``, ``amplitude``); ``reference``: lines reported without a verdict
    (the shaft); ``band_width_hz``: the demodulation band's width (lines beyond it get none)."""
    f = np.asarray(spectrum.freqs, float)
    df = f[1] - f[0]
    out = {}
    for name, f0 in lines.items():
        f0 = float(f0)
        peak, db, n, m, floor = line_strength(f, spectrum.amplitude, f0)
        w = line_window(f0, df)
        thr = detection_threshold_db(n, m) if n else float("nan")
        note, k = "", shaft_harmonic(f0, shaft_hz, df)
        if name in reference:
            note = "reference line"
        elif n == 0:
            note = "window or floor outside the spectrum"
        elif band_width_hz is not None and f0 + FLOOR_RING * w > float(band_width_hz):
            note = f"beyond the demodulation band's width ({float(band_width_hz):.0f} Hz)"
        elif k:
            note = f"shaft harmonic {k}x in the window"
        out[name] = LineVerdict(name, f0, peak, db, thr, n, None if note else bool(db > thr), note, w, floor)
    return out


def provenance(seconds=None) -> str:
    """One line: the rate, how the threshold is made and the records it was measured on; for a
    record of ``seconds`` outside :data:`MEASURED_LENGTHS_S`, a warning that the rate was not
    measured at that length."""
    measured = "; ".join(f"{100 * r:.1f} % of {n} lines on {src}"
                         for src, (n, r) in zip(HEALTHY_SOURCES, MEASURED_RATES.values()))
    lo, hi = MEASURED_LENGTHS_S
    warn = ""
    if seconds is not None and not lo * 0.999 <= float(seconds) <= hi * 1.001:
        warn = (f". This record is {float(seconds):.3g} s, outside the {lo:g}-{hi:g} s the rate was measured at"
                + (": a healthy machine's own lines stand out more in a longer record, the rate may be higher"
                   if seconds > hi else ": the rate may differ"))
    return (f"threshold: at most {100 * FALSE_ALARM:g} % false alarms per line on a healthy machine: the noise "
            f"quantile of the window's bins + {HEALTHY_MARGIN_DB:.1f} dB; measured {measured}{warn}")
