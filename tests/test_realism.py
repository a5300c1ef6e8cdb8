"""bearingsim.realism.rig_record against answers known without the code under test.

* Hertz pressure over a disc: the whole load when the disc covers the contact, 3 r^2 / (2 a b)
  of it for a small centred disc (p ~ p0 there, load (2/3) pi a b p0), nothing when the disc
  lies outside the ellipse;
* an effective depth can never exceed the ball's sag over the pit chord nor the machined depth,
  and a pit that takes the whole load unloads the ball (depth = its approach);
* log-normal factors with mean square 1 and the requested coefficient of variation;
* pass windows form a partition of unity (all factors 1: the signal is unchanged);
* an anti-alias decimation keeps a tone in band (1.2 kHz, on a bin) and removes one above the new Nyquist frequency;
* the engine's pass-to-pass variability: scaled by 1 - 2b/w with b from an independent healthy
  solve, acting on the sensor path only with its labelled draws, off for a bridged pit.
"""
import types

import numpy as np
import pytest

from bearingsim.realism import rig_record as rl
from oracles import passes_numpy

INCH = 25.4e-3


@pytest.fixture(scope="module")
def cwru():
    from bearingsim.case import load_case
    from pathlib import Path

    case = load_case(Path(__file__).resolve().parents[1] / "cases" / "cwru_6205.toml")
    return case.bearing(), case.operation(), case.loads()


def test_pit_load_fraction_limits():
    a, b = 1.0e-3, 0.1e-3
    assert rl.pit_load_fraction(a, b, 5e-3) == pytest.approx(1.0, abs=1e-6)
    r = 5e-6
    assert rl.pit_load_fraction(a, b, 2 * r) == pytest.approx(3 * r * r / (2 * a * b), rel=1e-3)
    assert rl.pit_load_fraction(a, b, 0.2e-3, offset=1.2e-3) == 0.0
    assert rl.pit_load_fraction(a, b, 0.2e-3, offset=0.5e-3) == \
        pytest.approx(rl.pit_load_fraction(a, b, 0.2e-3, offset=-0.5e-3))
    # off-centre pits sit where the pressure is lower; bigger pits take more
    assert rl.pit_load_fraction(a, b, 0.2e-3, offset=0.5e-3) < rl.pit_load_fraction(a, b, 0.2e-3)
    fr = [rl.pit_load_fraction(a, b, w) for w in (0.05e-3, 0.1e-3, 0.3e-3, 1e-3)]
    assert np.all(np.diff(fr) > 0)
    # a strip across the whole contact length, |x| < r: (2u - 2u^3/3) / (4/3), u = r/a
    u = 0.3
    strip = rl.pit_load_fraction(a, 1e-9 + 1e-6, 2 * u * a)       # b << r: the disc covers all y
    assert strip == pytest.approx((2 * u - 2 * u**3 / 3) / (4 / 3), rel=2e-3)


def test_pit_effective_depth_bounds_and_growth(cwru):
    bearing, op, loads = cwru
    deep = 0.011 * INCH
    d7 = rl.pit_effective_depth(bearing, op, loads, 0.007 * INCH, deep)
    d21 = rl.pit_effective_depth(bearing, op, loads, 0.021 * INCH, deep)
    for d in (d7, d21):
        assert 0.0 < d.depth <= min(d.sag, deep)
        assert 0.0 < d.load_fraction < 1.0
    # the sag grows as w^2 (x 9); the pit under a contact much less
    assert d21.sag / d7.sag == pytest.approx(9.0, rel=0.01)
    assert 1.5 < d21.depth / d7.depth < 0.75 * d21.sag / d7.sag
    # a shallow machined depth caps it
    assert rl.pit_effective_depth(bearing, op, loads, 0.021 * INCH, 1e-7).depth == pytest.approx(1e-7)
    # a pit that takes the whole load: the ball is unloaded (depth = approach, below the sag)
    big = rl.pit_effective_depth(bearing, op, loads, 3e-3, deep)
    assert big.load_fraction == pytest.approx(1.0, abs=1e-6)
    assert big.depth == pytest.approx(min(big.contact.delta, big.sag))


