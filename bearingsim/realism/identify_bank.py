"""The simulated records ``bearingsim identify`` learns from (its *bank*) and its twins: the bank's
spec, building it once with the data set engine (:func:`bearingsim.datasets.make_dataset`), its
cache and lock, the features every bank item (and every record) goes through, and the twin
simulated at an estimate.  Method: docs/identify.md.
"""
from __future__ import annotations

import copy
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

from .background_fit import shaft_speed
from ..case import case_from_dict, load_case
from ..datasets.cached import FileLock, cache_dir
from ..datasets.runner import make_dataset
from ..datasets.writer import CHUNK_FORMAT
from .fault_size import PASS_FEATURE_NAMES, line_frequency, pass_features, surface_speed
from ..names import CLASSES
from ..physics.kinematics import DefectFrequencies
from ..signals.features import fault_orders, octave_bands, window_features
from ..errors import succeeded

__all__ = ["BANK_FS", "BANK_WINDOW_S", "BANK_SEED", "BANK_COUNT", "BUILD_SECONDS_PER_ITEM", "bank_spec",
           "cache_dir", "bank_name", "build_bank", "FileLock", "measured_shaft_speed", "fault_kinematics",
           "bank_features", "prior_range_mm", "twin_spec", "twin_record", "bank_twins"]

#: the bank's sample rate (Hz) and window (s): records are resampled to it and cut into windows of it
BANK_FS = 12000.0
BANK_WINDOW_S = 0.2
#: the bank's seed and size (never the seeds of a test set: bench_identify uses 9001)
BANK_SEED = 7001
BANK_COUNT = 400
#: the build's cost on a 2-core CPU shared with other jobs, per item, compilation included (the
#: estimate printed before a build; docs/identify.md gives the measurements)
BUILD_SECONDS_PER_ITEM = 1.6
#: the compilation of the bank's programs before the first item finishes, on a 2-core CPU (s)
BUILD_COMPILE_S = 120.0


def bank_spec(count=BANK_COUNT, seed=BANK_SEED, template="dataset_cwru_4class"):
    """The bank's data set spec: the shipped four-class spec at 12 kHz, 0.2 s items, without
    ``realism_ingredients``: identify's figures (docs/identify.md, ``benchmarks/bench_identify.py``)
    were measured on a bank without them; the shipped spec's ``race_waviness`` (2026-11-28,
    measured for the transfer benchmark only) enters the bank once bench_identify has measured it."""
    spec = load_case(template) if not hasattr(template, "with_value") else template
    return (spec.with_value("dynamics.sample_rate_Hz", BANK_FS).with_value("dataset.duration_s", BANK_WINDOW_S)
            .with_value("dataset.count", int(count)).with_value("dataset.seed", int(seed))
            .with_value("dataset.realism_ingredients", []))


def bank_name(count, seed) -> str:
    """The cached bank's file name: its size and seed, the data set format it was simulated with
    and a digest of its spec's text (a bank from an older engine, whose random streams or physics
    differ, or from another version of the shipped spec is not reused)."""
    import hashlib

    digest = hashlib.sha256(bank_spec(count, seed).text.encode()).hexdigest()[:8]
    return f"identify_bank_{count}_{seed}_v{CHUNK_FORMAT}_{digest}.h5"


