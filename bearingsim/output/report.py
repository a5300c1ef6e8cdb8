"""Plain-text reports of cases and results: what ``bearingsim info|static|study|compare|spectrum``
print, usable as they are from Python (``print(report.info_text(case))``).

Engineering units in every label; the results themselves stay SI.
"""
from __future__ import annotations

import numpy as np

from ..case.units import from_si, label
from ..physics.hertz import hertz_contact
from ..physics.kinematics import ball_kinematics, defect_frequencies
from .io import RING_DOFS
from ..errors import failed

__all__ = ["table", "quantity", "info_text", "static_text", "tilt_text", "stiffness_text", "limits_summary", "limits_text", "study_text", "compare_text", "spectrum_text"]



def table(headers, rows, fmts) -> str:
    """Right-aligned text table: one ``fmts`` format string per column."""
    cols = [[h] + [f.format(r[i]) for r in rows] for i, (h, f) in enumerate(zip(headers, fmts))]
    w = [max(len(c) for c in col) for col in cols]
    lines = ["  ".join(c[0].rjust(wi) for c, wi in zip(cols, w)), "  ".join("-" * wi for wi in w)]
    for k in range(len(rows)):
        lines.append("  ".join(c[k + 1].rjust(wi) for c, wi in zip(cols, w)))
    return "\n".join(lines)


def quantity(value, unit: str, fmt: str = ".4f") -> str:
    """An SI value shown in ``unit`` with its label: ``quantity(0.022225, "mm")`` -> "22.2250 mm"."""
    return f"{from_si(float(value), unit):{fmt}} {label(unit)}"


def _pairs(rows) -> list[str]:
    return [f"  {k:<32} {v}" for k, v in rows]


