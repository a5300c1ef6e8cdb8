"""Motion of the balls and the shaft in one run (seeded: slip, speed fluctuation), and the
instants at which a ball meets a defect (MODEL.md sections 7 and 9).

The cage angle theta_c(t), the shaft angle phi(t) and the shaft speed are drawn once per run:

* speed fluctuation: omega(t) = omega_0 (1 + a s(t)), s a unit-RMS sum of 8 random-phase
  sinusoids with frequencies uniform in (0, B] (``speed_fluctuation_percent`` = 100 a,
  ``speed_fluctuation_bandwidth_Hz`` = B); the cage follows at the quasi-static ratio
  omega_c / omega_0;
* random slip: the cage advances one ball pitch (2 pi / Z) in (1 + eps_k) times its nominal
  time, eps_k ~ N(0, (slip_percent / 100)^2) independent per pitch; pitches start when a ball is
  at the spall centre, so successive ball passes over the spall are (1 + eps_k) T_BPFO apart
  (Randall & Antoni 2011: 1-2 %).  The cage angle is piecewise linear in the nominal progress;
  the phase is a random walk (the envelope's BPFO harmonics broaden as k^2).

Where a defect is at time t (:func:`bearingsim.defect.advance` with the run's own angles): an
outer spall stays; an inner spall turns with the shaft, centre + phi(t); a ball pit turns with
its ball, spin angle theta_b0 + k phi(t) with k = omega_R / omega the ball's spin speed relative
to the cage per unit shaft speed (2 pi BSF / omega), so speed fluctuation reaches every class.
A ball meets a defect when a *phase* crosses the defect's edge (or centre) modulo a period:

=========  =====================================  ========================
location   phase                                  period
=========  =====================================  ========================
outer      theta_c(t) - centre                    2 pi / Z (a ball pitch)
inner      theta_c(t) - phi(t) - centre           2 pi / Z
ball       centre + k phi(t)                      pi (outer, inner contact)
=========  =====================================  ========================
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..defect import as_defects
from .parameters import Realism

__all__ = ["Motion", "seed_streams", "draw_motion", "motion_at", "defect_phase", "defect_edge_times",
           "defect_pass_times", "motion_labels", "FLUCTUATION_TERMS"]

#: sinusoids in the speed fluctuation
FLUCTUATION_TERMS = 8


class Motion(NamedTuple):
    """One run's drawn cage and shaft motion (host arrays; see the module docstring)."""

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


def seed_streams(seed):
    """The run's four random streams: slip forward, slip backward, speed, noise."""
    ss = np.random.SeedSequence(int(seed))
    return [np.random.default_rng(s) for s in ss.spawn(4)]     # slip+, slip-, speed, noise


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


def _fluct(m: Motion, t, xp):
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


def _progress(m: Motion, t, xp):
    """Nominal cage progress u(t) in ball pitches (no slip)."""
    _, S = _fluct(m, t, xp)
    return m.Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))


def motion_at(m: Motion, t, xp=np):
    """(cage angle, shaft angle, shaft speed) at times t (``xp``: numpy or jax.numpy)."""
    s, S = _fluct(m, t, xp)
    u = m.Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))
    p = xp.interp(u, xp.asarray(m.knots_u), xp.asarray(m.knots_p))
    return 2 * np.pi / m.Z * p, m.omega0 * (t + m.fluct * S), m.omega0 * (1.0 + m.fluct * s)


def defect_phase(m: Motion, spall, t, spin_ratio=0.0):
    """(phase (rad) at times t, its period (rad)) of one defect in this run (module docstring):
    a ball meets the defect's centre when the phase is a multiple of the period."""
    theta, phi, _ = motion_at(m, t)
    c = float(spall.center)
    if spall.location == "outer":
        return theta - c, 2 * np.pi / m.Z
    if spall.location == "inner":
        return theta - phi - c, 2 * np.pi / m.Z
    return c + float(spin_ratio) * phi, np.pi


def _crossings(m: Motion, spall, offset, duration, spin_ratio):
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


def defect_edge_times(m: Motion, spalls, duration, spin_ratio=0.0):
    """Times (s) within [0, duration] at which a ball (or the pit) enters or leaves a defect
    (``spalls``: a Spall or a tuple; depth-0 ones ignored)."""
    out = [np.zeros(0)]
    for sp in as_defects(spalls):
        if _active(sp):
            h = 0.5 * float(sp.extent)
            out += [_crossings(m, sp, -h, duration, spin_ratio), _crossings(m, sp, h, duration, spin_ratio)]
    return np.unique(np.concatenate(out))


def defect_pass_times(m: Motion, spalls, duration, spin_ratio=0.0):
    """Times (s) within [0, duration] at which a ball centre passes a raceway defect's centre, or
    the pit passes a contact centre (``spalls``: a Spall or a tuple; depth-0 ones ignored)."""
    out = [np.zeros(0)]
    for sp in as_defects(spalls):
        if _active(sp):
            out.append(_crossings(m, sp, 0.0, duration, spin_ratio))
    return np.unique(np.concatenate(out))


def motion_labels(m: Motion, realism: Realism) -> dict:
    eps = np.asarray(m.slip_draws)
    return dict(seed=int(m.seed), slip_percent=float(realism.slip_percent),
                slip_draws=eps, pass_jitter_percent=float(100.0 * eps.std()) if eps.size > 1 else 0.0,
                speed_fluctuation_percent=float(realism.speed_fluctuation_percent),
                speed_fluctuation_bandwidth_Hz=float(realism.speed_fluctuation_bandwidth_Hz),
                speed_fluctuation_frequencies_Hz=np.asarray(m.fluct_freqs) if m.fluct else np.zeros(0),
                noise_rms=float(realism.noise_rms),
                noise_band=(np.asarray(realism.noise_band, float) if realism.noise_band else np.zeros(0)))
