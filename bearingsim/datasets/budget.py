"""What a run will need, said before it starts; what cannot fit is refused, naming the keys.

``bearingsim dataset`` with ``count = 1e10`` or ``duration_s = 1e6`` used to end in a NumPy
memory traceback after minutes of work.  Every command that sizes arrays from case keys is
estimated here first (:func:`check_case`): memory of the largest step, disk of the output (the
data set's ``.partial/`` chunks and its HDF5 file both), and a rough wall time on one process of
this class of machine.  A run whose memory exceeds the machine's available memory, or whose
output exceeds the free disk space, raises :class:`~bearingsim.errors.InputError` (exit 2)
naming the keys that size it, before anything is written.  The per-sample costs are measured
(``docs/scale.md``): they are estimates, meant to catch orders of magnitude, not to bill.

:func:`check_output` refuses an output path that cannot be written (a directory, a folder the
system does not let us write in): :class:`~bearingsim.errors.OutputError` (exit 4), nothing created.
"""
from __future__ import annotations

import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

from .. import runtime
from ..errors import InputError, OutputError

__all__ = ["Estimate", "check_case", "check_output", "dataset_estimate", "simulation_estimate",
           "available_memory", "free_disk", "human_bytes", "COMPILE_SECONDS", "program_key",
           "compile_seconds", "compile_notice", "mark_compiled"]

#: compile time (s) of each command's programs with an empty cache, on one process of the 2-core
#: test machine (measured 2026-11-25, see docs/scale.md "Compilation cache"); with a warm cache
#: (the second run) they load in about a second
COMPILE_SECONDS = {"static": 6.0, "sweep": 10.0, "study": 12.0, "simulate": 30.0, "compare": 35.0,
                   "dataset": 35.0, "demo": 60.0, "spectrum": 0.0, "set": 10.0}
#: with a warm cache a process still traces its programs and loads them from the cache: this
#: share of the compile time (measured: a 40-item data set, 16 s warm vs 48 s cold, contended)
WARM_FRACTION = 0.3

#: memory of the libraries and the compiled programs of one process (JAX, XLA; measured ~0.75 GB)
BASE_BYTES = 1.0e9
#: memory per item-sample while a chunk (or a simulation) runs: its states, forces and signals
#: (measured: 1.1 kB for the 6205 data sets, max RSS of 0.05 s vs 0.5 s items)
SAMPLE_BYTES = 1.2e3
#: wall time per item-sample of one process (measured 7-13 us on the 2-core test machine)
SAMPLE_SECONDS = 1.0e-5
#: bytes per quasi-static state kept (a JonesSolution: ~30 arrays of Z float64) per ball
STATE_BYTES_PER_BALL = 30 * 8


def human_bytes(x: float) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if abs(x) < 1000 or unit == "PB":
            return f"{x:.3g} {unit}"
        x /= 1000.0
    return f"{x:.3g} PB"


def _human_time(s: float) -> str:
    for unit, f in (("years", 3.15e7), ("days", 86400), ("h", 3600), ("min", 60)):
        if s >= f:
            return f"{s / f:.3g} {unit}"
    return f"{s:.2g} s"


def available_memory():
    """Bytes of physical memory available now (None where the system does not say)."""
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def free_disk(path):
    """Free bytes on the file system that will hold ``path`` (its first existing ancestor)."""
    p = Path(path).resolve()
    while not p.exists() and p != p.parent:
        p = p.parent
    try:
        return shutil.disk_usage(p).free
    except OSError:
        return None