def info_text(case) -> str:
    """Geometry, Hertz constants at alpha_0, kinematics, defect frequencies and spall of a case."""
    b = case.bearing()
    op = case.operation()
    a0 = float(b.free_contact_angle)
    out = [f"{case.title}", "=" * len(case.title), "", "Geometry"]
    out += _pairs([
        ("balls Z", f"{b.n_balls}"),
        ("ball diameter D", quantity(b.ball_diameter, "mm")),
        ("pitch diameter d_m", quantity(b.pitch_diameter, "mm")),
        ("groove curvature f_i / f_o", f"{float(b.f_inner):.4f} / {float(b.f_outer):.4f}"),
        ("total conformity B", f"{float(b.B):.4f}"),
        ("groove-centre distance A = BD", quantity(b.A, "mm")),
        ("free contact angle alpha_0", quantity(a0, "deg", ".3f")),
        ("diametral clearance P_d", quantity(b.diametral_clearance, "mm")),
        ("inner groove-centre radius R_i", quantity(b.inner_groove_radius, "mm")),
        ("outer raceway radius R_o", quantity(b.outer_raceway_radius, "mm")),
        ("ball mass m / inertia J", f"{quantity(b.ball_mass, 'g', '.3f')} / {float(b.ball_inertia):.4e} kg m^2"),
        ("effective modulus E'", quantity(b.effective_modulus, "GPa", ".2f")),
    ])
    out += ["", f"Hertz point contact at alpha_0 ({case.hertz_method})"]
    rows = []
    for name, inner in (("inner", True), ("outer", False)):
        c = hertz_contact(b, a0, inner, case.hertz_method)
        rows.append((name, from_si(float(c.sum_rho), "per_mm"), float(c.F_rho), float(c.kappa), float(c.K_ell),
                     float(c.E_ell), from_si(float(c.K), "N_per_mm1_5")))
    out.append(table(("contact", "sum_rho (1/mm)", "F(rho)", "kappa", "K(e)", "E(e)", "K (N/mm^1.5)"), rows,
                     ("{}", "{:.5f}", "{:.5f}", "{:.4f}", "{:.5f}", "{:.5f}", "{:.5g}")))
    n = from_si(float(op.speed), "rpm")
    kin = ball_kinematics(b, op, a0, a0)
    out += ["", f"Kinematics at alpha_0, {n:.1f} rpm, {op.control} raceway control"]
    out += _pairs([("orbital (cage) speed", quantity(kin.orbital_speed, "rpm", ".2f")),
                   ("ball spin speed", quantity(kin.spin_speed, "rpm", ".2f")),
                   ("spin-axis pitch beta", quantity(kin.beta, "deg", ".3f")),
                   ("centrifugal force F_c", f"{float(kin.centrifugal):.3f} N"),
                   ("gyroscopic moment M_g", f"{float(kin.gyroscopic):.5f} N m")])
    shaft = from_si(float(op.speed), "rev_s")
    f = defect_frequencies(b, shaft, a0)
    per_hz = defect_frequencies(b, 1.0, a0)          # multiples of the shaft frequency
    out += ["", f"Defect frequencies at alpha_0 (shaft {shaft:.3f} Hz); BSF once per ball revolution"]
    for name, field in (("FTF", "ftf"), ("BPFO", "bpfo"), ("BPFI", "bpfi"), ("BSF", "bsf"), ("2 BSF", "two_bsf")):
        out.append(f"  {name:<6} {float(getattr(f, field)):10.3f} Hz   {float(getattr(per_hz, field)):.5f} x shaft")
    sp = case.spall()
    if sp is not None:
        v = {k: float(getattr(f, k)) for k in ("shaft", "ftf", "bpfo", "bpfi", "bsf", "two_bsf")}
        size = (f"extent {quantity(sp.extent, 'deg', '.3f')} (arc {quantity(sp.length(b), 'mm', '.4f')}), "
                f"depth {quantity(sp.depth, 'mm', '.4f')}, {sp.profile}")
        if sp.location == "ball":
            out += ["", f"Pit on ball {sp.ball} (docs/model.md section 9)",
                    f"  spin angle from the outer contact {quantity(sp.center, 'deg', '.2f')}, {size}",
                    f"  impacts: once per ball turn on each raceway, 2 BSF = {v['two_bsf']:.3f} Hz in total "
                    f"(BSF {v['bsf']:.3f} Hz), modulated at FTF = {v['ftf']:.3f} Hz "
                    f"(lines 2 BSF +/- FTF: {v['two_bsf'] - v['ftf']:.3f}, {v['two_bsf'] + v['ftf']:.3f} Hz)"]
        elif sp.location == "inner":
            out += ["", "Spall on the inner raceway (turns with the inner ring, docs/model.md section 9)",
                    f"  centre at t = 0 {quantity(sp.center, 'deg', '.2f')}, {size}",
                    f"  impacts at BPFI = {v['bpfi']:.3f} Hz, modulated at the shaft frequency "
                    f"{v['shaft']:.3f} Hz (lines BPFI +/- f_r: {v['bpfi'] - v['shaft']:.3f}, "
                    f"{v['bpfi'] + v['shaft']:.3f} Hz)"]
        else:
            out += ["", "Spall on the outer raceway",
                    f"  centre {quantity(sp.center, 'deg', '.2f')}, {size}",
                    f"  impacts at BPFO = {v['bpfo']:.3f} Hz (and harmonics)"]
    return "\n".join(out)


