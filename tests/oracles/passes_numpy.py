"""The NumPy pass-to-pass variability (the package's former host twin of
:func:`bearingsim.dynamics.passes.pass_variability`): per-pass factors and delays from NumPy
generators seeded by an integer, the raised-cosine windows, the strike mask.  An independent
oracle for the tests only (the package draws from keys, in JAX)."""
from __future__ import annotations

import numpy as np

from bearingsim.errors import InputError

__all__ = ["pass_factors", "pass_variation", "vary_passes", "strike_mask"]

def pass_factors(rng: np.random.Generator, n, cv) -> np.ndarray:
    """``n`` log-normal factors with mean square 1 and coefficient of variation ``cv``
    (all 1 for cv = 0): ``exp(s xi - s^2)``, ``s^2 = ln(1 + cv^2)``, xi standard normal."""
    cv = float(cv)
    if cv < 0:
        raise InputError(f"cv must be >= 0, got {cv}",
                         "cv is the coefficient of variation of the pass factors, 0 for none")
    xi = rng.standard_normal(int(n))
    s2 = np.log1p(cv * cv)
    return np.exp(np.sqrt(s2) * xi - s2)


def pass_variation(x, fs, pass_times, cv, jitter, seed, strike_probability=1.0):
    """(varied x, factors, delays): :func:`vary_passes` of ``x`` with log-normal factors of
    coefficient of variation ``cv`` (:func:`pass_factors`) and Gaussian delays of standard
    deviation ``jitter`` x the mean pass interval, drawn (factors first, then delays) from
    ``numpy.random.default_rng(SeedSequence([seed, 9]))``: stream 9 of the run's realism seed,
    apart from the engine's slip, fluctuation and noise streams.  ``strike_probability`` < 1:
    each pass's factor is also multiplied by :func:`strike_mask` (stream 10; the part before the
    first pass keeps its factor).  ``cv = jitter = 0`` and probability 1 return ``x`` itself (and
    the draws, unused)."""
    tp = np.asarray(pass_times, dtype=float)
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 9]))
    fac = pass_factors(rng, tp.size + 1, cv)
    T = float(np.mean(np.diff(tp))) if tp.size > 1 else 0.0
    shifts = float(jitter) * T * rng.standard_normal(tp.size + 1)
    if strike_probability < 1.0:
        fac[1:] *= strike_mask(np.random.default_rng(np.random.SeedSequence([int(seed), 10])), tp.size,
                               strike_probability)
    if cv > 0 or jitter > 0 or strike_probability < 1.0:
        x = vary_passes(x, fs, tp, fac, shifts)
    return x, fac, shifts


def _ramp(t, edge, width):
    u = np.clip((t - edge) / width + 0.5, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * u)


def vary_passes(x, fs, pass_times, factors, shifts=None, lead=0.15, taper=0.1) -> np.ndarray:
    """Scale (and delay) the part of ``x`` (sampled at ``fs``) that belongs to each spall pass.

    Pass k owns ``[t_k - lead T, t_{k+1} - lead T)`` (T the mean pass interval): the ball enters
    the spall shortly before its centre passes and the structure rings afterwards.  Neighbouring
    windows overlap in raised-cosine tapers ``taper T`` wide (a partition of unity).  Piece k is
    multiplied by ``factors[k]`` and delayed by ``shifts[k]`` seconds (linear interpolation;
    default none), and the pieces are added.  There is one factor/shift per pass time plus one
    (index 0) for the part before the first pass; ``x`` is de-meaned first and the mean added
    back.  All factors 1 and no shifts return ``x``.
    """
    x = np.asarray(x, dtype=float)
    tp = np.sort(np.asarray(pass_times, dtype=float))
    factors = np.asarray(factors, dtype=float)
    if factors.size != tp.size + 1:
        raise InputError(f"need len(pass_times) + 1 = {tp.size + 1} factors, got {factors.size}",
                         "one factor per pass plus one (index 0) for the part before the first pass")
    shifts = np.zeros(factors.size) if shifts is None else np.asarray(shifts, dtype=float)
    if shifts.size != factors.size:
        raise InputError(f"need {factors.size} shifts (one per factor), got {shifts.size}",
                         "one delay (s) per factor, or shifts=None for none")
    m = x.mean()
    xc = x - m
    t = np.arange(x.size) / float(fs)
    T = float(np.mean(np.diff(tp))) if tp.size > 1 else max(t[-1], 1.0 / float(fs))
    edges = tp - lead * T
    w = taper * T
    # piece k is nonzero only between its rising and its falling taper: each is evaluated there
    # (one sample of zeros either side, so a delayed piece interpolates to zero exactly as over
    # the whole record); the sum is the same, element by element, as over the whole record
    n = x.size
    K = edges.size
    lo = np.searchsorted(t, edges - 0.5 * w, side="left")       # first sample a ramp may be > 0
    hi = np.searchsorted(t, edges + 0.5 * w, side="right")      # first sample past the ramp
    out = np.zeros(n)
    for k in range(factors.size):
        a = 0 if k == 0 else max(int(lo[k - 1]) - 1, 0)
        b = n if k == K else min(int(hi[k]) + 1, n)
        if b <= a:
            continue
        ts = t[a:b]
        win = (1.0 if k == 0 else _ramp(ts, edges[k - 1], w)) - (_ramp(ts, edges[k], w) if k < K else 0.0)
        piece = factors[k] * win * xc[a:b]
        if shifts[k] != 0.0:
            j0 = int(np.searchsorted(t, ts[0] + shifts[k], side="left"))
            j1 = int(np.searchsorted(t, ts[-1] + shifts[k], side="right"))
            if j1 > j0:
                out[j0:j1] += np.interp(t[j0:j1] - shifts[k], ts, piece, left=0.0, right=0.0)
        else:
            out[a:b] += piece
    return out + m


def strike_mask(rng: np.random.Generator, n, probability) -> np.ndarray:
    """``n`` pass factors that are 1 where the defect strikes and 0 where it does not, each pass
    independently with ``probability`` (1: every pass).  A ball pit meets the raceways only
    while the ball's spin axis keeps it on the rolling track; the axis wanders, so a real ball
    fault strikes on some passes and not on others (the rig's 0.007 in ball record: kurtosis 3.0,
    no stable 2 BSF line)."""
    p = float(probability)
    if not 0.0 <= p <= 1.0:
        raise InputError(f"strike probability must be within [0, 1], got {p}",
                         "1 strikes on every pass, 0 on none")
    return (rng.random(int(n)) < p).astype(float)
