"""One validity rule everywhere (issue 27 item 2): the core decides a state's verdict, and the
Python API, the command line, sets and sweeps report the same code with a reason that fits the
case.  Every test here failed before the fix it names."""
import os
import warnings
from pathlib import Path

import numpy as np
import pytest

import bearingsim as bs
from bearingsim.physics import jones
from bearingsim.app import workflows
from bearingsim.case import load_case, parse_case
from bearingsim.app.cli import main
from bearingsim.errors import InvalidStateError
from conftest import beyond_high_shoulder, beyond_low_shoulder

R = jones.RESULTS
DEMO = (Path(__file__).resolve().parents[1] / "cases" / "demo.toml").read_text()
B218 = """\
[bearing]
balls = 16
ball_diameter_mm = 22.225
pitch_diameter_mm = 125.26
inner_groove_curvature = 0.5232
outer_groove_curvature = 0.5232
free_contact_angle_deg = 40.0
"""
DEMO_DEFECT = """\
[defect]
center_deg = 0.0
extent_deg = 3.0
depth_mm = 0.3
profile = "rectangular"
"""


def _case(rpm, Fa, Fx, Fy, Mx, My, cage_deg=0.0, defect=False, extra=""):
    return (f'title = "random"\n{B218}[operation]\nspeed_rpm = {rpm}\ncage_angle_deg = {cage_deg}\n'
            f"[load]\naxial_N = {Fa}\nradial_x_N = {Fx}\nradial_y_N = {Fy}\nmoment_x_Nm = {Mx}\n"
            f"moment_y_Nm = {My}\n" + (DEMO_DEFECT if defect else "") + extra)


