"""The Campbell diagram of a rotor (``bearingsim rotor``, :mod:`bearingsim.app.rotor`): a ROSS
Campbell result drawn with matplotlib, names and units on the axes."""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..case.units import from_si

__all__ = ["plot_campbell"]


def plot_campbell(campbell, crossings=(), rigid_body=1e-3, title="", path=None):
    """The Campbell diagram: each tracked mode's damped natural frequency (Hz) against the rotor
    speed (rpm), coloured by whirl (forward, backward, mixed), the 1X line and the critical speeds;
    modes below ``rigid_body`` (rad/s: rigid-body modes) left out; returns the Figure (saved and
    closed with ``path``)."""
    rpm = from_si(np.asarray(campbell.speed_range, float), "rpm")
    hz = from_si(np.asarray(campbell.wd, float), "rev_s")
    whirl = np.asarray(campbell.whirl_values, float)
    fig, ax = plt.subplots(figsize=(9.0, 5.0))
    colours = {0.0: ("tab:blue", "forward whirl"), 1.0: ("tab:red", "backward whirl"), 0.5: ("tab:gray", "mixed whirl"),
               -1.0: ("tab:green", "axial or torsional")}
    whirl = np.nan_to_num(whirl, nan=-1.0)
    seen = set()
    for j in range(hz.shape[1]):
        if not np.all(np.isfinite(hz[:, j])) or np.max(hz[:, j]) <= from_si(rigid_body, "rev_s"):
            continue
        ax.plot(rpm, hz[:, j], color="0.8", lw=0.8, zorder=1)
        for v, (c, name) in colours.items():
            sel = whirl[:, j] == v
            if sel.any():
                ax.scatter(rpm[sel], hz[sel, j], s=12, color=c, zorder=2, label=None if name in seen else name)
                seen.add(name)
    top = float(np.nanmax(hz)) if np.isfinite(hz).any() else 1.0
    x = np.array([rpm[0], rpm[-1]])
    ax.plot(x, x / 60.0, "k--", lw=1.0, label="1X (shaft speed)")
    for k, c in enumerate(crossings):
        ax.plot(c["speed_rpm"], c["frequency_Hz"], "kx", ms=9, mew=2,
                label="critical speed" if k == 0 else None)
    ax.set_xlim(rpm[0], rpm[-1])
    ax.set_ylim(0.0, 1.05 * max(top, x[-1] / 60.0))
    ax.set_xlabel("rotor speed (rpm)")
    ax.set_ylabel("damped natural frequency (Hz)")
    ax.set_title(title or "Campbell diagram", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.tight_layout()
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
