"""The device program of a data set: one chunk of items in, its signals and simulated labels out.

:func:`simulate_chunk` (plan, k) is the unit of work (in-process and on the Dask workers).  It
pads chunk ``k`` to a multiple of the micro-batch width W (:func:`micro_batch`: cpu 4, gpu
up to 8192 by the device's memory) with its last item and calls :func:`device_program` once: per micro-batch of W items the
chunk program of :func:`bearingsim.dynamics.chunk_program` (quasi-static states and the pits'
effective depths, the Newton step count of the micro-batch from its menu, motion and the
record's time loop) and the signal stage :func:`bearingsim.signals.signal_stage.finish_items` (pass
variability and strikes, noise, background, fault level, issue 26's ingredients), every draw
from the item's key (:mod:`bearingsim.keys`).  The host puts the chunk's label arrays on the
device and takes the outputs back, both explicitly; it draws nothing and loops over no item.
Every program runs W items wide whatever the chunk size, so the bytes of an item do not depend
on the chunk size or the worker count (on the same device type).

Also here: :func:`run_settings` (the data set's substeps, fixed once).  The pits' effective
depths and unbridged fractions (``depth_rule = "pit"``, and the pass variability's scale under
``depth_rule = "machined"``) are computed inside the chunk program, from each item's healthy
contact: there is no host version.
"""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, succeeded
from .. import dynamics, warm
from ..case.units import from_si, to_si
from ..physics.defect import LOCATIONS, Spall
from ..physics.jones import load_vector
from ..physics.kinematics import Operation
from ..physics.pit import excited
from ..signals.signal_stage import ItemDraws, finish_items
from .spec import DatasetResult, item_locations, slots_of

__all__ = ["CHUNK_FIELDS", "BACKGROUND_FIELDS", "MICRO_BATCH", "DEFAULT_MICRO_BATCH", "Physics", "micro_batch", "program_threads",
           "chunk_keys", "plan_speed", "plan_program", "device_program", "simulate_chunk",
           "run_settings"]

BACKGROUND_FIELDS = ("background_noise_rms_m_s2", "background_shaft_rms_m_s2", "background_line_rms_m_s2",
                     "background_knock_rate_Hz")
#: the per-item label fields a chunk file carries (besides index and signals)
CHUNK_FIELDS = ("result", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz", "pass_jitter_percent", "pass_delay_sd_percent",
                "pass_amplitude_cv_percent", "signal_gain", "snr_dB", "effective_depth_mm",
                "unbridged_fraction") + BACKGROUND_FIELDS


@dataclass(frozen=True, eq=False)
class Physics:
    """The built physics objects every item of a data set shares (SI; no case file)."""

    bearing: object
    params: object              # dynamics.DynamicsParameters
    realism: object             # dynamics.Realism
    control: str
    hertz_method: str
    cage_angle: float
    profile: str

    @classmethod
    def of_scenario(cls, sc):
        """The physics of a :class:`~bearingsim.case.Scenario` (``case.build()``)."""
        return cls(sc.bearing, sc.params, sc.realism, sc.control, sc.hertz_method, float(sc.cage_angle), sc.profile)


#: the micro-batch width W of the device programs per JAX platform: every program call is W items
#: wide (the chunk is a loop over its micro-batches), so that an item's bytes do not depend on the
#: chunk size or the worker count (XLA's kernels may round the last bits by batch width).  A GPU's
#: entry is the widest W; :func:`micro_batch` narrows it to what the device's memory holds.
MICRO_BATCH = {"cpu": 4, "gpu": 8192}
#: W of a platform not in :data:`MICRO_BATCH`
DEFAULT_MICRO_BATCH = 1024
#: device memory per item and sample of a micro-batch's programs (states, accelerations, sensor,
#: signal stage), and the share of the device memory a micro-batch may take.  Measured on an H200
#: (jax 0.11.2, 2026-11-28, benchmarks/bench_gpu.py): the process's peak device memory was 112 B
#: per item and sample at W 8192 (4.12 GiB) and at W 32768 (16.46 GiB); 128 keeps a margin.
GPU_BYTES_PER_SAMPLE = 128
GPU_MEMORY_SHARE = 0.25


