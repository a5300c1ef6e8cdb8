"""bearingsim calibrate (bearingsim.realism.machine): the fit recovers a synthetic machine whose background
is known (the independent truth: the NumPy synthesis tests/oracles/background_numpy.py with chosen
parameters), the written spec loads and runs as a data set, the signal gain of a fault record
whose level is known, and the real CWRU normal record when ../shared/realdata is present."""
from pathlib import Path

import h5py
import numpy as np
import pytest

from bearingsim.signals.background import Background
from oracles.background_numpy import background_signal
from bearingsim.case import case_from_dict, load_case, parse_case
from bearingsim.app.cli import main
from bearingsim.datasets import make_dataset
from bearingsim.realism.machine import calibrate_machine
from bearingsim.realism.records import read_record
from bearingsim.app.signal_workflows import calibrate_case

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / ".." / "shared" / "realdata"
FS = 24000.0
RPM = 1790.0

#: a small template: the engine tests' CWRU-like bearing and the data set of tests/test_dataset.py
#: (the same compiled program: 3-item chunks of 0.02 s at 24 kHz)
TEMPLATE = (ROOT / "tests" / "data" / "cwru_like_6205.toml").read_text().replace(
    "sample_rate_Hz = 48000", "sample_rate_Hz = 24000") + """
[dataset]
count = 6
chunk = 3
seed = 7
duration_s = 0.02
healthy_fraction = 0.34
speed_rpm = [1720, 1800]
radial_N = [500, 2000]
spall_length_mm = [0.3, 1.0]
spall_depth_mm = [0.2794, 0.2794]
spall_center_deg = [0, 0]
"""

GRID = np.geomspace(50.0, 0.45 * FS, 48)
#: the known machine: shaft lines, 50 Hz supply, broadband RMS 1 m/s^2 shaped by a resonance
#: bump at 3 kHz (0.15 octave), modulation 0.2 / 0.1 / 0.15 at f_r / 2 f_r / 5 f_r, knocks at 4 per s
TRUTH = Background((0.3, 0.15, 0.08, 0.05, 0.03, 0.02), 50.0, (0.1, 0.04), 1.0, tuple(GRID),
                   tuple(10 * np.log10(1 + 30 * np.exp(-0.5 * (np.log2(GRID / 3000.0) / 0.15) ** 2))),
                   (0.2, 0.1, 0.0, 0.0, 0.15), 4.0, 10.0, 3000.0, 0.05)


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    d = tmp_path_factory.mktemp("machine")
    x = background_signal(np.random.default_rng(3), int(5 * FS), FS, RPM / 60.0, TRUTH)
    np.save(d / "healthy.npy", x / 9.80665)                 # in g, as many loggers write
    (d / "template.toml").write_text(TEMPLATE)
    cal = calibrate_case(d / "healthy.npy", d / "spec.toml", template=d / "template.toml",
                         sample_rate=FS, unit="g")
    return d, x, cal


def test_fit_recovers_the_known_machine(synthetic):
    _, x, cal = synthetic
    bg = cal.background
    # shaft speed from the harmonic search: within 1/16 bin of the 0.2 Hz resolution (x 6 for rpm)
    assert abs(60 * cal.shaft_hz - RPM) < 0.2, 60 * cal.shaft_hz
    # line amplitudes (least squares over 5 s): the estimate's noise is sigma sqrt(2/N) x the
    # PSD shape ~ 0.005 m/s^2; 0.015 = 3 of those
    np.testing.assert_allclose(bg.shaft_amplitudes, TRUTH.shaft_amplitudes, atol=0.015)
    assert cal.line_detected and bg.line_frequency == 50.0
    np.testing.assert_allclose(bg.line_amplitudes[:2], TRUTH.line_amplitudes, atol=0.015)
    assert max(bg.line_amplitudes[2:]) < 0.015                  # harmonics 3, 4 are absent
    # broadband RMS before the modulation: 2 % (knock masking, 5 s of noise)
    assert bg.noise_rms == pytest.approx(TRUTH.noise_rms, rel=0.02)
    mod = np.zeros(8)
    mod[:5] = TRUTH.modulation_depths
    np.testing.assert_allclose(bg.modulation_depths, mod, atol=0.03)
    # the resonance of the broadband shape: within 2 % (Welch bins of 23 Hz, 100 Hz smoothing)
    f = [r[0] for r in cal.resonances]
    assert any(abs(v / 3000.0 - 1) < 0.02 for v in f), cal.resonances
    # knocks: every one found (the number drawn, replayed in background_signal's documented draw
    # order: shaft phases, line phases, noise, modulation phases, then the Poisson count); the
    # peak of the band-passed ring within a factor 1.6
    rng = np.random.default_rng(3)
    rng.uniform(0, 1, 6), rng.uniform(0, 1, 2), rng.standard_normal(x.size), rng.uniform(0, 1, 5)
    drawn = rng.poisson(TRUTH.knock_rate * 5.0)
    assert 0.85 * drawn <= bg.knock_rate * 5.0 <= drawn       # two within ~5 ms count as one
    assert 10.0 / 1.6 < bg.knock_amplitude < 10.0 * 1.6
    # the fitted shape reproduces the truth's shape (dB, relative) within 2 dB over 200 Hz - 0.4 fs
    m = (GRID > 200) & (GRID < 0.4 * FS)
    fit = np.interp(np.log(GRID[m]), np.log(bg.psd_frequencies), bg.psd_levels_db)
    tru = np.asarray(TRUTH.psd_levels_db)[m]
    d = (fit - fit.mean()) - (tru - tru.mean())
    assert np.max(np.abs(d)) < 2.0, d


