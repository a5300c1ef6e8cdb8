"""The runner of a data set: the chunk plan, the device, the in-process loop or a Dask
cluster, interrupts, and the orchestration :func:`make_dataset`.

Device (``make_dataset(device=)``, CLI ``--device cpu|gpu``): JAX's default (the GPU where JAX
sees one) unless named; the summary says which device ran.  Chunk size: the spec's
``[dataset] chunk``, or with ``chunk = 0`` (or ``chunk="auto"``) what fills the device
(:func:`default_chunk`): on a CPU 16 items per core; on a GPU as many items as fit in a quarter
of its memory at :data:`BYTES_PER_SAMPLE` bytes per item and sample, at most
:data:`MAX_GPU_CHUNK`.  The chunk size changes no drawn label, and the signals (with the gain
a target SNR sets from them) only in their last bits (the dynamics batch rounds by batch width;
docs/scale.md).
"""
from __future__ import annotations

import contextlib
import os
import shutil
import signal
import threading
import time
import warnings
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from itertools import islice
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import warm
from ..case import Scenario, as_scenario, check_sampling
from ..errors import BearingsimError, failed, InputError, SettingWarning
from ..signals.background import Background
from ..signals.signal_stage import SignalSettings
from .program import CHUNK_FIELDS, Physics, micro_batch, program_threads, run_settings, simulate_chunk
from .spec import (DatasetResult, DatasetSummary, defect_geometry, draw_labels, settings, simulation_order, slots_of,
                   transfer_paths)
from .progress import Display, RunProgress
from .writer import (assemble, chunk_path, compression_options, finished_chunks, open_partial, partial_path,
                     read_chunk, spec_record, write_chunk)

__all__ = ["ChunkPlan", "Interrupted", "serial_imap", "threaded_imap", "make_dataset", "resolve_device", "default_chunk",
           "BYTES_PER_SAMPLE", "MAX_GPU_CHUNK", "DEVICES"]

#: the device names of ``--device`` (JAX platform names)
DEVICES = ("cpu", "gpu")
#: device memory per item and sample of a chunk's programs (states, accelerations, sensor,
#: signal stage): 112 B measured on an H200 (2026-11-28, benchmarks/bench_gpu.py, peak of the
#: process at W 8192 and 32768) and a margin; the GPU chunk rule keeps to a quarter of the memory
BYTES_PER_SAMPLE = 128
MAX_GPU_CHUNK = 8192


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


def serial_imap(fn, shared, items):
    """``(item, fn(shared, item))`` for every item, in this process, in order: how the chunks of
    a data set run without a cluster.
    :class:`bearingsim.datasets.distributed.DaskRunner` has the same ``imap`` on a Dask cluster."""
    for x in items:
        yield x, fn(shared, x)


def _chunk_alone(plan, k):
    """Chunk ``k`` with its micro-batches in one thread (chunks already run side by side)."""
    return simulate_chunk(plan, k, threads=1)


def threaded_imap(threads):
    """An ``imap`` like :func:`serial_imap` that runs up to ``threads`` items at once in threads of
    this process and yields them in order, the next one submitted before one is yielded (a
    compiled CPU program runs on one core: two chunks on two cores).  Results do not depend on
    the thread count (each item is the same programs on its own data)."""
    def imap(fn, shared, items):
        items = list(items)
        if threads <= 1 or len(items) <= 1:
            yield from serial_imap(fn, shared, items)
            return
        pool = ThreadPoolExecutor(threads, thread_name_prefix="bearingsim-chunk")
        try:
            todo = iter(items)
            pending = deque((x, pool.submit(fn, shared, x)) for x in islice(todo, threads))
            while pending:
                x, fut = pending.popleft()
                out = fut.result()
                nxt = next(todo, _END)
                if nxt is not _END:
                    pending.append((nxt, pool.submit(fn, shared, nxt)))
                yield x, out
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
    return imap


_END = object()


def resolve_device(device=None):
    """The JAX device a data set runs on: ``device`` "cpu" | "gpu" | None (JAX's default: the
    GPU where JAX sees one).  A GPU asked for where JAX sees none is one clear InputError."""
    import jax

    if device is None:
        return jax.devices()[0]
    if device not in DEVICES:
        raise InputError(f"device must be one of {', '.join(DEVICES)}, got {device!r}")
    try:
        return jax.devices(device)[0]
    except RuntimeError:
        raise InputError(f"--device {device}: JAX sees no {device.upper()} (devices: "
                         f"{', '.join(str(d) for d in jax.devices())}); for an NVIDIA GPU: "
                         "pip install -U \"jax[cuda12]\"") from None


