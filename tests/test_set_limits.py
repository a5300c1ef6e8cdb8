"""The limits diagram of a set study (issue 21 item 2): its values against the solution's own
per-ball output, and the figure."""
import numpy as np
import pytest

from bearingsim.case import load_case, parse_case
from bearingsim.app.set_workflows import study_limits, study_set_case
from bearingsim.output.plots_set import plot_set_limits


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
    out = plot_set_limits(study, lim, title=case.title, path=tmp_path / "limits.png")
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
    from bearingsim.output.set_report import SET_FIELDS, STUDY_FIELDS
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


# ----------------------------------------------------------- issue 34 / 35: honest set outputs
DB_LIGHT = load_case("harris218_db_light").text
#: the same Harris 218 alone: the DB pair's case without [set] and [study], with the axial load
#: that each bearing of the pair carries (~16 kN; 2 kN alone at 10000 rpm leaves a contact over
#: the shoulder: refused)
SINGLE_218 = DB_LIGHT.split("[set]")[0].replace("axial_N = 2000", "axial_N = 16000")


@pytest.fixture(scope="module")
def db_light(tmp_path_factory):
    """The light DB pair at 10000 rpm: (case, state, printed text, JSON record), solved once."""
    case = load_case("harris218_db_light")
    text, rec, sol = _static(case, tmp_path_factory.mktemp("db"), "db")
    return case, sol, text, rec


def _static(case, tmp_path, name):
    """``bearingsim static`` through its workflow entry: (printed text, JSON record, state)."""
    import json

    from bearingsim.app import workflows

    said = []
    sol = workflows.static_command(case, tmp_path / f"{name}.json", say=said.append)
    return "\n".join(said), json.loads((tmp_path / f"{name}.json").read_text()), sol


def test_every_bearing_of_a_set_reports_the_single_bearings_limits(db_light):
    """Issue 34: at 10000 rpm both bearings of the light DB pair need more friction than the
    available 0.07 (raceway control: 0.0805 and 0.0821, 1.15 and 1.17 x); each is flagged as a
    single bearing is (the same summary line, flag ``slip``), in the text and in the JSON, whose
    per-bearing ``limits`` are the single bearing's.  Before: numbers only, no flag, no JSON limits."""
    case, sol, text, rec = db_light
    assert "flags: slip (bearing 1, 2)" in text
    assert text.count("limits: raceway control needs 1.1") == 2
    assert rec["flags"] == {"slip": [1, 2]}
    mu = case.limits_settings()["friction_coefficient"]
    for k, b in enumerate(rec["bearings"]):
        lim = b["limits"]
        assert lim["slip"] is True and lim["flags"] == ["slip"] and not lim["overpressure"]
        need = max(max(lim["balls"]["friction_needed_inner"]), max(lim["balls"]["friction_needed_outer"]))
        assert lim["max_friction_ratio"] == pytest.approx(need / mu, rel=1e-12) and need / mu > 1.1
        # its life: the single bearing's record, the same hours the text gives
        assert f"bearing {k + 1} {b['life']['L10r_h']:.4g} h" in text


def test_single_and_set_json_speak_one_unit_convention(db_light, tmp_path):
    """Issue 34: a single bearing and each bearing of a set write the same keys in the same units
    for the same quantity (stiffness N/um and N m/mrad, displacements um and mrad, pressures MPa),
    the file says so in ``units``, and the printouts give stiffness in the same units.  Before: the
    single bearing's stiffness in N/m, the set's JSON in m / rad / Pa with other keys."""
    case, sol, text, rec = db_light
    single = parse_case(SINGLE_218, "single_218.toml")
    s_text, s_rec, _ = _static(single, tmp_path, "single")
    assert rec["units"] == s_rec["units"] and "engineering units" in rec["units"]
    for b in rec["bearings"]:
        assert set(s_rec) - {"units", "tilt", "tilt_note"} <= set(b)
        for key in ("ring_displacement", "loads", "balls", "stiffness", "limits", "life"):
            assert set(b[key]) == set(s_rec[key]), key
        assert set(b["limits"]["balls"]) == set(s_rec["limits"]["balls"])
    assert set(rec["shaft_displacement"]) == set(s_rec["ring_displacement"])
    assert set(rec["stiffness"]) == set(s_rec["stiffness"])
    assert rec["stiffness"]["units"] == s_rec["stiffness"]["units"]
    K = np.asarray(sol.stiffness)                   # SI inside
    assert rec["stiffness"]["axial_N_per_um"] == pytest.approx(K[2, 2] * 1e-6, rel=1e-12)
    assert rec["stiffness"]["tilt_x_Nm_per_mrad"] == pytest.approx(K[3, 3] * 1e-3, rel=1e-12)
    np.testing.assert_allclose(rec["stiffness"]["matrix_per_um_mrad"],
                               K * np.array([1e-6, 1e-6, 1e-6, 1e-3, 1e-3]), rtol=1e-12)
    Kb = np.asarray(sol.bearings[1].stiffness)
    assert rec["bearings"][1]["stiffness"]["axial_N_per_um"] == pytest.approx(Kb[2, 2] * 1e-6, rel=1e-12)
    assert rec["bearings"][1]["balls"]["p_max_inner_MPa"][0] == pytest.approx(
        float(sol.bearings[1].p_max_inner[0]) / 1e6, rel=1e-12)
    for t in (text, s_text):
        assert "N/um" in t and "N m/mrad" in t and " N/m," not in t and "N m/rad" not in t


