"""The NumPy draw of one run's cage and shaft motion (the package's former host twin of
:func:`bearingsim.dynamics.draw_motion`): the same distributions -- speed fluctuation of
random-phase sinusoids, a slip walk of pitches (1 + eps_k), eps_k ~ N(0, sigma^2) clipped to
+-0.5, anchored at the spall centre -- from NumPy's generators seeded by an integer.  The tests
compare the package's key-drawn statistics with it; it is no part of the package.  With it, the
former host evaluation of a motion (NumPy: ``motion_at``, the crossings on a dense grid), the
independent reference of the package's one JAX version."""
from __future__ import annotations

import numpy as np

import math
from typing import NamedTuple

import jax.numpy as jnp

from bearingsim.dynamics.motion import FLUCTUATION_TERMS, Motion
from bearingsim.dynamics.parameters import Realism
from bearingsim.physics.defect import as_defects


def seed_streams(seed):
    """The run's four NumPy random streams: slip forward, slip backward, speed, noise."""
    ss = np.random.SeedSequence(int(seed))
    return [np.random.default_rng(s) for s in ss.spawn(4)]


class HostMotion(NamedTuple):
    """One run's cage and shaft motion as NumPy arrays (the package's former host type)."""

    theta0: float               # cage angle at t = 0 (rad)
    omega_c: float              # nominal cage speed (rad/s)
    omega0: float               # nominal shaft speed (rad/s)
    Z: int
    fluct: float                # RMS speed fluctuation (fraction)
    fluct_freqs: np.ndarray     # (K,) Hz
    fluct_phases: np.ndarray    # (K,) rad
    knots_u: np.ndarray         # nominal progress (ball pitches) at the slip knots
    knots_p: np.ndarray         # actual progress at the slip knots
    slip_draws: np.ndarray      # eps_k of the pitches within the run
    seed: int


def _fluct(m: HostMotion, t, xp):
    """(s(t), integral of s from 0 to t) of the unit-RMS fluctuation."""
    if m.fluct == 0.0:
        z = xp.zeros_like(t)
        return z, z
    f = xp.asarray(m.fluct_freqs)
    ph = xp.asarray(m.fluct_phases)
    arg = 2 * np.pi * f * t[..., None] + ph
    c = math.sqrt(2.0 / len(m.fluct_freqs))
    s = c * xp.sum(xp.cos(arg), axis=-1)
    S = c * xp.sum((xp.sin(arg) - xp.sin(ph)) / (2 * np.pi * f), axis=-1)
    return s, S


def _progress(m: HostMotion, t, xp):
    """Nominal cage progress u(t) in ball pitches (no slip)."""
    _, S = _fluct(m, t, xp)
    return m.Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))


def _no_slip(m: HostMotion):
    """True for a run drawn without slip (its two sentinel knots at +-1e12)."""
    if np.size(m.knots_u) != 2:
        return False
    try:
        return float(np.asarray(m.knots_u)[0]) == -1e12
    except Exception:       # noqa: BLE001 -- traced knots: a drawn walk
        return False


def motion_at(m: HostMotion, t, xp=np):
    """(cage angle, shaft angle, shaft speed) at times t (``xp``: numpy or jax.numpy)."""
    s, S = _fluct(m, t, xp)
    u = m.Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))
    if _no_slip(m):         # the identity (interpolating between the +-1e12 sentinels would round u to 1e-4)
        p = u
    else:
        p = xp.interp(u, xp.asarray(m.knots_u), xp.asarray(m.knots_p))
    return 2 * np.pi / m.Z * p, m.omega0 * (t + m.fluct * S), m.omega0 * (1.0 + m.fluct * s)


def defect_phase(m: HostMotion, spall, t, spin_ratio=0.0):
    """(phase (rad) at times t, its period (rad)) of one defect in this run (module docstring):
    a ball meets the defect's centre when the phase is a multiple of the period."""
    theta, phi, _ = motion_at(m, t)
    c = float(spall.center)
    if spall.location == "outer":
        return theta - c, 2 * np.pi / m.Z
    if spall.location == "inner":
        return theta - phi - c, 2 * np.pi / m.Z
    return c + float(spin_ratio) * phi, np.pi


def _crossings(m: HostMotion, spall, offset, duration, spin_ratio):
    """Times in [0, duration] at which the defect phase equals ``offset`` modulo its period."""
    if m.omega_c <= 0.0 and spall.location != "ball":
        return np.zeros(0)
    tt = np.linspace(0.0, float(duration), max(2049, int(duration * 20000)))
    ph, period = defect_phase(m, spall, tt, spin_ratio)
    if ph[-1] < ph[0]:                      # the inner spall's phase decreases
        ph, tt = ph[::-1], tt[::-1]
    if not ph[-1] > ph[0]:
        return np.zeros(0)
    k0 = np.ceil((ph[0] - offset) / period)
    k1 = np.floor((ph[-1] - offset) / period)
    targets = offset + period * np.arange(k0, k1 + 1)
    return np.sort(np.interp(targets, ph, tt))


def _active(spall):
    return spall is not None and float(spall.depth) > 0.0


