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

Where a defect is at time t (:func:`bearingsim.physics.defect.advance` with the run's own angles): an
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

from ..errors import InputError
from ..physics.defect import as_defects
from ..keys import STREAMS
from .parameters import Realism

__all__ = ["Motion", "draw_motion", "motion_at", "defect_phase", "defect_edge_times", "DeviceMotion",
           "knot_count", "MOTION_STREAM", "motion_at_device", "motion_ok_device", "device_motion_of",
           "crossings_device", "pass_count", "defect_times_device", "motion_labels_device", "host_motion_of",
           "defect_pass_times", "motion_labels", "FLUCTUATION_TERMS"]

#: sinusoids in the speed fluctuation
FLUCTUATION_TERMS = 8


class Motion(NamedTuple):
    """One run's drawn cage and shaft motion as host arrays (:func:`host_motion_of` of the drawn
    :class:`DeviceMotion`; see the module docstring)."""

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


def _no_slip(m: Motion):
    """True for a run drawn without slip (its two sentinel knots at +-1e12)."""
    if np.size(m.knots_u) != 2:
        return False
    try:
        return float(np.asarray(m.knots_u)[0]) == -1e12
    except Exception:       # noqa: BLE001 -- traced knots: a drawn walk
        return False


def motion_at(m: Motion, t, xp=np):
    """(cage angle, shaft angle, shaft speed) at times t (``xp``: numpy or jax.numpy)."""
    s, S = _fluct(m, t, xp)
    u = m.Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))
    if _no_slip(m):         # the identity (interpolating between the +-1e12 sentinels would round u to 1e-4)
        p = u
    else:
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


# ------------------------------------------------------------------- the draw, from a key
# Every run draws its motion from its own ``jax.random`` key (a data set's item inside the
# chunk's compiled program, vmap over items; one simulation from the key of its seed): no host
# work per item.  Every array has a fixed size (set by the duration and the fastest cage), so
# one program serves a data set; what does not fit is flagged (:func:`motion_ok_device`), never
# cut silently.  The NumPy draw of the same distributions stays in the tests as an independent
# oracle of the statistics (tests/oracles/motion_numpy.py).

class DeviceMotion(NamedTuple):
    """One run's drawn motion as device arrays (a pytree; a leading item axis under vmap).  The
    slip knots are a fixed number per run: ``knots_u`` (nominal progress, ball pitches) and
    ``knots_p`` (actual progress); ``slip_draws`` (n_knots - 1,) the eps of each pitch and
    ``inside`` which of them fall within the run (the label's draws)."""

    theta0: jnp.ndarray
    omega_c: jnp.ndarray
    omega0: jnp.ndarray
    fluct: jnp.ndarray
    fluct_freqs: jnp.ndarray    # (K,) Hz
    fluct_phases: jnp.ndarray   # (K,) rad
    knots_u: jnp.ndarray        # (n_knots,)
    knots_p: jnp.ndarray        # (n_knots,)
    slip_draws: jnp.ndarray     # (n_knots - 1,)
    inside: jnp.ndarray         # (n_knots - 1,) bool


#: the item key's stream the motion is drawn from (``jax.random.fold_in(key, MOTION_STREAM)``);
#: the signal stage folds in other numbers (>= 2) for its own draws
MOTION_STREAM = STREAMS["motion"]

#: slip knots drawn before the run's start (progress never falls below its value at t = 0 by
#: more than the fluctuation's excursion: 1 + 4 a < 2 pitches for a < 0.25)
BACK_KNOTS = 8


def knot_count(Z, max_cage_hz, duration, fluct=0.0):
    """Forward slip knots a run needs (static): every pitch lasts at least half its nominal
    progress (eps is clipped at -0.5), so twice the nominal span over ``duration`` at cage
    frequency ``max_cage_hz`` (with the fluctuation's largest excursion 1 + 4 a: |s| <= sqrt(2K)
    = 4) plus margin.  A run beyond it is flagged by :func:`motion_ok_device`."""
    span = float(Z) * float(max_cage_hz) * float(duration) * (1.0 + 4.0 * float(fluct))
    return int(math.ceil(2.0 * (span + 4.0))) + 2


