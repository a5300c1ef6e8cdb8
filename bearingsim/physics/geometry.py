"""Bearing geometry and materials (docs/model.md section 2).

Everything is SI (m, Pa, kg/m^3) and radians.  ``Bearing`` is an equinox
module: a pytree whose float fields can be traced, vmapped and differentiated,
with the ball count ``n_balls`` static (one compilation per ball count).
"""
from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from ..errors import InputError
from ..hostarrays import f64, opt_f64, xp


_f64 = f64             # the fields' converters (bearingsim.hostarrays: NumPy unless traced)
_opt_f64 = opt_f64


#: bearing designs: "deep_groove" (full shoulders on both sides of both rings), "angular_contact"
#: (one high and one low shoulder on each ring; axial load in +z only), "auto" (angular contact
#: when the free contact angle alpha_0 > 0, else deep groove)
DESIGNS = ("auto", "deep_groove", "angular_contact")
#: catalogue-typical land heights (shoulder height above the groove bottom, in ball diameters) that
#: give the default shoulder angles (estimates, docs/physics.md "Shoulders"): a deep-groove ring's
#: lands stand ~0.2 D above the groove bottom (e.g. the 6205's inner-ring shoulder, ~34.4 mm over a
#: 31.1 mm groove bottom: 0.21 D), edge angle ~52 deg; an angular contact ring's high shoulder
#: ~0.38 D (edge ~74 deg: it holds a 40 deg contact and its ellipse up to the static rating, and
#: the Harris 218's inner contacts at 10 krpm, 71 deg; contacts beyond ~75 deg are over it), its
#: low shoulder only ~0.01 D (edge ~11 deg: the balls are snapped in over it, so the land may stand
#: only the snap-in interference above the ball's outermost point, ~0.005 D below the groove bottom)
LAND_HEIGHTS = {"deep_groove": (0.20, 0.20), "angular_contact": (0.38, 0.01)}


def shoulder_angle(land_height, f):
    """Groove-edge angle (rad) of a land ``land_height`` (in ball diameters) above the groove
    bottom of a groove of curvature ratio f = r/D, measured at the groove's curvature centre from
    the groove bottom: land_height = f (1 - cos theta)."""
    return jnp.arccos(jnp.clip(1.0 - land_height / f, -1.0, 1.0))


def land_height(angle, f):
    """Inverse of :func:`shoulder_angle`: the land height (in ball diameters) of an edge angle."""
    return f * (1.0 - jnp.cos(angle))


class Material(eqx.Module):
    """Isotropic elastic material: Young's modulus (Pa), Poisson ratio, density (kg/m^3)."""

    youngs_modulus: jnp.ndarray = eqx.field(converter=_f64)
    poisson_ratio: jnp.ndarray = eqx.field(converter=_f64)
    density: jnp.ndarray = eqx.field(converter=_f64)


