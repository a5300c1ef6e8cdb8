"""The NumPy draw of one run's cage and shaft motion (the package's former host twin of
:func:`bearingsim.dynamics.draw_motion`): the same distributions -- speed fluctuation of
random-phase sinusoids, a slip walk of pitches (1 + eps_k), eps_k ~ N(0, sigma^2) clipped to
+-0.5, anchored at the spall centre -- from NumPy's generators seeded by an integer.  The tests
compare the package's key-drawn statistics with it; it is no part of the package."""
from __future__ import annotations

import numpy as np

from bearingsim.dynamics.motion import FLUCTUATION_TERMS, Motion, motion_at
from bearingsim.dynamics.parameters import Realism


def seed_streams(seed):
    """The run's four NumPy random streams: slip forward, slip backward, speed, noise."""
    ss = np.random.SeedSequence(int(seed))
    return [np.random.default_rng(s) for s in ss.spawn(4)]


def _progress(m: Motion, t, xp=np):
    """Nominal cage progress u(t) in ball pitches (no slip): the cage angle of the motion
    without its slip knots, times Z / 2 pi."""
    theta, _, _ = motion_at(m._replace(knots_u=np.array([-1e12, 1e12]), knots_p=np.array([-1e12, 1e12])), t)
    return m.Z / (2 * np.pi) * theta


def draw_motion(seed, Z, theta0, omega_c, omega0, duration, spall_center=0.0,
                realism: Realism = Realism()) -> Motion:
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
    m = Motion(float(theta0), float(omega_c), float(omega0), int(Z), a, f, ph,
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