def static_text(case, sol, assessment=None) -> str:
    """Per-ball table, ring displacement, cage speed and stiffness diagonal of a solution; with
    ``assessment`` (:func:`bearingsim.app.workflows.assess_case`) the limits and the life."""
    q = np.asarray(sol.displacement)
    K = np.asarray(sol.stiffness)
    lines = [f"{case.title}",
             f"converged in {int(sol.iterations)} iterations, ring residual {float(sol.residual_norm):.2e} N",
             "ring displacement: " + ", ".join(f"{name} {quantity(v, unit, '.4f' if unit == 'um' else '.5f')}"
                                               for (name, unit), v in zip(RING_DOFS, q)),
             tilt_text(sol),
             f"cage speed {quantity(sol.cage_speed, 'rpm', '.2f')}", ""]
    columns = (("azimuth", "deg"), ("alpha_inner", "deg"), ("alpha_outer", "deg"), ("Q_inner", "N"),
               ("Q_outer", "N"), ("delta_inner", "um"), ("delta_outer", "um"), ("centrifugal", "N"),
               ("gyroscopic_moment", "Nm"), ("p_max_inner", "MPa"), ("p_max_outer", "MPa"))
    values = [from_si(np.asarray(getattr(sol, name)), unit) for name, unit in columns]
    values[0] = np.mod(values[0], 360.0)
    rows = [(j, *(float(v[j]) for v in values)) for j in range(sol.azimuth.shape[0])]
    lines.append(table(("ball", "psi deg", "a_i deg", "a_o deg", "Q_i N", "Q_o N", "d_i um", "d_o um", "F_c N",
                        "M_g N m", "p_i MPa", "p_o MPa"), rows,
                       ("{}", "{:.2f}", "{:.3f}", "{:.3f}", "{:.1f}", "{:.1f}", "{:.3f}", "{:.3f}", "{:.2f}",
                        "{:.4f}", "{:.0f}", "{:.0f}")))
    lines += ["", stiffness_text(K)]
    if assessment is not None:
        lines.append(limits_text(assessment))
    return "\n".join(lines)


def tilt_text(sol) -> str:
    """One line: the state's tilt model (``JonesSolution.tilt``) and its moments (applied, or, for
    a held tilt, the moments that hold it)."""
    M = np.asarray(sol.loads)[3:5]
    if getattr(sol, "tilt", "free") == "held":
        return (f"tilt: held at 0 (operation.tilt = \"held\"); moments holding it Mx {M[0]:.4g} N m, "
                f"My {M[1]:.4g} N m; the held ring's stiffness is the x, y, axial block")
    return (f"tilt: free (operation.tilt = \"free\"): moments applied Mx {M[0]:.4g} N m, My {M[1]:.4g} N m, "
            "tilts solved")


def stiffness_text(K, what="stiffness diagonal") -> str:
    """The diagonal of a 5x5 stiffness dR/dq (SI) in the printouts' units (N/um, N m/mrad: the
    JSON's, :data:`bearingsim.output.io.UNITS_NOTE`), for a single bearing and a set alike."""
    K = np.asarray(K, float)
    t, r = (lambda v: from_si(float(v), "N_per_um")), (lambda v: from_si(float(v), "Nm_per_mrad"))
    return (f"{what}: k_x {t(K[0, 0]):.5g} N/um, k_y {t(K[1, 1]):.5g} N/um, k_axial {t(K[2, 2]):.5g} N/um, "
            f"k_tilt_x {r(K[3, 3]):.5g} N m/mrad, k_tilt_y {r(K[4, 4]):.5g} N m/mrad")


def limits_summary(limits) -> str:
    """One line: the limits a state breaks (flags P, S, T, X of :func:`limits_text`), or that all
    are within; the same line for a single bearing and each bearing of a set."""
    L = limits
    deg = lambda x: from_si(np.asarray(x), "deg")
    summary = []
    if bool(L.any_overpressure):
        summary.append(f"pressure above the limit (max {float(L.max_pressure_ratio):.3f} x)")
    if bool(L.any_slip):
        summary.append(f"raceway control needs {float(L.max_friction_ratio):.2f} x the available friction")
    if bool(L.any_over_shoulder):
        summary.append("a loaded contact centred over a shoulder edge (flag X: outside the model for that ball; "
                       "refused for a healthy bearing)")
    if bool(L.any_truncated):
        summary.append(f"contact ellipse truncated by a shoulder (by {-float(deg(L.min_edge_margin)):.2f} deg)")
    return "limits: " + ("; ".join(summary) if summary else "all within (max p/limit "
                                                            f"{float(L.max_pressure_ratio):.3f}, max mu need/available "
                                                            f"{float(L.max_friction_ratio):.3f}, min edge margin "
                                                            f"{float(deg(L.min_edge_margin)):.2f} deg)")


