"""ISO/TS 16281 basic reference rating life of ball bearings from their load distribution
(docs/model.md section 11).

Every function is pure ``jax.numpy``, SI (N, m, rad) and batchable over leading axes; per-ball
arrays have the balls on the last axis.  With C the basic dynamic load rating (catalogue, N),
i rows, alpha the nominal contact angle (``Bearing.free_contact_angle``), gamma = D cos alpha /
d_m, rho = (f_i/f_o)(2 f_o - 1)/(2 f_i - 1) and t = 1.044 ((1 - gamma)/(1 + gamma))^1.72 rho^0.41:

    Q_ci = C / (0.407 Z (i cos alpha)^0.7) (1 + t^(10/3))^0.3        (inner ring, rotating)
    Q_co = C / (0.389 Z (i cos alpha)^0.7) (1 + t^(-10/3))^0.3       (outer ring, stationary)
    Q_ei = (sum_j Q_ij^3 / Z)^(1/3),  Q_eo = (sum_j Q_oj^(10/3) / Z)^(3/10)
    L10r = ((Q_ci/Q_ei)^(-10/3) + (Q_co/Q_eo)^(-10/3))^(-9/10)        (10^6 revolutions)

The cube mean of the rotating inner ring and the 10/3-power mean of the stationary outer ring
are the ISO/TS 16281 (ISO 281 background, Lundberg-Palmgren) equivalent loads: a point of the
rotating ring meets every ball's load, a point of the stationary ring only its own ball's.  At
speed each ball's own inner and outer contact loads enter (``JonesSolution.Q_inner`` /
``Q_outer``).  Bearings of a set (or the two rings of one bearing) fail independently, the
Weibull slope e = 10/9 of ball bearings gives L = (sum_k L_k^(-10/9))^(-9/10).

Hours: L10r 1e6 / (60 n) with the inner-ring speed n in rpm (:func:`life_hours`); the core's
speeds are rad/s, so :func:`life_hours` takes rad/s (``Operation.speed``) and
:func:`life_hours_rpm` rpm.

A bearing with a ring that carries no load lives forever on that ring (its term is 0); a bearing
that carries no load at all has an infinite life (``inf``), which is the limit of the formula.
"""
from __future__ import annotations

import jax.numpy as jnp

from ..hostarrays import f64

__all__ = [
    "WEIBULL_SLOPE",
    "nominal_angle",
    "contact_load_ratings",
    "equivalent_loads",
    "ring_lives",
    "rating_life",
    "set_life",
    "life_hours",
    "life_hours_rpm",
]

#: Weibull slope e of ball bearings (ISO 281): L_set = (sum L_k^(-e))^(-1/e).
WEIBULL_SLOPE = 10.0 / 9.0


_f64 = f64             # bearingsim.hostarrays: NumPy unless traced


def nominal_angle(bearing, contact_angle=None):
    """The nominal contact angle alpha of ISO 281 / ISO/TS 16281 (rad): ``contact_angle`` when
    given, else ``bearing.free_contact_angle``.  A deep-groove bearing's nominal angle is 0 even
    when its clearance gives it a free contact angle (``Bearing.from_clearance``): pass 0 then
    (the ISO/TS 16281 example 3 of docs/reference-data.md, 0.010 mm clearance, alpha_0 = 7.6 deg,
    agrees to 7e-5 with alpha = 0 and is 1.9 % off with alpha = alpha_0)."""
    return bearing.free_contact_angle if contact_angle is None else _f64(contact_angle)


def contact_load_ratings(bearing, C, rows=1, *, contact_angle=None):
    """Basic dynamic load ratings of a single contact (N): ``(Q_ci, Q_co)`` of the inner
    (rotating) and outer (stationary) raceway, from the bearing's dynamic load rating ``C`` (N)
    and its number of rows.  ``alpha`` is the nominal contact angle (:func:`nominal_angle`)."""
    C = _f64(C)
    D, dm = bearing.ball_diameter, bearing.pitch_diameter
    fi, fo = bearing.f_inner, bearing.f_outer
    alpha = nominal_angle(bearing, contact_angle)
    Z = bearing.n_balls
    gamma = D * jnp.cos(alpha) / dm
    rho = (fi / fo) * (2.0 * fo - 1.0) / (2.0 * fi - 1.0)
    t = 1.044 * ((1.0 - gamma) / (1.0 + gamma)) ** 1.72 * rho ** 0.41
    base = (rows * jnp.cos(alpha)) ** 0.7 * Z
    Q_ci = C / (0.407 * base) * (1.0 + t ** (10.0 / 3.0)) ** 0.3
    Q_co = C / (0.389 * base) * (1.0 + t ** (-10.0 / 3.0)) ** 0.3
    return Q_ci, Q_co


