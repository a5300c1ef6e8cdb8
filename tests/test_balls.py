"""The per-ball kernel (bearingsim.physics.balls, docs/model.md sections 3-5) against independent forms."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bearingsim as bs
from bearingsim.physics import hertz, jones
from bearingsim.physics import balls
from bearingsim.physics.hertz import stiffness_curve
from conftest import DEG

OP = bs.Operation.from_rpm(10000.0)


def test_transcendental_free_kinematics_equal_the_angle_form(b218):
    """ball_kinematics_cs (sines and cosines only) against docs/model.md's formulas written with
    arctan and cos(alpha - beta) in numpy, for every control and angles across 0-100 deg."""
    rng = np.random.default_rng(1)
    ai, ao = np.radians(rng.uniform(0, 100, 50)), np.radians(rng.uniform(0, 80, 50))
    g, w = float(b218.g), float(OP.speed)
    for control in ("outer", "inner", "equal"):
        beta = np.arctan2(np.sin(ai), np.cos(ai) - g) if control == "inner" else \
            np.arctan2(np.sin(ao), np.cos(ao) + g)
        ki = (1 - g * np.cos(ai)) / np.cos(ai - beta)
        ko = (1 + g * np.cos(ao)) / np.cos(ao - beta)
        wm = w * ki / (ki + ko)
        kin = bs.ball_kinematics(b218, bs.Operation.from_rpm(10000.0, control), ai, ao)
        ok = np.abs(np.cos(ai - beta)) > 0.05        # away from the cleared 0/0 at 90 deg
        np.testing.assert_allclose(np.asarray(kin.beta), beta, rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(np.asarray(kin.orbital_speed)[ok], wm[ok], rtol=1e-12)


def test_ball_equations_have_no_transcendental_functions(b218):
    """The solvers' inner loop: per ball only +, *, /, sqrt (and selects) -- no sin, cos, atan2,
    pow.  (Scalar geometry constants such as R_i = d_m/2 + (f_i - 1/2) D cos(alpha_0) are
    computed once, outside the vmapped per-ball work.)"""
    curve = stiffness_curve(b218)
    f = lambda v: balls.ball_equations(b218, OP, curve, v, 1e-5, 0.0, 500.0)[0]
    jaxpr = jax.make_jaxpr(jax.vmap(jax.jacfwd(f)))(jnp.ones((16, 4)))
    banned = {"sin", "cos", "tan", "atan2", "atan", "asin", "acos", "pow", "exp", "log", "cbrt"}
    per_ball = []

    def walk(j):
        for e in j.eqns:
            if str(e.primitive) in banned and any(getattr(v.aval, "shape", ()) for v in e.invars):
                per_ball.append(str(e.primitive))
            for p in e.params.values():
                if hasattr(p, "jaxpr"):
                    walk(p.jaxpr)
    walk(jaxpr.jaxpr)
    assert not per_ball, per_ball


def test_contact_rule_no_tie_past_the_inner_groove_centre(b218):
    """docs/model.md section 3: a ball whose centre is past the inner groove-curvature centre overlaps the
    inner raceway's sphere (delta_i > 0) with the normal pointing out of the raceway: Q_i = 0."""
    curve = stiffness_curve(b218)
    a0 = float(b218.free_contact_angle)
    A = float(b218.A)
    A1, A2 = A * np.sin(a0), A * np.cos(a0)
    # ball centre 1.3 mm beyond the outer groove centre's unloaded position, past (A1, A2)
    L = (float(b218.f_outer) - 0.5) * float(b218.ball_diameter) + 1.3e-3
    x = jnp.array([L * np.sin(a0), L * np.cos(a0)])
    st = balls.ball_state(b218, bs.Operation.from_rpm(0.0), x, A1, A2, curve, H_outer=1.3e-3)
    assert float(st.delta_inner) > 0 and np.cos(float(st.alpha_inner)) < 0
    assert float(st.Q_inner) == 0.0
    # the same overlap with the normal into the raceway is loaded
    x2 = jnp.array([A1, A2]) - (x - jnp.array([A1, A2]))
    st2 = balls.ball_state(b218, bs.Operation.from_rpm(0.0), x2, A1, A2, curve)
    assert float(st2.Q_inner) > 0