def test_pass_factors_and_cv():
    """The NumPy oracle's per-pass factors (tests/oracles/passes_numpy.py; the package's JAX ones
    are tested in tests/test_signal_stage.py): mean square 1, c.v. as asked."""
    rng = np.random.default_rng(0)
    f = passes_numpy.pass_factors(rng, 200_000, 0.5)
    assert np.mean(f * f) == pytest.approx(1.0, abs=0.02)           # ~10 sigma of the estimator
    assert np.std(f) / np.mean(f) == pytest.approx(0.5, rel=0.02)
    assert np.all(passes_numpy.pass_factors(rng, 10, 0.0) == 1.0)
    with pytest.raises(ValueError):
        passes_numpy.pass_factors(rng, 3, -0.1)
    assert rl.pass_cv(0.2e-3, 0.1e-3, 0.6) == 0.0                    # bridged by the contact
    assert rl.pass_cv(0.4e-3, 0.1e-3, 0.6) == pytest.approx(0.3)
    assert rl.pass_cv(0.0, 0.1e-3, 0.6) == 0.0


def test_vary_passes_is_a_partition_of_unity():
    """The oracle's windows (the JAX vary_passes equals them: tests/test_signal_stage.py)."""
    fs = 48000.0
    rng = np.random.default_rng(1)
    x = rng.standard_normal(48000) + 3.0
    tp = 0.004 + np.arange(100) / 107.4
    tp = tp[tp < 1.0]
    assert np.allclose(passes_numpy.vary_passes(x, fs, tp, np.ones(tp.size + 1)), x, atol=1e-12)
    assert np.allclose(passes_numpy.vary_passes(x, fs, tp, np.full(tp.size + 1, 2.0)), 2 * (x - x.mean()) + x.mean())
    # an impulse well inside pass k's window is scaled by factor k
    imp = np.zeros(48000)
    k = 10
    i = int(round((tp[k] + 0.3 / 107.4) * fs))
    imp[i] = 1.0
    fac = np.arange(tp.size + 1, dtype=float)          # factors[0]: before the first pass
    y = passes_numpy.vary_passes(imp, fs, tp, fac)
    m = imp.mean()
    assert y[i] == pytest.approx((1 - m) * fac[k + 1] + m, rel=1e-9)
    with pytest.raises(ValueError, match="factors"):
        passes_numpy.vary_passes(x, fs, tp, np.ones(3))


def test_decimate_record_anti_alias():
    fs = 48000.0
    t = np.arange(48000) / fs
    y, fs2 = rl.decimate_record(np.sin(2 * np.pi * 1200 * t) + np.sin(2 * np.pi * 8000 * t), fs, 12000.0)
    assert fs2 == 12000.0 and y.size == 12000
    spec = np.abs(np.fft.rfft(y[1000:-1000] * np.hanning(10000))) * 2 / np.hanning(10000).sum()
    f = np.fft.rfftfreq(10000, 1 / fs2)
    assert spec[np.argmin(np.abs(f - 1200))] == pytest.approx(1.0, rel=0.01)   # on a bin
    assert spec[np.argmin(np.abs(f - 4000))] < 1e-3                # 8 kHz would alias to 4 kHz
    with pytest.raises(ValueError, match="integer"):
        rl.decimate_record(y, 48000.0, 11000.0)


def test_sensor_record_without_variability_is_the_sensor_path():
    from bearingsim.dynamics import DynamicsParameters
    from bearingsim.dynamics.sensor import apply_sensor

    fs = 48000.0
    rng = np.random.default_rng(2)
    n = 4800
    a_h = rng.standard_normal(n)
    noise = 0.1 * rng.standard_normal(n)
    res = types.SimpleNamespace(time=np.arange(n) / fs, housing_acceleration=np.stack([a_h, 0 * a_h], 1),
                                pass_times=np.arange(0.001, 0.1, 1 / 107.4), noise=noise)
    params = DynamicsParameters(resonance_frequency=[3000.0, 3400.0], resonance_damping_ratio=[0.02, 0.03],
                                resonance_gain=[1.0, 2.0])
    y, fs_y, lab = rl.sensor_record(res, params, cv=0.0, seed=3)
    ref = np.asarray(apply_sensor(a_h, 1 / fs, [3000.0, 3400.0], [0.02, 0.03], [1.0, 2.0])) + noise
    assert fs_y == fs and np.allclose(y, ref, rtol=0, atol=1e-12)
    assert np.all(lab["pass_factors"] == 1.0)
    y2, _, lab2 = rl.sensor_record(res, params, cv=0.5, seed=3)
    y3, _, _ = rl.sensor_record(res, params, cv=0.5, seed=3)
    assert np.array_equal(y2, y3) and not np.allclose(y2, y)          # seeded, and it acts
    assert lab2["pass_factors"].size == lab2["pass_times"].size + 1


