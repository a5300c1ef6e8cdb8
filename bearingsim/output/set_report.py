"""A bearing set's printed text and results files (docs/model.md section 10): what ``bearingsim info`` /
``static`` / ``study`` print and write for a case with a [set] section.  Renders only: the state
(``SetSolution``), its assessment (:class:`bearingsim.app.set_workflows.SetAssessment`) and a study's
table (:func:`bearingsim.app.set_workflows.set_study_table`) are computed by the workflows.

One unit convention with the single bearing (:data:`bearingsim.output.io.UNITS_NOTE`, stated in the
JSON's ``units``): engineering units with the unit in each key name; the JSON record of every
bearing of a set is the single bearing's (:func:`bearingsim.output.io.static_to_dict`: the same
keys, units, ``limits`` with its ``flags`` and ``life``) plus its place in the set.  Azimuths are
stated in the shaft frame (``azimuth_shaft_deg``) besides each bearing's own frame; per-bearing
loads in each bearing's own frame (its axial load is positive when it carries load in its contact
direction).
"""
from __future__ import annotations

import numpy as np

from ..case import lookup
from ..case.units import from_si, label as unit_label
from ..physics.shaft import PRELOAD_CLASSES, preload_class_force, static_axial_capacity
from .io import RING_DOFS, UNITS_NOTE, atomic_path, case_attrs, static_to_dict, stiffness_to_dict, write_h5
from .report import limits_summary, quantity, stiffness_text
from ..errors import succeeded

__all__ = ["set_text", "set_info_text", "set_study_text", "set_to_dict", "write_set_study", "write_set_study_csv",
           "STUDY_FIELDS", "SET_FIELDS", "parameter_label", "preload_class_text"]


# ------------------------------------------------------------------------------------- text
def _kind(sol, k):
    P = float(np.asarray(sol.preload)[k])
    if float(np.asarray(sol.springs)[k]) > 0:
        return f"spring {P:.0f} N"
    return f"rigid {P:.0f} N (e = {float(np.asarray(sol.offset)[k]) * 1e6:.3f} um)" if P > 0 else "no preload"


def preload_class_text(case) -> str | None:
    """What the case's ``set.preload_class`` means: a share of the bearing's static axial
    capacity C_0a (bearingsim's convention, :data:`bearingsim.physics.shaft.PRELOAD_CLASSES`; not a
    manufacturer's catalogue class), with the force it gives.  None without a class."""
    cls = case.data.get("set", {}).get("preload_class")
    if cls is None:
        return None
    b = case.bearing()
    C0a = float(static_axial_capacity(b))
    return (f"preload class {cls!r} = {100 * PRELOAD_CLASSES[cls]:g} % of C_0a = {C0a / 1e3:.1f} kN (static axial "
            f"capacity: p_max 4.2 GPa at standstill) = {preload_class_force(b, cls):.0f} N; bearingsim's "
            "convention (light / medium / heavy = " + " / ".join(f"{100 * v:g}" for v in PRELOAD_CLASSES.values())
            + " % of C_0a), not a catalogue's classes")


def set_info_text(case) -> str:
    bset = case.bearing_set()
    lines = ["", f"Set: {bset.n} bearings on one rigid shaft (docs/model.md section 10; azimuths in the shaft frame)"]
    if preload_class_text(case):
        lines.append("  " + preload_class_text(case))
    for k, b in enumerate(bset.bearings):
        sp = "spring" if float(bset.springs[k]) else "rigid"
        lines.append(f"  bearing {k + 1}: z = {float(bset.positions[k]) * 1e3:8.2f} mm, facing "
                     f"{int(bset.facings[k]):+d}, Z = {b.n_balls}, D = {float(b.ball_diameter) * 1e3:.3f} mm, "
                     f"alpha_0 = {np.degrees(float(b.free_contact_angle)):.2f} deg, preload "
                     f"{float(bset.preload[k]):.1f} N ({sp})")
    return "\n".join(lines)


def _life_line(assessment) -> str | None:
    a = assessment
    if a.set_life_hours is None and all(b.life_hours is None for b in a.bearings):
        return None
    h = lambda v: "-" if v is None else f"{v:.4g} h"   # noqa: E731
    return ("ISO/TS 16281 L10r life: set " + h(a.set_life_hours) + "; "
            + ", ".join(f"bearing {k + 1} {h(b.life_hours)}" for k, b in enumerate(a.bearings)))