@pytest.mark.parametrize("H", [0.0, 5e-6])
def test_static_closed_form_is_the_exact_ball_equilibrium_at_rest(b218, H):
    curve = stiffness_curve(b218)
    op = bs.Operation.from_rpm(0.0)
    A1, A2 = balls.groove_centre_offsets(b218, jnp.array([20e-6, 0, 30e-6, 0, 0]), 0.0)
    x, d_c = balls.static_ball_position(b218, op, A1, A2, curve, H)
    st = balls.ball_state(b218, op, x, A1, A2, curve, H)
    assert float(d_c) == 0.0 and float(st.Q_inner) > 100.0
    assert abs(float(st.r_axial)) < 1e-9 * float(st.Q_inner)
    assert abs(float(st.r_radial)) < 1e-9 * float(st.Q_inner)
    assert float(st.alpha_inner) == pytest.approx(float(st.alpha_outer), abs=1e-13)


def test_fixed_step_ball_solver_converges_to_the_exact_one(b218):
    """A few Newton steps from the closed form reach the exact ball equilibrium (dynamics'
    solver): 3 steps to 1e-5 of the ball load (measured 2.8e-6), 6 to round-off."""
    curve = stiffness_curve(b218)
    A1, A2 = balls.groove_centre_offsets(b218, jnp.array([20e-6, 0, 30e-6, 0, 0]), 0.3)
    exact = balls.solve_ball(b218, OP, A1, A2, curve)
    st = balls.ball_state(b218, OP, exact, A1, A2, curve)
    assert max(abs(float(st.r_axial)), abs(float(st.r_radial))) < 1e-9 * float(st.Q_outer)
    for n, tol in ((3, 1e-5), (6, 1e-12)):
        x = balls.solve_ball_fixed(b218, OP, A1, A2, curve, iterations=n)
        s = balls.ball_state(b218, OP, x, A1, A2, curve)
        assert abs(float(s.Q_outer) - float(st.Q_outer)) < tol * float(st.Q_outer), n


def test_balls_at_ring_loads_equal_the_solved_state(b218):
    """The load-displacement map at a converged ring displacement returns the applied loads."""
    loads = bs.Loads(axial=9000.0, radial_x=2000.0, moment_y=40.0)
    sol = bs.solve(b218, OP, loads, cage_angle=0.2)
    st = bs.balls_at(b218, OP, sol.displacement, sol.azimuth, stiffness_curve(b218))
    R = np.asarray(bs.reactions_from_balls(st, sol.azimuth))
    np.testing.assert_allclose(R, np.asarray(loads), rtol=1e-9, atol=1e-7)
    np.testing.assert_allclose(np.asarray(st.Q_inner), np.asarray(sol.Q_inner), rtol=1e-9)


def _light_ball_sweep(lens, monkeypatch):
    """CWRU 6205 at 1797 rpm, 184 N radial and 27 N axial (a four-class data set item whose
    inner-race pit needed 8 Newton steps from the collinear start): ball 6 at azimuth 260 deg
    (opposite the radial load: the axial load keeps it in contact) over inner-race depths that put its groove-centre gap d_tot from 3 d_c / share_o down to
    -12 d_c.  Returns (d_tot / d_c, error per Newton step count 1..4 relative to the largest
    ball load, the start positions, d_c)."""
    from bearingsim.case import load_case
    from bearingsim.dynamics import bearing_force_history

    monkeypatch.setattr(balls, "LENS_START", lens)
    c = load_case("cwru_6205")
    b = c.bearing()
    op = bs.Operation.from_rpm(1797.0, "outer", True, True)
    curve = stiffness_curve(b)
    q = bs.solve(b, op, jones.load_vector(axial=27.0, radial_x=184.0)).displacement
    j = 6
    psi = b.ball_azimuths(np.pi / 9.0)
    A1, A2 = balls.groove_centre_offsets(b, q, psi)
    L0 = float(jnp.hypot(A1[j], A2[j]))
    _, d_c = balls.static_ball_position(b, op, A1, A2, curve)
    d_c = float(d_c[j])
    K_i, K_o = (float(hertz.power_eval(p, jnp.cos(0.1))) for p in (curve.inner_power, curve.outer_power))
    share_o = 1.0 / (1.0 + (K_o / K_i) ** (2.0 / 3.0))
    gap = np.linspace(-12.0 * d_c, 3.0 * d_c / share_o, 61)
    Hi = np.zeros((gap.size, 9))
    Hi[:, j] = L0 - float(b.A) - gap
    P = jnp.broadcast_to(psi, Hi.shape)

    @jax.jit
    def run(Hi):
        G, H = bearing_force_history(b, op, curve, q, P, jnp.zeros_like(Hi), Hi, 32)
        x0, _ = balls.static_ball_position(b, op, A1[None, :], A2[None, :], curve, 0.0, Hi)
        return G, H, x0

    G, H, x0 = map(np.asarray, run(jnp.asarray(Hi)))
    scale = np.max(np.hypot(G[-1], H[-1]), -1)
    conv = np.maximum(np.abs(G[-1] - G[-2]), np.abs(H[-1] - H[-2])).max(-1) / scale
    assert conv.max() <= 1e-10                      # the reference converged everywhere
    err = np.stack([np.maximum(np.abs(G[n] - G[-1]), np.abs(H[n] - H[-1])).max(-1) / scale for n in range(4)])
    return gap / d_c, err, x0, d_c


