"""Bearing sets on the edge (MODEL.md 10; core: :mod:`bearingsim.physics.shaft`): the workflows
(:func:`solve_set_case`, :func:`study_set_case`), the printed text, the JSON record and the
figures of a case with a [set] section.  :mod:`bearingsim.app.workflows` calls these when the case
describes a set (``solve_case``, ``study_case``, ``info_text``, ``static_command``,
``study_command`` dispatch on the case), so ``bearingsim static`` / ``study`` / ``info`` have no set
branch.

Azimuths are stated in the shaft frame (MODEL.md 10); per-bearing loads in each bearing's own
frame (its axial load is positive when it carries load in its contact direction).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..case import lookup, unit_of
from ..case.sets import set_layout
from ..case.units import label as unit_label
from ..errors import InputError
from ..output.io import atomic_path, case_attrs, write_h5
from ..physics.kinematics import Operation
from ..physics.life import life_hours
from ..physics.limits import contact_limits
from ..physics.shaft import (PRELOAD_CLASSES, preload_class_force, raise_for_set, set_lives, solve_set,
                             solve_set_batch, static_axial_capacity)

__all__ = ["solve_set_case", "study_set_case", "SetStudy", "set_text", "set_info_text",
           "set_study_text", "set_to_dict", "write_set_study", "plot_set_static", "plot_set_study",
           "study_limits", "plot_set_limits", "set_study_table", "write_set_study_csv", "STUDY_FIELDS",
           "parameter_label", "preload_class_text"]

DOF = (("x", "um", 1e6), ("y", "um", 1e6), ("axial", "um", 1e6), ("tilt_x", "mrad", 1e3),
       ("tilt_y", "mrad", 1e3))
#: the stiffness diagonal: radial (N/um), axial (N/um), tilt (N m/mrad)
K_DIAG = (("K_xx", 0, "N/um", 1e-6), ("K_zz", 2, "N/um", 1e-6), ("K_tilt_x", 3, "N m/mrad", 1e-3))


def _where(case):
    return f"set solve of {case.source}" if getattr(case, "source", None) else "set solve"


def solve_set_case(case, *, throw=True):
    """The set's state at the case's operating point (:class:`bearingsim.physics.shaft.SetSolution`)."""
    if not case.is_set:
        raise InputError(f"{case.source}: no [set] section: this is a single-bearing case")
    sol = solve_set(case.bearing_set(), case.operation(), case.loads(), cage_angle=case.cage_angle,
                    hertz_method=case.hertz_method, throw=False)
    if throw:
        raise_for_set(sol, _where(case))
    return sol


@dataclass
class SetStudy:
    parameter: str
    unit: str
    values: np.ndarray
    solution: object            # SetSolution with a leading axis (one item per value)


def study_set_case(case, *, throw=True) -> SetStudy:
    """The [study] of a set case: one batched solve when only the speed, the loads or the preload
    change (rigid offsets fixed at standstill from each item's preloads); else one solve per value."""
    import jax
    import jax.numpy as jnp

    st = case.data.get("study")
    if st is None:
        raise InputError(f"{case.source}: no [study] section")
    cases = case.study_cases()
    sets = [c.bearing_set() for c in cases]
    base = sets[0]
    same = all(jax.tree_util.tree_structure(s) == jax.tree_util.tree_structure(base) for s in sets) and all(
        np.array_equal(np.asarray(getattr(s.bearings[0], f)), np.asarray(getattr(base.bearings[0], f)))
        for s in sets for f in ("ball_diameter", "pitch_diameter", "f_inner", "f_outer", "free_contact_angle"))
    if same:
        ops = [c.operation() for c in cases]
        op = Operation(jnp.stack([o.speed for o in ops]), ops[0].control, ops[0].centrifugal, ops[0].gyroscopic)
        sol = solve_set_batch(base, op, jnp.stack([c.loads() for c in cases]),
                              cage_angle=case.cage_angle, preload=jnp.stack([s.preload for s in sets]),
                              facings=jnp.stack([s.facings for s in sets]),
                              positions=jnp.stack([s.positions for s in sets]),
                              springs=jnp.stack([s.springs for s in sets]), hertz_method=case.hertz_method)
    else:
        sols = [solve_set_case(c, throw=False) for c in cases]
        sol = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *sols)
    if throw:
        raise_for_set(sol, _where(case) + " (study)")
    return SetStudy(st["parameter"], unit_of(st["parameter"]), np.asarray(st["values"], float), sol)


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
    lines = ["", f"Set: {bset.n} bearings on one rigid shaft (MODEL.md 10; azimuths in the shaft frame)"]
    if preload_class_text(case):
        lines.append("  " + preload_class_text(case))
    for k, b in enumerate(bset.bearings):
        sp = "spring" if float(bset.springs[k]) else "rigid"
        lines.append(f"  bearing {k + 1}: z = {float(bset.positions[k]) * 1e3:8.2f} mm, facing "
                     f"{int(bset.facings[k]):+d}, Z = {b.n_balls}, D = {float(b.ball_diameter) * 1e3:.3f} mm, "
                     f"alpha_0 = {np.degrees(float(b.free_contact_angle)):.2f} deg, preload "
                     f"{float(bset.preload[k]):.1f} N ({sp})")
    return "\n".join(lines)