def micro_batch(platform, dev=None, samples=None, count=None) -> int:
    """The micro-batch width W of JAX platform ``platform`` ("cpu", "gpu", ...; None: JAX's default).

    * cpu: 4 (the four-class spec, warm programs, in-process wall on 2 cores, 2026-11-28: 16
      items W 16 6.9 s, W 8 5.9 s, W 4 3.9-4.1 s, W 2 5.0 s; 512 items W 16 ~30.5 s, W 8 27.6 s,
      W 4 25.5-27.4 s, W 2 32.3 s; 128 items W 16 3.4 s, W 64 5.9 s on 2026-11-25: a narrow
      micro-batch runs its Newton loops and its menu's step count for fewer items at once, and
      two of them keep both cores busy even for 8 items);
    * gpu: the largest power of two up to 8192 whose items of ``samples`` samples fit in a
      quarter of the device's memory at :data:`GPU_BYTES_PER_SAMPLE` bytes per item and sample
      (8192 for 4800 samples on an 80 GB H100 or a 141 GB H200).  Measured on one H200 (jax
      0.11.2, 2026-11-28, ``benchmarks/bench_gpu.py``, four-class 0.1 s items at 48 kHz, a
      W-item data set's second call in one process): W 8192 2621-2808 items/s, W 32768 3344
      items/s; 10^5 items as a whole command 49.7 s at W 8192 and 48.2 s at W 32768 (which pads
      10^5 items to 131 072).  8192 kept: the wider width's 19 % did not reach the whole command
      and would have changed every GPU item's bytes.  (Earlier, issue 32's CEO run: 32 768 items
      ~2.6x as fast at W 8192 as at W 1024.)  W depends on the device's memory and the item
      length only, so one GPU model and one spec give identical bytes for any chunk size and
      worker count.  A data set of fewer items (``count``) runs at the power of two that holds
      them, at least 1024 (16 items: 6.7-6.9 s as a whole command on the H200, 3.9 s of it the
      call), so on a GPU an item's last bits may depend on the count below 8192 items (never on
      the chunk size or the workers);
    * other platforms: :data:`DEFAULT_MICRO_BATCH`."""
    if platform is None:
        import jax
        dev = jax.devices()[0] if dev is None else dev
        platform = dev.platform
    W = MICRO_BATCH.get(str(platform), DEFAULT_MICRO_BATCH)
    if str(platform) == "gpu" and dev is not None and samples:
        try:
            mem = int((dev.memory_stats() or {}).get("bytes_limit", 16 << 30))
        except Exception:       # noqa: BLE001 - a backend without memory_stats
            mem = 16 << 30
        fit = int(GPU_MEMORY_SHARE * mem // (GPU_BYTES_PER_SAMPLE * int(samples)))
        while W > 256 and W > fit:
            W //= 2
    if str(platform) == "gpu" and count:
        need = 1 << max(int(count) - 1, 0).bit_length()
        W = min(W, max(need, min(W, 1024)))
    return W


def program_threads(dev) -> int:
    """Micro-batches run at once on device ``dev``: on a CPU one per core (a compiled time loop
    runs on one core; two micro-batches in two threads ran 1.7x as fast on 2 cores), else 1 (a
    GPU fills itself with one W-wide program).  ``BEARINGSIM_THREADS`` overrides the CPU count."""
    if getattr(dev, "platform", "cpu") != "cpu":
        return 1
    v = os.environ.get("BEARINGSIM_THREADS", "").strip()
    return max(1, int(v)) if v.isdigit() else max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                                                   else (os.cpu_count() or 1))


