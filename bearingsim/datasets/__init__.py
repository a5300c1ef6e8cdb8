"""Labelled data sets of simulated defect-impact signals (``bearingsim dataset``).

A data set spec is an ordinary case file plus a ``[dataset]`` section (see the case reference).
The package's files show the flow (with ``mldata``: the reader of a finished file; ``budget``: what a run needs; ``distributed``: the chunks on a Dask cluster):

``spec``     the [dataset] settings, the label fields, the class list (``("healthy",) +
             defect.LOCATIONS``) and the label draws: item i is a pure function of (spec, seed,
             i): its key ``jax.random.fold_in(PRNGKey(seed), i)`` draws all of its labels
             (vmapped, on the CPU);
``program``  the device program: :func:`simulate_chunk` (plan, k) pads the chunk to whole
             micro-batches (:func:`micro_batch`) and makes one call, :func:`device_program` (per
             micro-batch the chunk program of bearingsim.dynamics, then the signal stage);
``writer``   the resumable chunk files (a folder of raw .npy arrays per chunk, renamed
             atomically) and the HDF5 layout (``/signals`` uncompressed by default: ``compression=``);
``runner``   the chunk plan (built physics objects, not the case), the device (``device=``), the
             chunk size, the in-process loop or a Dask cluster, interrupts, :func:`make_dataset`;
``cached``   a set simulated once per spec into the data cache and read thereafter
             (:func:`cached_dataset`: training sets shared by runs, notebooks and tests).

Resumable and interruptible.  Each finished chunk is saved at once (atomically) in the folder
``<path>.partial/`` next to the output; an interrupted run (Ctrl-C, SIGTERM, a crash) keeps
every finished chunk, and running the same command again continues from them (a spec that
differs from the one the folder was started with is refused).  When every chunk is there the
HDF5 file is assembled from the folder in item order (atomically; the folder is then removed),
so the same spec and seed give a bit-identical file for any chunk size, however often the run
was interrupted and on any number of Dask workers (on the same device type: every program runs
on micro-batches of a fixed width per platform).  Memory stays bounded
by one chunk.  Ctrl-C / SIGTERM raise :class:`Interrupted` (exit code 130) with a one-line
message; nothing temporary is left behind.

``/signals``  float32 (N, T) sensor acceleration, m/s^2 (chunks (1, T), uncompressed unless told)
``/time``     float64 (T,) s
``/transfer_path`` float64 (N, M, 3) every item's sensor modes
``/labels``   compound (N,): the fields of :data:`LABEL_FIELDS` (docs/results.md); ``key`` is the
              item's key data (word0 << 32 | word1), from which all of its draws come.

Root attributes ``bearingsim_version``, ``case_toml``, ``seed`` (and ``count``,
``sample_rate_Hz``, ``duration_s``, ``balls``, ``ball_iterations``, ``substeps``, ``scheme``).
Items whose simulation failed keep a zero signal and a result code != 0
(:data:`DatasetResult`); nothing written is NaN.  ``/labels`` has the attributes
``field_units``, ``result_messages`` and ``class_names`` (JSON objects).
"""
from __future__ import annotations

from ..names import lazy_exports

#: every public name of the data set modules, by module: imported at first use (PEP 562), so that
#: ``bearingsim.datasets.mldata`` (NumPy and h5py only) does not load JAX through this package
_EXPORTS = {
    'cached': ('FileLock', 'cache_dir', 'cached_dataset', 'cached_name'),
    'program': ('BACKGROUND_FIELDS', 'CHUNK_FIELDS', 'DEFAULT_MICRO_BATCH', 'MICRO_BATCH', 'Physics', 'chunk_keys', 'device_program', 'micro_batch', 'plan_program', 'run_settings', 'simulate_chunk'),
    'runner': ('BYTES_PER_SAMPLE', 'DEVICES', 'MAX_GPU_CHUNK', 'ChunkPlan', 'Interrupted', 'default_chunk', 'make_dataset', 'resolve_device', 'serial_imap', 'signal_settings'),
    'spec': ('CLASSES', 'FIELD_STREAMS', 'LABEL_DTYPE', 'LABEL_FIELDS', 'RANGES', 'SPLITS', 'DatasetResult', 'DatasetSummary', 'class_counts', 'class_of_index', 'defect_geometry', 'draw_labels', 'item_keys', 'item_locations', 'item_seeds', 'result_messages', 'settings', 'simulation_order', 'slots_of', 'transfer_paths'),
    'writer': ('CHUNK_FORMAT', 'COMPRESSIONS', 'DEFAULT_COMPRESSION', 'partial_path'),
}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)


__all__ = ["ChunkPlan", "CHUNK_FIELDS", "BACKGROUND_FIELDS", "simulate_chunk", "device_program", "plan_program",
           "serial_imap", "run_settings", "Physics", "signal_settings",
           "micro_batch", "MICRO_BATCH", "DEFAULT_MICRO_BATCH", "chunk_keys", "CLASSES", "SPLITS", "RANGES", "FIELD_STREAMS", "LABEL_FIELDS",
           "LABEL_DTYPE", "DatasetResult", "DatasetSummary", "Interrupted", "draw_labels", "item_keys",
           "item_seeds", "class_counts", "class_of_index", "item_locations", "slots_of", "transfer_paths",
           "simulation_order", "defect_geometry", "settings", "result_messages", "make_dataset", "partial_path",
           "resolve_device", "default_chunk", "DEVICES", "BYTES_PER_SAMPLE", "MAX_GPU_CHUNK", "CHUNK_FORMAT",
           "COMPRESSIONS", "DEFAULT_COMPRESSION", "FileLock", "cache_dir", "cached_dataset", "cached_name"]