# The module is imported lazily (``bearingsim.Bearing``), possibly for the first time inside a
# user's jax.jit trace: its constants are made under ensure_compile_time_eval, so that they are
# concrete arrays and never that trace's tracers (which every later Bearing would then carry).
with jax.ensure_compile_time_eval():
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

    Shoulders (docs/model.md section 11; docs/physics.md "Shoulders"): each ring's groove spans contact angles
    from -theta_low to +theta_high, measured at its curvature centre from the groove bottom,
    positive on the side of the bearing's contact direction (outer ring +z, inner ring -z).
    ``shoulder_angles`` = [inner high, inner low, outer high, outer low] (rad) or None for the
    defaults of ``design`` (:data:`LAND_HEIGHTS`).  ``design`` (static): "auto" (angular contact
    when alpha_0 > 0), "deep_groove" (the default of :meth:`from_clearance`) or
    "angular_contact" (one low shoulder per ring: axial load in +z only).
    """

    n_balls: int = eqx.field(static=True)
    ball_diameter: jnp.ndarray = eqx.field(converter=_f64)
    pitch_diameter: jnp.ndarray = eqx.field(converter=_f64)
    f_inner: jnp.ndarray = eqx.field(converter=_f64)
    f_outer: jnp.ndarray = eqx.field(converter=_f64)
    free_contact_angle: jnp.ndarray = eqx.field(converter=_f64)
    ball_material: Material = STEEL
    ring_material: Material = STEEL
    shoulder_angles: jnp.ndarray | None = eqx.field(default=None, converter=_opt_f64)
    design: str = eqx.field(static=True, default="auto")

    def __check_init__(self):
        if self.design not in DESIGNS:
            raise InputError(f"design must be one of {DESIGNS}, got {self.design!r}",
                             "'auto' (angular contact when the free contact angle > 0, else deep groove), "
                             "'deep_groove' or 'angular_contact'")
        if self.shoulder_angles is not None and self.shoulder_angles.shape[-1:] != (4,):
            raise InputError("shoulder_angles must be [inner high, inner low, outer high, outer low] (rad), "
                             f"4 angles along the last axis, got shape {tuple(self.shoulder_angles.shape)}",
                             "or None for the design's catalogue-typical shoulders")

    @classmethod
    def from_clearance(cls, n_balls, ball_diameter, pitch_diameter, f_inner, f_outer,
                       diametral_clearance, ball_material=STEEL, ring_material=STEEL,
                       shoulder_angles=None, design="deep_groove"):
        """Bearing from its diametral clearance P_d (m): cos alpha_0 = 1 - P_d / (2 B D).  A
        bearing given by its clearance is a deep-groove bearing unless ``design`` says otherwise."""
        B = f_inner + f_outer - 1.0
        c = 1.0 - diametral_clearance / (2.0 * B * ball_diameter)
        # JAX's arccos on the host too (NumPy's libm differs from XLA's in the last bit for ~1/4
        # of the values: bearingsim.hostarrays moves only operations that agree to the bit)
        alpha0 = jnp.arccos(jnp.clip(c, -1.0, 1.0))
        return cls(n_balls, ball_diameter, pitch_diameter, f_inner, f_outer, alpha0,
                   ball_material, ring_material, shoulder_angles, design)

    # -- shoulders -----------------------------------------------------------------------
    @property
    def angular_contact(self):
        """True (a traced bool for "auto") when the bearing has low shoulders: it carries axial
        load in +z only."""
        if self.design == "auto":
            return self.free_contact_angle > 0.0
        return jnp.asarray(self.design == "angular_contact")

    @property
    def shoulders(self):
        """Groove-edge angles [inner high, inner low, outer high, outer low] (rad): the given
        ``shoulder_angles`` or the design's defaults (:data:`LAND_HEIGHTS`)."""
        if self.shoulder_angles is not None:
            return self.shoulder_angles

        def angles(kind):
            hi, lo = LAND_HEIGHTS[kind]
            return jnp.stack([shoulder_angle(hi, self.f_inner), shoulder_angle(lo, self.f_inner),
                              shoulder_angle(hi, self.f_outer), shoulder_angle(lo, self.f_outer)])

        if self.design == "auto":
            return jnp.where(self.angular_contact, angles("angular_contact"), angles("deep_groove"))
        return angles(self.design)

    # -- derived quantities (docs/model.md section 2) ---------------------------------
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
        a = self.free_contact_angle            # NumPy's cos is XLA's to the bit (bearingsim.hostarrays)
        return 0.5 * (self.pitch_diameter + self.ball_diameter * xp(a).cos(a))

    @property
    def inner_raceway_radius(self):
        """R_ir = (d_m - D cos alpha_0)/2: radius along which an inner-raceway spall's arc length is
        measured (m; docs/model.md section 9)."""
        a = self.free_contact_angle
        return 0.5 * (self.pitch_diameter - self.ball_diameter * xp(a).cos(a))

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
        return cage_angle + self.ball_pitch_angle * xp(cage_angle).arange(self.n_balls)
