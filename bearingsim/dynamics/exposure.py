"""A ball pit's exposure to the raceways, pass by pass, from the ball kinematics (issue 33;
docs/physics.md §8.3).

A pit on a ball strikes a raceway only where the ball's rolling track runs over it.  Frame: the
pitted ball's centre, ``e_r`` radial outward, ``e_z`` axial, ``e_t`` the rolling direction.  The
outer contact normal is ``n_o = cos(a_o) e_r + sin(a_o) e_z``, the inner contact lies at ``-n_i``
(docs/model.md §1), and raceway control (:func:`bearingsim.physics.kinematics.ball_kinematics`,
Harris & Kotzalas 2007, Vol. 2 ch. 2) gives the spin axis its pitch ``beta``, yaw 0:
``w0 = -sin(beta) e_r + cos(beta) e_z`` (so ``n_o . w0 = sin(a_o - beta)``: the rolling radius
``R cos(a_o - beta)`` of docs/model.md §8).  The axis wanders by a pitch ``dp`` (in the plane of
the bearing axis and the contact normal) and a yaw ``dy`` (toward the rolling direction):

    w = cos(dy) [-sin(beta + dp) e_r + cos(beta + dp) e_z] + sin(dy) e_t,

so the contacts' latitudes above the spin equator are (:func:`contact_latitudes`)

    sin(lat_o) = n_o . w = cos(dy) sin(a_o - beta - dp),   sin(lat_i) = -n_i . w = -cos(dy) sin(a_i - beta - dp)

(the yaw turns the spin equator about the contact normal: it moves a track only at second order).
A contact's rolling track on the ball is the circle of its latitude, of half-width the Hertz
semi-axis across rolling ``a`` (the major semi-axis, bearingsim.physics.hertz).  The pit, a disc of
radius ``r`` fixed on the ball at latitude ``lat_p`` above the nominal spin equator, keeps that
latitude while the axis wanders slowly against the spin (correlation times of cage revolutions,
several ball turns each), and passes contact ``c`` at the lateral offset ``R (lat_p - lat_c)``
from the track's centre line.  Its exposure on that pass is the fraction of its area inside the
track (:func:`strip_overlap`, 0..1; flat: ``r << R``).  Crossings alternate outer / inner at
2 BSF (a ball pit's pass times, :func:`bearingsim.dynamics.motion.crossings`: spin angle 0 is the
outer contact), and pitch and yaw are stationary Ornstein-Uhlenbeck processes in the ball's orbit
(:func:`wander`: s.d. ``sd``, correlation ``corr`` cage revolutions), sampled at the passes.

Everything is pure JAX (float64, SI), a function of the item's ``ball_exposure`` stream
(:data:`bearingsim.keys.STREAMS`) and its traced scalars: ``jax.vmap`` over items.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp

__all__ = ["EXPOSURE_DEFAULTS", "TRACK_FIELDS", "ball_track", "strip_overlap", "contact_latitudes", "wander",
           "draw_exposure", "pass_contacts", "pass_exposure", "exposure_at", "pass_distance"]

#: the per-item draws of the kinematic exposure (lo, hi), uniform, SI (rad; cage revolutions)
EXPOSURE_DEFAULTS = {
    "pit_latitude": (-0.1745329251994330, 0.1745329251994330),   # +-10 deg above/below the spin equator
    "wander_sd": (0.0174532925199433, 0.1047197551196598),       # 1-6 deg (pitch and yaw s.d.)
    "wander_correlation": (0.5, 2.0),                            # cage revolutions
}

#: the fields of :func:`ball_track` (one (7,) row per item)
TRACK_FIELDS = ("beta", "alpha_outer", "alpha_inner", "a_outer", "a_inner", "ball_radius", "pit_radius")


def ball_track(bearing, sol, pit_extent):
    """(7,) the pit's track geometry of one quasi-static state ``sol`` (a JonesSolution) in
    :data:`TRACK_FIELDS` order, SI: the spin-axis pitch, the contact angles and the Hertz
    semi-axes across rolling of the most loaded ball (largest outer load: the track the loaded
    passes roll; an estimate for the pitted ball anywhere in the load zone), the ball radius and
    the pit radius from ``pit_extent`` (the angle the pit subtends at the ball centre, rad)."""
    j = jnp.argmax(jnp.where(jnp.isfinite(sol.Q_outer), sol.Q_outer, -jnp.inf))
    R = 0.5 * bearing.ball_diameter
    return jnp.stack([sol.beta[j], sol.alpha_outer[j], sol.alpha_inner[j], sol.a_outer[j], sol.a_inner[j],
                      R + 0.0 * sol.beta[j], 0.5 * pit_extent * R])


def _disc_below(h, r):
    """Area of a disc of radius ``r`` (centre 0) below the line ``y = h``."""
    u = jnp.clip(h / r, -1.0, 1.0)
    return r * r * (jnp.arccos(-u) + u * jnp.sqrt(1.0 - u * u))


def strip_overlap(offset, half_width, radius):
    """The fraction (0..1) of a disc of ``radius`` whose centre lies ``offset`` from the centre
    line of a strip of ``half_width`` (same length unit) inside the strip:
    ``[S(w - d) - S(-w - d)] / (pi r^2)``, ``S(h) = r^2 (acos(-h/r) + (h/r) sqrt(1 - h^2/r^2))``
    (the disc's area below ``y = h``)."""
    r = jnp.maximum(radius, 1e-300)
    e = (_disc_below(half_width - offset, r) - _disc_below(-half_width - offset, r)) / (jnp.pi * r * r)
    return jnp.clip(e, 0.0, 1.0)


def contact_latitudes(track, pitch, yaw):
    """(outer, inner) latitudes (rad) of the contacts above the spin equator of the axis at
    pitch ``beta + pitch`` and yaw ``yaw`` (module docstring); ``track`` a :func:`ball_track` row."""
    beta, a_o, a_i = track[0], track[1], track[2]
    c = jnp.cos(yaw)
    lat_o = jnp.arcsin(jnp.clip(c * jnp.sin(a_o - beta - pitch), -1.0, 1.0))
    lat_i = jnp.arcsin(jnp.clip(-c * jnp.sin(a_i - beta - pitch), -1.0, 1.0))
    return lat_o, lat_i


def wander(key, u, sd, corr):
    """A stationary Ornstein-Uhlenbeck process of s.d. ``sd`` and correlation ``corr`` (in the
    unit of ``u``) sampled at the ascending ``u`` (P,) (+inf padded: 0 there), exactly:
    ``x_0 = sd xi_0``, ``x_k = rho_k x_(k-1) + sd sqrt(1 - rho_k^2) xi_k``, ``rho_k = exp(-(u_k -
    u_(k-1)) / corr)``."""
    xi = jax.random.normal(key, u.shape, jnp.float64)
    fin = jnp.isfinite(u)
    uu = jnp.where(fin, u, 0.0)
    du = jnp.concatenate([jnp.zeros(1), jnp.maximum(uu[1:] - uu[:-1], 0.0)])
    rho = jnp.exp(-du / jnp.maximum(corr, 1e-300))
    rho = rho.at[0].set(0.0)
    q = jnp.sqrt(jnp.maximum(1.0 - rho * rho, 0.0))

    def step(x, a):
        r, s, z = a
        y = r * x + sd * s * z
        return y, y

    _, x = jax.lax.scan(step, jnp.zeros((), jnp.float64), (rho, q, xi))
    return jnp.where(fin, x, 0.0)


def draw_exposure(key, ranges=None):
    """(pit latitude rad, wander s.d. rad, wander correlation cage revolutions) of one item,
    uniform in ``ranges`` (:data:`EXPOSURE_DEFAULTS` keys; missing ones take the defaults)."""
    r = dict(EXPOSURE_DEFAULTS, **dict(ranges or {}))
    k = jax.random.split(key, 3)
    return tuple(jax.random.uniform(kk, (), jnp.float64, *r[n])
                 for kk, n in zip(k, ("pit_latitude", "wander_sd", "wander_correlation")))


def pass_contacts(pass_times, spin_angle0):
    """(P,) True where a ball pit's pass meets the outer raceway: the passes alternate at half a
    ball turn, the first at spin angle ``pi ceil(spin_angle0 / pi)`` (even multiples of pi: the
    outer contact, :func:`bearingsim.dynamics.motion.crossings`)."""
    m0 = jnp.ceil(spin_angle0 / jnp.pi)
    k = jnp.arange(pass_times.shape[0], dtype=jnp.float64)
    return jnp.mod(m0 + k, 2.0) == 0.0


def pass_exposure(key, pass_times, ftf_hz, spin_angle0, track, pit_latitude, sd, corr):
    """(P,) the exposure (0..1) of a ball pit on each of its passes ``pass_times`` (P,) s
    (ascending, +inf padded: 0 there), module docstring: the axis's pitch and yaw wander
    (:func:`wander`, two independent processes of ``sd`` rad and ``corr`` cage revolutions at the
    passes' cage revolutions ``ftf_hz t``) from ``key``, the contacts' latitudes
    (:func:`contact_latitudes`), the pit's offset from each track's centre line and its overlap
    with the track (:func:`strip_overlap`).  ``track``: a :func:`ball_track` row."""
    u = ftf_hz * pass_times
    kp, ky = jax.random.split(key)
    pitch, yaw = wander(kp, u, sd, corr), wander(ky, u, sd, corr)
    lat_o, lat_i = contact_latitudes(track, pitch, yaw)
    outer = pass_contacts(pass_times, spin_angle0)
    R, r = track[5], track[6]
    offset = R * (pit_latitude - jnp.where(outer, lat_o, lat_i))
    e = strip_overlap(offset, jnp.where(outer, track[3], track[4]), r)
    return jnp.where(jnp.isfinite(pass_times), e, 0.0)


def exposure_at(t, pass_times, exposure):
    """The exposure as a function of time at ``t`` (T,): linear between the finite passes'
    values, the first (last) one before (after) them; 1 with no pass."""
    fin = jnp.isfinite(pass_times)
    n = jnp.sum(fin)
    last_t = jnp.max(jnp.where(fin, pass_times, -jnp.inf))
    last_e = exposure[jnp.maximum(n - 1, 0)]
    k = jnp.arange(pass_times.shape[0], dtype=jnp.float64)
    # padded knots continue past the last pass, increasing, with its value
    xp = jnp.where(fin, pass_times, jnp.where(n > 0, last_t, 0.0) + 1.0 + k)
    fp = jnp.where(fin, exposure, last_e)
    return jnp.where(n > 0, jnp.interp(t, xp, fp), 1.0)


def pass_distance(t, pass_times):
    """(T,) the time (s) from each of ``t`` to the nearest finite pass (+inf with none)."""
    tp = jnp.where(jnp.isfinite(pass_times), pass_times, jnp.inf)
    if tp.shape[0] == 1:
        return jnp.abs(t - tp[0])
    i = jnp.clip(jnp.searchsorted(tp, t), 1, tp.shape[0] - 1)
    return jnp.minimum(jnp.abs(t - tp[i - 1]), jnp.abs(tp[i] - t))
