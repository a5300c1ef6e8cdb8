"""The physics of a round EDM pit under a ball contact (docs/realism.md): the fraction of the
Hertz load a pit narrower than the contact ellipse takes away, the effective depth the Jones
model needs for that loss, and the pit's unbridged fraction under the contact (what the
pass-to-pass variability scales with).

The CWRU faults are round EDM pits (diameter w = 0.007-0.040 in, depth 0.011 in) at the
bottom of the groove.  The outer contact ellipse of a loaded 6205 ball is 2a ~ 1-2 mm across the
track and 2b ~ 0.15-0.3 mm along it, so a pit is much narrower than the contact: the ball does
not drop into it as into a full-width groove (the rectangular profile's drop, the ball's sag
over the chord, ~ w^2 / (4 D)).  It keeps rolling on the raceway beside the pit and only loses
the Hertz pressure over the pit's area.  :func:`pit_effective_depth` turns that lost fraction
phi of the ball load (at the ball's approach) into the depth the Jones model needs for the same
load loss, ``H = delta_o (1 - (1 - phi)^(2/3))`` (Q ~ delta^1.5), capped by the sag and the
machined depth.  Core: the Jones solve; no files.

Every formula exists once, in JAX (:func:`load_fraction`, :func:`effective_depth`,
:func:`unbridged`, :func:`pit_of_solution`: jit/vmap, for a data set chunk's program); the
functions taking and returning floats (:func:`pit_load_fraction`, :func:`pit_depth`,
:func:`unbridged_fraction`, ...) evaluate them for one contact.  The former NumPy versions are
the tests' oracle (tests/oracles/pit_numpy.py).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import InputError
from ..hostarrays import f64, xp
from .jones import solve

__all__ = ["Contact", "PIT_LOCATIONS", "contact_of", "contact_at", "PitDepth", "pit_load_fraction",
           "pit_depth", "pit_effective_depth", "pit_depth_of_solution", "unbridged_fraction",
           "pit_unbridged_fraction", "pass_cv", "load_fraction", "effective_depth", "unbridged", "pit_of_solution",
           "EXCITED_DEPTH_MIN", "excited"]

# ------------------------------------------------------------------------------ pit physics
def pit_load_fraction(a, b, pit_diameter, offset=0.0, n=2001) -> float:
    """Fraction of a Hertz contact's load carried over a round pit (:func:`load_fraction` of one
    contact, as a float).

    ``a`` semi-axis across the track, ``b`` along it, ``pit_diameter`` and ``offset`` (the
    distance across the track from the contact centre to the pit centre) in the same unit.  The
    Hertz pressure ``p0 sqrt(1 - x^2/a^2 - y^2/b^2)`` is integrated over the disc analytically in
    y and numerically in x (``n`` points, Simpson), divided by the load ``(2/3) pi a b p0``.
    Limits: 1 for a pit that covers the contact, ``3 r^2 / (2 a b)`` for a centred pit of radius
    r << b.
    """
    if not (float(a) > 0 and float(b) > 0 and float(pit_diameter) >= 0):
        raise InputError(f"pit_load_fraction: need the contact semi-axes a, b > 0 (m) and pit_diameter >= 0 (m), "
                         f"got a = {a}, b = {b}, pit_diameter = {pit_diameter}")
    return float(load_fraction(float(a), float(b), float(pit_diameter), float(offset), int(n)))


class Contact(NamedTuple):
    """One contact of the ball at a given azimuth in the healthy quasi-static state (SI)."""

    delta: float            # approach delta (m)
    a: float                # semi-axis across the track (m)
    b: float                # semi-axis along the track (m)
    Q: float                # load (N)
    alpha: float            # contact angle (rad)
    offset: float           # contact centre to the groove bottom across the track, f D sin(alpha) (m)


#: the smallest effective depth (m) of a pit that makes a fault signal: 10 nm, below the surface
#: roughness of the finest superfinished raceways and balls (Rq ~ 0.02-0.05 um).  A pit where the
#: ball carries (almost) no load, an outer-race pit outside the load zone, has a smaller one
#: (0 where the ball is off the raceway): the ball rolls over it as over the healthy raceway, and a
#: record of it is a healthy bearing's record, whatever its label says.
EXCITED_DEPTH_MIN = 10e-9


def excited(effective_depth):
    """Whether a pit of this effective depth (m; :func:`pit_depth`, any array) makes a fault
    signal: ``effective_depth >= EXCITED_DEPTH_MIN`` (NumPy or JAX arrays)."""
    return effective_depth >= EXCITED_DEPTH_MIN


#: where a pit sits: the outer or inner groove bottom, or a point of a ball's surface
PIT_LOCATIONS = ("outer", "inner", "ball")


def contact_of(sol, bearing, j, race="outer", centred=False) -> Contact:
    """:class:`Contact` of ball ``j`` of the (single, host) quasi-static solution ``sol`` at its
    ``race`` ("outer" or "inner") contact; ``offset`` is the contact centre's distance from the
    groove bottom, ``f D |sin alpha|`` (0 with ``centred``: a pit on the ball, which meets the
    contact on the ball's rolling circle)."""
    if race not in ("outer", "inner"):
        raise InputError(f"race must be 'outer' or 'inner', got {race!r}")
    get = lambda name: float(np.asarray(getattr(sol, f"{name}_{race}"))[j])  # noqa: E731
    alpha = get("alpha")
    f = float(bearing.f_outer if race == "outer" else bearing.f_inner)
    offset = 0.0 if centred else f * float(bearing.ball_diameter) * abs(np.sin(alpha))
    return Contact(get("delta"), get("a"), get("b"), get("Q"), alpha, offset)


def contact_at(bearing, op, loads, center=0.0, hertz_method="exact", race="outer") -> Contact:
    """The ``race`` contact of the ball placed at azimuth ``center`` in the healthy bearing."""
    sol = solve(bearing, op, loads, cage_angle=center, hertz_method=hertz_method)
    psi = np.asarray(sol.azimuth)
    j = int(np.argmin(np.abs(np.angle(np.exp(1j * (psi - center))))))
    return contact_of(sol, bearing, j, race)


class PitDepth(NamedTuple):
    """Result of :func:`pit_effective_depth` (SI)."""

    depth: float            # effective depth H for the Jones model (m)
    load_fraction: float    # phi: ball load lost over the pit at the ball's approach
    sag: float              # the ball's sag over the pit chord, D/2 - sqrt(D^2/4 - w^2/4) (m)
    contact: Contact        # the ball's healthy contact at the pit


def pit_depth(contact: Contact, pit_diameter, machined_depth, ball_diameter) -> PitDepth:
    """Effective depth of a round pit of ``pit_diameter`` (m) under the healthy ``contact``
    (:func:`effective_depth`): the pit removes the fraction phi of the contact's load
    (:func:`pit_load_fraction`, the pit ``contact.offset`` away from the contact centre across
    the track) at its approach, which the Jones model reproduces with the depth
    ``delta (1 - (1 - phi)^(2/3))`` (Q ~ delta^1.5), capped by the ball's sag over the pit chord
    and by the machined depth."""
    D, w = float(ball_diameter), float(pit_diameter)
    h, phi, sag = effective_depth((contact.delta, contact.a, contact.b, contact.offset), w, float(machined_depth), D)
    return PitDepth(float(h), float(phi), float(sag), contact)


def pit_effective_depth(bearing, op, loads, pit_diameter, machined_depth, center=0.0,
                        hertz_method="exact", location="outer") -> PitDepth:
    """Effective depth of a round EDM pit of ``pit_diameter`` (m), ``machined_depth`` deep, for
    the Jones model.

    ``location`` "outer" (default): the pit at the outer groove bottom at azimuth ``center``;
    the healthy quasi-static state with a ball there gives that ball's outer approach and contact
    ellipse (:func:`contact_at`), the contact centre ``f_o D sin(alpha_o)`` away from the groove
    bottom.  "inner": the pit at the inner groove bottom, met by the ball at azimuth ``center``
    (pass the load-zone centre: the pit turns with the shaft and its strongest impacts are
    there); its inner contact, offset ``f_i D sin(alpha_i)``.  "ball": a pit on the ball's
    rolling circle (no offset), met by the outer and the inner contact in turn: the mean of the
    two effective depths (the engine carries one depth per pit; :class:`PitDepth` reports the
    outer contact and the mean lost fraction).  The depth follows from :func:`pit_depth`.
    Neglected: the pressure redistribution around the pit (the remaining contact is not
    Hertzian) and the contact's entry/exit over the pit edges (the rectangular profile switches
    at the pit edges).
    """
    if location not in PIT_LOCATIONS:
        raise InputError(f"pit location must be one of {PIT_LOCATIONS}, got {location!r}")
    sol = solve(bearing, op, loads, cage_angle=center, hertz_method=hertz_method)
    psi = np.asarray(sol.azimuth)
    j = int(np.argmin(np.abs(np.angle(np.exp(1j * (psi - center))))))
    return pit_depth_of_solution(sol, bearing, j, location, pit_diameter, machined_depth)


def pit_depth_of_solution(sol, bearing, j, location, pit_diameter, machined_depth) -> PitDepth:
    """:func:`pit_effective_depth` for ball ``j`` of a healthy (single, host) quasi-static
    solution ``sol`` that is already at hand (the data sets solve their items in batches)."""
    D = float(bearing.ball_diameter)
    if location in ("outer", "inner"):
        return pit_depth(contact_of(sol, bearing, j, location), pit_diameter, machined_depth, D)
    if location != "ball":
        raise InputError(f"pit location must be one of {PIT_LOCATIONS}, got {location!r}")
    po = pit_depth(contact_of(sol, bearing, j, "outer", centred=True), pit_diameter, machined_depth, D)
    pi = pit_depth(contact_of(sol, bearing, j, "inner", centred=True), pit_diameter, machined_depth, D)
    return PitDepth(0.5 * (po.depth + pi.depth), 0.5 * (po.load_fraction + pi.load_fraction), po.sag,
                    po.contact)


# ------------------------------------------------------------------------------ variability
def unbridged_fraction(pit_diameter, contact_semi_axis_b) -> float:
    """``max(0, 1 - 2 b / w)``: the fraction of the pit length ``w`` that the contact (length 2b)
    cannot bridge, i.e. over which its central strip runs free (:func:`unbridged`, a float)."""
    return float(unbridged(float(pit_diameter), float(contact_semi_axis_b)))


def pit_unbridged_fraction(sol, bearing, j, location, pit_length) -> float:
    """:func:`unbridged_fraction` of a pit ``pit_length`` (m) long under ball ``j``'s contact in
    the healthy (single, host) quasi-static state ``sol``: its outer contact for an outer-race
    pit, its inner contact for an inner-race pit, the mean of the two for a pit on the ball
    (which meets both raceways in turn)."""
    if location in ("outer", "inner"):
        return unbridged_fraction(pit_length, contact_of(sol, bearing, j, location).b)
    if location != "ball":
        raise InputError(f"pit location must be one of {PIT_LOCATIONS}, got {location!r}")
    return 0.5 * sum(unbridged_fraction(pit_length, contact_of(sol, bearing, j, r, centred=True).b)
                     for r in ("outer", "inner"))


def pass_cv(pit_diameter, contact_semi_axis_b, cv_max) -> float:
    """Coefficient of variation of the per-pass impact factor, ``cv_max`` times
    :func:`unbridged_fraction`."""
    return float(cv_max) * unbridged_fraction(pit_diameter, contact_semi_axis_b)


# ------------------------------------------------------------------------ the formulas (JAX)
# One version, for one contact on the host and for a data set chunk's compiled program (traced
# arrays, vmap over items).

def load_fraction(a, b, pit_diameter, offset=0.0, n=2001):
    """Fraction of a Hertz contact's load carried over a round pit (:func:`pit_load_fraction`;
    jit/vmap, ``n`` static): the composite Simpson rule on ``n`` uniform points across the
    track; 0 for an empty pit, a pit beside the contact or a contact of zero size."""
    import jax.numpy as jnp

    n = n | 1
    a, b = jnp.asarray(a, jnp.float64), jnp.asarray(b, jnp.float64)
    r, e = 0.5 * jnp.asarray(pit_diameter, jnp.float64), jnp.abs(jnp.asarray(offset, jnp.float64))
    lo, hi = jnp.maximum(e - r, -a), jnp.minimum(e + r, a)
    valid = (r > 0.0) & (lo < hi) & (a > 0.0) & (b > 0.0)
    a_, b_ = jnp.where(valid, a, 1.0), jnp.where(valid, b, 1.0)
    lo, hi = jnp.where(valid, lo, 0.0), jnp.where(valid, hi, 1.0)
    x = lo + (hi - lo) * jnp.linspace(0.0, 1.0, n)
    c = b_ * jnp.sqrt(jnp.clip(1.0 - (x / a_) ** 2, 0.0, None))
    y0 = jnp.minimum(jnp.sqrt(jnp.clip(r * r - (x - e) ** 2, 0.0, None)), c)
    ratio = jnp.where(c > 0, y0 / jnp.where(c > 0, c, 1.0), 0.0)
    inner = y0 * jnp.sqrt(jnp.clip(c * c - y0 * y0, 0.0, None)) + c * c * jnp.arcsin(jnp.clip(ratio, 0.0, 1.0))
    w = jnp.ones(n).at[1:-1:2].set(4.0).at[2:-1:2].set(2.0)
    integral = (hi - lo) / (n - 1) / 3.0 * jnp.sum(w * inner / b_)
    return jnp.where(valid, jnp.minimum(1.0, integral / (2.0 / 3.0 * np.pi * a_ * b_)), 0.0)


def _contact(sol, bearing, j, race, centred):
    import jax.numpy as jnp

    get = lambda name: getattr(sol, f"{name}_{race}")[j]  # noqa: E731
    alpha = get("alpha")
    f = bearing.f_outer if race == "outer" else bearing.f_inner
    offset = 0.0 if centred else f * bearing.ball_diameter * jnp.abs(jnp.sin(alpha))
    return get("delta"), get("a"), get("b"), offset


def effective_depth(contact, w, machined, D):
    """(effective depth, lost load fraction phi, sag) of a round pit of diameter ``w`` under a
    contact ``(delta, a, b, offset)`` (:func:`pit_depth`; jit/vmap): ``delta (1 - (1 -
    phi)^(2/3))``, capped by the ball's sag over the pit chord and the ``machined`` depth."""
    import jax.numpy as jnp

    delta, a, b, offset = contact
    sag = 0.5 * D - jnp.sqrt(jnp.maximum(0.0, 0.25 * D * D - 0.25 * w * w))
    phi = jnp.where(a > 0, jnp.minimum(1.0, load_fraction(a, b, w, offset)), 0.0)
    h = jnp.maximum(delta, 0.0) * (1.0 - (1.0 - phi) ** (2.0 / 3.0))
    return jnp.minimum(jnp.minimum(h, sag), machined), phi, sag


def unbridged(pit_diameter, contact_semi_axis_b):
    """``max(0, 1 - 2 b / w)`` (:func:`unbridged_fraction`; jit/vmap; 0 for w = 0; NumPy where
    nothing is traced, :mod:`bearingsim.hostarrays`)."""
    xn = xp(pit_diameter, contact_semi_axis_b)
    w = f64(pit_diameter)
    return xn.where(w > 0.0, xn.maximum(0.0, 1.0 - 2.0 * contact_semi_axis_b / xn.where(w > 0, w, 1.0)), 0.0)


def pit_of_solution(sol, bearing, j, location, pit_diameter, machined_depth):
    """(effective depth, unbridged fraction) of :func:`pit_depth_of_solution` and
    :func:`pit_unbridged_fraction` for ball ``j`` of one healthy quasi-static state ``sol``
    (JAX arrays, jit/vmap); ``location`` an index into :data:`PIT_LOCATIONS` (traced: every
    race is evaluated and the item's taken)."""
    import jax.numpy as jnp

    D = bearing.ball_diameter
    w, m = jnp.asarray(pit_diameter, jnp.float64), jnp.asarray(machined_depth, jnp.float64)
    co, ci = _contact(sol, bearing, j, "outer", False), _contact(sol, bearing, j, "inner", False)
    cbo, cbi = _contact(sol, bearing, j, "outer", True), _contact(sol, bearing, j, "inner", True)
    d_o, d_i = effective_depth(co, w, m, D)[0], effective_depth(ci, w, m, D)[0]
    d_b = 0.5 * (effective_depth(cbo, w, m, D)[0] + effective_depth(cbi, w, m, D)[0])
    u_o, u_i = unbridged(w, co[2]), unbridged(w, ci[2])
    depth = jnp.where(location == 0, d_o, jnp.where(location == 1, d_i, d_b))
    u = jnp.where(location == 0, u_o, jnp.where(location == 1, u_i, 0.5 * (u_o + u_i)))
    return depth, u