def chunk_keys(lab_key) -> np.ndarray:
    """(N, 2) uint32 key data of the label field ``key`` (word0 << 32 | word1)."""
    k = np.asarray(lab_key, np.uint64)
    return np.stack([(k >> np.uint64(32)).astype(np.uint32), (k & np.uint64(0xFFFFFFFF)).astype(np.uint32)], -1)


_PROGRAMS: dict = {}


def plan_speed(plan) -> float:
    """The fastest shaft speed (rpm) the programs of ``plan`` are sized for (slip walk knots,
    pass lists): the spec's upper speed bound, so that another count or seed of the same spec
    runs the same compiled programs (the drawn items' maximum, where a plan has no bound)."""
    drawn = float(np.max(plan.lab["speed_rpm"]))
    bound = getattr(plan, "max_speed_rpm", None)
    return drawn if bound is None else max(float(bound), drawn)


def plan_program(plan):
    """The :class:`bearingsim.dynamics.ChunkProgram` of ``plan`` (built once per plan and process:
    the plan is pickled to Dask workers without it) and the plan's per-width constants."""
    import jax
    import jax.numpy as jnp

    key = id(plan)
    hit = _PROGRAMS.get(key)
    if hit is not None and hit[0] is plan:
        return hit[1], hit[2]
    ph = plan.physics
    T = int(round(plan.duration * plan.fs))
    prog = dynamics.chunk_program(ph.bearing, slots=plan.slots, profile=ph.profile, control=ph.control,
                                  hertz_method=ph.hertz_method, sample_rate=plan.fs, samples=T,
                                  substeps=plan.substeps, scheme="newmark", realism=ph.realism,
                                  max_speed_rpm=plan_speed(plan))
    W = plan.width
    dev = jax.devices(plan.device)[0] if plan.device else jax.devices()[0]
    params = jax.device_put(jax.tree_util.tree_map(lambda a: np.broadcast_to(a, (W,)) if np.ndim(a) == 0 else a,
                                                   ph.params), dev)
    if len(_PROGRAMS) > 4:
        _PROGRAMS.clear()
    _PROGRAMS[key] = (plan, prog, (dev, params))
    return prog, (dev, params)


def _host_inputs(plan, pad):
    """The per-item inputs of the padded items ``pad`` as host arrays (no per-item work)."""
    lab = plan.lab[pad]
    n = pad.size
    loads = np.zeros((n, 5))
    loads[:, 0], loads[:, 2] = lab["radial_N"], lab["axial_N"]
    li = np.select([plan.loc[pad] == L for L in LOCATIONS], list(range(len(LOCATIONS))), 0)
    modes = np.asarray(plan.modes[pad], float)
    sim = dict(keys=chunk_keys(lab["key"]), speed_rpm=np.asarray(lab["speed_rpm"], float), loads=loads,
               theta0=np.full(n, float(plan.physics.cage_angle)), location=li.astype(np.int32),
               center=np.asarray(plan.center[pad], float), extent=np.asarray(plan.extent[pad], float),
               depth=np.asarray(plan.depth[pad], float), modes=tuple(np.ascontiguousarray(modes[..., j])
                                                                    for j in range(3)))
    if plan.pit or plan.unbridged:
        sim["pit"] = (to_si(np.asarray(lab["spall_length_mm"], float), "mm"),
                      to_si(np.asarray(lab["spall_depth_mm"], float), "mm"))
    draws = ItemDraws(modes, np.asarray(lab["signal_gain"], float), np.asarray(lab["snr_dB"], float),
                      np.asarray(lab["strike_probability"], float), np.asarray(lab["spall_center_deg"], float))
    sig = dict(fault_class=np.asarray(lab["fault_class"], np.int32), draws=draws)
    return sim, sig


