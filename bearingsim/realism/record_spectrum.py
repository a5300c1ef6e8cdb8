"""A real record's spectra against a bearing's fault lines (``bearingsim spectrum RECORD``).

Reads a record file (:func:`bearingsim.realism.records.read_record`: .npz, .npy, .csv / .txt, .wav),
finds the shaft speed (given with ``rpm``, else searched within +-10 % of the file's nominal rpm
or the case's speed: :func:`bearingsim.realism.background_fit.shaft_speed`), computes the fault lines of
the case's bearing at that speed (docs/model.md section 8, free contact angle: BPFO, BPFI and its shaft-rate
sidebands BPFI -/+ f_r, 2 BSF, FTF, the shaft), the squared-envelope spectrum in the demodulation
band of largest envelope kurtosis (:func:`bearingsim.signals.envelope.select_band`, searched from
4 x the highest fault line up so that the band is wider than the lines it must carry) and the
amplitude spectrum, and for each line its strength over the local floor with a detection verdict
at a stated false-alarm rate (:mod:`bearingsim.realism.detection`).

An overlay (a ``bearingsim simulate`` output or a ``bearingsim dataset`` file, item ``item``)
gets its own envelope spectrum, in its own band chosen by the same rule among the bands that hold
its energy (:func:`simulation_band`: a simulation's quiet bands hold only numerical dust).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..case import as_scenario
from ..errors import failed, InputError
from ..output.io import read_simulation
from ..physics.kinematics import DefectFrequencies
from ..signals.envelope import amplitude_spectrum, envelope_spectrum, select_band
from ..signals.features import fault_orders
from .background_fit import shaft_speed
from .detection import LINE_WINDOW, line_verdicts, provenance
from .records import RECORD_SUFFIXES, UNITS, read_record

__all__ = ["RecordSpectrum", "Overlay", "record_spectrum", "read_overlay", "fault_line_table", "LINE_WINDOW",
           "MIN_RECORD_S", "bearing_frequencies", "demodulation_band", "simulation_band", "BAND_START",
           "ENERGY_SHARE"]

#: shortest record analysed (s): 10 revolutions of a 600 rpm shaft
MIN_RECORD_S = 0.1
#: the band search starts at this multiple of the highest fault line (a 1/3-octave band starting
#: there is 0.26 x its lower edge wide: wider than the line, with its floor ring)
BAND_START = 4.0
#: an overlay's band: among the fewest 1/3-octave bands, strongest first, that hold this share of
#: its energy (a `bearingsim simulate cwru_6205` output: 6 bands, 1.4-5.7 kHz around its 3.0 / 3.4 kHz
#: modes, the band 4490-5657 Hz; its 18-22.6 kHz band, picked by kurtosis alone, holds 0.3 %)
ENERGY_SHARE = 0.9


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
    strengths: dict           # name -> (measured Hz, dB over the local floor)
    overlay: Overlay | None = None
    verdicts: dict | None = None          # name -> detection.LineVerdict
    frequencies: DefectFrequencies | None = None   # the bearing's at the shaft speed (Hz)
    rate_source: str = "the file"         # where the sample rate came from
    threshold_note: str = ""              # the false-alarm rate and the records it was measured on


def bearing_frequencies(bearing, shaft_hz) -> DefectFrequencies:
    """The :class:`DefectFrequencies` (Hz, floats) of ``bearing`` at ``shaft_hz`` (free contact
    angle, docs/model.md section 8)."""
    return DefectFrequencies(*(float(v) * float(shaft_hz) for v in fault_orders(bearing)))


def fault_line_table(bearing, shaft_hz) -> dict:
    """name -> frequency (Hz) of the fault lines of ``bearing`` at ``shaft_hz`` (free contact
    angle, docs/model.md section 8)."""
    d = bearing_frequencies(bearing, shaft_hz)
    return {"BPFO": d.bpfo, "BPFI": d.bpfi, "BPFI-fr": d.bpfi - d.shaft, "BPFI+fr": d.bpfi + d.shaft,
            "2BSF": d.two_bsf, "FTF": d.ftf, "shaft": d.shaft}


def demodulation_band(x, fs, top_line_hz, what="record", rate_source="the file") -> tuple:
    """The record's demodulation band: the 1/3-octave band of largest envelope kurtosis from
    ``BAND_START`` x the highest fault line ``top_line_hz`` up (or fs/64, if higher), or an
    InputError when the sample rate leaves no such band."""
    f_min = max(float(fs) / 64.0, BAND_START * float(top_line_hz))
    try:
        return select_band(x, fs, f_min=f_min)
    except InputError:
        r = 2.0 ** (1.0 / 6.0)
        need = 2.0 * f_min * r * r / 0.98
        raise InputError(f"{what}: sample rate {float(fs):g} Hz ({rate_source}) leaves no demodulation band "
                         f"from {f_min:.0f} Hz ({BAND_START:g} x the highest fault line, {float(top_line_hz):.0f} "
                         f"Hz) up: the envelope needs a sample rate of at least ~{need:.0f} Hz",
                         "check --sample-rate-Hz: it must be the rate the record was sampled at") from None


def simulation_band(y, fs) -> tuple:
    """A simulation's demodulation band: the 1/3-octave band of largest envelope kurtosis (the
    record's rule) among the fewest bands, strongest first, that hold ``ENERGY_SHARE`` of its
    energy: where its sensor modes put it (a simulated impact's sharp edge rings every band, and
    a quiet band's few impulses have the largest kurtosis of all)."""
    _, centres, kurt = select_band(y, fs, return_kurtosis=True)
    r = 2.0 ** (1.0 / 6.0)
    spec = amplitude_spectrum(y, fs)
    f, P = np.asarray(spec.freqs), np.asarray(spec.amplitude) ** 2
    energy = np.array([P[(f >= c / r) & (f < c * r)].sum() for c in centres])
    order = np.argsort(energy)[::-1]
    share = np.cumsum(energy[order]) / max(energy.sum(), 1e-300)
    core = order[:int(np.searchsorted(share, ENERGY_SHARE)) + 1]
    i = int(core[np.argmax(kurt[core])])
    return float(centres[i] / r), float(centres[i] * r)


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
                if "result" in lab.dtype.names and failed(int(lab["result"])):
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
            float(sim["frequencies"].shaft), p.name)


