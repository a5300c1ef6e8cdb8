"""The flat Jones solver (docs/model.md section 4): equilibrium, symmetry, limits, stiffness, result
codes and the validity rule (docs/model.md section 3).  Literature values: tests/validation/."""
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings, strategies as st

import bearingsim as bs
from bearingsim.physics import jones
from bearingsim.xla import compiler_options
from conftest import (DEG, at_groove_bottom, ball_equilibrium_error, beyond_high_shoulder, beyond_low_shoulder,  # noqa: E402
                      equilibrium_error, inverted_contacts)


# ---------------------------------------------------------------------------- symmetry, limits
@pytest.mark.parametrize("rpm", [0.0, 10000.0])
def test_identical_balls_under_pure_thrust(b218, rpm):
    sol = bs.solve(b218, bs.Operation.from_rpm(rpm), bs.Loads(axial=17800.0), cage_angle=0.3)
    for arr in (sol.Q_inner, sol.Q_outer, sol.alpha_inner, sol.alpha_outer):
        a = np.asarray(arr)
        assert np.ptp(a) <= 1e-10 * np.max(np.abs(a))
    assert np.max(np.abs(np.asarray(sol.displacement)[[0, 1, 3, 4]])) < 1e-15


def test_static_contacts_are_collinear(b218):
    """At rest the balls are eliminated by the closed form: collinear contacts, Q_i = Q_o."""
    sol = bs.solve(b218, bs.Operation.from_rpm(0.0), bs.Loads(axial=8000.0, radial_x=3000.0, moment_y=100.0))
    loaded = np.asarray(sol.Q_inner) > 0
    assert 0 < loaded.sum() < 16
    np.testing.assert_allclose(sol.alpha_inner[loaded], sol.alpha_outer[loaded], atol=1e-12)
    np.testing.assert_allclose(sol.Q_inner, sol.Q_outer, rtol=1e-10, atol=1e-9)


def test_high_speed_outer_angle_below_inner_and_outer_load_above(b218):
    sol = bs.solve(b218, bs.Operation.from_rpm(10000.0), bs.Loads(axial=22250.0))
    assert np.all(np.asarray(sol.alpha_outer) < np.asarray(sol.alpha_inner))
    assert np.all(np.asarray(sol.Q_outer) > np.asarray(sol.Q_inner))
    # the outer-control spin/gyroscopic identity M_g = J w_m^2 sin(a_o) / g
    Mg = float(b218.ball_inertia) * float(sol.orbital_speed[0]) ** 2 * np.sin(float(sol.alpha_outer[0])) / float(b218.g)
    assert abs(float(sol.gyroscopic_moment[0]) / Mg - 1) < 1e-12
    Fc = 0.5 * float(b218.ball_mass) * float(b218.pitch_diameter) * float(sol.orbital_speed[0]) ** 2
    assert abs(float(sol.centrifugal[0]) / Fc - 1) < 1e-12


def test_continuity_as_speed_goes_to_zero(b218):
    loads = bs.Loads(axial=9000.0, radial_x=2500.0, moment_y=60.0)
    s0 = bs.solve(b218, bs.Operation.from_rpm(0.0), loads)
    prev = None
    for rpm in (100.0, 10.0, 1.0):
        s = bs.solve(b218, bs.Operation.from_rpm(rpm), loads)
        d = max(float(jnp.max(jnp.abs(s.Q_inner - s0.Q_inner))) / float(s0.Q_inner.max()),
                float(jnp.max(jnp.abs(s.displacement[:3] - s0.displacement[:3]))) / 1e-6 * 1e-3)
        if prev is not None:
            assert d < prev / 10 + 1e-12      # F_c, M_g ~ w^2: 10x slower -> >= 10x closer
        prev = d
    assert prev < 1e-6


def test_switches_off_recover_static_model(b218):
    loads = bs.Loads(axial=9000.0, radial_x=2500.0)
    s0 = bs.solve(b218, bs.Operation.from_rpm(0.0), loads)
    s = bs.solve(b218, bs.Operation.from_rpm(15000.0, centrifugal=False, gyroscopic=False), loads)
    np.testing.assert_allclose(s.Q_inner, s0.Q_inner, rtol=1e-9, atol=1e-7)
    np.testing.assert_allclose(s.displacement, s0.displacement, rtol=1e-9, atol=1e-14)
    assert float(s.cage_speed) > 0


