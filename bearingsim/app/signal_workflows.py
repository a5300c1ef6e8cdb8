"""The workflows of time signals, case-driven as :mod:`bearingsim.app.workflows`:

============================ =========================================== ======================
function                     result                                      command
============================ =========================================== ======================
:func:`simulate_case`        ``DynamicsResult``                          ``bearingsim simulate``
:func:`compare_case`         :class:`Comparison`                         ``bearingsim compare``
:func:`dataset_case`         ``DatasetSummary`` (file written)           ``bearingsim dataset``
:func:`spectrum_file`        :class:`EnvelopeAnalysis`                   ``bearingsim spectrum``
:func:`calibrate_case`       ``MachineCalibration`` (spec written)       ``bearingsim calibrate``
============================ =========================================== ======================

Nothing here prints or draws; :func:`dataset_case` and :func:`calibrate_case` write the file that
is their result.  Errors as in :mod:`bearingsim.app.workflows`.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import dynamics, warm
from ..case import as_scenario, check_sampling, load_case
from ..datasets.runner import make_dataset
from ..case.units import from_si
from ..errors import failed, InputError, NotConvergedError
from ..output import io
from ..physics import sweep as sweeps
from ..physics.kinematics import DefectFrequencies
from ..realism.records import read_record
from ..signals.envelope import envelope_spectrum, harmonic_peaks, peak_frequency, select_band
from ..signals.lines import fault_lines
from .workflows import check_solution, free_tilt_only

__all__ = ["simulate_case", "compare_case", "dataset_case", "spectrum_file", "calibrate_case", "envelope_band",
           "simulation_spectrum", "Comparison", "EnvelopeAnalysis"]


# ------------------------------------------------------------------------------- dynamics
def simulate_case(case, *, throw=True, progress=None, **kw):
    """The dynamic simulation of a case or its built scenario (``case.build()``, built once here):
    :func:`bearingsim.dynamics.simulate` with everything it says (bearing, operating point, loads,
    defect, cage angle, Hertz method and its ``[dynamics]``: duration, sample rate, seed,
    structure, realism); any keyword of ``simulate`` (``duration``, ``sample_rate``, ``seed``,
    ``params``, ``realism``, ...) overrides it.  The dynamics know nothing of cases.  Raises
    CaseError (an InputError) for a sample rate below twice the highest characteristic frequency
    (:func:`bearingsim.case.check_sampling`)."""
    sc = as_scenario(case)
    free_tilt_only(sc, "the dynamic simulation")
    check_sampling(sc)
    kw.setdefault("realism", sc.realism)
    kw.setdefault("theta0", sc.cage_angle)
    kw.setdefault("seed", sc.seed)
    kw.setdefault("hertz_method", sc.hertz_method)
    duration = kw.pop("duration", sc.duration)
    sample_rate = kw.pop("sample_rate", sc.sample_rate)
    params = kw.pop("params", sc.params)
    # the programs the last run of this case used load in the background meanwhile (two threads)
    with warm.prefetching(f"simulate|{sc.text}"):
        res = dynamics.simulate(sc.bearing, sc.operation, sc.loads, sc.spall, params, duration,
                                sample_rate, progress=progress, throw=False, **kw)
    if throw and failed(int(res.result)):
        code = dynamics.RESULTS(int(res.result))
        raise dynamics.DynamicsError(f"{sc.source}: the dynamic simulation failed: {code.message} after "
                                     f"{res.num_steps} steps", code.hint, code)
    return res


class Comparison(NamedTuple):
    """Result of :func:`compare_case`.  ``rows``: (quantity, unit, quasi-static, dynamic,
    dynamic / quasi-static or NaN where the quasi-static value is ~0)."""

    dynamic: object          # DynamicsResult
    indices: np.ndarray      # samples of the dynamic run that were compared
    quasi_static: object     # JonesSolution (len(indices),) at those cage angles
    rows: list


#: (quantity, unit, |quasi-static| below which no ratio is given, in that unit)
_COMPARED = (("Q_outer", "N", 1e-6), ("Q_inner", "N", 1e-6), ("alpha_outer", "deg", 1e-3),
             ("alpha_inner", "deg", 1e-3))


def compare_case(case, *, throw=True, max_angles=721) -> Comparison:
    """Quasi-static sweep at the cage angles of the dynamic run (subsampled to ``max_angles``),
    an inner spall or a ball pit turned to where it is at each of those instants, with peak
    values side by side.  Needs a ``[dynamics]`` section in the case file."""
    sc = as_scenario(case)
    if not sc.has_dynamics:
        raise InputError(f"{sc.source}: compare needs a [dynamics] section (duration_s, sample_rate_Hz)")
    res = simulate_case(sc)
    th = np.asarray(res.cage_angle)
    idx = np.unique(np.linspace(0, len(th) - 1, min(len(th), max_angles)).astype(int))
    spall = sc.spall
    centers = None          # a turning defect: its centre at each compared instant too
    if spall is not None and spall.location in ("inner", "ball"):
        rate = 1.0 if spall.location == "inner" else float(res.spin_ratio)
        centers = float(spall.center) + rate * np.asarray(res.shaft_angle)[idx]
    qs = sweeps.sweep(sc.bearing, sc.operation, sc.loads, spall, angles=th[idx], centers=centers,
                      hertz_method=sc.hertz_method)
    check_solution(qs, sc, "the quasi-static sweep at the dynamic run's cage angles", throw)

    def ratio(d, s, tol):        # amplification only where the static value is not ~0
        return d / s if abs(s) > tol else np.nan

    rows = []
    for name, unit, tol in _COMPARED:
        d = from_si(np.asarray(getattr(res, name))[idx], unit)
        s = from_si(np.asarray(getattr(qs, name)), unit)
        rows.append((f"max {name}", unit, s.max(), d.max(), ratio(d.max(), s.max(), tol)))
        if name.startswith("alpha"):
            rows.append((f"min {name}", unit, s.min(), d.min(), ratio(d.min(), s.min(), tol)))
    qd = from_si(np.asarray(res.ring_displacement)[idx], "um")
    qq = from_si(np.asarray(qs.displacement)[:, :3], "um")
    for j, lab in enumerate(("x", "y", "axial")):
        amp_s, amp_d = np.ptp(qq[:, j]), np.ptp(qd[:, j])
        rows.append((f"peak-to-peak ring {lab}", "um", amp_s, amp_d, ratio(amp_d, amp_s, 1e-6)))
    return Comparison(res, idx, qs, rows)


def dataset_case(case, path, *, throw=True, progress=False, runner=None, device=None, chunk=None,
                 compression=None):
    """Simulate the case's ``[dataset]`` into ``path`` (HDF5; ``dataset.make_dataset``).  Items
    that failed are in the file with a zero signal and a code; ``throw`` raises after writing
    (not for items excluded as ``fault_not_excited``: :class:`~bearingsim.datasets.DatasetSummary`).
    ``runner``: a :class:`bearingsim.datasets.distributed.DaskRunner` to run the chunks on a Dask cluster
    (same file); None runs them in this process.  ``device`` ("cpu", "gpu", None: JAX's
    default), ``chunk`` (items per chunk; 0: fill the device) and ``compression`` (of /signals)
    as in ``make_dataset``."""
    sc = as_scenario(case)
    free_tilt_only(sc, "the data set")
    summary = make_dataset(sc, path, progress=progress, runner=runner, device=device, chunk=chunk,
                           compression=compression)
    if throw and summary.failed:
        raise NotConvergedError(f"{sc.source}: {summary.failed} of {summary.count} items of the data "
                                f"set failed (written to {path} with labels/result != 0)")
    return summary


# ------------------------------------------------------------------------------- calibrate
def calibrate_case(healthy, output, *, template="dataset_cwru_4class", fault=None, fault_class=None,
                   channel=None, sample_rate=None, rpm=None, fault_rpm=None, unit=None, count=None,
                   duration_s=None, seed=None):
    """Calibrate a data set spec to the machine of a healthy record file (and at most one fault
    record file of a known class) and write it to ``output`` (TOML, atomically): see
    :mod:`bearingsim.realism.machine`.  Record files: .npz (a channel, fs, rpm, units), .npy, .csv / .txt;
    ``sample_rate`` / ``unit`` where the file does not say; ``rpm`` the healthy record's exact
    shaft speed (else searched near the .npz rpm or the template's speed).  Returns the
    ``MachineCalibration``."""
    # local: the machine fits load SciPy (scipy.signal, ~1-2 s), which only `bearingsim calibrate`
    # needs: every other command imports this module without it
    from ..realism.machine import calibrate_machine, write_spec

    tpl = load_case(template)
    x, fs, u, nominal, ch = read_record(healthy, channel, sample_rate, unit)
    kw = {}
    if fault is not None:
        if fault_class is None:
            raise InputError(f"{fault}: a fault record needs its class: --fault-class outer|inner|ball")
        y, ffs, _, _, _ = read_record(fault, ch if str(fault).lower().endswith(".npz") else None,
                                      sample_rate, u)
        kw = dict(fault=y, fault_class=fault_class, fault_sample_rate=ffs, fault_rpm=fault_rpm)
    elif fault_class is not None:
        raise InputError(f"--fault-class {fault_class} without a fault record (--fault RECORD)")
    cal = calibrate_machine(x, fs, tpl, unit=u, shaft_rpm=rpm, nominal_rpm=nominal, count=count,
                            duration_s=duration_s, seed=seed, source=str(healthy),
                            fault_source=str(fault), **kw)
    cal.fault["channel"] = ch
    write_spec(cal, output)
    return cal


# ------------------------------------------------------------------------------- spectra
def envelope_band(sample_rate, resonance_hz):
    """Demodulation band around the structural resonance (kept below 0.45 x the sample rate)."""
    return select_band(np.zeros(16), sample_rate, resonance_hz=min(resonance_hz, 0.45 * sample_rate))


def simulation_spectrum(res, case):
    """Squared-envelope spectrum of a simulation's sensor signal, in the resonance band of a case or scenario."""
    d = as_scenario(case).dynamics
    return envelope_spectrum(np.asarray(res.sensor_acceleration), d["sample_rate"],
                             band=envelope_band(d["sample_rate"], d["resonance_frequency"]))


class EnvelopeAnalysis(NamedTuple):
    """Result of :func:`spectrum_file` (frequencies in Hz)."""

    source: str
    samples: int
    sample_rate: float
    duration: float           # s
    band: tuple
    spectrum: object          # signal.EnvelopeSpectrum
    frequencies: DefectFrequencies  # shaft, ftf, bpfo, bpfi, bsf (Hz) of the simulation
    peak: float               # envelope peak near the fault frequency
    harmonics: list           # (k, measured Hz, amplitude) of k x the fault frequency
    fault: str = "BPFO"       # the defect's line: BPFO (outer race, healthy), BPFI (inner), 2BSF (ball)
    fault_hz: float = 0.0     # its frequency (Hz)
    markers: dict = None      # name -> Hz: the line, its sidebands, FTF / shaft (signal.fault_lines)


def spectrum_file(path, *, resonance_hz=3000.0) -> EnvelopeAnalysis:
    """Envelope analysis of a ``bearingsim simulate`` output: the peak near the defect's own line
    (BPFO for an outer-race spall or a healthy bearing, BPFI for an inner-race spall, 2 BSF for a
    ball pit: :func:`bearingsim.signals.lines.fault_lines`) and its harmonics.  The band is centred on
    the stored case's resonance (else ``resonance_hz``)."""
    sim = io.read_simulation(path)
    t, a, fr = sim["time"], sim["sensor_acceleration"], sim["frequencies"]
    fs = 1.0 / float(t[1] - t[0])
    location = None
    if sim["case"] is not None:
        sc = sim["case"].build()
        resonance_hz = sc.dynamics["resonance_frequency"]
        location = None if sc.spall is None else sc.spall.location
    band = envelope_band(fs, resonance_hz)
    es = envelope_spectrum(a, fs, band=band)
    name, f0, markers = fault_lines(fr, location)
    try:
        fp = peak_frequency(es, f0, rel_window=0.05)
    except ValueError as e:
        raise NotConvergedError(f"{path}: no envelope peak near {name} {f0:.3f} Hz: {e}") from None
    return EnvelopeAnalysis(str(path), t.size, fs, float(t[-1] - t[0]) + 1.0 / fs, band, es, fr, fp,
                            harmonic_peaks(es, f0, n=5, rel_window=0.03), name, f0, markers)
