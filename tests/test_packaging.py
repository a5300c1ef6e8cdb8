"""The built wheel, installed (not editable) into a fresh environment, is a complete bearingsim:
every module, every shipped case loadable by name, and the command line working from any folder.

Offline: the wheel is built with the test environment's own setuptools (no build isolation) and
installed without dependencies; the fresh environment borrows the dependencies (jax, ...) from
the test environment's site-packages through a .pth line, which does not run that environment's
own .pth files, so the editable bearingsim there stays invisible.
"""
import os
import subprocess
import sys
import sysconfig
import venv
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def run(cmd, cwd, **kw):
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    r = subprocess.run([str(c) for c in cmd], cwd=cwd, env=env, capture_output=True, text=True,
                       timeout=600, **kw)
    assert r.returncode == 0, f"{cmd}\n{r.stdout}\n{r.stderr}"
    return r.stdout


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    base = tmp_path_factory.mktemp("packaging")
    run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index",
         "-q", "-w", base / "dist", ROOT], cwd=base)
    wheel = next((base / "dist").glob("bearingsim-*.whl"))
    env = base / "env"
    venv.EnvBuilder(with_pip=False).create(env)
    py = env / "bin" / "python"
    site = Path(run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], cwd=base).strip())
    (site / "test_environment.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    run([sys.executable, "-m", "pip", "--python", py, "install", "--no-deps", "--no-index", "-q", wheel],
        cwd=base)
    elsewhere = base / "elsewhere"
    elsewhere.mkdir()
    return wheel, env, elsewhere


def test_wheel_holds_every_module_and_case(installed):
    wheel, _, _ = installed
    names = set(zipfile.ZipFile(wheel).namelist())
    modules = {p.relative_to(ROOT).as_posix() for p in (ROOT / "bearingsim").rglob("*.py")
               if "__pycache__" not in p.parts}
    cases = {"bearingsim/" + p.relative_to(ROOT).as_posix() for p in (ROOT / "cases").rglob("*.toml")}
    assert modules and cases
    assert not modules - names, "modules missing from the wheel (add the package to pyproject.toml)"
    assert not cases - names, "shipped cases missing from the wheel"


def test_installed_package_loads_every_shipped_case_by_name(installed):
    _, env, elsewhere = installed
    out = run([env / "bin" / "python", "-c",
               "import bearingsim, bearingsim.case as c\n"
               "print(bearingsim.__file__)\n"
               "for name in c.shipped_cases():\n"
               "    print(name, c.load_case(name).title != '')"], cwd=elsewhere)
    lines = out.splitlines()
    assert Path(lines[0]).is_relative_to(env), f"imported {lines[0]}, not the installed wheel"
    expected = sorted(p.relative_to(ROOT / "cases").with_suffix("").as_posix()
                      for p in (ROOT / "cases").rglob("*.toml"))
    assert [line.split()[0] for line in lines[1:]] == expected
    assert all(line.endswith("True") for line in lines[1:])


def test_installed_command_runs_from_another_folder(installed):
    _, env, elsewhere = installed
    out = run([env / "bin" / "bearingsim", "info", "demo"], cwd=elsewhere)
    assert "Harris 218" in out and "BPFO" in out
    r = subprocess.run([env / "bin" / "bearingsim", "info", "no_such_case"], cwd=elsewhere,
                       capture_output=True, text=True)
    assert r.returncode == 2 and "shipped cases: " in r.stderr and "Traceback" not in r.stderr


def test_installed_demo_runs_from_another_folder(installed):
    """`bearingsim demo --out DIR` from the installed wheel, outside the source tree: the shipped
    demo case found by name, every stage run, every result and plot written."""
    _, env, elsewhere = installed
    out_dir = elsewhere / "demo_out"
    out = run([env / "bin" / "bearingsim", "demo", "--out", out_dir], cwd=elsewhere)
    assert "done in" in out, out
    for name in ("static.json", "static.png", "sweep.h5", "sweep.png", "simulate.h5",
                 "sensor_acceleration.png", "envelope_spectrum.png"):
        assert (out_dir / name).stat().st_size > 0, f"demo did not write {name}:\n{out}"
