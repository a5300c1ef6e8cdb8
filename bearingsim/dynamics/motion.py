"""Motion of the balls and the shaft in one run (seeded: slip, speed fluctuation), and the
instants at which a ball meets a defect (docs/model.md sections 7 and 9).

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

import jax
import jax.numpy as jnp
import numpy as np

from ..physics.defect import as_defects
from ..keys import STREAMS
from ..programs import jit
from ..xla import QUICK_COMPILE
from .parameters import Realism

__all__ = ["Motion", "draw_motion", "motion_realism", "motion_at", "motion_ok", "knot_count", "MOTION_STREAM", "crossings",
           "crossing_grid", "pass_count", "defect_times", "motion_labels", "pad_knots", "defect_edge_times",
           "defect_pass_times", "run_labels", "run_motion_at", "FLUCTUATION_TERMS"]

#: sinusoids in the speed fluctuation
FLUCTUATION_TERMS = 8

# ------------------------------------------------------------------- the draw, from a key
# Every run draws its motion from its own ``jax.random`` key (a data set's item inside the
# chunk's compiled program, vmap over items; one simulation from the key of its seed): no host
# work per item.  Every array has a fixed size (set by the duration and the fastest cage), so
# one program serves a data set; what does not fit is flagged (:func:`motion_ok`), never
# cut silently.  The NumPy draw of the same distributions stays in the tests as an independent
# oracle of the statistics (tests/oracles/motion_numpy.py).

class Motion(NamedTuple):
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
    = 4) plus margin.  A run beyond it is flagged by :func:`motion_ok`."""
    span = float(Z) * float(max_cage_hz) * float(duration) * (1.0 + 4.0 * float(fluct))
    return int(math.ceil(2.0 * (span + 4.0))) + 2


def motion_realism(realism: Realism) -> Realism:
    """What of ``realism`` the motion draw reads -- slip, speed fluctuation and its bandwidth -- as
    float64 arrays (traced in a program, so one compiled time loop serves every value of them),
    the rest at its defaults (noise and the pass-to-pass variability belong to the signal
    stage).  Put on the default device explicitly (a chunk runs under ``jax.transfer_guard``)."""
    return Realism(*(jax.device_put(np.float64(v)) for v in (
        realism.slip_percent, realism.speed_fluctuation_percent, realism.speed_fluctuation_bandwidth_Hz)))


def draw_motion(key, Z, theta0, omega_c, omega0, duration, slip_center, realism: Realism, n_knots):
    """One run's cage and shaft motion drawn from a ``jax.random`` key (jit/vmap; ``Z`` and
    ``n_knots`` (:func:`knot_count`) static, the rest traced; ``realism``'s slip and speed
    fluctuation may be Python floats or arrays, :func:`motion_realism`): speed fluctuation of
    :data:`FLUCTUATION_TERMS` random-phase sinusoids, frequencies uniform in (0, B]; the slip
    walk's pitches (1 + eps_k), eps_k ~ N(0, sigma^2) clipped to +-0.5, anchored where a ball is
    at ``slip_center`` (the walk starts at the anchor pitch nearest the run's start: the same
    walk, its anchor an integer number of pitches away).  ``omega_c`` <= 0 (a failed item):
    no slip."""
    k_f, k_b, k_s = jax.random.split(key, 3)
    a = jnp.asarray(realism.speed_fluctuation_percent, jnp.float64) / 100.0
    K = FLUCTUATION_TERMS
    kf, kp = jax.random.split(k_s)
    f = jnp.maximum(jax.random.uniform(kf, (K,), jnp.float64)
                    * jnp.asarray(realism.speed_fluctuation_bandwidth_Hz, jnp.float64), 1e-3)
    ph = jax.random.uniform(kp, (K,), jnp.float64, 0.0, 2 * np.pi)
    theta0, omega_c, omega0 = (jnp.asarray(v, jnp.float64) for v in (theta0, omega_c, omega0))
    sigma = jnp.asarray(realism.slip_percent, jnp.float64) / 100.0
    moving = omega_c > 0.0
    eps_f = jnp.clip(jax.random.normal(k_f, (n_knots,), jnp.float64) * sigma, -0.5, 0.5)
    eps_b = jnp.clip(jax.random.normal(k_b, (BACK_KNOTS,), jnp.float64) * sigma, -0.5, 0.5)
    eps_f, eps_b = jnp.where(moving, eps_f, 0.0), jnp.where(moving, eps_b, 0.0)
    m = Motion(theta0, omega_c, omega0, jnp.asarray(a, jnp.float64), f, ph, jnp.zeros(2), jnp.zeros(2),
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
    u = _progress(m, Z, tt)
    lo, hi = jnp.min(u) - 2.0, jnp.max(u) + 2.0
    inside = (ku[1:] > lo) & (ku[:-1] < hi) & moving & (sigma > 0.0)
    return m._replace(knots_u=ku, knots_p=kp_, slip_draws=eps, inside=inside)


def _fluct(m: Motion, t):
    arg = 2 * np.pi * m.fluct_freqs * t[..., None] + m.fluct_phases
    c = math.sqrt(2.0 / FLUCTUATION_TERMS)
    s = c * jnp.sum(jnp.cos(arg), axis=-1)
    S = c * jnp.sum((jnp.sin(arg) - jnp.sin(m.fluct_phases)) / (2 * np.pi * m.fluct_freqs), axis=-1)
    return s, S


def _progress(m: Motion, Z, t):
    _, S = _fluct(m, t)
    return Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))


