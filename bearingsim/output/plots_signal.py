"""Plots for the signal stage: envelope spectrum with defect markers, time history with events.

matplotlib with the Agg backend (no display needed).  Each function draws into
``ax`` when given (so figures can be composed), otherwise into a new figure;
it returns the Figure and saves it at 120 dpi when ``path`` is given.
"""
from __future__ import annotations

import re
from pathlib import Path

import matplotlib.pyplot as plt
import matplotlib.transforms as mtransforms
import numpy as np

from ..case.units import from_si
from ..errors import InputError, InputTypeError
from ..names import CLASSES
from ..signals.envelope import EnvelopeSpectrum, Spectrum
from ..signals.lines import defect_markers

__all__ = ["plot_envelope_spectrum", "plot_time_history", "plot_transfer", "plot_record_spectrum"]

# colours per marker family; anything else cycles through _OTHER
_FAMILY_COLOURS = {"BPFO": "#d62728", "BPFI": "#9467bd", "BSF": "#8c564b", "2BSF": "#8c564b",
                   "FTF": "#2ca02c", "SHAFT": "#1f77b4", "BPFI-FR": "#c5b0d5", "BPFI+FR": "#c5b0d5"}
_OTHER = ["#ff7f0e", "#17becf", "#e377c2", "#bcbd22", "#7f7f7f"]
_HARM = re.compile(r"^(\d+)\s*[x×*]\s*(.+)$")
_DPI = 120
_MAX_LINES = 30    # event marks drawn as full-height lines up to this many in view


def _as_signal(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim != 1 or a.size < 2 or not np.all(np.isfinite(a)):
        raise InputError(f"{name} must be a 1-D array of at least 2 finite samples, got shape {a.shape}"
                         + ("" if a.ndim != 1 or a.size < 2 else f" with {int(np.sum(~np.isfinite(a)))} NaN/inf"),
                         "pass one channel of finite samples")
    return a


def _family(label: str) -> tuple[str, int]:
    m = _HARM.match(label)
    return (m.group(2), int(m.group(1))) if m else (label, 1)


def _new_axes(ax, figsize):
    if ax is None:
        fig, ax = plt.subplots(figsize=figsize, constrained_layout=True)
    else:
        fig = ax.figure
    return fig, ax


def _finish(fig, path):
    if path is not None:
        fig.savefig(path, dpi=_DPI)
    return fig


def plot_envelope_spectrum(spectrum: Spectrum, markers, title: str = "", fmax=None, path=None, ax=None,
                           unit: str = "m/s²"):
    """Squared-envelope spectrum (linear amplitude) with labelled defect-frequency markers.

    spectrum : :class:`~bearingsim.signals.envelope.EnvelopeSpectrum` (a plain ``Spectrum`` also works)
    markers  : list of ``(label, frequency_Hz)`` as from :func:`~bearingsim.signals.lines.defect_markers`
               (a dict is expanded with it).  ``"kxNAME"`` labels are drawn as harmonics of
               NAME in the same colour; BPFO is red, FTF green, shaft blue, others distinct.
    fmax     : upper frequency limit (Hz); default 1.2 x the highest marker (capped at fs/2).
    unit     : unit of the analysed signal; the envelope amplitude is in unit².
    """
    if not isinstance(spectrum, Spectrum):
        raise InputTypeError(f"spectrum must be a Spectrum/EnvelopeSpectrum, got {type(spectrum).__name__}",
                             "pass the result of bearingsim.signals.envelope.envelope_spectrum()")
    if isinstance(markers, dict):
        markers = defect_markers(markers)
    markers = [(str(lab), float(f)) for lab, f in (markers or [])]
    f_nyq = float(spectrum.freqs[-1])
    if fmax is None:
        fmax = 1.2 * max(f for _, f in markers) if markers else f_nyq
    fmax = min(float(fmax), f_nyq)
    if not fmax > 0:
        raise InputError(f"fmax must be > 0 Hz, got {fmax}",
                         "fmax is the upper frequency limit in Hz; None for 1.2 x the highest marker")

    fig, ax = _new_axes(ax, (10, 4.2))
    sel = spectrum.freqs <= fmax
    f, a = spectrum.freqs[sel], spectrum.amplitude[sel]
    is_env = isinstance(spectrum, EnvelopeSpectrum) or spectrum.band is not None
    ax.plot(f, a, color="0.15", lw=0.9, label="squared-envelope spectrum" if is_env else "amplitude spectrum")
    amax = float(a[f > 0].max()) if np.any(f > 0) and a[f > 0].max() > 0 else 1.0
    ax.set_ylim(0.0, 1.32 * amax)
    ax.set_xlim(0.0, fmax)

    trans = mtransforms.blended_transform_factory(ax.transData, ax.transAxes)
    colours, seen, other = {}, set(), iter(_OTHER * 10)
    for lab, fm in markers:
        fam, k = _family(lab)
        key = fam.upper()
        if key not in colours:
            colours[key] = _FAMILY_COLOURS.get(key) or next(other)
        c = colours[key]
        if not (0.0 < fm <= fmax):
            continue
        leg = None
        if key not in seen:
            seen.add(key)
            leg = f"{fam} & harmonics" if any(_family(m)[0].upper() == key and _family(m)[1] > 1
                                               for m, _ in markers) else fam
        ax.axvline(fm, color=c, ls="--", lw=1.1 if k == 1 else 0.9, alpha=0.85, label=leg, zorder=1)
        text = fam if k == 1 else f"{k}×{fam}"
        ax.text(fm, 0.985, f" {text} ", transform=trans, rotation=90, ha="right", va="top",
                fontsize=8.5, color=c, clip_on=True,
                bbox=dict(boxstyle="square,pad=0.1", fc="white", ec="none", alpha=0.8))

    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"squared-envelope amplitude (({unit})²)" if is_env else f"amplitude ({unit})")
    ax.grid(alpha=0.3)
    leg_title = None
    if spectrum.band is not None:
        lo, hi = spectrum.band
        leg_title = f"band {lo:.0f}–{hi:.0f} Hz"
    ax.legend(loc="upper right", fontsize=8, title=leg_title, title_fontsize=8, framealpha=0.9,
              bbox_to_anchor=(1.0, 0.80))
    if title:
        ax.set_title(title)
    return _finish(fig, path)


