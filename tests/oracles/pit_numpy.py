"""The NumPy pit physics (the package's former host twin of :mod:`bearingsim.physics.pit`'s JAX
formulas): scipy's Simpson rule on the actual points, plain floats.  An independent oracle for
the tests only."""
from __future__ import annotations

import numpy as np

from bearingsim.physics.pit import Contact, PitDepth


def pit_load_fraction(a, b, pit_diameter, offset=0.0, n=2001) -> float:
    """The load fraction over a round pit (bearingsim.physics.pit.pit_load_fraction states the
    integral), with scipy's Simpson rule on the actual points."""
    from scipy.integrate import simpson

    a, b, r, e = float(a), float(b), 0.5 * float(pit_diameter), abs(float(offset))
    if not (a > 0 and b > 0 and r >= 0):
        raise ValueError(f"need a, b > 0 and pit_diameter >= 0, got {a}, {b}, {pit_diameter}")
    lo, hi = max(e - r, -a), min(e + r, a)
    if r == 0.0 or lo >= hi:
        return 0.0
    x = np.linspace(lo, hi, n | 1)
    c = b * np.sqrt(np.clip(1.0 - (x / a) ** 2, 0.0, None))                 # ellipse half-chord
    y0 = np.minimum(np.sqrt(np.clip(r * r - (x - e) ** 2, 0.0, None)), c)    # disc within it
    ratio = np.divide(y0, c, out=np.zeros_like(c), where=c > 0)
    inner = y0 * np.sqrt(np.clip(c * c - y0 * y0, 0.0, None)) + c * c * np.arcsin(np.clip(ratio, 0, 1))
    return float(min(1.0, simpson(inner / b, x=x) / (2.0 / 3.0 * np.pi * a * b)))


def pit_depth(contact: Contact, pit_diameter, machined_depth, ball_diameter) -> PitDepth:
    """Effective depth of a round pit of ``pit_diameter`` (m) under the healthy ``contact``:
    the pit removes the fraction phi of the contact's load (:func:`pit_load_fraction`, the pit
    ``contact.offset`` away from the contact centre across the track) at its approach, which the
    Jones model reproduces with the depth ``delta (1 - (1 - phi)^(2/3))`` (Q ~ delta^1.5),
    capped by the ball's sag over the pit chord and by the machined depth."""
    D, w = float(ball_diameter), float(pit_diameter)
    sag = 0.5 * D - np.sqrt(max(0.0, 0.25 * D * D - 0.25 * w * w))
    phi = min(1.0, pit_load_fraction(contact.a, contact.b, w, contact.offset)) if contact.a > 0 else 0.0
    h = max(contact.delta, 0.0) * (1.0 - (1.0 - phi) ** (2.0 / 3.0))
    return PitDepth(float(min(h, sag, float(machined_depth))), phi, float(sag), contact)


def unbridged_fraction(pit_diameter, contact_semi_axis_b) -> float:
    """``max(0, 1 - 2 b / w)``: the fraction of the pit length ``w`` that the contact (length 2b)
    cannot bridge, i.e. over which its central strip runs free."""
    w, b = float(pit_diameter), float(contact_semi_axis_b)
    return max(0.0, 1.0 - 2.0 * b / w) if w > 0.0 else 0.0


def pit_depth_of_solution(sol, bearing, j, location, pit_diameter, machined_depth) -> PitDepth:
    """The effective depth of a pit under ball ``j`` of a healthy (host) solution, NumPy throughout."""
    from bearingsim.physics.pit import contact_of

    D = float(bearing.ball_diameter)
    if location in ("outer", "inner"):
        return pit_depth(contact_of(sol, bearing, j, location), pit_diameter, machined_depth, D)
    po = pit_depth(contact_of(sol, bearing, j, "outer", centred=True), pit_diameter, machined_depth, D)
    pi = pit_depth(contact_of(sol, bearing, j, "inner", centred=True), pit_diameter, machined_depth, D)
    return PitDepth(0.5 * (po.depth + pi.depth), 0.5 * (po.load_fraction + pi.load_fraction), po.sag, po.contact)


def pit_unbridged_fraction(sol, bearing, j, location, pit_length) -> float:
    from bearingsim.physics.pit import contact_of

    if location in ("outer", "inner"):
        return unbridged_fraction(pit_length, contact_of(sol, bearing, j, location).b)
    return 0.5 * sum(unbridged_fraction(pit_length, contact_of(sol, bearing, j, r, centred=True).b)
                     for r in ("outer", "inner"))
