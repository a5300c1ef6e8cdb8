"""Data set spec and labels: the [dataset] settings, the label fields, the class list and the
label draws.

An item is a pure function of (spec, seed, index): its key is
``jax.random.fold_in(jax.random.PRNGKey(seed), index)`` (:func:`item_keys`) and every random
label of the item is drawn from that key, each from its own sub-key ``fold_in(key, field id)``
(:data:`FIELD_STREAMS`), vectorised over the items (``vmap``) and always on the CPU, so the
labels are the same bytes on every device and for any chunk size or worker count.  The class of
an item comes from its index alone (class blocks of round(fraction x count) items: exact
balance); the train / validation / test split is exact per class (the items of a class ranked
by a uniform drawn from each item's key, cut at the fractions).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import dynamics
from ..case.scenario import as_scenario
from ..case.units import to_si
from ..physics.defect import LOCATIONS
from ..errors import InputError, ResultCode
from ..keys import STREAMS, item_keys as jax_item_keys
from ..names import CLASSES
from ..programs import jit

__all__ = ["LABEL_FIELDS", "LABEL_DTYPE", "SPLITS", "CLASSES", "RANGES", "CLASS_RANGES", "FIELD_STREAMS",
           "DatasetResult", "DatasetSummary", "result_messages", "settings", "class_counts", "class_of_index",
           "item_keys", "item_seeds", "draw_labels", "transfer_paths", "item_locations", "slots_of",
           "simulation_order", "defect_geometry"]

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
    "key": ("<u8", "-"),
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

#: the [dataset] ranges every item draws (speed, loads; the outer / healthy defect ranges)
RANGES = ("speed_rpm", "radial_N", "axial_N", "spall_length_mm", "spall_depth_mm", "spall_center_deg")
#: per class: its [dataset] ranges of (length, depth, centre)
CLASS_RANGES = {"healthy": RANGES[3:], "outer": RANGES[3:],
                "inner": ("inner_length_mm", "inner_depth_mm", "inner_center_deg"),
                "ball": ("ball_length_mm", "ball_depth_mm", "ball_spin_angle_deg")}
#: label -> the sub-key id of its draw (``fold_in(item key, id)``): from :data:`bearingsim.keys.STREAMS`; never renumber (the data set
#: version would change), add new ids at the end
FIELD_STREAMS = {k: STREAMS[k] for k in ("speed_rpm", "radial_N", "axial_N", "spall_length_mm", "spall_depth_mm",
                                         "spall_center_deg", "outer_position", "signal_gain", "snr_dB",
                                         "strike_probability", "split", "realism_seed", "transfer_path")}


def _result_members():
    """(name, (code, message, hint)) of the dynamics' result codes, then ``nonfinite_signal``."""
    members = [(m.name, (int(m), m.message, m.hint)) for m in dynamics.RESULTS]
    nonfinite = max(v[0] for _, v in members) + 1
    return members + [("nonfinite_signal", (nonfinite, "the simulated signal is not finite",
                                            "use more [dynamics] substeps; check the structural "
                                            "parameters")),
                      ("pit_contact", (nonfinite + 1, "the healthy quasi-static state at the pit (for its "
                                       "effective depth, dataset.depth_rule = \"pit\") did not converge",
                                       "narrow the [dataset] load and speed ranges")),
                      ("fault_not_excited", (nonfinite + 2, "the fault makes no impact in the record (its "
                       "pit lies where the ball carries almost no load: effective depth below 10 nm, "
                       "bearingsim.physics.pit.EXCITED_DEPTH_MIN; or a ball pit struck on none of the "
                       "record's passes), so the record would be a healthy bearing's under a fault label; "
                       "excluded",
                       "keep outer_center_positions_deg inside the load zone or raise the axial_N range "
                       "(every ball loaded); a longer duration_s or a higher ball_strike_probability"))]


#: per-item result codes of a data set (``/labels`` field ``result``): the simulation codes of
#: bearingsim.dynamics, plus ``nonfinite_signal``, ``pit_contact`` and ``fault_not_excited`` (an
#: item excluded, not a failure: :class:`DatasetSummary`).  Members carry ``message`` and ``hint``.
DatasetResult = ResultCode("DatasetResult", _result_members(), module="bearingsim.datasets")


def result_messages() -> dict:
    """Result code -> message of every :data:`DatasetResult` member (stored in the file)."""
    return {int(m): m.message for m in DatasetResult}