def plot_time_history(t, x, marks=None, title: str = "", path=None, ax=None, zoom=None,
                      ylabel: str = "acceleration (m/s²)", marks_label: str = "spall pass"):
    """Signal against time with vertical lines at event times (e.g. spall passes).

    zoom : optional ``(t0, t1)`` window in s; only that part is drawn and y is scaled to it.
    marks : event times in s; up to 30 in view are drawn as dotted full-height lines,
            more as a row of small ticks along the top edge (keeps long records readable).
    The time axis is shown in ms when the visible span is shorter than 0.1 s.
    """
    t = _as_signal(t, "t")
    x = _as_signal(x, "x")
    if t.size != x.size:
        raise InputError(f"t and x must have the same length, got {t.size} and {x.size}",
                         "t holds the time (s) of each sample of x")
    if zoom is not None:
        t0, t1 = (float(v) for v in zoom)
        if not t0 < t1:
            raise InputError(f"zoom must be (t0, t1) with t0 < t1, got {zoom!r}",
                             f"a window in s inside the record's {t[0]:g}–{t[-1]:g} s, or None for all of it")
        sel = (t >= t0) & (t <= t1)
        if not sel.any():
            raise InputError(f"zoom window {zoom!r} contains no samples (t spans {t[0]:g}–{t[-1]:g} s)",
                             "choose (t0, t1) inside the record's time span, or None for all of it")
        t, x = t[sel], x[sel]
    else:
        t0, t1 = float(t[0]), float(t[-1])
    tunit = "ms" if (t1 - t0) < 0.1 else "s"
    scale = from_si(1.0, tunit)

    fig, ax = _new_axes(ax, (10, 3.8))
    ax.plot(t * scale, x, color="#1f77b4", lw=0.6, label="signal")
    if marks is not None:
        mk = np.asarray(marks, dtype=float).ravel()
        mk = mk[(mk >= t0) & (mk <= t1)]
        if mk.size > _MAX_LINES:    # too many for full-height lines: a rug of ticks on the top edge
            trans = mtransforms.blended_transform_factory(ax.transData, ax.transAxes)
            ax.plot(mk * scale, np.full(mk.size, 0.985), ls="none", marker="v", ms=4.5, color="#d62728",
                    transform=trans, clip_on=False, label=f"{marks_label} ({mk.size})", zorder=3)
        for i, tm in enumerate(mk if mk.size <= _MAX_LINES else []):
            ax.axvline(tm * scale, color="#d62728", ls=":", lw=1.0, alpha=0.8,
                       label=marks_label if i == 0 else None, zorder=0)
    ax.set_xlim(t0 * scale, t1 * scale)
    ymax = float(np.max(np.abs(x))) or 1.0
    ax.set_ylim(-1.15 * ymax, 1.15 * ymax)
    ax.set_xlabel(f"time ({tunit})")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8, framealpha=0.9, bbox_to_anchor=(1.0, 0.94))
    if title:
        ax.set_title(title)
    return _finish(fig, path)