def test_gyroscopic_switch_matters_at_speed(b218):
    loads = bs.Loads(axial=9000.0)
    on = bs.solve(b218, bs.Operation.from_rpm(15000.0), loads)
    off = bs.solve(b218, bs.Operation.from_rpm(15000.0, gyroscopic=False), loads)
    assert float(jnp.max(off.gyroscopic_moment)) == 0.0
    assert abs(float(on.alpha_outer[0] - off.alpha_outer[0])) > 0.1 * DEG


def test_deep_groove_radial_load_centres_axially():
    """Clearance bearing (alpha_0 from P_d) under pure radial load: contacts at alpha ~ 0."""
    b = bs.Bearing.from_clearance(9, 7.94004e-3, 39.0398e-3, 0.52, 0.52, 12e-6)
    op = bs.Operation.from_rpm(1797.0)
    sol = bs.solve(b, op, bs.Loads(radial_x=1000.0))
    loaded = np.asarray(sol.Q_inner) > 0
    assert np.max(np.abs(np.asarray(sol.alpha_inner)[loaded])) < 1e-6
    assert equilibrium_error(b, sol, op) < 1e-9


def test_zero_load_at_rest_is_the_unloaded_bearing(b218):
    sol = bs.solve(b218, bs.Operation.from_rpm(0.0), bs.Loads())
    assert int(sol.result) == 0
    assert float(jnp.max(jnp.abs(sol.displacement))) == 0.0
    assert float(jnp.max(sol.Q_inner)) == 0.0
    assert np.all(np.isfinite(np.asarray(sol.alpha_inner)))


# ---------------------------------------------------------------------------- equilibrium
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(Fa=st.floats(3000.0, 40000.0), Fx=st.floats(-6000.0, 6000.0), Fy=st.floats(-6000.0, 6000.0),
       Mx=st.floats(-200.0, 200.0), My=st.floats(-200.0, 200.0), rpm=st.sampled_from([0.0, 6000.0, 12000.0]),
       cage=st.floats(0.0, 2 * np.pi))
# refused as 7 by the groove-bottom rule alone (a random search, issue 35): the older check failed them
@example(Fa=3406.2914875128213, Fx=1670.2719847905228, Fy=-3220.4197324208944, Mx=182.42622396327783,
         My=-121.99821703515678, rpm=6000.0, cage=1.9866138111029277)
@example(Fa=3172.7236382347355, Fx=4139.897744427237, Fy=-1053.9456165577076, Mx=-113.3153868703126,
         My=178.4653270779126, rpm=12000.0, cage=0.5392560412170171)
def test_global_equilibrium_random_combined_loads(b218, Fa, Fx, Fy, Mx, My, rpm, cage):
    """Ring and ball equilibrium re-derived in numpy from the reported per-ball output: 1e-9
    relative (the solver's tolerance is 1e-11 of the largest load).

    Part of this load space lies outside the model at speed (about 1 draw in 260 at 12 krpm: a
    lightly loaded ball's contact crosses the 218's low shoulder at -11.22 deg; near it others
    climb over the 74 deg high shoulder).  A refusal is accepted only when an independent check of
    the returned state confirms its reason (code 7: a loaded contact at or beyond the low
    shoulder, or the side load carried at the bottom of the groove, the most loaded inner contact
    below 1 deg; code 8: a loaded contact at or beyond the high shoulder; from the per-ball angles
    and the loads); any other refusal fails.  The explicit examples are draws the derandomized
    search can move onto after a change of code (issue 35: 0.5 % of draws were refused by the
    groove-bottom rule alone and failed the older check)."""
    op = bs.Operation.from_rpm(rpm)
    loads = bs.Loads(axial=Fa, radial_x=Fx, radial_y=Fy, moment_x=Mx, moment_y=My)
    sol = bs.solve(b218, op, loads, cage_angle=cage, throw=False)
    code = int(sol.result)
    if code != 0:
        assert code in (int(jones.RESULTS.low_shoulder), int(jones.RESULTS.over_shoulder)), (
            code, jones.RESULTS.of(code).message)
        if code == int(jones.RESULTS.low_shoulder):
            assert beyond_low_shoulder(b218, sol) or at_groove_bottom(b218, sol, loads), (
                "refused as low shoulder, but no loaded contact is beyond it and the load is not at the groove bottom")
        else:
            assert beyond_high_shoulder(b218, sol), "refused as over the shoulder, but no loaded contact is"
        return
    assert not beyond_low_shoulder(b218, sol) and not beyond_high_shoulder(b218, sol)
    assert equilibrium_error(b218, sol, op) <= 1e-9
    assert ball_equilibrium_error(b218, sol, op) <= 1e-9
    for arr in (sol.Q_inner, sol.Q_outer, sol.alpha_inner, sol.alpha_outer, sol.stiffness):
        assert np.all(np.isfinite(np.asarray(arr)))