def _write(tmp_path, text, name="c.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


# ------------------------------------------------------------------- the API and the CLI agree
def test_api_and_cli_give_the_same_verdict_on_random_cases():
    """200 random cases (fixed seed) of the 218 around the issue's example (up to 12 krpm, thrust
    0.5-20 kN, radial loads to 6 kN, moments to 200 N m, a third with the demo spall): the Python
    API (``bearingsim.solve``) and the command line's path (``workflows.solve_case`` of the case
    file) give the same code for every case; no state reported converged has a loaded contact at
    or beyond a shoulder (checked from the per-ball angles alone); the over-shoulder refusal does
    occur in this space (before the fix the API returned 0 where ``static`` refused with 8).
    ~200 solves of two compiled programs: about 20 s on the 2-core machine (the issue's 1000-case
    comparison is benchmarks/bench_validity.py)."""
    rng = np.random.default_rng(27)
    n = 200
    rpm = rng.choice([0.0, 6000.0, 12000.0], n)
    Fa = rng.uniform(500.0, 20000.0, n)
    Fx, Fy = rng.uniform(-6000.0, 6000.0, (2, n))
    Mx, My = rng.uniform(-200.0, 200.0, (2, n))
    cage = rng.uniform(0.0, 22.5, n)
    defect = rng.uniform(size=n) < 1.0 / 3.0
    counts = {}
    for k in range(n):
        case = parse_case(_case(rpm[k], Fa[k], Fx[k], Fy[k], Mx[k], My[k], cage[k], defect[k]), "r.toml")
        b, op = case.bearing(), case.operation()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", jones.OverloadWarning)
            api = bs.solve(b, op, case.loads(), cage_angle=case.cage_angle, spall=case.spall(), throw=False)
            cli = workflows.solve_case(case, throw=False)
        a, c = int(api.result), int(cli.result)
        assert a == c, (k, a, c)
        counts[a] = counts.get(a, 0) + 1
        if a == 0:
            assert not beyond_high_shoulder(b, api) and not beyond_low_shoulder(b, api), k
        elif a == int(R.over_shoulder):
            assert beyond_high_shoulder(b, api), k
    assert counts.get(0, 0) >= n // 2, counts
    assert counts.get(int(R.over_shoulder), 0) >= 1, counts


def test_api_refuses_the_issue_state_over_the_high_shoulder(tmp_path, capsys):
    """The issue's neighbourhood of the example (218, 12 krpm, 3 kN thrust, a moment): a converged
    state with a loaded contact beyond the 74 deg high shoulder is result 8 from bearingsim.solve
    itself, with a defect too, and `static` exits 3 naming it."""
    b = load_case("demo").bearing()
    op = bs.Operation.from_rpm(12000.0)
    F = bs.Loads(axial=3000.0, moment_y=152.0)
    sol = bs.solve(b, op, F, throw=False)
    assert int(sol.result) == int(R.over_shoulder) and beyond_high_shoulder(b, sol)
    with pytest.raises(InvalidStateError, match="beyond the edge of its groove"):
        bs.solve(b, op, F)
    sp = load_case("demo").spall()
    sol = bs.solve(b, op, F, spall=sp, throw=False)
    assert int(sol.result) == int(R.over_shoulder) and beyond_high_shoulder(b, sol)
    p = _write(tmp_path, _case(12000, 3000, 0, 0, 0, 152, defect=True))
    assert main(["static", str(p)]) == 3
    assert "beyond the edge of its groove" in capsys.readouterr().err


# -------------------------------------------------------------------------------------- sets
SET = B218 + """\
[operation]
speed_rpm = 10000
[load]
axial_N = {axial}
radial_x_N = 3000
[set]
{set}
"""


def test_set_refusals_name_their_reason_instead_of_crashing(tmp_path, capsys):
    """Codes 6-9 of a set used to crash (AttributeError '_Codes' has no 'loads'): a DT pair under a
    reverse axial load (7) and a preload of 1e9 N (6) raise InvalidStateError from Python and exit
    3 with one message from the command line; the hints are a set's."""
    from bearingsim.app.set_workflows import solve_set_case

    dt = 'title = "dt"\n' + SET.format(axial=-5000, set='arrangement = "DT"\nspacing_mm = 40')
    with pytest.raises(InvalidStateError) as e:
        solve_set_case(parse_case(dt, "dt.toml"))
    assert e.value.code == R.low_shoulder
    assert "DT pair" in e.value.hint and "DB back-to-back" not in e.value.hint
    big = 'title = "big"\n' + SET.format(axial=2000, set='arrangement = "DB"\nspacing_mm = 40\npreload_N = 1e9')
    with pytest.raises(InvalidStateError) as e:
        solve_set_case(parse_case(big, "big.toml"))
    assert e.value.code == R.beyond_bounds and "preload" in e.value.hint
    for name, text, what in (("dt.toml", dt, "low shoulders"), ("big.toml", big, "beyond 1 %")):
        assert main(["static", str(_write(tmp_path, text, name))]) == 3
        err = capsys.readouterr().err
        assert what in err and "Traceback" not in err and "AttributeError" not in err


def test_set_with_a_loaded_contact_over_a_shoulder_is_refused_like_one_bearing(tmp_path, capsys):
    """A DB pair whose inner contacts climb over a 45 deg inner shoulder (20 kN of thrust at 10 krpm):
    result 8, exit 3, as the same bearing alone (it used to exit 0 with a 'centre over a shoulder'
    line).  (~20 s on the 2-core machine: the set solve and the single solve with their own
    shoulder angles compile.)"""
    shoulders = "[shoulders]\ninner_high_deg = 45\n"
    text = 'title = "db"\n' + SET.format(axial=20000, set='arrangement = "DB"\nspacing_mm = 40\n'
                                         'preload_class = "light"') + shoulders
    from bearingsim.app.set_workflows import solve_set_case

    sol = solve_set_case(parse_case(text, "db.toml"), throw=False)
    assert int(sol.result) == int(R.over_shoulder)
    k = int(np.flatnonzero(np.asarray(sol.bearing_result))[0])
    assert beyond_high_shoulder(parse_case(text, "db.toml").bearing_set().bearings[k], sol.bearings[k])
    assert main(["static", str(_write(tmp_path, text))]) == 3
    assert "beyond the edge of its groove" in capsys.readouterr().err
    single = _case(10000, 20000, 3000, 0, 0, 0, extra=shoulders)
    assert main(["static", str(_write(tmp_path, single, "one.toml"))]) == 3
    assert "beyond the edge of its groove" in capsys.readouterr().err


def test_preload_above_the_static_capacity_warns(tmp_path, capsys):
    """A rigid preload of 1e6 N (p_max 5.4 GPa, C_0a of the 218 ~ 0.44 MN) used to pass silently:
    it warns as a single bearing over 4.2 GPa does, naming the static axial capacity."""
    from bearingsim.app.set_workflows import solve_set_case

    text = 'title = "p"\n' + SET.format(axial=2000, set='arrangement = "DB"\nspacing_mm = 40\npreload_N = 1e6')
    with pytest.warns(jones.OverloadWarning, match="static axial capacity C_0a"):
        sol = solve_set_case(parse_case(text, "p.toml"))
    assert float(np.max(np.asarray(sol.max_pressure))) > 5e9
    with pytest.warns(jones.OverloadWarning, match="static axial capacity C_0a"):
        assert main(["static", str(_write(tmp_path, text))]) == 0


# ----------------------------------------------------------------------------------- hints
def test_code_7_hint_depends_on_the_case():
    """'use a preloaded pair' for a negative axial load on one bearing only: not when Fz > 0 (the
    radial load or moment is the cause), not for a bearing already in a set."""
    b = load_case("demo").bearing()
    neg = jones.result_hint(R.low_shoulder, [0, 0, -1000.0, 0, 0], bearing=b)
    assert "negative or reversing axial load" in neg
    pos = jones.result_hint(R.low_shoulder, [845.0, 798.0, 3000.0, 0, -163.0], bearing=b)
    assert "negative" not in pos and "Fz = 3000 N" in pos
    in_set = jones.result_hint(R.low_shoulder, [0, 0, -1000.0, 0, 0], in_set=True)
    assert "preloaded pair" not in in_set and "in a set" in in_set


def test_acbb_without_axial_load_is_refused_with_the_physical_reason(tmp_path, capsys):
    """A 40 deg ACBB with 0 (or 10 N of) axial load and 3 kN radial at 10 krpm: healthy it was code 6
    ('check their units'), with the demo spall it converged (exit 0) to a degenerate state (288 um
    radial shift, two balls carrying the load).  Both are refused as 7 with the physical reason."""
    for Fa in (0, 10):
        for defect in (False, True):
            p = _write(tmp_path, _case(10000, Fa, 3000, 0, 0, 0, defect=defect))
            assert main(["static", str(p)]) == 3, (Fa, defect)
            err = capsys.readouterr().err
            assert "without enough axial load" in err and "check their units" not in err, err
    # a thrust that keeps the contact angles is accepted (the demo case without its spall)
    sol = bs.solve(load_case("demo").bearing(), bs.Operation.from_rpm(10000.0),
                   bs.Loads(axial=10000.0, radial_x=3000.0), throw=False)
    assert int(sol.result) == 0


# ------------------------------------------------------------------------------------ sweeps
def test_sweep_under_a_reverse_axial_load_has_the_static_verdict(tmp_path, capsys):
    """`sweep` used to exit 0 with every angle flagged and no message; `static` exits 3.  (~20 s on
    the 2-core machine: the sweep's warm-start and cold-start programs compile.)"""
    text = DEMO.replace("axial_N = 10000", "axial_N = -10000").replace("steps = 181", "steps = 5")
    p = _write(tmp_path, text)
    out = tmp_path / "s.h5"
    assert main(["static", str(p)]) == 3
    err_static = capsys.readouterr().err
    assert main(["sweep", str(p), "-o", str(out)]) == 3
    err = capsys.readouterr().err
    assert "low shoulders" in err and "Fz = -10000 N" in err and "low shoulders" in err_static
    assert not out.exists()


# ------------------------------------------------------------------------------------ output
def test_unwritable_output_exits_4_with_the_reason(tmp_path, capsys):
    """`-o` naming a directory, or a folder the system refuses (/sys), exit 4 (OutputError) with the
    reason; they used to exit 2 with a free-space message."""
    p = _write(tmp_path, DEMO.replace("steps = 181", "steps = 5"))
    (tmp_path / "out").mkdir()
    assert main(["sweep", str(p), "-o", str(tmp_path / "out")]) == 4
    err = capsys.readouterr().err
    assert "is a directory" in err and "free" not in err
    if os.path.isdir("/sys"):                       # Linux: sysfs takes no new files, even from root
        rc = main(["sweep", str(p), "-o", "/sys/bearingsim_out/s.h5"])
        err = capsys.readouterr().err
        assert rc == 4 and "does not accept files" in err and "free" not in err, err


# ---------------------------------------------------------------------------------- dynamics
@pytest.mark.parametrize("Fr, Fa, iterations", [(514.0, 10.0, 2), (700.0, 15.0, 1), (700.0, 15.0, 2),
                                                (1036.0, 25.0, 1)])
def test_dynamic_equilibrium_of_a_deep_groove_bearing_under_a_small_axial_load(Fr, Fa, iterations):
    """The issue's data set (Z = 8, d = 5.969 mm, pitch 31.623 mm, 0 deg, ~1500 rpm): items at
    514-1036 N radial with 10-25 N axial failed 'the dynamic model's own equilibrium at t = 0 was
    not found'.  The small axial load is the difference of the contacts' axial components, so the
    lean model's axial stiffness is 10-80 % off the quasi-static one and the chord iteration with
    it stalled (3.2 N left at 700 N / 15 N, 2 ball steps).  Now the equilibrium is found: the lean
    ring load at the returned state equals the applied loads to 1e-9 of the load scale."""
    import jax.numpy as jnp

    from bearingsim.dynamics.model import build_model, initial_state_jit
    from bearingsim.dynamics.parameters import DynamicsParameters
    from bearingsim.physics.hertz import stiffness_curve

    b = bs.Bearing(8, 5.969e-3, 31.623e-3, 0.52, 0.52, 0.0)
    op = bs.Operation.from_rpm(1500.0)
    F = bs.load_vector(axial=Fa, radial_x=Fr)
    sol = bs.solve(b, op, F)
    model = build_model(b, op, F, (), sol, DynamicsParameters(), stiffness_curve(b), iterations)
    stage0 = jnp.asarray([0.0, 0.0, float(op.speed)])
    y0, ok, _, _ = initial_state_jit(model, sol.displacement[:3], stage0)
    assert bool(ok)
    x = jnp.concatenate([y0[:2] - y0[3:5], y0[2:3]])            # shaft relative to the housing
    r = np.asarray(model.ring_load(x, stage0)) - np.asarray(F[:3])
    assert np.max(np.abs(r)) <= 1e-9 * (Fr + 1.0)


def test_every_result_enumeration_succeeds_at_the_one_value():
    """``errors.succeeded`` / ``failed`` compare with ``errors.SUCCESSFUL``: every enumeration's
    ``successful`` member has that value, and every other member is a failure."""
    from bearingsim.datasets import DatasetResult
    from bearingsim.dynamics import RESULTS as DYN
    from bearingsim.errors import SUCCESSFUL, failed, succeeded
    from bearingsim.physics.jones import RESULTS as JONES

    for enum in (JONES, DYN, DatasetResult):
        assert int(enum.successful) == SUCCESSFUL and succeeded(enum.successful)
        assert all(failed(m) for m in enum if m is not enum.successful)
        codes = np.array([int(m) for m in enum])
        assert np.array_equal(succeeded(codes), codes == int(enum.successful))