def draw_motion(key, Z, theta0, omega_c, omega0, duration, slip_center, realism: Realism, n_knots):
    """One run's cage and shaft motion drawn from a ``jax.random`` key (jit/vmap; ``Z``, ``realism``
    and ``n_knots`` (:func:`knot_count`) static, the rest traced): speed fluctuation of
    :data:`FLUCTUATION_TERMS` random-phase sinusoids, frequencies uniform in (0, B]; the slip
    walk's pitches (1 + eps_k), eps_k ~ N(0, sigma^2) clipped to +-0.5, anchored where a ball is
    at ``slip_center`` (the walk starts at the anchor pitch nearest the run's start: the same
    walk, its anchor an integer number of pitches away).  ``omega_c`` <= 0 (a failed item):
    no slip."""
    import jax
    import jax.numpy as jnp

    k_f, k_b, k_s = jax.random.split(key, 3)
    a = float(realism.speed_fluctuation_percent) / 100.0
    K = FLUCTUATION_TERMS
    kf, kp = jax.random.split(k_s)
    f = jnp.maximum(jax.random.uniform(kf, (K,), jnp.float64) * float(realism.speed_fluctuation_bandwidth_Hz), 1e-3)
    ph = jax.random.uniform(kp, (K,), jnp.float64, 0.0, 2 * np.pi)
    theta0, omega_c, omega0 = (jnp.asarray(v, jnp.float64) for v in (theta0, omega_c, omega0))
    sigma = float(realism.slip_percent) / 100.0
    moving = omega_c > 0.0
    eps_f = jnp.clip(jax.random.normal(k_f, (n_knots,), jnp.float64) * sigma, -0.5, 0.5)
    eps_b = jnp.clip(jax.random.normal(k_b, (BACK_KNOTS,), jnp.float64) * sigma, -0.5, 0.5)
    eps_f, eps_b = jnp.where(moving, eps_f, 0.0), jnp.where(moving, eps_b, 0.0)
    m = DeviceMotion(theta0, omega_c, omega0, jnp.asarray(a, jnp.float64), f, ph, jnp.zeros(2), jnp.zeros(2),
                     jnp.zeros(1), jnp.zeros(1, bool))
    u0 = Z / (2 * np.pi) * theta0
    p0 = Z * jnp.asarray(slip_center, jnp.float64) / (2 * np.pi)
    p0 = p0 + jnp.floor(u0 - p0)                            # the anchor pitch at or before the start
    U_f = jnp.cumsum(1.0 + eps_f)
    U_b = jnp.cumsum(1.0 + eps_b)
    ku = jnp.concatenate([p0 - U_b[::-1], p0[None], p0 + U_f])
    kp_ = jnp.concatenate([p0 - jnp.arange(BACK_KNOTS, 0, -1.0), p0[None], p0 + jnp.arange(1.0, n_knots + 1)])
    eps = jnp.concatenate([eps_b[::-1], eps_f])
    tt = jnp.linspace(0.0, float(duration), 257)
    u = _progress_device(m, Z, tt)
    lo, hi = jnp.min(u) - 2.0, jnp.max(u) + 2.0
    inside = (ku[1:] > lo) & (ku[:-1] < hi) & moving & (sigma > 0.0)
    return m._replace(knots_u=ku, knots_p=kp_, slip_draws=eps, inside=inside)


def _fluct_device(m: DeviceMotion, t):
    import jax.numpy as jnp

    arg = 2 * np.pi * m.fluct_freqs * t[..., None] + m.fluct_phases
    c = math.sqrt(2.0 / FLUCTUATION_TERMS)
    s = c * jnp.sum(jnp.cos(arg), axis=-1)
    S = c * jnp.sum((jnp.sin(arg) - jnp.sin(m.fluct_phases)) / (2 * np.pi * m.fluct_freqs), axis=-1)
    return s, S


def _progress_device(m: DeviceMotion, Z, t):
    _, S = _fluct_device(m, t)
    return Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))


def motion_at_device(m: DeviceMotion, Z, t):
    """:func:`motion_at` of a :class:`DeviceMotion` (jit/vmap): (cage angle, shaft angle, shaft
    speed) at times t (any shape)."""
    import jax.numpy as jnp

    s, S = _fluct_device(m, t)
    u = Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))
    p = jnp.interp(u, m.knots_u, m.knots_p)
    return 2 * np.pi / Z * p, m.omega0 * (t + m.fluct * S), m.omega0 * (1.0 + m.fluct * s)


def motion_ok_device(m: DeviceMotion, Z, duration):
    """True where the run's slip knots cover its progress (a knot count too small for the run
    would clamp the cage angle: flagged instead)."""
    import jax.numpy as jnp

    u = _progress_device(m, Z, jnp.linspace(0.0, float(duration), 257))
    return (m.knots_u[0] <= jnp.min(u) - 1.0) & (m.knots_u[-1] >= jnp.max(u) + 1.0)


def device_motion_of(m: Motion, duration=None, block=None):
    """A host :class:`Motion` as a :class:`DeviceMotion` (the same motion: for one simulation's
    time loop, and for a test's hand-made motion).  A run without slip gets exact whole-pitch knots over ``duration`` (s; required
    then).  The knots are padded by whole pitches beyond the last to a multiple of ``block``
    (default: none), so that runs of similar length share one program."""
    import jax.numpy as jnp

    ku, kp = np.asarray(m.knots_u, float), np.asarray(m.knots_p, float)
    if _no_slip(m):
        if duration is None:
            raise InputError("device_motion_of: a run without slip needs its duration (s), got None")
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
    return DeviceMotion(*(jnp.asarray(v, jnp.float64) for v in (m.theta0, m.omega_c, m.omega0, a, f, ph, ku, kp)),
                        jnp.zeros(ku.size - 1), jnp.zeros(ku.size - 1, bool))


def crossing_grid(duration):
    """Points of the dense time grid the crossings are interpolated on (as :func:`_crossings`)."""
    return max(2049, int(float(duration) * 20000))


