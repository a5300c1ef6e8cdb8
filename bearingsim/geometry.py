"""Bearing geometry and materials (MODEL.md section 2).

Everything is SI (m, Pa, kg/m^3) and radians.  ``Bearing`` is an equinox
module: a pytree whose float fields can be traced, vmapped and differentiated,
with the ball count ``n_balls`` static (one compilation per ball count).
"""
from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp


def _f64(x):
    return jnp.asarray(x, dtype=jnp.float64)


class Material(eqx.Module):
    """Isotropic elastic material: Young's modulus (Pa), Poisson ratio, density (kg/m^3)."""

    youngs_modulus: jnp.ndarray = eqx.field(converter=_f64)
    poisson_ratio: jnp.ndarray = eqx.field(converter=_f64)
    density: jnp.ndarray = eqx.field(converter=_f64)


#: Bearing steel as used by Harris & Kotzalas for the 218 example.
STEEL = Material(207.5e9, 0.3, 7850.0)
#: Hot-isostatically pressed silicon nitride (hybrid bearing balls).
SILICON_NITRIDE = Material(310.0e9, 0.26, 3200.0)


class Bearing(eqx.Module):
    """Single-row angular contact (or deep groove) ball bearing.

    Parameters are SI: ``ball_diameter`` D and ``pitch_diameter`` d_m in m,
    groove curvature ratios f_i = r_i/D, f_o = r_o/D (> 0.5), and the free
    contact angle alpha_0 in rad.  Use :meth:`from_clearance` to give the
    diametral clearance P_d instead (cos alpha_0 = 1 - P_d/(2BD)).
    """

    n_balls: int = eqx.field(static=True)
    ball_diameter: jnp.ndarray = eqx.field(converter=_f64)
    pitch_diameter: jnp.ndarray = eqx.field(converter=_f64)
    f_inner: jnp.ndarray = eqx.field(converter=_f64)
    f_outer: jnp.ndarray = eqx.field(converter=_f64)
    free_contact_angle: jnp.ndarray = eqx.field(converter=_f64)
    ball_material: Material = STEEL
    ring_material: Material = STEEL

    @classmethod
    def from_clearance(cls, n_balls, ball_diameter, pitch_diameter, f_inner, f_outer,
                       diametral_clearance, ball_material=STEEL, ring_material=STEEL):
        """Bearing from its diametral clearance P_d (m): cos alpha_0 = 1 - P_d / (2 B D)."""
        B = f_inner + f_outer - 1.0
        c = 1.0 - diametral_clearance / (2.0 * B * ball_diameter)
        alpha0 = jnp.arccos(jnp.clip(c, -1.0, 1.0))
        return cls(n_balls, ball_diameter, pitch_diameter, f_inner, f_outer, alpha0,
                   ball_material, ring_material)

    # -- derived quantities (MODEL.md section 2) ---------------------------------
    @property
    def B(self):
        """Total conformity B = f_i + f_o - 1."""
        return self.f_inner + self.f_outer - 1.0

    @property
    def A(self):
        """Distance between groove curvature centres when unloaded, A = B D (m)."""
        return self.B * self.ball_diameter

    @property
    def diametral_clearance(self):
        """P_d = 2 B D (1 - cos alpha_0) (m)."""
        return 2.0 * self.A * (1.0 - jnp.cos(self.free_contact_angle))

    @property
    def inner_groove_radius(self):
        """R_i: radius of the locus of inner groove curvature centres (m)."""
        D = self.ball_diameter
        return 0.5 * self.pitch_diameter + (self.f_inner - 0.5) * D * jnp.cos(self.free_contact_angle)

    @property
    def outer_raceway_radius(self):
        """R_o = (d_m + D cos alpha_0)/2: radius along which a spall's arc length is measured (m)."""
        return 0.5 * (self.pitch_diameter + self.ball_diameter * jnp.cos(self.free_contact_angle))

    @property
    def inner_raceway_radius(self):
        """R_ir = (d_m - D cos alpha_0)/2: radius along which an inner-raceway spall's arc length is
        measured (m; MODEL.md section 9)."""
        return 0.5 * (self.pitch_diameter - self.ball_diameter * jnp.cos(self.free_contact_angle))

    @property
    def inner_raceway_diameter(self):
        """Inner raceway (groove bottom) diameter d_i = d_m - D (m)."""
        return self.pitch_diameter - self.ball_diameter

    @property
    def outer_raceway_diameter(self):
        """Outer raceway (groove bottom) diameter d_o = d_m + D (m)."""
        return self.pitch_diameter + self.ball_diameter

    @property
    def g(self):
        """g = D / d_m."""
        return self.ball_diameter / self.pitch_diameter

    @property
    def ball_mass(self):
        """m = rho pi D^3 / 6 (kg)."""
        return self.ball_material.density * jnp.pi * self.ball_diameter ** 3 / 6.0

    @property
    def ball_inertia(self):
        """J = m D^2 / 10 (kg m^2), solid sphere about a diameter."""
        return self.ball_mass * self.ball_diameter ** 2 / 10.0

    @property
    def effective_modulus(self):
        """E' = 2 / [(1 - nu_b^2)/E_b + (1 - nu_r^2)/E_r] (Pa)."""
        b, r = self.ball_material, self.ring_material
        return 2.0 / ((1.0 - b.poisson_ratio ** 2) / b.youngs_modulus
                      + (1.0 - r.poisson_ratio ** 2) / r.youngs_modulus)

    @property
    def ball_pitch_angle(self):
        """Angular spacing of the balls, 2 pi / Z (rad)."""
        return 2.0 * jnp.pi / self.n_balls

    def ball_azimuths(self, cage_angle=0.0):
        """psi_j = theta_c + 2 pi j / Z, j = 0..Z-1 (rad)."""
        return cage_angle + self.ball_pitch_angle * jnp.arange(self.n_balls)
