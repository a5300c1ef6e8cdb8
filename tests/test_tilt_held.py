"""Single-bearing tilt free or held (issue 34 item 3; docs/physics.md "Tilt: free or held").

``tilt="held"`` fixes the inner ring's tilts at zero and solves the three translations under
[Fx, Fy, Fz]; the moments that hold the ring are reported in ``loads[3:5]``.  Checked against
truths that do not come from the held solve itself: the moment sum of the contact forces
recomputed in numpy from the per-ball loads and angles, the symmetric pure-thrust state (held ==
free), the free 5-DOF solve under the holding moments (the same state, tilt 0), and the linear
theory's direction of the change (a constraint stiffens: smaller radial displacement, a holding
moment against the free tilt).  The held program compiles once per configuration (the whole file
uses one, ~20 s at -O0, and the 8-speed-step retry of the refused state another).
"""
import json
from pathlib import Path

import numpy as np
import pytest

import bearingsim as bs
from bearingsim.app import cli, rotordynamics, signal_workflows, workflows
from bearingsim.case import CaseError, load_case, parse_case
from bearingsim.errors import InputError, InputTypeError, InvalidStateError
from bearingsim.output import io
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from bearingsim.output.plots import plot_static  # noqa: E402
from bearingsim.output.report import static_text
from bearingsim.physics import jones
from conftest import ball_equilibrium_error, equilibrium_error

ROOT = Path(__file__).resolve().parent.parent
OP = bs.Operation.from_rpm(10000.0)
COMBINED = bs.Loads(axial=10000.0, radial_x=3000.0)
#: a held Harris 218 case: harris218_combined without its moment, tilt held
HELD_TOML = ((ROOT / "cases" / "harris218_combined.toml").read_text()
             .replace("moment_y_Nm = 200", "moment_y_Nm = 0")
             .replace("cage_angle_deg = 0.0", 'cage_angle_deg = 0.0\ntilt = "held"'))


@pytest.fixture(scope="module")
def combined(b218):
    return {t: bs.solve(b218, OP, COMBINED, tilt=t) for t in ("free", "held")}


def _contact_moment_sum(b, sol):
    """Moment about the ring centre of the inner contact forces Q_i n_i (normal through the inner
    groove-curvature centre at R_i e_r(psi)), as 3-D cross products: the independent truth of the
    holding moment when no gyroscopic friction acts (sign: that of the applied loads)."""
    psi, a, Q = (np.asarray(x) for x in (sol.azimuth, sol.alpha_inner, sol.Q_inner))
    e_r = np.stack([np.cos(psi), np.sin(psi), 0.0 * psi], axis=-1)
    e_z = np.array([0.0, 0.0, 1.0])
    r = float(b.inner_groove_radius) * e_r
    f = Q[:, None] * (np.cos(a)[:, None] * e_r + np.sin(a)[:, None] * e_z)
    return np.sum(np.cross(r, f), axis=0)


# -------------------------------------------------------------------------- against truth
def test_held_tilt_is_zero_and_holding_moment_is_the_contact_moment_sum(b218):
    op = bs.Operation.from_rpm(10000.0, gyroscopic=False)        # no friction force: normal forces only
    sol = bs.solve(b218, op, COMBINED, tilt="held")
    assert sol.tilt == "held" and int(sol.result) == 0
    q = np.asarray(sol.displacement)
    assert q[3] == 0.0 and q[4] == 0.0                            # exactly: the tilts are not unknowns
    M = _contact_moment_sum(b218, sol)
    scale = float(b218.inner_groove_radius) * 10000.0             # R_i Fz ~ 560 N m
    assert abs(M[1]) > 0.05 * scale                               # a real moment (~130 N m), not ~0
    # 1e-9 of R_i Fz: the solve's force tolerance (1e-11 relative, 1e-9 N) with margin
    np.testing.assert_allclose(np.asarray(sol.loads)[3:], M[:2], rtol=0, atol=1e-9 * scale)
    np.testing.assert_array_equal(np.asarray(sol.loads)[:3], np.asarray(COMBINED)[:3])
    assert equilibrium_error(b218, sol, op) < 1e-9                # global equilibrium, relative
    assert ball_equilibrium_error(b218, sol, op) < 1e-9