def crossings_device(m: DeviceMotion, Z, location, center, spin_ratio, offset, duration, count):
    """:func:`_crossings` on the device: the (count,) times in [0, duration] at which the defect
    phase (``location`` static: "outer" | "inner" | "ball") equals ``offset`` modulo its period,
    ascending, padded with +inf; and the number of crossings (more than ``count``: the caller
    flags the run)."""
    import jax.numpy as jnp

    tt = jnp.linspace(0.0, float(duration), crossing_grid(duration))
    theta, phi, _ = motion_at_device(m, Z, tt)
    if location == "outer":
        ph, period, moving = theta - center, 2 * np.pi / Z, m.omega_c > 0.0
    elif location == "inner":
        ph, period, moving = theta - phi - center, 2 * np.pi / Z, m.omega_c > 0.0
    else:
        ph, period, moving = center + spin_ratio * phi, np.pi, True
    dec = ph[-1] < ph[0]                    # the inner spall's phase decreases
    ph = jnp.where(dec, ph[::-1], ph)
    tt = jnp.where(dec, tt[::-1], tt)
    k0 = jnp.ceil((ph[0] - offset) / period)
    k1 = jnp.floor((ph[-1] - offset) / period)
    targets = offset + period * (k0 + jnp.arange(count, dtype=jnp.float64))
    valid = (targets <= ph[-1]) & (ph[-1] > ph[0]) & moving
    times = jnp.where(valid, jnp.interp(targets, ph, tt), jnp.inf)
    n = jnp.where((ph[-1] > ph[0]) & moving, jnp.maximum(k1 - k0 + 1, 0), 0)
    return jnp.sort(times), n


def pass_count(max_shaft_hz, duration, bearing, fluct=0.0, slip=0.0):
    """Static bound on the number of times a ball meets a defect in ``duration`` at shaft speeds
    up to ``max_shaft_hz``: the largest of BPFI <= Z/2 (1 + D/d_m), BPFO <= Z/2 and 2 BSF <=
    d_m / D per shaft turn, with the fluctuation's excursion and 6 sigma of slip, plus 4."""
    g = float(bearing.ball_diameter) / float(bearing.pitch_diameter)
    per_rev = max(0.5 * bearing.n_balls * (1.0 + g), 1.0 / g)
    return int(math.ceil(per_rev * float(max_shaft_hz) * float(duration) * (1.0 + 4.0 * fluct) * (1.0 + 6.0 * slip))) + 4


def defect_times_device(m: DeviceMotion, Z, defects, spin_ratio, duration, count, offsets):
    """Crossing times of every active defect in ``defects`` (a tuple of Spall with traced
    centres, extents and depths; depth 0: inactive, its times +inf) at each of ``offsets``
    ("lo", "mid", "hi": the leading edge, the centre, the trailing edge), sorted, padded with
    +inf: (len(defects) * len(offsets) * count,), and whether every list fitted."""
    import jax.numpy as jnp

    out, ok = [], jnp.bool_(True)
    for sp in defects:
        active = jnp.asarray(sp.depth) > 0.0
        h = 0.5 * jnp.asarray(sp.extent)
        for o in offsets:
            off = {"lo": -h, "mid": 0.0 * h, "hi": h}[o]
            t, n = crossings_device(m, Z, sp.location, jnp.asarray(sp.center), spin_ratio, off, duration, count)
            out.append(jnp.where(active, t, jnp.inf))
            ok = ok & (~active | (n <= count))
    if not out:
        return jnp.full((1,), jnp.inf), ok
    return jnp.sort(jnp.concatenate(out)), ok


def host_motion_of(m: DeviceMotion, Z, seed=0) -> Motion:
    """A (single, concrete) :class:`DeviceMotion` as a host :class:`Motion`: the same cage and
    shaft motion for :func:`motion_at`, :func:`defect_edge_times` and the labels (its knots are
    finite, so :func:`motion_at` interpolates them; ``slip_draws`` those within the run)."""
    g = lambda v: np.asarray(v, float)  # noqa: E731
    eps = g(m.slip_draws)[np.asarray(m.inside, bool)]
    return Motion(float(m.theta0), float(m.omega_c), float(m.omega0), int(Z), float(m.fluct), g(m.fluct_freqs),
                  g(m.fluct_phases), g(m.knots_u), g(m.knots_p), eps, int(seed))


def motion_labels_device(m: DeviceMotion):
    """The per-item motion labels of :func:`motion_labels` that vary per item: the std (%) of
    the slip draws within the run (``pass_jitter_percent``; 0 with fewer than two)."""
    import jax.numpy as jnp

    w = m.inside.astype(jnp.float64)
    n = jnp.sum(w)
    mean = jnp.sum(w * m.slip_draws) / jnp.maximum(n, 1.0)
    var = jnp.sum(w * (m.slip_draws - mean) ** 2) / jnp.maximum(n, 1.0)
    return dict(pass_jitter_percent=jnp.where(n > 1, 100.0 * jnp.sqrt(var), 0.0))