def record_spectrum(path, case, *, rpm=None, channel=None, sample_rate=None, unit=None, overlay=None,
                    item=0) -> RecordSpectrum:
    """Spectra of the record file ``path`` with the fault lines of ``case`` (a Case; its bearing
    and, without ``rpm`` or a file rpm, its speed as the search centre); ``overlay``: a
    simulation file (see :func:`read_overlay`)."""
    sc = as_scenario(case)
    p = Path(path)
    if p.suffix.lower() not in RECORD_SUFFIXES:
        raise InputError(f"{p}: not a record file: give a .npz, .npy, .csv, .txt or .wav record "
                         "(a `bearingsim simulate` output is read as .h5)")
    x, fs, u, nominal, ch = read_record(p, channel, sample_rate, unit, default_unit="m/s^2")
    rate_source = "--sample-rate-Hz" if sample_rate is not None else "the file"
    a = _check(x, float(fs), str(p)) * UNITS[u]
    if rpm is not None:
        if not (np.isfinite(rpm) and rpm > 0):
            raise InputError(f"--rpm {rpm:g}: a shaft speed > 0 rpm")
        fr, how = float(rpm) / 60.0, "given (--rpm)"
    else:
        centre = nominal if nominal else sc.speed_rpm
        fr = shaft_speed(a, fs, centre / 60.0)
        how = f"found near {centre:g} rpm ({'the file' if nominal else 'the case'})"
    freqs = bearing_frequencies(sc.bearing, fr)
    lines = fault_line_table(sc.bearing, fr)
    top = max(lines.values())
    if 2.0 * top >= fs:
        raise InputError(f"{p}: sample rate {fs:g} Hz ({rate_source}) is below twice the highest fault line "
                         f"({top:.1f} Hz at {60 * fr:.0f} rpm)")
    band = demodulation_band(a, fs, top, str(p), rate_source)
    env = envelope_spectrum(a, fs, band=band)
    spec = amplitude_spectrum(a, fs)
    verdicts = line_verdicts(env, lines, fr, band_width_hz=band[1] - band[0])
    strengths = {k: (v.peak_hz, v.strength_db) for k, v in verdicts.items()}
    ov = None
    if overlay is not None:
        y, yfs, ysh, what = read_overlay(overlay, item)
        y = _check(y, yfs, f"--overlay {what}", min_s=0.01)
        yb = simulation_band(y, yfs)
        ov = Overlay(what, yfs, yb, envelope_spectrum(y, yfs, band=yb), ysh)
    return RecordSpectrum(str(p), ch, int(a.size), float(fs), u, case.title, fr, how, lines, band, env, spec,
                          strengths, ov, verdicts, freqs, rate_source, provenance(a.size / fs))
