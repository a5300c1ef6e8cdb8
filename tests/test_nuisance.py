"""bearingsim.nuisance (issue 26): each ingredient against a closed form or a limit it must meet,
and the interface the data engine relies on (pure JAX float64, vmappable, a function of the key)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bearingsim  # noqa: F401  (float64)
from bearingsim.signals import nuisance as nu

FS = 12000.0
T = 2400                      # 0.2 s


def _fixed(**kv):
    """Settings with every range of ``kv`` pinned to one value."""
    return {k: (v if isinstance(v, (int, float)) and k.endswith(("probability", "max")) else (v, v)) for k, v in kv.items()}


def test_load_zone_factor_is_stribeck():
    eps = 0.5
    psi_l = np.arccos(1 - 2 * eps)                      # the zone's edge: 90 deg at eps = 0.5
    assert float(nu.load_zone_factor(0.0, eps)) == pytest.approx(1.0, abs=1e-15)
    assert float(nu.load_zone_factor(psi_l, eps)) == pytest.approx(0.0, abs=1e-12)
    assert float(nu.load_zone_factor(np.pi, eps)) == 0.0
    psi = 0.7
    assert float(nu.load_zone_factor(psi, eps)) == pytest.approx((1 - (1 - np.cos(psi)) / (2 * eps)) ** 1.5, rel=1e-14)
    assert float(nu.load_zone_factor(psi, eps)) == float(nu.load_zone_factor(-psi, eps))


def test_band_noise_peaks_at_its_resonance():
    x = np.asarray(nu.band_noise(jax.random.PRNGKey(0), 48000, FS, 3000.0, 0.03))
    assert np.sqrt(np.mean(x * x)) == pytest.approx(1.0, rel=1e-12) and x.dtype == np.float64
    f = np.fft.rfftfreq(x.size, 1 / FS)
    P = np.abs(np.fft.rfft(x)) ** 2
    Ps = np.convolve(P, np.ones(200) / 200, "same")       # smoothed PSD
    assert abs(f[np.argmax(Ps)] - 3000.0) < 100.0         # the peak is the resonance (+- 3 %)


def test_shaft_modulation_depth_is_the_line_amplitude():
    # x = 1: the output is the envelope 1 + m1 cos(..) + m2 cos(2 ..); its Fourier amplitudes are m1, m2
    fr = 30.0                                              # 6 whole revolutions in 0.2 s
    s = _fixed(shaft_am_depth=0.3, misalignment_depth=0.1, shaft_harmonic_depth=0.0, looseness_probability=0.0)
    y, lab = nu.shaft_modulation(jax.random.PRNGKey(3), jnp.ones(T), FS, fr, s)
    A = 2 * np.abs(np.fft.rfft(np.asarray(y))) / T
    k = int(round(fr * T / FS))
    assert A[k] == pytest.approx(0.3, rel=1e-9) and A[2 * k] == pytest.approx(0.1, rel=1e-9)
    assert A[k // 2] < 1e-9 and float(lab["looseness"]) == 0.0          # no half orders when tight
    s["looseness_probability"] = 1.0
    s["looseness_depth"] = (0.2, 0.2)
    y, lab = nu.shaft_modulation(jax.random.PRNGKey(3), jnp.ones(T), FS, fr, s)
    A = 2 * np.abs(np.fft.rfft(np.asarray(y))) / T
    assert A[k // 2] == pytest.approx(0.2, rel=1e-9) and A[3 * k // 2] == pytest.approx(0.2, rel=1e-9)


def test_nuisance_lines_have_their_rms():
    # only the shaft lines: amplitude a (1, 0.7, 0.3) x rms, RMS of the sum = rms a sqrt(1 + 0.49 + 0.09)
    s = _fixed(shaft_line_relative=0.5, looseness_probability=0.0, rub_probability=0.0, near_line_probability=0.0,
               knock_rate_Hz=0.0)
    x, lab = nu.nuisance_signal(jax.random.PRNGKey(1), T, FS, 30.0, 12.0, 107.0, 162.0, 70.0, 2.0, s)
    assert np.sqrt(np.mean(np.asarray(x) ** 2)) == pytest.approx(2.0 * 0.5 * np.sqrt(1.58), rel=1e-9)
    assert float(lab["knock_rate_Hz"]) == 0.0 and float(lab["near_line_Hz"]) == 0.0


def test_a_near_line_is_near_its_bearing_order_and_not_on_it():
    s = _fixed(shaft_line_relative=0.0, looseness_probability=0.0, rub_probability=0.0, near_line_probability=1.0,
               knock_rate_Hz=0.0, near_line_offset_percent=1.0)
    for i in range(6):
        _, lab = nu.nuisance_signal(jax.random.PRNGKey(i), T, FS, 30.0, 12.0, 107.0, 162.0, 70.0, 1.0, s)
        f = float(lab["near_line_Hz"])
        assert min(abs(f / o - 1) for o in (107.0, 162.0, 140.0)) == pytest.approx(0.01, rel=1e-9)


def test_knocks_make_a_healthy_record_impulsive():
    s = _fixed(shaft_line_relative=0.0, looseness_probability=0.0, rub_probability=0.0, near_line_probability=0.0,
               knock_rate_Hz=20.0, knock_relative=10.0, knock_probability=1.0)
    x, _ = nu.nuisance_signal(jax.random.PRNGKey(2), T, FS, 30.0, 12.0, 107.0, 162.0, 70.0, 1.0, s)
    noise = np.random.default_rng(0).normal(size=T)
    y = noise + np.asarray(x)
    kurt = np.mean((y - y.mean()) ** 4) / np.var(y) ** 2
    assert kurt > 6.0                                       # Gaussian: 3


def test_fault_level_meets_its_snr():
    rng = np.random.default_rng(0)
    f, b = jnp.asarray(rng.normal(size=T) * 5 + 1), jnp.asarray(rng.normal(size=T) * 0.3)
    g, snr = nu.fault_level(jax.random.PRNGKey(0), f, b, {"fault_snr_dB": (-6.0, -6.0)})
    r = np.std(np.asarray(g * f)) / np.std(np.asarray(b))
    assert float(snr) == -6.0 and 20 * np.log10(r) == pytest.approx(-6.0, abs=1e-9)


def _impulses(bsf=70.0):
    t = np.arange(T) / FS
    ph = np.mod(2 * bsf * t, 1.0)
    x = np.where(ph < 2 * bsf / FS, 1.0, 0.0)               # one sample per 2 BSF crossing
    return jnp.asarray(np.convolve(x, np.exp(-np.arange(60) / 8.0) * np.sin(np.arange(60) * 1.7))[:T])


def test_ball_fault_keeps_rms_and_is_less_impulsive():
    x = _impulses()
    k0 = float(np.mean((x - x.mean()) ** 4) / np.var(x) ** 2)
    s = _fixed(ball_in_path=1.0, ball_noise_share=1.0, ball_roughness=1.0, ball_edge_ms=2.0, ball_unloaded=0.8,
               ball_load_eps=1.0, ball_ring_waviness=0.0)
    y, lab = nu.ball_fault_modulation(jax.random.PRNGKey(0), x, FS, 29.5, 11.8, 70.0, s)
    y = np.asarray(y)
    assert np.sqrt(np.mean(y ** 2)) == pytest.approx(np.sqrt(np.mean((np.asarray(x) - float(x.mean())) ** 2)), rel=1e-9)
    # rolling noise modulated by at most 1 : 0.8: near Gaussian (3); the impulse train: ~18
    assert np.mean(y ** 4) / np.var(y) ** 2 < 4.5 < k0
    assert float(lab["ball_noise_share"]) == 1.0


def test_ball_fault_noise_follows_the_load_zone():
    # no floor outside the zone, eps small: the contact noise's energy sits where the ball is loaded,
    # so its squared envelope carries the cage frequency (the pitted ball orbits with the cage)
    x = _impulses()
    s = _fixed(ball_in_path=1.0, ball_noise_share=1.0, ball_roughness=1.0, ball_unloaded=0.0, ball_load_eps=0.3,
               ball_load_exponent=1.0, ball_ring_waviness=0.0)
    ftf = 15.0                                             # 3 cage turns in 0.2 s
    y, _ = nu.ball_fault_modulation(jax.random.PRNGKey(4), x, FS, 29.5, ftf, 70.0, s)
    e = np.asarray(y) ** 2
    E = np.abs(np.fft.rfft(e - e.mean()))
    k = int(round(ftf * T / FS))
    assert E[k] > 5 * np.median(E[1:200])
    # a third of every cage turn (|psi| > 66 deg at eps = 0.3) carries no noise at all
    assert np.mean(e < 1e-20) > 0.5


def test_vmapped_is_itemwise_and_keyed():
    keys = jax.vmap(lambda i: nu.item_key(7, i))(jnp.arange(3))
    sh = jnp.array([29.0, 29.5, 30.0])
    f = jax.jit(jax.vmap(lambda k, s: nu.nuisance_signal(k, T, FS, s, 0.4 * s, 3.6 * s, 5.4 * s, 2.36 * s, 1.0)[0]))
    X = np.asarray(f(keys, sh))
    x1 = np.asarray(nu.nuisance_signal(keys[1], T, FS, sh[1], 0.4 * sh[1], 3.6 * sh[1], 5.4 * sh[1], 2.36 * sh[1], 1.0)[0])
    assert X.dtype == np.float64 and np.allclose(X[1], x1, rtol=1e-12, atol=1e-12)
    assert not np.allclose(X[0], X[1])
    b = jax.jit(jax.vmap(lambda k, x: nu.ball_fault_modulation(k, x, FS, 29.5, 11.8, 70.0)[0]))
    Y = np.asarray(b(keys, jnp.stack([_impulses()] * 3)))
    assert np.all(np.isfinite(Y)) and not np.allclose(Y[0], Y[1])
    m = jax.jit(jax.vmap(lambda k, x: nu.shaft_modulation(k, x, FS, 29.5)[0]))(keys, jnp.ones((3, T)))
    assert np.all(np.asarray(m) >= 0.0)


def test_unknown_settings_are_named():
    with pytest.raises(ValueError, match="ball_nonsense"):
        nu.settings_of({"ball_nonsense": (0, 1)})


def test_race_waviness_lines_have_their_depths():
    """The factor is 1 + d_j cos(2 pi f_j t + .) + d_j r_j cos(4 pi f_j t + .): on whole cycles its
    Fourier amplitude at f_j is the drawn depth d_j (the label), at 2 f_j at most d_j and at least
    the lowest ratio of ``waviness_second`` times it, its mean 1; with every order present."""
    f_r = 30.0          # frequencies on whole cycles of the 0.2 s record: 5 Hz bins
    ftf, bpfo, bpfi, bsf = 12.0, 105.0, 160.0, 70.0
    s = {"waviness_probability": 1.0, "waviness_depth": (0.02, 0.2), "waviness_second": (0.2, 1.0)}
    for seed in range(4):
        w, lab = nu.race_waviness(jax.random.PRNGKey(seed), T, FS, ftf, bpfo, bpfi, bsf, s)
        A = 2 * np.abs(np.fft.rfft(np.asarray(w))) / T
        assert np.asarray(w).mean() == pytest.approx(1.0, abs=1e-12)
        for f, name in ((bpfo, "bpfo"), (bpfi, "bpfi"), (2 * bsf, "2bsf")):
            d = float(lab[f"waviness_{name}_depth"])
            k = int(round(f * T / FS))
            assert 0.02 <= d <= 0.2
            assert A[k] == pytest.approx(d, rel=1e-9), name
            assert 0.2 * d * (1 - 1e-9) <= A[2 * k] <= d * (1 + 1e-9), name
        assert A[int(round(f_r * T / FS))] < 1e-12          # nothing at the shaft rate


def test_race_waviness_orders_are_present_at_their_probability():
    """Each of the three orders is present with ``waviness_probability`` (0.5, the default): over
    300 keys (fixed, so the count is too) the share of present orders lies within 4 sigma of 0.5,
    and the depths are log-uniform (median within 15 % of the geometric mean of the range)."""
    keys = jax.random.split(jax.random.PRNGKey(11), 300)
    f = jax.jit(jax.vmap(lambda k: nu.race_waviness(k, 256, FS, 12.0, 105.0, 160.0, 70.0)[1]))
    lab = f(keys)
    d = np.stack([np.asarray(lab[k]) for k in ("waviness_bpfo_depth", "waviness_bpfi_depth", "waviness_2bsf_depth")])
    on = d > 0
    p = on.mean()
    assert abs(p - 0.5) < 4 * np.sqrt(0.25 / on.size)
    lo, hi = nu.NUISANCE_DEFAULTS["waviness_depth"]
    assert np.all((d[on] >= lo) & (d[on] <= hi))
    assert np.median(d[on]) == pytest.approx(np.sqrt(lo * hi), rel=0.15)