def _ratings(case):
    """C (N) of every bearing of the set ([bearing] / [set.second_bearing]
    dynamic_load_rating_kN), or None when a bearing has no rating."""
    s = case.data["set"]
    facings, _, _, _, _, seconds = set_layout(s, 0.0)
    C1 = case.data["bearing"].get("dynamic_load_rating_kN")
    C2 = s.get("second_bearing", {}).get("dynamic_load_rating_kN")
    C = [C2 if k in seconds else C1 for k in range(len(facings))]
    return None if any(c is None for c in C) else [1e3 * c for c in C]


def set_lives_hours(case, sol):
    """(per-bearing lives (N,), set life) in hours at the case's speed (ISO/TS 16281), or None."""
    C = _ratings(case)
    if C is None:
        return None
    L, Ls = set_lives(case.bearing_set(), sol, C)
    w = case.operation().speed
    return np.asarray(life_hours(L, w)), float(life_hours(Ls, w))


def set_text(case, sol) -> str:
    """Per bearing: position, facing, preload kind, axial load (operating preload), lift-off
    margin, peak pressure and the per-ball table; per set: displacement and stiffness."""
    q = np.asarray(sol.displacement)
    K = np.asarray(sol.stiffness)
    lines = [case.title, f"converged in {int(sol.iterations)} iterations, residual {float(sol.residual_norm):.2e} N",
             "shaft displacement at O: " + ", ".join(f"{n} {v * s:.4f} {u}" for (n, u, s), v in zip(DOF, q)),
             "set stiffness: " + ", ".join(f"{n} {K[i, i] * s:.2f} {u}" for n, i, u, s in K_DIAG), ""]
    margin = np.asarray(sol.lift_off_margin)
    ratio = np.asarray(sol.ball_load_ratio)
    settings = case.limits_settings()
    pl, mu = settings["pressure_limit"], settings["friction_coefficient"]
    bset = case.bearing_set()
    limits = [contact_limits(sb, bb, case.operation().control, pressure_limit=pl, friction_coefficient=mu)
              for sb, bb in zip(sol.bearings, bset.bearings)]
    lives = set_lives_hours(case, sol)
    if preload_class_text(case):
        lines.insert(4, preload_class_text(case))
    if lives is not None:
        lines.insert(4, "ISO/TS 16281 L10r life: set " + f"{lives[1]:.4g} h; "
                     + ", ".join(f"bearing {k + 1} {h:.4g} h" for k, h in enumerate(lives[0])))
    for k, b in enumerate(sol.bearings):
        az = np.degrees(np.asarray(sol.shaft_azimuth(k)))
        lines.append(f"bearing {k + 1}: z = {float(np.asarray(sol.positions)[k]) * 1e3:.2f} mm, facing "
                     f"{int(np.asarray(sol.facings)[k]):+d}, preload {_kind(sol, k)}")
        lines.append(f"  axial load (operating preload) {float(b.loads[2]):.1f} N, radial "
                     f"{float(np.hypot(b.loads[0], b.loads[1])):.1f} N, lift-off margin "
                     + ("-" if not np.isfinite(margin[k]) else f"{margin[k]:.3f}")
                     + f" (axial load / preload), min/max ball load {ratio[k]:.3f}, p_max "
                     f"{float(b.max_pressure) / 1e6:.0f} MPa")
        lim = limits[k]
        lines.append(f"  limits: friction coefficient raceway control needs {float(np.max(lim.friction_inner)):.4f} "
                     f"inner / {float(np.max(lim.friction_outer)):.4f} outer (available {mu:g}), contacts over "
                     f"{pl / 1e9:g} GPa: {int(np.sum(np.asarray(lim.overpressure)))}, ellipse truncated by a "
                     f"shoulder: {int(np.sum(np.asarray(lim.truncated)))}, centre over a shoulder: "
                     f"{int(np.sum(np.asarray(lim.over_shoulder)))}")
        lines.append("   ball  azimuth_deg  alpha_i_deg  alpha_o_deg    Q_i_N    Q_o_N  p_max_i_MPa")
        for j in range(az.size):
            lines.append(f"  {j:5d} {az[j]:12.2f} {np.degrees(float(b.alpha_inner[j])):12.3f} "
                         f"{np.degrees(float(b.alpha_outer[j])):12.3f} {float(b.Q_inner[j]):8.1f} "
                         f"{float(b.Q_outer[j]):8.1f} {float(b.p_max_inner[j]) / 1e6:12.0f}")
        lines.append("")
    return "\n".join(lines)


