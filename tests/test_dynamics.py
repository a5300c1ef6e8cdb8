"""Dynamic layer (docs/model.md section 7): equilibrium, quasi-static limit, impulses at BPFO."""
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.signal as ss

import bearingsim as bs
from bearingsim.physics import hertz
from bearingsim import dynamics as dyn
from bearingsim.dynamics import sensor
from bearingsim.case import load_case, parse_case
from bearingsim.signals.envelope import envelope_spectrum, peak_frequency, squared_envelope
from bearingsim.physics.sweep import sweep
from bearingsim.programs import jit

CASES = Path(__file__).resolve().parent.parent / "cases"
CWRU_BPFO_MULT = 3.5848


#: a CWRU-like 6205 with a 0.021 in rectangular spall under 1000 N, fixed so that the engine's
#: checks do not move with the calibration of cases/cwru_6205.toml
CWRU_LIKE = (Path(__file__).resolve().parent / "data" / "cwru_like_6205.toml").read_text()


@pytest.fixture(scope="module")
def cwru():
    c = parse_case(CWRU_LIKE, "cwru_like.toml")
    return c, c.bearing(), c.operation(), c.loads(), c.spall()


@pytest.fixture(scope="module")
def cwru_run(cwru):
    """0.3 s of the CWRU 6205 with the 0.021 in spall, cage half a pitch before the spall."""
    c, b, op, F, sp = cwru
    d = c.dynamics_settings()
    theta0 = -np.pi / b.n_balls
    return dyn.simulate(b, op, F, sp, dyn.DynamicsParameters.from_settings(d), 0.3, 48000.0,
                        theta0=theta0, progress=False)


def test_healthy_stays_at_quasi_static_equilibrium():
    """Pure thrust, no spall, no unbalance: every ball is identical at every instant, the
    quasi-static state is an exact equilibrium of the dynamic model, nothing moves."""
    c = load_case(CASES / "harris218_thrust.toml")
    b, op, F = c.bearing(), c.operation(), c.loads()
    r = dyn.simulate(b, op, F, None, dyn.DynamicsParameters(), 0.004, 20000.0, progress=False)
    assert r.result == 0
    qs = r.quasi_static
    Qo = np.asarray(r.Q_outer)
    Qi = np.asarray(r.Q_inner)
    assert np.max(np.abs(Qo - np.asarray(qs.Q_outer)[None])) <= 1e-3 * np.max(qs.Q_outer)
    assert np.max(np.abs(Qi - np.asarray(qs.Q_inner)[None])) <= 1e-3 * np.max(qs.Q_inner)
    dz = np.asarray(r.ring_displacement)[:, 2] - float(qs.displacement[2])
    assert np.max(np.abs(dz)) <= 1e-3 * abs(float(qs.displacement[2]))
    assert np.max(np.abs(np.asarray(r.sensor_acceleration))) < 1e-6


def test_slow_heavily_damped_follows_quasi_static_sweep(cwru):
    """6 rpm, a ball crossing a ball-path spall, heavy contact damping: the dynamic ball
    loads follow the quasi-static sweep at the same cage angles."""
    c, b, _, F, sp = cwru
    op = bs.Operation.from_rpm(6.0)
    spall = bs.Spall(sp.center, sp.extent, sp.depth, "ball-path")
    p = dyn.DynamicsParameters(contact_damping_ratio=0.7, housing_damping=2e4)
    theta0 = float(sp.center) - 0.9 * float(sp.extent)
    sol = bs.solve(b, op, F, cage_angle=theta0, spall=spall)
    dur = 1.8 * float(sp.extent) / float(sol.cage_speed)
    r = dyn.simulate(b, op, F, spall, p, dur, 2000.0 / dur, theta0=theta0, progress=False)
    assert r.result == 0
    # every 10th sample: 200 cage angles over the crossing (the profile is smooth and the
    # loads follow it slowly; the sweep of all 2000 cost most of the test's minute)
    ref = sweep(b, op, F, spall, angles=np.asarray(r.cage_angle)[::10])
    assert np.all(np.asarray(ref.result) == 0)
    Qo, Qref = np.asarray(r.Q_outer)[::10], np.asarray(ref.Q_outer)
    err = np.max(np.abs(Qo - Qref)) / np.max(Qref)
    print("max relative ball-load difference dynamic vs sweep", err)
    assert err < 0.03, err
    # the ball over the spall really sheds load (the check is not trivial)
    assert Qref[:, 0].min() < 0.8 * Qref[:, 0].max()