def set_text(case, sol, assessment) -> str:
    """Per bearing: position, facing, preload kind, axial load (operating preload), lift-off
    margin, peak pressure, its limits (the single bearing's line: every limit it breaks, or all
    within) and the per-ball table; per set: displacement, stiffness, life, flags."""
    q = np.asarray(sol.displacement)
    lines = [case.title, f"converged in {int(sol.iterations)} iterations, residual {float(sol.residual_norm):.2e} N",
             "shaft displacement at O: " + ", ".join(f"{n} {quantity(v, u, '.4f')}" for (n, u), v in zip(RING_DOFS, q)),
             stiffness_text(sol.stiffness, "set stiffness"), ""]
    margin = np.asarray(sol.lift_off_margin)
    ratio = np.asarray(sol.ball_load_ratio)
    flags = assessment.flags
    if flags:
        lines.insert(4, "flags: " + "; ".join(f"{n} (bearing {', '.join(map(str, v))})" for n, v in flags.items()))
    if preload_class_text(case):
        lines.insert(4, preload_class_text(case))
    life = _life_line(assessment)
    if life is not None:
        lines.insert(4, life)
    st = assessment.bearings[0].settings
    pl, mu = st["pressure_limit"], st["friction_coefficient"]
    for k, b in enumerate(sol.bearings):
        az = np.degrees(np.asarray(sol.shaft_azimuth(k)))
        lines.append(f"bearing {k + 1}: z = {float(np.asarray(sol.positions)[k]) * 1e3:.2f} mm, facing "
                     f"{int(np.asarray(sol.facings)[k]):+d}, preload {_kind(sol, k)}")
        if assessment.preload_over_capacity[k]:
            lines.append(f"  its preload {float(assessment.preload[k]):.6g} N is above its static axial capacity "
                         f"C_0a = {float(assessment.static_capacity[k]):.6g} N (the thrust that alone gives 4.2 GPa "
                         "at standstill): flagged, not refused; lower the preload")
        lines.append(f"  axial load (operating preload) {float(b.loads[2]):.1f} N, radial "
                     f"{float(np.hypot(b.loads[0], b.loads[1])):.1f} N, lift-off margin "
                     + ("-" if not np.isfinite(margin[k]) else f"{margin[k]:.3f}")
                     + f" (axial load / preload), min/max ball load {ratio[k]:.3f}, p_max "
                     f"{float(b.max_pressure) / 1e6:.0f} MPa")
        lim = assessment.bearings[k].limits
        lines.append(f"  friction coefficient raceway control needs {float(np.max(lim.friction_inner)):.4f} "
                     f"inner / {float(np.max(lim.friction_outer)):.4f} outer (available {mu:g}), contacts over "
                     f"{pl / 1e9:g} GPa: {int(np.sum(np.asarray(lim.overpressure)))}, ellipse truncated by a "
                     f"shoulder: {int(np.sum(np.asarray(lim.truncated)))}, centre over a shoulder: "
                     f"{int(np.sum(np.asarray(lim.over_shoulder)))}")
        lines.append("  " + limits_summary(lim))
        lines.append("   ball  azimuth_deg  alpha_i_deg  alpha_o_deg    Q_i_N    Q_o_N  p_max_i_MPa")
        for j in range(az.size):
            lines.append(f"  {j:5d} {az[j]:12.2f} {np.degrees(float(b.alpha_inner[j])):12.3f} "
                         f"{np.degrees(float(b.alpha_outer[j])):12.3f} {float(b.Q_inner[j]):8.1f} "
                         f"{float(b.Q_outer[j]):8.1f} {float(b.p_max_inner[j]) / 1e6:12.0f}")
        lines.append("")
    return "\n".join(lines)


#: the set stiffness diagonal of the study text: (column, index, unit, SI -> unit)
K_DIAG = (("K_xx", 0, "N/um", 1e-6), ("K_zz", 2, "N/um", 1e-6), ("K_tilt_x", 3, "N m/mrad", 1e-3))


def set_study_text(case, study) -> str:
    sol = study.solution
    R = np.asarray(sol.axial_load)
    K = np.asarray(sol.stiffness)
    res = np.asarray(sol.result)
    head = f"{study.parameter} [{study.unit}]"
    lines = [case.title, f"{head:>28s}  " + "  ".join(f"Fa_{k + 1}_N" for k in range(R.shape[1]))
             + "   " + "  ".join(n + "_" + u.replace(" ", "").replace("/", "_per_") for n, _, u, _ in K_DIAG) + "  result"]
    for i, v in enumerate(study.values):
        lines.append(f"{v:28.6g}  " + "  ".join(f"{x:8.1f}" for x in R[i]) + "   "
                     + "  ".join(f"{K[i, j, j] * s:12.2f}" for _, j, _, s in K_DIAG) + f"  {int(res[i])}")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------- JSON
