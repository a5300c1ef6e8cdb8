"""Traced programs kept across processes: a warm start loads a program instead of tracing it.

JAX's persistent compilation cache (:mod:`bearingsim.runtime`) skips XLA's compilation, not
Python's tracing and lowering (most of a warm 16-item data set's 30 s).  :func:`jit` (every
program of the package) keeps the traced program: the first call of a configuration traces and
lowers it with :func:`jax.export.export`, writes the serialized program (StableHLO bytecode,
``flatbuffers``) to the program cache and runs it; the next process with the same configuration
reads it back (:func:`jax.export.deserialize`) and the persistent cache answers the compilation.

The key of a program is everything its trace depends on:

* the package source (a hash of every ``bearingsim/**/*.py`` file) and the versions of Python,
  jax, jaxlib, equinox, diffrax, optimistix, lineax and NumPy; float64 on or off;
* the platform it runs on (``cpu``, ``gpu``, ...);
* the function (module, qualified name, bytecode, constants, names, closure); one defined outside
  the package (a test's, a script's) is kept in memory only: the globals it reads are in no hash;
* every static argument (everything that is not an array, as :func:`equinox.filter_jit` splits
  them), by value: numbers, strings, enums, tuples, dicts, dataclasses, equinox modules' static
  fields, NumPy arrays by their bytes; an argument of a type it cannot describe exactly makes the
  call an ordinary (unkept) program, never a guess;
* the shape, dtype and weak type of every array argument.

Where: ``<compilation cache>/bearingsim-programs/`` (``bearingsim cache --clear`` clears both);
``BEARINGSIM_PROGRAM_CACHE=off`` keeps programs in memory only.  A file that cannot be read
(another jax, a partial copy) is traced again and replaced, with one line on stderr.  Files are
written atomically (a temporary file renamed).

:data:`COUNTS` counts, per process, the programs ``traced`` (and written), ``loaded`` from
files, ``compiled`` by XLA and answered by the compilation cache (``compile_cache_hits``), and
``unkept`` calls (a static argument it cannot describe, or a program :func:`jax.export` refuses);
:func:`counts` returns a copy (``benchmarks/bench_dataset.py`` prints it).
"""
from __future__ import annotations

import dataclasses
import enum
import functools
import hashlib
import os
import pickle
import sys
import threading
import types
import weakref
from pathlib import Path

import equinox as eqx
import jax
import numpy as np

from . import runtime
from .xla import compiler_options, lowering_platform

__all__ = ["jit", "KeptProgram", "COUNTS", "counts", "program_dir", "source_hash", "forget", "FORMAT", "record", "kept_programs",
           "count", "Undescribable", "describe"]

#: the layout of a kept program's file (bumped when it changes)
FORMAT = 1
COUNTS = {"traced": 0, "loaded": 0, "memory": 0, "unkept": 0, "compiled": 0, "compile_cache_hits": 0, "memo_hits": 0,
          "prefetched": 0}      # per process (see the module docstring)
_LOCK = threading.Lock()
_ALL: "weakref.WeakSet[KeptProgram]" = weakref.WeakSet()


def forget() -> None:
    """Drop every kept program this process holds in memory (the files stay): the next call of
    each loads it from its file, as a new process would (tests and benchmarks use it)."""
    for p in list(_ALL):
        with p._lock:
            p._programs.clear()


def counts() -> dict:
    """A copy of :data:`COUNTS`."""
    _listen()
    return dict(COUNTS)


@functools.cache
def _listen():
    """Count XLA compilations and compilation-cache hits (JAX's monitoring events)."""
    def on_duration(event, duration, **_):
        if event == "/jax/core/compile/backend_compile_duration":
            COUNTS["compiled"] += 1

    def on_event(event, **_):
        if event == "/jax/compilation_cache/cache_hits":
            COUNTS["compile_cache_hits"] += 1

    jax.monitoring.register_event_duration_secs_listener(on_duration)
    jax.monitoring.register_event_listener(on_event)
    return True


