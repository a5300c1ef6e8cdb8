"""Pass-to-pass variability of a defect's impacts (docs/realism.md): a record's housing
acceleration scaled and delayed pass by pass (log-normal factors, Gaussian delays, strikes that
miss), every draw from the record's ``jax.random`` key, then put through the sensor path again.
One version for a single run (:func:`bearingsim.dynamics.simulate`) and a data set item (the
signal stage, :mod:`bearingsim.signals.signal_stage`); the NumPy oracle is
tests/oracles/passes_numpy.py."""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..keys import stream_key
from ..programs import jit
from .sensor import run_filter, sensor_filter

__all__ = ["PassSettings", "pass_factors", "pass_shifts", "strike_factors", "vary_passes", "pass_variability"]


class PassSettings(NamedTuple):
    """The static settings of :func:`pass_variability` (hashable: one program per value)."""

    fs: float                       # sample rate (Hz)
    pass_cv_max: float = 0.0        # c.v. of the pass factors at unbridged fraction 1
    pass_delay_max: float = 0.0     # delay s.d. / mean pass interval at fraction 1
    pass_lead: float = 0.15         # a pass's piece starts this fraction of an interval before it
    pass_taper: float = 0.1         # raised-cosine taper between pieces (fraction of an interval)
    strikes: bool = False           # whether a pass may miss (a strike probability below 1)
    exposure: bool = False          # a ball pit's per-pass exposure replaces the strikes (issue 33)


def _mean_interval(tp):
    """Mean interval of the finite (sorted, +inf padded) pass times; 0 for fewer than two."""
    ok = jnp.isfinite(tp)
    k = jnp.sum(ok)
    d = jnp.where(ok[1:], tp[1:] - tp[:-1], 0.0)
    return jnp.where(k > 1, jnp.sum(d) / jnp.maximum(k - 1, 1), 0.0)


def pass_factors(key, n, cv):
    """``pass_factors`` of the NumPy oracle (tests/oracles/passes_numpy.py) from a key: ``exp(s xi - s^2)``, ``s^2 = ln(1 + cv^2)``."""
    s2 = jnp.log1p(cv * cv)
    return jnp.exp(jnp.sqrt(s2) * jax.random.normal(key, (n,), jnp.float64) - s2)


def pass_shifts(key, pass_times, jitter):
    """Gaussian pass delays (s), one per pass slot plus one: ``jitter`` x the mean pass interval
    (0 with fewer than two passes) x standard normals."""
    n = pass_times.shape[0] + 1
    return jitter * _mean_interval(pass_times) * jax.random.normal(key, (n,), jnp.float64)


def strike_factors(key, n, probability):
    """``strike_mask`` of the NumPy oracle (tests/oracles/passes_numpy.py) from a key: 1 where a pass strikes (probability
    ``probability``), else 0."""
    return (jax.random.uniform(key, (n,)) < probability).astype(jnp.float64)


def _ramp(t, sin_a, cos_a, edge, width):
    """The raised-cosine ramp 0 -> 1 of ``width`` centred on ``edge`` (+inf: 0) at the samples
    ``t``: ``0.5 + 0.5 sin(pi (t - e) / w)`` inside, by the angle-difference formula from
    ``sin_a``, ``cos_a`` = sin, cos of ``pi t / w`` (no transcendental per sample and edge)."""
    fin = jnp.isfinite(edge)
    e = jnp.where(fin, edge, 0.0)
    b = np.pi * e / width
    inner = 0.5 + 0.5 * (sin_a * jnp.cos(b) - cos_a * jnp.sin(b))
    d = t - e
    r = jnp.where(d <= -0.5 * width, 0.0, jnp.where(d >= 0.5 * width, 1.0, inner))
    return jnp.where(fin, r, 0.0)


def _delay(y, d):
    """``y`` (uniformly sampled) delayed by ``d`` samples, linear between samples, 0 outside
    (``numpy.interp(t - d / fs, t, y, left=0, right=0)``)."""
    n = y.shape[0]
    p = jnp.arange(n, dtype=jnp.float64) - d
    j = jnp.clip(jnp.floor(p), 0, n - 2).astype(jnp.int32)
    frac = p - j
    v = y[j] + frac * (y[j + 1] - y[j])
    return jnp.where((p >= 0) & (p <= n - 1), v, 0.0)