def set_to_dict(case, sol, assessment) -> dict:
    """The JSON record of a set's state (:data:`bearingsim.output.io.UNITS_NOTE`): the set's result,
    shaft displacement, loads, stiffness (:func:`bearingsim.output.io.stiffness_to_dict`), life and
    ``flags`` (``{name: [bearing numbers]}``: :attr:`SetAssessment.flags`); per bearing the single
    bearing's record (:func:`bearingsim.output.io.static_to_dict` with its assessment) plus its
    place in the set (``position_mm``, ``facing``, ``spring``, ``preload_N``, ``offset_um``,
    ``spring_shift_um``, ``static_axial_capacity_N``, ``preload_over_capacity``, ``azimuth_shaft_deg``)."""
    a = assessment
    q = np.asarray(sol.displacement)
    out = dict(units=UNITS_NOTE, title=case.title, converged=bool(succeeded(int(sol.result))), result=int(sol.result),
               message=sol.message()[0], iterations=int(sol.iterations), residual_norm=float(sol.residual_norm),
               residual_norm_units="N (moments divided by R_i)",
               shaft_displacement={f"{n}_{u}": from_si(float(v), u) for (n, u), v in zip(RING_DOFS, q)},
               loads=dict(zip(["radial_x_N", "radial_y_N", "axial_N", "moment_x_Nm", "moment_y_Nm"],
                              np.asarray(sol.loads).tolist())),
               stiffness=stiffness_to_dict(sol.stiffness),
               life=None if a.set_rating_life is None else {"L10r_Mrev": a.set_rating_life, "L10r_h": a.set_life_hours},
               flags=a.flags, bearings=[])
    for k, b in enumerate(sol.bearings):
        rec = static_to_dict(b, assessment=a.bearings[k])
        # a bearing of a set tilts with the shaft, which the set's other bearings hold: no free /
        # held tilt of its own (the single bearing's ``tilt``), one ``units`` note for the file
        for key in ("units", "tilt", "tilt_note"):
            rec.pop(key, None)
        rec.update(position_mm=from_si(float(np.asarray(sol.positions)[k]), "mm"),
                   facing=int(np.asarray(sol.facings)[k]), spring=bool(float(np.asarray(sol.springs)[k])),
                   preload_N=float(np.asarray(sol.preload)[k]),
                   offset_um=from_si(float(np.asarray(sol.offset)[k]), "um"),
                   spring_shift_um=from_si(float(np.asarray(sol.spring_shift)[k]), "um"),
                   static_axial_capacity_N=float(a.static_capacity[k]),
                   preload_over_capacity=bool(a.preload_over_capacity[k]),
                   azimuth_shaft_deg=from_si(np.asarray(sol.shaft_azimuth(k)), "deg").tolist())
        out["bearings"].append(rec)
    return out


# ------------------------------------------------------------------------------ study files
#: per bearing and per study value (arrays (M, N)): name -> (unit, description)
STUDY_FIELDS = {
    "preload_N": ("N", "the bearing's preload as set (rigid: fixed at standstill; spring: the spring force)"),
    "axial_load_N": ("N", "the axial load it carries in its contact direction: the operating preload"),
    "radial_load_N": ("N", "the radial load it carries"),
    "axial_stiffness_N_per_um": ("N/um", "its own axial stiffness dFz/dz (own frame)"),
    "radial_stiffness_N_per_um": ("N/um", "its own radial stiffness dFx/dx"),
    "tilt_stiffness_Nm_per_mrad": ("N m/mrad", "its own tilt stiffness dMx/dtheta_x"),
    "p_max_MPa": ("MPa", "the largest contact pressure of its balls (inner or outer)"),
    "life_h": ("h", "ISO/TS 16281 basic reference rating life L10r at the value's speed (needs "
                    "bearing.dynamic_load_rating_kN)"),
    "pressure_ratio": ("-", "limit: p_max / the pressure limit (limits.pressure_limit_MPa): over 1 is out"),
    "friction_ratio": ("-", "limit: friction coefficient raceway control needs / available: over 1 is out"),
    "edge_margin_deg": ("deg", "limit: the smallest margin of a loaded contact ellipse to a groove edge "
                               "(negative: truncated)"),
    "lift_off_margin": ("-", "limit: axial load / preload (0: the bearing unloads)"),
    "bearing_result": ("-", "the bearing's own validity code (0 valid; bearingsim.physics.jones.RESULTS)"),
}
#: per study value (arrays (M,)): name -> (unit, description)
SET_FIELDS = {
    "set_axial_stiffness_N_per_um": ("N/um", "the set's axial stiffness at the reference point"),
    "set_radial_stiffness_N_per_um": ("N/um", "the set's radial stiffness (x)"),
    "set_tilt_stiffness_Nm_per_mrad": ("N m/mrad", "the set's tilt stiffness (about x)"),
    "set_life_h": ("h", "ISO/TS 16281 life of the set (bearings fail independently)"),
    "result": ("-", "the set's result code (0 converged and every bearing valid)"),
}