def test_held_equilibrium_with_gyroscopic_friction(b218, combined):
    """At speed with M_g (raceway friction at the contacts): the numpy re-derivation of the ring
    equilibrium (conftest, docs/model.md section 4, friction included) against the reported loads and moments."""
    sol = combined["held"]
    assert int(sol.result) == 0 and np.all(np.asarray(sol.displacement)[3:] == 0.0)
    assert equilibrium_error(b218, sol, OP) < 1e-9
    assert ball_equilibrium_error(b218, sol, OP) < 1e-9


def test_pure_axial_held_equals_free(b218):
    """Symmetry: under pure thrust the free ring does not tilt, so holding it changes nothing."""
    loads = bs.Loads(axial=17800.0)
    free, held = (bs.solve(b218, OP, loads, cage_angle=0.3, tilt=t) for t in ("free", "held"))
    np.testing.assert_allclose(np.asarray(held.displacement)[:3], np.asarray(free.displacement)[:3],
                               rtol=1e-9, atol=1e-13)            # m: 1e-13 m ~ residual 1e-7 N / 1e8 N/m x 100
    for name in ("Q_inner", "Q_outer", "alpha_inner", "alpha_outer"):
        np.testing.assert_allclose(getattr(held, name), getattr(free, name), rtol=1e-9, atol=1e-9)
    # the holding moment of a symmetric state is ~0: 1e-9 of R_i Fz (rounding of 16 balls' sums)
    assert np.max(np.abs(np.asarray(held.loads)[3:])) < 1e-9 * float(b218.inner_groove_radius) * 17800.0


def test_radial_load_held_differs_from_free_in_the_expected_direction(b218, combined):
    free, held = combined["free"], combined["held"]
    qf, qh = np.asarray(free.displacement), np.asarray(held.displacement)
    assert qf[4] > 1e-4                                   # the free ring tilts (~1.7 mrad) under +Fx
    # holding the tilt is a constraint: it stiffens the ring (linear theory: (K_tt)^-1 <= [K^-1]_tt),
    # so the radial displacement under the same Fx is smaller (measured 56 vs 135 um) ...
    assert 0.0 < qh[0] < 0.8 * qf[0]
    # ... and the moment that holds it acts against the free tilt (M_y theta_y < 0)
    assert float(held.loads[4]) * qf[4] < 0.0
    # the load distribution differs: the most and least loaded balls change by more than 1 %
    Qf, Qh = np.asarray(free.Q_inner), np.asarray(held.Q_inner)
    assert abs(Qh.max() / Qf.max() - 1) > 0.01 and abs(Qh.min() / Qf.min() - 1) > 0.01