@functools.cache
def source_hash() -> str:
    """A hash of the package's source files and of the versions its traces depend on."""
    h = hashlib.sha256()
    root = Path(__file__).resolve().parent
    for p in sorted(root.rglob("*.py")):
        h.update(str(p.relative_to(root)).encode())
        h.update(p.read_bytes())
    from importlib import metadata
    for dist in ("jax", "jaxlib", "equinox", "diffrax", "optimistix", "lineax", "numpy"):
        try:
            v = metadata.version(dist)
        except metadata.PackageNotFoundError:
            v = "-"
        h.update(f"{dist}={v};".encode())
    h.update(f"py{sys.version_info[:2]};x64={jax.config.jax_enable_x64};fmt={FORMAT}".encode())
    return h.hexdigest()[:20]


def program_dir() -> Path | None:
    """The folder of kept programs (None: kept in memory only)."""
    v = os.environ.get("BEARINGSIM_PROGRAM_CACHE")
    if v is not None and v.strip().lower() in runtime.OFF_VALUES:
        return None
    d = runtime.configured_cache_dir()
    return None if d is None else d / runtime.PROGRAMS_FOLDER


#: set while a key is made when a function defined outside the package takes part: such a
#: program is kept in memory only (a user's script may change a global it reads, which no key sees)
_OUTSIDE = threading.local()


class _Unkept(Exception):
    """A static argument whose value cannot be described exactly."""


def _canon(x, depth=0) -> str:
    """An exact text of a static value (raises :class:`_Unkept` for anything it cannot describe)."""
    if depth > 40:
        raise _Unkept("nested too deep")
    if x is None or x is Ellipsis or isinstance(x, (bool, int, float, complex, str, bytes)):
        return f"{type(x).__name__}:{x!r}"
    if isinstance(x, enum.Enum):
        return f"E:{type(x).__module__}.{type(x).__qualname__}.{x.name}"
    if isinstance(x, np.generic):
        return f"np.{x.dtype}:{x.item()!r}"
    if isinstance(x, np.ndarray):
        a = np.ascontiguousarray(x)
        return f"nd{a.dtype}{a.shape}:{hashlib.sha256(a.tobytes()).hexdigest()[:20]}"
    if isinstance(x, (tuple, list)):
        return f"{type(x).__name__}(" + ",".join(_canon(v, depth + 1) for v in x) + ")"
    if isinstance(x, dict):
        return "dict{" + ",".join(sorted(f"{_canon(k, depth + 1)}:{_canon(v, depth + 1)}" for k, v in x.items())) + "}"
    if isinstance(x, (set, frozenset)):
        return f"{type(x).__name__}{{" + ",".join(sorted(_canon(v, depth + 1) for v in x)) + "}"
    if isinstance(x, type):
        return f"T:{x.__module__}.{x.__qualname__}"
    if isinstance(x, functools.partial):
        return f"partial({_canon(x.func, depth + 1)},{_canon(x.args, depth + 1)},{_canon(x.keywords, depth + 1)})"
    if isinstance(x, types.FunctionType):
        if not str(getattr(x, "__module__", "")).startswith("bearingsim"):
            _OUTSIDE.flag = True        # its globals are not in the source hash: memory only
        cells = tuple(c.cell_contents for c in (x.__closure__ or ()))
        return (f"F:{x.__module__}.{x.__qualname__}:{_canon(x.__code__, depth + 1)}{_canon(cells, depth + 1)}"
                f"{_canon(x.__defaults__, depth + 1)}{_canon(x.__kwdefaults__, depth + 1)}")
    if isinstance(x, types.CodeType):           # bytecode, constants (nested code too) and names
        return (f"C@{x.co_firstlineno}:{hashlib.sha256(x.co_code).hexdigest()[:12]}"
                f"{_canon(x.co_consts, depth + 1)}{_canon(x.co_names, depth + 1)}")
    if isinstance(x, (types.BuiltinFunctionType, np.ufunc)):
        return f"B:{getattr(x, '__module__', '')}.{x.__name__}"
    if isinstance(x, types.MethodType):
        return f"M:{_canon(x.__func__, depth + 1)}.{_canon(x.__self__, depth + 1)}"
    if isinstance(x, jax.Array) and not isinstance(x, jax.core.Tracer):
        return _canon(np.asarray(x), depth + 1)
    if isinstance(x, jax.tree_util.PyTreeDef):
        return _canon_tree(x, depth + 1)
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return (f"D:{type(x).__module__}.{type(x).__qualname__}(" +
                ",".join(f"{f.name}={_canon(getattr(x, f.name, None), depth + 1)}" for f in dataclasses.fields(x)) + ")")
    if type(x).__module__.split(".")[0] in ("equinox", "jax") and not getattr(x, "__dict__", {}) \
            and not getattr(type(x), "__slots__", ()):
        return f"S:{type(x).__module__}.{type(x).__qualname__}"      # a stateless sentinel (equinox's Missing)
    raise _Unkept(f"{type(x).__module__}.{type(x).__qualname__}")


