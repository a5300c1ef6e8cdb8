"""Labelled data sets of simulated defect-impact signals (``bearingsim dataset``).

A data set spec is an ordinary case file plus a ``[dataset]`` section (see the case reference):
``count`` item labels (class, speed, radial and axial load, defect length / depth / centre) are
drawn reproducibly with ``numpy.random.default_rng(seed)``, uniform in each [min, max] range, in
four class blocks (:data:`CLASSES`: healthy, outer race, inner race, ball; ``healthy_fraction``,
``outer_fraction``, ``inner_fraction``, ``ball_fraction``), each fault class with its own ranges.
All classes share one compiled program (:func:`bearingsim.dynamics.defect_slots`).  Every item
has its own realism seed (slip, speed fluctuation, noise: the [dynamics] keys), derived from
(seed, index), so an item's signal does not depend on which chunk it falls in.  The items are
simulated ``chunk`` at a time with :func:`bearingsim.dynamics.simulate_batch` (the last chunk
padded so nothing recompiles; the ball Newton steps and substeps fixed once for the data set).

Resumable and interruptible.  Each finished chunk is saved at once (atomically) in the folder
``<path>.partial/`` next to the output; an interrupted run (Ctrl-C, SIGTERM, a crash) keeps
every finished chunk, and running the same command again continues from them (a spec that
differs from the one the folder was started with is refused).  When every chunk is there the
HDF5 file is assembled from the folder in item order (atomically; the folder is then removed),
so the same spec and seed give a bit-identical file however often the run was interrupted.
Memory stays bounded by one chunk.  Ctrl-C / SIGTERM raise :class:`Interrupted` (exit code
130) with a one-line message; nothing temporary is left behind.

``/signals``  float32 (N, T) sensor acceleration, m/s^2 (chunks (1, T), gzip)
``/time``     float64 (T,) s
``/labels``   compound (N,): index, healthy, fault_class (0-3), speed_rpm, radial_N, axial_N,
              spall_length_mm, spall_depth_mm, spall_center_deg (the item's defect, any class),
              effective_depth_mm (the depth the simulation used: spall_depth_mm, or with
              ``depth_rule = "pit"`` the effective depth of a round pit, :func:`pit_depths`),
              bpfo_Hz, ftf_Hz, shaft_Hz, bpfi_Hz, bsf_Hz, result (0 = ok),
              realism_seed, slip_percent, pass_jitter_percent (the std of the item's drawn
              pass-interval factors), unbridged_fraction (of the item's pit under its contact),
              pass_amplitude_cv_percent and pass_delay_sd_percent (its pass-to-pass variability:
              the [dynamics] maxima times that fraction), speed_fluctuation_percent, noise_rms_m_s2

Root attributes ``bearingsim_version``, ``case_toml``, ``seed`` (and ``count``,
``sample_rate_Hz``, ``duration_s``, ``balls``, ``ball_iterations``, ``substeps``, ``scheme``).
Items whose simulation failed keep a zero signal and a result code != 0
(:data:`DatasetResult`: the codes of :mod:`bearingsim.dynamics` plus ``nonfinite_signal`` and
``pit_contact``);
nothing written is NaN.  ``/labels`` has the attributes ``field_units``, ``result_messages``
and ``class_names`` (JSON objects).
"""
from __future__ import annotations

import json
import os
import shutil
import signal
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import dynamics
from ._version import __version__
from .case import check_sampling
from .case.units import from_si, to_si
from .errors import BearingsimError, InputError, ResultCode

__all__ = ["ChunkPlan", "CHUNK_FIELDS", "simulate_chunk", "serial_imap", "pit_depths_batch", "CLASSES", "SPLITS", "transfer_paths", "item_background", "class_counts", "item_locations", "slots_of", "LABEL_FIELDS", "DatasetResult", "DatasetSummary", "Interrupted", "draw_labels",
           "item_seeds", "make_dataset", "partial_path", "pit_depths", "result_messages"]