@dataclass(frozen=True)
class Estimate:
    """What a run needs: ``memory`` (bytes, peak of one process), ``disk`` (bytes written),
    ``seconds`` (rough wall time of one process), and the case keys that size each."""

    what: str
    memory: float
    disk: float
    seconds: float
    memory_keys: tuple
    disk_keys: tuple
    #: compile time of the programs when the cache is cold (0: compiled before, loaded from the cache)
    compile_seconds: float = 0.0
    #: with a warm cache: the time to trace the programs and load them from the cache
    load_seconds: float = 0.0

    def text(self, workers: int = 1) -> str:
        t = self.seconds / max(workers, 1) + self.compile_seconds + self.load_seconds
        comp = f", compiling included (~{_human_time(self.compile_seconds)}, first run only)" \
            if self.compile_seconds else f", loading the compiled programs included (~{_human_time(self.load_seconds)})" \
            if self.load_seconds else ""
        return (f"{self.what}: needs ~{human_bytes(self.memory)} of memory per process, "
                f"~{human_bytes(self.disk)} of disk, ~{_human_time(t)}"
                f"{f' on {workers} workers' if workers > 1 else ' in one process'}{comp} (rough: a prior from "
                "costs measured on a 2-core machine, docs/scale.md; a data set's progress shows the measured rate)")

    def check(self, source, output=None):
        """Raise :class:`InputError` if the memory or the disk cannot fit (every problem at once)."""
        problems = []
        mem = available_memory()
        if mem is not None and self.memory > mem:
            problems.append(f"{self.what} needs ~{human_bytes(self.memory)} of memory, "
                            f"{human_bytes(mem)} are available: lower " + " or ".join(self.memory_keys))
        if output is not None and self.disk > 0:
            free = free_disk(output)
            if free is not None and self.disk > free:
                problems.append(f"{self.what} writes ~{human_bytes(self.disk)} next to {output}, "
                                f"{human_bytes(free)} are free: lower " + " or ".join(self.disk_keys))
        if problems:
            raise InputError(f"{source}: " + "; ".join(problems))


def dataset_estimate(case) -> Estimate:
    """A ``[dataset]``: chunks of ``chunk`` items x duration x sample rate samples; the labels;
    the signals written twice (float32 chunk files in ``.partial/``, then the HDF5 file)."""
    ds = case.data["dataset"]
    fs = float(case.dynamics_settings()["sample_rate"])
    n = int(ds["count"])
    T = float(ds["duration_s"]) * fs
    chunk = min(int(ds["chunk"]) or 16 * (os.cpu_count() or 1), n)   # 0: the CPU rule of dataset.default_chunk
    labels = n * 400.0                                  # label table, order, seeds, pit depths
    memory = BASE_BYTES + chunk * T * SAMPLE_BYTES + labels
    disk = 2 * 4.0 * n * T + labels
    return Estimate(f"{n} items x {T:.0f} samples", memory, disk, n * T * SAMPLE_SECONDS,
                    ("dataset.chunk", "dataset.duration_s", "dynamics.sample_rate_Hz", "dataset.count"),
                    ("dataset.count", "dataset.duration_s", "dynamics.sample_rate_Hz"))


def simulation_estimate(case) -> Estimate:
    """One ``[dynamics]`` run: duration x sample rate samples (states, forces, the file)."""
    d = case.dynamics_settings()
    T = float(d["duration"]) * float(d["sample_rate"])
    return Estimate(f"a simulation of {T:.0f} samples", BASE_BYTES + T * SAMPLE_BYTES, T * 8.0 * 40,
                    T * SAMPLE_SECONDS, ("dynamics.duration_s", "dynamics.sample_rate_Hz"),
                    ("dynamics.duration_s", "dynamics.sample_rate_Hz"))


def _states_estimate(case, what, count, keys) -> Estimate:
    Z = int(case.data["bearing"]["balls"])
    b = count * Z * STATE_BYTES_PER_BALL
    return Estimate(what, BASE_BYTES + 4 * b, b, count * 1e-4, keys, keys)


