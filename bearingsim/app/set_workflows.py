"""The workflows of a bearing set (docs/model.md section 10; core: :mod:`bearingsim.physics.shaft`): what a case
with a [set] section computes, returned as objects that :mod:`bearingsim.output.set_report` writes
and prints and :mod:`bearingsim.output.plots_set` draws, as the single-bearing workflows of
:mod:`bearingsim.app.workflows` return what :mod:`bearingsim.output.report` renders.

- :func:`solve_set_case` -> ``SetSolution``; :func:`assess_set_case` -> :class:`SetAssessment`
  (each bearing assessed by the single bearing's rule, :func:`bearingsim.app.assessment.assess_state`:
  the same limits and flags; the set's life; each bearing's static axial capacity);
- :func:`study_set_case` -> :class:`SetStudy`; :func:`study_limits` and :func:`set_study_table`:
  its values, limits, life and stiffness per bearing and value.

:mod:`bearingsim.app.workflows` calls these when the case describes a set, so ``bearingsim static`` /
``study`` / ``info`` have no set branch.
"""
from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from ..case import as_scenario, unit_of
from ..errors import InputError
from ..physics.life import life_hours, rating_life, set_life
from ..physics.limits import contact_limits
from ..physics.kinematics import Operation
from ..physics.shaft import raise_for_set, solve_set, solve_set_batch, static_axial_capacity
from .assessment import FLAGS, assess_state

__all__ = ["solve_set_case", "assess_set_case", "SetAssessment", "study_set_case", "SetStudy", "set_lives_hours",
           "study_limits", "set_study_table"]


def _where(case):
    return f"set solve of {case.source}" if getattr(case, "source", None) else "set solve"


def solve_set_case(case, *, throw=True):
    """The set's state at the operating point of a case or scenario
    (:class:`bearingsim.physics.shaft.SetSolution`)."""
    sc = as_scenario(case)
    if not sc.is_set:
        raise InputError(f"{sc.source}: no [set] section: this is a single-bearing case")
    sol = solve_set(sc.bearing_set, sc.operation, sc.loads, cage_angle=sc.cage_angle,
                    hertz_method=sc.hertz_method, throw=False)
    if throw:
        raise_for_set(sol, _where(sc))
    return sol


# ------------------------------------------------------------------------------ assessment
@dataclass(frozen=True)
class SetAssessment:
    """Limits, life and capacity of a set's state (:func:`assess_set_case`; ``bearingsim static``).

    ``bearings``: one :class:`bearingsim.app.assessment.Assessment` per bearing (its own limits and
    flags by the single bearing's rule, its life with its own rating); ``set_rating_life``: the
    set's L10r (10^6 revolutions; bearings fail independently) or None; ``set_life_hours``: at
    the case's speed or None; ``static_capacity``: each bearing's static axial capacity C_0a (N);
    ``preload``: each bearing's preload as set (N)."""

    bearings: tuple
    set_rating_life: float | None
    set_life_hours: float | None
    static_capacity: np.ndarray
    preload: np.ndarray

    @property
    def preload_over_capacity(self) -> np.ndarray:
        """(N,) bool: a preload above the bearing's static axial capacity C_0a (the preload alone
        gives more than 4.2 GPa at standstill)."""
        return self.preload > self.static_capacity

    @property
    def flags(self) -> dict:
        """Machine-readable flags: ``{name: [bearing numbers (1-based)]}`` for every flag of
        :data:`bearingsim.app.assessment.FLAGS` a bearing raises and ``preload_over_capacity``;
        empty when every limit is within."""
        out = {n: [k + 1 for k, a in enumerate(self.bearings) if n in a.flags] for n in FLAGS}
        out["preload_over_capacity"] = [int(k) + 1 for k in np.flatnonzero(self.preload_over_capacity)]
        return {n: v for n, v in out.items() if v}


def _ratings(sc):
    """C (N) of every bearing of the set (:attr:`Scenario.set_ratings`), None for a bearing without a rating."""
    return list(sc.set_ratings)


