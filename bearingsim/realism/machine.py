"""Calibrate a data set to your own machine (``bearingsim calibrate``; docs/realism.md,
"Calibrate to your own machine").  Records are read and checked by :mod:`bearingsim.realism.records`;
the background fits are :mod:`bearingsim.realism.background_fit` (NumPy, core); this module builds the
spec, fits the signal gain with simulated items, and runs the end-to-end transfer check.

An ML user with another rig has a healthy record (and perhaps one record of a known fault) and
the bearing's geometry.  :func:`calibrate_machine` fits what such records determine and writes a
data set spec (the template's geometry, structure and [dataset] ranges, with the fitted values)
that ``bearingsim dataset`` runs.  Each quantity by one documented method:

shaft speed
    Given (``shaft_rpm``), or searched within +-10 % of a nominal speed: the frequency whose
    harmonics k = 1..6 stand highest over the local median of the record's amplitude spectrum
    (Hann window, zero-padded 4x; sum of the positive dB excesses), refined to 1/16 of a bin.
supply lines
    50 and 60 Hz are both tried: the mean dB excess of their harmonics l = 1..4 over the local
    median, leaving out harmonics within 3 resolution bins of a shaft harmonic (those cannot be
    told apart from the shaft's own lines and stay in them).  The better one is kept when its
    excess is >= 6 dB; otherwise no supply lines.
line amplitudes
    One linear least-squares fit of a cosine and a sine at every shaft harmonic k f_r (k = 1..6)
    and every kept supply harmonic (below 0.45 fs) to the whole record: amplitude sqrt(a^2 + b^2).
    (A record longer than ``background_fit.MAX_ANALYSIS_SAMPLES`` samples is analysed over its first
    that many, as the output says: the memory stays bounded.)
knocks
    The residual (record minus the fitted lines) is band-passed from 1 kHz to 0.45 fs; samples
    whose Hilbert envelope exceeds 7 robust standard deviations (1.4826 MAD of the band-passed
    signal; a Gaussian envelope exceeds it with probability e^-24.5) are knocks, merged when
    closer than 5 ms.  Rate = knocks / duration; amplitude = the median peak |band-passed
    residual|; frequency = the strongest resonance found (below), damping its fitted ratio.
    Knock segments (20 ms from the onset) are left out of the broadband estimates.
broadband part
    RMS of the residual outside the knock segments (``noise_rms_m_s2``); its shape: the Welch
    PSD (Hann, segments of ~0.1 s) averaged over 48 log-spaced bands from 50 Hz to 0.45 fs
    (``psd_frequencies_Hz`` = band centres, ``psd_levels_dB`` = 10 log10 of the band means).
modulation
    The squared envelope of the broadband part (band-passed from max(500 Hz, 8 f_r, 5 x supply)
    to 0.45 fs): a modulation (1 + m cos 2 pi k f_r t) of noise puts a line 2 m times the
    envelope's mean at k f_r.  The line is the magnitude of the envelope's projection on
    exp(-2 pi i k f_r t), its noise bias removed in power with the mean of six off-line
    projections ((k +- 0.23, 0.31, 0.37) f_r); m_k for k = 1..8, clipped to [0, 0.9].
resonances
    Peaks of the Welch PSD of the residual (~10 Hz bins, smoothed by a 100 Hz moving average)
    between 1 kHz and 0.45 fs with a prominence of at least 3 dB; the strongest (by prominence,
    at most as many as the template has sensor modes).  Damping from the half-power width:
    zeta = width / (2 f_n) at half the peak's prominence above its base (linear PSD), the
    smoothing's width removed in quadrature, clipped to [0.005, 0.3]; a peak no wider than the
    smoothing is a tone and skipped.  The data set draws every sensor mode's frequency in
    [0.85 min, 1.15 max] of the peaks (at most 0.45 fs) and its damping in [0.67, 1.5] x the mean
    fitted ratio; the [dynamics] modes become the peaks (with the template's strongest gains
    when there are fewer peaks than its modes).
levels
    With a fault record of a known class: a few items of that class (:data:`GAIN_ITEMS`) are
    simulated with the spec at the record's speed (no background, signal gain 1, the transfer
    paths drawn as in the data set); the gain is sqrt(max(rms_fault^2 - rms_healthy^2, 0)) /
    median(rms of the items), and ``dataset.signal_gain`` becomes [gain / 3, 3 gain]
    (:data:`GAIN_SPREAD`) and the template's ``fault_snr_dB`` (a level relative to the
    background) is dropped: the fitted level replaces it.  Without one the template's ranges
    stay (``fault_snr_dB``: fault levels relative to this machine's fitted background).

The spec: the template case (geometry, materials, structure, [dataset] classes and size ranges)
with ``dynamics.sample_rate_Hz`` = the record's rate, the [dynamics] measurement noise off (the
machine's broadband part replaces it), ``dataset.background = "machine"``, the fitted
[background], ``dataset.speed_rpm`` = the measured speed +-2.5 % (:data:`SPEED_SPREAD`), and the
fitted resonance / gain ranges.  Records are accelerations in g or m/s^2 (``unit``: no default:
a factor 9.81 is not guessed).
"""
from __future__ import annotations

