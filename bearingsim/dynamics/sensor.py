"""Sensor path (docs/model.md section 7): structural resonances driven by the housing acceleration,
and measurement noise.

The sensor sits on the housing behind one or more lightly damped structural modes.  Mode k
(natural frequency f_k, damping ratio zeta_k, gain g_k) is a base-excited oscillator whose
relative displacement z_k obeys

    z_k'' + 2 zeta_k w_k z_k' + w_k^2 z_k = -a_h(t),        w_k = 2 pi f_k,

with a_h the housing acceleration along x.  The sensor reads

    a_s = a_h + sum_k g_k z_k''        (one mode with g = 1: the absolute acceleration of a
                                        resonator on the housing, Sawalhi & Randall 2008).

The modes are linear and one-way coupled (their reaction on the housing is neglected, see
docs/dynamics.md for its size), so they are not integrated with the shaft/housing equations:
they are applied afterwards, *exactly*, with the first-order-hold (FOH) discretisation of each
mode over the integrator's step h -- exact when a_h varies linearly between steps, for any
f_k h (no step-size limit from the resonances).  With s = (z, z') and v_n = (u_{n+1} - u_n)/h,

    s_{n+1} = Phi s_n + Gamma0 u_n + Gamma1 v_n,      z''_n = C s_n - u_n,

where exp(h [[A, B, 0], [0, 0, 1], [0, 0, 0]]) = [[Phi, Gamma0, Gamma1], [0, 1, 1], [0, 0, 1]]
(A = [[0, 1], [-w^2, -2 zeta w]], B = [0, -1], C = [-w^2, -2 zeta w]).

Noise (:func:`measurement_noise`) is Gaussian, white or band-limited, at a given RMS, drawn
from the run's (or item's) ``jax.random`` key.  Every function here is JAX, one version for a
single simulation, a data set item and the signal stage.
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from ..keys import stream_key
from ..programs import jit
from ..xla import QUICK_COMPILE

__all__ = ["SensorFilter", "sensor_filter", "host_sensor_filter", "host_measurement_noise", "filter_init", "filter_update", "filter_output", "step_response",
           "run_filter", "apply_sensor", "apply_sensor_batch", "measurement_noise", "G"]

#: standard gravity (m/s^2), for noise levels given in g
G = 9.80665


class SensorFilter(NamedTuple):
    """Discretised modes (arrays with a leading mode axis M)."""

    Phi: jnp.ndarray       # (M, 2, 2)
    Gamma0: jnp.ndarray    # (M, 2)
    Gamma1: jnp.ndarray    # (M, 2), divided by h (multiplies u_{n+1} - u_n)
    C: jnp.ndarray         # (M, 2)
    gain: jnp.ndarray      # (M,)
    w: jnp.ndarray         # (M,) rad/s
    zeta: jnp.ndarray      # (M,)


def sensor_filter(frequencies, damping_ratios, gains, h) -> SensorFilter:
    """FOH-exact discretisation of the modes over a step h (s), in JAX (jit/vmap; ``h`` may be
    traced): the matrix exponential of each mode's 4x4 augmented system
    (``jax.scipy.linalg.expm``), balanced first (similarity by d = (w^2, w, 1, 1/w): every entry
    of h D A D^-1 is of the order w h), so that its scaling and squaring takes few squarings and
    keeps full precision.  Leading batch axes of ``frequencies`` (with the same of
    ``damping_ratios``/``gains``) give a batch of filters.  One version for a simulation's time
    loop, a data set item's and the signal stage's (tests/oracles/sensor_numpy.py is scipy's)."""
    f = jnp.atleast_1d(jnp.asarray(frequencies, jnp.float64))
    z = jnp.broadcast_to(jnp.asarray(damping_ratios, jnp.float64), f.shape)
    g = jnp.broadcast_to(jnp.asarray(gains, jnp.float64), f.shape)
    h = jnp.asarray(h, jnp.float64)
    w = 2.0 * np.pi * f
    one, zero = jnp.ones_like(w), jnp.zeros_like(w)
    A = jnp.stack([jnp.stack([zero, one, zero, zero], -1), jnp.stack([-w * w, -2.0 * z * w, -one, zero], -1),
                   jnp.stack([zero, zero, zero, one], -1), jnp.stack([zero, zero, zero, zero], -1)], -2)
    d = jnp.stack([w * w, w, one, 1.0 / w], -1)
    Ab = A * d[..., :, None] / d[..., None, :]
    Eb = jax.vmap(jax.scipy.linalg.expm)(Ab.reshape((-1, 4, 4)) * h).reshape(A.shape)
    E = Eb * d[..., None, :] / d[..., :, None]
    C = jnp.stack([-w * w, -2.0 * z * w], axis=-1)
    return SensorFilter(E[..., :2, :2], E[..., :2, 2], E[..., :2, 3] / h, C, g, w, z)


def filter_init(flt: SensorFilter):
    """Modes at rest relative to the housing: s = 0, (M, 2)."""
    return jnp.zeros(flt.C.shape)


def step_response(flt: SensorFilter, tau):
    """(M, 2) state (z, z') of every mode a time tau after a unit step of the input, from rest."""
    w, z = flt.w, flt.zeta
    wd = w * jnp.sqrt(1.0 - z * z)
    e = jnp.exp(-z * w * tau)
    c, s = jnp.cos(wd * tau), jnp.sin(wd * tau)
    return jnp.stack([-(1.0 - e * (c + z * w / wd * s)) / (w * w), -e * s / wd], axis=-1)


def filter_update(flt: SensorFilter, s, u0, u1, jump_at=None, h=None):
    """State after one step with the input going linearly from u0 to u1; or, where ``jump_at``
    (fraction of the step h) is >= 0, holding u0 and jumping to u1 at that instant (exact for a
    force step inside the step, e.g. a ball crossing a rectangular spall edge)."""
    base = jnp.einsum("mij,mj->mi", flt.Phi, s) + flt.Gamma0 * u0
    ramp = flt.Gamma1 * (u1 - u0)
    if jump_at is None:
        return base + ramp
    jump = step_response(flt, jnp.maximum(1.0 - jump_at, 0.0) * h) * (u1 - u0)
    return base + jnp.where(jump_at >= 0.0, jump, ramp)


def filter_output(flt: SensorFilter, s, u):
    """Sensor acceleration a_h + sum_k g_k z_k'' for state s and input u."""
    zdd = jnp.sum(flt.C * s, axis=-1) - u
    return u + jnp.sum(flt.gain * zdd)


def run_filter(flt: SensorFilter, u):
    """The sensor signal of housing acceleration ``u`` (T,) through ``flt`` (one record; jit/vmap),
    modes at rest at the first sample, the input linear between samples."""
    def body(carry, u1):
        s, u0 = carry
        s = filter_update(flt, s, u0, u1)
        return (s, u1), filter_output(flt, s, u1)

    _, out = lax.scan(body, (filter_init(flt), u[0]), u[1:])
    return jnp.concatenate([jnp.atleast_1d(filter_output(flt, filter_init(flt), u[0])), out])


_run_filter_jit = jit(run_filter)
_run_filter_batch_jit = jit(jax.vmap(run_filter))
_sensor_filter_jit = jit(sensor_filter, options=QUICK_COMPILE)     # once per simulation: -O0


def host_sensor_filter(frequencies, damping_ratios, gains, h) -> SensorFilter:
    """:func:`sensor_filter` of host values as one kept program (:mod:`bearingsim.programs`; the
    step ``h`` an argument, not a constant): a simulation's set-up loads it instead of running
    ~25 operations one by one."""
    f = np.atleast_1d(np.asarray(frequencies, np.float64))
    z = np.broadcast_to(np.asarray(damping_ratios, np.float64), f.shape)
    g = np.broadcast_to(np.asarray(gains, np.float64), f.shape)
    return _sensor_filter_jit(f, z, g, np.float64(h))


def apply_sensor(housing_acceleration, h, frequencies, damping_ratios, gains=1.0):
    """The sensor signal of a housing-acceleration record sampled every h (s), modes at rest at
    the first sample (:func:`sensor_filter`, then a JAX scan, compiled once per record length
    and mode count); for signals outside a simulation (e.g. a different sensor
    path on a stored run, or a record varied pass by pass: the step is then the sample
    interval, the input linear between samples)."""
    return _run_filter_jit(host_sensor_filter(frequencies, damping_ratios, gains, h),
                           np.asarray(housing_acceleration, np.float64))


def apply_sensor_batch(housing_acceleration, h, frequencies, damping_ratios, gains=1.0):
    """:func:`apply_sensor` for N records at once: ``housing_acceleration`` (N, T), the modes
    (M,) for all or (N, M) per record (one program for the batch)."""
    u = np.asarray(housing_acceleration, np.float64)
    n = u.shape[0]
    f = np.atleast_1d(np.asarray(frequencies, np.float64))
    f = np.broadcast_to(f, (n,) + f.shape[-1:])
    return _run_filter_batch_jit(host_sensor_filter(f, damping_ratios, gains, h), u)


def measurement_noise(key, n, rms, fs=None, band=None):
    """Measurement noise from a ``jax.random`` key (a data set item's or a simulation's ``noise``
    stream, :data:`bearingsim.keys.STREAMS`): ``n`` Gaussian samples, band-limited to ``band`` =
    (lo, hi) Hz by zeroing the spectrum outside it (``fs`` needed), scaled to ``rms`` (m/s^2);
    None: white up to fs/2."""
    x = jax.random.normal(key, (int(n),), jnp.float64)
    if band is not None and n > 1:
        lo, hi = band
        X = jnp.fft.rfft(x)
        f = jnp.fft.rfftfreq(int(n), 1.0 / float(fs))
        x = jnp.fft.irfft(jnp.where((f < lo) | (f > hi), 0.0, X), int(n))
    s = jnp.sqrt(jnp.mean(x * x))
    return jnp.where(s > 0, x * (rms / jnp.where(s > 0, s, 1.0)), 0.0)


def _noise(key, rms, n, fs, band):
    return measurement_noise(stream_key(key, "noise"), n, rms, fs, band)


_noise_jit = jit(_noise)


def host_measurement_noise(key, n, rms, fs=None, band=None):
    """:func:`measurement_noise` of the item ``key``'s ``noise`` stream (:func:`bearingsim.keys.stream_key`,
    as a data set item draws it) as one kept program (:mod:`bearingsim.programs`; ``rms`` an
    argument, ``n``, ``fs`` and ``band`` its static settings): a simulation's noise without ~10
    operations run one by one."""
    return _noise_jit(np.asarray(key, np.uint32), np.float64(rms), int(n), None if fs is None else float(fs),
                      None if band is None else tuple(float(b) for b in band))