def assess_set_case(case, sol) -> SetAssessment:
    """Each bearing of the set's state ``sol`` assessed as a single bearing is
    (:func:`bearingsim.app.assessment.assess_state`: pressure, friction, shoulders, life with its
    own rating), the set's life from the bearings' (ISO/TS 16281, independent failures) and each
    bearing's preload against its static axial capacity."""
    sc = as_scenario(case)
    bset, op = sc.bearing_set, sc.operation
    base = sc.limits
    out = []
    for b, sb, C in zip(bset.bearings, sol.bearings, _ratings(sc)):
        out.append(assess_state(b, op, sb, {**base, "dynamic_load_rating": C}))
    L = [a.rating_life for a in out]
    Ls = hours = None
    if all(x is not None for x in L):
        Ls = float(set_life(jnp.asarray(L)))
        h = float(life_hours(Ls, op.speed))
        hours = h if np.isfinite(h) else None
    cap = np.array([float(static_axial_capacity(b)) for b in bset.bearings])
    return SetAssessment(tuple(out), Ls, hours, cap, np.asarray(sol.preload, float))


# ------------------------------------------------------------------------------------ study
@dataclass
class SetStudy:
    parameter: str
    unit: str
    values: np.ndarray
    solution: object            # SetSolution with a leading axis (one item per value)


def study_set_case(case, *, throw=True) -> SetStudy:
    """The [study] of a set case: one batched solve when only the speed, the loads or the preload
    change (rigid offsets fixed at standstill from each item's preloads); else one solve per value."""
    st = case.study_settings()
    if st is None:
        raise InputError(f"{case.source}: no [study] section")
    param, values = st
    cases = [c.build() for c in case.study_cases()]
    sets = [c.bearing_set for c in cases]
    base = sets[0]
    same = all(jax.tree_util.tree_structure(s) == jax.tree_util.tree_structure(base) for s in sets) and all(
        np.array_equal(np.asarray(getattr(s.bearings[0], f)), np.asarray(getattr(base.bearings[0], f)))
        for s in sets for f in ("ball_diameter", "pitch_diameter", "f_inner", "f_outer", "free_contact_angle"))
    if same:
        ops = [c.operation for c in cases]
        op = Operation(jnp.stack([o.speed for o in ops]), ops[0].control, ops[0].centrifugal, ops[0].gyroscopic)
        sol = solve_set_batch(base, op, jnp.stack([c.loads for c in cases]),
                              cage_angle=case.cage_angle, preload=jnp.stack([s.preload for s in sets]),
                              facings=jnp.stack([s.facings for s in sets]),
                              positions=jnp.stack([s.positions for s in sets]),
                              springs=jnp.stack([s.springs for s in sets]), hertz_method=case.hertz_method)
    else:
        sols = [solve_set_case(c, throw=False) for c in cases]
        sol = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *sols)
    if throw:
        raise_for_set(sol, _where(case) + " (study)")
    return SetStudy(param, unit_of(param), np.asarray(values, float), sol)


def set_lives_hours(case, sol):
    """(per-bearing lives (N,), set life) in hours at the case's speed (ISO/TS 16281, the nominal
    angle of the single bearing's rule: the free contact angle, 0 for a deep groove, as
    :func:`bearingsim.app.assessment.assess_state`), or None when a bearing has no rating."""
    sc = as_scenario(case)
    C = _ratings(sc)
    if any(c is None for c in C):
        return None
    bset = sc.bearing_set
    L = jnp.stack([rating_life(b, C[k], s.Q_inner, s.Q_outer,
                               contact_angle=float(b.free_contact_angle) if bool(b.angular_contact) else 0.0)
                   for k, (b, s) in enumerate(zip(bset.bearings, sol.bearings))], axis=-1)
    w = sc.operation.speed
    return np.asarray(life_hours(L, w)), float(life_hours(set_life(L), w))