def test_one_impulse_per_spall_pass(cwru, cwru_run):
    r = cwru_run
    fs = 48000.0
    t = np.asarray(r.time)
    band = (2625.0, 3375.0)
    env = squared_envelope(np.asarray(r.sensor_acceleration), fs, band)
    env = env - env.min()
    bpfo = r.frequencies.bpfo
    peaks, _ = ss.find_peaks(env, height=0.2 * env.max(), distance=int(0.6 * fs / bpfo))
    passes = r.pass_times[(r.pass_times > 0.0) & (r.pass_times < t[-1] - 2e-3)]
    assert len(passes) >= 30
    assert len(peaks) == len(passes)
    # each impulse follows its pass within a millisecond or two
    lag = t[peaks] - passes
    assert np.all((lag > -1e-3) & (lag < 3e-3)), lag


def test_envelope_peak_at_bpfo(cwru_run):
    r = cwru_run
    es = envelope_spectrum(np.asarray(r.sensor_acceleration), 48000.0, band=(2625.0, 3375.0))
    bpfo = r.frequencies.bpfo
    fp = peak_frequency(es, bpfo, rel_window=0.05)
    assert abs(fp - bpfo) / bpfo < 5e-3, (fp, bpfo)


def test_reported_bpfo_matches_cwru(cwru_run):
    fr = cwru_run.frequencies
    assert fr.shaft == pytest.approx(1797 / 60)
    ratio = fr.bpfo / fr.shaft
    # quasi-static cage speed at the loaded contact angle vs the alpha = 0 CWRU multiplier
    assert ratio == pytest.approx(CWRU_BPFO_MULT, rel=0.02)
    assert fr.bpfo == pytest.approx(9 * fr.ftf)


def test_fixed_step_matches_adaptive_reference(cwru):
    """The default fixed-step scheme (Newmark, one step per sample at 48 kHz, the spall edges
    integrated exactly inside their step) against diffrax Tsit5 at rtol = atol = 1e-7 with the
    edges as jump_ts and the sensor mode integrated in the ODE: 6 ms with one ball crossing the
    0.021 in spall (entry and exit)."""
    c, b, op, F, sp = cwru
    p = dyn.DynamicsParameters.from_settings(c.dynamics_settings())
    theta0 = float(sp.center) - float(sp.extent) - 0.05
    kw = dict(theta0=theta0, progress=False, record_balls=False, ball_iterations=1)
    fixed = dyn.simulate(b, op, F, sp, p, 0.006, 48000.0, **kw)
    ref = dyn.simulate(b, op, F, sp, p, 0.006, 48000.0, integrator="adaptive", rtol=1e-7, atol=1e-7, **kw)
    assert fixed.result == 0 and ref.result == 0 and fixed.scheme == "newmark" and fixed.substeps == 1
    assert len(fixed.jump_times) == 2
    a, a_ref = fixed.sensor_acceleration, ref.sensor_acceleration
    assert a_ref.std() > 10.0                       # the impacts are there
    rms_err = np.sqrt(np.mean((a - a_ref) ** 2)) / a_ref.std()
    ring_err = np.abs(fixed.ring_displacement - ref.ring_displacement).max() / \
        np.abs(ref.ring_displacement[:, 0]).max()
    print("sensor rms error", rms_err, "ring error", ring_err)
    assert rms_err < 0.03 and ring_err < 0.01
    # without the exact edges (Heun, same step) the error is several times larger
    heun = dyn.simulate(b, op, F, sp, p, 0.006, 48000.0, scheme="heun", substeps=1, **kw)
    assert np.sqrt(np.mean((heun.sensor_acceleration - a_ref) ** 2)) / a_ref.std() > 2 * rms_err


def test_exact_sensor_filter_matches_resonator_ode():
    """The FOH-exact discretisation of the modes equals the resonator ODE driven by the same
    piecewise-linear housing acceleration (scipy lsim), for any step (here f h = 0.25)."""
    from scipy import signal as sig

    fs = 12000.0
    rng = np.random.default_rng(1)
    u = rng.standard_normal(600)
    freqs, zetas, gains = [3000.0, 4200.0], [0.05, 0.02], [1.0, 0.5]
    out = np.asarray(sensor.apply_sensor(u, 1 / fs, freqs, zetas, gains))
    t = np.arange(u.size) / fs
    ref = u.copy()
    for f, z, g in zip(freqs, zetas, gains):
        w = 2 * np.pi * f
        # relative acceleration z'' = -2 zeta w z' - w^2 z - u of z'' + 2 zeta w z' + w^2 z = -u
        sysm = sig.StateSpace([[0, 1], [-w * w, -2 * z * w]], [[0], [-1]], [[-w * w, -2 * z * w]], [[-1]])
        ref += g * sig.lsim(sysm, u, t, interp=True)[1]
    assert np.max(np.abs(out - ref)) < 1e-7 * np.max(np.abs(ref))     # a zero-order hold: ~1e-1


