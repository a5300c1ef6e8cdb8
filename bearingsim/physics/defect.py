"""Localized defects (docs/model.md sections 5 and 9): a spall on the outer raceway, a spall on the
inner raceway, or a pit on one ball.

A defect is a depth profile that reduces a ball's contact deformation where the ball meets it:
delta_o = L_o - (f_o - 1/2) D - H_outer and delta_i = L_i - (f_i - 1/2) D - H_inner.
:func:`contact_depths` gives (H_outer, H_inner) per ball for one defect or several at once (a
tuple of :class:`Spall`); :func:`depth_profile` is the profile of one defect on its own surface.
Every profile is differentiable with respect to depth and extent (no NaN gradients).

Conventions (``Spall.center``):

* ``location="outer"``: azimuth psi_d of the spall centre in the fixed frame (the outer ring is
  fixed).  Arc length along the outer raceway, R_o = (d_m + D cos alpha_0)/2.
* ``location="inner"``: azimuth of the spall centre in the fixed frame *at the instant of the
  quasi-static solve*; the spall turns with the inner ring, psi_di(t) = phi_d + omega t.  Arc
  length along the inner raceway, R_ir = (d_m - D cos alpha_0)/2.
* ``location="ball"``: the pit is on ball ``ball`` (static index j, the ball at azimuth
  theta_c + 2 pi j / Z); ``center`` is its spin angle theta_b: the pit's angular position on the
  ball's rolling great circle, measured from the ball's outer contact point (theta_b = 0: the pit
  is in the outer contact, theta_b = pi: in the inner contact, half a ball turn later).  It
  advances at the ball's spin speed relative to the cage, theta_b(t) = theta_b0 + omega_R t.
  Arc length on the ball surface, radius D/2 (``extent`` is the angle the pit subtends at the
  ball centre).

The same two profiles for every location ("rectangular", "ball-path") and the same sag rule: the
contact can close only as far as a ball (radius D/2) spanning the defect's chord allows.  The
curvature of the raceway in the rolling direction is neglected (as for the outer spall, docs/model.md
5): it changes the sag-limited depth by a factor of about 1 -/+ D / (2 R) (outer / inner).
"""
from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from ..errors import InputError, InputTypeError
from ..hostarrays import f64
from ..names import LOCATIONS

PROFILES = ("rectangular", "ball-path")

__all__ = ["PROFILES", "LOCATIONS", "Spall", "NO_SPALL", "as_defects", "canonical_defects", "wrap_angle",
           "surface_radius", "depth_profile", "contact_depths", "ball_pit_depths", "advance"]


_f64 = f64             # bearingsim.hostarrays: NumPy unless traced


class Spall(eqx.Module):
    """A localized defect: centre (rad), extent (rad), depth d (m), profile, location.

    ``profile`` (static) is "rectangular" (the ball drops as far as it fits into the recess,
    a step) or "ball-path" (the ball pivots over the entry edge, drops and climbs out over the
    exit edge; continuous).  ``location`` (static) is "outer" (default), "inner" or "ball"; for
    "ball", ``ball`` (static) is the index of the pitted ball and ``center`` its spin angle (see
    the module docstring for every convention).  Depth 0 is the healthy bearing.
    """

    center: jnp.ndarray = eqx.field(converter=_f64, default=0.0)
    extent: jnp.ndarray = eqx.field(converter=_f64, default=0.0)
    depth: jnp.ndarray = eqx.field(converter=_f64, default=0.0)
    profile: str = eqx.field(static=True, default="ball-path")
    location: str = eqx.field(static=True, default="outer")
    ball: int = eqx.field(static=True, default=0)

    def __check_init__(self):
        if self.profile not in PROFILES:
            raise InputError(f"spall profile must be one of {PROFILES}, got {self.profile!r}",
                             "'ball-path' (default) or 'rectangular'")
        if self.location not in LOCATIONS:
            raise InputError(f"defect location must be one of {LOCATIONS}, got {self.location!r}",
                             "the surface the defect lies on: the outer or inner raceway, or a ball")
        if not isinstance(self.ball, int) or self.ball < 0:
            raise InputError(f"ball index must be an int >= 0, got {self.ball!r}",
                             "ball is the index (0 .. n_balls - 1) of the ball that carries a ball pit")

    @classmethod
    def from_length(cls, bearing, center, length, depth, profile="ball-path", location="outer", ball=0):
        """Defect given its arc length b (m) on its own surface: extent = b / R with R the
        outer raceway radius R_o, the inner raceway radius R_ir, or the ball radius D/2."""
        return cls(center, length / surface_radius(bearing, location), depth, profile, location, ball)

    def radius(self, bearing):
        """Radius of the surface the defect lies on (m): R_o, R_ir or D/2."""
        return surface_radius(bearing, self.location)

    def length(self, bearing):
        """Arc length b = R * extent (m) on the defect's surface."""
        return self.radius(bearing) * self.extent

    def edges(self):
        """Entry and exit angles (rad) of the defect, center -/+ extent/2 (azimuths in the fixed
        frame for a raceway spall; spin angles on the ball for a ball pit)."""
        return self.center - 0.5 * self.extent, self.center + 0.5 * self.extent


NO_SPALL = Spall(0.0, 0.0, 0.0)


