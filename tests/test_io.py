"""bearingsim.output.io: the fixed JSON and HDF5 layouts, units on every dataset, atomic writes, no NaN."""
import dataclasses
import json
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pytest

from bearingsim.output import io
from bearingsim.physics.kinematics import DefectFrequencies
from bearingsim.app import workflows
from bearingsim.case import load_case, parse_case
from bearingsim.errors import OutputError

ROOT = Path(__file__).resolve().parent.parent
SMALL = (ROOT / "tests" / "data" / "small_sweep.toml").read_text()


@pytest.fixture(scope="module")
def small():
    return parse_case(SMALL, "small.toml")


@pytest.fixture(scope="module")
def sweep(small):
    return workflows.sweep_case(small)


def test_static_json_interface(tmp_path):
    sol = workflows.solve_case(load_case("harris218_thrust"))
    io.write_static(tmp_path / "s.json", sol)
    d = json.loads((tmp_path / "s.json").read_text())
    assert d == json.loads(json.dumps(io.static_to_dict(sol)))
    assert d["converged"] is True and d["iterations"] > 0 and d["residual_norm"] < 1e-6
    assert d["ring_displacement"]["axial_um"] == pytest.approx(41.47, abs=0.01)
    for k in ("x_um", "y_um", "tilt_x_mrad", "tilt_y_mrad"):
        assert abs(d["ring_displacement"][k]) < 1e-9
    assert d["cage_speed_rpm"] == 0.0
    assert d["loads"]["axial_N"] == pytest.approx(22250)
    balls = d["balls"]
    for k in ("azimuth_deg", "alpha_inner_deg", "alpha_outer_deg", "Q_inner_N", "Q_outer_N", "delta_inner_um",
              "delta_outer_um", "centrifugal_N", "gyroscopic_moment_Nm", "p_max_inner_MPa", "p_max_outer_MPa",
              "orbital_speed_rpm", "spall_depth_um"):
        assert len(balls[k]) == 16
    assert balls["azimuth_deg"][1] == pytest.approx(22.5)
    assert balls["alpha_inner_deg"][0] == pytest.approx(41.72, abs=0.005)
    assert balls["Q_inner_N"][3] == pytest.approx(2089.6, abs=0.05)
    assert d["stiffness"]["dofs"] == ["x", "y", "axial", "tilt_x", "tilt_y"]
    assert np.asarray(d["stiffness"]["matrix_per_um_mrad"]).shape == (5, 5)


def test_sweep_layout(small, sweep, tmp_path):
    out = tmp_path / "sweep.h5"
    io.write_sweep(out, small, sweep)
    with h5py.File(out) as f:
        assert f.attrs["case_toml"] == SMALL and f.attrs["title"] == "small sweep"
        assert "bearingsim_version" in f.attrs
        g = f["sweep"]
        shapes = {"cage_angle": (61,), "azimuth": (61, 16), "alpha_inner": (61, 16), "alpha_outer": (61, 16),
                  "Q_inner": (61, 16), "Q_outer": (61, 16), "ring_displacement": (61, 5), "converged": (61,),
                  "stiffness": (61, 5, 5), "result": (61,)}
        for name, shape in shapes.items():
            assert g[name].shape == shape and "units" in g[name].attrs
        assert g["Q_inner"].attrs["units"] == "N" and g["alpha_inner"].attrs["units"] == "rad"
        assert np.all(g["converged"][()])
        np.testing.assert_allclose(g["Q_outer"][()], sweep.Q_outer)
        for name in g:
            a = g[name][()]
            assert a.dtype.kind not in "fc" or np.all(np.isfinite(a))
    assert [p.name for p in tmp_path.iterdir()] == ["sweep.h5"]          # no temporary file left


def test_study_layout(small, tmp_path):
    study = workflows.study_case(small)
    io.write_study(tmp_path / "study.h5", small, study)
    with h5py.File(tmp_path / "study.h5") as f:
        g = f["study"]
        assert g.attrs["parameter"] == "defect.depth_mm"
        np.testing.assert_allclose(g["values"][()], [0.0, 0.01, 0.3])
        assert g["values"].attrs["units"] == "mm"
        assert g["Q_outer"].shape == (3, 61, 16) and g["ring_displacement"].shape == (3, 61, 5)


def _namespace(sol):
    return SimpleNamespace(**{f.name: np.array(getattr(sol, f.name)) for f in dataclasses.fields(sol)})


def test_failed_states_are_flagged_and_zero(sweep):
    bad = _namespace(sweep)
    bad.result[[2, 5]] = 1
    bad.Q_outer[2] = np.nan
    ds = io.state_datasets(bad)
    assert list(np.flatnonzero(~ds["converged"][0])) == [2, 5]
    assert np.all(ds["Q_outer"][0][[2, 5]] == 0) and np.all(np.isfinite(ds["Q_outer"][0]))
    np.testing.assert_allclose(ds["Q_outer"][0][3], sweep.Q_outer[3])


def test_nan_is_refused_and_nothing_is_left(tmp_path):
    with pytest.raises(OutputError, match="refusing to write /g/x: it contains NaN") as e:
        io.write_h5(tmp_path / "x.h5", {"g": {"x": (np.array([1.0, np.nan]), "m")}})
    assert e.value.exit_code == 4 and isinstance(e.value, io.NonFiniteOutputError)
    with pytest.raises(OutputError, match="refusing to write x.json.v: it is inf"):
        io.write_json(tmp_path / "x.json", {"v": [1.0, np.inf]})
    assert list(tmp_path.iterdir()) == []


def test_unwritable_path_is_an_output_error(tmp_path):
    (tmp_path / "file").write_text("a file, not a folder")
    with pytest.raises(OutputError, match="cannot write .*file/x.h5") as e:
        io.write_h5(tmp_path / "file" / "x.h5", {"g": {"x": (np.zeros(2), "m")}})
    assert e.value.exit_code == 4


def fake_simulation(T=2000, fs=20000.0, Z=9):
    t = np.arange(T) / fs
    return SimpleNamespace(
        time=t, cage_angle=0.1 * t, ring_displacement=np.zeros((T, 3)), housing_displacement=np.zeros((T, 2)),
        housing_acceleration=np.zeros((T, 2)), sensor_acceleration=np.sin(2 * np.pi * 3000 * t),
        Q_inner=np.ones((T, Z)), Q_outer=np.ones((T, Z)), alpha_inner=np.zeros((T, Z)),
        alpha_outer=np.zeros((T, Z)), jump_times=np.array([0.01, 0.02]), pass_times=np.array([0.015]),
        frequencies=DefectFrequencies(shaft=30.0, ftf=12.0, bpfo=108.0, bpfi=162.0, bsf=70.0),
        contact_angle=0.0, result=0, num_steps=T, ball_iterations=2, contact_damping=np.ones(3))


def test_simulation_file_round_trip(tmp_path):
    case = load_case("cwru_6205")
    res = fake_simulation()
    io.write_simulation(tmp_path / "sim.h5", case, res)
    with h5py.File(tmp_path / "sim.h5") as f:
        g = f["dynamics"]
        assert g["Q_outer"].shape == (2000, 9) and g.attrs["balls"] == 9
        assert all("units" in g[k].attrs for k in g)
    back = io.read_simulation(tmp_path / "sim.h5")
    np.testing.assert_array_equal(back["time"], res.time)
    np.testing.assert_array_equal(back["sensor_acceleration"], res.sensor_acceleration)
    assert back["frequencies"] == res.frequencies and back["case"].data == case.data