@pytest.mark.parametrize("name, inches", [("cwru_6205_or007.toml", 0.007), ("cwru_6205.toml", 0.021)])
def test_calibrated_case_depths_are_the_pit_physics(name, inches):
    """The CWRU case files carry the effective depth of their pit (4 significant digits), and
    the outer-race cases the pass-to-pass variability of docs/calibrate_cwru.py (stage E): both
    maxima set, the delay's s.d. below half the pass interval."""
    from pathlib import Path

    from bearingsim.case import load_case

    case = load_case(Path(__file__).resolve().parents[1] / "cases" / name)
    b = case.bearing()
    pit = rl.pit_effective_depth(b, case.operation(), case.loads(), inches * INCH, 0.011 * INCH)
    assert float(case.spall().depth) == pytest.approx(pit.depth, rel=1e-3)
    assert float(case.spall().length(b)) == pytest.approx(inches * INCH, rel=1e-9)
    d = case.dynamics_settings()
    assert d["pass_amplitude_cv_max_percent"] > 0.0 and 0.0 < d["pass_delay_sd_max_percent"] < 50.0


def test_pit_depth_at_the_inner_race_and_on_a_ball(cwru):
    """The inner-race pit takes the ball's inner contact (offset f_i D sin(alpha_i) from the
    groove bottom), the ball pit both contacts centred (it meets them on the ball's rolling
    circle) and their mean; each depth from pit_depth on the contact read independently from
    the healthy Jones solution (bs.solve), and within the sag and the machined depth."""
    import bearingsim as bs

    bearing, op, loads = cwru
    w, deep = 0.014 * INCH, 0.011 * INCH
    sol = bs.solve(bearing, op, loads, cage_angle=0.0)
    D, fi = float(bearing.ball_diameter), float(bearing.f_inner)
    ai = float(sol.alpha_inner[0])
    ci = rl.Contact(float(sol.delta_inner[0]), float(sol.a_inner[0]), float(sol.b_inner[0]),
                    float(sol.Q_inner[0]), ai, fi * D * abs(np.sin(ai)))
    inner = rl.pit_effective_depth(bearing, op, loads, w, deep, 0.0, location="inner")
    assert inner.depth == pytest.approx(rl.pit_depth(ci, w, deep, D).depth, rel=1e-12)
    assert 0.0 < inner.depth <= min(inner.sag, deep) and inner.contact.offset > 0.0
    co = rl.Contact(float(sol.delta_outer[0]), float(sol.a_outer[0]), float(sol.b_outer[0]),
                    float(sol.Q_outer[0]), float(sol.alpha_outer[0]), 0.0)
    ball = rl.pit_effective_depth(bearing, op, loads, w, deep, 0.0, location="ball")
    both = [rl.pit_depth(c, w, deep, D).depth for c in (co, ci._replace(offset=0.0))]
    assert ball.depth == pytest.approx(np.mean(both), rel=1e-12)
    assert both[0] != both[1]          # the two contacts differ (conformity, load): a real mean
    with pytest.raises(ValueError, match="location"):
        rl.pit_effective_depth(bearing, op, loads, w, deep, location="cage")