def default_chunk(dev, samples, count) -> int:
    """Items per chunk that fill the device ``dev``: CPU 16 per core; GPU as many as fit in a
    quarter of its memory at :data:`BYTES_PER_SAMPLE` per item and sample (at most
    :data:`MAX_GPU_CHUNK`); never more than ``count``."""
    if dev.platform == "cpu":
        n = 16 * (os.cpu_count() or 1)
    else:
        try:
            mem = int((dev.memory_stats() or {}).get("bytes_limit", 16 << 30))
        except Exception:       # noqa: BLE001 - a backend without memory_stats
            mem = 16 << 30
        n = min(MAX_GPU_CHUNK, max(16, mem // 4 // (BYTES_PER_SAMPLE * max(int(samples), 1))))
    return max(1, min(int(n), int(count)))


@dataclass(frozen=True, eq=False)
class ChunkPlan:
    """Everything the chunks of one data set need, built and drawn before any chunk runs: the
    physics objects (no case file), the labels and the per-item inputs (picklable: a Dask run
    sends it once to every worker; the compiled programs are built in each process,
    :func:`bearingsim.datasets.program.plan_program`).  ``simulate_chunk(plan, k)`` is chunk
    ``k``: a loop over its micro-batches of ``width`` items, each the same compiled programs."""

    physics: Physics
    lab: np.ndarray
    order: np.ndarray
    chunk: int                      # items per chunk: a multiple of width
    loc: np.ndarray
    center: np.ndarray
    extent: np.ndarray
    depth: np.ndarray               # machined depth (m); with pit, > 0 marks the fault items
    duration: float
    fs: float
    substeps: int
    slots: tuple
    modes: np.ndarray               # (N, M, 3) every item's sensor modes (transfer_paths)
    signal: object                  # signal_stage.SignalSettings (static)
    pit: bool = False               # depth_rule "pit": the effective depths inside the chunk program
    unbridged: bool = False         # depth_rule "machined" with pass variability: the pits' unbridged fractions
                                    # from their healthy contacts, inside the chunk program
    width: int = 4                  # micro-batch width W of every program call (program.micro_batch)
    device: str = None              # JAX platform ("cpu", "gpu"); None: the worker's default
    max_speed_rpm: float = None     # the spec's fastest speed: sizes the programs (None: the drawn items')

    @property
    def chunks(self) -> int:
        return -(-self.lab.size // self.chunk)

    def items(self, k) -> np.ndarray:
        """Item indices of chunk ``k`` (the classes spread evenly over the chunks)."""
        return self.order[k * self.chunk:(k + 1) * self.chunk]


def signal_settings(sc, ds, fs, T, physics):
    """The :class:`bearingsim.signals.signal_stage.SignalSettings` of scenario ``sc``'s [dataset] (static);
    ``background = "machine"`` uses its [background] (:attr:`Scenario.background`)."""
    machine = None
    if ds.get("background", "none") == "machine":
        machine = sc.background if sc.background is not None else Background()
    return SignalSettings.from_dataset(ds, fs, T, physics.realism, physics.params.modes(), machine)


def make_dataset(case, path, progress=True, runner=None, *, device=None, chunk=None,
                 compression=None, max_speed_rpm=None) -> DatasetSummary:
    """Simulate the [dataset] of ``case`` (a :class:`~bearingsim.case.Case` or its built
    :class:`~bearingsim.case.Scenario`, built once here) and write it to ``path`` (HDF5), resumably.

    Finished chunks go to :func:`partial_path` at once; a rerun after an interruption continues
    from them; the file is assembled when all are there.  Ctrl-C / SIGTERM raise
    :class:`Interrupted`.  ``runner``: an object with ``imap(fn, shared, items)`` like
    :func:`serial_imap` (which runs when ``runner`` is None): :class:`bearingsim.datasets.distributed.DaskRunner`
    runs the chunks on a Dask cluster; the file is the same.  ``device``: "cpu" | "gpu" | None
    (:func:`resolve_device`); ``chunk``: items per chunk (None: the spec's ``chunk``; 0 or "auto":
    :func:`default_chunk`); ``compression`` of /signals: "none" (default), "gzip", "zstd", "lzf", "gzip1"
    (:mod:`bearingsim.datasets.writer`); ``max_speed_rpm``: size the programs for at least this
    speed (default the spec's fastest; identify's twins pass their bank's, so a twin at any speed
    runs the bank-sized programs kept by the first).  Returns a :class:`DatasetSummary` (``failed``: items with
    result != 0; ``seconds``: wall time of this run's simulations, compilation included;
    ``device``, ``chunk``).  ``progress``: True a bar on a terminal, a line per phase and chunk
    otherwise (from the first second, the remaining time measured: :mod:`bearingsim.datasets.progress`);
    False nothing; a callable receives every :class:`~bearingsim.datasets.progress.ProgressEvent`."""
    show = Display("dataset") if progress is True else progress if callable(progress) else None
    try:
        sc = as_scenario(case)
        # the chunk programs the last run of this spec used load in the background meanwhile
        ahead = (warm.prefetching(f"dataset|{sc.text}", resolve_device(device)) if runner is None
                 else contextlib.nullcontext())
        with ahead:
            return _make_dataset(sc, path, RunProgress(show if show is not None else lambda e: None), runner,
                                 device=device, chunk=chunk, compression=compression, max_speed_rpm=max_speed_rpm)
    finally:
        if isinstance(show, Display):
            show.close()


def _make_dataset(sc: Scenario, path, track, runner, *, device, chunk, compression, max_speed_rpm) -> DatasetSummary:
    """:func:`make_dataset` of scenario ``sc`` reporting to ``track`` (a :class:`RunProgress`, in phase "preparing")."""
    import jax

    compression_options(compression)                    # a bad name fails before any work
    imap = serial_imap if runner is None else runner.imap
    ds = settings(sc)
    check_sampling(sc, ds["speed_rpm"][1], "dataset.speed_rpm max")
    # the chunk program uses the default centrifugal/gyroscopic flags of Operation
    if not (sc.centrifugal and sc.gyroscopic):
        raise InputError(f"{sc.source}: [dataset] needs operation.centrifugal and "
                         "operation.gyroscopic true (the batch simulation always includes them)")
    dev = resolve_device(device)
    ph = Physics.of_scenario(sc)
    fs = sc.sample_rate
    duration = float(ds["duration_s"])
    T = int(round(duration * fs))
    lab = draw_labels(sc)
    n = lab.size
    chunk = ds.get("chunk", 16) if chunk is None else chunk
    chunk = default_chunk(dev, T, n) if chunk in (0, "auto") else min(int(chunk), n)
    width = micro_batch(dev.platform, dev, T, n)
    asked, chunk = chunk, -(-chunk // width) * width        # a whole number of micro-batches
    if chunk != asked and asked != n:
        warnings.warn(f"dataset.chunk {asked} rounded up to {chunk} items: a chunk is a whole number of "
                      f"micro-batches of {width} items on {dev.platform} (bearingsim.datasets.MICRO_BATCH)",
                      SettingWarning, stacklevel=3)     # the caller of make_dataset
    slots = slots_of(lab)
    loc, extent, depth, center = defect_geometry(ph.bearing, lab)
    folder = partial_path(path)
    spec = spec_record(sc, ds, n, T, fs, chunk)
    t0 = time.perf_counter()
    done = 0
    where = jax.default_device(dev) if runner is None else contextlib.nullcontext()
    try:
        with _signals_stop(), where:
            pit = ds.get("depth_rule", "machined") == "pit"
            unbridged = not pit and bool(ph.realism.pass_variation)     # the machined depth is simulated
            lab["slip_percent"] = ph.realism.slip_percent
            lab["speed_fluctuation_percent"] = ph.realism.speed_fluctuation_percent
            lab["noise_rms_m_s2"] = ph.realism.noise_rms
            modes = transfer_paths(sc, lab)
            chunks = -(-n // chunk)
            sub = open_partial(folder, spec, lambda: run_settings(ph, lab, extent, depth, center, fs))
            todo = [k for k in range(chunks) if not chunk_path(folder, k).exists()]
            done = n - sum(min(chunk, n - k * chunk) for k in todo)
            plan = ChunkPlan(ph, lab, simulation_order(lab["fault_class"]), chunk, loc, center, extent, depth,
                             duration, fs, sub, slots, modes, signal_settings(sc, ds, fs, T, ph), pit, unbridged,
                             width, dev.platform, max(float(ds["speed_rpm"][1]), float(max_speed_rpm or 0.0)))
            threads = program_threads(dev) if runner is None else 1
            wave = todo[:threads if runner is None else getattr(runner, "workers", None) or 1]
            track.start(n, done, sum(min(chunk, n - k * chunk) for k in wave))     # the first wave compiles
            run = (threaded_imap(threads), _chunk_alone) if threads > 1 and len(todo) > 1 else (imap, simulate_chunk)
            for k, out in run[0](run[1], plan, todo):     # finished chunks, streamed in order
                write_chunk(folder, k, out)
                done += out["index"].size
                track.advance(out["index"].size)
                del out
            track.report("writing")
            it = max(int(np.max(read_chunk(folder, k, "ball_iterations"), initial=1)) for k in range(chunks))
            assemble(sc, ds, path, folder, lab, T, fs, duration, it, sub, "newmark", chunks, modes,
                     CHUNK_FIELDS, compression)
            shutil.rmtree(folder, ignore_errors=True)
            track.report("done")
    except (_Stop, KeyboardInterrupt) as e:
        how = e.name if isinstance(e, _Stop) else (str(e) if str(e) in ("SIGINT", "SIGTERM") else "SIGINT")
        if folder.is_dir() and not finished_chunks(folder):     # nothing worth keeping
            shutil.rmtree(folder, ignore_errors=True)
        if not folder.exists():
            raise Interrupted(f"{how}: stopped before the first chunk finished; nothing written") from None
        raise Interrupted(f"{how}: stopped with {done} of {n} items finished, kept in {folder}; run "
                          "the same command again to continue") from None
    bad = failed(lab["result"])
    out = lab["result"] == int(DatasetResult.fault_not_excited)
    codes, counts = np.unique(lab["result"][bad], return_counts=True)
    return DatasetSummary(Path(path), n, T, int((bad & ~out).sum()), time.perf_counter() - t0,
                          {int(c): int(k) for c, k in zip(codes, counts)}, str(dev), chunk, int(out.sum()))
