"""Localized spall on the outer raceway (MODEL.md section 5).

A spall is a depth profile H(psi) that reduces the outer contact deformation of
a ball at azimuth psi: delta_o = L_o - (f_o - 1/2) D - H(psi).  Both profiles
are differentiable with respect to depth and extent.
"""
from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

PROFILES = ("rectangular", "ball-path")


def _f64(x):
    return jnp.asarray(x, dtype=jnp.float64)


class Spall(eqx.Module):
    """Spall on the outer raceway: centre psi_d (rad), circumferential extent (rad), depth d (m).

    ``profile`` (static) is "rectangular" (the ball drops as far as it fits into the recess,
    a step in psi) or "ball-path" (the ball centre pivots over the entry edge, drops and
    climbs out over the exit edge; continuous in psi).  Depth 0 is the healthy bearing.
    """

    center: jnp.ndarray = eqx.field(converter=_f64, default=0.0)
    extent: jnp.ndarray = eqx.field(converter=_f64, default=0.0)
    depth: jnp.ndarray = eqx.field(converter=_f64, default=0.0)
    profile: str = eqx.field(static=True, default="ball-path")

    def __check_init__(self):
        if self.profile not in PROFILES:
            raise ValueError(f"spall profile must be one of {PROFILES}, got {self.profile!r}")

    @classmethod
    def from_length(cls, bearing, center, length, depth, profile="ball-path"):
        """Spall given its arc length b (m) along the outer raceway: extent = b / R_o."""
        return cls(center, length / bearing.outer_raceway_radius, depth, profile)

    def length(self, bearing):
        """Arc length b = R_o * extent (m)."""
        return bearing.outer_raceway_radius * self.extent

    def edges(self):
        """Entry and exit azimuths (rad) of the spall, psi_d -/+ extent/2."""
        return self.center - 0.5 * self.extent, self.center + 0.5 * self.extent


NO_SPALL = Spall(0.0, 0.0, 0.0)


def wrap_angle(x):
    """Wrap to (-pi, pi]."""
    return jnp.pi - jnp.mod(jnp.pi - x, 2.0 * jnp.pi)


def _sag(D, x):
    """D/2 - sqrt(max(0, (D/2)^2 - x^2)): how far a ball of diameter D dips below a
    flat surface when it spans a chord 2x; safe gradient where the root vanishes."""
    r2 = 0.25 * D * D - x * x
    pos = r2 > 0.0
    return 0.5 * D - jnp.where(pos, jnp.sqrt(jnp.where(pos, r2, 1.0)), 0.0)


def depth_profile(bearing, spall: Spall, psi):
    """H(psi): the spall depth under a ball centred at azimuth psi (m); 0 outside the spall."""
    D = bearing.ball_diameter
    R_o = bearing.outer_raceway_radius
    u = wrap_angle(psi - spall.center)
    half = 0.5 * spall.extent
    inside = jnp.abs(u) <= half
    b = R_o * spall.extent
    if spall.profile == "rectangular":
        h = jnp.minimum(spall.depth, _sag(D, 0.5 * b))
    else:
        s = R_o * (u + half)
        h = jnp.minimum(spall.depth, _sag(D, jnp.minimum(s, b - s)))
    return jnp.where(inside & (spall.depth > 0.0), jnp.maximum(h, 0.0), 0.0)