def test_pit_depth_of_an_unloaded_contact_is_zero():
    """A contact without load (a = 0, delta <= 0) loses nothing over a pit."""
    c = rl.Contact(-1e-7, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert rl.pit_depth(c, 0.2e-3, 0.3e-3, 8e-3).depth == 0.0


@pytest.fixture(scope="module")
def cwru_runs():
    """The calibrated 0.021 in case, 40 ms at 24 kHz, with its pass-to-pass variability (seed 5)
    and the same draw with both maxima 0."""
    from pathlib import Path

    from bearingsim import dynamics as dyn
    from bearingsim.app import signal_workflows
    from bearingsim.case import load_case

    case = load_case(Path(__file__).resolve().parents[1] / "cases" / "cwru_6205.toml")
    d = case.dynamics_settings()
    on = dyn.Realism.from_settings(d)
    off = on._replace(pass_amplitude_cv_max_percent=0.0, pass_delay_sd_max_percent=0.0)
    kw = dict(params=dyn.DynamicsParameters.from_settings(d), duration=0.04, sample_rate=24000.0,
              seed=5, record_balls=False)
    return (case, on, signal_workflows.simulate_case(case, throw=False, realism=on, **kw),
            signal_workflows.simulate_case(case, throw=False, realism=off, **kw))


def test_engine_pass_variability_scales_with_the_unbridged_fraction(cwru_runs):
    """The engine's labels: c.v. and delay s.d. = the [dynamics] maxima x (1 - 2b/w), b the
    outer contact's semi-axis of the ball at the pit in the healthy state read through the
    single healthy solve of realism.contact_at (the engine takes its own zero-depth solve)."""
    case, on, r, _ = cwru_runs
    b = rl.contact_at(case.bearing(), case.operation(), case.loads(), float(case.spall().center)).b
    u = 1.0 - 2.0 * b / (0.021 * INCH)
    lab = r.realism
    assert lab["unbridged_fraction"] == pytest.approx(u, rel=1e-9)
    assert lab["pass_amplitude_cv_percent"] == pytest.approx(on.pass_amplitude_cv_max_percent * u, rel=1e-9)
    assert lab["pass_delay_sd_percent"] == pytest.approx(on.pass_delay_sd_max_percent * u, rel=1e-9)
    assert lab["pass_factors"].size == lab["pass_shifts"].size == r.pass_times.size + 1


def test_engine_pass_variability_acts_on_the_sensor_path_only(cwru_runs):
    """With the variability on, the sensor record is the sensor modes (apply_sensor) of the ODE's
    housing acceleration varied pass by pass with the labelled draws (vary_passes), plus the
    same noise; the motion, the housing acceleration and the noise equal those of the run with
    the variability off (the slip/noise streams do not move), and the records differ."""
    from bearingsim.dynamics.sensor import apply_sensor

    case, on, r, r0 = cwru_runs
    fs = 24000.0
    lab = r.realism
    for k in ("housing_acceleration", "ring_displacement", "noise", "cage_angle"):
        np.testing.assert_array_equal(getattr(r, k), getattr(r0, k))
    a = passes_numpy.vary_passes(r.housing_acceleration[:, 0], fs, r.pass_times, lab["pass_factors"], lab["pass_shifts"])
    f, z, g = (np.asarray(v) for v in case_params(case).modes())
    ref = np.asarray(apply_sensor(a, 1 / fs, f, z, g)) + r.noise
    scale = np.abs(ref).max()
    np.testing.assert_allclose(r.sensor_acceleration, ref, rtol=0, atol=1e-12 * scale)
    assert np.abs(r.sensor_acceleration - r0.sensor_acceleration).max() > 0.05 * scale


def case_params(case):
    from bearingsim.dynamics import DynamicsParameters

    return DynamicsParameters.from_settings(case.dynamics_settings())


def test_engine_pass_variability_off_for_a_bridged_pit(cwru_runs):
    """A pit shorter than the contact (w < 2b: unbridged fraction 0) is bridged every pass: with
    the maxima on, the record is the one without them (the engine's own sensor path)."""
    from bearingsim import dynamics as dyn
    from bearingsim.physics.defect import Spall

    case, on, _, _ = cwru_runs
    b = case.bearing()
    sp = case.spall()
    short = Spall.from_length(b, sp.center, 0.1e-3, sp.depth, sp.profile, "outer")   # 2b ~ 0.15 mm
    kw = dict(params=case_params(case), duration=0.02, sample_rate=24000.0, seed=5, record_balls=False)
    r1 = dyn.simulate(b, case.operation(), case.loads(), short, realism=on, **kw)
    r0 = dyn.simulate(b, case.operation(), case.loads(), short,
                      realism=on._replace(pass_amplitude_cv_max_percent=0.0, pass_delay_sd_max_percent=0.0), **kw)
    assert r1.realism["unbridged_fraction"] == 0.0
    np.testing.assert_array_equal(r1.sensor_acceleration, r0.sensor_acceleration)


def test_engine_pass_variability_needs_one_defect(cwru_runs):
    from bearingsim import dynamics as dyn
    from bearingsim.physics.defect import Spall
    from bearingsim.errors import InputError

    case, on, _, _ = cwru_runs
    b = case.bearing()
    two = (case.spall(), Spall.from_length(b, 1.0, 0.5e-3, 1e-6, "rectangular", "outer"))
    with pytest.raises(InputError, match="one defect"):
        dyn.simulate(b, case.operation(), case.loads(), two, realism=on, duration=0.01, sample_rate=24000.0)