import copy
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..signals.background import Background
from .background_fit import (MODULATION_HARMONICS, analysed_length, broadband_shape, fit_knocks,
                             fit_lines, modulation_depths, psd_resonances, shaft_speed, supply_lines)
from ..case import case_from_dict, check_sampling, load_case, to_toml
from ..datasets.runner import make_dataset
from ..names import CLASSES
from ..physics.defect import LOCATIONS
from ..errors import InputError, succeeded
from ..output.io import atomic_path
from ..output.report import calibration_text
from .records import UNITS, check_record, read_record
from ..signals.features import fault_orders
from .transfer import REAL_RECORDS, transfer_benchmark, transfer_text

__all__ = ["MachineCalibration", "calibrate_machine", "write_spec", "calibrated_transfer", "CalibratedTransfer",
           "GAIN_ITEMS", "GAIN_SPREAD", "SPEED_SPREAD", "RESONANCE_SPREAD", "DAMPING_SPREAD"]

#: items simulated to fit the signal gain to a fault record
GAIN_ITEMS = 6
#: the signal_gain range is [gain / GAIN_SPREAD, gain x GAIN_SPREAD]
GAIN_SPREAD = 3.0
#: dataset.speed_rpm = measured speed x (1 -+ SPEED_SPREAD)
SPEED_SPREAD = 0.025
#: resonance frequency range: [lo, hi] x the fitted peaks; damping range x the fitted ratio
RESONANCE_SPREAD = (0.85, 1.15)
DAMPING_SPREAD = (0.67, 1.5)
_FAULT_CLASSES = LOCATIONS


# ------------------------------------------------------------------------------ calibration
@dataclass
class MachineCalibration:
    """What :func:`calibrate_machine` fitted, the spec's TOML text and the validated case."""

    case: object
    text: str
    sample_rate_Hz: float
    duration_s: float
    shaft_hz: float
    shaft_source: str                  # "given" or "spectrum"
    background: Background
    line_detected: bool
    line_excess_db: float
    resonances: list                   # [(Hz, damping ratio, prominence dB)]
    resonance_range_Hz: tuple | None
    damping_range: tuple | None
    signal_gain: float | None          # fitted to the fault record (None: template's range)
    signal_gain_range: tuple
    fault: dict = field(default_factory=dict)   # class, rpm, rms, healthy rms, simulated rms
    record_s: float | None = None      # the healthy record's whole length; duration_s: the part analysed


def _record_rms(x):
    x = x - x.mean()
    return float(np.sqrt(np.mean(x * x)))


def _fit_gain(raw, fault_class, rpm, excess, fs, items=GAIN_ITEMS, seed=0, tmpdir=None):
    """(gain, median simulated rms) making items of ``fault_class`` at ``rpm`` match ``excess``."""
    import h5py

    r = copy.deepcopy(raw)
    ds = r["dataset"]
    for c in CLASSES:
        ds[f"{c}_fraction"] = 1.0 if c == fault_class else 0.0
    ds.update(count=int(items), chunk=int(items), speed_rpm=[float(rpm), float(rpm)], background="none",
              signal_gain=[1.0, 1.0], seed=int(seed))
    ds.pop("fault_snr_dB", None)         # the bearing's own signal, unscaled
    case = case_from_dict(r, "<signal gain fit>")
    with tempfile.TemporaryDirectory(dir=tmpdir) as d:
        path = Path(d) / "gain.h5"
        make_dataset(case, path, progress=False)
        with h5py.File(path, "r") as f:
            X = np.asarray(f["signals"], float)
            ok = succeeded(np.asarray(f["labels"])["result"])
    if not ok.any():
        raise InputError(f"the simulated {fault_class} items for the signal-gain fit all failed")
    X = X[ok] - X[ok].mean(axis=1, keepdims=True)
    sim = float(np.median(np.sqrt(np.mean(X * X, axis=1))))
    return excess / sim, sim