def test_light_ball_starts_in_the_raceways_corner(monkeypatch):
    """A ball at speed that its raceways barely reach (over a shallow pit, at the edge of the
    load zone: d_tot share_o < d_c) starts where F_c rolls it into the corner of the two
    raceways (balls.static_ball_position).  Over a gap on the groove-centre line (d_tot from 0
    to -12 d_c, where it still touches both raceways) the lean ball solve then converges
    quadratically: one Newton step within ITER_TOL (1e-3 of the largest ball load; measured
    6.3e-4), four within 1e-6 (1.7e-8); from the collinear start (nearly unloaded contacts: a
    zero-stiffness Newton step overshoots along the groove and creeps back) three steps are
    still 6e-3 to 1.6e-2 off.  Over the whole sweep the corner start is never worse than the
    collinear one (2-4 steps); above the switch the start is the collinear one, bit for bit, as
    for every loaded ball; at the switch it is continuous."""
    from bearingsim.dynamics.ball_force import ITER_TOL

    gap, err, x0, d_c = _light_ball_sweep(True, monkeypatch)
    _, err_old, x0_old, _ = _light_ball_sweep(False, monkeypatch)
    m = gap <= 0.0
    assert err[0, m].max() <= ITER_TOL, err[0, m].max()
    assert err[3, m].max() <= 1e-6, err[3, m].max()
    assert err_old[2, m].min() > 5 * ITER_TOL, err_old[2, m].min()
    assert np.all(err[1:].max(-1) <= err_old[1:].max(-1)), (err.max(-1), err_old.max(-1))
    same = np.all(x0 == x0_old, axis=(0, 2))
    assert np.all(same[gap > 3.0]) and not np.any(same[m])
    assert np.array_equal(x0[:, :, :6], x0_old[:, :, :6]) and np.array_equal(x0[:, :, 7:], x0_old[:, :, 7:])
    # continuity at the switch (bisected to 1e-18 m of depth): the corner meets the line there
    from bearingsim.case import load_case
    b = load_case("cwru_6205").bearing()
    op = bs.Operation.from_rpm(1797.0, "outer", True, True)
    curve = stiffness_curve(b)
    A1, A2 = balls.groove_centre_offsets(b, jnp.array([8e-6, 0.0, 6e-6, 0.0, 0.0]), 4.54)
    L0 = float(jnp.hypot(A1, A2))
    def start_fn(lens):
        monkeypatch.setattr(balls, "LENS_START", lens)
        f = jax.jit(lambda H: balls.static_ball_position(b, op, A1, A2, curve, 0.0, H)[0])
        f(0.0)                                          # traced now, with this flag
        return f

    start_old, start = start_fn(False), start_fn(True)

    def collinear(H):
        return np.array_equal(start(H), start_old(H))

    lo, hi = L0 - float(b.A) - 4.0 * d_c, L0 - float(b.A)         # collinear at lo, corner at hi
    assert collinear(lo) and not collinear(hi)
    while hi - lo > 1e-18:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if collinear(mid) else (lo, mid)
    jump = float(jnp.max(jnp.abs(start(hi) - start(lo))))
    print("jump at the switch", jump, "m; bracket", hi - lo)
    assert jump < 1e-10