def test_free_solve_under_the_holding_moments_is_the_held_state(b218, combined):
    """The held state is the free state under the moments that hold it: the 5-DOF solve with those
    moments applied finds tilt 0 and the same ball loads (an independent solve of all 5 DOF)."""
    held = combined["held"]
    free = bs.solve(b218, OP, held.loads, tilt="free")
    q = np.asarray(free.displacement)
    assert np.max(np.abs(q[3:])) < 1e-9                   # rad (1e-9 rad ~ 5e-11 m at R_i)
    np.testing.assert_allclose(q[:3], np.asarray(held.displacement)[:3], rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(free.Q_inner, held.Q_inner, rtol=1e-7, atol=1e-6)


# ----------------------------------------------------------------------- case, CLI, outputs
def test_case_key_default_and_refusals():
    assert load_case("harris218_combined").get("operation.tilt") == "free"       # default: unchanged results
    assert parse_case(HELD_TOML).get("operation.tilt") == "held"
    with pytest.raises(CaseError) as e:
        parse_case(HELD_TOML.replace('tilt = "held"', 'tilt = "fixed"'))
    assert "operation.tilt" in str(e.value) and '"free"' in str(e.value) and '"held"' in str(e.value)
    with pytest.raises(CaseError) as e:                                       # a held tilt takes no moment
        parse_case(HELD_TOML.replace("moment_y_Nm = 0", "moment_y_Nm = 200"))
    assert "load.moment_y_Nm = 200 with operation.tilt = \"held\"" in str(e.value)
    db = (ROOT / "cases" / "harris218_db_light.toml").read_text()
    with pytest.raises(CaseError, match=r"operation.tilt = \"held\" applies to a single bearing"):
        parse_case(db.replace("[operation]", '[operation]\ntilt = "held"'))
    case = parse_case(HELD_TOML)
    for run in (workflows.sweep_case, workflows.study_case, signal_workflows.simulate_case):
        with pytest.raises(InputError, match='operation.tilt = "held" is not supported'):
            run(case)
    with pytest.raises(InputError, match='operation.tilt = "held" is not supported'):
        signal_workflows.dataset_case(case, "unused.h5")
    with pytest.raises(InputError, match="tilt = 'tipped' is not a tilt mode"):
        jones.tilt_held("tipped")
    with pytest.raises(InputTypeError):
        jones.tilt_held(True)
    with pytest.raises(InputError, match="Mx, My must be 0 with tilt = 'held'"):
        bs.solve(bs.Bearing(16, 22.225e-3, 125.26e-3, 0.5232, 0.5232, np.deg2rad(40.0)), OP,
                 bs.Loads(axial=1.0, moment_y=1.0), tilt="held")


def test_rotor_stiffness_takes_the_case_tilt(monkeypatch):
    """The ROSS element's operating point is the case's: a held case is solved held."""
    seen = {}

    class Stop(Exception):
        pass

    def fake(*a, **kw):
        seen.update(kw)
        raise Stop

    monkeypatch.setattr(rotordynamics, "solve_batch", fake)
    with pytest.raises(Stop):
        rotordynamics.bearing_stiffness(parse_case(HELD_TOML), [10000.0])
    assert seen["tilt"] == "held"


def test_cli_and_api_agree_and_say_held(tmp_path, capsys, b218):
    path = tmp_path / "held.toml"
    path.write_text(HELD_TOML)
    js = tmp_path / "held.json"
    assert cli.main(["static", str(path), "--json", str(js)]) == 0
    out = capsys.readouterr().out
    assert 'tilt: held at 0 (operation.tilt = "held")' in out
    d = json.loads(js.read_text())
    assert d["tilt"] == "held" and d["tilt_note"].startswith("held:")
    api = workflows.solve_case(load_case(path))
    core = bs.solve(b218, OP, bs.Loads(axial=17800.0, radial_x=8000.0), tilt="held")
    assert api.tilt == core.tilt == "held"
    ref = io.static_to_dict(core)
    assert d["ring_displacement"]["tilt_x_mrad"] == 0.0 and d["ring_displacement"]["tilt_y_mrad"] == 0.0
    for key in ("ring_displacement", "loads"):
        for k, v in ref[key].items():
            assert d[key][k] == pytest.approx(v, rel=1e-12, abs=1e-12), (key, k)
    np.testing.assert_array_equal(np.asarray(api.Q_inner), np.asarray(core.Q_inner))
    assert "tilt: free" in static_text(load_case("harris218_combined"), bs.solve(b218, OP, COMBINED))
    fig = plot_static(core)
    titles = [ax.get_title() for ax in fig.axes]
    plt.close(fig)
    assert any("(held)" in t for t in titles)


def test_refused_state_is_refused_the_same_way(tmp_path, capsys, b218):
    """No axial load under a radial one: the same verdict (low shoulder, exit 3) held or free,
    from the CLI and from Python."""
    path = tmp_path / "radial.toml"
    path.write_text(HELD_TOML.replace("axial_N = 17800", "axial_N = 0"))
    assert cli.main(["static", str(path)]) == 3
    err = capsys.readouterr().err
    with pytest.raises(InvalidStateError) as api:
        workflows.solve_case(load_case(path))
    with pytest.raises(InvalidStateError) as core:
        bs.solve(b218, OP, bs.Loads(radial_x=8000.0), tilt="held")
    with pytest.raises(InvalidStateError) as free:
        bs.solve(b218, OP, bs.Loads(radial_x=8000.0), tilt="free")
    assert api.value.code == core.value.code == free.value.code == jones.RESULTS.low_shoulder
    # a refused held state holds nothing: its loads are the applied ones, no holding moment
    refused = bs.solve(b218, OP, bs.Loads(radial_x=8000.0), tilt="held", throw=False)
    np.testing.assert_array_equal(np.asarray(refused.loads), [8000.0, 0.0, 0.0, 0.0, 0.0])
    assert str(api.value) in err