def test_refused_low_shoulder_example_is_confirmed(b218):
    """The example that turned CI red at random (issue 27): Harris 218 at 12 000 rpm, Fa 3000 N,
    Fx 845, Fy 798, My -163 N m.  A ball's outer contact sits at -11.222 deg, past the low shoulder
    at -11.220 deg: the refusal is right, and the independent check above confirms it."""
    op = bs.Operation.from_rpm(12000.0)
    sol = bs.solve(b218, op, bs.Loads(axial=3000.0, radial_x=845.0, radial_y=798.0, moment_y=-163.0),
                   throw=False)
    assert int(sol.result) == int(jones.RESULTS.low_shoulder)
    assert beyond_low_shoulder(b218, sol)


@pytest.mark.parametrize("control", ["outer", "inner", "equal"])
def test_equilibrium_each_raceway_control(b218, control):
    op = bs.Operation.from_rpm(12000.0, control)
    sol = bs.solve(b218, op, bs.Loads(axial=12000.0, radial_x=3000.0, moment_y=-80.0))
    assert equilibrium_error(b218, sol, op) <= 1e-9
    assert ball_equilibrium_error(b218, sol, op) <= 1e-9


# ---------------------------------------------------------------------------- stiffness, gradients
@pytest.mark.parametrize("rpm", [0.0, 10000.0])
def test_stiffness_equals_central_difference(b218, rpm):
    """The Schur-complement stiffness equals central differences of the load-displacement map
    (balls iterated to convergence), to 2e-5 (the difference quotient's truncation).  (At 12 krpm
    this load puts an inner contact at 75.9 deg, over the 74.1 deg high shoulder: solve refuses it
    since issue 27, so the speed case runs at 10 krpm, inner contacts up to 71.5 deg.)"""
    op = bs.Operation.from_rpm(rpm)
    sol = bs.solve(b218, op, bs.Loads(axial=10000.0, radial_x=3000.0, moment_y=50.0), cage_angle=0.1)
    q = sol.displacement
    R = jax.jit(lambda q: jones.ring_reactions(b218, op, q, 0.1), compiler_options=compiler_options())
    K = np.asarray(sol.stiffness)
    h = np.array([1e-8, 1e-8, 1e-8, 1e-7, 1e-7])
    for j in range(5):
        e = jnp.zeros(5).at[j].set(h[j])
        fd = (np.asarray(R(q + e)) - np.asarray(R(q - e))) / (2 * h[j])
        np.testing.assert_allclose(K[:, j], fd, rtol=2e-5, atol=2e-5 * np.max(np.abs(K[:, j])))
    if rpm == 0.0:
        # nearly symmetric at rest; not exactly, because K is evaluated at the contact angle
        # (Q = K(alpha) delta^1.5 has no potential), which moves K by ~1e-4 here
        Ks = K / np.sqrt(np.outer(np.abs(np.diag(K)), np.abs(np.diag(K))))
        np.testing.assert_allclose(Ks, Ks.T, atol=1e-3)


