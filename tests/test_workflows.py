"""bearingsim.app.workflows: the case-driven functions the CLI, notebooks and README share."""
from pathlib import Path
from types import SimpleNamespace

import h5py
import jax
import numpy as np
import pytest

import bearingsim.physics.jones
import bearingsim.physics.sweep
from bearingsim.app import signal_workflows, workflows
from bearingsim.case import parse_case
from conftest import beyond_high_shoulder
from bearingsim.errors import InputError, InvalidStateError, NotConvergedError

ROOT = Path(__file__).resolve().parent.parent

# the case of tests/test_cli.py (same shapes: its compiled programs are reused), without its
# study, at a cage angle of 4 deg and with the Brewe-Hamrock Hertz approximation
SMALL = (ROOT / "tests" / "data" / "small_sweep.toml").read_text().split("[study]")[0]
BASE = SMALL.replace("speed_rpm = 10000", 'speed_rpm = 10000\ncage_angle_deg = 4.0\nhertz = "brewe-hamrock"')


def study(parameter, values):
    return parse_case(BASE.replace('hertz = "brewe-hamrock"', "") +
                      f'[study]\nparameter = "{parameter}"\nvalues = {values}\n', "study.toml")


class Recorder:
    """Stands in for a core call: records its arguments, returns a converged stub."""

    def __init__(self, monkeypatch, module, name, result=0):
        self.calls = []
        result = np.asarray(result)
        self.stub = SimpleNamespace(result=result, residual_norm=np.full(result.shape, 12.5),
                                    iterations=np.full(result.shape, 60))
        monkeypatch.setattr(module, name, self)

    def __call__(self, *args, **kw):
        self.calls.append((args, kw))
        return self.stub


def test_solve_case_passes_everything_the_case_says(monkeypatch):
    case = parse_case(BASE, "c.toml")
    rec = Recorder(monkeypatch, bearingsim.physics.jones, "solve")
    assert workflows.solve_case(case) is rec.stub
    (b, op, loads, *rest), kw = rec.calls[0]
    assert not rest and kw["cage_angle"] == pytest.approx(np.radians(4.0))
    assert kw["hertz_method"] == "brewe-hamrock" and float(kw["spall"].depth) == pytest.approx(3e-4)
    assert b.n_balls == 16 and float(op.speed_rpm) == pytest.approx(10000)
    np.testing.assert_allclose(loads, [3000, 0, 10000, 0, 0])


def test_sweep_case_passes_the_hertz_method_and_grid(monkeypatch):
    case = parse_case(BASE, "c.toml")
    rec = Recorder(monkeypatch, bearingsim.physics.sweep, "sweep_chunked", result=np.zeros(61))
    assert workflows.sweep_case(case) is rec.stub
    (b, op, loads, spall, angles), kw = rec.calls[0]
    assert kw["hertz_method"] == "brewe-hamrock" and float(spall.extent) == pytest.approx(np.radians(6))
    np.testing.assert_allclose(np.degrees(angles), np.linspace(-11.25, 11.25, 61))


def test_failed_states_raise_or_are_flagged(monkeypatch):
    case = parse_case(BASE, "c.toml")
    rec = Recorder(monkeypatch, bearingsim.physics.sweep, "sweep_chunked", result=np.r_[np.zeros(60), 1])
    with pytest.raises(NotConvergedError, match=r"c.toml: the cage-angle sweep failed \(item 60; 1 of 61"):
        workflows.sweep_case(case)
    assert workflows.sweep_case(case, throw=False) is rec.stub
    rec = Recorder(monkeypatch, bearingsim.physics.jones, "solve", result=1)
    with pytest.raises(NotConvergedError, match=r"c.toml: the quasi-static solve failed: .*residual 12.5 N") as e:
        workflows.solve_case(case)
    assert e.value.hint and e.value.exit_code == 3
    assert workflows.solve_case(case, throw=False) is rec.stub
    rec = Recorder(monkeypatch, bearingsim.physics.jones, "solve", result=4)        # an invalid state, not converged
    with pytest.raises(InvalidStateError, match="c.toml: the quasi-static solve failed"):
        workflows.solve_case(case)


def test_study_of_loads_is_one_batch_equal_to_one_sweep_per_value():
    # the ball over the 0.3 mm spall at 10 krpm touches the inner ring beyond its 74 deg shoulder at
    # some angles: those are refused (result 8, issue 27), the same in the batch and the sweeps
    case = study("load.axial_N", [10000, 14000])
    st = workflows.study_case(case, throw=False)
    assert st.batched and st.unit == "N" and st.parameter == "load.axial_N"
    codes = np.asarray(st.solution.result)
    assert np.asarray(st.solution.Q_outer).shape == (2, 61, 16) and set(np.unique(codes)) <= {0, 8}
    assert np.mean(st.converged) > 0.6
    for m, c in enumerate(case.study_cases()):
        s = c.sweep_settings()
        ref = bearingsim.physics.sweep.sweep(c.bearing(), c.operation(), c.loads(), c.spall(),
                                     angles=np.linspace(s["start"], s["stop"], s["steps"]))
        np.testing.assert_array_equal(codes[m], np.asarray(ref.result))
        for n in np.flatnonzero(codes[m] == 8):
            assert beyond_high_shoulder(c.bearing(), jax.tree_util.tree_map(lambda a: a[n], ref))
        np.testing.assert_allclose(st.solution.Q_outer[m], ref.Q_outer, rtol=1e-8, atol=1e-6)
        np.testing.assert_allclose(st.solution.alpha_inner[m], ref.alpha_inner, atol=1e-10)
        np.testing.assert_allclose(st.solution.cage_angle[m], ref.cage_angle, atol=0)