def calibrate_machine(healthy, sample_rate, case, *, unit, shaft_rpm=None, nominal_rpm=None, fault=None,
                      fault_class=None, fault_sample_rate=None, fault_rpm=None, count=None, duration_s=None,
                      seed=None, title=None, gain_items=GAIN_ITEMS, source="healthy record",
                      fault_source="fault record") -> MachineCalibration:
    """Fit the machine's background (and, with a fault record, the signal gain) and build the spec.

    ``healthy`` / ``fault``: 1-D accelerations in ``unit`` ("g" or "m/s^2") at ``sample_rate`` /
    ``fault_sample_rate`` (default: the same); ``case``: the template (a Case or a case name /
    path) with a [dataset]; ``shaft_rpm``: the healthy record's speed when known (else searched
    near ``nominal_rpm``, default the template's operation.speed_rpm); ``fault_rpm`` likewise for
    the fault record (default: searched near the healthy speed); ``count``, ``duration_s``,
    ``seed``: override the template's [dataset] values.  Returns a :class:`MachineCalibration`
    (``.case`` validated, ``.text`` its TOML)."""
    tpl = load_case(case) if isinstance(case, (str, Path)) else case
    if "dataset" not in tpl.raw:
        raise InputError(f"{tpl.source}: the template has no [dataset] section (use e.g. dataset_cwru_4class)")
    if unit not in UNITS:
        raise InputError(f"unit {unit!r}: one of {', '.join(UNITS)}")
    if (fault is None) != (fault_class is None):
        raise InputError("a fault record needs its class (--fault-class outer|inner|ball) and a class its record")
    if fault_class is not None and fault_class not in _FAULT_CLASSES:
        raise InputError(f"fault class {fault_class!r}: one of {', '.join(_FAULT_CLASSES)}")
    nominal = float(nominal_rpm if nominal_rpm is not None else tpl.data["operation"]["speed_rpm"])
    top_rpm = 1.1 * float(shaft_rpm if shaft_rpm is not None else nominal)
    x = check_record(healthy, sample_rate, source, tpl, top_rpm) * UNITS[unit]
    fs = float(sample_rate)
    record_s = x.size / fs
    x = x[:analysed_length(x.size)]      # at most background_fit.MAX_ANALYSIS_SAMPLES: bounded memory, said
    x = x - x.mean()
    T = x.size / fs
    if shaft_rpm is not None:
        if not (math.isfinite(float(shaft_rpm)) and float(shaft_rpm) > 0):
            raise InputError(f"shaft speed {shaft_rpm!r} rpm: give a finite speed > 0")
        fr, how = float(shaft_rpm) / 60.0, "given"
    else:
        fr, how = shaft_speed(x, fs, nominal / 60.0), "spectrum"
    F, kept, excess_db = supply_lines(x, fs, fr, T)
    detected = bool(kept) and excess_db >= 6.0
    shaft_amp, line_amp, lines = fit_lines(x, fs, fr, F, kept if detected else ())
    r = x - lines
    M = len(tpl.dynamics_settings().get("resonance_frequencies") or [1])
    res = psd_resonances(r, fs, M)
    kr, ka, keep = fit_knocks(r, fs)
    rb = r[keep]
    noise_rms = _record_rms(rb)
    pf, pl = broadband_shape(rb, fs)
    lo = min(max(500.0, 8.0 * fr, 5.0 * F), 0.3 * fs)
    md = modulation_depths(r, fs, fr, lo, orders=tuple(range(1, MODULATION_HARMONICS + 1)), keep=keep)
    noise_rms /= math.sqrt(1.0 + 0.5 * float(np.sum(md * md)))   # the RMS before the modulation
    kf, kz = (res[int(np.argmax([p[2] for p in res]))][:2] if res else (min(3000.0, 0.3 * fs), 0.05))
    bg = Background(tuple(shaft_amp), F, tuple(line_amp), noise_rms, tuple(pf), tuple(pl), tuple(md),
                    kr, ka if kr > 0 else 0.0, kf, kz)

    raw = copy.deepcopy(tpl.raw)
    raw["title"] = title or f"Data set calibrated to the machine of {Path(source).name}"
    used = f"the first {T:.2f} s of {record_s:.2f} s" if T < record_s else f"{T:.2f} s"
    raw["description"] = (f"Written by bearingsim calibrate from {source} ({used} at {fs:g} Hz, shaft "
                          f"{60 * fr:.1f} rpm from the {how})" + (f" and a {fault_class} fault record" if fault_class else "")
                          + f"; template {tpl.source}.")
    dyn = raw.setdefault("dynamics", {})
    dyn["sample_rate_Hz"] = fs
    dyn["noise_rms_m_s2"] = 0.0
    dyn.pop("noise_band_Hz", None)
    ds = raw["dataset"]
    rpm = 60.0 * fr
    ds["speed_rpm"] = [round(rpm * (1 - SPEED_SPREAD), 3), round(rpm * (1 + SPEED_SPREAD), 3)]
    raw.setdefault("operation", {})["speed_rpm"] = round(rpm, 3)
    if count is not None:
        ds["count"] = int(count)
    if duration_s is not None:
        ds["duration_s"] = float(duration_s)
    if seed is not None:
        ds["seed"] = int(seed)
    ds["chunk"] = min(int(ds.get("chunk", 16)), int(ds["count"]))
    ds["background"] = "machine"
    ds.pop("background_rms_m_s2", None)
    fr_range = z_range = None
    if res:
        fk = [p[0] for p in res]
        zk = [p[1] for p in res]
        fr_range = (round(max(RESONANCE_SPREAD[0] * min(fk), 200.0), 1),
                    round(min(RESONANCE_SPREAD[1] * max(fk), 0.45 * fs), 1))
        zm = float(np.mean(zk))
        z_range = (round(max(DAMPING_SPREAD[0] * zm, 1e-3), 5), round(min(DAMPING_SPREAD[1] * zm, 0.9), 5))
        ds["resonance_frequency_Hz"] = list(fr_range)
        ds["resonance_damping_ratio"] = list(z_range)
        # the [dynamics] modes: the peaks (in frequency order); fewer peaks than the template's
        # modes keep the template's strongest gains
        g = dyn.get("resonance_gains")
        dyn["resonance_frequencies_Hz"] = [round(v, 1) for v in fk]
        dyn["resonance_damping_ratios"] = [round(v, 5) for v in zk]
        if g is not None and len(g) > 1 and len(g) != len(fk):
            dyn["resonance_gains"] = sorted(float(v) for v in g)[-len(fk):]
        dyn.pop("resonance_frequency_Hz", None)
        dyn.pop("resonance_damping_ratio", None)
    raw["background"] = _background_table(bg)
    gain, fault_info = None, {}
    gain_range = tuple(ds.get("signal_gain", (1.0, 1.0)))
    if fault is not None:
        ffs = float(fault_sample_rate if fault_sample_rate is not None else fs)
        if not math.isclose(ffs, fs, rel_tol=1e-9):
            raise InputError(f"{fault_source}: sample rate {ffs:g} Hz differs from the healthy record's "
                             f"{fs:g} Hz: the data set has one rate")
        y = check_record(fault, ffs, fault_source, tpl, top_rpm) * UNITS[unit]
        y = y[:analysed_length(y.size)]
        frf = float(fault_rpm) / 60.0 if fault_rpm is not None else shaft_speed(y, fs, fr, search=0.03)
        rms_f, rms_h = _record_rms(y), _record_rms(x)
        excess = math.sqrt(max(rms_f ** 2 - rms_h ** 2, 0.0))
        if excess <= 0.05 * rms_h:
            raise InputError(f"{fault_source}: its RMS ({rms_f:.4g} m/s^2) is not above the healthy record's "
                             f"({rms_h:.4g} m/s^2): no fault level to fit the signal gain to")
        probe = case_from_dict(raw, "<calibrated spec>")      # validates before simulating
        gain, sim = _fit_gain(probe.raw, fault_class, 60.0 * frf, excess, fs, gain_items)
        gain_range = (round(gain / GAIN_SPREAD, 5), round(gain * GAIN_SPREAD, 5))
        ds["signal_gain"] = list(gain_range)
        ds.pop("fault_snr_dB", None)     # the fitted level replaces the template's ratio to the background
        fault_info = {"class": fault_class, "rpm": 60.0 * frf, "rms_m_s2": rms_f, "healthy_rms_m_s2": rms_h,
                      "excess_rms_m_s2": excess, "simulated_rms_m_s2": sim, "items": int(gain_items)}
    header = ("Data set spec calibrated to a machine by `bearingsim calibrate` (docs/realism.md,\n"
              "\"Calibrate to your own machine\"): run it with `bearingsim dataset SPEC.toml -o data.h5`.")
    text = to_toml(raw, header=header)
    out = case_from_dict(raw, "<calibrated spec>")
    check_sampling(out, out.data["dataset"]["speed_rpm"][1], "dataset.speed_rpm max")
    return MachineCalibration(out, text, fs, T, fr, how, bg, detected, float(excess_db), res, fr_range, z_range,
                              gain, tuple(gain_range), fault_info, record_s)


