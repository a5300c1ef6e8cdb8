"""A ball pit's kinematic exposure (issue 33; bearingsim.dynamics.exposure, docs/physics.md §8.3):
the overlap against its closed forms and limits, the spin-axis geometry, the pass-by-pass draw
from the item's key, the signal stage's use of it, and the option off giving the bytes of before."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from bearingsim.app.workflows import solve_case
from bearingsim.case import load_case
from bearingsim.dynamics import Realism
from bearingsim.dynamics import exposure as ex
from bearingsim.dynamics.passes import vary_passes
from bearingsim.dynamics.sensor import run_filter, sensor_filter
from bearingsim.errors import InputError
from bearingsim.keys import STREAMS, stream_key
from bearingsim.signals import nuisance as nu
from bearingsim.signals.signal_stage import ItemDraws, SignalSettings, finish_items, item_keys

FS = 12000.0
R = 3.97e-3                                  # the 6205's ball radius (m)
A = 0.6e-3                                   # a track half-width (m): the CWRU items' a is 0.4-0.9 mm
TP = np.concatenate([0.003 + np.arange(17) / 170.0, np.full(7, np.inf)])    # 2 BSF = 170 Hz, +inf padded


def _track(alpha=0.0, beta=0.0, a=A, pit_r=0.2e-3):
    return jnp.array([beta, alpha, alpha, a, a, R, pit_r])


def test_ball_track_is_the_most_loaded_balls_raceway_control():
    case = load_case("dataset_cwru_4class")                   # outer raceway control, 100 N radial, 43.7 N axial
    sol = solve_case(case)
    b = case.bearing()
    t = np.asarray(ex.ball_track(b, sol, 0.1))
    j = int(np.argmax(np.asarray(sol.Q_outer)))
    want = [sol.beta[j], sol.alpha_outer[j], sol.alpha_inner[j], sol.a_outer[j], sol.a_inner[j]]
    assert np.array_equal(t[:5], np.asarray(want, float))
    ao = float(sol.alpha_outer[j])
    assert np.tan(t[0]) == pytest.approx(np.sin(ao) / (np.cos(ao) + float(b.g)), rel=1e-10)   # Harris: outer control
    R_b = 0.5 * float(b.ball_diameter)
    assert t[5] == R_b and t[6] == pytest.approx(0.5 * 0.1 * R_b, rel=1e-15)      # pit radius = extent / 2 x R
    assert 0.3e-3 < t[3] < 1.0e-3 and 0.0 < t[0] < t[1]       # the CWRU point: a 0.59 mm, beta below alpha


def test_overlap_is_a_fraction_with_its_closed_forms():
    rng = np.random.default_rng(0)
    d = rng.normal(0.0, 1e-3, 2000)
    w = rng.uniform(0.0, 1e-3, 2000)
    r = rng.uniform(1e-6, 1e-3, 2000)
    e = np.asarray(ex.strip_overlap(d, w, r))
    assert np.all((e >= 0.0) & (e <= 1.0))
    # inside (|d| + r <= w): 1; outside (|d| >= w + r): 0; centre on an edge of a wide strip: 1/2
    assert np.allclose(e[np.abs(d) + r <= w], 1.0, rtol=0, atol=1e-14) and np.all(e[np.abs(d) >= w + r] == 0.0)
    assert float(ex.strip_overlap(A, A, 0.2e-3)) == pytest.approx(0.5, abs=1e-14)
    # a strip narrower than the pit, centred: the disc's central band, 2 (w r sqrt(1-u^2) + r^2 asin u) / (pi r^2)
    u = 0.3
    band = 2 * (u * np.sqrt(1 - u * u) + np.arcsin(u)) / np.pi
    assert float(ex.strip_overlap(0.0, u * 1e-3, 1e-3)) == pytest.approx(band, rel=1e-13)


def test_contact_latitudes_follow_the_pitch_and_the_yaw_only_at_second_order():
    t = _track(alpha=np.radians(4.0), beta=np.radians(3.4))
    lo, li = ex.contact_latitudes(t, 0.0, 0.0)
    assert float(lo) == pytest.approx(np.radians(0.6), rel=1e-12) and float(li) == pytest.approx(-float(lo), rel=1e-12)
    lo_p, _ = ex.contact_latitudes(t, np.radians(2.0), 0.0)
    assert float(lo_p) == pytest.approx(np.radians(-1.4), rel=1e-12)          # the pitch moves the track
    lo_y, _ = ex.contact_latitudes(t, 0.0, np.radians(5.0))
    assert abs(float(lo_y) - float(lo)) < 1e-3 * np.radians(5.0)             # the yaw: cos(5 deg) - 1 of it


def test_pit_on_the_track_without_wander_is_exposed_every_pass_and_far_off_never():
    key = jax.random.PRNGKey(1)
    on = np.asarray(ex.pass_exposure(key, jnp.asarray(TP), 12.0, 0.3, _track(), 0.0, 0.0, 1.0))
    assert np.all(on[:17] == 1.0) and np.all(on[17:] == 0.0)
    off = np.asarray(ex.pass_exposure(key, jnp.asarray(TP), 12.0, 0.3, _track(), np.radians(20.0), 0.0, 1.0))
    assert np.all(off == 0.0)                                             # 1.4 mm off a 0.6 mm track, pit 0.2 mm


def test_zero_wander_reproduces_the_nominal_exposure():
    # alpha 8, beta 6 deg: the outer track 2 deg above the spin equator, the inner 2 deg below; the
    # pit 1.5 deg above: each contact's nominal overlap, alternating from the first pass's contact
    t = _track(alpha=np.radians(8.0), beta=np.radians(6.0), a=0.15e-3, pit_r=0.3e-3)
    lat = np.radians(1.5)
    lo, li = ex.contact_latitudes(t, 0.0, 0.0)
    eo, ei = (float(ex.strip_overlap(R * (lat - lc), 0.15e-3, 0.3e-3)) for lc in (lo, li))
    assert 0.0 < ei < eo < 1.0
    for spin0, first_outer in ((0.0, True), (0.5, False), (4.0, True)):
        e = np.asarray(ex.pass_exposure(jax.random.PRNGKey(5), jnp.asarray(TP), 12.0, spin0, t, lat, 0.0, 1.0))[:17]
        want = np.where((np.arange(17) % 2 == 0) == first_outer, eo, ei)
        assert np.allclose(e, want, rtol=1e-14, atol=0.0)


def test_wander_is_a_stationary_ou_process():
    u = jnp.asarray(np.arange(4000) * 0.1)
    x = np.stack([np.asarray(ex.wander(k, u, 0.05, 1.0)) for k in jax.random.split(jax.random.PRNGKey(2), 8)])
    assert np.std(x) == pytest.approx(0.05, rel=0.05)                     # 32 000 samples, ~400 independent per path
    r1 = np.mean(x[:, 1:] * x[:, :-1]) / np.mean(x * x)
    assert r1 == pytest.approx(np.exp(-0.1), abs=0.02)                    # lag 0.1 cage rev, correlation 1 rev


def test_pass_exposure_is_the_keys_and_differs_between_keys():
    t = _track(alpha=np.radians(4.0), beta=np.radians(3.4))
    k1, k2 = item_keys(0, np.arange(2))
    args = (jnp.asarray(TP), 12.0, 0.3, t, np.radians(5.0), np.radians(4.0), 1.0)
    a, b, c = (np.asarray(ex.pass_exposure(k, *args)) for k in (k1, k1, k2))
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert 0.0 < a[:17].min() < a[:17].max() <= 1.0                     # the wander moves the exposure pass to pass
    assert STREAMS["ball_exposure"] not in [v for n, v in STREAMS.items() if n != "ball_exposure"]


def test_ball_fault_model_gate_is_the_exposure():
    # the kinematic gate: the contact noise vanishes where the exposure does, and the bursts sit on the passes
    T = 1200
    t = np.arange(T) / FS
    e = np.where(t < 0.05, 1.0, 0.0)
    d = np.asarray(ex.pass_distance(jnp.asarray(t), jnp.asarray(TP)))
    s = {k: (v, v) for k, v in (("ball_noise_share", 1.0), ("ball_roughness", 0.0), ("ball_edge_ms", 0.5),
                                ("ball_ring_waviness", 0.0))}
    y, lab = nu.ball_fault_modulation(jax.random.PRNGKey(3), jnp.ones(T), FS, 30.0, 12.0, 85.0, s,
                                      (jnp.asarray(e), jnp.asarray(d)))
    y = np.asarray(y)
    assert np.all(y[t >= 0.05] == 0.0) and np.sqrt(np.mean(y[t < 0.05] ** 2)) > 0.0
    assert float(lab["ball_in_path"]) == pytest.approx(np.mean(e), rel=1e-14)
    far = d > 1.5e-3                                                      # 6 sigma of a 0.5 ms (2 sigma) burst
    assert np.max(np.abs(y[(t < 0.05) & far])) < 1e-6 * np.max(np.abs(y))


def _settings(**kw):
    return SignalSettings(FS, 1200, "none", pass_cv_max=0.0, pass_delay_max=0.0, modes=((3000.0,), (0.02,), (1.0,)),
                          **kw)


def _inputs(n):
    t = np.arange(1200) / FS
    tp = np.tile(TP, (n, 1))
    housing = np.tile(np.sum([np.exp(-((t - x) / 2e-4) ** 2) for x in TP[:17]], 0), (n, 1))
    draws = ItemDraws(np.tile([[3000.0, 0.02, 1.0]], (n, 1, 1)), np.ones(n), np.zeros(n), np.ones(n),
                      np.full(n, 30.0))
    return tp, housing, draws


def test_kinematic_exposure_scales_the_ball_pits_passes_in_the_signal_stage():
    n = 3
    tp, housing, draws = _inputs(n)
    keys = item_keys(0, np.array([4, 4, 5]))
    freqs = np.tile([12.0, 107.0, 162.0, 85.0], (n, 1))
    track = np.tile(np.asarray(_track(alpha=np.radians(4.0), beta=np.radians(3.4))), (n, 1))
    s = _settings(ball_exposure="kinematic",
                  exposure_ranges=(("pit_latitude", (0.09, 0.09)), ("wander_sd", (0.07, 0.07))))
    cls = np.array([3, 3, 3], np.int32)
    x, _ = finish_items(keys, housing, 0.0 * housing, tp, np.zeros(n), cls, np.full(n, 30.0), draws, s, freqs, track)
    x = np.asarray(x)
    assert np.array_equal(x[0], x[1]) and not np.array_equal(x[0], x[2])      # the item's key decides
    # the record is the engine's impacts scaled pass by pass by the key's exposure, filtered again
    kd, kw = jax.random.split(stream_key(keys[0], "ball_exposure"))
    lat, sd, corr = ex.draw_exposure(kd, s.exposure_ranges)
    assert float(lat) == pytest.approx(0.09) and float(sd) == pytest.approx(0.07)
    e = ex.pass_exposure(kw, jnp.asarray(TP), 12.0, np.radians(30.0), jnp.asarray(track[0]), lat, sd, corr)
    assert 0.0 < float(jnp.min(e[:17])) < float(jnp.max(e[:17]))
    v = vary_passes(housing[0], FS, jnp.asarray(TP), jnp.concatenate([jnp.ones(1), e]), jnp.zeros(TP.size + 1))
    want = np.asarray(run_filter(sensor_filter(jnp.array([3000.0]), jnp.array([0.02]), jnp.array([1.0]), 1 / FS), v))
    assert np.max(np.abs(x[0] - want)) < 1e-12 * np.max(np.abs(want))
    with pytest.raises(InputError, match="ball track"):
        finish_items(keys, housing, housing, tp, np.zeros(n), cls, np.full(n, 30.0), draws, s, freqs)


def test_the_option_and_its_ranges_from_the_case():
    case = load_case("dataset_cwru_4class")
    ds = dict(case.data["dataset"])
    assert ds["ball_exposure"] == "gate"
    off = SignalSettings.from_dataset(ds, FS, 1200, Realism(), ((3000.0,), (0.02,), (1.0,)))
    assert off.ball_exposure == "gate" and not off.passes().exposure
    ds.update(ball_exposure="kinematic", ball_pit_latitude_deg=[-5.0, 5.0], ball_axis_wander_deg=[2.0, 3.0])
    on = SignalSettings.from_dataset(ds, FS, 1200, Realism(), ((3000.0,), (0.02,), (1.0,)))
    r = dict(on.exposure_ranges)
    assert on.passes().exposure and r["pit_latitude"] == pytest.approx((-np.radians(5.0), np.radians(5.0)), rel=1e-15)
    assert r["wander_sd"] == pytest.approx((np.radians(2.0), np.radians(3.0)), rel=1e-15)
    assert r["wander_correlation"] == (0.5, 2.0)
    with pytest.raises(InputError, match="ball_exposure"):
        SignalSettings(FS, 1200, ball_exposure="random")
    with pytest.raises(InputError):
        case.with_value("dataset.ball_exposure", "random")


# The signal stage of four items (healthy, outer, inner, ball) with every issue-26 ingredient and
# the strikes on, as it was before the kinematic exposure existed (recorded 2026-11-27 from commit
# c6d478b; XLA's -O0 and default levels agree to 3e-16): ball_exposure "gate" must keep them.
_BEFORE_RMS = [0.9557595332318475, 1.4264521261604708, 3.460028549944358, 1.1750927418719872]
_BEFORE_600 = [-3.9326635178501849e-03, 1.9099958122381184e+00, 3.0237193583370466e+01, -1.8379343430227454e-01]


def test_option_off_keeps_the_items_of_before():
    # ~8-14 s cold (the signal stage compiled with every ingredient: the gate's own path); 2 s warm
    N, T = 4, 1200
    s = SignalSettings(FS, T, "random", pass_cv_max=0.02, pass_delay_max=0.05, fault_snr_dB=(0.0, 10.0),
                       strike_probability=(0.5, 1.0), modes=((3000.0,), (0.02,), (1.0,)),
                       ingredients=("ball_fault_model", "nuisance", "shaft_modulation"))    # issue 26's
    assert s.ball_exposure == "gate" and not s.passes().exposure
    t = np.arange(T) / FS
    tp = np.full((N, 24), np.inf)
    tp[:, :17] = 0.003 + np.arange(17) / 170.0
    housing = np.stack([np.sum([np.exp(-((t - x) / 2e-4) ** 2) for x in tp[i, :17]], 0) for i in range(N)])
    draws = ItemDraws(np.tile([[3000.0, 0.02, 1.0]], (N, 1, 1)), np.ones(N), np.array([0.0, 5.0, 5.0, 5.0]),
                      np.array([1.0, 1.0, 1.0, 0.6]), np.array([0.0, 0.0, 0.0, 100.0]))
    freqs = np.tile([12.0, 107.0, 162.0, 70.0], (N, 1))
    x, _ = finish_items(item_keys(7, np.arange(N)), housing, 0.5 * housing, tp, np.array([0.0, 0.5, 0.5, 0.5]),
                        np.arange(N, dtype=np.int32), np.full(N, 29.95), draws, s, freqs)
    x = np.asarray(x)
    # 1e-12: rounding of another XLA optimisation level or CPU; any change of a draw or a step is O(1)
    assert np.allclose(np.sqrt(np.mean(x * x, 1)), _BEFORE_RMS, rtol=1e-12, atol=0.0)
    assert np.allclose(x[:, 600], _BEFORE_600, rtol=1e-12, atol=1e-14)
