"""A real record's spectra against a bearing's fault lines (``bearingsim spectrum RECORD``).

Reads a record file (:func:`bearingsim.realism.records.read_record`: .npz, .npy, .csv / .txt, .wav),
finds the shaft speed (given with ``rpm``, else searched within +-10 % of the file's nominal rpm
or the case's speed: :func:`bearingsim.realism.background_fit.shaft_speed`), computes the fault lines of
the case's bearing at that speed (MODEL.md 8, free contact angle: BPFO, BPFI and its shaft-rate
sidebands BPFI -/+ f_r, 2 BSF, FTF, the shaft), the squared-envelope spectrum in the demodulation
band of largest envelope kurtosis (:func:`bearingsim.signals.envelope.select_band`) and the amplitude
spectrum, and the strength of each line: its largest bin within +-1.5 % over the spectrum's
median between 1 and 20 x the shaft frequency (dB), as :mod:`bearingsim.signals.features` measures it.

An overlay (a ``bearingsim simulate`` output or a ``bearingsim dataset`` file, item ``item``)
gets its own envelope spectrum, in its own band of largest kurtosis, for comparison.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..output.io import read_simulation
from ..signals.envelope import amplitude_spectrum, envelope_spectrum, select_band
from ..signals.features import fault_orders
from .background_fit import shaft_speed
from .records import RECORD_SUFFIXES, UNITS, read_record

__all__ = ["RecordSpectrum", "Overlay", "record_spectrum", "read_overlay", "fault_line_table", "LINE_WINDOW",
           "MIN_RECORD_S"]

#: a line's search window (relative, at least two bins), as in bearingsim.signals.features
LINE_WINDOW = 0.015
#: shortest record analysed (s): 10 revolutions of a 600 rpm shaft
MIN_RECORD_S = 0.1


@dataclass(frozen=True)
class Overlay:
    """A simulated signal's envelope spectrum (``source``: the file and item)."""

    source: str
    sample_rate: float
    band: tuple
    spectrum: object
    shaft_hz: float | None


@dataclass(frozen=True)
class RecordSpectrum:
    """What :func:`record_spectrum` found (frequencies in Hz, signals in m/s^2)."""

    source: str
    channel: str | None
    samples: int
    sample_rate: float
    unit: str                 # the file's unit (converted to m/s^2 for the spectra)
    case_title: str
    shaft_hz: float
    shaft_source: str         # "given (--rpm)" / "found near ... rpm"
    lines: dict               # name -> Hz: BPFO, BPFI, BPFI-fr, BPFI+fr, 2BSF, FTF, shaft
    band: tuple
    envelope: object          # signal.EnvelopeSpectrum
    spectrum: object          # signal.Spectrum (amplitude)
    strengths: dict           # name -> (measured Hz, dB over the floor)
    overlay: Overlay | None = None


def fault_line_table(bearing, shaft_hz) -> dict:
    """name -> frequency (Hz) of the fault lines of ``bearing`` at ``shaft_hz`` (free contact
    angle, MODEL.md 8)."""
    o = fault_orders(bearing)
    f = float(shaft_hz)
    return {"BPFO": o.bpfo * f, "BPFI": o.bpfi * f, "BPFI-fr": (o.bpfi - 1.0) * f, "BPFI+fr": (o.bpfi + 1.0) * f,
            "2BSF": o.two_bsf * f, "FTF": o.ftf * f, "shaft": f}


def _strength(spec, f0, shaft_hz):
    f, S = np.asarray(spec.freqs), np.asarray(spec.amplitude)
    df = f[1] - f[0]
    m = np.abs(f - f0) <= max(LINE_WINDOW * f0, 2.0 * df)
    fl = (f >= shaft_hz) & (f <= 20.0 * shaft_hz)
    floor = max(float(np.median(S[fl])) if fl.any() else float(np.median(S)), 1e-300)
    if not m.any():
        return float("nan"), float("nan")
    k = np.flatnonzero(m)[int(np.argmax(S[m]))]
    return float(f[k]), float(20.0 * np.log10(max(S[k], 1e-300) / floor))