def test_gradient_through_the_solve_is_the_implicit_derivative(b218):
    """jax.grad through solve_state (implicit function theorem at the converged state) equals
    central differences of converged solves, for a load and for the speed."""
    op = bs.Operation.from_rpm(9000.0)

    def Qmax(Fx, w):
        o = bs.Operation(w, "outer")
        s = jones.solve_state(b218, o, bs.Loads(axial=10000.0, radial_x=Fx), cage_angle=0.05)
        return jnp.max(s.Q_outer), s.displacement[0]

    f = jax.jit(Qmax, compiler_options=compiler_options())
    g = jax.jit(jax.jacfwd(Qmax, argnums=(0, 1)), compiler_options=compiler_options())(2000.0, op.speed)
    for k, (x0, h) in enumerate(((2000.0, 1e-2), (float(op.speed), 1e-3))):
        args = [2000.0, float(op.speed)]
        hi, lo = list(args), list(args)
        hi[k] += h
        lo[k] -= h
        fd = [(float(a) - float(b)) / (2 * h) for a, b in zip(f(*hi), f(*lo))]
        ad = [float(g[0][k]), float(g[1][k])]
        np.testing.assert_allclose(ad, fd, rtol=1e-5, atol=1e-12)


# ---------------------------------------------------------------------------- batch, codes
def test_batch_equals_single_solves(b218):
    op = bs.Operation.from_rpm(8000.0)
    loads = np.array([[1000.0, 0, 12000.0, 0, 40.0], [0, -2000.0, 6000.0, -30.0, 0], [0, 0, 22250.0, 0, 0],
                      [0, 0, 500.0, 0, 0], [3000.0, 1000.0, 9000.0, 20.0, -20.0]])   # 5: one compiled shape
    batch = bs.solve_batch(b218, op, loads)
    for k in range(5):
        s = bs.solve(b218, op, loads[k])
        np.testing.assert_allclose(batch.Q_inner[k], s.Q_inner, rtol=1e-10, atol=1e-8)
        np.testing.assert_allclose(batch.displacement[k], s.displacement, rtol=1e-10, atol=1e-16)


def test_non_convergence_raises_with_residual_and_hint(b218):
    op = bs.Operation.from_rpm(10000.0)
    with pytest.raises(bs.NotConvergedError, match=r"(?s)residual .* N.*Hint"):
        bs.solve(b218, op, bs.Loads(axial=17800.0), maxit=1, speed_steps=8)
    sol = bs.solve(b218, op, bs.Loads(axial=17800.0), maxit=1, speed_steps=8, throw=False)
    assert int(sol.result) == bs.RESULTS.max_iterations
    assert sol.message() == [bs.RESULTS.max_iterations.message]


def test_batch_throw_names_the_failed_items(b218):
    op = bs.Operation.from_rpm(0.0)
    loads = np.array([[0, 0, 10000.0, 0, 0], [0, 0, 1e9, 0, 0], [0, 0, 2e4, 0, 0], [0, 0, 3e4, 0, 0],
                      [0, 0, 4e4, 0, 0]])
    sol = bs.solve_batch(b218, op, loads)
    assert list(np.asarray(sol.result)) == [0, bs.RESULTS.beyond_bounds, 0, 0, 0]
    with pytest.raises(bs.InvalidStateError, match=r"item 1; 1 of 5 failed.*1 % of the ball diameter"):
        bs.solve_batch(b218, op, loads, throw=True)


@pytest.mark.parametrize("loads", [bs.Loads(axial=1e9), bs.Loads(axial=5000.0, radial_x=1e8)])
def test_loads_beyond_any_capacity_are_refused(b218, loads):
    """1e9 N axial (26 mm displacement, 48 GPa) must not be reported as converged."""
    sol = bs.solve(b218, bs.Operation.from_rpm(0.0), loads, throw=False)
    assert int(sol.result) != 0
    with pytest.raises(bs.NotConvergedError):
        bs.solve(b218, bs.Operation.from_rpm(0.0), loads)


def test_pressure_above_static_capacity_warns(b218):
    """4.2 GPa (ISO 76 static-capacity stress) is a warning, not a failure."""
    with pytest.warns(bs.OverloadWarning, match="4.2 GPa"):
        sol = bs.solve(b218, bs.Operation.from_rpm(0.0), bs.Loads(axial=1e6))
    assert int(sol.result) == 0 and bool(sol.overloaded)
    assert float(sol.max_pressure) > jones.PRESSURE_WARNING