def test_study_of_the_spall_runs_one_sweep_per_value():
    st = workflows.study_case(study("defect.depth_mm", [0.0, 0.3]), throw=False)
    assert not st.batched and st.unit == "mm"
    codes = np.asarray(st.solution.result)
    assert np.all(codes[0] == 0) and set(np.unique(codes[1])) <= {0, 8}   # 8: ball over the spall
    Qo = np.asarray(st.solution.Q_outer)
    assert Qo.shape == (2, 61, 16) and Qo[1].min() < Qo[0].min()     # the spall unloads a ball


@pytest.mark.parametrize("param, values, words", [
    ("bearing.balls", [14, 16], "number of balls"),
    ("sweep.steps", [11, 21], "number of cage angles"),
])
def test_study_refuses_keys_that_change_the_shape(param, values, words):
    with pytest.raises(InputError, match=words) as e:
        workflows.study_case(study(param, values))
    assert e.value.exit_code == 2 and "study.toml" in str(e.value)


def test_study_without_study_section_is_an_input_error():
    with pytest.raises(InputError, match=r"no \[study\] section"):
        workflows.study_case(parse_case(BASE, "c.toml"))


def test_simulate_case_throw(monkeypatch):
    import bearingsim.dynamics

    case = parse_case(BASE, "sim.toml")
    failed = type("R", (), {"result": 1, "num_steps": 77})()
    monkeypatch.setattr(bearingsim.dynamics, "simulate", lambda *a, **kw: failed)
    with pytest.raises(NotConvergedError, match="sim.toml: the dynamic simulation failed") as e:
        signal_workflows.simulate_case(case)
    assert "77 steps" in str(e.value) and e.value.hint and e.value.exit_code == 3
    assert signal_workflows.simulate_case(case, throw=False) is failed


def test_simulate_case_prefetches_what_the_last_run_of_the_case_used(monkeypatch):
    """Issue 32: a simulation's programs load in the background (warm.prefetching, two threads)
    under a name of the case's own text, so a second run of the case (``bearingsim simulate``,
    a notebook) loads them beside its quasi-static start (measured: 3.55-3.85 -> 3.29-3.47 s
    for `bearingsim simulate cwru_6205`, warm); another case does not share the record."""
    import contextlib

    import bearingsim.dynamics
    from bearingsim import warm

    names = []

    @contextlib.contextmanager
    def seen(name, device=None):
        names.append(name)
        yield

    monkeypatch.setattr(warm, "prefetching", seen)
    monkeypatch.setattr(bearingsim.dynamics, "simulate", lambda *a, **kw: type("R", (), {"result": 0})())
    case = parse_case(BASE, "sim.toml")
    signal_workflows.simulate_case(case)
    signal_workflows.simulate_case(case.with_value("load.axial_N", 123.0))
    assert names[0] == f"simulate|{case.build().text}" and names[1] != names[0] and len(names) == 2


def test_compare_needs_a_dynamics_section():
    with pytest.raises(InputError, match=r"compare needs a \[dynamics\] section"):
        signal_workflows.compare_case(parse_case(BASE, "c.toml"))


def test_spectrum_file_refuses_other_files(tmp_path):
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = np.zeros(3)
    (tmp_path / "text.h5").write_text("not hdf5")
    for name in ("other.h5", "text.h5", "missing.h5"):
        with pytest.raises(InputError, match="not a bearingsim simulate output"):
            signal_workflows.spectrum_file(tmp_path / name)
    with pytest.raises(InputError, match="is a directory"):
        signal_workflows.spectrum_file(tmp_path)


def test_envelope_band_around_the_resonance():
    assert signal_workflows.envelope_band(48000.0, 3000.0) == pytest.approx((2625.0, 3375.0))
    lo, hi = signal_workflows.envelope_band(4000.0, 3000.0)          # resonance above 0.45 fs: clipped
    assert lo == pytest.approx(1800.0 * 0.875) and hi < 2000.0


def test_a_set_case_goes_through_the_same_workflows():
    """A case with [set] takes the single-bearing entries (issue 27 item 7): solve_case returns the
    set's state (the same as the set workflow's), info_text adds the set's bearings, and
    static_command says the set's text (no JSON or plot asked: nothing else)."""
    from bearingsim.app import set_workflows as sets
    from bearingsim.case import load_case
    from bearingsim.output import set_report
    from bearingsim.physics.shaft import SetSolution

    case = load_case("harris218_db_medium")
    sol = workflows.solve_case(case)
    assert isinstance(sol, SetSolution) and int(sol.result) == 0
    np.testing.assert_array_equal(np.asarray(sol.displacement), np.asarray(sets.solve_set_case(case).displacement))
    assert workflows.info_text(case).endswith(set_report.set_info_text(case))
    said = []
    workflows.static_command(case, say=said.append)
    assert said == [set_report.set_text(case, sol, sets.assess_set_case(case, sol))]
