"""The signal stage on the device (bearingsim.signals.signal_stage): every draw against its stated
distribution, every synthesis against the NumPy reference fed the same random numbers, and the
whole stage's determinism (same key, same bytes; vmap = per item; chunk-independent)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from bearingsim.dynamics import passes as pv, sensor
from oracles import passes_numpy as passes
from bearingsim.signals import signal_stage as ss
from bearingsim.signals import background as bgm
from bearingsim.signals.background import BACKGROUND_DEFAULTS, Background
from oracles.background_numpy import background_signal, random_background
from bearingsim.dynamics import Realism

FS = 12000.0


def rel_err(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


# --- pass-to-pass variability ---------------------------------------------------------------

@pytest.mark.parametrize("npass,pad", [(9, 4), (1, 3), (0, 2), (12, 0), (0, 0)])
def test_vary_passes_equals_numpy_for_the_same_factors(npass, pad):
    rng = np.random.default_rng(npass)
    n = 2400
    x = rng.standard_normal(n) + 0.3
    tp = np.sort(rng.uniform(0.0, n / FS, npass))
    fac = rng.lognormal(0.0, 0.5, npass + 1)
    sh = rng.normal(0.0, 2e-4, npass + 1)
    if npass:
        sh[1] = 0.0                                        # an unshifted piece
    ref = passes.vary_passes(x, FS, tp, fac, sh)
    tpp = np.concatenate([tp, np.full(pad, np.inf)])
    facp = np.concatenate([fac, rng.uniform(0, 2, pad)])    # padded slots: anything, never used
    shp = np.concatenate([sh, rng.normal(0, 1e-3, pad)])
    got = jax.jit(pv.vary_passes, static_argnums=1)(x, FS, tpp, facp, shp)
    # same formulas, summation order differs: a few ulps of the record
    assert rel_err(got, ref) < 1e-12


def test_pass_draws_have_their_stated_statistics():
    key = jax.random.PRNGKey(3)
    n, cv = 200_000, 0.3
    f = np.asarray(pv.pass_factors(key, n, cv))
    se = 1.0 / np.sqrt(n)
    # log-normal exp(s xi - s^2): E f^2 = 1, c.v. = sqrt(exp(s^2) - 1) = cv
    assert np.mean(f * f) == pytest.approx(1.0, abs=8 * se * np.sqrt(np.var(f * f)))
    assert np.std(f) / np.mean(f) == pytest.approx(cv, rel=0.02)
    assert np.all(np.asarray(pv.pass_factors(key, 10, 0.0)) == 1.0)
    p = 0.37
    m = np.asarray(pv.strike_factors(key, n, p))
    assert set(np.unique(m)) == {0.0, 1.0}
    assert m.mean() == pytest.approx(p, abs=5 * np.sqrt(p * (1 - p) / n))        # binomial, 5 sigma
    tp = np.concatenate([0.01 + 0.0093 * np.arange(10), np.full(5, np.inf)])
    sh = np.asarray(jax.jit(jax.vmap(lambda k: pv.pass_shifts(k, jnp.asarray(tp), 0.05)))(jax.random.split(key, 4000)))
    assert np.std(sh) == pytest.approx(0.05 * 0.0093, rel=0.03)               # 64000 normals: 0.3 % s.e.
    assert np.all(np.asarray(pv.pass_shifts(key, jnp.asarray([0.01, np.inf]), 0.05)) == 0.0)   # one pass


# --- background -----------------------------------------------------------------------------

def replay_draws(rng, bg, n, fs, knock_max):
    """The random numbers numpy's background_signal consumes, in its order, as BackgroundDraws."""
    sp = rng.uniform(0, 2 * np.pi, len(bg.shaft_amplitudes))
    lp = rng.uniform(0, 2 * np.pi, len(bg.line_amplitudes))
    noise = rng.standard_normal(n)
    mp = rng.uniform(0, 2 * np.pi, len(bg.modulation_depths))
    lmp = rng.uniform(0, 2 * np.pi, len(bg.line_modulation_depths)) if len(bg.line_modulation_depths) else np.zeros(0)
    m = rng.poisson(bg.knock_rate * n / fs)
    times = rng.uniform(0.0, n / fs, m)
    signs = rng.choice([-1.0, 1.0], m)
    assert m <= knock_max
    pad = knock_max - m
    return bgm.BackgroundDraws(sp, lp, noise, mp, lmp, np.concatenate([times, np.zeros(pad)]),
                              np.concatenate([signs, np.zeros(pad)]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_background_synthesis_equals_numpy_for_the_same_draws(seed):
    n = 4800
    rng = np.random.default_rng(seed)
    bg = random_background(rng, FS)._replace(knock_rate=60.0)   # several knocks in 0.4 s
    state = rng.bit_generator.state
    ref = background_signal(rng, n, FS, 29.7, bg)
    rng.bit_generator.state = state
    draws = replay_draws(rng, bg, n, FS, 60)
    assert np.count_nonzero(draws.knock_signs) > 3
    got = jax.jit(bgm.synthesize_background, static_argnums=2)(
        Background(*(jnp.asarray(v, jnp.float64) for v in bg)), draws, FS, 29.7)
    assert rel_err(got, ref) < 1e-10


def test_white_machine_background_equals_numpy_and_labels():
    n = 3000
    bg = Background((0.2, 0.05), 50.0, (0.03,), 0.4, (), (), (0.2, 0.1), 5.0, 1.5, 2500.0, 0.03, (0.1,))
    rng = np.random.default_rng(7)
    ref = background_signal(rng, n, FS, 25.0, bg)
    draws = replay_draws(np.random.default_rng(7), bg, n, FS, 20)
    # one compiled program, not one per operation (eager: ~160 programs, ~10 s of the suite)
    synth = jax.jit(lambda b, d: bgm.synthesize_background(b, d, FS, 25.0))
    got = synth(Background(*(jnp.asarray(v, jnp.float64) for v in bg)), draws)
    assert rel_err(got, ref) < 1e-10
    lab = {k: float(v) for k, v in bgm.background_labels(bg).items()}
    assert lab == pytest.approx(bg.as_labels(), rel=1e-14)


@pytest.fixture(scope="module")
def drawn():
    keys = jax.random.split(jax.random.PRNGKey(11), 4000)
    return jax.jit(jax.vmap(lambda k: bgm.draw_background(k, FS)))(keys)


def test_drawn_backgrounds_are_in_their_ranges(drawn):
    r, top = BACKGROUND_DEFAULTS, 0.45 * FS
    b = {k: np.asarray(v) for k, v in drawn._asdict().items()}
    n = b["noise_rms"].size
    rms = b["noise_rms"]
    assert rms.min() >= r["noise_rms_m_s2"][0] and rms.max() <= r["noise_rms_m_s2"][1]
    # log-uniform: log rms uniform on [log lo, log hi]: mean at the midpoint (s.e. (b-a)/sqrt(12 n))
    lo, hi = np.log(r["noise_rms_m_s2"])
    assert np.mean(np.log(rms)) == pytest.approx(0.5 * (lo + hi), abs=5 * (hi - lo) / np.sqrt(12 * n))
    rel = b["shaft_amplitudes"] / rms[:, None]
    assert b["shaft_amplitudes"].shape == (n, 6) and rel.min() >= 0.01 * (1 - 1e-12) and rel.max() <= 1.0 + 1e-12
    rel = b["line_amplitudes"] / rms[:, None]
    assert b["line_amplitudes"].shape == (n, 4) and rel.min() >= 0.003 * (1 - 1e-12) and rel.max() <= 0.3 + 1e-12
    assert set(np.unique(b["line_frequency"])) == {50.0, 60.0}
    assert np.mean(b["line_frequency"] == 50.0) == pytest.approx(0.5, abs=5 * 0.5 / np.sqrt(n))
    md = b["modulation_depths"]
    assert md.shape == (n, 8) and md.min() >= 0.0 and md.max() <= 0.4
    strong = np.mean(md > 0.03)           # strong (p = 0.4) and above 0.03: 0.4 x 0.37 / 0.4 = 0.925 of them
    p = 0.4 * (0.4 - 0.03) / 0.4
    assert strong == pytest.approx(p, abs=5 * np.sqrt(p * (1 - p) / md.size))
    assert b["line_modulation_depths"].shape == (n, 2)
    assert b["knock_rate"].min() >= 0.0 and b["knock_rate"].max() <= 20.0
    ka = b["knock_amplitude"] / rms
    assert ka.min() >= 0.5 * (1 - 1e-12) and ka.max() <= 8.0 * (1 + 1e-12)
    assert b["knock_frequency"].min() >= 1000.0 and b["knock_frequency"].max() <= min(5500.0, top) * (1 + 1e-12)
    assert b["knock_damping"].min() >= 0.01 and b["knock_damping"].max() <= 0.08
    # PSD: the tilt and 1-4 bumps of <= 25 dB over a tilt within -6..3 dB/octave
    g = bgm.psd_grid(FS)
    lv = b["psd_levels_db"] - b["psd_levels_db"][:, :1]
    octaves = np.log2(g / g[0])
    assert np.all(lv <= 3.0 * octaves + 10 * np.log10(1 + 4 * 10 ** 2.5) + 1e-9)
    assert np.all(lv >= -6.0 * octaves - 10 * np.log10(1 + 4 * 10 ** 2.5) - 1e-9)
    lab = jax.vmap(bgm.background_labels)(drawn)
    shaft_rms = np.sqrt(0.5 * np.sum(b["shaft_amplitudes"] ** 2, 1))
    assert np.allclose(lab["background_shaft_rms_m_s2"], shaft_rms, rtol=1e-14)


def test_drawn_background_lines_sit_at_their_drawn_frequencies_and_amplitudes():
    n = int(FS)                          # 1 s: 1 Hz bins, every line on a bin
    key = jax.random.PRNGKey(5)
    bg = jax.jit(lambda k: bgm.draw_background(k, FS))(key)._replace(noise_rms=0.0, knock_amplitude=0.0)
    x = np.asarray(jax.jit(lambda k, b: bgm.background_record(k, b, n, FS, 31.0, 4))(jax.random.PRNGKey(6), bg))
    A = np.abs(np.fft.rfft(x)) * 2 / n
    lines = {31 * k: a for k, a in enumerate(np.asarray(bg.shaft_amplitudes), 1)}
    lf = int(bg.line_frequency)
    lines.update({lf * k: a for k, a in enumerate(np.asarray(bg.line_amplitudes), 1)})
    for f, a in lines.items():
        assert A[f] == pytest.approx(a, rel=1e-9), f
    rest = np.delete(A, list(lines))
    assert rest.max() < 1e-9 * max(lines.values())


def test_modulation_depth_shows_in_the_squared_record():
    """White noise times 1 + m cos(2 pi f_r t + p): its square regresses on cos/sin at f_r with
    amplitude 2 m sigma^2 against a mean of sigma^2 (1 + m^2 / 2)."""
    n, fr, m = int(FS), 30.0, 0.3
    bg = Background((), 60.0, (), 1.0, (), (), (m,), 0.0, 0.0, 3000.0, 0.05, ())
    t = np.arange(n) / FS
    ratios = []
    records = jax.jit(jax.vmap(lambda k: bgm.background_record(k, bg, n, FS, fr, 1)))
    for r in np.asarray(records(jax.random.split(jax.random.PRNGKey(0), 16))):
        y = r ** 2
        c, s = 2 * np.mean(y * np.cos(2 * np.pi * fr * t)), 2 * np.mean(y * np.sin(2 * np.pi * fr * t))
        ratios.append(np.hypot(c, s) / np.mean(y))
    # per record the s.e. of c, s is ~ 2 sqrt(2 / n) = 0.026; over 16 records 0.0065
    assert np.mean(ratios) == pytest.approx(2 * m / (1 + m * m / 2), abs=0.03)


def test_knock_counts_are_poisson():
    bg = Background((), 60.0, (), 0.0, (), (), (), 20.0, 1.0, 3000.0, 0.05, ())
    n, kmax = 4800, 30                   # P(Poisson(8) > 30) < 1e-9: no count truncated
    # one program that keeps the knocks only: the draws' (T,) noise of 20 000 records (96 M normals,
    # ~10 s of eager work at -O0, which the next test waited for) is never computed
    knocks = jax.jit(jax.vmap(lambda k: (lambda b: (b.knock_signs, b.knock_times))(
        bgm.background_draws(k, bg, n, FS, kmax))))
    signs, times = knocks(jax.random.split(jax.random.PRNGKey(2), 20000))
    d = bgm.BackgroundDraws(None, None, None, None, None, times, signs)
    counts = np.count_nonzero(np.asarray(d.knock_signs), axis=1)
    lam = 20.0 * n / FS                  # 8 per record
    assert counts.mean() == pytest.approx(lam, abs=5 * np.sqrt(lam / counts.size))
    assert counts.var() == pytest.approx(lam, rel=0.05)
    used = np.asarray(d.knock_signs) != 0
    assert np.all(np.abs(np.asarray(d.knock_signs))[used] == 1.0)
    times = np.asarray(d.knock_times)[used]
    assert times.min() >= 0.0 and times.max() < n / FS


# --- sensor path, noise, fault level -------------------------------------------------------

def test_modes_discretised_in_jax_equal_scipy_and_filter_equals_apply_sensor():
    """The one (balanced, JAX) discretisation equals scipy's (the oracle) to 1e-12 at the sample
    interval, and the jitted filter equals apply_sensor bit for bit in effect (1e-12)."""
    from oracles.sensor_numpy import sensor_filter as scipy_filter

    f, z, g = np.array([1500.0, 3356.0, 5400.0]), np.array([0.01, 0.05, 0.08]), np.array([0.3, 2.0, 9.0])
    h = 1.0 / 48000.0
    a, b = sensor.sensor_filter(f, z, g, h), scipy_filter(f, z, g, h)
    for x, y in zip(a, b):
        assert rel_err(x, y) < 1e-12
    u = np.random.default_rng(0).standard_normal(3000)
    got = jax.jit(sensor.run_filter)(a, u)
    assert rel_err(got, sensor.apply_sensor(u, h, f, z, g)) < 1e-12


def test_measurement_noise_has_its_rms_and_band():
    key = jax.random.PRNGKey(4)
    x = np.asarray(sensor.measurement_noise(key, 4800, 0.7, 48000.0, (500.0, 5000.0)))
    assert np.sqrt(np.mean(x * x)) == pytest.approx(0.7, rel=1e-12)
    X = np.abs(np.fft.rfft(x))
    f = np.fft.rfftfreq(4800, 1 / 48000.0)
    out = (f < 500.0) | (f > 5000.0)
    assert X[out].max() < 1e-12 * X[~out].max()
    w = np.asarray(sensor.measurement_noise(key, 4800, 0.7))
    assert np.sqrt(np.mean(w * w)) == pytest.approx(0.7, rel=1e-12) and abs(np.mean(w)) < 5 * 0.7 / np.sqrt(4800)
    assert np.array_equal(w, np.asarray(sensor.measurement_noise(key, 4800, 0.7)))


@pytest.mark.parametrize("snr", [-7.5, 0.0, 12.3, 25.0])
def test_fault_level_gives_the_requested_snr(snr):
    rng = np.random.default_rng(int(snr * 10) + 100)
    a = 3.0 + rng.standard_normal(2000) * np.exp(rng.uniform(-5, 5))
    x = rng.standard_normal(2000) * 0.4
    out, gain, lab = ss.fault_level(jnp.asarray(a), jnp.asarray(x), 1.0, snr, True)
    fault = np.asarray(out) - x
    got = 20 * np.log10(np.std(fault) / np.sqrt(np.mean(x * x)))
    assert got == pytest.approx(snr, abs=1e-9) and float(lab) == pytest.approx(snr, abs=1e-9)
    assert np.allclose(fault, float(gain) * a, rtol=1e-15)
    out, gain, _ = ss.fault_level(jnp.asarray(a), jnp.asarray(x), 2.5, snr, False)    # healthy: the drawn gain
    assert float(gain) == 2.5 and np.allclose(np.asarray(out), 2.5 * a + x, rtol=1e-15)
    out, gain, lab = ss.fault_level(jnp.zeros(2000), jnp.asarray(x), 1.0, snr, True)  # flat: no gain, label 0
    assert float(gain) == 1.0 and float(lab) == 0.0


# --- the per-item draws and the whole stage ---------------------------------------------------

DS = dict(background="random", background_rms_m_s2=(0.2, 2.0), fault_snr_dB=(0, 25),
          ball_strike_probability=(0.1, 1.0), outer_center_positions_deg=[0, 0, 90, -90, 180],
          resonance_frequency_Hz=(1500, 5500), resonance_damping_ratio=(0.01, 0.08), resonance_gain=(0.3, 10))
MODES = ([2977.6, 3356.0], [0.01329, 0.01937], [1.883, 8.852])


def settings(T=2400, fs=FS, **kw):
    realism = Realism(0.9, 0.1, 5.0, 0.0, None, 2.334, 9.089)
    return ss.SignalSettings.from_dataset(dict(DS, **kw), fs, T, realism, MODES)


def test_item_draws_follow_the_dataset_ranges():
    n = 8000
    cls = np.arange(n) % 4
    d = ss.draw_items(ss.item_keys(0, np.arange(n)), jnp.asarray(cls), settings())
    f, z, g = (np.asarray(d.modes[..., j]) for j in range(3))
    assert np.all(np.diff(f, axis=1) >= 0) and f.min() >= 1500 and f.max() <= 5500
    assert z.min() >= 0.01 and z.max() <= 0.08 and g.min() >= 0.3 and g.max() <= 10
    lo, hi = np.log(1500), np.log(5500)       # log-uniform
    assert np.mean(np.log(f)) == pytest.approx(0.5 * (lo + hi), abs=5 * (hi - lo) / np.sqrt(12 * f.size))
    snr, p = np.asarray(d.snr_dB), np.asarray(d.strike_probability)
    assert np.all(snr[cls == 0] == 0) and snr[cls > 0].min() >= 0 and snr[cls > 0].max() <= 25
    assert np.all(p[cls != 3] == 1.0) and p[cls == 3].min() >= 0.1 and p[cls == 3].max() <= 1.0
    assert np.all(np.asarray(d.signal_gain) == 1.0)
    pos = np.asarray(d.outer_center_deg)
    assert set(np.unique(pos)) == {0.0, 90.0, -90.0, 180.0}
    assert np.mean(pos == 0.0) == pytest.approx(0.4, abs=5 * np.sqrt(0.24 / n))
    nominal = ss.draw_items(ss.item_keys(0, np.arange(3)), jnp.zeros(3, int),
                            settings(resonance_frequency_Hz=None, resonance_damping_ratio=None, resonance_gain=None))
    assert np.array_equal(np.asarray(nominal.modes[1]), np.stack(MODES, -1))


def chunk_inputs(n, T=2400, fs=FS, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(T) / fs
    h = np.stack([np.sin(2 * np.pi * 3000 * t) * np.exp(-((t * rng.uniform(90, 160)) % 1) * 30) for _ in range(n)])
    tp = np.full((n, 24), np.inf)
    for i in range(n):
        k = rng.integers(0, 20)
        tp[i, :k] = 0.004 + np.arange(k) / 107.0
    return dict(housing=h, sensor=1.1 * h, pass_times=tp, unbridged=rng.uniform(0, 1, n) * (rng.random(n) < 0.7),
                fault_class=np.arange(n) % 4, shaft_hz=rng.uniform(28.5, 30.0, n))


def run(st, idx, inp, keys=None):
    keys = ss.item_keys(0, idx) if keys is None else keys
    fc = jnp.asarray(inp["fault_class"][idx])
    d = ss.draw_items(keys, fc, st)
    return ss.finish_items(keys, *(jnp.asarray(inp[k][idx]) for k in ("housing", "sensor", "pass_times", "unbridged")),
                           fc, jnp.asarray(inp["shaft_hz"][idx]), d, st)


def test_finish_items_is_reproducible_chunk_independent_and_vmap_equals_per_item():
    st = settings()
    inp = chunk_inputs(6)
    idx = np.arange(6)
    out, lab = run(st, idx, inp)
    again, lab2 = run(st, idx, inp)
    assert np.asarray(out).tobytes() == np.asarray(again).tobytes()
    assert all(np.array_equal(lab[k], lab2[k]) for k in lab)
    # another batch width, same items: the same records to rounding (a program compiled for
    # another width may order its float operations differently: bitwise equal at XLA's default
    # optimisation, not at -O0; the data engine runs fixed-width micro-batches, so its files are
    # identical bytes for any chunk size: tests/test_dataset_engine.py)
    part, lp = run(st, idx[2:5], inp)
    assert rel_err(np.asarray(part), np.asarray(out[2:5])) < 1e-12
    assert all(np.allclose(lp[k], lab[k][2:5], rtol=1e-12, atol=1e-12) for k in lab)
    other, _ = run(st, idx, inp, keys=ss.item_keys(1, idx))
    assert np.all(np.any(np.asarray(other) != np.asarray(out), axis=1))
    keys = ss.item_keys(0, idx)
    d = ss.draw_items(keys, jnp.asarray(inp["fault_class"]), st)
    one = jax.jit(ss.finish_item, static_argnums=8)
    for i in (0, 3, 5):
        y, li = one(keys[i], *(jnp.asarray(inp[k][i]) for k in ("housing", "sensor", "pass_times", "unbridged",
                                                                  "fault_class", "shaft_hz")),
                    jax.tree_util.tree_map(lambda a: a[i], d), st)
        assert rel_err(y, out[i]) < 1e-12
        assert all(float(li[k]) == pytest.approx(float(lab[k][i]), rel=1e-12, abs=1e-12) for k in ss.LABELS)
    assert np.all(np.asarray(lab["finite"]))
    snr = np.asarray(lab["snr_dB"])
    assert np.allclose(snr[inp["fault_class"] > 0], np.asarray(d.snr_dB)[inp["fault_class"] > 0], atol=1e-9)


def test_finish_items_varies_passes_like_numpy_then_runs_the_item_modes():
    """No background, no noise: the record is the item's modes applied to numpy's vary_passes of
    its housing acceleration with the factors and delays its key gives (public functions)."""
    st = settings(background="none", signal_gain=(2.0, 2.0))
    inp = chunk_inputs(4, seed=3)
    inp["unbridged"] = np.array([0.0, 0.8, 0.5, 0.0])
    inp["pass_times"][:, :12] = 0.004 + np.arange(12) / 120.0
    idx = np.arange(4)
    out, lab = run(st, idx, inp)
    keys = ss.item_keys(0, idx)
    d = ss.draw_items(keys, jnp.asarray(inp["fault_class"]), st)
    for i in range(4):
        u, p = inp["unbridged"][i], float(d.strike_probability[i])
        tp = inp["pass_times"][i]
        P = tp.size
        kp = jax.random.split(ss.stream_key(keys[i], "passes"))
        fac = np.array(pv.pass_factors(kp[0], P + 1, st.pass_cv_max * u))
        sh = np.asarray(pv.pass_shifts(kp[1], jnp.asarray(tp), st.pass_delay_max * u))
        fac[1:] *= np.asarray(pv.strike_factors(ss.stream_key(keys[i], "strike"), P, p))
        fin = np.isfinite(tp)
        k = int(fin.sum())
        if u > 0 or p < 1:
            varied = passes.vary_passes(inp["housing"][i], FS, tp[fin], fac[:k + 1], sh[:k + 1])
            m = np.asarray(d.modes[i])
            ref = 2.0 * np.asarray(sensor.apply_sensor(varied, 1 / FS, m[:, 0], m[:, 1], m[:, 2]))
        else:
            ref = 2.0 * inp["sensor"][i]
        assert rel_err(out[i], ref) < 1e-10, i
        assert float(lab["pass_amplitude_cv_percent"][i]) == pytest.approx(2.334 * u, rel=1e-12)
    assert np.all(np.asarray(lab["snr_dB"]) == 0) and np.all(np.asarray(lab["background_noise_rms_m_s2"]) == 0)


def test_struck_says_whether_the_defect_struck_inside_the_record():
    """``struck`` (the caller's test for a fault item that makes no impact): False for a record
    with no pass inside it and for a ball pit whose strike probability (1e-3) missed every one
    of its 12 passes (none strikes with probability 0.988 per item; the keys are fixed); True
    for the other classes, which strike on every pass."""
    st = settings(background="none", ball_strike_probability=(0.001, 0.001))
    inp = chunk_inputs(8, seed=3)
    inp["pass_times"][:] = np.inf
    inp["pass_times"][:, :12] = 0.004 + np.arange(12) / 120.0
    inp["pass_times"][[0, 1], :12] += 1.0              # items 0 and 1: every pass after the record's 0.2 s
    out, lab = run(st, np.arange(8), inp)
    want = (inp["fault_class"] != 3) & (np.arange(8) > 1)
    assert np.array_equal(np.asarray(lab["struck"]), want)


def test_machine_background_settings():
    bg = Background((0.2, 0.05), 50.0, (0.03,), 0.4, (100.0, 1000.0, 4000.0), (0.0, 10.0, -5.0), (0.2,), 3.0, 1.5,
                    2500.0, 0.03, ())
    st = ss.SignalSettings.from_dataset(dict(DS, background="machine"), FS, 2400,
                                        Realism(0.9, 0.1, 5.0, 0.0, None, 0.0, 0.0), MODES, machine=bg)
    assert hash(st) == hash(ss.SignalSettings.from_dataset(dict(DS, background="machine"), FS, 2400,
                                                           Realism(0.9, 0.1, 5.0, 0.0, None, 0.0, 0.0), MODES,
                                                           machine=bg))
    inp = chunk_inputs(3)
    out, lab = run(st, np.arange(3), inp)
    for k, v in bg.as_labels().items():
        assert np.allclose(np.asarray(lab[k]), v, rtol=1e-14)
    with pytest.raises(ValueError, match="background"):
        ss.SignalSettings(FS, 100, background="wrong")