def _r(v, d=6):
    return float(f"{float(v):.{d}g}")


def _background_table(bg: Background) -> dict:
    t = {"noise_rms_m_s2": _r(bg.noise_rms),
         "psd_frequencies_Hz": [_r(v, 5) for v in bg.psd_frequencies],
         "psd_levels_dB": [round(float(v), 2) for v in bg.psd_levels_db],
         "shaft_amplitudes_m_s2": [_r(v, 4) for v in bg.shaft_amplitudes],
         "line_frequency_Hz": float(bg.line_frequency),
         "modulation_depths": [round(float(v), 4) for v in bg.modulation_depths],
         "knock_rate_Hz": _r(bg.knock_rate, 4),
         "knock_amplitude_m_s2": _r(bg.knock_amplitude, 4),
         "knock_frequency_Hz": round(float(bg.knock_frequency), 1),
         "knock_damping_ratio": _r(bg.knock_damping, 4)}
    if len(bg.line_amplitudes):
        t["line_amplitudes_m_s2"] = [_r(v, 4) for v in bg.line_amplitudes]
    return t


def write_spec(cal: MachineCalibration, path) -> Path:
    """Write the calibrated spec (TOML) atomically."""
    path = Path(path)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(cal.text, encoding="utf-8")
    return path


# ------------------------------------------------------------------------------ transfer check
@dataclass
class CalibratedTransfer:
    """Result of :func:`calibrated_transfer`."""

    calibration: MachineCalibration
    reports: list                      # bearingsim.realism.transfer.TransferReport per classifier
    used: tuple                        # the records the calibration used (file stems)
    tested: tuple                      # the records the benchmark tested on
    count: int
    seconds: float                     # the data set's simulation (compilation included)

    def text(self) -> str:
        return "\n".join([f"calibrated on {', '.join(self.used)} only; tested on the other records: "
                          f"{', '.join(self.tested)}",
                          calibration_text(self.calibration),
                          f"{self.count} items of {self.calibration.case.data['dataset']['duration_s']:g} s "
                          f"at {self.calibration.sample_rate_Hz:g} Hz simulated in {self.seconds:.0f} s",
                          transfer_text(self.reports)])