@dataclass(frozen=True)
class DatasetSummary:
    """What :func:`make_dataset` wrote: ``failed`` items (a simulation failed), ``excluded``
    items (``fault_not_excited``: the simulation is right, but a fault item of it would be a
    healthy record; :func:`bearingsim.datasets.load_dataset` drops both), ``failures``: code ->
    count of every :data:`DatasetResult` code != 0 among them; ``device`` the JAX device the
    chunks ran on; ``chunk`` the items per chunk."""

    path: Path
    count: int
    samples: int
    failed: int
    seconds: float          # wall time of the simulations (compilation included)
    failures: dict = field(default_factory=dict)
    device: str = ""
    chunk: int = 0
    excluded: int = 0

    @property
    def converged(self) -> bool:
        return self.failed == 0

    def message(self) -> list:
        return [f"{n} {DatasetResult(c).message}" for c, n in sorted(self.failures.items())]

    @property
    def seconds_per_item(self) -> float:
        return self.seconds / max(self.count, 1)


def settings(case) -> dict:
    """The [dataset] spec (engineering units) of a case or scenario
    (:class:`~bearingsim.case.Scenario`), or one clear :class:`InputError`."""
    sc = as_scenario(case)
    ds = sc.dataset
    if ds is None:
        raise InputError(f"{sc.source}: no [dataset] section: add one with at least count = N "
                         "(see the case reference)")
    missing = [k for k in RANGES if k not in ds]
    if missing:  # the case reader reports these; guard for hand-built cases
        raise InputError(f"{sc.source}: [dataset] lacks " + ", ".join(f"dataset.{k}" for k in missing))
    return ds


def class_counts(ds: dict, n: int) -> dict:
    """Items per class (dict over :data:`CLASSES`): healthy, inner and ball round(fraction x n),
    outer the rest."""
    nh = min(n, int(round(float(ds.get("healthy_fraction", 0.2)) * n)))
    ni = min(n - nh, int(round(float(ds.get("inner_fraction", 0.0)) * n)))
    nb = min(n - nh - ni, int(round(float(ds.get("ball_fraction", 0.0)) * n)))
    return {"healthy": nh, "outer": n - nh - ni - nb, "inner": ni, "ball": nb}


def class_of_index(ds: dict, n: int) -> np.ndarray:
    """(n,) ``fault_class`` of every item: class blocks in the order of :data:`CLASSES`."""
    counts = class_counts(ds, n)
    return np.repeat(np.arange(len(CLASSES), dtype=np.int32), [counts[c] for c in CLASSES])


def _cpu():
    import jax
    return jax.default_device(jax.devices("cpu")[0])


def item_keys(seed, n, start=0) -> np.ndarray:
    """(n, 2) uint32: the raw key data of items ``start .. start + n - 1``,
    ``jax.random.fold_in(jax.random.PRNGKey(seed), index)``."""
    with _cpu():
        return np.asarray(jax_item_keys(seed, np.arange(start, start + n))).astype(np.uint32)


def _u(k, lo, hi):
    import jax
    import jax.numpy as jnp
    return jnp.where(lo == hi, lo, jax.random.uniform(k, (), jnp.float64, lo, hi))


def _logu(k, lo, hi):
    import jax
    import jax.numpy as jnp
    safe = lambda v: jnp.log(jnp.where(v > 0, v, 1.0))  # noqa: E731
    return jnp.where(lo == hi, lo, jnp.exp(jax.random.uniform(k, (), jnp.float64, safe(lo), safe(hi))))


def _draw_one(key, cls, r):
    """Every random label of one item (a dict of scalars) from its key; ``r``: the spec's ranges
    as arrays (``_tables``)."""
    import jax
    import jax.numpy as jnp
    k = {name: jax.random.fold_in(key, i) for name, i in FIELD_STREAMS.items()}
    out = {f: _u(k[f], r[f][0], r[f][1]) for f in RANGES[:3]}
    for j, f in enumerate(RANGES[3:]):
        out[f] = _u(k[f], r["class"][cls, j, 0], r["class"][cls, j, 1])
    pos = r["positions"]
    choice = jax.random.randint(k["outer_position"], (), 0, pos.shape[0])
    out["spall_center_deg"] = jnp.where((cls == 1) & r["has_positions"], pos[choice], out["spall_center_deg"])
    out["signal_gain"] = _logu(k["signal_gain"], r["signal_gain"][0], r["signal_gain"][1])
    snr = r["snr_dB"][jnp.where(cls == 3, 1, 0)]          # the ball class's own range (ball_fault_snr_dB)
    out["snr_dB"] = jnp.where((cls > 0) & r["has_snr"], _u(k["snr_dB"], snr[0], snr[1]), 0.0)
    out["strike_probability"] = jnp.where(cls == 3, _u(k["strike_probability"], *r["strike"]), 1.0)
    out["split_u"] = jax.random.uniform(k["split"], (), jnp.float64)
    out["realism_seed"] = jax.random.bits(k["realism_seed"], (), jnp.uint32)
    M = r["modes"].shape[0]
    km = jax.random.split(k["transfer_path"], 3)
    modes = []
    for j, log in enumerate((True, False, True)):
        lo, hi = r["mode_ranges"][j]
        v = jax.random.uniform(km[j], (M,), jnp.float64)
        drawn = jnp.exp(jnp.log(lo) + v * (jnp.log(hi) - jnp.log(lo))) if log else lo + v * (hi - lo)
        drawn = jnp.sort(drawn) if j == 0 else drawn
        modes.append(jnp.where(r["mode_given"][j], drawn, r["modes"][:, j]))
    out["transfer_path"] = jnp.stack(modes, -1)
    return out