def plot_transfer(reports, path=None):
    """The transfer benchmark (:func:`bearingsim.realism.transfer.transfer_benchmark`): per classifier its
    confusion matrix on the real windows (rows the true class, as fractions of the row) and the
    accuracy of every real record."""
    n = len(reports)
    fig, axes = plt.subplots(2, n, figsize=(5.2 * n, 8.4), squeeze=False,
                             gridspec_kw={"height_ratios": [1.0, 0.8]})
    for k, r in enumerate(reports):
        ax = axes[0, k]
        cm = np.asarray(r.confusion, float)
        frac = cm / np.maximum(cm.sum(1, keepdims=True), 1.0)
        ax.imshow(frac, vmin=0.0, vmax=1.0, cmap="Blues")
        ax.set_xticks(range(len(CLASSES)), CLASSES)
        ax.set_yticks(range(len(CLASSES)), CLASSES)
        ax.set_xlabel("predicted class")
        ax.set_ylabel("true class (real records)")
        for i in range(4):
            for j in range(4):
                if cm[i].sum() > 0:
                    ax.text(j, i, f"{frac[i, j]:.2f}\n({int(cm[i, j])})", ha="center", va="center",
                            color="white" if frac[i, j] > 0.6 else "black", fontsize=8)
        wc, wv = r.worst_class
        ax.set_title(f"{r.classifier.replace('_', ' ')}\nbalanced accuracy {r.balanced_accuracy:.2f}, "
                     f"worst class {wc} {wv:.2f}", fontsize=10)
        ax = axes[1, k]
        recs = list(r.per_record)
        acc = [r.per_record[q][1] for q in recs]
        ax.barh(range(len(recs)), acc, color=["#2ca02c" if a >= 0.7 else "#d62728" for a in acc])
        for i, a in enumerate(acc):             # the value, also for a bar of length 0
            ax.text(min(a, 0.86) + 0.02, i, f"{a:.2f}", va="center", fontsize=8)
        ax.set_yticks(range(len(recs)), [q.replace("cwru_", "").replace("_0hp", "") for q in recs], fontsize=8)
        ax.set_xlim(0.0, 1.0)
        ax.axvline(0.7, color="0.5", lw=0.8, ls="--")
        ax.set_xlabel("accuracy over the record's windows (-)")
        ax.invert_yaxis()
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=_DPI)
        plt.close(fig)
    return fig