#: label field -> (numpy dtype, unit)
LABEL_FIELDS: dict[str, tuple[str, str]] = {
    "index": ("<i8", "-"),
    "healthy": ("?", "-"),
    "fault_class": ("<i4", "-"),
    "speed_rpm": ("<f8", "rpm"),
    "radial_N": ("<f8", "N"),
    "axial_N": ("<f8", "N"),
    "spall_length_mm": ("<f8", "mm"),
    "spall_depth_mm": ("<f8", "mm"),
    "effective_depth_mm": ("<f8", "mm"),
    "spall_center_deg": ("<f8", "deg"),
    "bpfo_Hz": ("<f8", "Hz"),
    "ftf_Hz": ("<f8", "Hz"),
    "shaft_Hz": ("<f8", "Hz"),
    "bpfi_Hz": ("<f8", "Hz"),
    "bsf_Hz": ("<f8", "Hz"),
    "result": ("<i4", "-"),
    "realism_seed": ("<u4", "-"),
    "slip_percent": ("<f8", "%"),
    "pass_jitter_percent": ("<f8", "%"),
    "unbridged_fraction": ("<f8", "-"),
    "pass_amplitude_cv_percent": ("<f8", "%"),
    "pass_delay_sd_percent": ("<f8", "%"),
    "speed_fluctuation_percent": ("<f8", "%"),
    "noise_rms_m_s2": ("<f8", "m/s^2"),
    "split": ("<i1", "-"),
    "signal_gain": ("<f8", "-"),
    "snr_dB": ("<f8", "dB"),
    "strike_probability": ("<f8", "-"),
    "background_noise_rms_m_s2": ("<f8", "m/s^2"),
    "background_shaft_rms_m_s2": ("<f8", "m/s^2"),
    "background_line_rms_m_s2": ("<f8", "m/s^2"),
    "background_knock_rate_Hz": ("<f8", "Hz"),
}
#: names of the label field ``split`` (assigned per item and class: ``dataset.split_fractions``)
SPLITS = ("train", "validation", "test")
LABEL_DTYPE = np.dtype([(k, v[0]) for k, v in LABEL_FIELDS.items()])

#: ranges of [dataset], in the order they are drawn
_RANGES = ("speed_rpm", "radial_N", "axial_N", "spall_length_mm", "spall_depth_mm", "spall_center_deg")
#: the four classes (label field ``fault_class`` = index); a fault class's defect location
CLASSES = ("healthy", "outer", "inner", "ball")
#: per fault class: its [dataset] ranges for (length, depth, centre) -- drawn after _RANGES, only
#: for a class with a non-zero fraction (so outer-only specs draw exactly what they always did)
_CLASS_RANGES = {"inner": ("inner_length_mm", "inner_depth_mm", "inner_center_deg"),
                 "ball": ("ball_length_mm", "ball_depth_mm", "ball_spin_angle_deg")}


def _result_members():
    """(name, (code, message, hint)) of the dynamics' result codes, then ``nonfinite_signal``."""
    members = [(m.name, (int(m), m.message, m.hint)) for m in dynamics.RESULTS]
    nonfinite = max(v[0] for _, v in members) + 1
    return members + [("nonfinite_signal", (nonfinite, "the simulated signal is not finite",
                                            "use more [dynamics] substeps; check the structural "
                                            "parameters")),
                      ("pit_contact", (nonfinite + 1, "the healthy quasi-static state at the pit (for its "
                                       "effective depth, dataset.depth_rule = \"pit\") did not converge",
                                       "narrow the [dataset] load and speed ranges"))]


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


def class_counts(ds: dict, n: int) -> dict:
    """Items per class (dict over :data:`CLASSES`): healthy, inner and ball round(fraction x n),
    outer the rest."""
    nh = min(n, int(round(float(ds.get("healthy_fraction", 0.2)) * n)))
    ni = min(n - nh, int(round(float(ds.get("inner_fraction", 0.0)) * n)))
    nb = min(n - nh - ni, int(round(float(ds.get("ball_fraction", 0.0)) * n)))
    return {"healthy": nh, "outer": n - nh - ni - nb, "inner": ni, "ball": nb}


def draw_labels(case) -> np.ndarray:
    """The (N,) label table of the case's [dataset] (frequencies 0 and result 0 until simulated).

    Each range is drawn with ``rng.uniform(min, max, N)`` in the order of :data:`_RANGES` from
    ``numpy.random.default_rng(seed)``, then the inner and the ball ranges (only for a class
    that has items).  Items come in class blocks: healthy (depth and length 0), outer, inner,
    ball (``fault_class`` 0-3, :data:`CLASSES`); ``spall_*`` hold the item's own defect (for a
    ball pit ``spall_center_deg`` is its spin angle at t = 0, the pit on ball 0)."""
    ds = _settings(case)
    n = int(ds["count"])
    rng = np.random.default_rng(int(ds["seed"]))
    lab = np.zeros(n, LABEL_DTYPE)
    lab["index"] = np.arange(n)
    for k in _RANGES:
        lo, hi = ds[k]
        lab[k] = lo if lo == hi else rng.uniform(lo, hi, n)
    counts = class_counts(ds, n)
    start = 0
    for c, name in enumerate(CLASSES):
        sl = slice(start, start + counts[name])
        start += counts[name]
        lab["fault_class"][sl] = c
        if name in _CLASS_RANGES and counts[name]:
            for key, field in zip(_CLASS_RANGES[name], ("spall_length_mm", "spall_depth_mm", "spall_center_deg")):
                lo, hi = ds[key]
                lab[field][sl] = lo if lo == hi else rng.uniform(lo, hi, n)[sl]
    healthy = lab["fault_class"] == 0
    lab["healthy"] = healthy
    lab["spall_length_mm"][healthy] = 0.0
    lab["spall_depth_mm"][healthy] = 0.0
    _draw_randomisation(ds, lab)
    return lab


