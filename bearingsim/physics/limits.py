"""Limits of a healthy bearing's state, per contact (docs/model.md section 11): contact pressure, the
friction coefficient that raceway control needs, the contact ellipse against the shoulders.

Pure ``jax.numpy`` on a :class:`~bearingsim.physics.jones.JonesSolution` (any leading batch axes, balls
last) and its :class:`~bearingsim.physics.geometry.Bearing` and :class:`~bearingsim.physics.kinematics.Operation`;
SI and radians.  Nothing here refuses a state: the margins and flags are for the report (every
solve refuses a state whose loaded contact centre lies at or beyond a shoulder edge, result
``over_shoulder`` or ``low_shoulder``, by the same rule: :func:`bearingsim.physics.jones.shoulder_crossings`).

* Pressure: ``p_max / pressure_limit`` per contact; the ISO 76 static-capacity stress of ball
  bearings, 4.2 GPa, is the default (permanent deformation ~1e-4 D starts there).
* Friction: the raceway-control hypothesis (docs/model.md section 4) makes the controlling contact's friction
  supply the whole gyroscopic moment M_g: the friction force lambda M_g / D at a contact with
  control factor lambda (outer control: 2 M_g / D at the outer contact), so the friction
  coefficient it needs is mu = lambda |M_g| / (D Q).  ``friction_ratio`` = mu / (the available
  coefficient): above 1 the ball spins (gyroscopic slip) and the hypothesis does not hold.
  A contact without load (Q = 0) needs nothing (0).
* Shoulders: a contact at angle alpha on a groove of radius f D has its ellipse's half-width a
  (the semi-major axis, across the rolling direction, in the groove's cross-section) subtend
  a / (f D) on the groove; the groove spans -theta_low..theta_high (``Bearing.shoulders``).
  Margins (rad, negative = over the edge): high theta_high - (alpha + a/(fD)), low
  theta_low + (alpha - a/(fD)).  ``truncated``: a loaded contact's ellipse runs over an edge;
  ``over_shoulder``: a loaded contact's centre lies at or beyond an edge.
"""
from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from ..hostarrays import host, xp
from .kinematics import CONTROL_FACTORS

__all__ = ["PRESSURE_LIMIT", "FRICTION_COEFFICIENT", "ContactLimits", "contact_limits",
           "required_friction", "edge_margins"]

#: ISO 76 static-capacity stress of ball bearings (Pa)
PRESSURE_LIMIT = 4.2e9
#: default available friction (traction) coefficient at a raceway contact: an estimate for a
#: lubricated steel contact (EHL traction coefficients are ~0.03-0.1); a case key sets it
FRICTION_COEFFICIENT = 0.07


class ContactLimits(eqx.Module):
    """Per-contact margins and flags (shapes as the solution's per-ball arrays, (..., Z)); the
    ``any_*`` properties reduce the balls."""

    pressure_ratio_inner: jnp.ndarray      # p_max / pressure limit
    pressure_ratio_outer: jnp.ndarray
    friction_inner: jnp.ndarray            # friction coefficient raceway control needs there
    friction_outer: jnp.ndarray
    friction_ratio: jnp.ndarray            # max(friction_inner, friction_outer) / available
    edge_high_inner: jnp.ndarray           # rad, negative: over the high shoulder's edge
    edge_low_inner: jnp.ndarray
    edge_high_outer: jnp.ndarray
    edge_low_outer: jnp.ndarray
    truncated_inner: jnp.ndarray           # bool: a loaded contact's ellipse runs over an edge
    truncated_outer: jnp.ndarray
    over_shoulder_inner: jnp.ndarray       # bool: a loaded contact's centre is at or beyond an edge
    over_shoulder_outer: jnp.ndarray

    # NumPy on a concrete result, JAX on a traced one (bearingsim.hostarrays)
    @property
    def overpressure(self):
        """(..., Z) bool: a contact above the pressure limit."""
        return (host(self.pressure_ratio_inner) > 1.0) | (host(self.pressure_ratio_outer) > 1.0)

    @property
    def slip(self):
        """(..., Z) bool: raceway control needs more friction than is available."""
        return host(self.friction_ratio) > 1.0

    @property
    def truncated(self):
        return host(self.truncated_inner) | host(self.truncated_outer)

    @property
    def over_shoulder(self):
        return host(self.over_shoulder_inner) | host(self.over_shoulder_outer)

    @property
    def any_overpressure(self):
        x = self.overpressure
        return xp(x).any(x, axis=-1)

    @property
    def any_slip(self):
        x = self.slip
        return xp(x).any(x, axis=-1)

    @property
    def any_truncated(self):
        x = self.truncated
        return xp(x).any(x, axis=-1)

    @property
    def any_over_shoulder(self):
        x = self.over_shoulder
        return xp(x).any(x, axis=-1)

    @property
    def max_pressure_ratio(self):
        pi, po = host(self.pressure_ratio_inner), host(self.pressure_ratio_outer)
        x = xp(pi, po)
        return x.maximum(x.max(pi, axis=-1), x.max(po, axis=-1))

    @property
    def max_friction_ratio(self):
        f = host(self.friction_ratio)
        return xp(f).max(f, axis=-1)

    @property
    def min_edge_margin(self):
        """Smallest edge margin over the contacts (rad; pi when no contact is loaded)."""
        e = [host(v) for v in (self.edge_high_inner, self.edge_low_inner, self.edge_high_outer, self.edge_low_outer)]
        x = xp(*e)
        return x.min(x.minimum(x.minimum(e[0], e[1]), x.minimum(e[2], e[3])), axis=-1)