def limits_text(assessment) -> str:
    """Per-contact limits (pressure, friction raceway control needs, ellipse against the shoulders)
    and the ISO/TS 16281 life of an :class:`~bearingsim.app.workflows.Assessment`."""
    a = assessment
    L, st = a.limits, a.settings
    deg = lambda x: from_si(np.asarray(x), "deg")
    mu_av = float(st["friction_coefficient"])
    flags = lambda j: "".join(c for c, f in (("P", L.overpressure), ("S", L.slip), ("T", L.truncated),
                                               ("X", L.over_shoulder)) if bool(np.asarray(f)[j]))
    mu = np.maximum(np.asarray(L.friction_inner), np.asarray(L.friction_outer))
    rows = [(j, float(np.asarray(L.pressure_ratio_inner)[j]), float(np.asarray(L.pressure_ratio_outer)[j]), float(mu[j]),
             float(deg(L.edge_high_inner)[j]), float(deg(L.edge_low_inner)[j]), float(deg(L.edge_high_outer)[j]),
             float(deg(L.edge_low_outer)[j]), flags(j) or "-") for j in range(mu.shape[-1])]
    loaded_edges = lambda v: "-" if v >= 179.0 else f"{v:.2f}"
    lines = ["", f"Limits (docs/model.md section 11): p_max / {from_si(float(st['pressure_limit']), 'MPa'):.0f} MPa, friction "
             f"raceway control needs (available {mu_av:g}), contact ellipse to the shoulder edges "
             "(deg; negative: over the edge)",
             table(("ball", "p_i/lim", "p_o/lim", "mu need", "edge i hi", "edge i lo", "edge o hi", "edge o lo",
                    "flags"),
                   [(r[0], r[1], r[2], r[3], loaded_edges(r[4]), loaded_edges(r[5]), loaded_edges(r[6]),
                     loaded_edges(r[7]), r[8]) for r in rows],
                   ("{}", "{:.3f}", "{:.3f}", "{:.4f}", "{}", "{}", "{}", "{}", "{}")),
             "flags: P pressure above the limit, S raceway control needs more friction than available "
             "(the ball slips), T ellipse truncated by a shoulder, X contact centre over a shoulder edge"]
    lines.append(limits_summary(L))
    if st["dynamic_load_rating"] is not None:
        C = from_si(float(st["dynamic_load_rating"]), "kN")
        if a.rating_life is None:
            lines.append(f"life (ISO/TS 16281, C = {C:g} kN): not computed (a defect: the rating life is a "
                         "healthy bearing's; or no loaded contact)")
        else:
            rings = ", ".join(f"{n} ring {v:.4g}" if v is not None else f"{n} ring unloaded"
                              for n, v in zip(("inner", "outer"), a.ring_lives))
            hours = f", {a.life_hours:.4g} h at the case's speed" if a.life_hours is not None else \
                " (standstill: no hours)"
            lines.append(f"life (ISO/TS 16281, C = {C:g} kN, nominal angle {from_si(a.nominal_angle, 'deg'):.1f} deg): "
                         f"L10r = {a.rating_life:.4g} million revolutions ({rings}){hours}")
    return "\n".join(lines)