def _logu(rng, lo, hi, n):
    return np.full(n, float(lo)) if lo == hi else np.exp(rng.uniform(np.log(lo), np.log(hi), n))


def _draw_randomisation(ds, lab):
    """The domain-randomisation labels, from their own stream (SeedSequence([seed, 1001])) so that
    the draws above stay what they always were: outer-pit positions, signal gain, ball strike
    probability, the train / validation / test split per class."""
    n = lab.size
    rng = np.random.default_rng(np.random.SeedSequence([int(ds["seed"]), 1001]))
    pos = ds.get("outer_center_positions_deg")
    outer = lab["fault_class"] == 1
    choice = rng.integers(0, len(pos) if pos else 1, n)
    if pos:
        lab["spall_center_deg"][outer] = np.asarray(pos, float)[choice[outer]]
    lab["signal_gain"] = _logu(rng, *ds.get("signal_gain", (1.0, 1.0)), n)
    snr = ds.get("fault_snr_dB")
    if snr is not None:     # the target ratio; the chunk sets the gain that meets it (label snr_dB)
        lab["snr_dB"] = np.where(lab["fault_class"] > 0, rng.uniform(snr[0], snr[1], n), 0.0)
    lo, hi = ds.get("ball_strike_probability", (1.0, 1.0))
    p = rng.uniform(lo, hi, n) if lo != hi else np.full(n, float(lo))
    lab["strike_probability"] = np.where(lab["fault_class"] == 3, p, 1.0)
    frac = np.asarray(ds.get("split_fractions", (0.7, 0.15, 0.15)), float)
    frac = frac / frac.sum()
    for c in range(len(CLASSES)):
        idx = np.flatnonzero(lab["fault_class"] == c)
        idx = idx[rng.permutation(idx.size)]
        cuts = np.round(np.cumsum(frac)[:-1] * idx.size).astype(int)
        for part, block in enumerate(np.split(idx, cuts)):
            lab["split"][block] = part


def transfer_paths(case, lab) -> np.ndarray:
    """(N, M, 3) sensor modes of every item (frequency Hz, damping ratio, gain): the [dynamics]
    modes, or, per ``[dataset] resonance_*`` range given, drawn per item and mode (frequency and
    gain log-uniform, damping uniform) from SeedSequence([seed, 1002])."""
    ds, d = _settings(case), case.dynamics_settings()
    params = dynamics.DynamicsParameters.from_settings(d)
    f, z, g = (np.asarray(v, float) for v in params.modes())
    n, M = lab.size, f.shape[-1]
    out = np.stack([np.broadcast_to(v, (n, M)) for v in (f, z, g)], -1).copy()
    rng = np.random.default_rng(np.random.SeedSequence([int(ds["seed"]), 1002]))
    for j, (key, log) in enumerate((("resonance_frequency_Hz", True), ("resonance_damping_ratio", False),
                                    ("resonance_gain", True))):
        r = ds.get(key)
        if r is not None:
            lo, hi = r
            v = _logu(rng, lo, hi, n * M) if log else rng.uniform(lo, hi, n * M)
            out[..., j] = np.sort(v.reshape(n, M), axis=1) if j == 0 else v.reshape(n, M)
    return out


def item_background(case, ds, fs):
    """A function (realism seed, shaft Hz, T) -> (background record, labels) of the data set's
    ``background`` setting (None for "none")."""
    from . import background as bgm

    kind = ds.get("background", "none")
    if kind == "none":
        return None
    if kind == "machine":
        sec = case.si("background") if "background" in case.data else {}
        fixed = bgm.Background(tuple(sec.get("shaft_amplitudes") or ()), float(sec.get("line_frequency", 60.0)),
                               tuple(sec.get("line_amplitudes") or ()), float(sec.get("noise_rms", 0.0)),
                               tuple(sec.get("psd_frequencies") or ()), tuple(sec.get("psd_levels") or ()),
                               tuple(sec.get("modulation_depths") or ()), float(sec.get("knock_rate", 0.0)),
                               float(sec.get("knock_amplitude", 0.0)), float(sec.get("knock_frequency", 3000.0)),
                               float(sec.get("knock_damping_ratio", 0.05)))
    rms = tuple(ds.get("background_rms_m_s2", (0.2, 2.0)))

    def draw(seed, shaft_hz, T):
        rng = np.random.default_rng(np.random.SeedSequence([int(seed), 11]))
        bg = fixed if kind == "machine" else bgm.random_background(rng, fs, {"noise_rms_m_s2": rms})
        return bgm.background_signal(rng, T, fs, shaft_hz, bg), bg.as_labels()
    return draw


def _order(fault_class: np.ndarray) -> np.ndarray:
    """Simulation order: the items of every class spread evenly over the run, so that every
    chunk has about the same mix (and the same shapes)."""
    idx = [np.flatnonzero(fault_class == c) for c in range(len(CLASSES))]
    key = np.concatenate([(np.arange(i.size) + 0.5) / max(i.size, 1) for i in idx])
    return np.concatenate(idx)[np.argsort(key, kind="stable")]


