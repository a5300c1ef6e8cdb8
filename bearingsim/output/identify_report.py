"""What ``bearingsim identify`` found, rendered: the printed text, the JSON mapping and the figure
of the record against its simulated twins.  Takes the ``Identification`` of
:func:`bearingsim.realism.identify.identify` (read by its attributes; this module computes
nothing new).
"""
from __future__ import annotations

import json

import numpy as np

from ..signals.envelope import envelope_spectrum

__all__ = ["identification_to_dict", "identification_text", "plot_identification"]

IN = 25.4       # mm per inch


def identification_to_dict(r) -> dict:
    """The identification as a JSON-ready mapping (its fields; tuples as lists)."""
    d = {k: getattr(r, k) for k in r.__dataclass_fields__}
    return json.loads(json.dumps(d, default=lambda v: list(v) if isinstance(v, tuple) else float(v)))


def _f(v, fmt="{:.3f}", none="not identifiable"):
    return none if v is None else fmt.format(v)


def identification_text(r) -> str:
    """The identification as the lines ``bearingsim identify`` prints."""
    p = ", ".join(f"{k} {v:.2f}" for k, v in r.probabilities.items())
    win = f"{r.windows} windows of {r.window_s:g} s"
    if r.uncertain:
        rows = [f"class: uncertain (most probable: {r.most_probable}, p {r.probabilities[r.most_probable]:.2f} "
                f"< {r.uncertain_below:g}; calibrated probabilities: {p}; {win})"]
    else:
        rows = [f"class: {r.fault_class}  (calibrated probabilities: {p}; {win})"]
    rows.append(f"shaft speed: {r.shaft_hz:.3f} Hz = {r.rpm:.1f} rpm (from the record's spectrum)")
    if r.line_hz is not None:
        rows.append(f"fault line: {r.line_hz:.3f} Hz = {r.order:.4f} x f_r, {r.line_db:.1f} dB over the floor")
    if r.fault_class not in ("healthy", "uncertain"):
        ci = r.contact_angle_interval_deg
        rows.append("contact angle: " + _f(r.contact_angle_deg, "{:.1f} deg") +
                    (f"  ({r.level:.0%}: {ci[0]:.1f}-{ci[1]:.1f} deg; with up to {100 * r.slip_max:g} % slip "
                     f"{r.contact_angle_interval_slip_deg[0]:.1f}-{r.contact_angle_interval_slip_deg[1]:.1f} deg)"
                     if ci else ""))
        li = r.length_interval_mm
        none = "size not resolved" if r.size_resolved is False else "not identifiable"
        rows.append("defect length: " + _f(r.length_mm, "{:.3f} mm", none) +
                    (f"  ({r.level:.0%}: {li[0]:.3f}-{li[1]:.3f} mm = {li[0] / IN:.4f}-{li[1] / IN:.4f} in)"
                     if li else ""))
    rows += [f"note: {m}" for m in r.messages]
    return "\n".join(rows)


def plot_identification(x, fs, r, twin=None, path=None, title=""):
    """The record's squared-envelope spectrum with the twins' (their mean, mirrored; each scaled to
    its own peak) and four passes in time of the record and the first twin; returns the figure
    (saved to ``path`` when given, then closed).  ``twin``: (records (N, T) or (T,), fs), or None
    (an uncertain or healthy answer has no twin)."""
    import matplotlib.pyplot as plt     # only when a figure is asked for (the caller picks the backend)

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 7))
    band = (2000.0, min(5500.0, 0.45 * fs))
    es = envelope_spectrum(np.asarray(x, float), fs, band=band)
    m = es.freqs <= 600
    a1.plot(es.freqs[m], es.amplitude[m] / es.amplitude[m][1:].max(), lw=0.8, label="measured")
    if twin is not None:
        acc = None
        for y in np.atleast_2d(twin[0]):
            et = envelope_spectrum(y, twin[1], band=(band[0], min(band[1], 0.45 * twin[1])))
            a = np.interp(es.freqs[m], et.freqs, et.amplitude)
            a = a / max(a[1:].max(), 1e-300)
            acc = a if acc is None else acc + a
        acc = acc / len(np.atleast_2d(twin[0]))
        a1.plot(es.freqs[m], -acc / max(acc[1:].max(), 1e-300), lw=0.8,
                label=f"simulated twin, mean of {len(np.atleast_2d(twin[0]))} (mirrored)")
    if r.line_hz:
        for k in (1, 2, 3):
            a1.axvline(k * r.line_hz, color="r", ls=":", lw=0.8)
    a1.set_xlabel("frequency (Hz)")
    a1.set_ylabel("squared envelope (normalised, -)")
    a1.legend(loc="upper right")
    a1.set_title(title or f"identified: {r.fault_class}")
    P = 1.0 / r.line_hz if r.line_hz else 0.05
    n = int(min(4 * P, 0.2) * fs)
    t = np.arange(n) / fs * 1e3
    xs = np.asarray(x, float)[:n]
    a2.plot(t, xs / np.max(np.abs(xs)), lw=0.7, label="measured")
    if twin is not None:
        nt = int(min(4 * P, 0.2) * twin[1])
        tt = np.arange(nt) / twin[1] * 1e3
        ys = np.atleast_2d(twin[0])[0][:nt]
        a2.plot(tt, ys / np.max(np.abs(ys)) - 2.2, lw=0.7, label="twin (offset)")
    a2.set_xlabel("time (ms)")
    a2.set_ylabel("acceleration (normalised, -)")
    a2.legend(loc="upper right")
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