def study_text(case, study) -> str:
    """Extremes of loads and contact angles per study value."""
    sol = study.solution
    Qo, Qi = np.asarray(sol.Q_outer), np.asarray(sol.Q_inner)
    ai, ao = from_si(np.asarray(sol.alpha_inner), "deg"), from_si(np.asarray(sol.alpha_outer), "deg")
    rows = [(v, Qi[m].max(), Qo[m].max(), ai[m].min(), ai[m].max(), ao[m].min(), ao[m].max())
            for m, v in enumerate(study.values)]
    how = "one batch" if study.batched else "one sweep per value"
    return (f"{case.title}: study of {study.parameter} over {study.values} ({how})\n"
            + table((study.parameter, "max Q_i N", "max Q_o N", "min a_i", "max a_i", "min a_o", "max a_o"),
                    rows, ("{:g}", "{:.1f}", "{:.1f}", "{:.2f}", "{:.2f}", "{:.2f}", "{:.2f}")))


def compare_text(case, comparison) -> str:
    """Peaks of the quasi-static sweep and of the dynamic run, with the amplification."""
    bad = int(np.sum(failed(np.asarray(comparison.quasi_static.result))))
    head = (f"{case.title}: quasi-static sweep at {len(comparison.indices)} cage angles of the dynamic run "
            f"({float(comparison.dynamic.time[-1]):.4f} s){'; %d angles did not converge' % bad if bad else ''}")
    return head + "\n" + table(("quantity", "unit", "quasi-static", "dynamic", "dynamic / static"), comparison.rows,
                               ("{}", "{}", "{:.3f}", "{:.3f}", "{:.3f}"))


def spectrum_text(analysis) -> str:
    """Sampling, band, the envelope peak near the defect's line (BPFO, BPFI, 2 BSF) and its
    harmonics."""
    a = analysis
    f0, name = a.fault_hz, a.fault
    rows = [(k, k * f0, fk, ak, (fk - k * f0) / (k * f0) * 100) for k, fk, ak in a.harmonics]
    return "\n".join([
        f"{a.source}: {a.samples} samples at {a.sample_rate:.0f} Hz ({a.duration:.4f} s), "
        f"band {a.band[0]:.0f}-{a.band[1]:.0f} Hz, resolution {a.spectrum.resolution:.3f} Hz",
        f"envelope peak near {name}: {a.peak:.4f} Hz; reported {name} {f0:.4f} Hz; "
        f"relative difference {(a.peak - f0) / f0 * 100:+.4f} %",
        table(("k", f"k x {name} Hz", "measured Hz", "amplitude (m/s^2)^2", "diff %"), rows,
              ("{}", "{:.3f}", "{:.3f}", "{:.4g}", "{:+.4f}"))])


def _record_part(cal) -> str:
    """The record's length and rate, and the part the machine fits analysed when it was cut
    (at most background_fit.MAX_ANALYSIS_SAMPLES samples)."""
    whole = getattr(cal, "record_s", None)
    if whole is None or whole <= cal.duration_s * (1 + 1e-9):
        return f"{cal.duration_s:.2f} s at {cal.sample_rate_Hz:g} Hz"
    return (f"{whole:.2f} s at {cal.sample_rate_Hz:g} Hz, the first {cal.duration_s:.2f} s analysed (at most "
            f"{round(cal.duration_s * cal.sample_rate_Hz)} samples: the memory stays bounded)")