def equivalent_loads(Q_inner, Q_outer):
    """Equivalent contact loads (N) over the last axis (balls): ``(Q_ei, Q_eo)`` with the cube
    mean of the rotating inner ring and the 10/3-power mean of the stationary outer ring.
    Negative loads (none in a valid state) count as 0."""
    Qi = jnp.maximum(_f64(Q_inner), 0.0)
    Qo = jnp.maximum(_f64(Q_outer), 0.0)
    return _root(jnp.mean(Qi ** 3, axis=-1), 3.0), _root(jnp.mean(Qo ** (10.0 / 3.0), axis=-1), 10.0 / 3.0)


def _root(m, p):
    """m^(1/p) with 0 (and a zero, not NaN, derivative) at m = 0."""
    return jnp.where(m > 0.0, jnp.where(m > 0.0, m, 1.0) ** (1.0 / p), 0.0)


def _safe_ratio_power(Q_e, Q_c):
    """(Q_c / Q_e)^(-10/3) = (Q_e / Q_c)^(10/3): 0 for an unloaded ring (no NaN, safe gradient)."""
    return (Q_e / Q_c) ** (10.0 / 3.0)


def ring_lives(bearing, C, Q_inner, Q_outer, rows=1, *, contact_angle=None):
    """Rating lives of the inner and outer ring alone (10^6 revolutions): ``(L_i, L_o)``,
    ``L = (Q_c/Q_e)^3``; ``inf`` for a ring without load.  ``set_life((L_i, L_o))`` is
    :func:`rating_life`."""
    Q_ci, Q_co = contact_load_ratings(bearing, C, rows, contact_angle=contact_angle)
    Q_ei, Q_eo = equivalent_loads(Q_inner, Q_outer)
    with_inf = lambda Qc, Qe: jnp.where(Qe > 0.0, (Qc / jnp.where(Qe > 0.0, Qe, 1.0)) ** 3, jnp.inf)
    return with_inf(Q_ci, Q_ei), with_inf(Q_co, Q_eo)


def rating_life(bearing, C, Q_inner, Q_outer, rows=1, *, contact_angle=None):
    """ISO/TS 16281 basic reference rating life L10r (10^6 revolutions) of one bearing from its
    per-ball contact loads (N, balls on the last axis): ``inf`` when no ball is loaded.
    ``contact_angle``: the nominal angle (:func:`nominal_angle`; 0 for a deep-groove bearing)."""
    Q_ci, Q_co = contact_load_ratings(bearing, C, rows, contact_angle=contact_angle)
    Q_ei, Q_eo = equivalent_loads(Q_inner, Q_outer)
    s = _safe_ratio_power(Q_ei, Q_ci) + _safe_ratio_power(Q_eo, Q_co)
    return jnp.where(s > 0.0, jnp.where(s > 0.0, s, 1.0) ** (-0.9), jnp.inf)


def set_life(lives):
    """Life of bearings that fail independently (a set, or the rings of one bearing):
    ``(sum_k L_k^(-10/9))^(-9/10)`` over the last axis; infinite lives drop out."""
    L = _f64(lives)
    s = jnp.sum(jnp.where(jnp.isfinite(L), L ** (-WEIBULL_SLOPE), 0.0), axis=-1)
    return jnp.where(s > 0.0, jnp.where(s > 0.0, s, 1.0) ** (-1.0 / WEIBULL_SLOPE), jnp.inf)


def life_hours(L10r, speed):
    """Life in hours at the inner-ring speed ``speed`` in rad/s (``Operation.speed``):
    L10r 1e6 / (60 n), n = 60 speed / (2 pi) rpm; ``inf`` at standstill."""
    speed = _f64(speed)
    rev_per_hour = speed / (2.0 * jnp.pi) * 3600.0
    return jnp.where(rev_per_hour > 0.0, _f64(L10r) * 1e6 / jnp.where(rev_per_hour > 0.0, rev_per_hour, 1.0),
                     jnp.inf)


def life_hours_rpm(L10r, speed_rpm):
    """Life in hours at the inner-ring speed ``speed_rpm`` in rpm: L10r 1e6 / (60 n)."""
    return life_hours(L10r, _f64(speed_rpm) * (2.0 * jnp.pi / 60.0))