def check_case(case, command, output=None):
    """Refuse a run of ``command`` on ``case`` that cannot fit (:class:`InputError` naming the
    keys); return its :class:`Estimate` (or None for a command that sizes nothing)."""
    est = []
    if command in ("sweep", "demo"):
        steps = int(case.data.get("sweep", {}).get("steps", 181))
        est.append(_states_estimate(case, f"a sweep of {steps} cage angles", steps, ("sweep.steps",)))
    if command == "study":
        st = case.study_settings()
        steps = int(case.data.get("sweep", {}).get("steps", 181))
        m = len(st[1]) if st else 1
        est.append(_states_estimate(case, f"a study of {m} values x {steps} cage angles", m * steps,
                                    ("study.values", "sweep.steps")))
    if command in ("simulate", "compare", "demo") and "dynamics" in case.data:
        est.append(simulation_estimate(case))
    if command == "dataset" and "dataset" in case.data:
        est.append(dataset_estimate(case))
    problems = []
    for e in est:
        try:
            e.check(case.source, output)
        except InputError as err:
            problems.append(str(err).split(": ", 1)[1])
    if problems:
        raise InputError(f"{case.source}: " + "; ".join(problems))
    if not est:
        return None
    from dataclasses import replace

    cold = compile_seconds(case, command)
    if cold is not None:
        return replace(est[-1], compile_seconds=cold)
    what = "set" if getattr(case, "is_set", False) and command in ("static", "study") else command
    return replace(est[-1], load_seconds=WARM_FRACTION * COMPILE_SECONDS.get(what, 0.0))


def program_key(case, command) -> str:
    """What decides which programs ``command`` compiles for ``case`` (the command, a set or one
    bearing, the number of balls, a defect or not, the data set's chunk and samples): two runs
    with the same key share their compiled programs."""
    d = case.data
    parts = [command, "set" if getattr(case, "is_set", False) else "one",
             str(d.get("bearing", {}).get("balls")), str(sorted(d.get("defect", {}) or d.get("spall", {}) or {}))]
    if command == "dataset" and "dataset" in d:
        parts += [str(d["dataset"].get("chunk")), str(d["dataset"].get("duration_s")),
                  str(d.get("dynamics", {}).get("sample_rate_Hz"))]
    if command in ("simulate", "compare", "demo") and "dynamics" in d:
        parts += [str(d["dynamics"].get("duration_s")), str(d["dynamics"].get("sample_rate_Hz"))]
    return "|".join(parts)


def compile_seconds(case, command):
    """Seconds the programs of ``command`` on ``case`` take to compile in this process: None when
    they were compiled into the persistent cache before (:func:`bearingsim.runtime.cold`)."""
    what = "set" if getattr(case, "is_set", False) and command in ("static", "study") else command
    s = COMPILE_SECONDS.get(what, 0.0)
    if not s or not runtime.cold(program_key(case, command)):
        return None
    return s


def compile_notice(case, command):
    """The line a command prints before it compiles with a cold cache (None when warm)."""
    s = compile_seconds(case, command)
    if s is None:
        return None
    where = runtime.configured_cache_dir()
    keep = f"kept in {where}" if where is not None else "not kept: BEARINGSIM_CACHE_DIR is off"
    return f"compiling, first run only: ~{_human_time(s)} (rough; the compiled programs are {keep})"


def mark_compiled(case, command):
    """Record that ``command``'s programs for ``case`` are in the persistent cache."""
    runtime.mark_warm(program_key(case, command))


def check_output(path, flag="-o"):
    """Refuse an output path that cannot be written, before any work: an existing directory, a
    parent that is a file, a folder the system will not let us write in (permissions, a read-only
    or virtual file system such as /sys): :class:`~bearingsim.errors.OutputError` (exit 4) naming
    the reason.  Nothing is left behind (the probe file is removed at once)."""
    if path is None:
        return
    p = Path(path)
    if p.is_dir():
        raise OutputError(f"cannot write {flag} {path}: it is a directory; give a file name, e.g. "
                          f"{p / 'out.h5'}")
    parent = p.absolute().parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise OutputError(f"cannot write {flag} {path}: {parent} is not a directory")
    try:
        with tempfile.TemporaryFile(dir=parent, prefix=".bearingsim-probe-"):
            pass
    except OSError as e:
        raise OutputError(f"cannot write {flag} {path}: {parent} does not accept files "
                          f"({e.strerror or e})") from None