def as_defects(spall) -> tuple:
    """The defects as a tuple of :class:`Spall` (None -> (), one Spall -> (spall,))."""
    if spall is None:
        return ()
    if isinstance(spall, Spall):
        return (spall,)
    out = tuple(spall)
    if not all(isinstance(s, Spall) for s in out):
        raise InputTypeError("defects must be None, a Spall or a tuple of Spall, got a sequence holding "
                             + ", ".join(sorted({type(s).__name__ for s in out if not isinstance(s, Spall)})),
                             "build each defect with Spall(...) or Spall.from_length(...)")
    return out


def canonical_defects(spall):
    """One form per set of defects (None; a Spall; a tuple of two or more): the compiled solvers
    are keyed on it, so ``Spall`` and ``(Spall,)`` share one compilation."""
    d = as_defects(spall)
    return None if not d else d[0] if len(d) == 1 else d


def surface_radius(bearing, location):
    """R_o (outer raceway), R_ir (inner raceway) or D/2 (ball): where arc lengths are measured."""
    if location == "outer":
        return bearing.outer_raceway_radius
    if location == "inner":
        return bearing.inner_raceway_radius
    if location == "ball":
        return 0.5 * bearing.ball_diameter
    raise InputError(f"defect location must be one of {LOCATIONS}, got {location!r}",
                     "the surface the defect lies on: the outer or inner raceway, or a ball")


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
    """H(psi): the defect depth at angle ``psi`` on its own surface (m); 0 outside it.

    For a raceway spall ``psi`` is the azimuth of a ball centre (fixed frame); for a ball pit it
    is the angular position of a contact point on the ball's rolling great circle (0: the outer
    contact, pi: the inner contact; the pit sits at ``spall.center``).  Use
    :func:`contact_depths` for the (H_outer, H_inner) of every ball."""
    D = bearing.ball_diameter
    R = surface_radius(bearing, spall.location)
    u = wrap_angle(psi - spall.center)
    half = 0.5 * spall.extent
    inside = jnp.abs(u) <= half
    b = R * spall.extent
    if spall.profile == "rectangular":
        h = jnp.minimum(spall.depth, _sag(D, 0.5 * b))
    else:
        s = R * (u + half)
        h = jnp.minimum(spall.depth, _sag(D, jnp.minimum(s, b - s)))
    return jnp.where(inside & (spall.depth > 0.0), jnp.maximum(h, 0.0), 0.0)


def ball_pit_depths(bearing, spall: Spall):
    """(H_b at the outer contact, H_b at the inner contact) of the pitted ball (scalars, m):
    the pit profile at spin angles 0 (outer contact) and pi (inner contact)."""
    return depth_profile(bearing, spall, 0.0), depth_profile(bearing, spall, jnp.pi)


def contact_depths(bearing, spall, psi):
    """(H_outer, H_inner): the depth of every defect under each ball, shape of ``psi`` (the ball
    azimuths, (Z,), fixed frame, ball j at psi[j]), or (None, None) without a defect.

    ``spall``: None, a :class:`Spall` or a tuple of them (several defects at once).  An outer
    spall enters H_outer, an inner spall H_inner, a ball pit the pitted ball's H_outer while the
    pit is in the outer contact and its H_inner while it is in the inner contact.  Where two
    defects meet the same contact the deeper one counts (``maximum``)."""
    defects = as_defects(spall)
    if not defects:
        return None, None
    psi = jnp.asarray(psi, jnp.float64)
    Ho = jnp.zeros_like(psi)
    Hi = jnp.zeros_like(psi)
    for sp in defects:
        if sp.location == "outer":
            Ho = jnp.maximum(Ho, depth_profile(bearing, sp, psi))
        elif sp.location == "inner":
            Hi = jnp.maximum(Hi, depth_profile(bearing, sp, psi))
        else:
            if sp.ball >= bearing.n_balls:
                raise InputError(f"ball pit on ball {sp.ball}: the bearing has {bearing.n_balls} balls",
                                 f"the ball index must be 0 .. {bearing.n_balls - 1}")
            ho, hi = ball_pit_depths(bearing, sp)
            mine = jnp.arange(bearing.n_balls) == sp.ball
            mine = jnp.broadcast_to(mine, psi.shape)
            Ho = jnp.maximum(Ho, jnp.where(mine, ho[..., None] if jnp.ndim(ho) else ho, 0.0))
            Hi = jnp.maximum(Hi, jnp.where(mine, hi[..., None] if jnp.ndim(hi) else hi, 0.0))
    return Ho, Hi


def advance(spall, t, shaft_speed, spin_speed=0.0):
    """The defects at time t (s) from their state at t = 0: an outer spall stays, an inner spall
    turns with the inner ring (center + omega t, ``shaft_speed`` omega in rad/s), a ball pit turns
    with its ball relative to the cage (center + omega_R t, ``spin_speed`` omega_R in rad/s, e.g.
    2 pi BSF or ``ball_kinematics(...).spin_speed``).  The pitted ball's own azimuth is the cage's
    business (theta_c(t) + 2 pi j / Z).  Returns the same structure (a Spall or a tuple); pure JAX
    (t may be traced), so ``contact_depths(bearing, advance(spall, t, w, wR), psi(t))`` gives
    (H_outer, H_inner) per ball at any instant."""
    def one(sp):
        if sp.location == "outer":
            return sp
        rate = shaft_speed if sp.location == "inner" else spin_speed
        return eqx.tree_at(lambda s: s.center, sp, sp.center + rate * t)

    if isinstance(spall, Spall):
        return one(spall)
    return tuple(one(sp) for sp in as_defects(spall))