def _draw_thresholds(ax, verdicts, fmax):
    """Each fault line's detection threshold over its search window (a bar at the level a peak
    must pass) and the peak, filled when detected."""
    first = True
    for v in verdicts.values():
        if v.detected is None or not (0.0 < v.expected_hz <= fmax):
            continue
        level = v.floor * 10.0 ** (v.threshold_db / 20.0)
        half = max(v.window_hz, 0.004 * fmax)          # the window, at least visible
        ax.hlines(level, v.expected_hz - half, v.expected_hz + half, color="#d62728", lw=2.2,
                  label=f"detection threshold ({100 * v.false_alarm:g} % false alarms per line)" if first else None,
                  zorder=3)
        peak = v.floor * 10.0 ** (v.strength_db / 20.0)
        ax.plot(v.peak_hz, peak, "v", ms=6, color="#d62728", mfc="#d62728" if v.detected else "white", zorder=4,
                label="line peak (filled: detected)" if first else None)
        first = False
    if not first:
        old = ax.get_legend()
        ax.legend(loc="upper right", fontsize=8, framealpha=0.9, bbox_to_anchor=(1.0, 0.80), title_fontsize=8,
                  title=old.get_title().get_text() if old is not None else None)


def plot_record_spectrum(rs, path=None, fmax=None):
    """A record's squared-envelope spectrum with the bearing's fault lines (BPFO and BPFI with
    harmonics, BPFI -/+ f_r, 2 BSF, FTF, shaft) and, on its own axis, a simulation's (``rs.overlay``);
    below, the amplitude spectrum with the demodulation band.  ``rs``: a
    :class:`bearingsim.realism.record_spectrum.RecordSpectrum`."""
    L = rs.lines
    marks = defect_markers({k: L[k] for k in ("BPFO", "BPFI", "BPFI-fr", "BPFI+fr", "2BSF", "FTF", "shaft")},
                           n_harmonics=3, harmonics_of=("BPFO", "BPFI"))
    fmax = 1.1 * 3.0 * max(L["BPFO"], L["BPFI"]) if fmax is None else float(fmax)
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(11, 7.5), constrained_layout=True,
                                  gridspec_kw=dict(height_ratios=(3, 2)))
    plot_envelope_spectrum(rs.envelope, marks, fmax=fmax, ax=ax, unit="m/s²",
                           title=f"{Path(rs.source).name}{f' ({rs.channel})' if rs.channel else ''}: squared-envelope "
                                 f"spectrum\nfault lines of {rs.case_title.split(',')[0]} at shaft "
                                 f"{60 * rs.shaft_hz:.1f} rpm ({rs.shaft_source.split(' (')[0]})")
    _draw_thresholds(ax, rs.verdicts or {}, fmax)
    if rs.overlay is not None:
        ov = rs.overlay
        tw = ax.twinx()
        sel = ov.spectrum.freqs <= fmax
        tw.plot(ov.spectrum.freqs[sel], ov.spectrum.amplitude[sel], color="#ff7f0e", lw=0.9, alpha=0.75,
                label=f"simulation: {ov.source}" + (f", {60 * ov.shaft_hz:.0f} rpm" if ov.shaft_hz else "")
                + f", band {ov.band[0]:.0f}–{ov.band[1]:.0f} Hz")
        top = ov.spectrum.amplitude[sel][ov.spectrum.freqs[sel] > 0].max()
        tw.set_ylim(0.0, 1.32 * top if top > 0 else 1.0)
        tw.set_ylabel("simulation: squared-envelope amplitude ((m/s²)²)", color="#ff7f0e")
        tw.tick_params(axis="y", colors="#ff7f0e")
        tw.legend(loc="upper right", bbox_to_anchor=(1.0, 0.25), fontsize=8, framealpha=0.9)
    f, A = rs.spectrum.freqs, rs.spectrum.amplitude
    ax2.semilogy(f[1:], np.maximum(A[1:], 1e-12), color="0.2", lw=0.6, label="amplitude spectrum")
    ax2.axvspan(*rs.band, color="#ff7f0e", alpha=0.15, label=f"demodulation band {rs.band[0]:.0f}–{rs.band[1]:.0f} Hz")
    ax2.set_xlim(0.0, rs.sample_rate / 2.0)
    ax2.set_xlabel("frequency (Hz)")
    ax2.set_ylabel("amplitude (m/s²)")
    ax2.grid(alpha=0.3, which="both")
    ax2.legend(loc="upper right", fontsize=8)
    return _finish(fig, path)