def device_program(plan, pad, threads=None):
    """The chunk's programs on the padded item indices ``pad`` (a multiple of ``plan.width``
    items): per micro-batch of W = ``plan.width`` items the chunk program
    (:func:`bearingsim.dynamics.chunk_program`: states, pit depths, Newton count, motion, time
    loop) and the signal stage (:func:`bearingsim.signals.signal_stage.finish_items`: pass variability,
    strikes, noise, background, fault level, issue 26's ingredients), every draw from the item's
    key.  The inputs go to the device explicitly (``jax.device_put``) and the outputs come back
    explicitly (``jax.device_get``): no implicit transfer and no per-item host work.  The
    micro-batches run in ``threads`` threads (None: :func:`program_threads`; 1 when the caller
    already runs chunks side by side).  Returns a dict of (len(pad),) / (len(pad), T) host
    arrays: the signals and :data:`CHUNK_FIELDS`."""
    import jax

    prog, (dev, params) = plan_program(plan)
    W = plan.width
    if pad.size % W:
        raise InputError(f"device_program: a chunk is a multiple of the micro-batch width {W}, got {pad.size} items")
    sim, sig = _host_inputs(plan, pad)

    def micro(j):                               # one micro-batch: the same compiled programs for every j
        cut = lambda a: jax.tree_util.tree_map(lambda v: v[j:j + W], a)  # noqa: E731
        s_in = jax.device_put(cut(sim), dev)
        g_in = jax.device_put(cut({k: v for k, v in sig.items() if v is not None}), dev)
        out = prog(s_in["keys"], s_in["speed_rpm"], s_in["loads"], s_in["theta0"], s_in["location"],
                   s_in["center"], s_in["extent"], s_in["depth"], s_in["modes"], params, pit=s_in.get("pit"),
                   keep_depth=not plan.pit, track=plan.signal.ball_exposure == "kinematic")
        unb = out["unbridged"]
        freqs = jax.numpy.stack([out[k] for k in ("ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz")], -1)
        x, lb = finish_items(s_in["keys"], out["housing_acceleration"], out["sensor"], out["pass_times"], unb,
                             g_in["fault_class"], out["shaft_Hz"], g_in["draws"], plan.signal, freqs,
                             out.get("ball_track"))
        keep = {k: out[k] for k in ("result", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz", "pass_jitter_percent",
                                    "pit_depth", "unbridged", "pit_ok")}
        host = jax.device_get((x, lb, keep))
        host[2]["ball_iterations"] = np.full(W, out["ball_iterations"], np.int32)
        return host

    starts = range(0, pad.size, W)
    threads = min(program_threads(dev) if threads is None else int(threads), len(starts))
    if threads > 1:         # a CPU program runs on one core: one micro-batch per core at a time
        with ThreadPoolExecutor(threads, thread_name_prefix="bearingsim-micro-batch") as pool:
            parts = list(pool.map(micro, starts))
    else:
        parts = [micro(j) for j in starts]
    cat = lambda i, k: np.concatenate([p[i][k] for p in parts])  # noqa: E731
    sig_all = np.concatenate([p[0] for p in parts])
    code = cat(2, "result").astype(np.int32)
    code = np.where(succeeded(code) & ~cat(1, "finite"), int(DatasetResult.nonfinite_signal), code)
    code = np.where(cat(2, "pit_ok"), code, int(DatasetResult.pit_contact))
    # a fault item whose pit makes no impact in the record would be a healthy record under a fault label:
    # a pit the ball does not load (depth_rule "pit"), or a ball pit that struck on none of the passes
    quiet = ~cat(1, "struck")
    if plan.pit:
        quiet = quiet | ~excited(np.asarray(cat(2, "pit_depth"), float))
    code = np.where(succeeded(code) & (plan.lab["fault_class"][pad] > 0) & quiet,
                    int(DatasetResult.fault_not_excited), code)
    ok = succeeded(code)
    out = dict(signals=np.where(ok[:, None], sig_all, 0.0).astype(np.float32), result=code,
               ball_iterations=cat(2, "ball_iterations"))
    for k in ("signal_gain", "snr_dB", "pass_amplitude_cv_percent", "pass_delay_sd_percent") + BACKGROUND_FIELDS:
        out[k] = np.asarray(cat(1, k), float)
    out["pass_jitter_percent"] = np.asarray(cat(2, "pass_jitter_percent"), float)
    for k in ("ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz"):
        v = np.asarray(cat(2, k), float)
        out[k] = np.where(np.isfinite(v) & ok, v, 0.0)
    out["effective_depth_mm"] = from_si(np.asarray(cat(2, "pit_depth"), float), "mm")
    out["unbridged_fraction"] = np.asarray(cat(2, "unbridged"), float)
    return out