def test_step_inside_a_step_is_exact():
    """A unit step of the input at 0.3 of a step: the jump update equals the continuous response."""
    h = 1 / 48000.0
    flt = sensor.sensor_filter(3000.0, 0.05, 1.0, h)
    s = sensor.filter_update(flt, sensor.filter_init(flt), 0.0, 1.0, jnp_float(0.3), h)
    fine = sensor.sensor_filter(3000.0, 0.05, 1.0, 0.7 * h)     # at rest until 0.3 h, then held
    s_ref = np.asarray(fine.Gamma0)
    np.testing.assert_allclose(np.asarray(s), s_ref, rtol=1e-10, atol=1e-18)


def key_motion(seed, Z, theta0, wc, w0, duration, center=0.0, realism=dyn.Realism()):
    """The package's draw (from the key of item 0 of a run seeded ``seed``, as simulate draws it)
    (a dynamics.Motion)."""
    nk = dyn.knot_count(Z, wc / (2 * np.pi), duration, realism.speed_fluctuation_percent / 100.0)
    dm = dyn.draw_motion(dyn.item_keys(seed, [0])[0], Z, theta0, wc, w0, duration, center, realism, nk)
    return dm


def jnp_float(x):
    import jax.numpy as jnp
    return jnp.float64(x)


def test_slip_jitters_the_pass_interval():
    """Ball passes over the spall centre are (1 + eps) T_BPFO apart, std(eps) = slip_percent;
    the mean stays at BPFO; without slip they are exactly periodic."""
    Z, wc = 9, 75.0
    T = 2 * np.pi / Z / wc
    sp = bs.Spall(0.3, 0.02, 1e-4, "rectangular")
    m = key_motion(5, Z, 0.0, wc, 188.0, 30.0, float(sp.center), dyn.Realism(slip_percent=1.5))
    tp = dyn.defect_pass_times(m, Z, sp, 30.0)
    d = np.diff(tp) / T
    assert d.size > 3000
    assert abs(d.mean() - 1.0) < 2e-3
    assert d.std() == pytest.approx(0.015, rel=0.06)
    assert np.corrcoef(d[:-1], d[1:])[0, 1] == pytest.approx(0.0, abs=0.06)    # independent
    m0 = key_motion(5, Z, 0.0, wc, 188.0, 1.0, float(sp.center))
    assert np.ptp(np.diff(dyn.defect_pass_times(m0, Z, sp, 1.0))) < 1e-9


def test_speed_fluctuation_and_noise_levels():
    m = key_motion(2, 9, 0.0, 75.0, 188.0, 20.0, 0.0, dyn.Realism(speed_fluctuation_percent=2.0,
                                                                        speed_fluctuation_bandwidth_Hz=4.0))
    t = np.linspace(0, 20, 200001)
    _, _, w = dyn.motion_at(m, 9, t)
    assert np.std(w / 188.0 - 1.0) == pytest.approx(0.02, rel=0.35)      # 8 random sinusoids
    import jax
    x = np.asarray(sensor.measurement_noise(jax.random.PRNGKey(0), 48000, 0.686, 48000.0, (2000.0, 6000.0)))
    assert np.sqrt(np.mean(x ** 2)) == pytest.approx(0.686, rel=1e-12)
    X = np.abs(np.fft.rfft(x))
    f = np.fft.rfftfreq(x.size, 1 / 48000.0)
    assert np.max(X[(f < 1990) | (f > 6010)]) < 1e-9 * X.max()


def test_realism_is_seeded_and_labelled(cwru):
    c, b, op, F, sp = cwru
    real = dyn.Realism(slip_percent=2.0, noise_rms=0.5)
    kw = dict(theta0=-0.3, progress=False, record_balls=False, realism=real)
    r1 = dyn.simulate(b, op, F, sp, None, 0.01, 48000.0, seed=4, **kw)
    r2 = dyn.simulate(b, op, F, sp, None, 0.01, 48000.0, seed=4, **kw)
    r3 = dyn.simulate(b, op, F, sp, None, 0.01, 48000.0, seed=5, **kw)
    assert np.array_equal(r1.sensor_acceleration, r2.sensor_acceleration)
    assert not np.array_equal(r1.sensor_acceleration, r3.sensor_acceleration)
    assert r1.realism["seed"] == 4 and r1.realism["slip_percent"] == 2.0
    assert np.sqrt(np.mean(r1.noise ** 2)) == pytest.approx(0.5, rel=1e-9)