def study_limits(case, study: SetStudy) -> dict:
    """Per bearing over the study's values (arrays (values, bearings)): the largest p_max over
    the pressure limit, the largest friction coefficient raceway control needs over the available
    one, the smallest contact-ellipse margin to a groove edge (deg; negative: truncated), the
    lift-off margin (axial load / preload)."""
    sc = as_scenario(case)
    settings = sc.limits
    bset = sc.bearing_set
    sol = study.solution
    out = {"pressure": [], "friction": [], "edge_deg": []}
    for sb, bb in zip(sol.bearings, bset.bearings):
        lim = contact_limits(sb, bb, sc.operation.control, pressure_limit=settings["pressure_limit"],
                             friction_coefficient=settings["friction_coefficient"])
        out["pressure"].append(np.max(np.maximum(np.asarray(lim.pressure_ratio_inner),
                                                 np.asarray(lim.pressure_ratio_outer)), axis=-1))
        out["friction"].append(np.max(np.asarray(lim.friction_ratio), axis=-1))
        loaded_i, loaded_o = np.asarray(sb.Q_inner) > 0.0, np.asarray(sb.Q_outer) > 0.0
        edge = [np.where(loaded_i, np.asarray(v), np.inf) for v in (lim.edge_high_inner, lim.edge_low_inner)] + \
               [np.where(loaded_o, np.asarray(v), np.inf) for v in (lim.edge_high_outer, lim.edge_low_outer)]
        e = np.min(np.stack([np.min(v, axis=-1) for v in edge]), axis=0)
        out["edge_deg"].append(np.degrees(np.where(np.isfinite(e), e, np.nan)))
    res = {k: np.stack(v, axis=-1) for k, v in out.items()}
    res["lift_off"] = np.asarray(sol.lift_off_margin)
    return res


def set_study_table(case, study: SetStudy) -> dict:
    """Every output of a set study: ``{name: (array, unit)}`` with ``values`` (M,), the per-bearing
    fields of :data:`bearingsim.output.set_report.STUDY_FIELDS` (M, N) and the set fields of
    :data:`~bearingsim.output.set_report.SET_FIELDS` (M,), in their units; life is NaN where a
    bearing has no rating, a limit NaN where it is undefined (no loaded contact)."""
    sol = study.solution
    M, N = np.asarray(sol.axial_load).shape
    out = {"values": (np.asarray(study.values, float), study.unit or "-")}
    Kb = np.stack([np.asarray(b.stiffness) for b in sol.bearings], axis=1)          # (M, N, 5, 5)
    loads = np.stack([np.asarray(b.loads) for b in sol.bearings], axis=1)           # (M, N, 5)
    pmax = np.stack([np.maximum(np.max(np.asarray(b.p_max_inner), -1), np.max(np.asarray(b.p_max_outer), -1))
                     for b in sol.bearings], axis=1)
    out["preload_N"] = (np.broadcast_to(np.asarray(sol.preload, float), (M, N)).copy(), "N")
    out["axial_load_N"] = (np.asarray(sol.axial_load, float), "N")
    out["radial_load_N"] = (np.hypot(loads[..., 0], loads[..., 1]), "N")
    out["axial_stiffness_N_per_um"] = (Kb[..., 2, 2] * 1e-6, "N/um")
    out["radial_stiffness_N_per_um"] = (Kb[..., 0, 0] * 1e-6, "N/um")
    out["tilt_stiffness_Nm_per_mrad"] = (Kb[..., 3, 3] * 1e-3, "N m/mrad")
    out["p_max_MPa"] = (pmax / 1e6, "MPa")
    life = np.full((M, N), np.nan)
    whole = np.full(M, np.nan)
    for i, c in enumerate(case.study_cases()):
        item = jax.tree_util.tree_map(lambda a: a[i], sol)
        lv = set_lives_hours(c, item)
        if lv is not None:
            life[i], whole[i] = lv
    out["life_h"] = (life, "h")
    lim = study_limits(case, study)
    out["pressure_ratio"] = (np.asarray(lim["pressure"], float), "-")
    out["friction_ratio"] = (np.asarray(lim["friction"], float), "-")
    out["edge_margin_deg"] = (np.asarray(lim["edge_deg"], float), "deg")
    out["lift_off_margin"] = (np.asarray(lim["lift_off"], float).reshape(M, N), "-")
    out["bearing_result"] = (np.asarray(sol.bearing_result), "-")
    K = np.asarray(sol.stiffness)
    out["set_axial_stiffness_N_per_um"] = (K[:, 2, 2] * 1e-6, "N/um")
    out["set_radial_stiffness_N_per_um"] = (K[:, 0, 0] * 1e-6, "N/um")
    out["set_tilt_stiffness_Nm_per_mrad"] = (K[:, 3, 3] * 1e-3, "N m/mrad")
    out["set_life_h"] = (whole, "h")
    out["result"] = (np.asarray(sol.result), "-")
    return out
