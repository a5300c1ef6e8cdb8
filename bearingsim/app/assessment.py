"""The assessment of one bearing's quasi-static state: its per-contact limits (docs/model.md section 11) and
its ISO/TS 16281 life, by one rule for a single bearing (:func:`bearingsim.app.workflows.assess_case`)
and for each bearing of a set (:func:`bearingsim.app.set_workflows.assess_set_case`), so that both
report the same limits and flags (issue 34).  Computes only; :mod:`bearingsim.output` renders.

Flags (:data:`FLAGS`, the same names in the JSON ``limits`` of either): ``overpressure`` (a contact
above the case's pressure limit, 4.2 GPa by default: the state is solved, the steel is not elastic
there), ``slip`` (raceway control needs more friction than is available), ``truncated`` (a contact
ellipse truncated by a shoulder), ``over_shoulder`` (a loaded contact centred over a shoulder
edge).  A flagged state is returned (exit 0) with its flags; what is refused is refused by the
solver's result code, the same for a single bearing and a set.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..physics import life
from ..physics.limits import contact_limits
from ..programs import jit
from ..xla import QUICK_COMPILE
from ..errors import succeeded

__all__ = ["Assessment", "assess_state", "FLAGS"]

#: the machine-readable flags of an assessment, in the order they are reported
FLAGS = ("overpressure", "slip", "truncated", "over_shoulder")


@dataclass(frozen=True)
class Assessment:
    """Limits and life of a quasi-static state (:func:`assess_state`; ``bearingsim static``).

    ``limits``: :class:`bearingsim.physics.limits.ContactLimits`; ``settings``: the case's
    ``limits_settings()`` (SI; for a bearing of a set with that bearing's own rating);
    ``rating_life``: ISO/TS 16281 L10r (10^6 revolutions) or None (no dynamic load rating in the
    case, no load, or a defect: the life is a healthy bearing's); ``ring_lives``: (inner, outer) in
    10^6 revolutions or None; ``life_hours``: at the case's speed, None at standstill or without a
    life; ``nominal_angle``: the contact angle of the life formula (rad; 0 for a deep groove)."""

    limits: object
    settings: dict
    rating_life: float | None
    ring_lives: tuple | None
    life_hours: float | None
    nominal_angle: float

    @property
    def flags(self) -> tuple:
        """The names of :data:`FLAGS` that this state raises (empty: every limit within)."""
        L = self.limits
        on = (L.any_overpressure, L.any_slip, L.any_truncated, L.any_over_shoulder)
        return tuple(n for n, f in zip(FLAGS, on) if bool(np.asarray(f)))


def _contact_limits_jit():
    """:func:`bearingsim.physics.limits.contact_limits` as one compiled program (cached on disk), not
    some thirty small eager ones: a warm ``bearingsim static`` loads one program instead."""
    global _LIMITS_JIT
    if _LIMITS_JIT is None:
        _LIMITS_JIT = jit(contact_limits, options=QUICK_COMPILE)     # once per report: -O0
    return _LIMITS_JIT


_LIMITS_JIT = None


def assess_state(bearing, op, sol, settings: dict, *, healthy: bool = True) -> Assessment:
    """Per-contact limits (pressure, the friction raceway control needs, the ellipse against the
    shoulders) of the single state ``sol`` of ``bearing`` at ``op`` and, when ``settings`` gives a
    ``dynamic_load_rating`` (N), the state is valid (``sol.result == 0``) and ``healthy``, its
    ISO/TS 16281 rating life."""
    lim = _contact_limits_jit()(sol, bearing, op.control, pressure_limit=settings["pressure_limit"],
                                friction_coefficient=settings["friction_coefficient"])
    alpha = float(bearing.free_contact_angle) if bool(bearing.angular_contact) else 0.0
    L = rings = hours = None
    C = settings["dynamic_load_rating"]
    if C is not None and succeeded(int(sol.result)) and healthy:
        Lr = float(life.rating_life(bearing, C, sol.Q_inner, sol.Q_outer, contact_angle=alpha))
        if np.isfinite(Lr):
            L = Lr
            Li, Lo = life.ring_lives(bearing, C, sol.Q_inner, sol.Q_outer, contact_angle=alpha)
            rings = tuple(float(x) if np.isfinite(float(x)) else None for x in (Li, Lo))
            h = float(life.life_hours(Lr, op.speed))
            hours = h if np.isfinite(h) else None
    return Assessment(lim, settings, L, rings, hours, alpha)