def calibrated_transfer(template, data_dir, count=400, *, duration_s=0.2, out_dir=None,
                        healthy="cwru_normal_0hp_12k_decimated", fault=None, fault_class=None, seed=0,
                        channel="DE", records=None, progress=False) -> CalibratedTransfer:
    """The issue's check, end to end: calibrate ``template`` (a Case or a name / path) on the
    ``healthy`` record of ``data_dir`` (and at most one ``fault`` record of ``fault_class``),
    simulate ``count`` items of ``duration_s`` at the record's rate, run the transfer benchmark
    (:func:`bearingsim.realism.transfer.transfer_benchmark`, 0.2 s windows) on the real records
    (``records``, default :data:`bearingsim.realism.transfer.REAL_RECORDS`) that the calibration did not
    use.  ``out_dir``: where the spec and the data set go (default: a temporary folder, removed)."""
    data_dir = Path(data_dir)
    tpl = load_case(template) if isinstance(template, (str, Path)) else template
    x, fs, unit, rpm, _ = read_record(data_dir / f"{healthy}.npz", channel)
    kw = {}
    if fault is not None:
        y, ffs, _, _, _ = read_record(data_dir / f"{fault}.npz", channel, unit=unit)
        kw = dict(fault=y, fault_class=fault_class, fault_sample_rate=ffs)
    used = (healthy,) + ((fault,) if fault else ())
    tested = {k: v for k, v in (REAL_RECORDS if records is None else records).items() if k not in used}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(out_dir) if out_dir is not None else Path(tmp)
        cal = calibrate_machine(x, fs, tpl, unit=unit, nominal_rpm=rpm, count=count, duration_s=duration_s,
                                seed=seed, source=f"{healthy}.npz", fault_source=f"{fault}.npz", **kw)
        spec = write_spec(cal, out / "calibrated_spec.toml")
        h5 = out / "calibrated.h5"
        s = make_dataset(load_case(spec), h5, progress=progress)
        reports = transfer_benchmark(h5, data_dir, fault_orders(cal.case.bearing()), 0.2, tested)
    return CalibratedTransfer(cal, reports, used, tuple(tested), int(count), s.seconds)
