"""The writer of a data set: the resumable chunk files and the HDF5 layout.

Chunk files: every finished chunk is a folder ``chunk_NNNNNN/`` of raw ``.npy`` arrays (no zip,
no CRC per item) in ``<path>.partial/``, written into a hidden folder and renamed in one step
(atomic: a chunk is either complete or absent).  The HDF5 file is assembled from them in item
order, atomically.

Compression of ``/signals`` (:data:`COMPRESSIONS`, ``make_dataset(compression=)``, CLI
``--compression``): simulated float32 signals carry noise in every mantissa bit, so no lossless
codec saves much.  Measured (benchmarks/bench_dataset.py, 2000 x 4800 float32, contended 2-core
CPU): none 396 MB/s write, 861 MB/s read, size 1.00; lzf 51 / 709 MB/s, 1.00 (saves nothing);
gzip-4 19 / 73 MB/s, 0.93; gzip-1 20 / 87 MB/s, 0.93; blosc-zstd-1 with byte shuffle
(``hdf5plugin``) 71 / 232 MB/s, 0.86; blosc-lz4 182 / 518 MB/s, 0.90.  The rule: ``none`` by
default (the writer keeps up with a GPU: ~10^4 items of 4800 samples per second), ``zstd`` for
an archive where ``hdf5plugin`` is installed (the ``compress`` extra; readers need it too),
``gzip`` for an archive any HDF5 reader opens (7 % smaller, 20x slower to write).
"""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np

from .._version import __version__
from ..case.units import from_si, to_si
from ..errors import InputError
from ..output import io
from .spec import CLASSES, LABEL_FIELDS, result_messages

__all__ = ["CHUNK_FORMAT", "COMPRESSIONS", "DEFAULT_COMPRESSION", "partial_path", "write_atomic", "chunk_path",
           "write_chunk", "read_chunk", "finished_chunks", "spec_record", "open_partial", "assemble",
           "compression_options"]

#: layout of the chunk files (4: a folder of .npy arrays per chunk; items drawn from keys; 5: one
#: registry of streams, the chunk on the device, pit labels and ball_iterations per item; 6: the
#: programs sized by the spec's speed bound, so the slip walk's knot count and with it the motion
#: draws changed, issue 32; 7: fault items that make no impact flagged fault_not_excited and zeroed,
#: so a cached identify bank of 6 holding them is not reused); a partial folder of another layout is
#: refused like one of another spec
CHUNK_FORMAT = 7
#: codecs of /signals: name -> h5py create_dataset keywords
COMPRESSIONS = {"none": {}, "lzf": {"compression": "lzf"}, "gzip": {"compression": "gzip", "compression_opts": 4},
                "gzip1": {"compression": "gzip", "compression_opts": 1}, "zstd": None}
DEFAULT_COMPRESSION = "none"


def compression_options(name) -> dict:
    """h5py keywords of the codec ``name`` (:data:`COMPRESSIONS`), or one clear InputError."""
    name = DEFAULT_COMPRESSION if name is None else name
    if name not in COMPRESSIONS:
        raise InputError(f"compression must be one of {', '.join(COMPRESSIONS)}, got {name!r}")
    if name == "zstd":
        try:
            import hdf5plugin
        except ImportError:
            raise InputError("compression zstd needs hdf5plugin: pip install 'bearingsim[compress]' "
                             "(or use gzip)") from None
        return dict(hdf5plugin.Blosc(cname="zstd", clevel=1, shuffle=hdf5plugin.Blosc.SHUFFLE))
    return COMPRESSIONS[name]


def partial_path(path) -> Path:
    """The folder that holds the finished chunks of an unfinished run writing ``path``."""
    path = Path(path)
    return path.with_name(path.name + ".partial")


def write_atomic(path: Path, write):
    """``write(fh)`` into a hidden temporary file beside ``path``, then renamed to ``path``."""
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with open(tmp, "wb") as fh:
            write(fh)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def chunk_path(folder: Path, k: int) -> Path:
    return Path(folder) / f"chunk_{k:06d}"


