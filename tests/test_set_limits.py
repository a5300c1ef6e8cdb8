"""The limits diagram of a set study (issue 21 item 2): its values against the solution's own
per-ball output, and the figure."""
import numpy as np
import pytest

from bearingsim.case import load_case
from bearingsim.app.sets import plot_set_limits, study_limits, study_set_case


def test_limits_over_speed_of_a_db_pair(tmp_path):
    case = load_case("harris218_db_light")
    study = study_set_case(case, throw=False)
    lim = study_limits(case, study)
    n, nb = study.values.size, len(study.solution.bearings)
    assert all(np.shape(lim[k]) == (n, nb) for k in ("pressure", "friction", "edge_deg", "lift_off"))
    pl = case.limits_settings()["pressure_limit"]
    for k, b in enumerate(study.solution.bearings):
        p = np.maximum(np.asarray(b.p_max_inner), np.asarray(b.p_max_outer)).max(axis=-1) / pl
        np.testing.assert_allclose(lim["pressure"][:, k], p, rtol=1e-12)
    # at rest raceway control needs no friction (no gyroscopic moment); a rigid DB preload grows
    # with speed (the balls' centrifugal forces), so the lift-off margin does too
    assert np.all(lim["friction"][0] == 0.0)
    assert np.all(np.diff(lim["lift_off"], axis=0) > 0.0)
    out = plot_set_limits(case, study, title=case.title, path=tmp_path / "limits.png")
    assert out == tmp_path / "limits.png" and out.stat().st_size > 10_000


def test_set_study_writes_every_output_per_bearing_and_value(tmp_path, capsys):
    """`bearingsim study` on a DB pair (issue 27 item 6): the CSV and the HDF5 hold, per bearing
    and per speed, the preload, the axial / radial / tilt stiffness, the life and the limits;
    checked against independent relations: a rigid pair's radial and axial set stiffness is the
    sum of its bearings' (both see the shaft's translation unchanged), the light class is 0.3 %
    of C_0a, the set life is (sum L_k^(-10/9))^(-9/10) (ISO/TS 16281, independent failures),
    the lift-off margin is the axial load over the preload."""
    import csv

    import h5py

    from bearingsim.app.cli import main
    from bearingsim.app.sets import SET_FIELDS, STUDY_FIELDS
    from bearingsim.physics.shaft import static_axial_capacity

    out, plots = tmp_path / "s.h5", tmp_path / "plots"
    assert main(["study", "harris218_db_light", "-o", str(out), "--plot", str(plots)]) == 0
    assert f"wrote {tmp_path / 's.csv'}" in capsys.readouterr().out
    with h5py.File(out, "r") as f:
        g = f["set_study"]
        v = g["values"][()]
        h = {k: g[k][()] for k in list(STUDY_FIELDS) + list(SET_FIELDS)}
        assert g["axial_stiffness_N_per_um"].attrs["units"] == "N/um" and g.attrs["parameter_label"] == \
            "inner-ring speed n (rpm)"
        assert "life_h_defined" in g and not g["life_h_defined"][0].any() and g["life_h_defined"][1:].all()
    M, N = v.size, 2
    assert all(h[k].shape == (M, N) for k in STUDY_FIELDS) and all(h[k].shape == (M,) for k in SET_FIELDS)
    case = load_case("harris218_db_light")
    C0a = float(static_axial_capacity(case.bearing()))
    np.testing.assert_allclose(h["preload_N"], 0.003 * C0a, rtol=1e-12)
    np.testing.assert_allclose(h["set_radial_stiffness_N_per_um"], h["radial_stiffness_N_per_um"].sum(1), rtol=1e-8)
    np.testing.assert_allclose(h["set_axial_stiffness_N_per_um"], h["axial_stiffness_N_per_um"].sum(1), rtol=1e-8)
    L = h["life_h"][1:]                     # at standstill a life in hours is infinite: undefined
    np.testing.assert_allclose(h["set_life_h"][1:], np.sum(L ** (-10 / 9), axis=1) ** (-9 / 10), rtol=1e-10)
    assert np.all(np.diff(h["life_h"][1:], axis=0) < 0)        # faster: fewer hours
    np.testing.assert_allclose(h["lift_off_margin"], h["axial_load_N"] / h["preload_N"], rtol=1e-10)
    assert np.all(h["result"] == 0) and np.all(h["bearing_result"] == 0)
    # the CSV: a row per value and bearing, the same numbers (6 significant digits), units named
    rows = list(csv.reader((tmp_path / "s.csv").open()))
    head, units, body = rows[0], rows[1], rows[2:]
    assert head[:2] == ["speed_rpm", "bearing"] and units[0].startswith("# units: rpm")
    assert len(body) == M * N and set(head) >= set(STUDY_FIELDS) | set(SET_FIELDS)
    col = {k: i for i, k in enumerate(head)}
    for r in body:
        i, k = list(v).index(float(r[0])), int(r[1]) - 1
        for name in ("axial_stiffness_N_per_um", "tilt_stiffness_Nm_per_mrad", "pressure_ratio", "preload_N"):
            assert float(r[col[name]]) == pytest.approx(h[name][i, k], rel=1e-5)
        assert (r[col["life_h"]] == "") == (i == 0)
    names = sorted(p.name for p in plots.iterdir())
    assert names == ["limits_set_operation_speed_rpm.png", "study_set_operation_speed_rpm.png"]


def test_preload_class_says_what_it_is(capsys):
    from bearingsim.app.cli import main

    assert main(["info", "harris218_db_medium"]) == 0
    out = capsys.readouterr().out
    assert "preload class 'medium' = 0.6 % of C_0a" in out and "not a catalogue's classes" in out
