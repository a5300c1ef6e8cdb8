"""What a warm start reads instead of computing again (issue 32), beside the kept programs of
:mod:`bearingsim.programs`: :func:`memo` (a small host result kept under the exact key of its
inputs: a data set's substeps) and :func:`prefetching` (the kept programs the last run of the
same name used, loaded and compiled in background threads while the run does its other work)."""
from __future__ import annotations

import contextlib
import hashlib
import json
import os
import threading

import jax

from . import programs

__all__ = ["memo", "prefetching", "recall"]


def _memo_path(name: str, inputs):
    """The file of ``inputs`` under ``name`` (None: no cache folder, or inputs it cannot describe)."""
    d = programs.program_dir()
    if d is None:
        return None
    try:
        leaves, tree = jax.tree_util.tree_flatten(inputs)
        desc = f"{name}|{programs.describe(tree)}|{programs.describe(tuple(leaves))}"
    except programs.Undescribable:
        return None
    key = hashlib.sha256(f"{programs.source_hash()}|{desc}".encode()).hexdigest()[:32]
    return d / f"{key}.memo.json"


def recall(name: str, inputs, default=None):
    """The value :func:`memo` kept for ``inputs`` under ``name``, else ``default`` (nothing is
    computed): for a caller that starts work only a miss needs (a compile thread)."""
    path = _memo_path(name, inputs)
    if path is None:
        return default
    try:
        value = json.loads(path.read_text())["value"]
    except (OSError, ValueError, KeyError):
        return default
    programs.count("memo_hits")
    return value


def memo(name: str, inputs, compute):
    """``compute()`` once per ``inputs`` across processes: a small host result (a JSON value: a
    number, a string, a list) kept beside the programs (:func:`bearingsim.programs.program_dir`), keyed like a program
    by the package source and the exact value of ``inputs`` (a tree of numbers, strings, arrays,
    dataclasses, equinox modules).  For settings a data set derives from a few host solves
    (:func:`bearingsim.datasets.program.run_settings`, 2.2 s of a warm 16-item run): a warm start
    reads them.  Inputs it cannot describe exactly, or no cache folder: computed every time.
    :data:`bearingsim.programs.COUNTS` counts ``memo_hits``."""
    path = _memo_path(name, inputs)
    if path is None:
        return compute()
    missing = object()
    value = recall(name, inputs, missing)
    if value is not missing:
        return value
    value = compute()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.{threading.get_ident()}.tmp")
        tmp.write_text(json.dumps({"name": name, "value": value}))
        os.replace(tmp, path)
    except (OSError, TypeError, ValueError):     # a read-only cache, a value JSON cannot hold
        pass
    return value


@contextlib.contextmanager
def prefetching(name: str, device=None):
    """Load and compile, in background threads, the kept programs that the last run under
    ``name`` used, while this run does its other work (imports done: drawing labels, host
    solves) -- XLA releases the GIL while it deserializes an executable, so on two cores the
    three programs of a data set chunk load in ~1.6 s instead of ~2.2 s, and beside the label
    draws.  Records the programs this run uses (a small JSON file beside the programs, written
    atomically) for the next run.  A program not prefetched is loaded or traced by its first
    call as usual; the threads are joined on exit."""
    d = programs.program_dir()
    if d is None:
        yield
        return
    dev = jax.devices()[0] if device is None else device
    path = d / f"{hashlib.sha256(f'{programs.source_hash()}|{name}|{dev.platform}'.encode()).hexdigest()[:32]}.prefetch.json"
    try:
        recorded = [tuple(e) for e in json.loads(path.read_text())]
    except (OSError, ValueError, TypeError):
        recorded = []
    by_name = programs.kept_programs()
    todo = [(by_name[n], k) for n, k in recorded if n in by_name]

    queue = list(reversed(todo))

    def load():
        while True:
            try:
                p, k = queue.pop()          # atomic under the GIL: each program taken once
            except IndexError:
                return
            p.prefetch(k, dev)

    # two loaders taking the programs in the order the last run's main thread first needed them,
    # then those only its background threads used (a compile thread's early call of a program
    # the main thread needs later: ball_errors before solve_state, a warm `bearingsim simulate`)
    threads = [threading.Thread(target=load, daemon=True, name="bearingsim-prefetch")
               for _ in range(min(2, len(todo)))]
    for t in threads:
        t.start()
    mine: dict = {}             # (name, key) in the order of first use
    programs.record(mine)
    try:
        yield
    finally:
        programs.record(mine, on=False)
        for t in threads:
            t.join()
        order = (sorted((k for k, r in mine.items() if r is not None), key=mine.get)
                 + [k for k, r in mine.items() if r is None])
        if order and order != recorded:
            try:
                d.mkdir(parents=True, exist_ok=True)
                tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
                tmp.write_text(json.dumps(order))
                os.replace(tmp, path)
            except OSError:
                pass