def _canon_tree(tree, depth=0) -> str:
    """An exact text of a tree structure: node types, their aux data (by :func:`_canon`), children."""
    node = tree.node_data()
    if node is None:                        # a leaf
        return "*"
    kind, aux = node
    return (f"{_canon(kind, depth + 1)}[{_canon(aux, depth + 1)}](" +
            ",".join(_canon_tree(c, depth + 1) for c in tree.children()) + ")")


class _Slot:
    """Where an output array goes in a kept program's output template."""

    __slots__ = ("i",)

    def __init__(self, i):
        self.i = i

    def __reduce__(self):
        return (_Slot, (self.i,))


def _device(dyn_leaves):
    """The device a call runs on: a committed argument's, else JAX's default device."""
    for leaf in dyn_leaves:
        if isinstance(leaf, jax.Array) and getattr(leaf, "committed", False):
            return next(iter(leaf.devices()))
    dev = jax.config.jax_default_device
    if dev is None:
        return jax.devices()[0]
    return jax.devices(dev)[0] if isinstance(dev, str) else dev


class KeptProgram:
    """:func:`equinox.filter_jit` of ``fun`` compiled with :func:`bearingsim.xla.compiler_options`,
    whose traced programs are kept on disk (:func:`jit`).  Called inside another trace it is a
    plain nested ``filter_jit`` (the outer program's options apply)."""

    def __init__(self, fun, name=None, options=()):
        self._fun, self._extra = fun, tuple(options)      # extra: per-program XLA options
        self._name = name or f"{getattr(fun, '__module__', '?')}.{getattr(fun, '__qualname__', repr(fun))}"
        self._programs: dict = {}
        self._plain = None
        self._nested = None
        self._lock = threading.Lock()       # threads calling a new configuration at once trace it once
        functools.update_wrapper(self, fun)
        _ALL.add(self)

    # -- the fallbacks: an ordinary jit (a static it cannot describe) and the nested call
    def _jit(self, *args, **kwargs):
        with _LOCK:
            COUNTS["unkept"] += 1
        if self._plain is None:
            self._plain = eqx.filter_jit(self._fun, compiler_options=compiler_options(self._extra) or None)
        try:
            return self._plain(*args, **kwargs)
        except ValueError as e:
            if "compiler_options" not in str(e):
                raise
        return self._inner(*args, **kwargs)

    def __call__(self, *args, **kwargs):
        _listen()
        leaves, tree = jax.tree_util.tree_flatten((args, kwargs))
        is_dyn = [eqx.is_array(v) for v in leaves]
        dyn = [v for v, d in zip(leaves, is_dyn) if d]
        if any(isinstance(v, jax.core.Tracer) for v in dyn):        # inside another program
            return self._inner(*args, **kwargs)
        try:
            static = [None if d else v for v, d in zip(leaves, is_dyn)]
            avals = tuple((tuple(np.shape(v)), str(v.dtype), bool(getattr(v, "weak_type", False)))
                          for v in dyn)
            dev = _device(dyn)
            _OUTSIDE.flag = False
            desc = (f"{self._name}|{_canon(self._fun)}|{_canon_tree(tree)}|{_canon(static)}|{avals}|"
                    f"{dev.platform}|{_canon(compiler_options(self._extra))}")
            disk = not _OUTSIDE.flag
        except _Unkept:
            return self._jit(*args, **kwargs)
        key = hashlib.sha256(f"{source_hash()}|{desc}".encode()).hexdigest()[:32]
        mem = (key, dev.id)
        prog = self._programs.get(mem)
        if prog is None:
            with self._lock:
                prog = self._programs.get(mem)
                if prog is None:
                    prog = self._load_or_trace(key, tree, is_dyn, static, dyn, avals, dev, disk) or False
                    self._programs[mem] = prog
        elif prog is not False:
            with _LOCK:
                COUNTS["memory"] += 1
        if _RECORDING and disk and prog is not False:
            _note_use((self._name, key), threading.current_thread() is threading.main_thread())
        if prog is False:                               # jax.export refused it: an ordinary program
            return self._jit(*args, **kwargs)
        call, template = prog
        try:
            flat = call(*dyn)
        except ValueError as e:     # inside another trace on constants: JAX takes compile options at the top only
            if "compiler_options" not in str(e):
                raise
            return self._inner(*args, **kwargs)
        out_leaves, out_tree = jax.tree_util.tree_flatten(template)
        merged = [flat[v.i] if isinstance(v, _Slot) else v for v in out_leaves]
        return jax.tree_util.tree_unflatten(out_tree, merged)

    def _inner(self, *args, **kwargs):
        if self._nested is None:
            self._nested = eqx.filter_jit(self._fun)
        return self._nested(*args, **kwargs)

    def _load_or_trace(self, key, tree, is_dyn, static, dyn, avals, dev, disk=True):
        d = program_dir() if disk else None
        path = None if d is None else d / f"{key}.jaxprog"
        if path is not None and path.is_file():
            why = "another format"          # a file of another bearingsim/JAX version
            try:
                blob = pickle.loads(path.read_bytes())
                if blob.get("format") == FORMAT:
                    exp = jax.export.deserialize(bytearray(blob["exported"]))
                    # a file written by a process whose source changed while it ran (a developer
                    # editing during a run) can hold another program under this key: its
                    # arguments must be exactly this call's, else it is traced again
                    if [(tuple(a.shape), np.dtype(a.dtype)) for a in exp.in_avals] == \
                            [(tuple(s), np.dtype(t)) for s, t, _ in avals]:
                        with _LOCK:
                            COUNTS["loaded"] += 1
                        return self._callable(exp, dev), blob["template"]
                    why = "its arguments differ from the call's"
            except Exception as e:      # noqa: BLE001 - any unreadable file is traced again
                why = type(e).__name__
            print(f"bearingsim: kept program {path.name} of {self._name} unreadable ({why}); "
                  "tracing it again", file=sys.stderr)
        holder = {}

        def flat_fun(*dyn_in):       # named after the function below (the exported module's name)
            it = iter(dyn_in)
            args, kwargs = jax.tree_util.tree_unflatten(tree, [next(it) if d_ else s for s, d_ in zip(static, is_dyn)])
            out = self._fun(*args, **kwargs)
            o_leaves, o_tree = jax.tree_util.tree_flatten(out)
            arrays, slots, n = [], [], 0
            for v in o_leaves:
                if eqx.is_array(v):
                    arrays.append(v)
                    slots.append(_Slot(n))
                    n += 1
                else:
                    slots.append(v)
            holder["template"] = jax.tree_util.tree_unflatten(o_tree, slots)
            return arrays

        flat_fun.__name__ = flat_fun.__qualname__ = getattr(self._fun, "__name__", "program")
        specs = [jax.ShapeDtypeStruct(s, np.dtype(t), weak_type=w) for s, t, w in avals]
        try:
            exp = jax.export.export(jax.jit(flat_fun), platforms=[lowering_platform(dev)])(*specs)
            data = exp.serialize()
            exp = jax.export.deserialize(data)          # the same program, cold or warm
            blob = pickle.dumps({"format": FORMAT, "name": self._name, "exported": bytes(data),
                                 "template": holder["template"]})
        except Exception:   # noqa: BLE001 - a program export refuses (a host callback, ...): unkept
            return None
        with _LOCK:
            COUNTS["traced"] += 1
        if path is not None:
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
                tmp = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
                tmp.write_bytes(blob)
                os.replace(tmp, path)
            except OSError:
                pass            # a read-only cache: kept in memory for this process
        return self._callable(exp, dev), holder["template"]

    @property
    def name(self) -> str:
        return self._name

    def prefetch(self, key, dev):
        """Load the kept program ``key`` and compile it for ``dev`` ahead of its first call
        (:func:`bearingsim.warm.prefetching`; a missing or unreadable file: nothing)."""
        mem, d = (key, dev.id), program_dir()
        if d is None or mem in self._programs:
            return
        with self._lock:
            if mem in self._programs:
                return
            try:
                blob = pickle.loads((d / f"{key}.jaxprog").read_bytes())
                if blob.get("format") != FORMAT:
                    return
                exp = jax.export.deserialize(bytearray(blob["exported"]))
                on = jax.sharding.SingleDeviceSharding(dev)
                specs = [jax.ShapeDtypeStruct(a.shape, a.dtype, sharding=on) for a in exp.in_avals]
                jitted = self._callable(exp, dev)
                compiled = jitted.lower(*specs).compile()
            except Exception:           # noqa: BLE001 - the call loads or traces it itself
                return

            def call(*a):
                try:
                    return compiled(*a)
                except TypeError:       # an argument's weak type: the jitted program (compiles it again)
                    return jitted(*a)
            with _LOCK:
                COUNTS["loaded"] += 1
                COUNTS["prefetched"] += 1
            self._programs[mem] = (call, blob["template"])

    def _callable(self, exp, dev):
        def call(*a):
            return exp.call(*a)

        # compile logs and profiles name the program after its function (jit(ball_errors)); every
        # argument placed on ``dev``: committed or not, one compiled program (jit compiles again
        # for another pattern of committed arguments)
        call.__name__ = call.__qualname__ = getattr(self._fun, "__name__", "program")
        on = jax.sharding.SingleDeviceSharding(dev)
        n = len(exp.in_avals)
        return jax.jit(call, in_shardings=(on,) * n, compiler_options=compiler_options(self._extra) or None)

    def lower(self, *args, **kwargs):
        """The ordinary (unkept) lowering of ``fun`` for these arguments."""
        return eqx.filter_jit(self._fun, compiler_options=compiler_options(self._extra) or None).lower(*args, **kwargs)