def vary_passes(x, fs, pass_times, factors, shifts, lead=0.15, taper=0.1):
    """``vary_passes`` of the NumPy oracle (tests/oracles/passes_numpy.py) in JAX: ``pass_times`` (P,) padded with +inf (their
    windows vanish), ``factors`` and ``shifts`` (P + 1,) (index 0: before the first pass)."""
    x = jnp.asarray(x, jnp.float64)
    n = x.shape[0]
    tp = jnp.sort(jnp.asarray(pass_times, jnp.float64))
    t = jnp.arange(n) / float(fs)
    k = jnp.sum(jnp.isfinite(tp))
    T = jnp.where(k > 1, _mean_interval(tp), jnp.maximum(t[-1], 1.0 / float(fs)))
    m = jnp.mean(x)
    xc = x - m
    edges, w = tp - lead * T, taper * T
    P = tp.shape[0]
    sin_a, cos_a = jnp.sin(np.pi * t / w), jnp.cos(np.pi * t / w)
    if P:
        up = lambda j: jnp.where(j < P, _ramp(t, sin_a, cos_a, edges[jnp.minimum(j, P - 1)], w), 0.0)  # noqa: E731
    else:
        up = lambda j: jnp.zeros(n)  # noqa: E731

    def piece(j, carry):            # pieces one at a time: memory O(n) per item
        acc, prev = carry
        nxt = up(j)
        y = factors[j] * (prev - nxt) * xc
        y = jnp.where(shifts[j] != 0.0, _delay(y, shifts[j] * float(fs)), y)
        return acc + y, nxt
    # the pieces after the last finite pass are 0: the loop stops there
    acc, _ = jax.lax.fori_loop(0, k + 1, piece, (jnp.zeros(n), jnp.ones(n)))
    return acc + m


@jit
def pass_variability(key, housing, sensor, pass_times, unbridged, modes, strike_probability, s: PassSettings,
                     exposure=None):
    """One record's pass-to-pass variability (the first step of a data set item's signal stage,
    :func:`bearingsim.signals.signal_stage.finish_item`; a single simulation,
    :func:`bearingsim.dynamics.simulate`, applies the same): the housing acceleration
    ``housing`` (T,) varied pass by pass (:func:`vary_passes`: factors of c.v. ``s.pass_cv_max``
    x ``unbridged``, delays of s.d. ``s.pass_delay_max`` x ``unbridged`` mean pass intervals, the
    strikes of probability ``strike_probability``, all drawn from the key's ``passes`` and
    ``strike`` streams) and put through the sensor ``modes`` (M, 3) (f Hz, zeta, gain) again;
    a record whose pit is bridged and always strikes keeps ``sensor``.  ``pass_times`` (P,) s,
    sorted, +inf padded.  Returns (sensor record, factors (P + 1,), shifts (P + 1,) s, c.v.,
    delay fraction).  One compiled program per settings and shapes (pass arrays, not Python
    floats, for ``unbridged`` and ``strike_probability``).  With ``s.exposure``, ``exposure`` (P,)
    (0..1 per pass, :func:`bearingsim.dynamics.exposure.pass_exposure`: the ball pit's kinematic
    exposure; 1 for other defects) multiplies the passes instead of the drawn strikes, and a record
    with an exposure below 1 is varied and filtered again."""
    fs = s.fs
    P = pass_times.shape[0]
    cv = s.pass_cv_max * unbridged
    jitter = s.pass_delay_max * unbridged
    p = strike_probability
    kp = jax.random.split(stream_key(key, "passes"))
    fac = pass_factors(kp[0], P + 1, cv)
    shifts = pass_shifts(kp[1], pass_times, jitter)
    if s.exposure:
        fac = fac.at[1:].multiply(exposure)
        miss = jnp.any(exposure < 1.0)
    else:
        fac = fac.at[1:].multiply(strike_factors(stream_key(key, "strike"), P, p))
        miss = p < 1.0
    active = (cv > 0) | (jitter > 0) | miss
    varied = jnp.where(active, vary_passes(housing, fs, pass_times, fac, shifts, s.pass_lead, s.pass_taper),
                       housing)
    if s.pass_cv_max > 0 or s.pass_delay_max > 0 or s.strikes or s.exposure:
        f, z, g = modes[:, 0], modes[:, 1], modes[:, 2]
        y = run_filter(sensor_filter(f, z, g, 1.0 / fs), varied)
        a = jnp.where((unbridged > 0.0) | miss, y, sensor)
    else:
        a = sensor
    return a, fac, shifts, cv, jitter
