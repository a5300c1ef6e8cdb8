"""Envelope analysis (bearingsim.signals.envelope) against signals whose answer is known by construction.

Truths used here do not come from the code under test:
* a synthetic outer-race fault: impacts at exactly f_d = 107.36 Hz (±1 % seeded jitter
  of the inter-arrival times, renormalised to zero mean) each ringing a 3 kHz mode
  (damping ratio 0.05), buried in white noise (SNR -15.5 dB, rms ratio);
* an AM carrier A (1 + m cos 2π f_m t) cos 2π f_c t, whose squared envelope is
  A²(1 + m²/2) + 2 m A² cos 2π f_m t + (m² A²/2) cos 4π f_m t, so after the mean is removed the
  envelope spectrum has a line of height 2 m A² at f_m and m² A²/2 at 2 f_m;
* a pure tone placed between bins.
Tolerances: defect lines 0.5 % of k*f_d; AM line amplitudes 1 %; tone frequency 1 % of a bin.
"""
import numpy as np
import pytest

from bearingsim.signals import envelope as bsig
from bearingsim.signals import lines as blines

FS = 48_000.0
FD = 107.36          # impact rate (Hz) = "BPFO" of the synthetic fault
FN = 3_000.0         # resonance excited by the impacts (Hz)
ZETA = 0.05
NOISE_RMS = 1.0      # impulse-response peak amplitude is 1 m/s²; fault rms ~0.168 m/s²
INTERF = 10.0        # 50 Hz and 29.95 Hz interference amplitude: 10x the fault amplitude


def fault_signal(seed=0, noise_rms=NOISE_RMS, duration=1.0):
    """(t, clean fault, fault + noise, impact times); exact impact times, vectorised superposition."""
    rng = np.random.default_rng(seed)
    T = 1.0 / FD
    n = int(np.ceil(duration * FD)) + 1
    eps = rng.uniform(-0.01, 0.01, n - 1)
    eps -= eps.mean()                                  # mean inter-arrival time exactly 1/f_d
    t_imp = rng.uniform(0.0, T) + np.concatenate([[0.0], np.cumsum(T * (1.0 + eps))])
    t_imp = t_imp[t_imp < duration]
    t = np.arange(int(round(duration * FS))) / FS
    wn = 2 * np.pi * FN
    wd = wn * np.sqrt(1 - ZETA**2)
    tau = t[None, :] - t_imp[:, None]
    tp = np.clip(tau, 0.0, None)
    clean = np.where(tau >= 0.0, np.exp(-ZETA * wn * tp) * np.sin(wd * tp), 0.0).sum(axis=0)
    return t, clean, clean + noise_rms * rng.standard_normal(t.size), t_imp


def interference(t):
    return INTERF * np.sin(2 * np.pi * 50.0 * t + 0.3) + INTERF * np.sin(2 * np.pi * 29.95 * t + 1.1)


def largest_line(spec, f_lo=5.0, f_hi=600.0):
    m = (spec.freqs >= f_lo) & (spec.freqs <= f_hi)
    i = np.argmax(spec.amplitude[m])
    return spec.freqs[m][i], spec.amplitude[m][i]


@pytest.fixture(scope="module")
def fault():
    return fault_signal()


@pytest.fixture(scope="module")
def band():
    return bsig.select_band(np.zeros(16), FS, resonance_hz=FN)


# --------------------------------------------------------------------------- synthetic fault
def test_raw_spectrum_shows_nothing_at_fault_frequency(fault):
    t, clean, x, _ = fault
    raw = bsig.amplitude_spectrum(x, FS)
    near = np.abs(raw.freqs - FD) <= 2 * raw.df
    ref = (raw.freqs >= 50.0) & (raw.freqs <= 200.0)
    ratio = raw.amplitude[near].max() / np.median(raw.amplitude[ref])
    assert ratio < 3.0, ratio                          # measured 1.74: at the noise floor
    assert 20 * np.log10(clean.std() / NOISE_RMS) < -15.0


def test_envelope_spectrum_finds_bpfo_and_harmonics(fault, band):
    _, _, x, _ = fault
    assert band == (2625.0, 3375.0)
    es = bsig.envelope_spectrum(x, FS, band=band)
    assert isinstance(es, bsig.EnvelopeSpectrum) and es.band == band and es.fs == FS
    f1 = bsig.peak_frequency(es, FD)
    assert abs(f1 / FD - 1) < 0.005, f1               # measured +0.078 %
    f_big, _ = largest_line(es)
    assert abs(f_big / FD - 1) < 0.005, f_big         # BPFO is the largest line 5-600 Hz
    peaks = bsig.harmonic_peaks(es, FD, n=4)
    assert [k for k, _, _ in peaks] == [1, 2, 3, 4]
    for k, fk, ak in peaks[1:]:
        assert abs(fk / (k * FD) - 1) < 0.005, (k, fk)  # measured <= 0.15 %
        assert ak > 0