#: the dicts of (kept program name, key) that the active :func:`record` calls fill
_RECORDING: list = []


def record(into: dict, on: bool = True) -> None:
    """Record in ``into`` (a dict, in order of first use) the (name, key) of every kept program
    called from now on: the rank of the main thread's first call of it, None while only other
    threads called it (``on`` False: stop; :func:`bearingsim.warm.prefetching`)."""
    with _LOCK:
        _RECORDING.append(into) if on else _RECORDING.remove(into)


def _note_use(entry, main: bool) -> None:
    with _LOCK:
        for rec in (r for r in _RECORDING if r.get(entry) is None):
            rec[entry] = sum(v is not None for v in rec.values()) if main else None


def kept_programs() -> dict:
    """Every :class:`KeptProgram` of this process by its name."""
    return {p.name: p for p in list(_ALL)}


def count(what: str) -> None:
    """Add one to :data:`COUNTS` ``what`` (thread-safe)."""
    with _LOCK:
        COUNTS[what] = COUNTS.get(what, 0) + 1


Undescribable = _Unkept        # a value describe() cannot describe exactly


def describe(value) -> str:
    """The exact text of a static value or tree structure that program keys use (raises
    :class:`Undescribable`)."""
    return _canon(value)


def jit(fun=None, *, name=None, options=()):
    """:func:`equinox.filter_jit` (arrays traced, everything else static) whose traced programs are
    kept in the program cache (module docstring); ``jit(f)`` or a decorator.  ``options``: extra
    XLA options of this program, (key, value) pairs (:data:`bearingsim.xla.QUICK_COMPILE`)."""
    if fun is None:
        return lambda f: KeptProgram(f, name, options)
    return KeptProgram(fun, name, options)
