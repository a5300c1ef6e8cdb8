"""Plots a bearing engineer would put in a report (matplotlib, no display needed)."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

RAD2DEG = 180.0 / np.pi
C_IN, C_OUT = "#1f77b4", "#d62728"


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
    lo, hi = np.rad2deg(span[0]) % 360.0, np.rad2deg(span[1]) % 360.0
    kw = dict(color="0.55", alpha=0.3, lw=0)
    if hi < lo:   # straddles 0 deg
        ax.axvspan(lo, 360.0, label="spall" if label else None, **kw)
        ax.axvspan(0.0, hi, **kw)
    else:
        ax.axvspan(lo, hi, label="spall" if label else None, **kw)


def polar_loads(ax, sol, spall=None, title="Ball loads"):
    """Polar load distribution: Q_i and Q_o at each ball azimuth (frame of MODEL.md: 0 deg = +x)."""
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
    psi = np.mod(np.asarray(sol.azimuth), 2 * np.pi) * RAD2DEG
    order = np.argsort(psi)
    _shade_azimuth(ax, _spall_span(spall))
    ax.plot(psi[order], np.asarray(sol.alpha_inner)[order] * RAD2DEG, "-s", color=C_IN, ms=4, label=r"$\alpha_i$ inner")
    ax.plot(psi[order], np.asarray(sol.alpha_outer)[order] * RAD2DEG, "-o", color=C_OUT, ms=4, label=r"$\alpha_o$ outer")
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
    q = np.asarray(sol.displacement)
    rpm = float(sol.cage_speed) * 60 / (2 * np.pi)
    ax.set_title(f"ring: x {q[0]*1e6:.2f} µm, y {q[1]*1e6:.2f} µm, axial {q[2]*1e6:.2f} µm, "
                 f"tilt {q[3]*1e3:.3f}/{q[4]*1e3:.3f} mrad; cage {rpm:.0f} rpm", fontsize=9)
    if title:
        fig.suptitle(title)
    if path is not None:
        fig.savefig(path, dpi=130)
        plt.close(fig)
    return fig
