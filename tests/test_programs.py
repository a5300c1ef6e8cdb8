"""The program cache (bearingsim.programs): a warm process loads a traced program instead of
tracing it, the key tells every static configuration apart, and a bad file is traced again."""
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from bearingsim import programs, warm, xla
from bearingsim.programs import jit

ROOT = Path(__file__).resolve().parent.parent


class Scale(eqx.Module):
    gain: jax.Array
    mode: str = eqx.field(static=True)


def _f(x, s: Scale, power, flag=True):
    y = s.gain * x ** power
    return {"y": y if flag else -y, "mode": s.mode, "n": power}


def test_kept_program_equals_the_function_and_tells_statics_apart(tmp_path, monkeypatch):
    """Every static value is part of the key: another power, flag, static field or shape gives
    another program (and the right answer), never a neighbour's (the collision that sank the
    last attempt: a program run with another configuration's arguments)."""
    monkeypatch.setenv("JAX_COMPILATION_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(programs, "program_dir", lambda: tmp_path / "p")
    f = jit(_f)
    x = jnp.linspace(0.0, 1.0, 5)
    before = programs.counts()
    for power in (1, 2, 3.0):
        for flag in (True, False):
            for mode in ("a", "b"):
                out = f(x, Scale(jnp.asarray(2.0), mode), power, flag=flag)
                want = _f(x, Scale(jnp.asarray(2.0), mode), power, flag)
                np.testing.assert_allclose(out["y"], want["y"], rtol=1e-14)   # compiled vs op by op: rounding only
                assert out["mode"] == mode and out["n"] == power
    out = f(jnp.ones(3), Scale(jnp.asarray(2.0), "a"), 2)           # another shape
    assert out["y"].shape == (3,)
    after = programs.counts()
    assert after["traced"] - before["traced"] == 13
    # a function defined outside the package (here a test's) is kept in memory only: the globals
    # it reads are in no hash, so a file could outlive an edit of them
    assert not (tmp_path / "p").exists()
    assert after["unkept"] == before["unkept"]


def test_the_key_holds_a_function_s_constants():
    """Two functions alike but for a constant (the same bytecode) are two programs."""
    f2 = jit(lambda x: x * 2.0)
    f3 = jit(lambda x: x * 3.0)
    np.testing.assert_array_equal(f2(jnp.ones(2)), [2.0, 2.0])
    np.testing.assert_array_equal(f3(jnp.ones(2)), [3.0, 3.0])
    assert programs._canon(lambda x: x * 2.0) != programs._canon(lambda x: x * 3.0)


def test_an_unknown_static_type_runs_unkept(tmp_path, monkeypatch):
    monkeypatch.setattr(programs, "program_dir", lambda: tmp_path / "p")

    class Opaque:
        pass

    f = jit(lambda x, o: x + 1.0)
    before = programs.counts()["unkept"]
    np.testing.assert_array_equal(f(jnp.zeros(2), Opaque()), [1.0, 1.0])
    assert programs.counts()["unkept"] == before + 1
    assert not (tmp_path / "p").exists()


def test_nested_call_inside_another_program_is_inlined():
    inner = jit(lambda x, k: x * k)
    outer = jax.jit(lambda x: inner(x, 3.0) + 1.0)
    np.testing.assert_allclose(outer(jnp.ones(2)), [4.0, 4.0])


SCRIPT = textwrap.dedent("""
    import json
    from bearingsim import programs
    from bearingsim.case import load_case
    from bearingsim.physics.hertz import stiffness_curve
    c = stiffness_curve(load_case("demo").bearing(), "exact")     # a program of the package
    leaves = [float(v) for v in __import__("jax").tree_util.tree_leaves(c)[0].ravel()[:4]]
    print(json.dumps(dict(programs.counts(), y=leaves)))
""")


def _run(cache):
    env = dict(os.environ, JAX_COMPILATION_CACHE_DIR=str(cache), BEARINGSIM_PROGRAM_CACHE="on")
    p = subprocess.run([sys.executable, "-c", SCRIPT], env=env,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    import json
    return json.loads(p.stdout.strip().splitlines()[-1]), p.stderr


def test_a_warm_process_loads_and_does_not_trace(tmp_path):
    cold, _ = _run(tmp_path)
    warm, _ = _run(tmp_path)
    assert cold["traced"] == 1 and cold["loaded"] == 0
    assert warm["traced"] == 0 and warm["loaded"] == 1
    assert warm["y"] == cold["y"] and len(cold["y"]) == 4
    # a damaged file: traced again with one line, and replaced
    (f,) = (tmp_path / "bearingsim-programs").glob("*.jaxprog")
    f.write_bytes(b"not a program")
    again, err = _run(tmp_path)
    assert again["traced"] == 1 and again["y"] == cold["y"]
    assert "unreadable" in err and "tracing it again" in err
    assert _run(tmp_path)[0]["loaded"] == 1
    # another program under this key (a process whose source was edited while it ran wrote it):
    # its arguments differ from the call's, so it is traced again, never run with the wrong ones
    import pickle
    spec = jax.ShapeDtypeStruct((2,), np.float64)
    other = jax.export.export(jax.jit(lambda a, b: a + b))(spec, spec)
    f.write_bytes(pickle.dumps({"format": programs.FORMAT, "exported": other.serialize(), "template": None}))
    again, err = _run(tmp_path)
    assert again["traced"] == 1 and again["y"] == cold["y"]
    assert "unreadable (its arguments differ" in err


def test_the_cache_can_be_switched_off(monkeypatch):
    monkeypatch.setenv("BEARINGSIM_PROGRAM_CACHE", "off")
    assert programs.program_dir() is None


def test_memo_computes_once_per_exact_input_and_survives_a_bad_file(tmp_path, monkeypatch):
    """warm.memo (the data set's substeps, run_settings): the second call with equal inputs
    reads the kept value without computing; any other input value (a float's last bit, another
    array, another equinox field) computes again; a damaged file is computed and replaced."""
    monkeypatch.setattr(programs, "program_dir", lambda: tmp_path / "p")
    calls = []

    def compute(v):
        def f():
            calls.append(v)
            return v
        return f

    base = (Scale(jnp.asarray(2.0), "a"), 0.1, np.arange(3.0), ("outer", "ball"))
    hits = programs.counts()["memo_hits"]
    assert warm.memo("t", base, compute(1)) == 1
    assert warm.memo("t", base, compute(2)) == 1            # read, not computed
    assert programs.counts()["memo_hits"] == hits + 1 and calls == [1]
    assert warm.recall("t", base) == 1 and warm.recall("t", base[:1] + (0.2,) + base[2:], "none") == "none"
    for other in ((Scale(jnp.asarray(2.0), "b"),) + base[1:], base[:1] + (np.nextafter(0.1, 1.0),) + base[2:],
                  base[:2] + (np.arange(3.0) + 1e-12,) + base[3:], base[:3] + (("outer",),)):
        assert warm.memo("t", other, compute(3)) == 3
    assert warm.memo("u", base, compute(4)) == 4             # another name
    assert calls == [1, 3, 3, 3, 3, 4]
    for f in (tmp_path / "p").glob("*.memo.json"):
        f.write_text("{not json")
    assert warm.memo("t", base, compute(5)) == 5 and warm.memo("t", base, compute(6)) == 5
    monkeypatch.setattr(programs, "program_dir", lambda: None)   # no cache folder: every call computes
    assert warm.memo("t", base, compute(7)) == 7


def test_prefetching_loads_what_the_last_run_used_before_it_is_called(tmp_path, monkeypatch):
    """warm.prefetching (a data set's chunk programs load in background threads while its
    labels are drawn): a run records the kept programs it used; the next run under the same name
    loads and compiles them before their first call, which then neither loads nor traces, with
    the same result."""
    from bearingsim.keys import item_keys
    monkeypatch.setattr(programs, "program_dir", lambda: tmp_path / "p")
    programs.forget()
    with warm.prefetching("t"):
        first = np.asarray(item_keys(3, [0, 1, 5]))
    assert len(list((tmp_path / "p").glob("*.prefetch.json"))) == 1
    programs.forget()
    before = programs.counts()
    with warm.prefetching("t"):
        pass                                    # the threads are joined on exit
    mid = programs.counts()
    assert mid["prefetched"] - before["prefetched"] == 1 and mid["traced"] == before["traced"]
    again = np.asarray(item_keys(3, [0, 1, 5]))
    after = programs.counts()
    assert after["loaded"] == mid["loaded"] and after["traced"] == mid["traced"]
    assert after["memory"] == mid["memory"] + 1
    np.testing.assert_array_equal(again, first)
    with warm.prefetching("another name"):  # nothing recorded under it: nothing loaded
        pass
    assert programs.counts()["prefetched"] == after["prefetched"]


def test_prefetching_loads_first_what_the_main_thread_needed_first(tmp_path, monkeypatch, b218):
    """The recorded order is the main thread's order of first use, then the programs only other
    threads used: a background thread's early call of a program the main thread needs later
    (a warm `bearingsim simulate`: the ball check's compile thread called ball_errors before the
    main thread needed solve_state) does not put it ahead of the main thread's first program."""
    import json
    import threading

    from bearingsim.keys import item_keys
    from bearingsim.physics.hertz import stiffness_curve

    monkeypatch.setattr(programs, "program_dir", lambda: tmp_path / "p")
    with warm.prefetching("order"):
        t = threading.Thread(target=lambda: stiffness_curve(b218))     # another thread first
        t.start()
        t.join()
        item_keys(3, [0, 1])                                           # the main thread: keys,
        stiffness_curve(b218)                                          # then the curve
    (rec,) = (tmp_path / "p").glob("*.prefetch.json")
    names = [n.rsplit(".", 1)[-1] for n, _ in json.loads(rec.read_text())]
    assert names == ["_item_keys", "_stiffness_curve"]


def test_the_export_lowers_for_the_platform_a_gpu_device_names():
    """A JAX GPU device says ``gpu`` but :func:`jax.export.export` lowers for ``cuda`` or ``rocm``:
    exporting with the device's own name failed every kept program on an H200 (jax 0.11.2,
    2026-11-28: "exported for platforms ('gpu',) but it is used on ('cuda',)").  The CPU's name
    is its lowering platform, and the name given is one the exporter accepts."""
    class Client:
        def __init__(self, version):
            self.platform_version = version

    class Device:
        def __init__(self, platform, version=""):
            self.platform, self.client = platform, Client(version)

    assert xla.lowering_platform(Device("gpu", "PJRT C API\ncuda 13000")) == "cuda"
    assert xla.lowering_platform(Device("gpu", "rocm 6.2")) == "rocm"
    cpu = jax.devices("cpu")[0]
    assert xla.lowering_platform(cpu) == "cpu"
    exp = jax.export.export(jax.jit(lambda a: a + 1.0), platforms=[xla.lowering_platform(cpu)])(
        jax.ShapeDtypeStruct((2,), np.float64))
    assert exp.platforms == ("cpu",)


def test_a_program_s_own_options_are_part_of_its_key_and_an_unknown_one_falls_back(tmp_path, monkeypatch):
    """``jit(f, options=...)`` compiles with the package's options plus its own (the single Jones
    state at LLVM -O0, ``xla.QUICK_COMPILE``): the same answer as without them, a program of its
    own (the options are in the key: a warm process never runs the other level's program), and an
    option this jaxlib does not know gives the package's options alone, not a failure."""
    monkeypatch.setattr(programs, "program_dir", lambda: tmp_path / "p")
    quick = xla.compiler_options(xla.QUICK_COMPILE)
    assert dict(xla.QUICK_COMPILE).items() <= quick.items() and xla.PREFERRED_OPTIONS.items() <= quick.items()
    # LLVM at -O0: one object file (xla.QUICK_CODEGEN); XLA's default level: its parallel parts
    assert dict([xla.QUICK_CODEGEN]).items() <= quick.items()
    assert xla.QUICK_CODEGEN[0] not in xla.compiler_options()
    assert xla.compiler_options((("xla_no_such_option_here", 1),)) == xla.compiler_options()
    x = jnp.linspace(0.0, 1.0, 7)
    s = Scale(jnp.asarray(2.0), "a")
    before = programs.counts()["traced"]
    a = jit(_f)(x, s, 3)
    b = jit(_f, options=xla.QUICK_COMPILE)(x, s, 3)
    assert programs.counts()["traced"] == before + 2
    np.testing.assert_allclose(np.asarray(a["y"]), np.asarray(b["y"]), rtol=1e-15)
