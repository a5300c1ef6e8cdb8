"""Where the suite's time goes: a pytest plugin that adds up, per test, the time JAX spends
tracing, lowering and compiling (``jax.monitoring`` duration events) and the programs
``bearingsim.programs`` traced, loaded and compiled, then a report per file.

    PYTHONPATH=benchmarks .venv/bin/python -m pytest -p suite_census -n 2 --dist loadfile tests ...
    .venv/bin/python benchmarks/suite_census.py [CENSUS_DIR]     # the report

Each process (controller, xdist workers) writes ``$BEARINGSIM_CENSUS_DIR/<pid>.json`` (default
``.census/``) at its end: ``{nodeid: {"wall_s", "trace_s", "lower_s", "compile_s",
"cache_hit_s", "traced", "loaded", "compiled"}}`` and, under ``"programs"``, every XLA compilation
of the process as ``[nodeid, module name, seconds]`` (the report's families: which programs, in
how many configurations; through JAX's private ``compiler._compile_and_write_cache``, left out
with a line where this JAX has no such function).  Notebook kernels run in their own processes
and are not seen: their time shows as wall time only.
"""
from __future__ import annotations

import json
import os
import sys
import time
from collections import defaultdict
from pathlib import Path

#: jax.monitoring duration events -> column
EVENTS = {
    "/jax/core/compile/jaxpr_trace_duration": "trace_s",
    "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower_s",
    "/jax/core/compile/backend_compile_duration": "compile_s",
    "/jax/compilation_cache/cache_retrieval_time_sec": "cache_hit_s",
}
COLUMNS = ("wall_s", "trace_s", "lower_s", "compile_s", "cache_hit_s", "traced", "loaded", "compiled")

_rows: dict = defaultdict(lambda: dict.fromkeys(COLUMNS, 0.0))
_current = ["<collection>"]
_programs: list = []


def _log_compilations():
    """Wrap JAX's compile-and-write-cache step to log (test, module name, seconds) per compilation."""
    try:
        from jax._src import compiler
        inner = compiler._compile_and_write_cache
    except (ImportError, AttributeError):
        print("suite_census: this JAX has no compiler._compile_and_write_cache; no program families")
        return

    def logged(*args, **kwargs):
        t0 = time.perf_counter()
        out = inner(*args, **kwargs)
        name = kwargs.get("module_name", args[5] if len(args) > 5 else "?")
        _programs.append([_current[0], str(name), round(time.perf_counter() - t0, 4)])
        return out

    compiler._compile_and_write_cache = logged


def _listener(event, duration, **_):
    col = EVENTS.get(event)
    if col:
        _rows[_current[0]][col] += float(duration)


def _program_counts():
    try:
        from bearingsim import programs
        c = programs.counts()
        return {k: c.get(k, 0) for k in ("traced", "loaded", "compiled")}
    except Exception:           # noqa: BLE001 - census only
        return dict(traced=0, loaded=0, compiled=0)


def pytest_configure(config):
    import jax.monitoring
    jax.monitoring.register_event_duration_secs_listener(_listener)
    _log_compilations()


def pytest_runtest_protocol(item, nextitem):
    _current[0] = item.nodeid
    before = _program_counts()
    t0 = time.perf_counter()
    item._census = (before, t0)


def pytest_runtest_makereport(item, call):
    if call.when == "teardown" and hasattr(item, "_census"):
        before, t0 = item._census
        row = _rows[item.nodeid]
        row["wall_s"] += time.perf_counter() - t0
        after = _program_counts()
        for k in ("traced", "loaded", "compiled"):
            row[k] += after[k] - before[k]


def pytest_unconfigure(config):
    out = Path(os.environ.get("BEARINGSIM_CENSUS_DIR", ".census"))
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{os.getpid()}.json").write_text(json.dumps({**_rows, "programs": _programs}, indent=0))


def report(folder):
    files: dict = defaultdict(lambda: dict.fromkeys(COLUMNS, 0.0))
    programs: list = []
    for p in Path(folder).glob("*.json"):
        rows = json.loads(p.read_text())
        programs += rows.pop("programs", [])
        for nodeid, row in rows.items():
            f = files[nodeid.split("::")[0]]
            for k in COLUMNS:
                f[k] += row.get(k, 0.0)
    total = dict.fromkeys(COLUMNS, 0.0)
    print(f"{'file':58s} " + " ".join(f"{c:>10s}" for c in COLUMNS))
    for name, f in sorted(files.items(), key=lambda kv: -kv[1]["wall_s"]):
        for k in COLUMNS:
            total[k] += f[k]
        print(f"{name[:58]:58s} " + " ".join(f"{f[c]:10.1f}" for c in COLUMNS))
    print(f"{'total':58s} " + " ".join(f"{total[c]:10.1f}" for c in COLUMNS))
    if programs:
        fam: dict = defaultdict(lambda: [0, 0.0, set()])
        for nodeid, name, sec in programs:
            fam[name][0] += 1
            fam[name][1] += sec
            fam[name][2].add(nodeid.split("::")[0])
        small = [sec for _, _, sec in programs if sec < 0.25]
        print(f"\n{len(programs)} compilations, {sum(s for *_, s in programs):.0f} s; "
              f"{len(small)} under 0.25 s ({sum(small):.0f} s). Largest program families:")
        print(f"{'program':40s} {'configurations':>14s} {'seconds':>8s} {'files':>6s}")
        for name, (n, sec, fs) in sorted(fam.items(), key=lambda kv: -kv[1][1])[:20]:
            print(f"{name[:40]:40s} {n:14d} {sec:8.1f} {len(fs):6d}")


if __name__ == "__main__":
    report(sys.argv[1] if len(sys.argv) > 1 else ".census")