def motion_at(m: Motion, Z, t):
    """(cage angle, shaft angle, shaft speed) of the run at times t (any shape; jit/vmap):
    theta_c = 2 pi / Z p(u), u the nominal progress with the speed fluctuation, p the slip walk
    interpolated between its knots; phi = omega_0 (t + a S(t)); omega = omega_0 (1 + a s(t))."""
    s, S = _fluct(m, t)
    u = Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))
    p = jnp.interp(u, m.knots_u, m.knots_p)
    return 2 * np.pi / Z * p, m.omega0 * (t + m.fluct * S), m.omega0 * (1.0 + m.fluct * s)


def motion_ok(m: Motion, Z, duration):
    """True where the run's slip knots cover its progress (a knot count too small for the run
    would clamp the cage angle: flagged instead)."""
    u = _progress(m, Z, jnp.linspace(0.0, float(duration), 257))
    return (m.knots_u[0] <= jnp.min(u) - 1.0) & (m.knots_u[-1] >= jnp.max(u) + 1.0)


def crossing_grid(duration):
    """Points of the dense time grid the crossings are interpolated on (as :func:`_crossings`)."""
    return max(2049, int(float(duration) * 20000))


def crossings(m: Motion, Z, location, center, spin_ratio, offset, duration, count):
    """The (count,) times in [0, duration] at which the defect
    phase (``location`` static: "outer" | "inner" | "ball") equals ``offset`` modulo its period,
    ascending, padded with +inf; and the number of crossings (more than ``count``: the caller
    flags the run)."""
    tt = jnp.linspace(0.0, float(duration), crossing_grid(duration))
    theta, phi, _ = motion_at(m, Z, tt)
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


def defect_times(m: Motion, Z, defects, spin_ratio, duration, count, offsets):
    """Crossing times of every active defect in ``defects`` (a tuple of Spall with traced
    centres, extents and depths; depth 0: inactive, its times +inf) at each of ``offsets``
    ("lo", "mid", "hi": the leading edge, the centre, the trailing edge), sorted, padded with
    +inf: (len(defects) * len(offsets) * count,), and whether every list fitted."""
    out, ok = [], jnp.bool_(True)
    for sp in defects:
        active = jnp.asarray(sp.depth) > 0.0
        h = 0.5 * jnp.asarray(sp.extent)
        for o in offsets:
            off = {"lo": -h, "mid": 0.0 * h, "hi": h}[o]
            t, n = crossings(m, Z, sp.location, jnp.asarray(sp.center), spin_ratio, off, duration, count)
            out.append(jnp.where(active, t, jnp.inf))
            ok = ok & (~active | (n <= count))
    if not out:
        return jnp.full((1,), jnp.inf), ok
    return jnp.sort(jnp.concatenate(out)), ok


def motion_labels(m: Motion):
    """The per-item motion labels (jit/vmap): the std (%) of the slip draws within the run
    (``pass_jitter_percent``; 0 with fewer than two)."""
    w = m.inside.astype(jnp.float64)
    n = jnp.sum(w)
    mean = jnp.sum(w * m.slip_draws) / jnp.maximum(n, 1.0)
    var = jnp.sum(w * (m.slip_draws - mean) ** 2) / jnp.maximum(n, 1.0)
    return dict(pass_jitter_percent=jnp.where(n > 1, 100.0 * jnp.sqrt(var), 0.0))