def build_bank(path=None, count=BANK_COUNT, seed=BANK_SEED, progress=True) -> Path:
    """Simulate the bank (``count`` items, ``seed``) into ``path`` (HDF5; None: the bank cache,
    :func:`cache_dir`) unless it is there.  Processes that need the same bank at once (test
    workers, notebooks, two shells) build it once: the others wait on a lock file beside it and
    then read it.  ``progress``: a line on stderr with the estimate before the build (the
    compilation comes first), the data set engine's progress while it runs
    (:func:`bearingsim.datasets.make_dataset`) and a line with the time taken."""
    path = Path(path) if path is not None else cache_dir() / bank_name(count, seed)
    if path.exists():
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    with FileLock(path.with_name(path.name + ".lock")):
        if not path.exists():
            if progress:
                est = BUILD_COMPILE_S + BUILD_SECONDS_PER_ITEM * int(count)
                print(f"identify: simulating its bank once ({int(count)} items, 0.2 s at 12 kHz) into {path}; "
                      f"about {est / 60:.0f} min on a 2-core CPU, the first ~{BUILD_COMPILE_S / 60:.0f} min "
                      "compiling; later calls read it", file=sys.stderr, flush=True)
            t0 = time.perf_counter()
            make_dataset(bank_spec(count, seed), path, progress=progress)
            if progress:
                print(f"identify: bank built in {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    return path


def measured_shaft_speed(x, fs, nominal_hz) -> float:
    """The shaft frequency (Hz) of a record: the harmonic search of
    :func:`bearingsim.realism.background_fit.shaft_speed` within +-10 % of ``nominal_hz``."""
    return float(shaft_speed(np.asarray(x, float) - np.mean(x), fs, nominal_hz))


def fault_kinematics(x, fs, bearing, fr, location, orders=None):
    """(the fault line of ``location`` measured in ``x``, the contact's surface speed over the
    defect in m/s, the :class:`DefectFrequencies` the measured line implies): FTF = BPFO / Z
    (outer), f_r - BPFI / Z (inner), BSF = line / 2 (ball); the others at their nominal orders."""
    o = orders if orders is not None else fault_orders(bearing)
    nom = DefectFrequencies(fr, o.ftf * fr, o.bpfo * fr, o.bpfi * fr, 0.5 * o.two_bsf * fr)
    f_nom = {"outer": nom.bpfo, "inner": nom.bpfi, "ball": nom.two_bsf}[location]
    line = line_frequency(np.asarray(x, float), fs, f_nom, octave_bands(fs), rel=0.03)
    Z = int(bearing.n_balls)
    f = {"outer": nom._replace(bpfo=line.hz, ftf=line.hz / Z),
         "inner": nom._replace(bpfi=line.hz, ftf=fr - line.hz / Z),
         "ball": nom._replace(bsf=0.5 * line.hz)}[location]
    return line, surface_speed(bearing, fr, location, f.ftf, f.bsf), f


def bank_features(path, bearing=None) -> dict:
    """The bank's features (cached as ``<path>.features.npz``): ``wf`` (window features), ``pf``
    (pass features, fault items), ``cls``, ``length_mm``, ``split``, ``fr``."""
    path = Path(path)
    cache = path.with_suffix(".features.npz")
    if cache.exists() and cache.stat().st_mtime >= path.stat().st_mtime:
        with np.load(cache) as z:
            return {k: z[k] for k in z.files}
    if bearing is None:
        bearing = bank_spec(10).bearing()
    with h5py.File(path, "r") as h:
        X = h["signals"][:].astype(float)
        lab = h["labels"][:]
        fs = float(h.attrs.get("sample_rate_Hz", BANK_FS))
    ok = succeeded(lab["result"])
    X, lab = X[ok], lab[ok]
    cls = np.asarray(lab["fault_class"], int)
    nominal = float(bank_spec(10).data["operation"]["speed_rpm"]) / 60.0
    o = fault_orders(bearing)
    fr = np.array([measured_shaft_speed(x, fs, nominal) for x in X])
    wf = window_features(X, fs, fr, o)
    pf = np.zeros((len(X), len(PASS_FEATURE_NAMES)))
    for i in np.flatnonzero(cls > 0):
        line, v, _ = fault_kinematics(X[i], fs, bearing, fr[i], CLASSES[cls[i]], o)
        pf[i] = pass_features(X[i][None], fs, 1.0 / line.hz, v)[0]
    out = {"wf": wf, "pf": pf, "cls": cls, "length_mm": np.asarray(lab["spall_length_mm"], float),
           "split": np.asarray(lab["split"], int), "fr": fr, "fr_true": np.asarray(lab["shaft_Hz"], float),
           "bpfo_Hz": np.asarray(lab["bpfo_Hz"], float), "bpfi_Hz": np.asarray(lab["bpfi_Hz"], float)}
    np.savez(cache, **out)
    return out


def prior_range_mm(spec=None) -> tuple:
    """The bank spec's range of defect lengths (mm) over its fault classes: the prior, outside of
    which a length is not identifiable."""
    ds = (spec if spec is not None else bank_spec(10)).data["dataset"]
    keys = ("spall_length_mm", "inner_length_mm", "ball_length_mm")
    return (float(min(ds[k][0] for k in keys if k in ds)), float(max(ds[k][1] for k in keys if k in ds)))


# ----------------------------------------------------------------------------------- the twin

#: the twin's speed is rounded to this step (rpm), so that twins of records a few rpm apart are
#: the same data set configuration
TWIN_RPM_STEP = 1.0


def twin_spec(r, count=16, seed=8001):
    """The bank's spec narrowed to the estimate ``r`` (an Identification): every item at the
    identified speed (rounded to :data:`TWIN_RPM_STEP`), class and length (the transfer path,
    background, fault level and loads drawn as in the bank): the twin is ``count`` machines like
    the bank's with this fault."""
    raw = copy.deepcopy(bank_spec(count, seed).raw)
    ds = raw["dataset"]
    rpm = round(float(r.rpm) / TWIN_RPM_STEP) * TWIN_RPM_STEP
    ds["speed_rpm"] = [rpm, rpm]
    for k in CLASSES:
        ds[f"{k}_fraction"] = 1.0 if k == r.fault_class else 0.0
    if r.fault_class != "healthy":
        L = r.length_mm if r.length_mm is not None else (float(np.sqrt(np.prod(r.length_interval_mm)))
                                                          if r.length_interval_mm else 0.5334)
        key = {"outer": "spall_length_mm", "inner": "inner_length_mm", "ball": "ball_length_mm"}[r.fault_class]
        ds[key] = [float(L), float(L)]
    return case_from_dict(raw, "identify twin")


def twin_record(r, count=16, progress=False):
    """(records (count, T) in m/s^2, fs) of the simulated twin at the estimate ``r``
    (:func:`twin_spec`, 0.2 s each at 12 kHz).  Its programs are sized for the bank's fastest
    speed (or the twin's, when faster), so a twin at any speed up to it runs the programs kept
    by the first one (:mod:`bearingsim.programs`): only the first twin of a class compiles."""
    spec = twin_spec(r, count)
    top = max(float(bank_spec(10).data["dataset"]["speed_rpm"][1]), float(spec.data["dataset"]["speed_rpm"][1]))
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "twin.h5"
        make_dataset(spec, p, progress=progress, max_speed_rpm=top)
        with h5py.File(p, "r") as h:
            return h["signals"][:].astype(float), BANK_FS


def bank_twins(bank, r, k=8):
    """(records (k, T), fs) of the ``k`` records of ``bank`` (its file, or an identifier trained
    on it) nearest the estimate ``r``
    (its class; nearest in log length and speed): simulations by the engine near the estimate, at
    no new cost (the notebook's twin; :func:`twin_record` simulates the estimate itself)."""
    with h5py.File(getattr(bank, "bank", bank), "r") as h:
        lab = h["labels"][:]
        c = CLASSES.index(r.fault_class)
        idx = np.flatnonzero((lab["fault_class"] == c) & succeeded(lab["result"]))
        if c and r.length_interval_mm:
            L = r.length_mm or float(np.sqrt(np.prod(r.length_interval_mm)))
            d = np.abs(np.log(lab["spall_length_mm"][idx] / L)) + np.abs(lab["speed_rpm"][idx] / r.rpm - 1.0) * 10
        else:
            d = np.abs(lab["speed_rpm"][idx] / r.rpm - 1.0)
        pick = np.sort(idx[np.argsort(d)[:k]])
        return h["signals"][pick].astype(float), float(h.attrs.get("sample_rate_Hz", BANK_FS))
