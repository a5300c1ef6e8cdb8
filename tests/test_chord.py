"""The chord method of the time loop's ball solve (bearingsim.dynamics.bearing_force_chord):
the balls' positions carried from step to step, one chord correction and one evaluation whose
residuals decide; a full solve at defect edges and wherever a chord step misses CHORD_TOL."""
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bearingsim as bs
from bearingsim.physics import balls, hertz
from bearingsim import dynamics as dyn
from bearingsim.case import load_case, parse_case
from bearingsim.dynamics.ball_force import ITER_TOL
from bearingsim.programs import jit

CWRU_LIKE = (Path(__file__).resolve().parent / "data" / "cwru_like_6205.toml").read_text()
CONVERGED = 8           # Newton steps: the lean solve converged (ball loads to ~1e-12, see test_dynamics)


def _case(name):
    return parse_case(CWRU_LIKE, "cwru_like.toml") if name == "cwru_like" else load_case(name)


@pytest.fixture(scope="module", params=["cwru_like", "cwru_6205"])
def trajectory(request):
    """40 ms of a simulation with the full solve: the model, the ring displacement and the motion
    per sample, and which samples' steps hold a defect edge."""
    c = _case(request.param)
    b, op, F, sp = c.bearing(), c.operation(), c.loads(), c.spall()
    p = dyn.DynamicsParameters.from_settings(c.dynamics_settings())
    r = dyn.simulate(b, op, F, sp, p, 0.04, 48000.0, theta0=c.cage_angle, progress=False, ball_solver="full")
    model = dyn.build_model(b, op, F, (sp,), r.quasi_static, p, hertz.stiffness_curve(b), r.ball_iterations,
                            r.spin_ratio)
    stage = np.stack([r.cage_angle, r.shaft_angle, r.shaft_speed], -1)
    # sample k's state is reached by step k - 1: its edge flag is that step's
    edge = np.zeros(r.time.size, bool)
    k = np.searchsorted(r.time, r.jump_times)
    edge[k[k < r.time.size]] = True
    return request.param, model, r, stage, edge


@jit
def _replay(model, rel, stage, edge):
    """The chord solve along a given trajectory (the time loop's ball solve, open loop): the
    final carry, and per sample the ring load, the record and whether it was solved in full."""
    def body(bc, xs):
        R, rec, new = model.ring_load_chord(xs[0], xs[1], bc, xs[2])
        return new, (R, rec, new.full > bc.full)
    return jax.lax.scan(body, dyn.initial_ball_carry(model.bearing.n_balls), (rel, stage, edge))


@jit
def _converged(model, rel, stage):
    """The lean solve iterated to convergence at every sample: ring load and contact loads."""
    def one(x, s):
        psi = model.bearing.ball_azimuths(s[0])
        q = jnp.concatenate([x, model.tilts])
        op = eqx.tree_at(lambda o: o.speed, model.op, s[2])
        Ho, Hi = model.depths(psi, s[1])
        R, st = dyn.bearing_force(model.bearing, op, model.curve, q, psi, Ho, Hi, CONVERGED, full_state=True)
        return R, jnp.stack([st.Q_inner, st.Q_outer])
    return jax.vmap(one)(rel, stage)


def test_chord_loads_match_the_converged_solve(trajectory):
    """Along 40 ms of the CWRU-like (1000 N) and the calibrated CWRU (100 N) runs, the chord
    solve's ring loads and recorded contact loads equal the converged ball solve to 1e-5 of the
    largest ball load in the steps the chord answered: an accepted step's residuals are within
    CHORD_TOL = 1e-5 of that load, and a ball's load error is about K_i / (K_i + K_o) ~ 0.5 of
    its residual.  The full steps (every defect edge among them) are those of bearing_force,
    within ITER_TOL."""
    name, model, r, stage, edge = trajectory
    rel, st = jnp.asarray(r.ring_displacement), jnp.asarray(stage)
    bc, (R, rec, full) = _replay(model, rel, st, jnp.asarray(edge))
    R_ref, Q_ref = _converged(model, rel, st)
    R, rec, full, R_ref, Q_ref = map(np.asarray, (R, rec, full, R_ref, Q_ref))
    scale = np.max(Q_ref, axis=(1, 2))                              # largest ball load per sample
    err_q = np.max(np.abs(rec[:, :2] - Q_ref), axis=(1, 2)) / scale
    err_r = np.max(np.abs(R - R_ref), axis=1) / scale
    chord = ~full
    msg = (f"{name}: chord steps {chord.mean():.3f}, error {err_q[chord].max():.2e} (loads) "
           f"{err_r[chord].max():.2e} (ring); full steps {err_q[full].max():.2e}")
    print(msg)
    assert chord.mean() > 0.8, msg                                  # the chord did answer
    assert err_q[chord].max() <= 1e-5, msg
    assert err_r[chord].max() <= 1e-5 * model.bearing.n_balls, msg  # a sum over the balls
    assert err_q[full].max() <= ITER_TOL, msg
    assert 0.0 < float(bc.worst) <= dyn.CHORD_TOL
    assert np.all(full[edge])                                       # every defect edge in full