def defect_edge_times(m: HostMotion, spalls, duration, spin_ratio=0.0):
    """Times (s) within [0, duration] at which a ball (or the pit) enters or leaves a defect
    (``spalls``: a Spall or a tuple; depth-0 ones ignored)."""
    out = [np.zeros(0)]
    for sp in as_defects(spalls):
        if _active(sp):
            h = 0.5 * float(sp.extent)
            out += [_crossings(m, sp, -h, duration, spin_ratio), _crossings(m, sp, h, duration, spin_ratio)]
    return np.unique(np.concatenate(out))


def defect_pass_times(m: HostMotion, spalls, duration, spin_ratio=0.0):
    """Times (s) within [0, duration] at which a ball centre passes a raceway defect's centre, or
    the pit passes a contact centre (``spalls``: a Spall or a tuple; depth-0 ones ignored)."""
    out = [np.zeros(0)]
    for sp in as_defects(spalls):
        if _active(sp):
            out.append(_crossings(m, sp, 0.0, duration, spin_ratio))
    return np.unique(np.concatenate(out))


def to_motion(m: HostMotion, duration=None, block=None) -> Motion:
    """A :class:`HostMotion` as the package's :class:`~bearingsim.dynamics.Motion` (the same
    motion).  A run without slip gets exact whole-pitch knots over ``duration`` (s; required
    then).  The knots are padded by whole pitches beyond the last to a multiple of ``block``
    (default: none), so that runs of similar length share one program."""
    ku, kp = np.asarray(m.knots_u, float), np.asarray(m.knots_p, float)
    if _no_slip(m):
        if duration is None:
            raise ValueError("to_motion: a run without slip needs its duration (s), got None")
        u = _progress(m, np.linspace(0.0, float(duration), 257), np)
        ku = kp = np.arange(np.floor(u.min()) - 4.0, np.ceil(u.max()) + 5.0)
    n = ku.size if block is None else int(block) * (ku.size // int(block) + 1)
    if n > ku.size:
        extra = np.arange(1, n - ku.size + 1, dtype=float)
        ku, kp = np.concatenate([ku, ku[-1] + extra]), np.concatenate([kp, kp[-1] + extra])
    f = np.zeros(FLUCTUATION_TERMS) + 1.0
    ph = np.zeros(FLUCTUATION_TERMS)
    a = 0.0
    if m.fluct:
        f, ph, a = np.asarray(m.fluct_freqs, float), np.asarray(m.fluct_phases, float), float(m.fluct)
    return Motion(*(jnp.asarray(v, jnp.float64) for v in (m.theta0, m.omega_c, m.omega0, a, f, ph, ku, kp)),
                        jnp.zeros(ku.size - 1), jnp.zeros(ku.size - 1, bool))



def draw_motion(seed, Z, theta0, omega_c, omega0, duration, spall_center=0.0,
                realism: Realism = Realism()) -> HostMotion:
    """Draw the cage and shaft motion of one run (reproducible from ``seed``; a longer run with
    the same seed starts with the same draws)."""
    r_fwd, r_bwd, r_speed, _ = seed_streams(seed)
    a = float(realism.speed_fluctuation_percent) / 100.0
    if a > 0.0:
        K = FLUCTUATION_TERMS
        f = r_speed.uniform(0.0, 1.0, K) * float(realism.speed_fluctuation_bandwidth_Hz)
        f = np.maximum(f, 1e-3)
        ph = r_speed.uniform(0.0, 2 * np.pi, K)
    else:
        f, ph = np.ones(1), np.zeros(1)
    m = HostMotion(float(theta0), float(omega_c), float(omega0), int(Z), a, f, ph,
               np.array([-1e12, 1e12]), np.array([-1e12, 1e12]), np.zeros(0), int(seed))
    sigma = float(realism.slip_percent) / 100.0
    if sigma <= 0.0 or omega_c <= 0.0:
        return m
    p0 = Z * float(spall_center) / (2 * np.pi)
    tt = np.linspace(0.0, float(duration), 257)
    u = _progress(m, tt, np)
    lo, hi = float(u.min()) - 2.0, float(u.max()) + 2.0

    def walk(rng, limit, sign):
        steps = []
        total = 0.0
        while total < limit:
            e = np.clip(rng.standard_normal(64) * sigma, -0.5, 0.5)
            steps.append(e)
            total += float(np.sum(1.0 + e))
        e = np.concatenate(steps)
        return e, sign * np.cumsum(1.0 + e)

    e_f, U_f = walk(r_fwd, max(hi - p0, 0.0) + 2.0, 1.0)
    e_b, U_b = walk(r_bwd, max(p0 - lo, 0.0) + 2.0, -1.0)
    ku = np.concatenate([p0 + U_b[::-1], [p0], p0 + U_f])
    kp = np.concatenate([p0 - np.arange(len(U_b), 0, -1), [p0], p0 + np.arange(1, len(U_f) + 1)])
    inside = (ku[1:] > lo) & (ku[:-1] < hi)
    eps = np.concatenate([e_b[::-1], e_f])[inside]
    return m._replace(knots_u=ku, knots_p=kp.astype(float), slip_draws=eps)
