"""The drawn motion and the defect timings on the device (issue 25): the statistics of the JAX
draws against the model's definition (and the host draws), and the device's edge / pass times,
stage and jump arrays against independent NumPy computations on the same motion.  The NumPy
draw of the same distributions is the oracle tests/oracles/motion_numpy.py (no longer in the
package: one engine, issue 32)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from bearingsim import dynamics as dyn
from bearingsim.dynamics import sensor
from bearingsim.physics.defect import Spall
from bearingsim.physics.geometry import Bearing
from oracles import motion_numpy as oracle
from oracles.motion_numpy import draw_motion as numpy_draw_motion

Z = 9
FS = 48000.0


@pytest.fixture(scope="module")
def bearing():
    return Bearing.from_clearance(Z, 7.94004e-3, 39.0398e-3, 0.52, 0.52, 0.0)


def draws(n, realism, duration=0.1, omega_c=2 * np.pi * 11.9, omega0=2 * np.pi * 30.0, center=0.0):
    nk = dyn.knot_count(Z, omega_c / (2 * np.pi), duration, realism.speed_fluctuation_percent / 100)
    keys = jax.random.split(jax.random.key(1), n)
    f = jax.jit(jax.vmap(lambda k: dyn.draw_motion(k, Z, 0.0, omega_c, omega0, duration, center, realism, nk)))
    return f(keys), nk


def test_slip_draws_statistics():
    """eps_k ~ N(0, sigma^2) per pitch (docs/model.md section 7, realism 'slip_percent', shipped
    0.9 %): over 2000 runs (~20 000 pitches) the sample mean is within 4 standard errors of 0 and
    the sample s.d. within 3 % of sigma (its standard error is sigma / sqrt(2 n) ~ 0.5 %)."""
    sigma = 0.009
    m, _ = draws(2000, dyn.Realism(slip_percent=100 * sigma))
    eps = np.asarray(m.slip_draws)[np.asarray(m.inside)]
    assert eps.size > 15000
    assert abs(eps.mean()) < 4 * sigma / np.sqrt(eps.size)
    assert abs(eps.std() / sigma - 1.0) < 0.03


def test_slip_walk_limits_and_coverage():
    """The walk's pitches are clipped to 1 +- 0.5 (a large sigma exercises the clip: the
    fraction at the limits is the normal tail P(|x| > 0.5 / sigma) within 3 s.e.), and the knots
    cover every run (motion_ok)."""
    sigma = 0.4
    m, _ = draws(400, dyn.Realism(slip_percent=100 * sigma))
    eps = np.asarray(m.slip_draws)
    assert eps.min() >= -0.5 and eps.max() <= 0.5
    from scipy.stats import norm
    p = 2 * norm.sf(0.5 / sigma)
    frac = np.mean(np.abs(eps) == 0.5)
    assert abs(frac - p) < 3 * np.sqrt(p * (1 - p) / eps.size)
    ok = jax.vmap(lambda mm: dyn.motion_ok(mm, Z, 0.1))(m)
    assert bool(np.all(np.asarray(ok)))


def test_pass_intervals_follow_slip(bearing):
    """The outer-race pass intervals are (1 + eps_k) T_BPFO (no fluctuation): their relative
    s.d. is sigma within 4 % over 2000 runs, their mean T_BPFO within 0.1 %."""
    sigma, wc = 0.009, 2 * np.pi * 11.9
    m, _ = draws(2000, dyn.Realism(slip_percent=100 * sigma), omega_c=wc)
    sp = (Spall(0.0, 0.05, 1e-5, "rectangular", "outer", 0),)
    P = 40
    t = jax.jit(jax.vmap(lambda mm: dyn.defect_times(mm, Z, sp, 0.0, 0.1, P, ("mid",))[0]))(m)
    t = np.asarray(t)
    with np.errstate(invalid="ignore"):
        d = np.diff(t, axis=1)
    d = d[np.isfinite(d)]
    T = 2 * np.pi / (Z * wc)
    assert abs(d.mean() / T - 1) < 1e-3
    assert abs(d.std() / T / sigma - 1) < 0.04


def test_speed_fluctuation_rms_and_spectrum():
    """omega(t) = omega_0 (1 + a s(t)), s unit RMS: the ensemble RMS of omega / omega_0 - 1 at
    fixed instants is a within 4 % (2000 runs: s.e. ~1.6 %), the same as the host draws of
    draw_motion within 6 %; the 8 frequencies are uniform in (0, B]: mean B / 2 within 2 %,
    none outside."""
    a, B = 0.001, 5.0
    realism = dyn.Realism(speed_fluctuation_percent=100 * a, speed_fluctuation_bandwidth_Hz=B)
    m, _ = draws(2000, realism)
    t = jnp.linspace(0.0, 0.1, 5)
    w = jax.vmap(lambda mm: dyn.motion_at(mm, Z, t)[2])(m)
    dev = np.asarray(w) / (2 * np.pi * 30.0) - 1.0
    rms = np.sqrt(np.mean(dev ** 2))
    assert abs(rms / a - 1) < 0.04
    f = np.asarray(m.fluct_freqs)
    assert f.min() > 0 and f.max() <= B
    assert abs(f.mean() / (B / 2) - 1) < 0.02
    host = np.array([oracle.motion_at(numpy_draw_motion(s, Z, 0.0, 2 * np.pi * 11.9, 2 * np.pi * 30.0, 0.1, 0.0, realism),
                                   np.asarray(t))[2] for s in range(600)]) / (2 * np.pi * 30.0) - 1.0
    assert abs(np.sqrt(np.mean(host ** 2)) / rms - 1) < 0.06


def _host_motion(seed=3):
    realism = dyn.Realism(slip_percent=0.9, speed_fluctuation_percent=0.1)
    return numpy_draw_motion(seed, Z, 0.0, 2 * np.pi * 11.9, 2 * np.pi * 29.95, 0.1, 0.0, realism)


@pytest.mark.parametrize("location", ["outer", "inner", "ball"])
def test_defect_times_equal_the_numpy_oracle(location):
    """The edge and pass times (the program's padded lists, and a single run's
    defect_edge_times / defect_pass_times) equal the NumPy oracle's crossings of the same motion
    to 1e-9 s (the same interpolation on the same grid; a step is 2e-5 s)."""
    m = _host_motion()
    md = oracle.to_motion(m)
    sp = Spall(0.7, 0.04, 1e-5, "rectangular", location, 0)
    k = 2.3 if location == "ball" else 0.0
    for offsets, dur, ref, one in ((("lo", "hi"), 0.1 + 1 / FS, oracle.defect_edge_times(m, sp, 0.1 + 1 / FS, k),
                                    dyn.defect_edge_times(md, Z, sp, 0.1 + 1 / FS, k)),
                                   (("mid",), 0.1, oracle.defect_pass_times(m, sp, 0.1, k),
                                    dyn.defect_pass_times(md, Z, sp, 0.1, k))):
        t, ok = dyn.defect_times(md, Z, (sp,), k, dur, 40, offsets)
        t = np.asarray(t)
        assert bool(ok)
        got = t[np.isfinite(t)]
        assert got.size == ref.size > 3
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9)
        np.testing.assert_allclose(one, ref, rtol=0, atol=1e-9)
    inactive = Spall(0.7, 0.04, 0.0, "rectangular", location, 0)
    t, _ = dyn.defect_times(md, Z, (inactive,), k, 0.1, 40, ("mid",))
    assert np.all(np.isinf(np.asarray(t)))


def test_pass_list_overflow_is_flagged():
    m = oracle.to_motion(_host_motion())
    sp = Spall(0.0, 0.04, 1e-5, "rectangular", "outer", 0)
    _, ok = dyn.defect_times(m, Z, (sp,), 0.0, 0.1, 5, ("mid",))
    assert not bool(ok)


def test_stages_and_jumps_equal_host():
    """The time loop's inputs built on the device equal the NumPy oracle's motion_at at the stage
    instants and an independent NumPy search of the first edge at or after each step's start
    (1e-12)."""
    m = _host_motion()
    md = oracle.to_motion(m)
    sub, T = 2, 700
    st = np.asarray(dyn.motion_stages(md, Z, 100, T, FS, "newmark", sub))
    t = (100 + np.arange(T)[:, None] + (np.arange(sub)[None, :] + 1.0) / sub) / FS     # Newmark: step ends
    ref = np.stack(oracle.motion_at(m, t), -1)
    np.testing.assert_allclose(st[:, :, 0, :], ref, rtol=1e-12, atol=1e-12)
    edges = oracle.defect_edge_times(m, Spall(0.0, 0.04, 1e-5, "rectangular", "outer", 0), 0.1)
    h = 1.0 / (sub * FS)
    pad = np.concatenate([edges, np.full(7, np.inf)])
    j = np.asarray(dyn.edge_fractions(jnp.asarray(pad), 100, T, sub, h))
    t0 = (100 + np.arange(T))[:, None] * sub * h + np.arange(sub)[None, :] * h
    want = np.full(t0.shape, -1.0)
    for idx in np.ndindex(t0.shape):
        later = edges[edges >= t0[idx]]
        if later.size and (later[0] - t0[idx]) / h < 1.0:
            want[idx] = (later[0] - t0[idx]) / h
    assert np.sum(want >= 0) > 0
    np.testing.assert_allclose(j, want, rtol=0, atol=1e-9)


def test_sensor_filter_equals_scipy():
    """The one sensor filter (JAX, balanced, jitted as inside the chunk program) against scipy's
    unbalanced matrix exponential (tests/oracles/sensor_numpy.py): the ill-scaled augmented
    system (w^2 ~ 4e8 beside 1) costs scipy's ~1e-14 of its norm, 1e-9 relative in the small
    entries (far below the time loop's own error, 1e-2)."""
    from oracles.sensor_numpy import sensor_filter as scipy_filter

    f, z, g, h = np.array([2977.6, 3356.0]), np.array([0.013, 0.019]), np.array([1.9, 8.8]), 1 / 96000
    a = scipy_filter(f, z, g, h)
    b = jax.jit(sensor.sensor_filter)(f, z, g, h)
    for x, y in zip(a, b):
        np.testing.assert_allclose(np.asarray(y), np.asarray(x), rtol=1e-8, atol=1e-16)