def test_ball_balance_is_ball_state():
    """balls.ball_balance (both contacts as one stacked array) gives the residuals, loads and
    contact directions of balls.ball_state to round-off, dropped and carried balls included."""
    c = load_case("cwru_6205")
    b, op = c.bearing(), c.operation()
    curve = hertz.stiffness_curve(b)
    q = bs.solve(b, op, c.loads(), spall=c.spall()).displacement
    A1, A2 = balls.groove_centre_offsets(b, q, b.ball_azimuths(0.3))
    x0, _ = balls.static_ball_position(b, op, A1, A2, curve)
    rng = np.random.default_rng(0)
    X = x0 + rng.normal(0.0, 2e-7, x0.shape)
    Ho = jnp.asarray(rng.uniform(0.0, 3e-6, 9) * (rng.uniform(size=9) > 0.5))
    ws = jnp.full(9, 80.0)
    r1, r2, G, H, rec = balls.ball_balance(b, op, (X[0], X[1]), A1, A2, curve, Ho, 0.0 * Ho, ws)
    st = balls.ball_state(b, op, (X[0], X[1]), A1, A2, curve, Ho, 0.0 * Ho, ws)
    scale = float(jnp.max(st.Q_outer))
    for got, want in ((r1, st.r_axial), (r2, st.r_radial), (G, st.ball_G), (H, st.ball_H), (rec[0], st.Q_inner),
                      (rec[1], st.Q_outer)):
        assert float(jnp.max(jnp.abs(got - want))) <= 1e-13 * scale
    for k, a in ((2, st.alpha_inner), (4, st.alpha_outer)):
        assert float(jnp.max(jnp.abs(jnp.arctan2(rec[k], rec[k + 1]) - a))) <= 1e-14
    # the dynamics' Newton step differentiates ball_balance (issue 32): its Jacobian is ball_state's,
    # and both are the central difference of the residuals (an independent check, step 1e-10 m)
    one, zero = jnp.ones(9), jnp.zeros(9)
    bal = lambda x1, x2: balls.ball_balance(b, op, (x1, x2), A1, A2, curve, Ho, 0.0 * Ho, ws)[:4]  # noqa: E731
    sta = lambda x1, x2: (lambda s: (s.r_axial, s.r_radial, s.ball_G, s.ball_H))(  # noqa: E731
        balls.ball_state(b, op, (x1, x2), A1, A2, curve, Ho, 0.0 * Ho, ws))
    jscale = scale / 1e-6                               # N per um of ball travel
    for t in ((one, zero), (zero, one)):
        _, d_bal = jax.jvp(bal, (X[0], X[1]), t)
        _, d_sta = jax.jvp(sta, (X[0], X[1]), t)
        e = 1e-10
        fd = [(p - m) / (2 * e) for p, m in zip(bal(X[0] + e * t[0], X[1] + e * t[1]),
                                                bal(X[0] - e * t[0], X[1] - e * t[1]))]
        for got, want, num in zip(d_bal, d_sta, fd):
            assert float(jnp.max(jnp.abs(got - want))) <= 1e-12 * jscale
            assert float(jnp.max(jnp.abs(got - num))) <= 1e-4 * jscale


def test_precompile_threads_compile_the_programs_the_run_uses(caplog, tmp_path, monkeypatch):
    """simulate compiles the ball-step check and the time loop in background threads
    (dynamics.precompile_ball_check, precompile_fixed) while the quasi-static solve and the
    equilibrium at t = 0 compile: after the threads are joined the run itself compiles neither
    (the warm-ups built the same programs: same padding, static arguments and shapes).  A
    bearing with 11 balls, used by no other test, so that nothing is compiled before; a program
    folder of its own, so that no earlier run's kept Newton count (below) skips the check.  The
    same simulation again reads the check's Newton count (bearingsim.warm.memo): no check runs,
    the same record."""
    import logging

    from bearingsim import programs

    monkeypatch.setattr(programs, "program_dir", lambda: tmp_path / "p")

    c = parse_case(CWRU_LIKE.replace("balls = 9", "balls = 11"), "eleven.toml")
    b, op, F, sp = c.bearing(), c.operation(), c.loads(), c.spall()
    p = dyn.DynamicsParameters.from_settings(c.dynamics_settings())
    before = jax.config.jax_log_compiles
    jax.config.update("jax_log_compiles", True)    # global: a context would hold in this thread only
    try:
        with caplog.at_level(logging.WARNING):
            r = dyn.simulate(b, op, F, sp, p, 0.01, 48000.0, theta0=c.cage_angle, progress=False)
    finally:
        jax.config.update("jax_log_compiles", before)
    assert r.result == 0
    compiles = [(rec.threadName, rec.getMessage()) for rec in caplog.records if "Compiling" in rec.getMessage()]
    names = ("jit(ball_errors)", "jit(_advance_device)")
    for name in names:
        threads = [t for t, m in compiles if name in m]
        assert threads, f"{name} was not compiled at all: {compiles}"
        assert all(t == "bearingsim-precompile" for t in threads), (name, threads)
    # a second configuration already compiled: no thread
    assert dyn.precompile_ball_check(b, op, (sp,), hertz.stiffness_curve(b), c.cage_angle) is None
    hits = programs.counts()["memo_hits"]
    again = dyn.simulate(b, op, F, sp, p, 0.01, 48000.0, theta0=c.cage_angle, progress=False)
    assert programs.counts()["memo_hits"] == hits + 1
    assert again.realism["ball_solver_error"] == r.realism["ball_solver_error"] and again.ball_iterations == r.ball_iterations
    np.testing.assert_array_equal(np.asarray(again.sensor_acceleration), np.asarray(r.sensor_acceleration))