# ------------------------------------------------------------------- one run on the host
# A single run (``simulate``) evaluates the same functions eagerly on its one motion: no
# second version of a formula.

def pad_knots(m: Motion, block=256) -> Motion:
    """``m`` with its slip knots padded by whole pitches beyond the last to a multiple of
    ``block`` (runs of similar length then share one time-loop program; the interpolation
    inside the run is unchanged)."""
    ku, kp = np.asarray(m.knots_u, float), np.asarray(m.knots_p, float)
    n = int(block) * (ku.size // int(block) + 1)
    extra = np.arange(1, n - ku.size + 1, dtype=float)
    ku, kp = np.concatenate([ku, ku[-1] + extra]), np.concatenate([kp, kp[-1] + extra])
    z = np.zeros(n - 1)
    return m._replace(knots_u=ku, knots_p=kp, slip_draws=z, inside=z.astype(bool))


#: one run's motion at its samples, and its defect times: compiled programs (kept, loaded warm),
#: not op-by-op dispatch (each eager op is a small program of its own)
run_motion_at = jit(motion_at)


def _defect_times_only(m, Z, defects, spin_ratio, duration, count, offsets):
    return defect_times(m, Z, defects, spin_ratio, duration, count, offsets)[0]


_defect_times_jit = jit(_defect_times_only, options=QUICK_COMPILE)     # once per simulation: -O0


def _times(m: Motion, Z, spalls, duration, spin_ratio, offsets):
    active = tuple(sp for sp in as_defects(spalls) if sp is not None and float(sp.depth) > 0.0)
    if not active:
        return np.zeros(0)
    # the list's length: the largest phase span over the run in periods, plus margin, rounded up
    # to a power of two (few programs)
    theta, phi, _ = (np.asarray(v) for v in run_motion_at(m, Z, np.linspace(0.0, float(duration), 65)))
    need = 0
    for sp in active:
        span = {"outer": theta, "inner": theta - phi, "ball": float(spin_ratio) * phi}[sp.location]
        period = np.pi if sp.location == "ball" else 2 * np.pi / Z
        need = max(need, int(np.ceil(float(np.ptp(span)) / period)) + 4)
    count = 1 << max(need - 1, 7).bit_length()
    t = np.asarray(_defect_times_jit(m, Z, active, np.float64(spin_ratio), float(duration), count,
                                     tuple(offsets)))
    return np.unique(t[np.isfinite(t)])


def defect_edge_times(m: Motion, Z, spalls, duration, spin_ratio=0.0):
    """Times (s) within [0, duration] at which a ball (or the pit) enters or leaves a defect
    (``spalls``: a Spall or a tuple; depth-0 ones ignored): :func:`crossings` of one run."""
    return _times(m, Z, spalls, duration, spin_ratio, ("lo", "hi"))


def defect_pass_times(m: Motion, Z, spalls, duration, spin_ratio=0.0):
    """Times (s) within [0, duration] at which a ball centre passes a raceway defect's centre, or
    the pit passes a contact centre (``spalls``: a Spall or a tuple; depth-0 ones ignored)."""
    return _times(m, Z, spalls, duration, spin_ratio, ("mid",))


def run_labels(m: Motion, realism: Realism, seed=0) -> dict:
    """The motion labels of one run: its seed, the realism settings, the slip draws within the
    run and their std (%), the fluctuation's frequencies."""
    eps = np.asarray(m.slip_draws, float)[np.asarray(m.inside, bool)]
    fluct = float(m.fluct) > 0.0
    return dict(seed=int(seed), slip_percent=float(realism.slip_percent),
                slip_draws=eps, pass_jitter_percent=float(100.0 * eps.std()) if eps.size > 1 else 0.0,
                speed_fluctuation_percent=float(realism.speed_fluctuation_percent),
                speed_fluctuation_bandwidth_Hz=float(realism.speed_fluctuation_bandwidth_Hz),
                speed_fluctuation_frequencies_Hz=np.asarray(m.fluct_freqs, float) if fluct else np.zeros(0),
                noise_rms=float(realism.noise_rms),
                noise_band=(np.asarray(realism.noise_band, float) if realism.noise_band else np.zeros(0)))