def write_chunk(folder: Path, k: int, arrays: dict):
    """Chunk ``k``'s arrays as raw .npy files in ``chunk_NNNNNN/`` (atomically: a hidden folder
    renamed in one step)."""
    final = chunk_path(folder, k)
    tmp = final.with_name(f".{final.name}.tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir()
    try:
        for name, a in arrays.items():
            np.save(tmp / f"{name}.npy", np.ascontiguousarray(a), allow_pickle=False)
        os.replace(tmp, final)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def read_chunk(folder: Path, k: int, name: str, mmap=False) -> np.ndarray:
    return np.load(chunk_path(folder, k) / f"{name}.npy", mmap_mode="r" if mmap else None, allow_pickle=False)


def finished_chunks(folder: Path) -> list:
    return sorted(p.name for p in Path(folder).glob("chunk_*") if p.is_dir())


def spec_record(sc, ds, n, T, fs, chunk):
    """What decides a partial folder's chunks (a rerun continues only the same spec): scenario ``sc``'s TOML, seed, sizes."""
    return {"bearingsim_version": __version__, "chunk_format": CHUNK_FORMAT, "case_toml": sc.text,
            "seed": int(ds["seed"]), "count": n, "samples": T, "sample_rate_Hz": fs, "chunk": chunk}


def open_partial(folder: Path, spec: dict, settings):
    """The partial folder of this spec (created if absent) and its substeps (``settings()`` the
    first time)."""
    f = folder / "spec.json"
    if f.exists():
        try:
            old = json.loads(f.read_text())
        except (OSError, ValueError):
            old = None
        if old is None or {k: old.get(k) for k in spec} != spec:
            raise InputError(f"{folder} holds the finished chunks of a run with a different spec (or "
                             "bearingsim version); delete it to start afresh, or write elsewhere")
        return old["substeps"]
    sub = settings()
    folder.mkdir(parents=True, exist_ok=True)
    write_atomic(f, lambda fh: fh.write(json.dumps(dict(spec, substeps=sub)).encode()))
    return sub


def assemble(sc, ds, path, folder, lab, T, fs, duration, it, sub, scheme, chunks, modes, fields,
             compression=None):
    """Write the HDF5 file from the finished chunks, in item order (atomically); ``fields``: the
    label fields the chunks carry."""
    import h5py

    opts = compression_options(compression)
    n = lab.size
    Z = sc.bearing.n_balls
    for k in range(chunks):
        idx = read_chunk(folder, k, "index")
        for name in fields:
            lab[name][idx] = read_chunk(folder, k, name)
    lab["shaft_Hz"] = from_si(to_si(lab["speed_rpm"], "rpm"), "rev_s")
    units = {k: u for k, (_, u) in LABEL_FIELDS.items()}
    with io.atomic_path(path) as tmp:
        with h5py.File(tmp, "w", track_order=True) as f:
            f.attrs["bearingsim_version"] = __version__
            f.attrs["case_toml"] = sc.text
            f.attrs["seed"] = int(ds["seed"])
            f.attrs["count"] = n
            f.attrs["balls"] = Z
            f.attrs["sample_rate_Hz"] = fs
            f.attrs["duration_s"] = duration
            f.attrs["ball_iterations"] = int(it)
            f.attrs["substeps"] = int(sub)
            f.attrs["scheme"] = scheme
            sig = f.create_dataset("signals", shape=(n, T), dtype="float32", chunks=(1, T), fillvalue=0.0,
                                   **opts)
            sig.attrs["units"] = "m/s^2"
            sig.attrs["description"] = ("sensor acceleration (sensor modes, slip, speed fluctuation, "
                                        "pass-to-pass variability and noise of the [dynamics] keys); "
                                        "row i has the labels /labels[i]; zero where result != 0")
            for k in range(chunks):                    # one chunk in memory at a time
                idx = read_chunk(folder, k, "index")
                x = read_chunk(folder, k, "signals", mmap=True)
                order = np.argsort(idx, kind="stable")
                idx = idx[order]
                # runs of consecutive indices are written as one slab
                breaks = np.flatnonzero(np.diff(idx) != 1) + 1
                for run in np.split(np.arange(idx.size), breaks):
                    sig[idx[run[0]]:idx[run[-1]] + 1] = x[order[run]]
            tp = f.create_dataset("transfer_path", data=modes)
            tp.attrs["units"] = "Hz, -, -"
            tp.attrs["description"] = ("(N, M, 3): every item's sensor modes: frequency (Hz), damping "
                                       "ratio, gain (domain randomisation: [dataset] resonance_*)")
            tm = f.create_dataset("time", data=np.arange(T) / fs)
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
                "key: the item's jax.random key data (word0 << 32 | word1) = fold_in(PRNGKey(seed), "
                "index), every random draw of the item comes from it; realism_seed (drawn from the "
                "key) seeds the item's slip, speed fluctuation, noise and pass-to-pass variability")