def test_written_spec_loads_and_runs_as_a_data_set(synthetic, capsys):
    d, _, cal = synthetic
    spec = load_case(d / "spec.toml")
    ds = spec.data["dataset"]
    assert ds["background"] == "machine" and spec.get("dynamics.sample_rate_Hz") == FS
    assert spec.get("background.noise_rms_m_s2") == pytest.approx(cal.background.noise_rms, rel=1e-5)
    lo, hi = ds["resonance_frequency_Hz"]
    assert lo < 3000.0 < hi and hi <= 0.45 * FS
    assert spec.get("dynamics.noise_rms_m_s2") == 0.0        # the machine's broadband replaces it
    assert main(["dataset", str(d / "spec.toml"), "-o", str(d / "data.h5")]) == 0
    with h5py.File(d / "data.h5", "r") as f:
        lab = np.asarray(f["labels"])
        X = np.asarray(f["signals"], float)
    assert np.all(lab["result"] == 0)
    np.testing.assert_allclose(lab["background_noise_rms_m_s2"], spec.get("background.noise_rms_m_s2"), rtol=1e-12)
    # every item carries the machine's broadband level (its RMS at least the background's)
    assert np.all(np.sqrt(np.mean(X * X, axis=1)) > 0.7 * cal.background.noise_rms)


def test_signal_gain_of_a_fault_record_of_known_level(synthetic):
    """A fault record = the machine + g0 x a simulated outer-race signal of the calibrated spec at
    gain 1: the fit must return g0 (the median item of the same draw; the background adds in
    power)."""
    d, x, _ = synthetic
    g0 = 4.0
    raw = load_case(d / "spec.toml").raw
    raw["dataset"].update(count=3, chunk=3, healthy_fraction=0.0, seed=0, speed_rpm=[RPM, RPM],
                          background="none")
    probe = case_from_dict(raw, "probe")
    make_dataset(probe, d / "probe.h5", progress=False)
    with h5py.File(d / "probe.h5", "r") as f:
        S = np.asarray(f["signals"], float)
    rms = np.sqrt(np.mean((S - S.mean(1, keepdims=True)) ** 2, axis=1))
    item = S[np.argsort(rms)[1]]                           # the median of the three
    y = background_signal(np.random.default_rng(5), int(2 * FS), FS, RPM / 60.0, TRUTH)
    y = y + g0 * np.resize(item - item.mean(), y.size)
    cal = calibrate_machine(x, FS, load_case(d / "template.toml"), unit="m/s^2", shaft_rpm=RPM, fault=y,
                            fault_class="outer", fault_rpm=RPM, gain_items=3, seed=0)
    # the two background records' RMS differ by their 2 % sampling scatter (of 1 m/s^2 under
    # a ~3 m/s^2 fault): 5 %
    assert cal.signal_gain == pytest.approx(g0, rel=0.05)
    lo, hi = cal.case.data["dataset"]["signal_gain"]
    assert lo == pytest.approx(g0 / 3, rel=0.06) and hi == pytest.approx(3 * g0, rel=0.06)


def test_record_readers(tmp_path):
    x = np.sin(np.arange(3000) * 0.1)
    (tmp_path / "r.csv").write_text("# acceleration\n" + "\n".join(f"{v:.9f}" for v in x))
    y, fs, unit, rpm, ch = read_record(tmp_path / "r.csv", sample_rate=3000.0, unit="m/s^2")
    np.testing.assert_allclose(y.ravel(), x, atol=1e-9)
    assert (fs, unit, rpm, ch) == (3000.0, "m/s^2", None, None)
    np.savez(tmp_path / "r.npz", DE=x, FE=x, fs=3000.0, rpm=1797.0, units="g (acceleration)")
    y, fs, unit, rpm, ch = read_record(tmp_path / "r.npz")
    assert (fs, unit, rpm, ch) == (3000.0, "g", 1797.0, "DE")
    _, _, _, _, ch = read_record(tmp_path / "r.npz", "FE")
    assert ch == "FE"


@pytest.mark.skipif(not (DATA / "cwru_normal_0hp_12k_decimated.npz").is_file(),
                    reason=f"real CWRU records not found in {DATA.resolve()} (never committed; "
                           "see ../shared/realdata/README.md)")
def test_real_normal_record(tmp_path, capsys):
    rec = DATA / "cwru_normal_0hp_12k_decimated.npz"
    assert main(["calibrate", str(rec), "-o", str(tmp_path / "spec.toml"), "--count", "8"]) == 0
    out = capsys.readouterr().out
    assert "shaft 1795" in out and "wrote" in out
    spec = load_case(tmp_path / "spec.toml")
    with np.load(rec) as z:
        x = z["DE"].astype(float) * 9.80665
    # the broadband part is nearly all of the record (lines ~1 % of its power): its RMS with the
    # fitted modulation (x sqrt(1 + sum m_k^2 / 2)) is the record's
    m = np.asarray(spec.get("background.modulation_depths"))
    rms = spec.get("background.noise_rms_m_s2") * np.sqrt(1 + 0.5 * np.sum(m * m))
    assert rms == pytest.approx(x.std(), rel=0.03)
    assert m[3] > 0.2           # the record's broadband is modulated at 4 f_r ~ 2 x 60 Hz
    assert spec.get("operation.speed_rpm") == pytest.approx(1796.0, abs=2.0)   # the file's 1796 rpm
    lo, hi = spec.data["dataset"]["resonance_frequency_Hz"]
    assert 1000.0 < lo < hi <= 5400.0
    assert spec.data["dataset"]["count"] == 8 and spec.get("dynamics.sample_rate_Hz") == 12000.0
    parse_case(spec.text)                                     # the TOML is the case