def test_a_preload_over_the_static_capacity_is_flagged_as_a_single_bearing_is(tmp_path):
    """Issue 34/35: 1e6 N of preload on a Harris 218 DB pair (C_0a = 436 kN; 5.5 GPa) and 1e6 N of
    thrust on one Harris 218 get one verdict: solved and returned (exit 0), flagged
    ``overpressure`` in the JSON's ``limits`` and in the Python results (``overloaded``), the set
    also ``preload_over_capacity`` per bearing.  Before: the set's JSON had no flag at all."""
    from bearingsim.app.cli import main

    over = tmp_path / "db_1MN.toml"
    over.write_text(DB_LIGHT.replace('preload_class = "light"', "preload_N = 1000000"))
    one = tmp_path / "one_1MN.toml"
    one.write_text(SINGLE_218.replace("axial_N = 16000", "axial_N = 1000000"))
    recs = []
    for path in (over, one):
        with pytest.warns(UserWarning, match="exceeds 4.2 GPa"):
            assert main(["static", str(path), "--json", str(path.with_suffix(".json"))]) == 0
        import json
        recs.append(json.loads(path.with_suffix(".json").read_text()))
    pair, single = recs
    from bearingsim.app.workflows import solve_case

    with pytest.warns(UserWarning, match="exceeds 4.2 GPa"):
        sol = solve_case(load_case(over))
    assert np.all(np.asarray(sol.overloaded)) and int(sol.result) == 0
    assert single["converged"] and single["limits"]["overpressure"] and "overpressure" in single["limits"]["flags"]
    assert pair["converged"] and pair["flags"]["overpressure"] == [1, 2]
    assert pair["flags"]["preload_over_capacity"] == [1, 2]
    for b in pair["bearings"]:
        assert b["limits"]["overpressure"] and b["preload_over_capacity"]
        assert b["static_axial_capacity_N"] == pytest.approx(436.1e3, rel=1e-3)
        assert max(b["balls"]["p_max_inner_MPa"] + b["balls"]["p_max_outer_MPa"]) > 5000.0


def test_a_set_iteration_that_stops_over_a_shoulder_names_the_shoulder(db_light):
    """Issue 35: a set whose Newton iteration stops (maximum iterations) with a bearing over its
    groove edge (its own code 8) is refused for that (code 8, a set's hint: not the single bearing's
    "use a preloaded pair"), naming the bearing; with
    every bearing inside the model the hint names what a case can change, not a ``maxit`` that no
    case key sets.  Constructed from a solved state (the codes set as the solver leaves them).
    Before: max_iterations with the hint "raise maxit"."""
    import equinox as eqx

    from bearingsim.errors import InvalidStateError, NotConvergedError
    from bearingsim.physics.jones import RESULTS
    from bearingsim.physics.set_verdict import SET_NEWTON_HINT, SET_SHOULDER_HINT
    from bearingsim.physics.shaft import raise_for_set

    sol = db_light[1]
    stopped = eqx.tree_at(lambda s: (s.result, s.bearings[1].result), sol,
                          (np.int32(RESULTS.max_iterations), np.int32(RESULTS.over_shoulder)))
    with pytest.raises(InvalidStateError) as e:
        raise_for_set(stopped, "set solve of db.toml")
    assert e.value.code == RESULTS.over_shoulder and "bearing 2 of 2" in e.value.message
    assert "beyond the edge of its groove" in e.value.message and "maxit" not in e.value.hint
    assert e.value.hint == SET_SHOULDER_HINT and "a preloaded pair" not in e.value.hint
    stalled = eqx.tree_at(lambda s: s.result, sol, np.int32(RESULTS.max_iterations))
    with pytest.raises(NotConvergedError) as e:
        raise_for_set(stalled, "set solve of db.toml")
    assert e.value.code == RESULTS.max_iterations and e.value.hint == SET_NEWTON_HINT
    assert "raise maxit" not in e.value.hint


def test_a_real_set_stopped_by_the_iteration_is_refused_for_its_bearings_state():
    """Issue 35, a real case (found by a random search of 384 sets): a DT pair at 24893 rpm under
    Fx = 9013 N and a reverse Fz = -22176 N ends its Newton iteration at the maximum (code 1) with
    both bearings against their low shoulders (code 7).  It is refused as code 7 with the set's
    hint (a DT pair carries one axial direction), naming the bearing, not as "maximum iterations"
    with "raise maxit".  Before: NotConvergedError, code 1, hint "raise maxit, ..."."""
    from bearingsim.app.set_workflows import solve_set_case
    from bearingsim.errors import InvalidStateError
    from bearingsim.physics.jones import RESULTS

    text = (DB_LIGHT.split("[operation]")[0] + "[operation]\nspeed_rpm = 24893\nraceway_control = \"outer\"\n"
            "[load]\naxial_N = -22176\nradial_x_N = 9013\n[set]\narrangement = \"DT\"\nspacing_mm = 40\n")
    case = parse_case(text, "dt.toml")
    sol = solve_set_case(case, throw=False)
    assert int(sol.result) == RESULTS.max_iterations and np.all(np.asarray(sol.bearing_result) == 7)
    with pytest.raises(InvalidStateError) as e:
        solve_set_case(case)
    assert e.value.code == RESULTS.low_shoulder and "bearing 1 of 2" in e.value.message
    assert "DT pair" in e.value.hint and "maxit" not in e.value.hint