def required_friction(sol, bearing, control="outer"):
    """(mu_inner, mu_outer): the friction coefficient each contact must supply under the raceway
    control hypothesis ``control``: lambda |M_g| / (D Q), 0 where Q = 0 or lambda = 0."""
    lam_i, lam_o = CONTROL_FACTORS[control]
    D = bearing.ball_diameter
    Mg = jnp.abs(sol.gyroscopic_moment)

    def mu(lam, Q):
        return jnp.where(Q > 0.0, lam * Mg / (D * jnp.where(Q > 0.0, Q, 1.0)), 0.0)

    return mu(lam_i, sol.Q_inner), mu(lam_o, sol.Q_outer)


def edge_margins(sol, bearing):
    """Edge margins (rad) of every contact ellipse: (high_inner, low_inner, high_outer,
    low_outer); contacts without load get pi (no constraint)."""
    D = bearing.ball_diameter
    sh = bearing.shoulders
    th = [sh[..., k, None] for k in range(4)]          # broadcast against (..., Z)

    def margins(alpha, a, f, hi, lo, Q):
        half = a / (f * D)
        loaded = Q > 0.0
        return (jnp.where(loaded, hi - (alpha + half), jnp.pi),
                jnp.where(loaded, lo + (alpha - half), jnp.pi))

    hi_i, lo_i = margins(sol.alpha_inner, sol.a_inner, bearing.f_inner, th[0], th[1], sol.Q_inner)
    hi_o, lo_o = margins(sol.alpha_outer, sol.a_outer, bearing.f_outer, th[2], th[3], sol.Q_outer)
    return hi_i, lo_i, hi_o, lo_o


def contact_limits(sol, bearing, control="outer", *, pressure_limit=PRESSURE_LIMIT,
                   friction_coefficient=FRICTION_COEFFICIENT) -> ContactLimits:
    """Per-contact limits of the state ``sol`` of ``bearing`` under raceway control ``control``
    (``Operation.control``).  ``pressure_limit`` (Pa) and ``friction_coefficient`` may be arrays
    broadcasting against the batch axes."""
    pl = jnp.asarray(pressure_limit, jnp.float64)[..., None]
    mu_av = jnp.asarray(friction_coefficient, jnp.float64)[..., None]
    mu_i, mu_o = required_friction(sol, bearing, control)
    hi_i, lo_i, hi_o, lo_o = edge_margins(sol, bearing)
    sh = bearing.shoulders
    th = [sh[..., k, None] for k in range(4)]
    li, lo = sol.Q_inner > 0.0, sol.Q_outer > 0.0
    over_i = li & ((sol.alpha_inner >= th[0]) | (sol.alpha_inner <= -th[1]))
    over_o = lo & ((sol.alpha_outer >= th[2]) | (sol.alpha_outer <= -th[3]))
    return ContactLimits(
        pressure_ratio_inner=sol.p_max_inner / pl, pressure_ratio_outer=sol.p_max_outer / pl,
        friction_inner=mu_i, friction_outer=mu_o, friction_ratio=jnp.maximum(mu_i, mu_o) / mu_av,
        edge_high_inner=hi_i, edge_low_inner=lo_i, edge_high_outer=hi_o, edge_low_outer=lo_o,
        truncated_inner=li & (jnp.minimum(hi_i, lo_i) < 0.0),
        truncated_outer=lo & (jnp.minimum(hi_o, lo_o) < 0.0),
        over_shoulder_inner=over_i, over_shoulder_outer=over_o)
