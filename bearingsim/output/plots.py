"""Plots a bearing engineer would put in a report (matplotlib, no display needed)."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from ..case.units import from_si
from ..physics.defect import depth_profile
from ..signals.lines import defect_markers, fault_lines
from .plots_signal import plot_envelope_spectrum, plot_time_history
from ..errors import failed, succeeded

C_IN, C_OUT = "#1f77b4", "#d62728"


def _finish(fig, title, path, dpi=120):
    """Common tail of every report figure: title, save (then close) when a path is given."""
    if title:
        fig.suptitle(title)
    if path is not None:
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
    return fig


def _closed(a):
    a = np.asarray(a)
    return np.concatenate([a, a[:1]])


def _spall_span(spall):
    if spall is None or float(spall.depth) <= 0.0:
        return None
    lo, hi = (float(v) for v in spall.edges())
    return lo, hi


def _shade_polar(ax, span, rmax):
    if span is None:
        return
    th = np.linspace(span[0], span[1], 30)
    ax.fill_between(th, 0, rmax, color="0.55", alpha=0.3, lw=0, label="spall")


def _shade_azimuth(ax, span, label=True):
    if span is None:
        return
    lo, hi = from_si(span[0], "deg") % 360.0, from_si(span[1], "deg") % 360.0
    kw = dict(color="0.55", alpha=0.3, lw=0)
    if hi < lo:   # straddles 0 deg
        ax.axvspan(lo, 360.0, label="spall" if label else None, **kw)
        ax.axvspan(0.0, hi, **kw)
    else:
        ax.axvspan(lo, hi, label="spall" if label else None, **kw)


def polar_loads(ax, sol, spall=None, title="Ball loads"):
    """Polar load distribution: Q_i and Q_o at each ball azimuth (frame of docs/model.md: 0 deg = +x)."""
    psi = np.asarray(sol.azimuth)
    order = np.argsort(np.mod(psi, 2 * np.pi))
    psi = np.mod(psi, 2 * np.pi)[order]
    Qi, Qo = np.asarray(sol.Q_inner)[order], np.asarray(sol.Q_outer)[order]
    rmax = max(float(np.max(Qo)), float(np.max(Qi)), 1e-9) * 1.15
    _shade_polar(ax, _spall_span(spall), rmax)
    ax.plot(_closed(psi), _closed(Qo), "-o", color=C_OUT, ms=4, lw=1.4, label="$Q_o$ outer")
    ax.plot(_closed(psi), _closed(Qi), "--s", color=C_IN, ms=3.5, lw=1.2, label="$Q_i$ inner")
    ax.set_ylim(0, rmax)
    ax.set_title(title + " (N)", pad=14)
    ax.legend(loc="lower left", bbox_to_anchor=(-0.15, -0.15), fontsize=8, frameon=False)
    ax.tick_params(labelsize=8)


def contact_angles(ax, sol, spall=None):
    psi = from_si(np.mod(np.asarray(sol.azimuth), 2 * np.pi), "deg")
    order = np.argsort(psi)
    _shade_azimuth(ax, _spall_span(spall))
    ax.plot(psi[order], from_si(np.asarray(sol.alpha_inner)[order], "deg"), "-s", color=C_IN, ms=4,
            label=r"$\alpha_i$ inner")
    ax.plot(psi[order], from_si(np.asarray(sol.alpha_outer)[order], "deg"), "-o", color=C_OUT, ms=4,
            label=r"$\alpha_o$ outer")
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 45))
    ax.set_xlabel("ball azimuth ψ (deg)")
    ax.set_ylabel("contact angle (deg)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)


def plot_static(sol, title="", spall=None, path=None):
    """Polar load distribution and contact angles against azimuth for one quasi-static state."""
    fig = plt.figure(figsize=(11, 4.6), constrained_layout=True)
    gs = fig.add_gridspec(1, 5)
    axp = fig.add_subplot(gs[0, :2], projection="polar")
    polar_loads(axp, sol, spall)
    ax = fig.add_subplot(gs[0, 2:])
    contact_angles(ax, sol, spall)
    x, y, z = from_si(np.asarray(sol.displacement[:3]), "um")
    tx, ty = from_si(np.asarray(sol.displacement[3:]), "mrad")
    rpm = from_si(float(sol.cage_speed), "rpm")
    ax.set_title(f"ring: x {x:.2f} µm, y {y:.2f} µm, axial {z:.2f} µm, "
                 f"tilt {tx:.3f}/{ty:.3f} mrad ({getattr(sol, 'tilt', 'free')}); cage {rpm:.0f} rpm", fontsize=9)
    return _finish(fig, title, path, dpi=130)


# ------------------------------------------------------------------------------- sweeps
#: (JonesSolution field, axis label, unit of the axis)
_QUANTITIES = [("alpha_inner", r"$\alpha_i$ (deg)", "deg"), ("alpha_outer", r"$\alpha_o$ (deg)", "deg"),
               ("Q_inner", r"$Q_i$ (N)", "N"), ("Q_outer", r"$Q_o$ (N)", "N")]


def _take(sol, n):
    import jax

    # on host arrays: indexing a JAX array compiles an eager slice and squeeze per field and shape
    return jax.tree_util.tree_map(lambda a: np.asarray(a)[n] if np.ndim(a) > 0 else a, sol)


def spall_traces(sweep_sol, center=0.0):
    """Follow the balls past the spall.  For every cage angle, the ball nearest the spall centre
    (k = 0) and its neighbours (k = -1 trailing, +1 leading): returns u (deg, position of the
    nearest ball relative to the spall centre, sorted) and {name: (N, 3) array for k = -1, 0, 1}.
    Over one ball pitch this covers every configuration of the ball set relative to the spall."""
    psi = np.asarray(sweep_sol.azimuth)
    u_all = np.mod(psi - center + np.pi, 2 * np.pi) - np.pi
    near = np.argmin(np.abs(u_all), axis=1)
    Z = psi.shape[1]
    n = np.arange(psi.shape[0])
    u = from_si(u_all[n, near], "deg")
    order = np.argsort(u, kind="stable")
    out = {}
    for name, _, _ in _QUANTITIES:
        v = np.asarray(getattr(sweep_sol, name))
        out[name] = np.stack([v[n, (near + k) % Z] for k in (-1, 0, 1)], axis=1)[order]
    ok = succeeded(np.asarray(sweep_sol.result))[order]
    return u[order], out, ok


def _center(spall):
    return 0.0 if spall is None else float(spall.center)


def plot_sweep(sweep_sol, title="", spall=None, path=None):
    """As the balls pass the spall: contact angles and loads of the ball nearest the spall and
    of its neighbours against its position relative to the spall centre; ring displacement and
    cage speed against cage angle; polar load distribution with a ball at the spall centre."""
    fig = plt.figure(figsize=(13, 8.5), constrained_layout=True)
    gs = fig.add_gridspec(3, 3)
    u, tr, ok = spall_traces(sweep_sol, _center(spall))
    half = None if spall is None else from_si(0.5 * float(spall.extent), "deg")
    styles = [("trailing neighbour", "--", "0.45"), ("ball over the spall", "-", None), ("leading neighbour", ":", "0.2")]
    for k, (name, label, unit) in enumerate(_QUANTITIES):
        ax = fig.add_subplot(gs[k // 2, k % 2])
        if half is not None and float(spall.depth) > 0:
            ax.axvspan(-half, half, color="0.55", alpha=0.3, lw=0, label="spall")
        col = C_IN if "inner" in name else C_OUT
        for i, (lab, ls, c) in enumerate(styles):
            ax.plot(u[ok], from_si(tr[name][ok, i], unit), ls, color=c or col, lw=1.5 if i == 1 else 1.1,
                    label=lab)
        ax.set_xlabel("ball position relative to the spall centre (deg)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        if k == 0:
            ax.legend(fontsize=8)
    th = from_si(np.asarray(sweep_sol.cage_angle), "deg")
    q = np.asarray(sweep_sol.displacement)
    ax = fig.add_subplot(gs[2, :2])
    for j, lab in enumerate(["x", "y", "axial"]):
        ax.plot(th, from_si(q[:, j], "um"), label=f"{lab} (µm)")
    ax2 = ax.twinx()
    ax2.plot(th, from_si(q[:, 3], "mrad"), ":", color="0.3", label="tilt x (mrad)")
    ax2.plot(th, from_si(q[:, 4], "mrad"), "--", color="0.5", label="tilt y (mrad)")
    ax2.set_ylabel("tilt (mrad)")
    ax.set_xlabel("cage angle θ_c (deg)")
    ax.set_ylabel("ring displacement (µm)")
    ax.grid(alpha=0.3)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=8, ncol=5, loc="best")
    bad = failed(np.asarray(sweep_sol.result))
    for t in th[bad]:
        ax.axvline(t, color="red", alpha=0.4)
    psi = np.asarray(sweep_sol.azimuth)
    uu = np.abs(np.mod(psi - _center(spall) + np.pi, 2 * np.pi) - np.pi).min(axis=1)
    n = int(np.argmin(uu))
    axp = fig.add_subplot(gs[:2, 2], projection="polar")
    polar_loads(axp, _take(sweep_sol, n), spall, title=f"Ball loads, θ_c = {th[n]:.2f}°")
    axc = fig.add_subplot(gs[2, 2])
    axc.plot(th, from_si(np.asarray(sweep_sol.cage_speed), "rpm"), color="k")
    axc.set_xlabel("cage angle θ_c (deg)")
    axc.set_ylabel("mean orbital (cage) speed (rpm)")
    axc.grid(alpha=0.3)
    axc.ticklabel_format(useOffset=False)
    if np.any(bad):
        fig.text(0.01, 0.01, f"{int(bad.sum())} angle(s) did not converge (red lines)", color="red")
    return _finish(fig, title, path, dpi=120)


def plot_study(study_sols, values, parameter, unit_label="", title="", spall=None, path=None):
    """Paper-style study: alpha_i, alpha_o, Q_i, Q_o of every ball against its azimuth with a
    ball at the spall centre, one curve per value, spall shaded; the ball passing the spall
    against its position; polar distribution of Q_o."""
    fig = plt.figure(figsize=(15, 8.5), constrained_layout=True)
    gs = fig.add_gridspec(2, 3)
    cmap = plt.get_cmap("viridis")
    colors = [cmap(x) for x in np.linspace(0.0, 0.9, len(values))]
    span = _spall_span(spall)
    axes = [fig.add_subplot(gs[0, 0]), fig.add_subplot(gs[0, 1]), fig.add_subplot(gs[1, 0]),
            fig.add_subplot(gs[1, 1])]
    axp = fig.add_subplot(gs[0, 2], projection="polar")
    axt = fig.add_subplot(gs[1, 2])
    rmax = 0.0
    for m, (v, c) in enumerate(zip(values, colors)):
        s = _take(study_sols, m)
        psi = np.asarray(s.azimuth)
        uu = np.abs(np.mod(psi - _center(spall) + np.pi, 2 * np.pi) - np.pi).min(axis=1)
        one = _take(s, int(np.argmin(uu)))
        az = np.mod(np.asarray(one.azimuth), 2 * np.pi)
        order = np.argsort(az)
        lab = f"{v:g} {unit_label}".strip()
        for ax, (name, label, unit) in zip(axes, _QUANTITIES):
            ax.plot(from_si(az[order], "deg"), from_si(np.asarray(getattr(one, name))[order], unit), "-o",
                    ms=3.5, color=c, lw=1.3, label=lab)
        Qo = np.asarray(one.Q_outer)[order]
        rmax = max(rmax, float(Qo.max()))
        axp.plot(_closed(az[order]), _closed(Qo), "-o", ms=3, color=c, lw=1.2)
        u, tr, ok = spall_traces(s, _center(spall))
        axt.plot(u[ok], tr["Q_outer"][ok, 1], color=c, lw=1.4, label=lab)
        axt.plot(u[ok], tr["Q_inner"][ok, 1], "--", color=c, lw=1.0)
    for ax, (name, label, _) in zip(axes, _QUANTITIES):
        _shade_azimuth(ax, span, label=False)
        ax.set_xlim(0, 360)
        ax.set_xticks(np.arange(0, 361, 45))
        ax.set_xlabel("ball azimuth ψ (deg)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(title=parameter, fontsize=8, title_fontsize=8)
    if span is not None:
        axp.fill_between(np.linspace(span[0], span[1], 30), 0, rmax * 1.1, color="0.55", alpha=0.3, lw=0)
        half = from_si(0.5 * float(spall.extent), "deg")
        axt.axvspan(-half, half, color="0.55", alpha=0.3, lw=0)
    axp.set_ylim(0, rmax * 1.1)
    axp.set_title("$Q_o$ (N), a ball at the spall centre", pad=14)
    axt.set_xlabel("ball position relative to the spall centre (deg)")
    axt.set_ylabel("$Q_o$ (solid), $Q_i$ (dashed) of the passing ball (N)")
    axt.grid(alpha=0.3)
    return _finish(fig, title, path, dpi=120)


# ------------------------------------------------------------------------------- dynamics
def _balls_over_spall(res, bearing, spall):
    """Balls that meet the defect during a simulation: those crossing an outer spall, the pitted
    ball; for an inner spall (it turns) the three whose inner load varies most; else the three
    most loaded."""
    Qo = np.asarray(res.Q_outer)
    if spall is not None and spall.location == "ball":
        return np.array([spall.ball])
    if spall is not None and spall.location == "inner":
        return np.argsort(-np.ptp(np.asarray(res.Q_inner), axis=0))[:3]
    if spall is not None and bearing is not None:
        import jax.numpy as jnp

        Z = Qo.shape[1]
        psi = np.asarray(res.cage_angle)[:, None] + 2 * np.pi * np.arange(Z) / Z
        inside = np.asarray(depth_profile(bearing, spall, jnp.asarray(psi))) > 0
        balls = np.flatnonzero(inside.any(axis=0))
        if balls.size:
            return balls
    return np.argsort(-Qo.max(axis=0))[:3]


def plot_simulation(res, outdir, title="", bearing=None, spall=None, spectrum=None):
    """Figures of a dynamic simulation written into ``outdir``: sensor acceleration (whole run and
    three spall passes), outer loads of the balls that pass the spall, and the envelope spectrum
    with the defect's line (BPFO, BPFI or 2 BSF), its sidebands and harmonics when ``spectrum``
    is given.  Returns the paths written."""
    from pathlib import Path

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    t = np.asarray(res.time)
    a = np.asarray(res.sensor_acceleration)
    passes = np.asarray(res.pass_times)
    fr = res.frequencies
    location = None if spall is None else spall.location
    name, f0, lines = fault_lines(fr, location)
    written = [outdir / "sensor_acceleration.png"]
    plt.close(plot_time_history(t, a, marks=passes, title=f"{title}: sensor acceleration", path=written[-1]))
    if passes.size:
        t0 = max(float(t[0]), float(passes[0]) - 0.5 / f0)
        t1 = min(float(t[-1]), t0 + 3.0 / f0)
        written.append(outdir / "sensor_acceleration_zoom.png")
        plt.close(plot_time_history(t, a, marks=passes, zoom=(t0, t1), path=written[-1],
                                    title=f"{title}: sensor acceleration (3 defect passes)"))
    fig, ax = plt.subplots(figsize=(10, 4), constrained_layout=True)
    which = "inner" if location == "inner" else "outer"
    Q = np.asarray(res.Q_inner if which == "inner" else res.Q_outer)
    for j in _balls_over_spall(res, bearing, spall):
        ax.plot(from_si(t, "ms"), Q[:, j], lw=0.8, label=f"ball {j}")
    for tm in passes[:30]:
        ax.axvline(from_si(tm, "ms"), color="#d62728", ls=":", lw=0.8)
    ax.set_xlabel("time (ms)")
    ax.set_ylabel(f"{which} contact load Q_{which[0]} (N)")
    ax.set_title(f"{title}: {which} loads of the balls that meet the defect")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=4)
    written.append(outdir / "ball_loads.png")
    _finish(fig, "", written[-1])
    if spectrum is not None:
        written.append(outdir / "envelope_spectrum.png")
        plt.close(plot_envelope_spectrum(spectrum, defect_markers(lines, harmonics_of=(name,)),
                                         title=f"{title}: squared-envelope spectrum", path=written[-1],
                                         fmax=5.5 * f0))
    return written


def plot_compare(comparison, title="", path=None):
    """Dynamic run against the quasi-static sweep at its cage angles (a
    :class:`bearingsim.app.signal_workflows.Comparison`): Q_o, Q_i, alpha_o of the ball whose load varies
    most, and the ring displacement, against the cage angle."""
    res, idx, qs = comparison.dynamic, comparison.indices, comparison.quasi_static
    th = from_si(np.unwrap(np.asarray(res.cage_angle)), "deg")
    j = int(np.argmax(np.ptp(np.asarray(res.Q_outer)[idx], axis=0)))
    fig, axes = plt.subplots(2, 2, figsize=(13, 7.5), constrained_layout=True)
    for ax, (name, lab, unit) in zip(axes.ravel()[:3], (_QUANTITIES[3], _QUANTITIES[2], _QUANTITIES[1])):
        ax.plot(th, from_si(np.asarray(getattr(res, name))[:, j], unit), lw=0.9, label=f"dynamic, ball {j}")
        ax.plot(th[idx], from_si(np.asarray(getattr(qs, name))[:, j], unit), ".", ms=3, label="quasi-static sweep")
        ax.set_xlabel("cage angle θ_c (deg)")
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    ax = axes[1, 1]
    qd = from_si(np.asarray(res.ring_displacement), "um")
    for k, lab in enumerate(("x", "y", "axial")):
        line, = ax.plot(th, qd[:, k], lw=0.9, label=f"{lab} dynamic")
        ax.plot(th[idx], from_si(np.asarray(qs.displacement)[:, k], "um"), ".", ms=3, color=line.get_color(),
                label=f"{lab} quasi-static")
    ax.set_xlabel("cage angle θ_c (deg)")
    ax.set_ylabel("ring displacement (µm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return _finish(fig, f"{title}: static vs swept vs dynamic" if title else "", path)