def item_locations(lab) -> np.ndarray:
    """Defect location of every item ("outer" for healthy ones: their depth is 0)."""
    names = np.array(["outer", "outer", "inner", "ball"])
    return names[lab["fault_class"]]


def slots_of(lab) -> tuple:
    """The defect locations the data set's program carries (those of its fault classes)."""
    present = set(item_locations(lab[~lab["healthy"]]).tolist())
    return tuple(L for L in ("outer", "inner", "ball") if L in present)


class Interrupted(BearingsimError):
    """The run was interrupted (Ctrl-C / SIGTERM); finished chunks are kept (exit code 130)."""

    exit_code = 130


class _Stop(BaseException):
    def __init__(self, signum):
        super().__init__(signum)
        self.name = signal.Signals(signum).name


@contextmanager
def _signals_stop():
    """SIGINT and SIGTERM raise :class:`_Stop` (so that cleanup runs) while the block runs."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        raise _Stop(signum)

    old = {sg: signal.signal(sg, handler) for sg in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sg, h in old.items():
            signal.signal(sg, h)


def partial_path(path) -> Path:
    """The folder that holds the finished chunks of an unfinished run writing ``path``."""
    path = Path(path)
    return path.with_name(path.name + ".partial")


def item_seeds(seed, n) -> np.ndarray:
    """Realism seed of every item: from (data set seed, item index)."""
    return np.array([np.random.SeedSequence([int(seed), i]).generate_state(1)[0] for i in range(n)],
                    dtype=np.uint32)


def pit_depths(case, lab, chunk, slots, profile="rectangular", imap=None):
    """(depth in m, ok, unbridged fraction) per item for ``[dataset] depth_rule = "pit"`` (and
    for the pass-to-pass variability, which scales with the unbridged fraction of the item's
    pit under the same contact, :func:`bearingsim.pit.pit_unbridged_fraction`): every fault item's defect
    is a round EDM pit of diameter ``spall_length_mm`` and machined depth ``spall_depth_mm``
    narrower than the ball's contact ellipse, and the simulation takes the depth that loses the
    same Hertz load (:func:`bearingsim.pit.pit_depth_of_solution`: the ball keeps rolling on
    the raceway beside the pit; the groove rule of the machined depth would let it drop by its
    sag over the chord, ~w^2 / 4D, and its impacts grow with the square of the size).

    Each item's healthy contact at its own speed and loads comes from one batched quasi-static
    solve per ``chunk`` items (:func:`bearingsim.dynamics.quasi_static_batch` with depth-0
    slots: the program the simulation compiles anyway), with ball 0 at the pit for an outer-race
    pit and at the load-zone centre (azimuth 0: the radial load is along +x) for an inner-race or
    ball pit.  ``ok`` is False where that state did not converge (the item is then flagged
    ``pit_contact``); healthy items get 0 (depth and fraction).  ``imap`` runs the batches
    (:func:`serial_imap` by default; :mod:`bearingsim.distributed` on a Dask cluster): each is
    :func:`pit_depths_batch` of the same items, so the numbers do not depend on where it ran."""
    n = lab.size
    out, ok, unbridged = np.zeros(n), np.ones(n, bool), np.zeros(n)
    faulty = np.flatnonzero(~lab["healthy"])
    batches = [faulty[k:k + chunk] for k in range(0, faulty.size, chunk)]
    for idx, (d, good, u) in (imap or serial_imap)(pit_depths_batch, (case, lab, chunk, slots, profile), batches):
        out[idx], ok[idx], unbridged[idx] = d, good, u
    return out, ok, unbridged


def pit_depths_batch(shared, idx):
    """(depth in m, ok, unbridged fraction) of the fault items ``idx`` (at most ``chunk``; padded
    to ``chunk`` so that every batch is one program): one batch of :func:`pit_depths`; ``shared``
    is ``(case, lab, chunk, slots, profile)``."""
    import jax
    import jax.numpy as jnp

    from .kinematics import Operation
    from .pit import pit_depth_of_solution, pit_unbridged_fraction

    case, lab, chunk, slots, profile = shared
    b = case.bearing()
    loc = item_locations(lab)
    w = to_si(lab["spall_length_mm"], "mm")
    machined = to_si(lab["spall_depth_mm"], "mm")
    center = to_si(lab["spall_center_deg"], "deg")
    control = case.data["operation"]["raceway_control"]
    out, ok, unbridged = np.zeros(idx.size), np.ones(idx.size, bool), np.zeros(idx.size)
    pad = np.concatenate([idx, np.repeat(idx[-1:], chunk - idx.size)])
    m = pad.size
    one = jnp.ones(m)
    op = Operation(jnp.asarray(2 * np.pi * lab["speed_rpm"][pad] / 60.0), control, one, one)
    F = np.zeros((m, 5))
    F[:, 0], F[:, 2] = lab["radial_N"][pad], lab["axial_N"][pad]
    th = np.where(loc[pad] == "outer", center[pad], 0.0)
    zero = np.zeros(m)
    slots_h = dynamics.defect_slots(loc[pad], zero, zero, zero, profile, slots)
    sols = dynamics.quasi_static_batch(b, op, jnp.asarray(F), jnp.asarray(th), slots_h, case.hertz_method)
    host = jax.tree_util.tree_map(np.asarray, sols)
    for j, i in enumerate(idx):
        if int(host.result[j]) != 0:
            ok[j] = False
            continue
        sol_j = jax.tree_util.tree_map(lambda a: a[j], host)
        out[j] = pit_depth_of_solution(sol_j, b, 0, str(loc[i]), w[i], machined[i]).depth
        unbridged[j] = pit_unbridged_fraction(sol_j, b, 0, str(loc[i]), w[i])
    return out, ok, unbridged


def _run_settings(case, lab, extent, depth, center, profile, fs, params):
    """(ball Newton steps, substeps) for the whole data set: :func:`dynamics.batch_settings` on
    the extreme items of every class (:func:`dynamics.extreme_items`: fastest, slowest, most and
    least loaded, largest defect), the largest count, fixed once so that no chunk recompiles."""
    from .defect import Spall
    from .jones import load_vector
    from .kinematics import Operation

    b = case.bearing()
    o = case.data["operation"]
    slots = slots_of(lab)
    loc = item_locations(lab)
    load = lab["radial_N"] + lab["axial_N"]
    size = np.asarray(extent, float) * np.asarray(depth, float)
    check = dynamics.extreme_items(lab["fault_class"], lab["speed_rpm"], load, size)
    its, subs = [], []
    for i in check:
        op = Operation.from_rpm(float(lab["speed_rpm"][i]), o["raceway_control"], True, True)
        F = load_vector(axial=float(lab["axial_N"][i]), radial_x=float(lab["radial_N"][i]))
        sp = tuple(Spall(float(center[i]) if L == loc[i] else 0.0, float(extent[i]) if L == loc[i] else 0.0,
                         float(depth[i]) if L == loc[i] else 0.0, profile, L, 0) for L in slots)
        it, sub = dynamics.batch_settings(b, op, F, sp, case.cage_angle, fs, params, case.hertz_method)
        if it is not None:
            its.append(it)
            subs.append(sub)
    it = dynamics.next_iterations(its)
    return it, max(subs, default=1)


#: layout of the chunk files (2: with the pass-to-pass variability labels); a partial folder of
#: another layout is refused like one of another spec
CHUNK_FORMAT = 3


def _spec_record(case, ds, n, T, fs, chunk):
    return {"bearingsim_version": __version__, "chunk_format": CHUNK_FORMAT, "case_toml": case.text,
            "seed": int(ds["seed"]), "count": n, "samples": T, "sample_rate_Hz": fs, "chunk": chunk}


def _open_partial(folder: Path, spec: dict, settings):
    """The partial folder of this spec (created if absent) and its (ball_iterations, substeps)."""
    f = folder / "spec.json"
    if f.exists():
        try:
            old = json.loads(f.read_text())
        except (OSError, ValueError):
            old = None
        if old is None or {k: old.get(k) for k in spec} != spec:
            raise InputError(f"{folder} holds the finished chunks of a run with a different spec (or "
                             "bearingsim version); delete it to start afresh, or write elsewhere")
        return old["ball_iterations"], old["substeps"]
    it, sub = settings()
    folder.mkdir(parents=True, exist_ok=True)
    _write_atomic(f, lambda fh: fh.write(json.dumps(dict(spec, ball_iterations=it, substeps=sub)).encode()))
    return it, sub


def _write_atomic(path: Path, write):
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with open(tmp, "wb") as fh:
            write(fh)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def _chunk_file(folder: Path, k: int) -> Path:
    return folder / f"chunk_{k:06d}.npz"


_BACKGROUND_FIELDS = ("background_noise_rms_m_s2", "background_shaft_rms_m_s2", "background_line_rms_m_s2",
                      "background_knock_rate_Hz")
#: the per-item label fields a chunk file carries (besides index and signals)
CHUNK_FIELDS = ("result", "bpfo_Hz", "bpfi_Hz", "bsf_Hz", "pass_jitter_percent", "pass_delay_sd_percent",
                 "pass_amplitude_cv_percent", "signal_gain", "snr_dB") + _BACKGROUND_FIELDS


def _simulate_chunk(case, b, lab, idx, chunk, loads, center, extent, depth, profile, params, realism,
                    duration, fs, seeds, it, sub, loc, slots, pit_ok, unbridged, modes=None, background=None,
                    fault_snr=False):
    import equinox as eqx

    m = idx.size
    pad = np.concatenate([idx, np.repeat(idx[-1:], chunk - m)])
    if modes is not None:
        params = eqx.tree_at(lambda p: (p.resonance_frequency, p.resonance_damping_ratio, p.resonance_gain),
                             params, tuple(np.asarray(modes[pad][..., j]) for j in range(3)))
    strike = lab["strike_probability"][pad]
    res = dynamics.simulate_batch(
        b, lab["speed_rpm"][pad], loads[pad], center[pad], extent[pad], depth[pad], profile, params,
        duration, fs, case.cage_angle, location=loc[pad], slots=slots, realism=realism, seeds=seeds[pad],
        control=case.data["operation"]["raceway_control"], hertz_method=case.hertz_method,
        ball_iterations=it, substeps=sub, unbridged=unbridged[pad],
        strike=strike if np.any(strike < 1.0) else None)
    a = np.asarray(res.sensor_acceleration)[:m]
    gain = lab["signal_gain"][idx].copy()
    snr = np.zeros(m)
    bg_labels = {k: np.zeros(m) for k in _BACKGROUND_FIELDS}
    if background is None:
        a = a * gain[:, None]
    else:
        T = a.shape[1]
        rms = lambda v: float(np.sqrt(np.mean(v * v)))  # noqa: E731
        for j, i in enumerate(idx):
            x, lb = background(seeds[i], lab["speed_rpm"][i] / 60.0, T)
            s = rms(a[j] - a[j].mean())
            if fault_snr and lab["fault_class"][i] > 0 and s > 0.0:
                gain[j] = 10.0 ** (lab["snr_dB"][i] / 20.0) * rms(x) / s
            snr[j] = 20.0 * np.log10(gain[j] * s / rms(x)) if s > 0.0 and rms(x) > 0.0 else 0.0
            a[j] = gain[j] * a[j] + x
            for k in _BACKGROUND_FIELDS:
                bg_labels[k][j] = lb[k]
    code = np.asarray(res.result)[:m].astype(np.int32)
    finite = np.all(np.isfinite(a), axis=1)
    code = np.where((code == 0) & ~finite, int(DatasetResult.nonfinite_signal), code)
    code = np.where(pit_ok[idx], code, int(DatasetResult.pit_contact))
    ok = code == 0
    jitter = np.array([r["pass_jitter_percent"] for r in res.realism[:m]])
    delay = np.array([r.get("pass_delay_sd_percent", 0.0) for r in res.realism[:m]])
    cv = np.array([r.get("pass_amplitude_cv_percent", 0.0) for r in res.realism[:m]])
    freq = {k: np.broadcast_to(np.asarray(getattr(res, k), float), (chunk,))[:m]
            for k in ("bpfo_Hz", "bpfi_Hz", "bsf_Hz")}
    return dict(index=idx, signals=np.where(ok[:, None], a, 0.0).astype(np.float32), result=code,
                pass_jitter_percent=jitter, pass_delay_sd_percent=delay, pass_amplitude_cv_percent=cv,
                **bg_labels, signal_gain=gain, snr_dB=snr,
                **{k: np.where(np.isfinite(v) & ok, v, 0.0) for k, v in freq.items()})


def _assemble(case, ds, path, folder, lab, T, ts, fs, duration, it, sub, scheme, chunks, modes):
    """Write the HDF5 file from the finished chunks, in item order (atomically)."""
    import h5py

    from . import io

    n = lab.size
    Z = case.bearing().n_balls
    for k in range(chunks):
        with np.load(_chunk_file(folder, k)) as c:
            idx = c["index"]
            for name in CHUNK_FIELDS:
                lab[name][idx] = c[name]
    lab["ftf_Hz"] = lab["bpfo_Hz"] / Z
    lab["shaft_Hz"] = from_si(to_si(lab["speed_rpm"], "rpm"), "rev_s")
    units = {k: u for k, (_, u) in LABEL_FIELDS.items()}
    with io.atomic_path(path) as tmp:
        with h5py.File(tmp, "w", track_order=True) as f:
            f.attrs["bearingsim_version"] = __version__
            f.attrs["case_toml"] = case.text
            f.attrs["seed"] = int(ds["seed"])
            f.attrs["count"] = n
            f.attrs["balls"] = Z
            f.attrs["sample_rate_Hz"] = fs
            f.attrs["duration_s"] = duration
            f.attrs["ball_iterations"] = int(it)
            f.attrs["substeps"] = int(sub)
            f.attrs["scheme"] = scheme
            sig = f.create_dataset("signals", shape=(n, T), dtype="float32", chunks=(1, T),
                                   compression="gzip", fillvalue=0.0)
            sig.attrs["units"] = "m/s^2"
            sig.attrs["description"] = ("sensor acceleration (sensor modes, slip, speed fluctuation, "
                                        "pass-to-pass variability and noise of the [dynamics] keys); "
                                        "row i has the labels /labels[i]; zero where result != 0")
            for k in range(chunks):                    # one chunk in memory at a time
                with np.load(_chunk_file(folder, k)) as c:
                    for j, i in enumerate(c["index"]):
                        sig[i] = c["signals"][j]
            tp = f.create_dataset("transfer_path", data=modes)
            tp.attrs["units"] = "Hz, -, -"
            tp.attrs["description"] = ("(N, M, 3): every item's sensor modes: frequency (Hz), damping "
                                       "ratio, gain (domain randomisation: [dataset] resonance_*)")
            tm = f.create_dataset("time", data=ts)
            tm.attrs["units"] = "s"
            lb = f.create_dataset("labels", data=lab)
            lb.attrs["units"] = "see field_units"
            lb.attrs["field_units"] = json.dumps(units)     # JSON {field: unit}
            lb.attrs["result_messages"] = json.dumps({str(c): t for c, t in result_messages().items()})
            lb.attrs["class_names"] = json.dumps({str(c): name for c, name in enumerate(CLASSES)})
            lb.attrs["description"] = (
                "one row per item (row i of /signals); fault_class 0 healthy, 1 outer race, 2 inner "
                "race, 3 ball (class_names); healthy items have spall depth and length 0; spall_* are "
                "the item's defect (length on its own surface; for a ball pit spall_center_deg is "
                "its spin angle at t = 0, 0 = in the outer contact, the pit on ball 0); "
                "bpfo_Hz = Z ftf_Hz from the quasi-static cage speed of the item, bpfi_Hz and bsf_Hz "
                "(a pit meets a raceway at 2 bsf_Hz) at its mean loaded contact angle; result 0 = ok; "
                "realism_seed seeds the item's slip, speed fluctuation, noise and pass-to-pass variability")


def serial_imap(fn, shared, items):
    """``(item, fn(shared, item))`` for every item, in this process, in order: how the chunks of
    a data set (and the batches of :func:`pit_depths`) run without a cluster.
    :class:`bearingsim.distributed.DaskRunner` has the same ``imap`` on a Dask cluster."""
    for x in items:
        yield x, fn(shared, x)


@dataclass(frozen=True, eq=False)
class ChunkPlan:
    """Everything the chunks of one data set need, drawn and fixed before any chunk runs
    (picklable: a Dask run sends it once to every worker).  ``simulate_chunk(plan, k)`` is chunk
    ``k``; every chunk pads to ``chunk`` items, so every chunk is the same compiled program."""

    case: object
    lab: np.ndarray
    order: np.ndarray
    chunk: int
    loads: np.ndarray
    center: np.ndarray
    extent: np.ndarray
    depth: np.ndarray
    profile: str
    params: object
    realism: object
    duration: float
    fs: float
    seeds: np.ndarray
    ball_iterations: object
    substeps: int
    loc: np.ndarray
    slots: tuple
    pit_ok: np.ndarray
    unbridged: np.ndarray
    modes: np.ndarray = None        # (N, M, 3) every item's sensor modes (transfer_paths)
    fault_snr: bool = False         # dataset.fault_snr_dB given

    @property
    def chunks(self) -> int:
        return -(-self.lab.size // self.chunk)

    def items(self, k) -> np.ndarray:
        """Item indices of chunk ``k`` (the classes spread evenly over the chunks)."""
        return self.order[k * self.chunk:(k + 1) * self.chunk]


def simulate_chunk(plan: ChunkPlan, k: int) -> dict:
    """Chunk ``k`` of a data set: the arrays of its chunk file (``index``, ``signals`` and the
    per-item label fields the simulation fills).  A pure function of (plan, k): every item's
    realism seed comes from (seed, item index), so the in-process loop and any Dask worker give
    the same bytes."""
    p = plan
    background = item_background(p.case, _settings(p.case), p.fs)
    return _simulate_chunk(p.case, p.case.bearing(), p.lab, p.items(k), p.chunk, p.loads, p.center,
                           p.extent, p.depth, p.profile, p.params, p.realism, p.duration, p.fs, p.seeds,
                           p.ball_iterations, p.substeps, p.loc, p.slots, p.pit_ok, p.unbridged, p.modes,
                           background, p.fault_snr)


def make_dataset(case, path, progress=True, runner=None) -> DatasetSummary:
    """Simulate the [dataset] of ``case`` and write it to ``path`` (HDF5), resumably.

    Finished chunks go to :func:`partial_path` at once; a rerun after an interruption continues
    from them; the file is assembled when all are there.  Ctrl-C / SIGTERM raise
    :class:`Interrupted`.  ``runner``: an object with ``imap(fn, shared, items)`` like
    :func:`serial_imap` (which runs when ``runner`` is None): :class:`bearingsim.distributed.DaskRunner`
    runs the chunks on a Dask cluster; the file is the same.  Returns a :class:`DatasetSummary`
    (``failed``: items with result != 0; ``seconds``: wall time of this run's simulations,
    compilation included)."""
    from tqdm import tqdm

    imap = serial_imap if runner is None else runner.imap
    ds = _settings(case)
    check_sampling(case, ds["speed_rpm"][1], "dataset.speed_rpm max")
    d = case.dynamics_settings()
    b = case.bearing()
    o = case.data["operation"]
    # simulate_batch uses the default centrifugal/gyroscopic flags of Operation
    if not (o["centrifugal"] and o["gyroscopic"]):
        raise InputError(f"{case.source}: [dataset] needs operation.centrifugal and "
                         "operation.gyroscopic true (the batch simulation always includes them)")
    profile = case.data.get("defect", {}).get("profile", "rectangular")
    params = dynamics.DynamicsParameters.from_settings(d)
    realism = dynamics.Realism.from_settings(d)
    fs = float(d["sample_rate"])
    duration = float(ds["duration_s"])
    T = int(round(duration * fs))
    ts = np.arange(T) / fs
    lab = draw_labels(case)
    n = lab.size
    chunk = min(int(ds["chunk"]), n)
    loc = item_locations(lab)
    slots = slots_of(lab)
    radius = {"outer": float(b.outer_raceway_radius), "inner": float(b.inner_raceway_radius),
              "ball": 0.5 * float(b.ball_diameter)}
    extent = to_si(lab["spall_length_mm"], "mm") / np.array([radius[L] for L in loc])
    depth = to_si(lab["spall_depth_mm"], "mm")
    center = to_si(lab["spall_center_deg"], "deg")
    pit_ok, unbridged = np.ones(n, bool), np.zeros(n)
    if ds.get("depth_rule", "machined") == "pit" or realism.pass_variation:
        pit, pit_ok, unbridged = pit_depths(case, lab, chunk, slots, profile, imap=imap)
        if ds.get("depth_rule", "machined") == "pit":
            depth = pit
    lab["unbridged_fraction"] = unbridged
    lab["effective_depth_mm"] = from_si(depth, "mm")
    loads = np.zeros((n, 5))
    loads[:, 0] = lab["radial_N"]
    loads[:, 2] = lab["axial_N"]
    seeds = item_seeds(ds["seed"], n)
    lab["realism_seed"] = seeds
    lab["slip_percent"] = realism.slip_percent
    lab["speed_fluctuation_percent"] = realism.speed_fluctuation_percent
    lab["noise_rms_m_s2"] = realism.noise_rms
    modes = transfer_paths(case, lab)
    order = _order(lab["fault_class"])
    chunks = -(-n // chunk)
    folder = partial_path(path)
    spec = _spec_record(case, ds, n, T, fs, chunk)
    t0 = time.perf_counter()
    done = 0
    bar = None
    try:
        with _signals_stop():
            it, sub = _open_partial(folder, spec, lambda: _run_settings(
                case, lab, extent, depth, center, profile, fs, params))
            todo = [k for k in range(chunks) if not _chunk_file(folder, k).exists()]
            done = sum(min(chunk, n - k * chunk) for k in range(chunks)) - \
                sum(min(chunk, n - k * chunk) for k in todo)
            bar = tqdm(total=n, initial=done, desc="dataset", unit="item",
                       disable=None if progress else True, dynamic_ncols=True)
            plan = ChunkPlan(case, lab, order, chunk, loads, center, extent, depth, profile, params,
                             realism, duration, fs, seeds, it, sub, loc, slots, pit_ok, unbridged,
                             modes, "fault_snr_dB" in ds)
            for k, out in imap(simulate_chunk, plan, todo):     # finished chunks, streamed
                _write_atomic(_chunk_file(folder, k), lambda fh: np.savez(fh, **out))
                done += out["index"].size
                bar.update(out["index"].size)
                del out
            bar.close()
            _assemble(case, ds, path, folder, lab, T, ts, fs, duration, it, sub, "newmark", chunks, modes)
            shutil.rmtree(folder, ignore_errors=True)
    except (_Stop, KeyboardInterrupt) as e:
        if bar is not None:
            bar.close()
        how = e.name if isinstance(e, _Stop) else (str(e) if str(e) in ("SIGINT", "SIGTERM") else "SIGINT")
        if folder.is_dir() and not any(folder.glob("chunk_*.npz")):     # nothing worth keeping
            shutil.rmtree(folder, ignore_errors=True)
        if not folder.exists():
            raise Interrupted(f"{how}: stopped before the first chunk finished; nothing written") from None
        raise Interrupted(f"{how}: stopped with {done} of {n} items finished, kept in {folder}; run "
                          "the same command again to continue") from None
    failed = lab["result"] != 0
    codes, counts = np.unique(lab["result"][failed], return_counts=True)
    return DatasetSummary(Path(path), n, T, int(failed.sum()), time.perf_counter() - t0,
                          {int(c): int(k) for c, k in zip(codes, counts)})
