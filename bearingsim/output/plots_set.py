"""Figures of a bearing set (docs/model.md section 10): its state (contact loads and angles per ball, per
bearing), a study over its parameter (preload, stiffness, life, pressure) and the limits diagram.
Draws what :mod:`bearingsim.app.set_workflows` computed (Agg backend, matplotlib imported when a
figure is asked for); every axis names its quantity and unit.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .io import atomic_path
from .set_report import parameter_label

__all__ = ["plot_set_static", "plot_set_study", "plot_set_limits"]


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


def plot_set_study(study, title="", path=None, table=None):
    """A set study over its parameter, one axis per unit: the preload and the operating axial
    load of each bearing (N); the axial, radial (N/um) and tilt (N m/mrad) stiffness of each
    bearing and of the set; the L10r life of each bearing and of the set (h, log scale; needs
    ``table``, :func:`bearingsim.app.set_workflows.set_study_table`, and the bearings' ratings)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
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


def plot_set_limits(study, limits: dict, title="", path=None):
    """The limits diagram over the study's parameter (speed, preload, ...): per bearing the peak
    pressure over its limit, the friction raceway control needs over the available, the smallest
    ellipse-to-edge margin and the lift-off margin (``limits``:
    :func:`bearingsim.app.set_workflows.study_limits`); the shaded side of each line is out of margin."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    lim = limits
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
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120, format=Path(path).suffix.lstrip(".") or "png")
    plt.close(fig)
    return path