def test_bandpass_is_what_rescues_the_fault_from_low_frequency_interference(fault, band):
    t, _, x, _ = fault
    xi = x + interference(t)
    raw_env = bsig.envelope_spectrum(xi, FS)
    f_big, a_big = largest_line(raw_env)
    assert abs(f_big / FD - 1) > 0.005                # dominated by the 50-29.95 Hz beat
    assert abs(f_big - 20.05) < 0.5
    a_fd = raw_env.amplitude[np.argmin(np.abs(raw_env.freqs - FD))]
    assert a_fd < 0.01 * a_big                        # measured 1/525
    es = bsig.envelope_spectrum(xi, FS, band=band)
    f_big, _ = largest_line(es)
    assert abs(f_big / FD - 1) < 0.005, f_big
    assert abs(bsig.peak_frequency(es, FD) / FD - 1) < 0.005


def test_kurtosis_band_selection_finds_the_resonance():
    # the heuristic needs a little more SNR than the known-resonance band (-12 dB here)
    t, _, x, _ = fault_signal(seed=3, noise_rms=0.5)
    xi = x + interference(t)
    band, centres, kurt = bsig.select_band(xi, FS, return_kurtosis=True)
    assert band[0] < FN < band[1], band
    assert np.allclose(centres[1:] / centres[:-1], 2 ** (1 / 3))
    assert bsig.select_band(xi, FS) == band
    es = bsig.envelope_spectrum(xi, FS, band=band)
    assert abs(bsig.peak_frequency(es, FD) / FD - 1) < 0.005


# --------------------------------------------------------------------------- AM carrier
@pytest.mark.parametrize("f_m", [37.0, 37.3])        # on a bin / between bins
@pytest.mark.parametrize("use_band", [False, True])
def test_am_carrier_squared_envelope_line_matches_2mA2(f_m, use_band):
    fs, fc, m, A = 10_000.0, 1_000.0, 0.5, 2.0
    t = np.arange(10_000) / fs
    x = A * (1 + m * np.cos(2 * np.pi * f_m * t)) * np.cos(2 * np.pi * fc * t)
    es = bsig.envelope_spectrum(x, fs, band=(700.0, 1300.0) if use_band else None)
    (_, f1, a1), (_, f2, a2) = bsig.harmonic_peaks(es, f_m, n=2)
    assert abs(a1 / (2 * m * A**2) - 1) < 0.01, a1    # 4.0; measured error <= 0.12 %
    assert abs(a2 / (m**2 * A**2 / 2) - 1) < 0.01, a2  # 0.5
    assert abs(f1 - f_m) < 0.01 * es.resolution
    if f_m == 37.0:                                   # on-bin: the raw bin itself is exact
        assert abs(es.amplitude[np.argmin(np.abs(es.freqs - f_m))] / 4.0 - 1) < 1e-4


# --------------------------------------------------------------------------- peak interpolation
@pytest.mark.parametrize("delta", [0.1, 0.25, 0.37, 0.5, 0.77])
def test_peak_interpolation_better_than_one_percent_of_a_bin(delta):
    fs, n = 1_000.0, 1_000                           # 1 Hz bins
    f = 123.0 + delta
    x = 0.7 * np.cos(2 * np.pi * f * np.arange(n) / fs + 1.0)
    s = bsig.amplitude_spectrum(x, fs)
    assert s.resolution == 1.0
    fp = bsig.peak_frequency(s, f)
    assert abs(fp - f) < 0.01 * s.resolution, fp - f  # measured <= 0.0016 bin
    (_, _, a), = bsig.harmonic_peaks(s, f, n=1)
    assert abs(a / 0.7 - 1) < 0.005                   # measured <= 0.16 %


def test_peak_frequency_without_a_peak_raises():
    s = bsig.Spectrum(freqs=np.arange(100.0), amplitude=np.arange(100.0), band=None, fs=200.0, n_samples=100)
    with pytest.raises(ValueError, match="no local maximum"):
        bsig.peak_frequency(s, 50.0)
    assert np.isnan(bsig.harmonic_peaks(s, 50.0, n=1)[0][1])


