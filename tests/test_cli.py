"""The command line: commands, what they print and write, exit codes 0 / 2 / 3 / 4.

The layouts of the files are tested in test_io.py, the computations in test_workflows.py and the
bad inputs in test_bad_inputs.py."""
import json
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pytest

from bearingsim.app import cli, signal_workflows, workflows
from bearingsim.physics.kinematics import DefectFrequencies
from bearingsim.output import io
from bearingsim.case import load_case
from bearingsim.datasets import DatasetResult, DatasetSummary

ROOT = Path(__file__).resolve().parent.parent
SMALL = ROOT / "tests" / "data" / "small_sweep.toml"


def test_info_by_name(capsys):
    assert cli.main(["info", "harris218_thrust"]) == 0
    out = capsys.readouterr().out
    assert "1.2965e+06" in out and "1.3486e+06" in out    # K_i, K_o in N/mm^1.5 (docs/reference-data.md: 1.297e6, 1.349e6)
    assert "BPFO" in out and "once per ball revolution" in out and "22.2250 mm" in out


def test_static_prints_and_writes(tmp_path, capsys):
    js, png = tmp_path / "s.json", tmp_path / "plots" / "s.png"
    assert cli.main(["static", str(ROOT / "cases" / "harris218_thrust.toml"), "--json", str(js), "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "converged in" in out and "p_o MPa" in out and "axial 41.4" in out and f"wrote {js}" in out
    assert json.loads(js.read_text())["converged"] is True
    assert png.stat().st_size > 10000


def test_non_convergence_exit_3_with_hint(tmp_path, capsys):
    case = tmp_path / "hard.toml"
    case.write_text(SMALL.read_text().replace("axial_N = 10000", "axial_N = 1000")
                    .replace("radial_x_N = 3000", "radial_x_N = 20000")
                    .replace("speed_rpm = 10000", 'speed_rpm = 20000\nraceway_control = "inner"')
                    .split("[defect]")[0])
    assert cli.main(["static", str(case), "--json", str(tmp_path / "x.json")]) == 3
    err = capsys.readouterr().err
    assert "hard.toml: the quasi-static solve failed" in err and "residual" in err and "Hint" in err
    assert not (tmp_path / "x.json").exists()


def test_unwritable_output_exit_4(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    assert cli.main(["static", "harris218_thrust", "--json", str(tmp_path / "file" / "s.json")]) == 4
    assert "cannot write" in capsys.readouterr().err


def test_sweep_and_study(tmp_path, capsys):
    assert cli.main(["sweep", str(SMALL), "-o", str(tmp_path / "sweep.h5"), "--plot", str(tmp_path / "plots")]) == 0
    out = capsys.readouterr().out
    assert "61 cage angles from -11.250 to 11.250 deg" in out
    with h5py.File(tmp_path / "sweep.h5") as f:
        assert f["sweep"]["Q_outer"].shape == (61, 16)
    assert cli.main(["study", str(SMALL), "-o", str(tmp_path / "study.h5"), "--plot", str(tmp_path / "plots")]) == 0
    out = capsys.readouterr().out
    assert "study of defect.depth_mm over [0.0, 0.01, 0.3] (one sweep per value)" in out and "max Q_o N" in out
    with h5py.File(tmp_path / "study.h5") as f:
        assert f["study"]["Q_outer"].shape == (3, 61, 16)
    assert {p.name for p in (tmp_path / "plots").iterdir()} == {"sweep.png", "study_defect_depth_mm.png"}


def test_demo_without_dynamics(tmp_path, capsys):
    out = tmp_path / "demo"
    assert cli.main(["demo", "--case", str(SMALL), "--out", str(out)]) == 0
    assert {p.name for p in out.iterdir()} == {"static.json", "static.png", "sweep.h5", "sweep.png"}
    text = capsys.readouterr().out
    assert "[1/4] quasi-static solve" in text and "[3/4]" not in text and str(out.resolve()) in text


def test_spectrum_of_a_simulation_file(tmp_path, capsys):
    """An impulse train at BPFO ringing the case's 3 kHz resonance: the peak is found at BPFO."""
    case = load_case("cwru_6205")
    fs, bpfo = 24000.0, 107.4
    t = np.arange(int(0.5 * fs)) / fs
    a = np.exp(-600.0 * np.mod(t, 1 / bpfo)) * np.sin(2 * np.pi * 3000.0 * t)
    res = SimpleNamespace(
        time=t, cage_angle=t, ring_displacement=np.zeros((t.size, 3)), housing_displacement=np.zeros((t.size, 2)),
        housing_acceleration=np.zeros((t.size, 2)), sensor_acceleration=a, Q_inner=np.zeros((t.size, 9)),
        Q_outer=np.zeros((t.size, 9)), alpha_inner=np.zeros((t.size, 9)), alpha_outer=np.zeros((t.size, 9)),
        jump_times=np.zeros(0), pass_times=np.zeros(0), contact_angle=0.0, result=0, num_steps=1,
        ball_iterations=1, contact_damping=np.zeros(3),
        frequencies=DefectFrequencies(shaft=29.95, ftf=bpfo / 9, bpfo=bpfo, bpfi=162.0, bsf=70.0))
    io.write_simulation(tmp_path / "sim.h5", case, res)
    assert cli.main(["spectrum", str(tmp_path / "sim.h5"), "--plot", str(tmp_path / "env.png")]) == 0
    out = capsys.readouterr().out
    assert "band 2625-3375 Hz" in out and "relative difference" in out
    assert abs(signal_workflows.spectrum_file(tmp_path / "sim.h5").peak - bpfo) < 2.1       # resolution 2 Hz
    assert (tmp_path / "env.png").stat().st_size > 10_000


def test_dataset_reports_failed_items(tmp_path, monkeypatch, capsys):
    code = int(DatasetResult.nonfinite_signal)
    summary = DatasetSummary(tmp_path / "d.h5", 6, 480, 2, 1.5, {code: 2})
    monkeypatch.setattr(signal_workflows, "dataset_case", lambda case, path, **kw: summary)
    assert cli.main(["dataset", "dataset_cwru", "-o", str(tmp_path / "d.h5")]) == 0
    err = capsys.readouterr().err
    assert "2 of 6 items failed (2 the simulated signal is not finite)" in err
    assert summary.message() == ["2 the simulated signal is not finite"] and not summary.converged


@pytest.mark.parametrize("argv", [["--help"], ["static", "--help"]])
def test_help(argv, capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(argv)
    assert e.value.code == 0 and "bearingsim" in capsys.readouterr().out


def test_static_and_info_on_a_set(tmp_path, capsys):
    """`bearingsim static` and `info` on a set case (docs/model.md section 10): per bearing the axial load,
    the lift-off margin and every ball; the JSON record and the polar plot are written."""
    import json
    js, png = tmp_path / "set.json", tmp_path / "set.png"
    assert cli.main(["static", "harris218_db_medium", "--json", str(js), "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "bearing 2: z = 40.00 mm, facing -1" in out and "lift-off margin" in out
    rec = json.loads(js.read_text())
    assert rec["result"] == 0 and len(rec["bearings"]) == 2 and png.stat().st_size > 0
    # the shaft's axial equilibrium from the record: R1z - R2z = Fz
    Fz = rec["bearings"][0]["loads"]["axial_N"] - rec["bearings"][1]["loads"]["axial_N"]
    assert abs(Fz - 2000.0) < 1e-6
    assert cli.main(["info", "spindle_tbt_spring"]) == 0
    assert "bearing 4: z =   400.00 mm, facing -1" in capsys.readouterr().out


def test_an_overload_warning_is_one_clean_line(tmp_path):
    """Issue 35: a state over the ISO 76 4.2 GPa prints one line, not Python's warning with the
    package's file path and source line (a real process: pytest records warnings itself)."""
    import subprocess
    import sys

    case = load_case("harris218_thrust").with_value("load.axial_N", 600000.0)      # p_max ~4.8 GPa
    p = tmp_path / "heavy.toml"
    p.write_text(case.text)
    r = subprocess.run([sys.executable, "-m", "bearingsim.app.cli", "static", str(p)], capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert lines and all(ln.startswith("bearingsim: warning: ") for ln in lines), r.stderr
    assert "GPa" in r.stderr and ".py:" not in r.stderr and "warnings.warn" not in r.stderr


@pytest.mark.parametrize("argv", [["static", "harris218_thrust", "--plot"], ["spectrum", "rec.npz", "--plot"]])
def test_an_unwritable_plot_is_refused_before_the_work(argv, tmp_path, monkeypatch, capsys):
    """Issue 35: `static --plot` and `spectrum -o` into a folder that takes no files computed first
    (11-20 s), then failed with a raw Errno message: now exit 4 at once, one clean line."""
    (tmp_path / "file").write_text("x")
    monkeypatch.setattr(workflows, "static_command", lambda *a, **k: pytest.fail("computed before the check"))
    assert cli.main(argv + [str(tmp_path / "file" / "out.png")]) == 4
    err = capsys.readouterr().err
    assert err.startswith("bearingsim: error: cannot write --plot") and "Traceback" not in err


def test_the_console_command_leaves_after_the_exit_handlers_with_the_exit_code(tmp_path):
    """``bearingsim`` (cli.run) skips the interpreter's teardown only after the exit handlers ran
    and the streams are flushed, and exits with main's code: 2 for a case that does not exist,
    0 for ``info``; a non-daemon thread still running is waited for (the ordinary exit)."""
    import subprocess
    import sys

    def console(args, thread=False):
        # the thread (3 s, started after the imports) outlives the command: os._exit would lose it
        code = ("import atexit, sys, threading, time; "
                "atexit.register(lambda: print('handler ran', flush=True)); "
                f"sys.argv = ['bearingsim'] + {args!r}; from bearingsim.app.cli import run; "
                + ("threading.Thread(target=lambda: (time.sleep(3.0), print('thread done'))).start(); " if thread else "")
                + "print('before', end=''); run()")
        return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=120)

    r = console(["static", "no_such_case"])
    assert r.returncode == 2 and r.stdout == "beforehandler ran\n" and "no such case file" in r.stderr
    r = console(["info", "demo"])
    assert r.returncode == 0 and r.stdout.startswith("before") and r.stdout.endswith("handler ran\n"), r.stdout[-200:]
    r = console(["info", "demo"], thread=True)
    assert r.returncode == 0 and "thread done" in r.stdout and r.stdout.endswith("handler ran\n")
