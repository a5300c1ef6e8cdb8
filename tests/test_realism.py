"""bearingsim.realism against answers known without the code under test.

* Hertz pressure over a disc: the whole load when the disc covers the contact, 3 r^2 / (2 a b)
  of it for a small centred disc (p ~ p0 there, load (2/3) pi a b p0), nothing when the disc
  lies outside the ellipse;
* an effective depth can never exceed the ball's sag over the pit chord nor the machined depth,
  and a pit that takes the whole load unloads the ball (depth = its approach);
* log-normal factors with mean square 1 and the requested coefficient of variation;
* pass windows form a partition of unity (all factors 1: the signal is unchanged);
* an anti-alias decimation keeps a tone in band (1.2 kHz, on a bin) and removes one above the new Nyquist frequency.
"""
import types

import numpy as np
import pytest

from bearingsim import realism as rl

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
    rng = np.random.default_rng(0)
    f = rl.pass_factors(rng, 200_000, 0.5)
    assert np.mean(f * f) == pytest.approx(1.0, abs=0.02)           # ~10 sigma of the estimator
    assert np.std(f) / np.mean(f) == pytest.approx(0.5, rel=0.02)
    assert np.all(rl.pass_factors(rng, 10, 0.0) == 1.0)
    with pytest.raises(ValueError):
        rl.pass_factors(rng, 3, -0.1)
    assert rl.pass_cv(0.2e-3, 0.1e-3, 0.6) == 0.0                    # bridged by the contact
    assert rl.pass_cv(0.4e-3, 0.1e-3, 0.6) == pytest.approx(0.3)
    assert rl.pass_cv(0.0, 0.1e-3, 0.6) == 0.0


def test_vary_passes_is_a_partition_of_unity():
    fs = 48000.0
    rng = np.random.default_rng(1)
    x = rng.standard_normal(48000) + 3.0
    tp = 0.004 + np.arange(100) / 107.4
    tp = tp[tp < 1.0]
    assert np.allclose(rl.vary_passes(x, fs, tp, np.ones(tp.size + 1)), x, atol=1e-12)
    assert np.allclose(rl.vary_passes(x, fs, tp, np.full(tp.size + 1, 2.0)), 2 * (x - x.mean()) + x.mean())
    # an impulse well inside pass k's window is scaled by factor k
    imp = np.zeros(48000)
    k = 10
    i = int(round((tp[k] + 0.3 / 107.4) * fs))
    imp[i] = 1.0
    fac = np.arange(tp.size + 1, dtype=float)          # factors[0]: before the first pass
    y = rl.vary_passes(imp, fs, tp, fac)
    m = imp.mean()
    assert y[i] == pytest.approx((1 - m) * fac[k + 1] + m, rel=1e-9)
    with pytest.raises(ValueError, match="factors"):
        rl.vary_passes(x, fs, tp, np.ones(3))


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
    from bearingsim.sensor import apply_sensor

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
    the variability constants are those of docs/calibrate_cwru.py (finite, >= 0)."""
    from pathlib import Path

    from bearingsim.case import load_case

    case = load_case(Path(__file__).resolve().parents[1] / "cases" / name)
    b = case.bearing()
    pit = rl.pit_effective_depth(b, case.operation(), case.loads(), inches * INCH, 0.011 * INCH)
    assert float(case.spall().depth) == pytest.approx(pit.depth, rel=1e-3)
    assert float(case.spall().length(b)) == pytest.approx(inches * INCH, rel=1e-9)
    assert rl.CWRU_PASS_CV_MAX >= 0.0 and 0.0 <= rl.CWRU_PASS_JITTER_MAX < 0.5


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
