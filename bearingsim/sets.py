"""Bearing sets on the edge (MODEL.md 10; core: :mod:`bearingsim.shaft`): the workflows
(:func:`solve_set_case`, :func:`study_set_case`), the printed text, the JSON record and the
figures of a case with a [set] section.  ``bearingsim static`` / ``study`` / ``info`` call these
when the case describes a set.

Azimuths are stated in the shaft frame (MODEL.md 10); per-bearing loads in each bearing's own
frame (its axial load is positive when it carries load in its contact direction).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError

__all__ = ["solve_set_case", "study_set_case", "SetStudy", "set_text", "set_info_text",
           "set_study_text", "set_to_dict", "write_set_study", "plot_set_static", "plot_set_study",
           "study_limits", "plot_set_limits"]

DOF = (("x", "um", 1e6), ("y", "um", 1e6), ("axial", "um", 1e6), ("tilt_x", "mrad", 1e3),
       ("tilt_y", "mrad", 1e3))
#: the stiffness diagonal: radial (N/um), axial (N/um), tilt (N m/mrad)
K_DIAG = (("K_xx", 0, "N/um", 1e-6), ("K_zz", 2, "N/um", 1e-6), ("K_tilt_x", 3, "N m/mrad", 1e-3))


def _where(case):
    return f"set solve of {case.source}" if getattr(case, "source", None) else "set solve"


def solve_set_case(case, *, throw=True):
    """The set's state at the case's operating point (:class:`bearingsim.shaft.SetSolution`)."""
    from .shaft import raise_for_set, solve_set
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

    from .kinematics import Operation
    from .shaft import raise_for_set, solve_set_batch
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
    from .case import unit_of
    return SetStudy(st["parameter"], unit_of(st["parameter"]), np.asarray(st["values"], float), sol)


# ------------------------------------------------------------------------------------- text
def _kind(sol, k):
    P = float(np.asarray(sol.preload)[k])
    if float(np.asarray(sol.springs)[k]) > 0:
        return f"spring {P:.0f} N"
    return f"rigid {P:.0f} N (e = {float(np.asarray(sol.offset)[k]) * 1e6:.3f} um)" if P > 0 else "no preload"


def set_info_text(case) -> str:
    bset = case.bearing_set()
    lines = ["", f"Set: {bset.n} bearings on one rigid shaft (MODEL.md 10; azimuths in the shaft frame)"]
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
    from .case.sets import set_layout
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
    from .life import life_hours
    from .shaft import set_lives
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
    from .limits import contact_limits
    settings = case.limits_settings()
    pl, mu = settings["pressure_limit"], settings["friction_coefficient"]
    bset = case.bearing_set()
    limits = [contact_limits(sb, bb, case.operation().control, pressure_limit=pl, friction_coefficient=mu)
              for sb, bb in zip(sol.bearings, bset.bearings)]
    lives = set_lives_hours(case, sol)
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


def write_set_study(path, case, study: SetStudy):
    """The HDF5 of ``bearingsim study`` on a set: group ``/set_study`` with ``values`` (in the
    key's unit), ``axial_load`` (M, N) (N), ``stiffness`` (M, 5, 5) (SI), ``displacement`` (M, 5),
    ``result`` (M,) and ``bearing_result`` (M, N); attribute ``parameter``."""
    from .io import case_attrs, write_h5
    sol = study.solution
    ds = {"values": (np.asarray(study.values, float), study.unit or "1"),
          "axial_load": (np.asarray(sol.axial_load), "N"),
          "stiffness": (np.asarray(sol.stiffness), "SI (N/m, N/rad, N m/m, N m/rad)"),
          "displacement": (np.asarray(sol.displacement), "m, m, m, rad, rad"),
          "result": (np.asarray(sol.result), "1"),
          "bearing_result": (np.asarray(sol.bearing_result), "1"),
          "@attrs": {"parameter": study.parameter}}
    write_h5(path, {"set_study": ds}, attrs=case_attrs(case))


# ------------------------------------------------------------------------------------ plots
def plot_set_static(sol, title="", path=None):
    """Polar plot of the inner contact loads of every ball, one panel per bearing (shaft frame)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    n = sol.n
    fig, axes = plt.subplots(1, n, subplot_kw=dict(projection="polar"), figsize=(3.6 * n, 3.8))
    axes = np.atleast_1d(axes)
    for k, (ax, b) in enumerate(zip(axes, sol.bearings)):
        az = np.asarray(sol.shaft_azimuth(k))
        order = np.argsort(np.mod(az, 2 * np.pi))
        a = np.mod(az, 2 * np.pi)[order]
        Q = np.asarray(b.Q_inner)[order]
        ax.plot(np.append(a, a[0]), np.append(Q, Q[0]), "o-", ms=3)
        ax.set_title(f"bearing {k + 1} (facing {int(np.asarray(sol.facings)[k]):+d})\n"
                     f"Fa = {float(b.loads[2]):.0f} N", fontsize=9)
    fig.suptitle(title + "\ninner contact load per ball (N), shaft-frame azimuth", fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def plot_set_study(study: SetStudy, title="", path=None):
    """Operating preload (axial load) of each bearing and the set stiffness vs the parameter."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    sol = study.solution
    v = study.values
    R = np.asarray(sol.axial_load)
    K = np.asarray(sol.stiffness)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    for k in range(R.shape[1]):
        a1.plot(v, R[:, k], "o-", label=f"bearing {k + 1}")
    a1.set_xlabel(f"{study.parameter} [{study.unit}]")
    a1.set_ylabel("axial load (operating preload) [N]")
    a1.legend(fontsize=8)
    for name, j, unit, s in K_DIAG:
        a2.plot(v, K[:, j, j] * s, "o-", label=f"{name} [{unit}]")
    a2.set_xlabel(f"{study.parameter} [{study.unit}]")
    a2.set_ylabel("set stiffness")
    a2.legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def study_limits(case, study: SetStudy) -> dict:
    """Per bearing over the study's values (arrays (values, bearings)): the largest p_max over
    the pressure limit, the largest friction coefficient raceway control needs over the available
    one, the smallest contact-ellipse margin to a groove edge (deg; negative: truncated), the
    lift-off margin (axial load / preload)."""
    from .limits import contact_limits
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
    for ax in axes[1]:
        ax.set_xlabel(f"{study.parameter} [{study.unit}]")
    fig.suptitle((title + "\n" if title else "") + "limits over " + study.parameter, fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def _save(fig, path):
    if path is None:
        return fig
    from .io import atomic_path
    import matplotlib.pyplot as plt
    from pathlib import Path
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120, format=Path(path).suffix.lstrip(".") or "png")
    plt.close(fig)
    return path