def _tables(sc, ds):
    """The spec's ranges as float64 arrays (the arguments of the vmapped draw)."""
    rng = lambda key, d=(1.0, 1.0): np.asarray(ds.get(key) or d, float)  # noqa: E731
    r = {f: rng(f) for f in RANGES[:3]}
    r["class"] = np.array([[np.asarray(ds.get(k) or ds[RANGES[3 + j]], float) for j, k in enumerate(CLASS_RANGES[c])]
                           for c in CLASSES])
    pos = ds.get("outer_center_positions_deg")
    r["positions"], r["has_positions"] = np.asarray(pos or [0.0], float), bool(pos)
    r["signal_gain"] = rng("signal_gain")
    snr = rng("fault_snr_dB", (0.0, 0.0))
    r["snr_dB"] = np.stack([snr, np.asarray(ds.get("ball_fault_snr_dB") or snr, float)])     # (2, 2): others, ball
    r["has_snr"] = ds.get("fault_snr_dB") is not None
    r["strike"] = rng("ball_strike_probability")
    params = sc.params
    r["modes"] = np.stack([np.asarray(v, float).reshape(-1) for v in params.modes()], -1)   # (M, 3)
    keys = ("resonance_frequency_Hz", "resonance_damping_ratio", "resonance_gain")
    r["mode_ranges"] = np.array([rng(k) for k in keys])
    r["mode_given"] = np.array([ds.get(k) is not None for k in keys])
    return r


#: the label draw runs on blocks of one fixed width (the last padded, the rest discarded): one
#: program serves every count (a width per power of two traced one more program for each new
#: power: the "traced 1" of a warm 10^5-item run on a GPU, 2026-11-28; ~2 s on 2 cores).  A block
#: draws in ~3 ms on the 2-core CPU, so 16 items pay nothing for it
DRAW_BLOCK = 4096


