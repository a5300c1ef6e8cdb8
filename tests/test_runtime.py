"""Every entry point uses a persistent compilation cache by default (issue 27 item 3): a per-user
folder (~/.cache/bearingsim/jax, or $XDG_CACHE_HOME/bearingsim/jax), moved by
BEARINGSIM_CACHE_DIR, switched off by BEARINGSIM_CACHE_DIR=off, JAX_COMPILATION_CACHE_DIR first;
`import bearingsim` and `bearingsim --help` load no JAX; a cold cache is said and counted."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

from bearingsim import runtime

ROOT = Path(__file__).resolve().parents[1]
SNIPPET = ("import sys, bearingsim, jax, jax.numpy as jnp; "
           "print(jax.jit(lambda x: x * 3.0 + 1.0)(jnp.arange(3.0)).dtype); "
           "print(jax.config.jax_compilation_cache_dir)")


def run(env_extra, tmp_path, code=SNIPPET):
    env = {k: v for k, v in os.environ.items()
           if k not in ("JAX_COMPILATION_CACHE_DIR", "BEARINGSIM_CACHE_DIR", "XDG_CACHE_HOME", "BEARINGSIM_CACHE",
                        "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "JAX_ENABLE_X64")}
    env.update(HOME=str(tmp_path / "home"), PYTHONPATH=str(ROOT), **env_extra)
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300,
                       cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    return r.stdout.split()


def entries(d):
    return [p for p in Path(d).glob("*") if p.is_file()] if Path(d).is_dir() else []


def test_default_cache_is_in_the_users_home(tmp_path):
    dtype, where = run({}, tmp_path)
    home = tmp_path / "home" / ".cache" / "bearingsim" / "jax"
    assert dtype == "float64" and Path(where) == home
    assert entries(home), "the compiled program was not kept"


def test_bearingsim_cache_dir_moves_it_and_off_disables_it(tmp_path):
    moved = tmp_path / "elsewhere"
    _, where = run({"BEARINGSIM_CACHE_DIR": str(moved)}, tmp_path)
    assert Path(where) == moved and entries(moved)
    assert not (tmp_path / "home" / ".cache").exists()
    out = run({"BEARINGSIM_CACHE_DIR": "off"}, tmp_path)
    assert out == ["float64"] or out[1] in ("None", "")         # no folder configured
    assert not (tmp_path / "home" / ".cache").exists()
    xdg = tmp_path / "xdg"
    _, where = run({"XDG_CACHE_HOME": str(xdg)}, tmp_path)
    assert Path(where) == xdg / "bearingsim" / "jax"


def test_jax_variable_keeps_precedence(tmp_path):
    make = tmp_path / "make_cache"
    _, where = run({"JAX_COMPILATION_CACHE_DIR": str(make), "BEARINGSIM_CACHE_DIR": str(tmp_path / "b")}, tmp_path)
    assert Path(where) == make and entries(make) and not (tmp_path / "b").exists()


def test_cache_dir_rules():
    assert runtime.cache_dir({"HOME": "/h"}) == Path("/h/.cache/bearingsim/jax")
    assert runtime.cache_dir({"HOME": "/h", "XDG_CACHE_HOME": "/x"}) == Path("/x/bearingsim/jax")
    assert runtime.cache_dir({"HOME": "/h", "BEARINGSIM_CACHE_DIR": "/b"}) == Path("/b")
    for off in ("off", "0", "none", "", "OFF"):
        assert runtime.cache_dir({"HOME": "/h", "BEARINGSIM_CACHE_DIR": off}) is None
    assert runtime.cache_dir({"JAX_COMPILATION_CACHE_DIR": "/j", "BEARINGSIM_CACHE_DIR": "off"}) == Path("/j")


def test_import_and_help_load_no_jax(tmp_path):
    code = ("import sys, bearingsim; from bearingsim.app.cli import build_parser; "
            "h = build_parser().format_help(); print('jax' in sys.modules, 'spectrum' in h, "
            "bearingsim.__version__ is not None)")
    assert run({"BEARINGSIM_CACHE_DIR": "off"}, tmp_path, code) == ["False", "True", "True"]
    # the exports still resolve (at first use)
    code = "import bearingsim; print(bearingsim.solve.__name__, bearingsim.load_dataset.__name__)"
    assert run({"BEARINGSIM_CACHE_DIR": "off"}, tmp_path, code) == ["solve", "load_dataset"]


#: the nouns a user types (issue 27 item 7)
NOUNS = ("solve", "solve_batch", "solve_set", "sweep", "simulate", "load_case", "solve_case", "study_case",
         "make_dataset", "load_dataset", "identify", "Bearing", "BearingSet", "Operation", "Spall")


def test_every_exported_noun_resolves_lazily(tmp_path):
    """Each name of ``bearingsim.__all__`` resolves at first use, after an import that loaded no
    JAX, and the nouns a user types are bearingsim's objects of that name (the function or class,
    or for ``sweep`` and ``identify`` the module that calls it: Python rebinds ``bearingsim.physics.sweep``
    to the submodule whenever it is imported, so the submodule-first order is checked too)."""
    code = ("import sys, bearingsim; before = 'jax' in sys.modules; "
            "missing = [n for n in bearingsim.__all__ if getattr(bearingsim, n, None) is None]; "
            "import bearingsim.physics.sweep as sw, bearingsim.realism.identify as idm; "
            "print(before, missing, sw is bearingsim.physics.sweep, callable(bearingsim.physics.sweep), "
            "callable(bearingsim.realism.identify), set(bearingsim.__all__) <= set(dir(bearingsim)))")
    assert run({"BEARINGSIM_CACHE_DIR": "off"}, tmp_path, code) == ["False", "[]"] + ["True"] * 4
    code = "import bearingsim.physics.sweep, bearingsim; print(callable(bearingsim.physics.sweep), bearingsim.physics.sweep.sweep.__module__)"
    assert run({"BEARINGSIM_CACHE_DIR": "off"}, tmp_path, code) == ["True", "bearingsim.physics.sweep"]
    code = ("import bearingsim; print(*[(o.__name__.split('.')[-1], o.__module__.split('.')[0]) == (n, 'bearingsim') "
            f"for n, o in ((n, getattr(bearingsim, n)) for n in {NOUNS!r})])")
    assert run({"BEARINGSIM_CACHE_DIR": "off"}, tmp_path, code) == ["True"] * len(NOUNS)


def test_cold_cache_is_said_and_counted(tmp_path, monkeypatch):
    from bearingsim.datasets import budget
    from bearingsim.case import load_case

    monkeypatch.setattr(runtime, "configured_cache_dir", lambda: tmp_path)
    case = load_case("dataset_cwru")
    est = budget.check_case(case, "dataset")
    assert est.compile_seconds == budget.COMPILE_SECONDS["dataset"]
    assert "compiling included" in est.text() and "first run only" in budget.compile_notice(case, "dataset")
    base = est.seconds
    assert f"~{budget.human_bytes(0)}" not in est.text()
    budget.mark_compiled(case, "dataset")
    warm = budget.check_case(case, "dataset")
    assert warm.compile_seconds == 0.0 and budget.compile_notice(case, "dataset") is None
    assert warm.seconds == base and "compiling" not in warm.text()
    assert 0 < warm.load_seconds < est.compile_seconds and "loading the compiled programs" in warm.text()
    # another shape of programs (item length) is cold again
    other = case.with_value("dataset.duration_s", 0.05)
    assert budget.compile_notice(other, "dataset") is not None


def test_cache_command_says_where_and_clears(tmp_path):
    code = ("from bearingsim.app.cli import main; import jax, jax.numpy as jnp; jax.jit(lambda x: x + 2.0)(jnp.ones(2)); "
            "main(['cache']); main(['cache', '--clear'])")
    d = tmp_path / "c"
    banks = tmp_path / "banks"          # never the test session's bank cache (run() drops BEARINGSIM_CACHE)
    banks.mkdir()
    (banks / "identify_bank_160_7101_v6.h5").write_bytes(b"x" * 10)
    (banks / "keep.txt").write_text("not a bank")
    (banks / "transfer_cwru_120_v7_0123456789ab.h5").write_bytes(b"y" * 10)     # a cached data set
    (banks / "transfer_cwru_120_v7_0123456789ab.h5.lock").write_bytes(b"")
    out = " ".join(run({"BEARINGSIM_CACHE_DIR": str(d), "BEARINGSIM_CACHE": str(banks)}, tmp_path, code))
    assert f"compilation cache: {d}" in out and "cleared:" in out and not entries(d)
    assert "identify banks:" in out and "1 identify bank files deleted" in out     # issue 34: the bank too
    assert "cached data sets: 1 files" in out and "1 cached data sets deleted" in out
    assert sorted(p.name for p in banks.iterdir()) == ["keep.txt"]


def test_cache_command_names_an_unusable_folder(tmp_path):
    """Issue 35: `bearingsim cache` with an unusable BEARINGSIM_CACHE_DIR said "off
    (BEARINGSIM_CACHE_DIR=off)"; it names the folder and why."""
    (tmp_path / "file").write_text("x")
    bad = tmp_path / "file" / "cache"
    code = "from bearingsim.app.cli import main; main(['cache']); main(['cache', '--clear'])"
    out = " ".join(run({"BEARINGSIM_CACHE_DIR": str(bad)}, tmp_path, code))
    assert f"compilation cache: {bad} cannot be used" in out and "=off)" not in out