def simulate_chunk(plan, k: int, threads=None) -> dict:
    """Chunk ``k`` of a data set: the arrays of its chunk file (``index``, ``signals`` and the
    per-item label fields the simulation fills, :data:`CHUNK_FIELDS`, and ``ball_iterations``:
    the Newton count each item's micro-batch ran with).  A pure function of (plan, k): every
    item's draws come from its own key and every program runs on micro-batches of the fixed
    width ``plan.width`` (the chunk padded to a multiple of it with its last item; only the
    micro-batches holding items run), so the in-process loop, any chunk size that is a multiple
    of the width and any Dask worker give the same bytes on the same device type.  Runs on
    ``plan.device`` (a JAX platform name; None: JAX's default); ``threads``: see
    :func:`device_program`."""
    import contextlib

    import jax

    idx = plan.items(k)
    m = idx.size
    W = plan.width
    pad = np.concatenate([idx, np.repeat(idx[-1:], -(-m // W) * W - m)])
    where = jax.default_device(jax.devices(plan.device)[0]) if plan.device else contextlib.nullcontext()
    with where:
        out = device_program(plan, pad) if threads is None else device_program(plan, pad, threads)
    return dict(index=idx, **{name: v[:m] for name, v in out.items()})


def run_settings(physics, lab, extent, depth, center, fs) -> int:
    """Substeps per sample for the whole data set: :func:`dynamics.batch_settings` on the extreme
    items of every class (:func:`dynamics.extreme_items`: fastest, slowest, most and least
    loaded, largest defect), the largest, fixed once so that no chunk recompiles.  (The Newton
    step count is chosen per micro-batch inside the chunk program.)  The host solves are kept
    across processes (:func:`bearingsim.warm.memo`, keyed by the physics and the extreme
    items' values): a warm start of the same data set reads the number."""
    ph = physics
    slots = slots_of(lab)
    loc = item_locations(lab)
    load = lab["radial_N"] + lab["axial_N"]
    size = np.asarray(extent, float) * np.asarray(depth, float)
    check = [int(i) for i in dynamics.extreme_items(lab["fault_class"], lab["speed_rpm"], load, size)]
    items = tuple((float(lab["speed_rpm"][i]), float(lab["axial_N"][i]), float(lab["radial_N"][i]), str(loc[i]),
                   float(center[i]), float(extent[i]), float(depth[i])) for i in check)

    def compute():
        subs = []
        for rpm, axial, radial, li, c, e, d in items:
            op = Operation.from_rpm(rpm, ph.control, True, True)
            F = load_vector(axial=axial, radial_x=radial)
            sp = tuple(Spall(c if L == li else 0.0, e if L == li else 0.0, d if L == li else 0.0, ph.profile, L, 0)
                       for L in slots)
            it, sub = dynamics.batch_settings(ph.bearing, op, F, sp, ph.cage_angle, fs, ph.params, ph.hertz_method)
            if it is not None:
                subs.append(int(sub))
        return max(subs, default=1)

    inputs = (ph.bearing, ph.params, ph.control, ph.hertz_method, ph.profile, float(ph.cage_angle), float(fs),
              tuple(slots), items)
    return int(warm.memo("run_settings", inputs, compute))
