"""Labelled data sets of simulated defect-impact signals (``bearingsim dataset``).

A data set spec is an ordinary case file plus a ``[dataset]`` section (see the case reference):
``count`` item labels (speed, radial and axial load, spall length / depth / centre) are drawn
reproducibly with ``numpy.random.default_rng(seed)``, uniform in each [min, max] range, the
first ``round(healthy_fraction * count)`` items healthy (spall depth and length 0).  The items
are simulated ``chunk`` at a time with :func:`bearingsim.dynamics.simulate_batch` (the last
chunk padded so nothing recompiles) and streamed into one HDF5 file, written atomically:

``/signals``  float32 (N, T) sensor acceleration, m/s^2 (chunks (1, T), gzip)
``/time``     float64 (T,) s
``/labels``   compound (N,): index, healthy, speed_rpm, radial_N, axial_N, spall_length_mm,
              spall_depth_mm, spall_center_deg, bpfo_Hz, ftf_Hz, shaft_Hz, result (0 = ok)

Root attributes ``bearingsim_version``, ``case_toml``, ``seed`` (and ``count``,
``sample_rate_Hz``, ``duration_s``, ``balls``).  Items whose simulation failed keep a zero signal
and a result code != 0 (:data:`DatasetResult`: the codes of :mod:`bearingsim.dynamics` plus
``nonfinite_signal``); nothing written is NaN.  ``/labels`` has the attributes ``field_units``
and ``result_messages`` (JSON objects).
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import dynamics
from ._version import __version__
from .case import check_sampling
from .case.units import from_si, to_si
from .errors import InputError, ResultCode

__all__ = ["LABEL_FIELDS", "DatasetResult", "DatasetSummary", "draw_labels", "make_dataset",
           "result_messages"]

#: label field -> (numpy dtype, unit)
LABEL_FIELDS: dict[str, tuple[str, str]] = {
    "index": ("<i8", "-"),
    "healthy": ("?", "-"),
    "speed_rpm": ("<f8", "rpm"),
    "radial_N": ("<f8", "N"),
    "axial_N": ("<f8", "N"),
    "spall_length_mm": ("<f8", "mm"),
    "spall_depth_mm": ("<f8", "mm"),
    "spall_center_deg": ("<f8", "deg"),
    "bpfo_Hz": ("<f8", "Hz"),
    "ftf_Hz": ("<f8", "Hz"),
    "shaft_Hz": ("<f8", "Hz"),
    "result": ("<i4", "-"),
}
LABEL_DTYPE = np.dtype([(k, v[0]) for k, v in LABEL_FIELDS.items()])

#: ranges of [dataset], in the order they are drawn
_RANGES = ("speed_rpm", "radial_N", "axial_N", "spall_length_mm", "spall_depth_mm", "spall_center_deg")

#: names of the dynamics' result codes while bearingsim.dynamics still has a plain dict of them
_DYNAMICS_NAMES = {0: "successful", 1: "max_steps_reached", 2: "integration_failed",
                   3: "initial_state_not_converged"}


def _result_members():
    """(name, (code, message, hint)) of the dynamics' result codes, then ``nonfinite_signal``
    (4, or the first code after the dynamics' own)."""
    codes = getattr(dynamics, "RESULTS", None)
    if codes is not None:
        members = [(m.name, (int(m), m.message, m.hint)) for m in codes]
    else:
        members = [(_DYNAMICS_NAMES.get(c, f"code_{c}"), (c, msg, ""))
                   for c, msg in dynamics.RESULT_MESSAGES.items()]
    nonfinite = max([4] + [v[0] + 1 for _, v in members])
    return members + [("nonfinite_signal", (nonfinite, "the simulated signal is not finite",
                                            "tighten [dynamics] rtol/atol; check the structural "
                                            "parameters"))]


#: per-item result codes of a data set (``/labels`` field ``result``): the simulation codes of
#: bearingsim.dynamics, plus ``nonfinite_signal``.  Members carry ``message`` and ``hint``.
DatasetResult = ResultCode("DatasetResult", _result_members(), module=__name__)


def result_messages() -> dict:
    """Result code -> message of every :data:`DatasetResult` member (stored in the file)."""
    return {int(m): m.message for m in DatasetResult}


@dataclass(frozen=True)
class DatasetSummary:
    """What :func:`make_dataset` wrote: ``failed`` items (``failures``: code -> count of the
    :data:`DatasetResult` codes != 0 among them)."""

    path: Path
    count: int
    samples: int
    failed: int
    seconds: float          # wall time of the simulations (compilation included)
    failures: dict = field(default_factory=dict)

    @property
    def converged(self) -> bool:
        return self.failed == 0

    def message(self) -> list:
        return [f"{n} {DatasetResult(c).message}" for c, n in sorted(self.failures.items())]

    @property
    def seconds_per_item(self) -> float:
        return self.seconds / max(self.count, 1)


def _settings(case) -> dict:
    ds = case.data.get("dataset")
    if ds is None:
        raise InputError(f"{case.source}: no [dataset] section: add one with at least count = N "
                         "(see the case reference)")
    missing = [k for k in _RANGES if k not in ds]
    if missing:  # the case reader reports these; guard for hand-built cases
        raise InputError(f"{case.source}: [dataset] lacks " + ", ".join(f"dataset.{k}" for k in missing))
    return ds


def draw_labels(case) -> np.ndarray:
    """The (N,) label table of the case's [dataset] (frequencies 0 and result 0 until simulated).

    Each range is drawn with ``rng.uniform(min, max, N)`` in the order of :data:`_RANGES` from
    ``numpy.random.default_rng(seed)``; items 0 .. round(healthy_fraction N) - 1 are healthy."""
    ds = _settings(case)
    n = int(ds["count"])
    rng = np.random.default_rng(int(ds["seed"]))
    lab = np.zeros(n, LABEL_DTYPE)
    lab["index"] = np.arange(n)
    for k in _RANGES:
        lo, hi = ds[k]
        lab[k] = lo if lo == hi else rng.uniform(lo, hi, n)
    n_h = min(n, int(round(float(ds["healthy_fraction"]) * n)))
    lab["healthy"][:n_h] = True
    lab["spall_length_mm"][:n_h] = 0.0
    lab["spall_depth_mm"][:n_h] = 0.0
    return lab


def _order(healthy: np.ndarray) -> np.ndarray:
    """Simulation order: healthy items spread evenly among the spalled ones, so that every chunk
    has the same shapes (a chunk of healthy items only would pad its spall edge times
    differently and recompile)."""
    h, s = np.flatnonzero(healthy), np.flatnonzero(~healthy)
    key = np.concatenate([(np.arange(h.size) + 0.5) / max(h.size, 1),
                          (np.arange(s.size) + 0.5) / max(s.size, 1)])
    return np.concatenate([h, s])[np.argsort(key, kind="stable")]


def _ball_iterations(case, lab, extent, depth, profile):
    """Lean ball-solver Newton steps for the whole data set (as simulate_batch's "auto", on the
    fastest and the most heavily loaded item), fixed once so that no chunk recompiles."""
    import jax.numpy as jnp

    from .defect import Spall
    from .dynamics import _MAX_ITER, choose_iterations
    from .hertz import stiffness_curve
    from .jones import load_vector, solve
    from .kinematics import Operation

    b = case.bearing()
    o = case.data["operation"]
    curve = stiffness_curve(b, case.hertz_method)
    its = []
    for i in {int(np.argmax(lab["speed_rpm"])), int(np.argmax(lab["radial_N"] + lab["axial_N"]))}:
        op = Operation.from_rpm(float(lab["speed_rpm"][i]), o["raceway_control"], True, True)
        F = load_vector(axial=float(lab["axial_N"][i]), radial_x=float(lab["radial_N"][i]))
        sp = Spall(float(to_si(lab["spall_center_deg"][i], "deg")), float(extent[i]), float(depth[i]), profile)
        sol = solve(b, op, F, cage_angle=case.cage_angle, spall=sp, hertz_method=case.hertz_method,
                    throw=False)
        if int(sol.result) != 0:
            continue
        its.append(choose_iterations(b, op, jnp.asarray(sol.displacement), sp, curve, case.cage_angle))
    if not its or 0 in its:
        return 0
    return min(max(its) + 1, _MAX_ITER)


def make_dataset(case, path, progress=True) -> DatasetSummary:
    """Simulate the [dataset] of ``case`` and write it to ``path`` (HDF5, atomically).

    Memory stays bounded by one chunk whatever the count: each chunk is written as soon as it
    is simulated.  Returns a :class:`DatasetSummary` (``failed``: items with result != 0)."""
    import h5py
    from tqdm import tqdm

    ds = _settings(case)
    check_sampling(case, ds["speed_rpm"][1], "dataset.speed_rpm max")

    from . import io
    from .dynamics import DynamicsParameters, _time_grid, simulate_batch

    d = case.dynamics_settings()
    b = case.bearing()
    Z = b.n_balls
    o = case.data["operation"]
    # simulate_batch uses the default raceway control/centrifugal/gyroscopic flags of Operation
    if not (o["centrifugal"] and o["gyroscopic"]):
        raise InputError(f"{case.source}: [dataset] needs operation.centrifugal and "
                         "operation.gyroscopic true (the batch simulation always includes them)")
    profile = case.data.get("defect", {}).get("profile", "rectangular")
    params = DynamicsParameters.from_settings(d)
    fs = float(d["sample_rate"])
    duration = float(ds["duration_s"])
    ts = _time_grid(duration, fs)
    T = ts.size
    lab = draw_labels(case)
    n = lab.size
    chunk = min(int(ds["chunk"]), n)
    R_o = float(b.outer_raceway_radius)
    # healthy items: depth 0 (that is what healthy means to the model) over a spall of the
    # largest length of the range, so that the step limit of the chunk (a quarter of the time
    # a ball takes to cross its shortest spall) is not driven to zero
    sim_len = to_si(np.where(lab["healthy"], float(ds["spall_length_mm"][1]), lab["spall_length_mm"]), "mm")
    extent = sim_len / R_o
    depth = to_si(lab["spall_depth_mm"], "mm")
    center = to_si(lab["spall_center_deg"], "deg")
    loads = np.zeros((n, 5))
    loads[:, 0] = lab["radial_N"]
    loads[:, 2] = lab["axial_N"]
    order = _order(lab["healthy"])
    iterations = _ball_iterations(case, lab, extent, depth, profile)
    units = {k: u for k, (_, u) in LABEL_FIELDS.items()}
    failed = 0
    t0 = time.perf_counter()
    with io.atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["bearingsim_version"] = __version__
            f.attrs["case_toml"] = case.text
            f.attrs["seed"] = int(ds["seed"])
            f.attrs["count"] = n
            f.attrs["balls"] = Z
            f.attrs["sample_rate_Hz"] = fs
            f.attrs["duration_s"] = duration
            f.attrs["ball_iterations"] = int(iterations)
            sig = f.create_dataset("signals", shape=(n, T), dtype="float32", chunks=(1, T),
                                   compression="gzip", fillvalue=0.0)
            sig.attrs["units"] = "m/s^2"
            sig.attrs["description"] = ("sensor (resonator) acceleration; row i has the labels "
                                        "/labels[i]; zero where result != 0")
            tm = f.create_dataset("time", data=ts)
            tm.attrs["units"] = "s"
            msgs = result_messages()
            bar = tqdm(total=n, desc="dataset", unit="item", disable=None if progress else True,
                       dynamic_ncols=True)
            try:
                for k in range(0, n, chunk):
                    idx = order[k:k + chunk]
                    m = idx.size
                    pad = np.concatenate([idx, np.repeat(idx[-1:], chunk - m)])
                    seed = int(np.random.SeedSequence([int(ds["seed"]), k // chunk]).generate_state(1)[0])
                    res = simulate_batch(
                        b, lab["speed_rpm"][pad], loads[pad], center[pad], extent[pad], depth[pad],
                        profile, params, duration, fs, case.cage_angle, d["rtol"], d["atol"],
                        d["noise_rms"], seed, o["raceway_control"], case.hertz_method,
                        ball_iterations=iterations)
                    a = np.asarray(res.sensor_acceleration)[:m]
                    code = np.asarray(res.result)[:m].astype(np.int32)
                    bpfo = np.asarray(res.bpfo_Hz)[:m]
                    finite = np.all(np.isfinite(a), axis=1)
                    code = np.where((code == 0) & ~finite, int(DatasetResult.nonfinite_signal), code)
                    ok = code == 0
                    a = np.where(ok[:, None], a, 0.0).astype(np.float32)
                    bpfo = np.where(np.isfinite(bpfo), bpfo, 0.0)
                    lab["result"][idx] = code
                    lab["bpfo_Hz"][idx] = bpfo
                    lab["ftf_Hz"][idx] = bpfo / Z
                    lab["shaft_Hz"][idx] = from_si(to_si(lab["speed_rpm"][idx], "rpm"), "rev_s")
                    for j, i in enumerate(idx):       # rows out of order; one (1, T) chunk each
                        sig[i] = a[j]
                    failed += int(np.sum(~ok))
                    bar.update(m)
                    if failed:
                        bar.set_postfix(failed=failed)
            finally:
                bar.close()
            lb = f.create_dataset("labels", data=lab)
            lb.attrs["units"] = "see field_units"
            lb.attrs["field_units"] = json.dumps(units)     # JSON {field: unit}
            lb.attrs["result_messages"] = json.dumps({str(c): t for c, t in msgs.items()})
            lb.attrs["description"] = (
                "one row per item (row i of /signals); healthy items have spall depth and length 0; "
                "bpfo_Hz = Z ftf_Hz from the quasi-static cage speed of the item; result 0 = ok")
    codes, counts = np.unique(lab["result"][lab["result"] != 0], return_counts=True)
    return DatasetSummary(Path(path), n, T, failed, time.perf_counter() - t0,
                          {int(c): int(k) for c, k in zip(codes, counts)})
