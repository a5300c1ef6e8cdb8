"""The NumPy/SciPy sensor path (the package's former host twins of :mod:`bearingsim.dynamics.sensor`):
the modes discretised with scipy's matrix exponential of the unbalanced 4x4 system, and NumPy
measurement noise.  An independent oracle for the tests only."""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import scipy.linalg

from bearingsim.dynamics.sensor import SensorFilter


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