# ---------------------------------------------------------------------------- validity (docs/model.md section 3)
# The case a new user reported: a deep ball-path spall; the old solver returned "converged" with
# ball 0 at alpha_i = -179.2 deg carrying 31 kN as a tie and the ring displaced towards +x.
USER_BEARING = dict(n_balls=14, ball_diameter=10.63e-3, pitch_diameter=52.65e-3, f_inner=0.517,
                    f_outer=0.536, free_contact_angle=14.8 * DEG)
USER_LOADS = bs.Loads(axial=2210.0, radial_x=-5042.0, radial_y=2840.0, moment_x=-9.27, moment_y=-1.18)
USER_SPALL = bs.Spall(5.38 * DEG, 11.3 * DEG, 0.5e-3, "ball-path")


def test_user_deep_spall_case_gives_the_physical_state():
    """An independent solver finds ball 0 out of inner contact, the load zone around 130-160 deg
    and Q_max ~ 2.2 kN (issue 8)."""
    b = bs.Bearing(**USER_BEARING)
    op = bs.Operation.from_rpm(7600.0, "outer")
    sol = bs.solve(b, op, USER_LOADS, cage_angle=4.01 * DEG, spall=USER_SPALL)
    Qi, psi = np.asarray(sol.Q_inner), np.asarray(sol.azimuth)
    assert Qi[0] == 0.0 and inverted_contacts(sol) == 0
    zone = np.degrees(psi[Qi > 0.9 * Qi.max()]) % 360
    assert np.all((zone > 120) & (zone < 170)), zone
    assert 2.0e3 < Qi.max() < 2.4e3
    # the ring moves towards the radial load (150 deg), not away from it
    q = np.asarray(sol.displacement)
    assert np.degrees(np.arctan2(q[1], q[0])) % 360 == pytest.approx(150, abs=20)
    assert equilibrium_error(b, sol, op) <= 1e-9 and ball_equilibrium_error(b, sol, op) <= 1e-9


def _random_cases(draw, n):
    """n random valid cases for one (Z, control): deep spalls, heavy combined loads, high speed."""
    rows = []
    for _ in range(n):
        D = draw(st.floats(5e-3, 25e-3))
        rows.append(dict(
            D=D, dm=D * draw(st.floats(3.5, 8.0)), fi=draw(st.floats(0.505, 0.54)),
            fo=draw(st.floats(0.505, 0.54)), a0=draw(st.floats(0.0, 40.0)) * DEG,
            rpm=draw(st.sampled_from([0.0, 3000.0, 10000.0, 20000.0])),
            Fa=draw(st.floats(0.0, 20000.0)), Fx=draw(st.floats(-20000.0, 20000.0)),
            Fy=draw(st.floats(-5000.0, 5000.0)), Mx=draw(st.floats(-50.0, 50.0)),
            My=draw(st.floats(-50.0, 50.0)), cage=draw(st.floats(0.0, 2 * np.pi)),
            c=draw(st.floats(0.0, 2 * np.pi)), ext=draw(st.floats(1.0, 15.0)) * DEG,
            depth=draw(st.sampled_from([0.0, 0.05, 0.3, 0.5, 1.0])) * 1e-3))
    return rows


@pytest.mark.parametrize("Z, control, profile", [(14, "outer", "ball-path"), (9, "inner", "rectangular"),
                                                  (11, "equal", "ball-path")])
