"""Simulated data sets kept in the data cache: a training set simulated once per spec and read
thereafter, by a later run, a notebook, a benchmark or a test of the same session.

Where: ``$BEARINGSIM_CACHE``, else ``~/.cache/bearingsim`` (:func:`cache_dir`; ``bearingsim cache``
names it, ``bearingsim cache --clear`` leaves it).  A file's name holds its purpose, the data set
format it was simulated with and a digest of its spec's whole text (count, seed and every
setting): a set of another spec, or simulated by an older engine, is never reused.  Processes
that need the same set at once (test workers, notebook kernels, two shells) build it once: the
others wait on a lock file beside it (:class:`FileLock`), then read it.  The set is written by
:func:`bearingsim.datasets.runner.make_dataset`, atomically: a build that is interrupted leaves
its finished chunks for the next call to resume and never a half-written file.
"""
from __future__ import annotations

import hashlib
import os
import sys
import time
from pathlib import Path

from ..errors import InputError
from .runner import make_dataset
from .writer import CHUNK_FORMAT

__all__ = ["cache_dir", "FileLock", "cached_name", "cached_dataset"]


def cache_dir() -> Path:
    """Where cached data sets (and identify's banks) are kept: $BEARINGSIM_CACHE, else
    ~/.cache/bearingsim."""
    d = os.environ.get("BEARINGSIM_CACHE")
    return Path(d) if d else Path.home() / ".cache" / "bearingsim"


class FileLock:
    """An exclusive lock on ``path`` (``fcntl.flock``: released when the holder exits, even by a
    crash); where the platform has no ``fcntl``, no lock (the data set is written atomically, so
    two builders only waste time)."""

    def __init__(self, path):
        self.path, self.fd, self.fcntl = Path(path), None, None

    def __enter__(self):
        try:
            import fcntl  # local: POSIX only (Windows has no fcntl: no lock there)
        except ImportError:
            return self
        self.fcntl = fcntl
        self.fd = os.open(self.path, os.O_CREAT | os.O_RDWR, 0o644)
        fcntl.flock(self.fd, fcntl.LOCK_EX)
        return self

    def __exit__(self, *exc):
        if self.fd is not None:
            self.fcntl.flock(self.fd, self.fcntl.LOCK_UN)
            os.close(self.fd)
        return False


def cached_name(spec, purpose: str) -> str:
    """The cached set's file name: ``<purpose>_<count>_v<format>_<digest of the spec's text>.h5``."""
    if not purpose or not all(c.isalnum() or c in "_-" for c in purpose):
        raise InputError(f"purpose {purpose!r}: letters, digits, '_' and '-' only (it begins a file name)",
                         "name the set's use, e.g. 'transfer_train'")
    digest = hashlib.sha256(spec.text.encode()).hexdigest()[:12]
    return f"{purpose}_{int(spec.get('dataset.count'))}_v{CHUNK_FORMAT}_{digest}.h5"


def cached_dataset(spec, purpose: str = "dataset", directory=None, progress: bool = True) -> Path:
    """The data set of ``spec`` (a data set spec, :func:`bearingsim.case.load_case`) in the data
    cache (``directory``: None, :func:`cache_dir`), simulated there by
    :func:`bearingsim.datasets.runner.make_dataset` unless it is there already; returns its path.
    ``purpose`` begins the file's name.  ``progress``: a line on stderr when it is read from the
    cache or built, the engine's progress while it builds."""
    path = Path(directory if directory is not None else cache_dir()) / cached_name(spec, purpose)
    if path.exists():
        if progress:
            print(f"bearingsim: {purpose}: read from the data cache ({path})", file=sys.stderr, flush=True)
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    with FileLock(path.with_name(path.name + ".lock")):
        if not path.exists():
            t0 = time.perf_counter()
            make_dataset(spec, path, progress=progress)
            if progress:
                print(f"bearingsim: {purpose}: simulated into the data cache in {time.perf_counter() - t0:.0f} s "
                      f"({path}); later calls read it", file=sys.stderr, flush=True)
    return path
