"""Command line: ``bearingsim info|static|sweep|study|simulate|spectrum|dataset|demo``.

Engineering units with the unit in every name; SI inside.  Exit codes: 0 success, 2 bad input,
3 a solve did not converge, 4 an output could not be written.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from .errors import BearingsimError, InputError, NotConvergedError, OutputError

RAD2DEG = 180.0 / np.pi


def _load(path):
    from .case import load_case

    p = Path(path)
    if not p.is_file():
        raise InputError(f"{path}: no such case file")
    return load_case(p)


def _fmt_table(headers, rows, fmts):
    cols = [[h] + [f.format(r[i]) for r in rows] for i, (h, f) in enumerate(zip(headers, fmts))]
    w = [max(len(c) for c in col) for col in cols]
    lines = ["  ".join(c[0].rjust(wi) for c, wi in zip(cols, w))]
    lines.append("  ".join("-" * wi for wi in w))
    for k in range(len(rows)):
        lines.append("  ".join(c[k + 1].rjust(wi) for c, wi in zip(cols, w)))
    return "\n".join(lines)


# ------------------------------------------------------------------------------------ info
def info_text(case) -> str:
    import bearingsim as bs

    b = case.bearing()
    op = case.operation()
    a0 = float(b.free_contact_angle)
    out = [f"{case.title}", "=" * len(case.title), "", "Geometry"]
    rows = [
        ("balls Z", f"{b.n_balls}"),
        ("ball diameter D", f"{float(b.ball_diameter)*1e3:.4f} mm"),
        ("pitch diameter d_m", f"{float(b.pitch_diameter)*1e3:.4f} mm"),
        ("groove curvature f_i / f_o", f"{float(b.f_inner):.4f} / {float(b.f_outer):.4f}"),
        ("total conformity B", f"{float(b.B):.4f}"),
        ("groove-centre distance A = BD", f"{float(b.A)*1e3:.4f} mm"),
        ("free contact angle alpha_0", f"{a0*RAD2DEG:.3f} deg"),
        ("diametral clearance P_d", f"{float(b.diametral_clearance)*1e3:.4f} mm"),
        ("inner groove-centre radius R_i", f"{float(b.inner_groove_radius)*1e3:.4f} mm"),
        ("outer raceway radius R_o", f"{float(b.outer_raceway_radius)*1e3:.4f} mm"),
        ("ball mass m / inertia J", f"{float(b.ball_mass)*1e3:.3f} g / {float(b.ball_inertia):.4e} kg m^2"),
        ("effective modulus E'", f"{float(b.effective_modulus)/1e9:.2f} GPa"),
    ]
    out += [f"  {k:<32} {v}" for k, v in rows]
    out += ["", f"Hertz point contact at alpha_0 ({case.hertz_method})"]
    hdr = ("contact", "sum_rho (1/mm)", "F(rho)", "kappa", "K(e)", "E(e)", "K (N/mm^1.5)")
    trs = []
    for name, inner in (("inner", True), ("outer", False)):
        c = bs.hertz_contact(b, a0, inner, case.hertz_method)
        trs.append((name, float(c.sum_rho) / 1e3, float(c.F_rho), float(c.kappa), float(c.K_ell),
                    float(c.E_ell), float(c.K) / 1e3 ** 1.5))
    out.append(_fmt_table(hdr, trs, ("{}", "{:.5f}", "{:.5f}", "{:.4f}", "{:.5f}", "{:.5f}", "{:.5g}")))
    n = float(op.speed_rpm)
    kin = bs.ball_kinematics(b, op, a0, a0)
    out += ["", f"Kinematics at alpha_0, {n:.1f} rpm, {op.control} raceway control"]
    out += [f"  {'orbital (cage) speed':<32} {float(kin.orbital_speed)*60/(2*np.pi):.2f} rpm",
            f"  {'ball spin speed':<32} {float(kin.spin_speed)*60/(2*np.pi):.2f} rpm",
            f"  {'spin-axis pitch beta':<32} {float(kin.beta)*RAD2DEG:.3f} deg",
            f"  {'centrifugal force F_c':<32} {float(kin.centrifugal):.3f} N",
            f"  {'gyroscopic moment M_g':<32} {float(kin.gyroscopic):.5f} N m"]
    f = bs.defect_frequencies(b, n / 60.0, a0)
    out += ["", f"Defect frequencies at alpha_0 (shaft {n/60:.3f} Hz); BSF once per ball revolution"]
    for name, v in (("FTF", f.ftf), ("BPFO", f.bpfo), ("BPFI", f.bpfi), ("BSF", f.bsf), ("2 BSF", f.two_bsf)):
        mult = float(v) / (n / 60.0) if n > 0 else float(bs.defect_frequencies(b, 1.0, a0)._asdict()[
            {"FTF": "ftf", "BPFO": "bpfo", "BPFI": "bpfi", "BSF": "bsf", "2 BSF": "two_bsf"}[name]])
        out.append(f"  {name:<6} {float(v):10.3f} Hz   {mult:.5f} x shaft")
    sp = case.spall()
    if sp is not None:
        out += ["", "Spall on the outer raceway",
                f"  centre {float(sp.center)*RAD2DEG:.2f} deg, extent {float(sp.extent)*RAD2DEG:.3f} deg "
                f"(arc {float(sp.length(b))*1e3:.3f} mm), depth {float(sp.depth)*1e3:.3f} mm, {sp.profile}"]
    return "\n".join(out)


def cmd_info(args):
    case = _load(args.case)
    print(info_text(case))
    return 0


# ------------------------------------------------------------------------------------ static
def solve_case(case, throw=True):
    import bearingsim as bs

    return bs.solve(case.bearing(), case.operation(), case.loads(), cage_angle=case.cage_angle,
                    spall=case.spall(), hertz_method=case.hertz_method, throw=throw)


def static_text(case, sol) -> str:
    q = np.asarray(sol.displacement)
    K = np.asarray(sol.stiffness)
    lines = [f"{case.title}",
             f"converged in {int(sol.iterations)} iterations, ring residual {float(sol.residual_norm):.2e} N",
             f"ring displacement: x {q[0]*1e6:.4f} um, y {q[1]*1e6:.4f} um, axial {q[2]*1e6:.4f} um, "
             f"tilt_x {q[3]*1e3:.5f} mrad, tilt_y {q[4]*1e3:.5f} mrad",
             f"cage speed {float(sol.cage_speed)*60/(2*np.pi):.2f} rpm", ""]
    hdr = ("ball", "psi deg", "a_i deg", "a_o deg", "Q_i N", "Q_o N", "d_i um", "d_o um", "F_c N",
           "M_g N m", "p_i MPa", "p_o MPa")
    rows = []
    for j in range(len(q) and sol.azimuth.shape[0]):
        rows.append((j, float(np.mod(sol.azimuth[j], 2 * np.pi)) * RAD2DEG, float(sol.alpha_inner[j]) * RAD2DEG,
                     float(sol.alpha_outer[j]) * RAD2DEG, float(sol.Q_inner[j]), float(sol.Q_outer[j]),
                     float(sol.delta_inner[j]) * 1e6, float(sol.delta_outer[j]) * 1e6,
                     float(sol.centrifugal[j]), float(sol.gyroscopic_moment[j]),
                     float(sol.p_max_inner[j]) * 1e-6, float(sol.p_max_outer[j]) * 1e-6))
    lines.append(_fmt_table(hdr, rows, ("{}", "{:.2f}", "{:.3f}", "{:.3f}", "{:.1f}", "{:.1f}", "{:.3f}",
                                        "{:.3f}", "{:.2f}", "{:.4f}", "{:.0f}", "{:.0f}")))
    lines += ["", "stiffness diagonal: "
              f"k_x {K[0,0]:.4e} N/m, k_y {K[1,1]:.4e} N/m, k_axial {K[2,2]:.4e} N/m, "
              f"k_tilt_x {K[3,3]:.4e} N m/rad, k_tilt_y {K[4,4]:.4e} N m/rad"]
    return "\n".join(lines)


def cmd_static(args):
    import bearingsim as bs
    from . import io

    case = _load(args.case)
    sol = solve_case(case, throw=False)
    if int(sol.result) != 0:
        raise NotConvergedError(
            f"{args.case}: the quasi-static solve did not converge: {sol.message()[0]} "
            f"(ring residual {float(sol.residual_norm):.3g} N after {int(sol.iterations)} iterations)",
            hint="check that the bearing can carry these loads (an angular contact bearing needs "
                 "axial load in its contact direction), or lower the speed.")
    print(static_text(case, sol))
    if args.json:
        io.write_json(args.json, io.static_to_dict(sol))
        print(f"\nwrote {args.json}")
    if args.plot:
        from .plots import plot_static

        Path(args.plot).parent.mkdir(parents=True, exist_ok=True)
        plot_static(sol, title=case.title, spall=case.spall(), path=args.plot)
        print(f"wrote {args.plot}")
    return 0



# ------------------------------------------------------------------------------------ sweep
def _progress(total, desc):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="angle", disable=None, dynamic_ncols=True)


def run_sweep(case, progress=True, resolve_edges=True):
    from .sweep import sweep_angles, sweep_chunked

    b, op, loads, spall = case.bearing(), case.operation(), case.loads(), case.spall()
    st = case.sweep_settings()
    angles = sweep_angles(b, spall, st["start"], st["stop"], st["steps"], resolve_edges)
    bar = _progress(len(angles), "sweep") if progress else None
    try:
        sol = sweep_chunked(b, op, loads, spall, angles, chunk=max(32, min(256, len(angles))),
                            progress=None if bar is None else bar.update,
                            hertz_method=case.hertz_method)
    finally:
        if bar is not None:
            bar.close()
    return sol


def _report_failures(result, what):
    bad = int(np.sum(np.asarray(result) != 0))
    if bad:
        print(f"bearingsim: warning: {bad} of {np.asarray(result).size} {what} did not converge; they are "
              "flagged in 'converged' (values set to 0)", file=sys.stderr)
    return bad


def cmd_sweep(args):
    from . import io

    case = _load(args.case)
    sol = run_sweep(case)
    _report_failures(sol.result, "cage angles")
    groups = {"sweep": io.state_datasets(sol)}
    io.write_h5(args.output, groups, attrs={"case_toml": case.text, "title": case.title})
    th = np.asarray(sol.cage_angle) * RAD2DEG
    Qo = np.asarray(sol.Q_outer)
    print(f"{case.title}: {len(th)} cage angles from {th[0]:.3f} to {th[-1]:.3f} deg, "
          f"max Q_o {Qo.max():.1f} N, min Q_o {Qo.min():.1f} N")
    print(f"wrote {args.output}")
    if args.plot:
        from .plots import plot_sweep

        d = Path(args.plot)
        d.mkdir(parents=True, exist_ok=True)
        plot_sweep(sol, title=case.title, spall=case.spall(), path=d / "sweep.png")
        print(f"wrote {d / 'sweep.png'}")
    return 0


# ------------------------------------------------------------------------------------ study
def run_study(case, progress=True):
    import jax
    import jax.numpy as jnp

    from .sweep import sweep

    spec = case.study_settings()
    if spec is None:
        raise InputError(f"{case.source}: no [study] section: add one, e.g.\n[study]\n"
                       'parameter = "operation.speed_rpm"\nvalues = [0, 5000, 10000]')
    param, values = spec
    if param == "bearing.balls":
        raise InputError(f"{case.source}: study.parameter = 'bearing.balls' changes the number of balls "
                       "and so the shape of every result; run one sweep per ball count instead")
    from tqdm import tqdm

    sols = []
    for v in tqdm(values, desc=f"study {param}", unit="value", disable=None if progress else True):
        c = case.with_value(param, v)
        b, op, loads, spall = c.bearing(), c.operation(), c.loads(), c.spall()
        st = c.sweep_settings()
        # one uniform grid for every value, so the study is one rectangular array
        sols.append(sweep(b, op, loads, spall, start=st["start"], stop=st["stop"], steps=st["steps"],
                          resolve_edges=False, hertz_method=c.hertz_method))
    stacked = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *sols)
    return param, list(values), stacked


def _unit_of(param):
    last = param.split(".")[-1]
    for suffix in ("_rpm", "_deg", "_mm", "_N", "_Nm", "_GPa", "_kg_m3", "_s", "_Hz"):
        if last.endswith(suffix):
            return suffix[1:]
    return ""


def cmd_study(args):
    from . import io

    case = _load(args.case)
    param, values, sol = run_study(case)
    _report_failures(sol.result, "study states")
    ds = io.state_datasets(sol)
    unit = _unit_of(param)
    ds["values"] = (np.asarray(values, dtype=float), unit or "1")
    ds["@attrs"] = {"parameter": param}
    io.write_h5(args.output, {"study": ds}, attrs={"case_toml": case.text, "title": case.title})
    print(f"{case.title}: study of {param} over {values}")
    Qo = np.asarray(sol.Q_outer)
    Qi = np.asarray(sol.Q_inner)
    ai, ao = np.asarray(sol.alpha_inner) * RAD2DEG, np.asarray(sol.alpha_outer) * RAD2DEG
    rows = [(v, Qi[m].max(), Qo[m].max(), ai[m].min(), ai[m].max(), ao[m].min(), ao[m].max())
            for m, v in enumerate(values)]
    print(_fmt_table((param, "max Q_i N", "max Q_o N", "min a_i", "max a_i", "min a_o", "max a_o"), rows,
                     ("{:g}", "{:.1f}", "{:.1f}", "{:.2f}", "{:.2f}", "{:.2f}", "{:.2f}")))
    print(f"wrote {args.output}")
    if args.plot:
        from .plots import plot_study

        d = Path(args.plot)
        d.mkdir(parents=True, exist_ok=True)
        name = "study_" + param.replace(".", "_") + ".png"
        plot_study(sol, values, param, unit, title=case.title, spall=case.spall(), path=d / name)
        print(f"wrote {d / name}")
    return 0


# ------------------------------------------------------------------------------------ simulate
def simulate_datasets(res, Z):
    """The fixed /dynamics layout of ``bearingsim simulate`` (SI)."""
    fr = res.frequencies
    attrs = dict(fr)
    attrs.update(
        contact_angle_rad=float(res.contact_angle),
        frequency_note=("ftf = quasi-static cage speed / 2 pi, bpfo = Z ftf; bpfi and bsf (once per "
                        "ball revolution) from MODEL.md section 8 at the mean loaded contact angle "
                        "contact_angle_rad"),
        result=int(res.result), num_steps=int(res.num_steps), balls=int(Z),
        ball_iterations=int(res.ball_iterations),
        contact_damping_Ns_per_m=np.asarray(res.contact_damping))
    return {
        "time": (np.asarray(res.time), "s"),
        "cage_angle": (np.asarray(res.cage_angle), "rad"),
        "ring_displacement": (np.asarray(res.ring_displacement), "m (shaft relative to housing: x, y, axial)"),
        "housing_displacement": (np.asarray(res.housing_displacement), "m (x, y)"),
        "housing_acceleration": (np.asarray(res.housing_acceleration), "m/s^2 (x, y)"),
        "sensor_acceleration": (np.asarray(res.sensor_acceleration), "m/s^2"),
        "Q_inner": (np.asarray(res.Q_inner), "N"),
        "Q_outer": (np.asarray(res.Q_outer), "N"),
        "alpha_inner": (np.asarray(res.alpha_inner), "rad"),
        "alpha_outer": (np.asarray(res.alpha_outer), "rad"),
        "spall_edge_times": (np.asarray(res.jump_times, float), "s"),
        "spall_pass_times": (np.asarray(res.pass_times, float), "s"),
        "@attrs": attrs,
    }


def _band(fs, f_n):
    from .signal import select_band

    return select_band(np.zeros(16), fs, resonance_hz=min(f_n, 0.45 * fs))


def plot_simulation(res, case, d, outdir):
    import matplotlib.pyplot as plt

    from .plots_signal import plot_envelope_spectrum, plot_time_history
    from .signal import envelope_spectrum

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    t = np.asarray(res.time)
    a = np.asarray(res.sensor_acceleration)
    passes = np.asarray(res.pass_times)
    written = []
    p = outdir / "sensor_acceleration.png"
    plt.close(plot_time_history(t, a, marks=passes, title=f"{case.title}: sensor acceleration", path=p))
    written.append(p)
    if passes.size:
        bpfo = res.frequencies["bpfo_Hz"]
        t0 = max(float(t[0]), float(passes[0]) - 0.5 / bpfo)
        t1 = min(float(t[-1]), t0 + 3.0 / bpfo)
        p = outdir / "sensor_acceleration_zoom.png"
        plt.close(plot_time_history(t, a, marks=passes, zoom=(t0, t1),
                                    title=f"{case.title}: sensor acceleration (3 spall passes)", path=p))
        written.append(p)
    Qo = np.asarray(res.Q_outer)
    fig, ax = plt.subplots(figsize=(10, 4), constrained_layout=True)
    H = np.asarray(res.Q_outer)
    sp = case.spall()
    if sp is not None:
        from .defect import depth_profile
        import jax.numpy as jnp
        psi = np.asarray(res.cage_angle)[:, None] + 2 * np.pi * np.arange(Qo.shape[1]) / Qo.shape[1]
        inside = np.asarray(depth_profile(case.bearing(), sp, jnp.asarray(psi))) > 0
        balls = np.flatnonzero(inside.any(axis=0))
    else:
        balls = np.argsort(-Qo.max(axis=0))[:3]
    for j in (balls if balls.size else range(Qo.shape[1])):
        ax.plot(t * 1e3, H[:, j], lw=0.8, label=f"ball {j}")
    for tm in passes[:30]:
        ax.axvline(tm * 1e3, color="#d62728", ls=":", lw=0.8)
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("outer contact load Q_o (N)")
    ax.set_title(f"{case.title}: outer loads of the balls that pass the spall")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=4)
    p = outdir / "ball_loads.png"
    fig.savefig(p, dpi=120)
    plt.close(fig)
    written.append(p)
    fs = float(d["sample_rate"])
    if t.size > 64:
        band = _band(fs, d["resonance_frequency"])
        es = envelope_spectrum(a, fs, band=band)
        fr = res.frequencies
        p = outdir / "envelope_spectrum.png"
        plt.close(plot_envelope_spectrum(es, {"BPFO": fr["bpfo_Hz"], "FTF": fr["ftf_Hz"],
                                              "shaft": fr["shaft_Hz"]},
                                         title=f"{case.title}: squared-envelope spectrum", path=p,
                                         fmax=5.5 * fr["bpfo_Hz"]))
        written.append(p)
    return written


def cmd_simulate(args):
    from . import io
    from .dynamics import RESULT_MESSAGES, simulate_case

    case = _load(args.case)
    d = case.dynamics_settings()
    res = simulate_case(case, throw=False)
    if res.result != 0:
        raise NotConvergedError(f"{args.case}: the dynamic simulation failed: {RESULT_MESSAGES[res.result]} "
                                f"after {res.num_steps} steps",
                                hint="loosen [dynamics] rtol/atol or check the structural parameters.")
    Z = case.bearing().n_balls
    io.write_h5(args.output, {"dynamics": simulate_datasets(res, Z)},
                attrs={"case_toml": case.text, "title": case.title})
    fr = res.frequencies
    a = np.asarray(res.sensor_acceleration)
    print(f"{case.title}: {float(res.time[-1]):.4f} s simulated in {res.num_steps} steps "
          f"({res.ball_iterations or 'exact'} ball Newton steps), sensor rms {a.std():.4g} m/s^2, "
          f"{len(res.pass_times)} spall passes")
    print("  ".join(f"{k[:-3]} {v:.4f} Hz" for k, v in fr.items()))
    print(f"wrote {args.output}")
    if args.plot:
        for p in plot_simulation(res, case, d, args.plot):
            print(f"wrote {p}")
    return 0


def cmd_spectrum(args):
    import h5py

    from .case import parse_case
    from .signal import envelope_spectrum, harmonic_peaks, peak_frequency

    try:
        with h5py.File(args.input, "r") as f:
            g = f["dynamics"]
            t = g["time"][()]
            a = g["sensor_acceleration"][()]
            fr = {k: float(g.attrs[k]) for k in ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz")}
            toml = f.attrs.get("case_toml", "")
    except (OSError, KeyError) as e:
        raise InputError(f"{args.input}: not a bearingsim simulate output ({e})")
    fs = 1.0 / float(t[1] - t[0])
    f_n = 3000.0
    if toml:
        try:
            f_n = parse_case(toml).dynamics_settings()["resonance_frequency"]
        except Exception:
            pass
    band = _band(fs, f_n)
    es = envelope_spectrum(a, fs, band=band)
    bpfo = fr["bpfo_Hz"]
    try:
        fp = peak_frequency(es, bpfo, rel_window=0.05)
    except ValueError as e:
        raise NotConvergedError(f"{args.input}: no envelope peak near BPFO {bpfo:.3f} Hz: {e}")
    print(f"{args.input}: {t.size} samples at {fs:.0f} Hz ({t[-1] - t[0] + 1 / fs:.4f} s), "
          f"band {band[0]:.0f}-{band[1]:.0f} Hz, resolution {es.resolution:.3f} Hz")
    print(f"envelope peak near BPFO: {fp:.4f} Hz; reported bpfo_Hz {bpfo:.4f} Hz; "
          f"relative difference {(fp - bpfo) / bpfo * 100:+.4f} %")
    rows = [(k, k * bpfo, fk, ak, (fk - k * bpfo) / (k * bpfo) * 100)
            for k, fk, ak in harmonic_peaks(es, bpfo, n=5, rel_window=0.03)]
    print(_fmt_table(("k", "k x bpfo Hz", "measured Hz", "amplitude (m/s^2)^2", "diff %"), rows,
                     ("{}", "{:.3f}", "{:.3f}", "{:.4g}", "{:+.4f}")))
    if args.plot:
        from .plots_signal import plot_envelope_spectrum
        import matplotlib.pyplot as plt

        Path(args.plot).parent.mkdir(parents=True, exist_ok=True)
        plt.close(plot_envelope_spectrum(es, {"BPFO": bpfo, "FTF": fr["ftf_Hz"], "shaft": fr["shaft_Hz"]},
                                         title=f"{args.input}: squared-envelope spectrum",
                                         fmax=5.5 * bpfo, path=args.plot))
        print(f"wrote {args.plot}")
    return 0


# ------------------------------------------------------------------------------------ dataset
def cmd_dataset(args):
    from .dataset import make_dataset, result_messages

    case = _load(args.spec)
    s = make_dataset(case, args.output, progress=True)
    print(f"{case.title}: {s.count} items x {s.samples} samples in {s.seconds:.1f} s "
          f"({s.seconds_per_item:.3f} s per item, compilation included)")
    if s.failed:
        import h5py

        with h5py.File(args.output, "r") as f:
            codes = f["labels"]["result"]
        msgs = result_messages()
        detail = ", ".join(f"{int(np.sum(codes == c))} {msgs.get(int(c), c)}"
                           for c in np.unique(codes[codes != 0]))
        print(f"bearingsim: warning: {s.failed} of {s.count} items failed ({detail}); their "
              "signals are zero and labels/result != 0", file=sys.stderr)
    else:
        print("all items simulated successfully")
    print(f"wrote {args.output}")
    return 0


# ------------------------------------------------------------------------------------ compare
def compare_static_dynamic(case, max_angles=721):
    """Quasi-static sweep at the cage angles of a dynamic run (subsampled to ``max_angles``).

    Returns (dynamics result, indices of the compared samples, sweep solution, table rows) where
    each row is (quantity, unit, quasi-static peak, dynamic peak, dynamic / quasi-static)."""
    from .dynamics import simulate_case
    from .sweep import sweep

    res = simulate_case(case, throw=False)
    if res.result != 0:
        raise NotConvergedError(f"{case.source}: the dynamic simulation failed (result {res.result})")
    th = np.asarray(res.cage_angle)
    idx = np.unique(np.linspace(0, len(th) - 1, min(len(th), max_angles)).astype(int))
    qs = sweep(case.bearing(), case.operation(), case.loads(), case.spall(), angles=th[idx],
               hertz_method=case.hertz_method)
    rows = []

    def ratio(d, s, tol):        # amplification only where the static value is not ~0
        return d / s if abs(s) > tol else np.nan

    for name, unit, f, tol in (("Q_outer", "N", 1.0, 1e-6), ("Q_inner", "N", 1.0, 1e-6),
                               ("alpha_outer", "deg", RAD2DEG, 1e-3), ("alpha_inner", "deg", RAD2DEG, 1e-3)):
        d = np.asarray(getattr(res, name))[idx] * f
        s = np.asarray(getattr(qs, name)) * f
        rows.append((f"max {name}", unit, s.max(), d.max(), ratio(d.max(), s.max(), tol)))
        if name.startswith("alpha"):
            rows.append((f"min {name}", unit, s.min(), d.min(), ratio(d.min(), s.min(), tol)))
    qd = np.asarray(res.ring_displacement)[idx] * 1e6
    qq = np.asarray(qs.displacement)[:, :3] * 1e6
    for j, lab in enumerate(("x", "y", "axial")):
        amp_s, amp_d = np.ptp(qq[:, j]), np.ptp(qd[:, j])
        rows.append((f"peak-to-peak ring {lab}", "um", amp_s, amp_d, ratio(amp_d, amp_s, 1e-6)))
    return res, idx, qs, rows


def cmd_compare(args):
    case = _load(args.case)
    if case.data.get("dynamics") is None:
        raise InputError(f"{args.case}: compare needs a [dynamics] section (duration_s, sample_rate_Hz)")
    res, idx, qs, rows = compare_static_dynamic(case)
    bad = int(np.sum(np.asarray(qs.result) != 0))
    print(f"{case.title}: quasi-static sweep at {len(idx)} cage angles of the dynamic run "
          f"({float(res.time[-1]):.4f} s){'; %d angles did not converge' % bad if bad else ''}")
    print(_fmt_table(("quantity", "unit", "quasi-static", "dynamic", "dynamic / static"), rows,
                     ("{}", "{}", "{:.3f}", "{:.3f}", "{:.3f}")))
    if args.plot:
        import matplotlib.pyplot as plt

        d = Path(args.plot)
        d.mkdir(parents=True, exist_ok=True)
        th = np.unwrap(np.asarray(res.cage_angle)) * RAD2DEG
        Qo = np.asarray(res.Q_outer)
        j = int(np.argmax(np.ptp(Qo[idx], axis=0)))
        fig, axes = plt.subplots(2, 2, figsize=(13, 7.5), constrained_layout=True)
        for ax, (name, lab, f) in zip(axes.ravel()[:3], (("Q_outer", "$Q_o$ (N)", 1.0), ("Q_inner", "$Q_i$ (N)", 1.0),
                                                          ("alpha_outer", r"$\alpha_o$ (deg)", RAD2DEG))):
            ax.plot(th, np.asarray(getattr(res, name))[:, j] * f, lw=0.9, label=f"dynamic, ball {j}")
            ax.plot(th[idx], np.asarray(getattr(qs, name))[:, j] * f, ".", ms=3, label="quasi-static sweep")
            ax.set_xlabel("cage angle θ_c (deg)")
            ax.set_ylabel(lab)
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8)
        ax = axes[1, 1]
        qd = np.asarray(res.ring_displacement) * 1e6
        for k, lab in enumerate(("x", "y", "axial")):
            line, = ax.plot(th, qd[:, k], lw=0.9, label=f"{lab} dynamic")
            ax.plot(th[idx], np.asarray(qs.displacement)[:, k] * 1e6, ".", ms=3, color=line.get_color(),
                    label=f"{lab} quasi-static")
        ax.set_xlabel("cage angle θ_c (deg)")
        ax.set_ylabel("ring displacement (µm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
        fig.suptitle(f"{case.title}: static vs swept vs dynamic")
        fig.savefig(d / "compare.png", dpi=120)
        plt.close(fig)
        print(f"wrote {d / 'compare.png'}")
    return 0


# ------------------------------------------------------------------------------------ demo
DEFAULT_CASE = Path(__file__).resolve().parent.parent / "cases" / "demo.toml"


def cmd_demo(args):
    import time

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    case_path = Path(args.case) if args.case else DEFAULT_CASE
    case = _load(case_path)
    t0 = time.time()
    print(f"bearingsim demo: {case_path}\n")
    print(info_text(case), "\n")
    print("[1/4] quasi-static solve (compiles once, ~10 s)")
    cmd_static(argparse.Namespace(case=str(case_path), json=str(out / "static.json"),
                                  plot=str(out / "static.png")))
    print("\n[2/4] cage-angle sweep past the spall")
    cmd_sweep(argparse.Namespace(case=str(case_path), output=str(out / "sweep.h5"), plot=str(out)))
    if case.data.get("dynamics") is not None and case.spall() is not None:
        print("\n[3/4] dynamic simulation past the spall")
        cmd_simulate(argparse.Namespace(case=str(case_path), output=str(out / "simulate.h5"), plot=str(out)))
        print("\n[4/4] squared-envelope spectrum")
        cmd_spectrum(argparse.Namespace(input=str(out / "simulate.h5"), plot=str(out / "envelope_spectrum.png")))
    print(f"\ndone in {time.time() - t0:.0f} s; all results and plots are in {out.resolve()}")
    return 0


def build_parser():
    p = argparse.ArgumentParser(prog="bearingsim", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    s = sub.add_parser("info", help="geometry, Hertz constants, kinematics and defect frequencies of a case")
    s.add_argument("case")
    s.set_defaults(func=cmd_info)
    s = sub.add_parser("static", help="quasi-static Jones solution: per-ball table, displacement, stiffness")
    s.add_argument("case")
    s.add_argument("--json", metavar="OUT.json", help="write the solution as JSON")
    s.add_argument("--plot", metavar="OUT.png", help="polar load distribution and contact angles")
    s.set_defaults(func=cmd_static)
    s = sub.add_parser("sweep", help="quasi-static states over cage angles as the balls pass the spall")
    s.add_argument("case")
    s.add_argument("-o", "--output", required=True, metavar="OUT.h5")
    s.add_argument("--plot", metavar="DIR", help="write plots into DIR")
    s.set_defaults(func=cmd_sweep)
    s = sub.add_parser("study", help="a cage-angle sweep for each value of one case key ([study])")
    s.add_argument("case")
    s.add_argument("-o", "--output", required=True, metavar="OUT.h5")
    s.add_argument("--plot", metavar="DIR", help="write plots into DIR")
    s.set_defaults(func=cmd_study)
    s = sub.add_parser("simulate", help="dynamic simulation (shaft, housing, sensor resonator) "
                       "with the Jones bearing forces; HDF5 output")
    s.add_argument("case")
    s.add_argument("-o", "--output", required=True, metavar="OUT.h5")
    s.add_argument("--plot", metavar="DIR", help="write plots into DIR")
    s.set_defaults(func=cmd_simulate)
    s = sub.add_parser("spectrum", help="envelope spectrum of a simulate output: peak near BPFO, harmonics")
    s.add_argument("input", metavar="OUT.h5")
    s.add_argument("--plot", metavar="PNG", help="write the envelope spectrum plot")
    s.set_defaults(func=cmd_spectrum)
    s = sub.add_parser("dataset", help="labelled data set of simulated sensor signals ([dataset] "
                       "ranges of speed, loads and spall); HDF5 output")
    s.add_argument("spec", metavar="SPEC.toml")
    s.add_argument("-o", "--output", required=True, metavar="OUT.h5")
    s.set_defaults(func=cmd_dataset)
    s = sub.add_parser("compare", help="quasi-static sweep and dynamic run side by side, with amplification")
    s.add_argument("case")
    s.add_argument("--plot", metavar="DIR", help="write compare.png into DIR")
    s.set_defaults(func=cmd_compare)
    s = sub.add_parser("demo", help="run the default case end to end and write all results and plots")
    s.add_argument("--case", default=None, help="case file (default: the Harris 218 demo case)")
    s.add_argument("--out", default="results/demo", help="output folder (default results/demo)")
    s.set_defaults(func=cmd_demo)
    return p


def main(argv=None):
    import matplotlib

    matplotlib.use("Agg")          # files only, no display needed
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except BearingsimError as e:     # the one place where errors become exit codes
        print(f"bearingsim: error: {e}", file=sys.stderr)
        return e.exit_code
    except OSError as e:             # a file the system refused outside bearingsim.io (plots)
        print(f"bearingsim: error: cannot write output: {e}", file=sys.stderr)
        return OutputError.exit_code


if __name__ == "__main__":
    sys.exit(main())