@settings(max_examples=2, deadline=None)
@given(data=st.data())
def test_random_search_never_reports_an_invalid_state_as_converged(Z, control, profile, data):
    """Batches of random cases (geometry, loads, speed up to 20 krpm, spalls up to 1 mm deep):
    every converged item has no loaded contact at |alpha| >= 90 deg and holds ring and ball
    equilibrium (re-derived in numpy, 1e-8); most items are answered (the solver is not passing
    by flagging everything): converged, or refused for a shoulder that an independent check of the
    returned state confirms (code 7: a loaded contact at or beyond the low shoulder, or the side
    load carried at the groove bottom; code 8: a loaded contact at or beyond the high shoulder;
    from the per-ball angles and the loads, as test_global_equilibrium_random_combined_loads).
    Counting only converged items made the bar depend on how many random heavy combined loads
    climb a shoulder: 11 of 24 converged with 10 confirmed shoulder refusals failed it (issue 35)."""
    rows = _random_cases(data.draw, 24)
    col = lambda *keys: jnp.array([[r[k] for k in keys] for r in rows])
    geo, F = col("D", "dm", "fi", "fo", "a0"), col("Fx", "Fy", "Fa", "Mx", "My")
    w = jnp.array([r["rpm"] for r in rows]) * np.pi / 30
    spall, cage = col("c", "ext", "depth"), jnp.array([r["cage"] for r in rows])
    sols = _batch(Z, control, profile)(geo, w, F, spall, cage)
    codes = np.asarray(sols.result)
    for k in np.flatnonzero(codes == 0):
        one = jax.tree_util.tree_map(lambda a: a[k], sols)
        bk = bs.Bearing(Z, *np.asarray(geo[k]))
        opk = bs.Operation(w[k], control)
        assert inverted_contacts(one) == 0, rows[k]
        assert equilibrium_error(bk, one, opk) <= 1e-8, rows[k]
        assert ball_equilibrium_error(bk, one, opk) <= 1e-8, rows[k]
        assert np.all(np.isfinite(np.asarray(one.stiffness)))
    confirmed = 0
    for k in np.flatnonzero((codes == int(jones.RESULTS.low_shoulder)) | (codes == int(jones.RESULTS.over_shoulder))):
        one = jax.tree_util.tree_map(lambda a: a[k], sols)
        bk = bs.Bearing(Z, *np.asarray(geo[k]))
        if codes[k] == int(jones.RESULTS.low_shoulder):
            confirmed += beyond_low_shoulder(bk, one) or at_groove_bottom(bk, one, np.asarray(F[k]))
        else:
            confirmed += beyond_high_shoulder(bk, one)
    answered = (np.sum(codes == 0) + confirmed) / codes.size
    assert answered >= 0.5, (answered, np.unique(codes, return_counts=True))


@functools.lru_cache(maxsize=None)
def _batch(Z, control, profile):
    def one(geo, w, F, spall, cage):
        b = bs.Bearing(Z, *geo)
        sp = bs.Spall(spall[0], spall[1], spall[2], profile)
        return jones.solve_state(b, bs.Operation(w, control), F, cage_angle=cage, spall=sp,
                                 speed_steps=2)

    return jax.jit(jax.vmap(one), compiler_options=compiler_options())

def test_default_materials_stay_concrete_when_first_imported_inside_a_trace():
    """``bearingsim.Bearing`` imports physics/geometry lazily; a first use inside a user's
    jax.jit trace used to make its module constants STEEL and SILICON_NITRIDE out of that
    trace's tracers, which every later Bearing with the default materials then carried (a
    second program failed with "Execution supplied 5 arguments but compiled program expected
    11": the random search below, run alone).  A fresh interpreter, geometry not yet imported:
    the constants are concrete after the trace and a second program runs."""
    import subprocess
    import sys

    code = ("import sys, jax, jax.numpy as jnp; import bearingsim as bs; "
            "assert 'bearingsim.physics.geometry' not in sys.modules; "
            "f = lambda D: bs.Bearing(9, D, 0.039, 0.52, 0.52, 0.0).effective_modulus; "
            "a = float(jax.jit(f)(0.00794)); "
            "from bearingsim.physics import geometry as G; "
            "bad = [n for m in (G.STEEL, G.SILICON_NITRIDE) for n in ('youngs_modulus', 'poisson_ratio', 'density') "
            "if isinstance(getattr(m, n), jax.core.Tracer)]; "
            "assert not bad, bad; b = float(jax.jit(f)(0.00794)); assert a == b and a > 2e11, (a, b); print('ok')")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "ok" in p.stdout, p.stdout[-2000:] + p.stderr[-2000:]