def parameter_label(parameter: str, unit: str | None = None) -> str:
    """A study parameter as a reader names it: "inner-ring speed n (rpm)" for
    ``operation.speed_rpm`` (the key's documented name and unit)."""
    key = lookup(parameter)
    name = key.doc.split(":")[0] if key is not None and key.doc else parameter
    u = unit or (key.unit if key is not None else "")
    try:
        u = unit_label(u) if u else ""
    except KeyError:
        pass
    return f"{name} ({u})" if u else name


def write_set_study(path, case, study, table: dict):
    """The HDF5 of ``bearingsim study`` on a set: group ``/set_study`` with ``values`` (in the
    key's unit), ``axial_load`` (M, N) (N), ``stiffness`` (M, 5, 5) (SI), ``displacement`` (M, 5),
    ``result`` (M,), ``bearing_result`` (M, N) and every field of the study's ``table``
    (:func:`bearingsim.app.set_workflows.set_study_table`; per bearing (M, N): :data:`STUDY_FIELDS`;
    per value (M,): :data:`SET_FIELDS`; each with its ``units`` and ``description``; a field with
    undefined entries (NaN: no rating, no loaded contact) is written with 0 there and a boolean
    ``NAME_defined`` beside it); attributes ``parameter`` and ``parameter_label``."""
    sol = study.solution
    ds = {"values": (np.asarray(study.values, float), study.unit or "1"),
          "axial_load": (np.asarray(sol.axial_load), "N"),
          "stiffness": (np.asarray(sol.stiffness), "SI (N/m, N/rad, N m/m, N m/rad)"),
          "displacement": (np.asarray(sol.displacement), "m, m, m, rad, rad"),
          "result": (np.asarray(sol.result), "1"),
          "bearing_result": (np.asarray(sol.bearing_result), "1"),
          "@attrs": {"parameter": study.parameter, "parameter_label": parameter_label(study.parameter, study.unit),
                     "axes": "per-bearing fields (values, bearings); set fields (values,)"}}
    docs = {**STUDY_FIELDS, **SET_FIELDS}
    for name, (arr, unit) in table.items():
        if name in ("values", "result", "bearing_result"):
            continue
        a = np.asarray(arr, float)
        ok = np.isfinite(a)
        ds[name] = (np.where(ok, a, 0.0), unit, {"description": docs[name][1]})
        if not ok.all():
            ds[name + "_defined"] = (ok, "1", {"description": f"where {name} is defined"})
    write_h5(path, {"set_study": ds}, attrs=case_attrs(case))


def write_set_study_csv(path, study, table: dict):
    """The set study as CSV (atomically): one row per study value and bearing (``bearing`` 1..N),
    the columns of :data:`STUDY_FIELDS` then those of :data:`SET_FIELDS` (repeated on the rows of
    one value); a header line names each column's unit; undefined entries are empty."""
    v = table["values"][0]
    M, N = table["axial_load_N"][0].shape
    per = list(STUDY_FIELDS)
    whole = list(SET_FIELDS)
    name = study.parameter.split(".")[-1]
    head = [name, "bearing"] + per + whole
    units = [study.unit or "-", "-"] + [table[k][1] for k in per] + [table[k][1] for k in whole]

    def cell(x):
        x = float(x)
        return "" if not np.isfinite(x) else (f"{x:.0f}" if x == int(x) and abs(x) < 1e15 else f"{x:.6g}")

    rows = [",".join(head), "# units: " + ",".join(units)]
    for i in range(M):
        for k in range(N):
            rows.append(",".join([cell(v[i]), str(k + 1)] + [cell(table[f][0][i, k]) for f in per]
                                 + [cell(table[f][0][i]) for f in whole]))
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path