def set_study_text(case, study: SetStudy) -> str:
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


def set_to_dict(case, sol) -> dict:
    """A JSON record of a set's state (SI; azimuths of each bearing in the shaft frame)."""
    lives = set_lives_hours(case, sol)
    out = dict(title=case.title, result=int(sol.result), displacement=np.asarray(sol.displacement),
               displacement_units="m, m, m, rad, rad", stiffness=np.asarray(sol.stiffness),
               stiffness_units="N/m (forces/translations), N/rad, N m/m, N m/rad",
               bearings=[])
    if lives is not None:
        out["life_hours"] = lives[1]
    for k, b in enumerate(sol.bearings):
        out["bearings"].append(dict(
            position_m=float(np.asarray(sol.positions)[k]), facing=int(np.asarray(sol.facings)[k]),
            spring=bool(float(np.asarray(sol.springs)[k])), preload_N=float(np.asarray(sol.preload)[k]),
            offset_m=float(np.asarray(sol.offset)[k]), spring_shift_m=float(np.asarray(sol.spring_shift)[k]),
            loads=np.asarray(b.loads), result=int(b.result), azimuth_rad=np.asarray(sol.shaft_azimuth(k)),
            alpha_inner_rad=np.asarray(b.alpha_inner), alpha_outer_rad=np.asarray(b.alpha_outer),
            Q_inner_N=np.asarray(b.Q_inner), Q_outer_N=np.asarray(b.Q_outer),
            p_max_inner_Pa=np.asarray(b.p_max_inner), p_max_outer_Pa=np.asarray(b.p_max_outer)))
        if lives is not None:
            out["bearings"][-1]["life_hours"] = float(lives[0][k])
    return out


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


def set_study_table(case, study: SetStudy) -> dict:
    """Every output of a set study: ``{name: (array, unit)}`` with ``values`` (M,), the per-bearing
    fields of :data:`STUDY_FIELDS` (M, N) and the set fields of :data:`SET_FIELDS` (M,); life is
    NaN where a bearing has no rating, a limit NaN where it is undefined (no loaded contact)."""
    import jax

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
    set_life = np.full(M, np.nan)
    cases = case.study_cases()
    for i, c in enumerate(cases):
        item = jax.tree_util.tree_map(lambda a: a[i], sol)
        lv = set_lives_hours(c, item)
        if lv is not None:
            life[i], set_life[i] = lv
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
    out["set_life_h"] = (set_life, "h")
    out["result"] = (np.asarray(sol.result), "-")
    return out


def write_set_study(path, case, study: SetStudy, table: dict | None = None):
    """The HDF5 of ``bearingsim study`` on a set: group ``/set_study`` with ``values`` (in the
    key's unit), ``axial_load`` (M, N) (N), ``stiffness`` (M, 5, 5) (SI), ``displacement`` (M, 5),
    ``result`` (M,), ``bearing_result`` (M, N) and every field of :func:`set_study_table`
    (per bearing (M, N): :data:`STUDY_FIELDS`; per value (M,): :data:`SET_FIELDS`; each with its
    ``units`` and ``description``; a field with undefined entries (NaN: no rating, no loaded
    contact) is written with 0 there and a boolean ``NAME_defined`` beside it); attributes
    ``parameter`` and ``parameter_label``."""
    sol = study.solution
    table = set_study_table(case, study) if table is None else table
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


def write_set_study_csv(path, case, study: SetStudy, table: dict | None = None):
    """The set study as CSV (atomically): one row per study value and bearing (``bearing`` 1..N),
    the columns of :data:`STUDY_FIELDS` then those of :data:`SET_FIELDS` (repeated on the rows of
    one value); a header line names each column's unit; undefined entries are empty."""
    table = set_study_table(case, study) if table is None else table
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
    from pathlib import Path
    with atomic_path(path) as tmp:
        Path(tmp).write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


