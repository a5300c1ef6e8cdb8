"""Sensor path (MODEL.md section 7): structural resonances driven by the housing acceleration,
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
from ``numpy.random.default_rng(seed)`` (reproducible, per item).
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg
from jax import lax

from ..programs import jit

__all__ = ["SensorFilter", "sensor_filter", "filter_init", "filter_update", "filter_output", "step_response",
           "apply_sensor", "apply_sensor_batch", "measurement_noise", "G", "sensor_filter_device"]

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
    """FOH-exact discretisation of the modes over a step h (s), on the host (scipy's matrix
    exponential of each mode's 4x4 augmented system: nothing to compile); concrete values only.
    Leading batch axes of ``frequencies`` (with the same of ``damping_ratios``/``gains``) give
    a batch of filters."""
    f = np.atleast_1d(np.asarray(frequencies, np.float64))
    z = np.broadcast_to(np.asarray(damping_ratios, np.float64), f.shape)
    g = np.broadcast_to(np.asarray(gains, np.float64), f.shape)
    h = float(h)
    w = 2.0 * np.pi * f
    Phi, G0, G1 = np.zeros(f.shape + (2, 2)), np.zeros(f.shape + (2,)), np.zeros(f.shape + (2,))
    for idx in np.ndindex(f.shape):
        wk, zk = w[idx], z[idx]
        M = np.zeros((4, 4))
        M[0, 1], M[1, 0], M[1, 1], M[1, 2], M[2, 3] = 1.0, -wk * wk, -2.0 * zk * wk, -1.0, 1.0
        E = scipy.linalg.expm(M * h)
        Phi[idx], G0[idx], G1[idx] = E[:2, :2], E[:2, 2], E[:2, 3] / h
    C = np.stack([-w * w, -2.0 * z * w], axis=-1)
    return SensorFilter(*(jnp.asarray(a) for a in (Phi, G0, G1, C, g, w, z)))


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


def _run_filter(flt: SensorFilter, u):
    def body(carry, u1):
        s, u0 = carry
        s = filter_update(flt, s, u0, u1)
        return (s, u1), filter_output(flt, s, u1)

    _, out = lax.scan(body, (filter_init(flt), u[0]), u[1:])
    return jnp.concatenate([jnp.atleast_1d(filter_output(flt, filter_init(flt), u[0])), out])


_run_filter_jit = jit(_run_filter)
_run_filter_batch_jit = jit(jax.vmap(_run_filter))


def apply_sensor(housing_acceleration, h, frequencies, damping_ratios, gains=1.0):
    """The sensor signal of a housing-acceleration record sampled every h (s), modes at rest at
    the first sample (the modes discretised on the host, then a JAX scan, compiled once per
    record length and mode count); for signals outside a simulation (e.g. a different sensor
    path on a stored run, or a record varied pass by pass: the step is then the sample
    interval, the input linear between samples)."""
    u = jnp.asarray(housing_acceleration, jnp.float64)
    return _run_filter_jit(sensor_filter(frequencies, damping_ratios, gains, h), u)


def apply_sensor_batch(housing_acceleration, h, frequencies, damping_ratios, gains=1.0):
    """:func:`apply_sensor` for N records at once: ``housing_acceleration`` (N, T), the modes
    (M,) for all or (N, M) per record (one program for the batch)."""
    u = jnp.asarray(housing_acceleration, jnp.float64)
    n = u.shape[0]
    f = np.atleast_1d(np.asarray(frequencies, np.float64))
    f = np.broadcast_to(f, (n,) + f.shape[-1:])
    z = np.broadcast_to(np.asarray(damping_ratios, np.float64), f.shape)
    g = np.broadcast_to(np.asarray(gains, np.float64), f.shape)
    return _run_filter_batch_jit(sensor_filter(f, z, g, h), u)


def measurement_noise(rng: np.random.Generator, n, rms, fs=None, band=None) -> np.ndarray:
    """n samples of zero-mean Gaussian noise with the given RMS (m/s^2).  ``band`` = (lo, hi) Hz
    (with ``fs``): the noise is band-limited by zeroing its spectrum outside the band, then
    rescaled to the RMS; None: white up to fs/2."""
    x = rng.standard_normal(n)
    if band is not None and n > 1:
        lo, hi = band
        X = np.fft.rfft(x)
        f = np.fft.rfftfreq(n, 1.0 / float(fs))
        X[(f < lo) | (f > hi)] = 0.0
        x = np.fft.irfft(X, n)
    s = float(np.sqrt(np.mean(x * x))) if n else 0.0
    return x * (float(rms) / s) if s > 0 else x * 0.0


def sensor_filter_device(frequencies, damping_ratios, gains, h) -> SensorFilter:
    """:func:`sensor_filter` as a traceable JAX function (jit/vmap: the matrix exponential of
    each mode's augmented system by :func:`jax.scipy.linalg.expm`), for filters built inside a
    compiled program from per-item modes ``(M,)``; ``h`` may be traced."""
    f = jnp.atleast_1d(jnp.asarray(frequencies, jnp.float64))
    z = jnp.broadcast_to(jnp.asarray(damping_ratios, jnp.float64), f.shape)
    g = jnp.broadcast_to(jnp.asarray(gains, jnp.float64), f.shape)
    w = 2.0 * np.pi * f
    zero, one = jnp.zeros_like(w), jnp.ones_like(w)
    M = jnp.stack([jnp.stack([zero, one, zero, zero], -1),
                   jnp.stack([-w * w, -2.0 * z * w, -one, zero], -1),
                   jnp.stack([zero, zero, zero, one], -1),
                   jnp.stack([zero, zero, zero, zero], -1)], -2)
    E = jax.vmap(jax.scipy.linalg.expm)((M * h).reshape((-1, 4, 4))).reshape(M.shape)
    C = jnp.stack([-w * w, -2.0 * z * w], axis=-1)
    return SensorFilter(E[..., :2, :2], E[..., :2, 2], E[..., :2, 3] / h, C, g, w, z)