# --------------------------------------------------------------------------- small API pieces
def test_select_band_with_known_resonance_and_clipping():
    assert bsig.select_band(np.zeros(8), 48_000.0, resonance_hz=3_000.0, bandwidth_hz=1_000.0) == (2500.0, 3500.0)
    lo, hi = bsig.select_band(np.zeros(8), 10_000.0, resonance_hz=4_800.0)
    assert lo == 4_200.0 and hi == 0.98 * 5_000.0
    with pytest.raises(ValueError, match="resonance_hz"):
        bsig.select_band(np.zeros(8), 10_000.0, resonance_hz=6_000.0)


def test_defect_markers():
    mk = blines.defect_markers({"BPFO": 107.4, "FTF": 11.9, "shaft": 29.95})
    assert [lab for lab, _ in mk] == ["BPFO", "2xBPFO", "3xBPFO", "4xBPFO", "5xBPFO", "FTF", "shaft"]
    assert np.allclose([f for _, f in mk], [107.4, 214.8, 322.2, 429.6, 537.0, 11.9, 29.95])
    assert len(blines.defect_markers({"BPFO": 100.0}, n_harmonics=3)) == 3


def test_bandpass_is_zero_phase_and_unit_gain_in_band():
    fs = 10_000.0
    t = np.arange(20_000) / fs
    x = np.sin(2 * np.pi * 1_000.0 * t)
    y = bsig.bandpass(x, fs, 800.0, 1_250.0)
    mid = slice(2_000, 18_000)
    assert np.max(np.abs(y[mid] - x[mid])) < 1e-3
    assert np.max(np.abs(bsig.bandpass(np.sin(2 * np.pi * 50.0 * t), fs, 800.0, 1_250.0)[mid])) < 1e-6


# --------------------------------------------------------------------------- bad input
def test_bad_inputs_have_clear_messages():
    x = np.random.default_rng(0).standard_normal(1000)
    with pytest.raises(ValueError, match=r"f_hi must be < fs/2 = 500 Hz"):
        bsig.bandpass(x, 1000.0, 100.0, 500.0)
    with pytest.raises(ValueError, match=r"f_lo must be > 0"):
        bsig.bandpass(x, 1000.0, 0.0, 200.0)
    with pytest.raises(ValueError, match=r"f_lo must be < f_hi"):
        bsig.bandpass(x, 1000.0, 300.0, 200.0)
    with pytest.raises(ValueError, match=r"f_hi must be < fs/2"):
        bsig.envelope_spectrum(x, 1000.0, band=(100.0, 600.0))
    xn = x.copy()
    xn[17] = np.nan
    with pytest.raises(ValueError, match=r"x must be finite.*index 17"):
        bsig.envelope_spectrum(xn, 1000.0)
    with pytest.raises(ValueError, match=r"x must be a 1-D array.*\(2, 500\)"):
        bsig.squared_envelope(x.reshape(2, 500), 1000.0)
    with pytest.raises(ValueError, match=r"fs must be a finite sampling frequency > 0"):
        bsig.envelope_spectrum(x, 0.0)
    with pytest.raises(ValueError, match=r"nfft must be >= len\(x\)"):
        bsig.amplitude_spectrum(x, 1000.0, nfft=10)
    with pytest.raises(ValueError, match=r"too short"):
        bsig.bandpass(x[:20], 1000.0, 100.0, 200.0)


# --------------------------------------------------------------------------- plots (smoke)
def test_plots_return_figure_and_save_png(fault, band, tmp_path):
    import matplotlib.pyplot as plt

    from bearingsim.output.plots_signal import plot_envelope_spectrum, plot_time_history

    t, clean, x, t_imp = fault
    es = bsig.envelope_spectrum(x, FS, band=band)
    mk = blines.defect_markers({"BPFO": FD, "FTF": 11.9, "shaft": 29.95})
    fig = plot_envelope_spectrum(es, mk, title="env", path=tmp_path / "env.png")
    ax = fig.axes[0]
    assert ax.get_xlim()[1] == pytest.approx(1.2 * 5 * FD)
    assert "Hz" in ax.get_xlabel() and "m/s²" in ax.get_ylabel()
    assert {txt.get_text().strip() for txt in ax.texts} >= {"BPFO", "5×BPFO", "FTF", "shaft"}
    fig2 = plot_time_history(t, clean, marks=t_imp, zoom=(0.1, 0.14), path=tmp_path / "t.png")
    assert fig2.axes[0].get_xlabel() == "time (ms)"
    assert (tmp_path / "env.png").stat().st_size > 10_000 and (tmp_path / "t.png").stat().st_size > 10_000
    plt.close("all")