# ------------------------------------------------------------------------------------ plots
def plot_set_static(sol, title="", path=None):
    """One column per bearing (shaft frame): above, the polar plot of the inner and outer contact
    loads of every ball; below, the inner and outer contact angles of every ball over its azimuth."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    n = sol.n
    fig = plt.figure(figsize=(3.8 * n, 7.2))
    for k, b in enumerate(sol.bearings):
        az = np.asarray(sol.shaft_azimuth(k))
        order = np.argsort(np.mod(az, 2 * np.pi))
        a = np.mod(az, 2 * np.pi)[order]
        ax = fig.add_subplot(2, n, k + 1, projection="polar")
        for Q, lab in ((np.asarray(b.Q_inner)[order], "inner"), (np.asarray(b.Q_outer)[order], "outer")):
            ax.plot(np.append(a, a[0]), np.append(Q, Q[0]), "o-", ms=3, label=lab)
        ax.set_title(f"bearing {k + 1} (facing {int(np.asarray(sol.facings)[k]):+d})\n"
                     f"Fa = {float(b.loads[2]):.0f} N; contact load (N)", fontsize=9)
        ax.tick_params(labelsize=7)
        from matplotlib.ticker import MaxNLocator
        ax.yaxis.set_major_locator(MaxNLocator(nbins=4))
        if k == 0:
            ax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(-0.25, -0.15))
        ax2 = fig.add_subplot(2, n, n + k + 1)
        deg = np.degrees(a)
        ax2.plot(deg, np.degrees(np.asarray(b.alpha_inner))[order], "o-", ms=3, label="inner")
        ax2.plot(deg, np.degrees(np.asarray(b.alpha_outer))[order], "s-", ms=3, label="outer")
        ax2.set_xlim(0, 360)
        ax2.set_xticks(range(0, 361, 90))
        ax2.set_xlabel("ball azimuth, shaft frame (deg)")
        ax2.set_ylabel("contact angle (deg)")
        ax2.grid(alpha=0.3)
        ax2.legend(fontsize=7)
    fig.suptitle(title + "\ncontact loads and contact angles per ball", fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def _strip_fixed_speed(title, parameter):
    """A title without its fixed speed ("..., 10000 rpm") when the study runs the speed."""
    import re
    if not parameter.endswith("speed_rpm"):
        return title
    return re.sub(r",?\s*\d[\d,.]*\s*rpm\b", "", title).strip(" ,")


def _value_axis(ax, values, xlabel):
    from matplotlib.ticker import MaxNLocator, ScalarFormatter
    ax.set_xlabel(xlabel)
    ax.xaxis.set_major_locator(MaxNLocator(nbins=7))
    f = ScalarFormatter(useOffset=False)
    f.set_scientific(False)
    ax.xaxis.set_major_formatter(f)
    ax.grid(alpha=0.3)


def plot_set_study(study: SetStudy, title="", path=None, table=None, case=None):
    """A set study over its parameter, one axis per unit: the preload and the operating axial
    load of each bearing (N); the axial, radial (N/um) and tilt (N m/mrad) stiffness of each
    bearing and of the set; the L10r life of each bearing and of the set (h, log scale; needs
    ``case`` or ``table`` and the bearings' ratings)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if table is None:
        table = set_study_table(case, study) if case is not None else None
    sol = study.solution
    v = np.asarray(study.values, float)
    xl = parameter_label(study.parameter, study.unit)
    R = np.asarray(sol.axial_load)
    K = np.asarray(sol.stiffness)
    N = R.shape[1]
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    fig, axes = plt.subplots(2, 3, figsize=(14, 7.5))
    a = axes[0, 0]
    for k in range(N):
        a.plot(v, R[:, k], "o-", ms=4, color=colours[k % 10], label=f"bearing {k + 1}: operating")
        if table is not None:
            a.plot(v, table["preload_N"][0][:, k], "--", color=colours[k % 10], lw=1, label=f"bearing {k + 1}: as set")
    a.set_ylabel("axial load: preload (N)")
    a.set_title("preload", fontsize=10)
    a.legend(fontsize=7)
    stiff = (("axial stiffness (N/µm)", 2, 1e-6, "axial_stiffness_N_per_um"),
             ("radial stiffness (N/µm)", 0, 1e-6, "radial_stiffness_N_per_um"),
             ("tilt stiffness (N m/mrad)", 3, 1e-3, "tilt_stiffness_Nm_per_mrad"))
    for ax, (lab, j, sc, key) in zip((axes[0, 1], axes[0, 2], axes[1, 0]), stiff):
        ax.plot(v, K[:, j, j] * sc, "o-", ms=4, color="k", label="set")
        if table is not None:
            for k in range(N):
                ax.plot(v, table[key][0][:, k], "o--", ms=3, lw=1, color=colours[k % 10], label=f"bearing {k + 1}")
        ax.set_ylabel(lab)
        ax.set_title(lab.split(" (")[0], fontsize=10)
        ax.legend(fontsize=7)
    a = axes[1, 1]
    life = None if table is None else table["life_h"][0]
    if life is not None and np.isfinite(life).any():
        for k in range(N):
            a.semilogy(v, life[:, k], "o--", ms=3, lw=1, color=colours[k % 10], label=f"bearing {k + 1}")
        a.semilogy(v, table["set_life_h"][0], "o-", ms=4, color="k", label="set")
        a.legend(fontsize=7)
    else:
        a.text(0.5, 0.5, "no life: give bearing.dynamic_load_rating_kN", ha="center", va="center",
               transform=a.transAxes, fontsize=9)
    a.set_ylabel("L10r life (h)")
    a.set_title("ISO/TS 16281 life", fontsize=10)
    a = axes[1, 2]
    if table is not None:
        for k in range(N):
            a.plot(v, table["p_max_MPa"][0][:, k], "o-", ms=3, color=colours[k % 10], label=f"bearing {k + 1}")
        a.legend(fontsize=7)
    a.set_ylabel("largest contact pressure p_max (MPa)")
    a.set_title("contact pressure", fontsize=10)
    for ax in axes.ravel():
        _value_axis(ax, v, xl)
    fig.suptitle(_strip_fixed_speed(title, study.parameter) + f"\nset study over {xl}", fontsize=11)
    fig.tight_layout()
    return _save(fig, path)


def study_limits(case, study: SetStudy) -> dict:
    """Per bearing over the study's values (arrays (values, bearings)): the largest p_max over
    the pressure limit, the largest friction coefficient raceway control needs over the available
    one, the smallest contact-ellipse margin to a groove edge (deg; negative: truncated), the
    lift-off margin (axial load / preload)."""
    settings = case.limits_settings()
    bset = case.bearing_set()
    sol = study.solution
    out = {"pressure": [], "friction": [], "edge_deg": []}
    for sb, bb in zip(sol.bearings, bset.bearings):
        lim = contact_limits(sb, bb, case.operation().control, pressure_limit=settings["pressure_limit"],
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


def plot_set_limits(case, study: SetStudy, title="", path=None):
    """The limits diagram over the study's parameter (speed, preload, ...): per bearing the peak
    pressure over its limit, the friction raceway control needs over the available, the smallest
    ellipse-to-edge margin and the lift-off margin; the shaded side of each line is out of margin."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    lim = study_limits(case, study)
    v = study.values
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    panels = (("pressure", "p_max / pressure limit (-)", 1.0, "above"),
              ("friction", "friction needed / available (-)", 1.0, "above"),
              ("edge_deg", "smallest ellipse margin to a groove edge (deg)", 0.0, "below"),
              ("lift_off", "lift-off margin: axial load / preload (-)", 0.0, "below"))
    for ax, (key, label, bound, bad) in zip(axes.ravel(), panels):
        y = np.asarray(lim[key], float)
        y = y[:, None] if y.ndim == 1 else y
        for k in range(y.shape[1]):
            ax.plot(v, y[:, k], "o-", ms=3, label=f"bearing {k + 1}")
        ax.axhline(bound, color="0.3", lw=0.8, ls="--")
        lo, hi = ax.get_ylim()
        if bad == "above":
            ax.axhspan(bound, max(hi, bound * 1.05 + 1e-9), color="#d62728", alpha=0.08)
        else:
            ax.axhspan(min(lo, bound - 1e-9), bound, color="#d62728", alpha=0.08)
        ax.set_ylabel(label, fontsize=9)
        ax.legend(fontsize=7)
    xl = parameter_label(study.parameter, study.unit)
    for ax in axes.ravel():
        _value_axis(ax, v, xl if ax in axes[1] else "")
    title = _strip_fixed_speed(title, study.parameter)
    fig.suptitle((title + "\n" if title else "") + "limits over " + xl, fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def _save(fig, path):
    if path is None:
        return fig
    import matplotlib.pyplot as plt
    from pathlib import Path
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120, format=Path(path).suffix.lstrip(".") or "png")
    plt.close(fig)
    return path