def calibration_text(cal, output=None) -> str:
    """What ``bearingsim calibrate`` fitted (bearingsim.realism.machine.MachineCalibration)."""
    bg = cal.background
    mm = lambda v: ", ".join(f"{a:.4g}" for a in v) or "-"
    lines = [f"{cal.case.title}",
             f"record: {_record_part(cal)}; shaft {60 * cal.shaft_hz:.1f} rpm "
             f"({cal.shaft_hz:.3f} Hz, {cal.shaft_source})",
             f"shaft lines k = 1..{len(bg.shaft_amplitudes)}: {mm(bg.shaft_amplitudes)} m/s^2",
             (f"supply {bg.line_frequency:g} Hz ({cal.line_excess_db:.1f} dB over the floor), lines: "
              f"{mm(bg.line_amplitudes)} m/s^2") if cal.line_detected else
             "supply lines: none told apart from the shaft's (kept in them)",
             f"broadband: rms {bg.noise_rms:.4g} m/s^2, shape at {len(bg.psd_frequencies)} frequencies "
             f"{bg.psd_frequencies[0]:.0f}-{bg.psd_frequencies[-1]:.0f} Hz, shaft-rate modulation "
             f"{mm(bg.modulation_depths)}",
             f"knocks: {bg.knock_rate:.3g} per s, peak {bg.knock_amplitude:.3g} m/s^2" if bg.knock_rate > 0
             else "knocks: none",
             "resonances: " + ("; ".join(f"{f:.0f} Hz, damping {z:.4f} ({p:.1f} dB)" for f, z, p in cal.resonances)
                               or "none found (the template's transfer path kept)")]
    if cal.resonance_range_Hz:
        lines.append(f"dataset.resonance_frequency_Hz = [{cal.resonance_range_Hz[0]:g}, {cal.resonance_range_Hz[1]:g}], "
                     f"resonance_damping_ratio = [{cal.damping_range[0]:g}, {cal.damping_range[1]:g}]")
    if cal.signal_gain is not None:
        f = cal.fault
        lines.append(f"signal gain {cal.signal_gain:.4g} from the {f['class']} record (rms {f['rms_m_s2']:.4g}, "
                     f"{f['excess_rms_m_s2']:.4g} m/s^2 above the healthy; {f['items']} simulated items "
                     f"{f['simulated_rms_m_s2']:.4g} m/s^2 at gain 1): dataset.signal_gain = "
                     f"[{cal.signal_gain_range[0]:g}, {cal.signal_gain_range[1]:g}]")
    else:
        lines.append(f"dataset.signal_gain = [{cal.signal_gain_range[0]:g}, {cal.signal_gain_range[1]:g}] "
                     "(the template's: no fault record)")
    return "\n".join(lines)


def record_spectrum_text(rs) -> str:
    """A record's sampling, shaft speed, band, the strength of each fault line over the envelope
    spectrum's local floor and its detection verdict at the stated false-alarm rate
    (bearingsim.realism.record_spectrum.RecordSpectrum)."""
    v = rs.verdicts
    rows = [(k, f0, v[k].peak_hz, v[k].strength_db, v[k].threshold_db, v[k].verdict + (f" ({v[k].note})" if v[k].note
                                                                                    else ""))
            for k, f0 in rs.lines.items()]
    found = [k for k in rs.lines if v[k].detected]
    out = [f"{rs.source}{f' channel {rs.channel}' if rs.channel else ''}: {rs.samples} samples at "
           f"{rs.sample_rate:g} Hz ({rs.samples / rs.sample_rate:.3f} s; sample rate from {rs.rate_source}), "
           f"unit {rs.unit}",
           f"bearing: {rs.case_title}; shaft {60 * rs.shaft_hz:.1f} rpm ({rs.shaft_hz:.3f} Hz, {rs.shaft_source})",
           f"squared-envelope spectrum in the band of largest envelope kurtosis "
           f"{rs.band[0]:.0f}-{rs.band[1]:.0f} Hz, resolution {rs.envelope.resolution:.3f} Hz",
           table(("line", "expected Hz", "peak Hz", "dB over floor", "threshold dB", "verdict"), rows,
                 ("{}", "{:.3f}", "{:.3f}", "{:.1f}", "{:.1f}", "{}")),
           ("fault lines detected: " + ", ".join(found)) if found else "no fault line detected",
           f"(dB over the local floor: the median of the envelope spectrum within 6 x the line's search window; "
           f"{rs.threshold_note})"]
    if rs.overlay is not None:
        ov = rs.overlay
        out.append(f"overlay: {ov.source} at {ov.sample_rate:g} Hz, band {ov.band[0]:.0f}-{ov.band[1]:.0f} Hz"
                   + (f", shaft {60 * ov.shaft_hz:.1f} rpm" if ov.shaft_hz else ""))
    return "\n".join(out)
