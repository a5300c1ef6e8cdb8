"""Command line and results files: the fixed JSON/HDF5 interfaces, units, clear errors."""
import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from bearingsim import cli

ROOT = Path(__file__).resolve().parent.parent
SMALL_SWEEP = """
title = "small sweep"
[bearing]
balls = 16
ball_diameter_mm = 22.225
pitch_diameter_mm = 125.26
inner_groove_curvature = 0.5232
outer_groove_curvature = 0.5232
free_contact_angle_deg = 40.0
[operation]
speed_rpm = 10000
[load]
axial_N = 10000
radial_x_N = 3000
[defect]
center_deg = 0.0
extent_deg = 6.0
depth_mm = 0.3
profile = "ball-path"
[sweep]
start_deg = -11.25
stop_deg = 11.25
steps = 61
[study]
parameter = "defect.depth_mm"
values = [0.0, 0.01, 0.3]
"""


def test_info(capsys):
    assert cli.main(["info", str(ROOT / "cases" / "harris218_thrust.toml")]) == 0
    out = capsys.readouterr().out
    assert "1.2965e+06" in out and "1.3486e+06" in out    # K_i, K_o in N/mm^1.5 (reference-data.md: 1.297e6, 1.349e6)
    assert "BPFO" in out and "once per ball revolution" in out


def test_static_json_interface(tmp_path, capsys):
    js, png = tmp_path / "s.json", tmp_path / "s.png"
    assert cli.main(["static", str(ROOT / "cases" / "harris218_thrust.toml"), "--json", str(js), "--plot", str(png)]) == 0
    d = json.loads(js.read_text())
    assert d["converged"] is True and d["iterations"] > 0 and d["residual_norm"] < 1e-6
    assert d["ring_displacement"]["axial_um"] == pytest.approx(41.47, abs=0.01)
    for k in ("x_um", "y_um", "tilt_x_mrad", "tilt_y_mrad"):
        assert abs(d["ring_displacement"][k]) < 1e-9
    assert d["cage_speed_rpm"] == 0.0
    balls = d["balls"]
    for k in ("azimuth_deg", "alpha_inner_deg", "alpha_outer_deg", "Q_inner_N", "Q_outer_N", "delta_inner_um",
              "delta_outer_um", "centrifugal_N", "gyroscopic_moment_Nm", "p_max_inner_MPa", "p_max_outer_MPa"):
        assert len(balls[k]) == 16
    assert balls["alpha_inner_deg"][0] == pytest.approx(41.72, abs=0.005)
    assert balls["Q_inner_N"][3] == pytest.approx(2089.6, abs=0.05)
    assert d["stiffness"]["dofs"] == ["x", "y", "axial", "tilt_x", "tilt_y"]
    assert np.asarray(d["stiffness"]["matrix"]).shape == (5, 5)
    assert png.stat().st_size > 10000
    assert "ball" in capsys.readouterr().out


def test_bad_input_exit_2_names_the_key(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(SMALL_SWEEP.replace("balls = 16", "balls = 2").replace("speed_rpm", "sped_rpm"))
    assert cli.main(["static", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bearing.balls = 2" in err and "did you mean 'speed_rpm'" in err
    assert cli.main(["static", str(tmp_path / "missing.toml")]) == 2


def test_non_convergence_exit_3_with_hint(tmp_path, capsys):
    case = tmp_path / "hard.toml"
    case.write_text(SMALL_SWEEP.replace("axial_N = 10000", "axial_N = 1000").replace("radial_x_N = 3000", "radial_x_N = 20000")
                    .replace("speed_rpm = 10000", 'speed_rpm = 20000\nraceway_control = "inner"')
                    .split("[defect]")[0])
    assert cli.main(["static", str(case), "--json", str(tmp_path / "x.json")]) == 3
    err = capsys.readouterr().err
    assert "hard.toml: the quasi-static solve failed" in err and "residual" in err and "Hint" in err
    assert not (tmp_path / "x.json").exists()


def test_sweep_and_study_h5_layout(tmp_path, capsys):
    case = tmp_path / "c.toml"
    case.write_text(SMALL_SWEEP)
    out = tmp_path / "sweep.h5"
    assert cli.main(["sweep", str(case), "-o", str(out), "--plot", str(tmp_path / "plots")]) == 0
    with h5py.File(out) as f:
        assert f.attrs["case_toml"] == SMALL_SWEEP and "bearingsim_version" in f.attrs
        g = f["sweep"]
        shapes = {"cage_angle": (61,), "azimuth": (61, 16), "alpha_inner": (61, 16), "alpha_outer": (61, 16),
                  "Q_inner": (61, 16), "Q_outer": (61, 16), "ring_displacement": (61, 5), "converged": (61,),
                  "stiffness": (61, 5, 5)}
        for name, shape in shapes.items():
            assert g[name].shape == shape and "units" in g[name].attrs
        assert g["Q_inner"].attrs["units"] == "N" and g["alpha_inner"].attrs["units"] == "rad"
        assert np.all(g["converged"][()])
        for name in g:
            a = g[name][()]
            assert a.dtype.kind not in "fc" or np.all(np.isfinite(a))
    assert (tmp_path / "plots" / "sweep.png").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]       # atomic write
    out2 = tmp_path / "study.h5"
    assert cli.main(["study", str(case), "-o", str(out2), "--plot", str(tmp_path / "plots")]) == 0
    with h5py.File(out2) as f:
        g = f["study"]
        assert g.attrs["parameter"] == "defect.depth_mm"
        np.testing.assert_allclose(g["values"][()], [0.0, 0.01, 0.3])
        assert g["values"].attrs["units"] == "mm"
        assert g["Q_outer"].shape == (3, 61, 16) and g["ring_displacement"].shape == (3, 61, 5)
        Qo = g["Q_outer"][()]
        assert Qo[2].min() < Qo[0].min()            # the deep spall unloads the passing ball
    assert (tmp_path / "plots" / "study_defect_depth_mm.png").exists()