def _draw(sc, ds, start, n):
    total = int(ds["count"])
    cls = class_of_index(ds, total)[start:start + n]
    r = _tables(sc, ds)             # host arrays: the program takes them as they are (no eager copies)
    flags = {k: r.pop(k) for k in ("has_positions", "has_snr")}
    width = DRAW_BLOCK
    blocks = max(1, -(-n // width))
    padded = np.concatenate([cls, np.zeros(blocks * width - n, cls.dtype)])     # every item's draws are its own
    parts = []
    with _cpu():
        for b in range(blocks):
            o = b * width
            parts.append(_draw_batch(np.int64(int(ds["seed"])), np.arange(start + o, start + o + width, dtype=np.uint32),
                                     padded[o:o + width], r, flags))
    out = {k: np.concatenate([np.asarray(p[k]) for p in parts])[:n] for k in parts[0]}
    keys = out.pop("key").astype(np.uint32)
    return keys, cls, out


@jit
def _draw_batch(seed, index, cls, r, flags):
    """Every item's key (:func:`bearingsim.keys.item_keys`) and label draws, in one kept program
    per spec layout (:mod:`bearingsim.programs`: a warm start neither traces nor runs eager
    one-op programs)."""
    import jax
    keys = jax_item_keys(seed, index)
    out = jax.vmap(lambda key, c: _draw_one(key, c, dict(r, **flags)))(keys, cls)
    out["key"] = keys
    return out


def draw_labels(case) -> np.ndarray:
    """The (N,) label table of the [dataset] of a case or scenario (frequencies 0 and result 0
    until simulated).

    Items come in class blocks (healthy, outer, inner, ball: ``fault_class`` 0-3, :data:`CLASSES`,
    round(fraction x N) items each, outer the rest).  Every item draws from its own key
    (:func:`item_keys`, stored in the label ``key`` as ``word0 << 32 | word1``): speed and loads
    uniform in their ranges; length, depth and centre uniform in its class's ranges (healthy:
    length and depth 0; an outer pit's centre one of ``outer_center_positions_deg``, each entry
    equally likely, when given; for a ball pit ``spall_center_deg`` is its spin angle at t = 0, the
    pit on ball 0); the signal gain log-uniform; the target SNR (fault classes) and the strike
    probability (ball class) uniform; the split exact per class; ``realism_seed`` (uint32, its own
    sub-key) seeds the item's realism draws."""
    sc = as_scenario(case)
    ds = settings(sc)
    n = int(ds["count"])
    keys, cls, d = _draw(sc, ds, 0, n)
    lab = np.zeros(n, LABEL_DTYPE)
    lab["index"] = np.arange(n)
    lab["fault_class"] = cls
    for f in RANGES + ("signal_gain", "snr_dB", "strike_probability", "realism_seed"):
        lab[f] = d[f]
    lab["key"] = (keys[:, 0].astype(np.uint64) << np.uint64(32)) | keys[:, 1].astype(np.uint64)
    healthy = cls == 0
    lab["healthy"] = healthy
    lab["spall_length_mm"][healthy] = 0.0
    lab["spall_depth_mm"][healthy] = 0.0
    frac = np.asarray(ds.get("split_fractions", (0.7, 0.15, 0.15)), float)
    frac = frac / frac.sum()
    for c in range(len(CLASSES)):
        idx = np.flatnonzero(cls == c)
        idx = idx[np.argsort(d["split_u"][idx], kind="stable")]
        cuts = np.round(np.cumsum(frac)[:-1] * idx.size).astype(int)
        for part, block in enumerate(np.split(idx, cuts)):
            lab["split"][block] = part
    return lab


def item_seeds(seed, n) -> np.ndarray:
    """Realism seed (uint32) of items 0 .. n-1: drawn from each item's key (label ``realism_seed``)."""
    import jax
    import jax.numpy as jnp
    keys = item_keys(seed, n)
    with _cpu():
        k = jax.vmap(lambda key: jax.random.fold_in(key, FIELD_STREAMS["realism_seed"]))(jnp.asarray(keys))
        return np.asarray(jax.vmap(lambda kk: jax.random.bits(kk, (), jnp.uint32))(k))


def transfer_paths(case, lab) -> np.ndarray:
    """(N, M, 3) sensor modes of every item (frequency Hz, damping ratio, gain): the [dynamics]
    modes, or, per ``[dataset] resonance_*`` range given, drawn per item and mode from the item's
    key (frequency and gain log-uniform, damping uniform; frequencies sorted)."""
    sc = as_scenario(case)
    ds = settings(sc)
    idx = np.asarray(lab["index"])
    _, _, d = _draw(sc, ds, 0, int(ds["count"]))
    return np.ascontiguousarray(d["transfer_path"][idx])


def item_locations(lab) -> np.ndarray:
    """Defect location of every item ("outer" for healthy ones: their depth is 0)."""
    names = np.array((LOCATIONS[0],) + LOCATIONS)
    return names[lab["fault_class"]]


def slots_of(lab) -> tuple:
    """The defect locations the data set's program carries (those of its fault classes)."""
    present = set(item_locations(lab[~lab["healthy"]]).tolist())
    return tuple(L for L in LOCATIONS if L in present)


def simulation_order(fault_class: np.ndarray) -> np.ndarray:
    """Simulation order: the items of every class spread evenly over the run, so that every
    chunk has about the same mix (and the same shapes)."""
    idx = [np.flatnonzero(fault_class == c) for c in range(len(CLASSES))]
    key = np.concatenate([(np.arange(i.size) + 0.5) / max(i.size, 1) for i in idx])
    return np.concatenate(idx)[np.argsort(key, kind="stable")]


def defect_geometry(bearing, lab):
    """(location, extent rad, depth m, centre rad) of every item's drawn defect (SI)."""
    loc = item_locations(lab)
    radius = {"outer": float(bearing.outer_raceway_radius), "inner": float(bearing.inner_raceway_radius),
              "ball": 0.5 * float(bearing.ball_diameter)}
    extent = to_si(lab["spall_length_mm"], "mm") / np.array([radius[L] for L in loc])
    return loc, extent, to_si(lab["spall_depth_mm"], "mm"), to_si(lab["spall_center_deg"], "deg")