# --------------------------------------------------------------------------- record metrics
def periodic_impacts(duration=2.0, f_d=FD, fn=FN, zeta=ZETA, fs=FS):
    """Exactly periodic unit impacts ringing a mode: sum_k exp(-zeta wn tau) sin(wd tau)."""
    t = np.arange(int(round(duration * fs))) / fs
    wn = 2 * np.pi * fn
    wd = wn * np.sqrt(1 - zeta**2)
    tau = np.mod(t, 1.0 / f_d)                 # time since the last impact (previous ones have died out)
    return np.exp(-zeta * wn * tau) * np.sin(wd * tau)


def test_record_metrics_of_known_signals():
    """RMS, kurtosis of a sine (A/sqrt 2, 1.5) and of Gaussian noise (sigma, 3 +- 5 sigma of the
    estimator, sqrt(24/n) = 0.016 for n = 96000)."""
    t = np.arange(96_000) / FS
    sine = 2.0 * np.sin(2 * np.pi * 1234.5 * t) + 7.0          # the mean is removed
    m = blines.record_metrics(sine, FS, 29.95, 3.5848)
    assert m.rms == pytest.approx(2.0 / np.sqrt(2.0), rel=1e-3)
    assert m.kurtosis == pytest.approx(1.5, rel=1e-3)
    g = np.random.default_rng(1).standard_normal(t.size) * 0.3
    m = blines.record_metrics(g, FS, 29.95, 3.5848)
    assert m.rms == pytest.approx(0.3, rel=0.01)
    assert abs(m.kurtosis - 3.0) < 5 * np.sqrt(24 / t.size)


def test_record_metrics_harmonic_ratios_of_a_periodic_impact_train():
    """Squared envelope of impacts ringing a mode: a train of exp(-2 zeta wn t) pulses with period
    1/f_d, whose Fourier coefficients are 1/(2 zeta wn + i 2 pi k f_d), so
    A_k/A_1 = sqrt(a^2 + w^2) / sqrt(a^2 + k^2 w^2), a = 2 zeta wn, w = 2 pi f_d (0.864, 0.724).
    Tolerance 0.03: the picked bin may lie 1/8 bin off the line (4x zero padding, Hann scalloping
    < 2 %) and the band-pass slightly shapes the envelope."""
    x = periodic_impacts()
    shaft = 29.95
    m = blines.record_metrics(x, FS, shaft, FD / shaft, band=(1500.0, 4500.0))
    a, w = 2 * ZETA * 2 * np.pi * FN, 2 * np.pi * FD
    for k, got in ((2, m.a2_a1), (3, m.a3_a1)):
        assert got == pytest.approx(np.hypot(a, w) / np.hypot(a, k * w), abs=0.03)
    # the line: within half a native bin fs/n (0.5 Hz for 2 s) of the true rate
    assert abs(m.peak_hz - FD) < 0.5 * FS / x.size
    assert m.peak_order == pytest.approx(m.peak_hz / shaft)
    # kurtosis of the impact train is large and the band kurtosis close to it
    assert m.kurtosis > 10 and m.band_kurtosis > 10


def test_record_metrics_peak_over_median_falls_with_noise():
    """Same impacts, more noise: the BPFO line over the floor must drop (and stay positive with
    little noise)."""
    x = periodic_impacts(duration=1.0)
    rng = np.random.default_rng(3)
    noise = rng.standard_normal(x.size)
    db = [blines.record_metrics(x + s * noise, FS, 29.95, FD / 29.95).peak_over_median_db
          for s in (0.05, 0.5, 2.0)]
    assert db[0] > db[1] > db[2] and db[0] > 20.0


def test_record_metrics_bad_inputs():
    x = periodic_impacts(duration=0.2)
    with pytest.raises(ValueError, match="band must be a pair"):
        blines.record_metrics(x, FS, 29.95, 3.58, band=None)
    with pytest.raises(ValueError, match="constant"):
        blines.record_metrics(np.ones(1000), FS, 29.95, 3.58)
    with pytest.raises(ValueError, match="shaft_hz and fault_order must be > 0"):
        blines.record_metrics(x, FS, -1.0, 3.58)
    with pytest.raises(ValueError, match=r"f_hi must be < fs/2"):
        blines.record_metrics(x, 12000.0, 29.95, 3.58, band=(2500.0, 6500.0))