def test_lean_ball_solver_accuracy(cwru):
    c, b, op, F, sp = cwru
    sol = bs.solve(b, op, F, cage_angle=0.0, spall=sp)
    curve = hertz.stiffness_curve(b)
    n, err = dyn.choose_ball_iterations(b, op, sol.displacement, sp, curve)
    assert n == 1 and err <= 1e-3
    n, err = dyn.choose_ball_iterations(b, op, sol.displacement, sp, curve, tol=1e-9)
    assert 2 <= n <= 3 and err <= 1e-9             # quadratic convergence from the closed form


@pytest.mark.parametrize("name", ["demo", "cwru_6205_inner"])
def test_converged_lean_solve_is_the_exact_ball_state(name):
    """The reference of choose_ball_iterations (the lean solve iterated to convergence) is the
    exact ball state of balls.balls_at -- balls over the demo's 0.16 mm spall at 10 000 rpm
    (dropped and carried) and under an inner-race spall included.  Tolerance 1e-10 of the
    largest ball load: both are converged Newton solutions (measured 5e-14)."""
    import jax
    import jax.numpy as jnp
    c = load_case(name)
    b, op, F, sp = c.bearing(), c.operation(), c.loads(), c.spall()
    curve = hertz.stiffness_curve(b)
    q = bs.solve(b, op, F, cage_angle=c.cage_angle, spall=sp).displacement

    @jit
    def worst(th):
        def at(t):
            psi = b.ball_azimuths(t)
            Ho, Hi = bs.contact_depths(b, sp, psi)
            ref = bs.balls_at(b, op, q, psi, curve, H_outer=Ho, H_inner=Hi)
            G, H = dyn.bearing_force_history(b, op, curve, q, psi, Ho, Hi, dyn.REF_ITERATIONS)
            scale = jnp.maximum(jnp.max(ref.Q_outer), jnp.max(ref.Q_inner))
            return jnp.maximum(jnp.max(jnp.abs(G[-1] - ref.ball_G)), jnp.max(jnp.abs(H[-1] - ref.ball_H))) / scale
        return jnp.max(jax.vmap(at)(th))

    th = (float(sp.center) if sp.location == "outer" else 0.0) + jnp.linspace(-0.2, 0.2, 9)
    assert float(worst(th)) <= 1e-10


def test_ball_records_of_the_time_loop_equal_a_separate_solve(cwru_run):
    """The per-sample ball loads and angles recorded in the time loop (from the step's own ball
    solve) equal a separate solve with one Newton step more at the recorded ring displacements
    (ball_records): 1e-5 of the largest load, 1e-4 deg (measured 1e-6, 2e-5 deg)."""
    import importlib
    sim = importlib.import_module("bearingsim.dynamics.simulate")
    r = cwru_run
    c = parse_case(CWRU_LIKE, "cwru_like.toml")
    b = c.bearing()
    n = 2400                                                   # 50 ms with four spall passes
    model = dyn.build_model(b, c.operation(), c.loads(), (c.spall(),), r.quasi_static,
                            dyn.DynamicsParameters.from_settings(c.dynamics_settings()),
                            hertz.stiffness_curve(b), r.ball_iterations, r.spin_ratio)
    ref = sim.ball_records(model, r.ring_displacement[:n], r.cage_angle[:n], r.shaft_angle[:n],
                           r.shaft_speed[:n], r.ball_iterations + 1)
    scale = float(np.max(ref[1]))
    for got, want in zip((r.Q_inner, r.Q_outer), ref[:2]):
        assert np.max(np.abs(got[:n] - want)) <= 1e-5 * scale
    for got, want in zip((r.alpha_inner, r.alpha_outer), ref[2:]):
        assert np.degrees(np.max(np.abs(got[:n] - want))) <= 1e-4


def test_failed_initial_state_is_flagged():
    """A quasi-static state that is not valid is flagged, never integrated silently."""
    c = parse_case(CWRU_LIKE, "cwru_like.toml")
    b, op = c.bearing(), c.operation()
    F = np.array([1e7, 0.0, 0.0, 0.0, 0.0])      # far beyond the bearing's capacity
    r = dyn.simulate(b, op, F, None, None, 0.002, 48000.0, progress=False, throw=False,
                     record_balls=False, ball_iterations=1, substeps=1)
    assert r.result == dyn.RESULTS.initial_state and np.all(r.sensor_acceleration == 0)
    with pytest.raises(dyn.DynamicsError) as e:
        dyn.simulate(b, op, F, None, None, 0.002, 48000.0, progress=False, ball_iterations=1, substeps=1)
    assert e.value.code == dyn.RESULTS.initial_state and isinstance(e.value, bs.NotConvergedError)