def _check(x, fs, what, min_s=MIN_RECORD_S):
    a = np.asarray(x)
    if a.ndim == 2 and 1 in a.shape:
        a = a.ravel()
    if a.dtype.kind not in "biuf" or a.ndim != 1:
        raise InputError(f"{what}: need one channel of numbers (got shape {a.shape}, type {a.dtype})")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{what}: {int(np.sum(~np.isfinite(a)))} of {a.size} samples are NaN or infinite")
    if not (np.isfinite(fs) and fs > 0):
        raise InputError(f"{what}: sample rate {fs!r} Hz: give a finite sample rate > 0 (--sample-rate-Hz)")
    if a.size / fs < min_s or a.size < 64:
        raise InputError(f"{what}: {a.size} samples = {a.size / fs:.3g} s is too short: the spectrum "
                         f"needs at least {min_s:g} s and 64 samples")
    if np.ptp(a) == 0:
        raise InputError(f"{what}: all samples are equal (no signal)")
    return a.astype(np.float64)


def read_overlay(path, item=0) -> tuple[np.ndarray, float, float | None, str]:
    """(signal m/s^2, sample rate, shaft Hz or None, description) of a simulation to overlay: a
    ``bearingsim simulate`` output or item ``item`` of a ``bearingsim dataset`` file."""
    import h5py

    p = Path(path)
    if not p.is_file():
        raise InputError(f"--overlay {p}: no such file")
    try:
        with h5py.File(p, "r") as f:
            is_dataset = "signals" in f and "labels" in f
            if is_dataset:
                n = f["signals"].shape[0]
                if not 0 <= int(item) < n:
                    raise InputError(f"--item {item}: the data set {p} has items 0..{n - 1}")
                x = np.asarray(f["signals"][int(item)], float)
                lab = f["labels"][int(item)]
                fs = float(f.attrs["sample_rate_Hz"])
                shaft = float(lab["shaft_Hz"]) if "shaft_Hz" in lab.dtype.names else None
                if "result" in lab.dtype.names and int(lab["result"]) != 0:
                    raise InputError(f"--overlay {p}: item {item} failed to simulate (result "
                                     f"{int(lab['result'])}): pick another with --item")
                return x, fs, shaft, f"{p.name} item {item}"
    except OSError as e:
        raise InputError(f"--overlay {p}: not a bearingsim simulate or dataset file ({e})") from None
    try:
        sim = read_simulation(p)
    except InputError as e:
        raise InputError(f"--overlay {e}: give a simulate output or a dataset file") from None
    t = sim["time"]
    return (np.asarray(sim["sensor_acceleration"], float), 1.0 / float(t[1] - t[0]),
            float(sim["frequencies"]["shaft_Hz"]), p.name)


def record_spectrum(path, case, *, rpm=None, channel=None, sample_rate=None, unit=None, overlay=None,
                    item=0) -> RecordSpectrum:
    """Spectra of the record file ``path`` with the fault lines of ``case`` (a Case; its bearing
    and, without ``rpm`` or a file rpm, its speed as the search centre); ``overlay``: a
    simulation file (see :func:`read_overlay`)."""
    p = Path(path)
    if p.suffix.lower() not in RECORD_SUFFIXES:
        raise InputError(f"{p}: not a record file: give a .npz, .npy, .csv, .txt or .wav record "
                         "(a `bearingsim simulate` output is read as .h5)")
    x, fs, u, nominal, ch = read_record(p, channel, sample_rate, unit, default_unit="m/s^2")
    a = _check(x, float(fs), str(p)) * UNITS[u]
    if rpm is not None:
        if not (np.isfinite(rpm) and rpm > 0):
            raise InputError(f"--rpm {rpm:g}: a shaft speed > 0 rpm")
        fr, how = float(rpm) / 60.0, "given (--rpm)"
    else:
        centre = nominal if nominal else float(case.data["operation"]["speed_rpm"])
        fr = shaft_speed(a, fs, centre / 60.0)
        how = f"found near {centre:g} rpm ({'the file' if nominal else 'the case'})"
    lines = fault_line_table(case.bearing(), fr)
    if 2.0 * max(lines.values()) >= fs:
        raise InputError(f"{p}: sample rate {fs:g} Hz is below twice the highest fault line "
                         f"({max(lines.values()):.1f} Hz at {60 * fr:.0f} rpm)")
    band = select_band(a, fs)
    env = envelope_spectrum(a, fs, band=band)
    spec = amplitude_spectrum(a, fs)
    strengths = {k: _strength(env, v, fr) for k, v in lines.items()}
    ov = None
    if overlay is not None:
        y, yfs, ysh, what = read_overlay(overlay, item)
        y = _check(y, yfs, f"--overlay {what}", min_s=0.01)
        yb = select_band(y, yfs)
        ov = Overlay(what, yfs, yb, envelope_spectrum(y, yfs, band=yb), ysh)
    return RecordSpectrum(str(p), ch, int(a.size), float(fs), u, case.title, fr, how, lines, band, env, spec,
                          strengths, ov)