def test_failed_items_are_merged_with_their_retries_as_a_loop_would():
    """newton.retry_failed: the failed items' retries replace them where ``take`` says so, the
    rest stay; the padding to a power of two (copies of the first failed item) changes nothing.
    Checked against a NumPy loop over the items, with 3 failures (padded to 4) in 8 items."""
    from typing import NamedTuple

    from bearingsim.physics.newton import retry_failed

    class Sol(NamedTuple):
        result: jnp.ndarray
        x: jnp.ndarray
        y: jnp.ndarray

    rng = np.random.default_rng(3)
    result = np.array([0, 2, 0, 2, 0, 0, 2, 0])
    sol = Sol(jnp.asarray(result), jnp.asarray(rng.normal(size=(8, 3))), jnp.asarray(rng.normal(size=8)))
    calls = []

    def run(idx):                          # item i solved again: result 0 for odd i, x = 10 i
        calls.append(np.array(idx))
        return Sol(jnp.asarray(np.where(idx % 2 == 1, 0, 2)), jnp.asarray(10.0 * np.repeat(idx[:, None], 3, 1)),
                   jnp.asarray(-1.0 * idx))

    got = retry_failed(sol, run, take=lambda r, s: r < s)
    assert len(calls) == 1 and calls[0].tolist() == [1, 3, 6, 1]
    want = {k: np.array(v) for k, v in sol._asdict().items()}
    for i in np.flatnonzero(result):       # the loop: each failed item's retry, kept where it is better
        if i % 2 == 1:
            want["result"][i], want["x"][i], want["y"][i] = 0, 10.0 * i, -1.0 * i
    for k, v in want.items():
        np.testing.assert_array_equal(np.asarray(getattr(got, k)), v)
    ok = Sol(jnp.zeros(4, int), sol.x[:4], sol.y[:4])
    assert retry_failed(ok, run) is ok and len(calls) == 1      # nothing failed: nothing solved again


def test_a_failed_solve_and_its_retry_are_one_compiled_program(b218, monkeypatch):
    """solve's retry with 8 speed steps runs the program of the first try (the stage count is
    traced, newton.speed_stages): a refused load compiles one Jones program, not two."""
    from bearingsim import programs
    from bearingsim.errors import failed
    from bearingsim.physics import jones as jn

    calls = []
    first = jn._solve_jit

    def counted(*a, **k):
        calls.append(int(k["speed_steps"]))
        return first(*a, **k)

    monkeypatch.setattr(jn, "_solve_jit", counted)
    seen: dict = {}
    programs.record(seen)
    try:
        # no axial load on an angular contact bearing: refused (low shoulder), after the retry
        sol = bs.solve(b218, bs.Operation.from_rpm(10000.0, "outer", True, True), [4000.0, 2000.0, 0.0, 0.0, 0.0],
                       throw=False)
    finally:
        programs.record(seen, on=False)
    assert failed(int(sol.result)) and calls == [1, 8]
    assert len([key for name, key in seen if "solve_state" in name]) == 1, seen


def test_a_traced_stage_count_gives_the_stages_of_a_fixed_one(b218):
    """newton.speed_stages: the while loop over a traced count runs the stages of the scan over
    a Python count (the same fractions k / steps): the same iterations and codes, the same state
    to round-off (the two programs fuse differently: ~1e-16 of each quantity)."""
    op = bs.Operation.from_rpm(10000.0, "outer", True, True)
    F = jnp.asarray([2000.0, 0.0, 8000.0, 0.0, 0.0])
    steps = 3
    fixed = jax.jit(lambda F: jones.solve_state(b218, op, F, speed_steps=steps))(F)
    traced = jax.jit(lambda F, n: jones.solve_state(b218, op, F, speed_steps=n))(F, jnp.int32(steps))
    assert int(fixed.result) == int(traced.result) == 0
    assert int(fixed.iterations) == int(traced.iterations) and fixed.iterations.dtype == traced.iterations.dtype
    for name in ("displacement", "Q_inner", "Q_outer", "alpha_inner", "alpha_outer", "ball_position"):
        a, t = np.asarray(getattr(fixed, name)), np.asarray(getattr(traced, name))
        np.testing.assert_allclose(t, a, rtol=1e-12, atol=1e-12 * np.max(np.abs(a)), err_msg=name)
