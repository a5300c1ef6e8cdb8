"""Real CWRU records (../shared/realdata, never committed) against bearingsim.

1. ``signal.record_metrics`` is the reference analysis: it reproduces analyze_real.py's own numbers
   on the real records (to round-off) and the real-record table of docs/reference-data.md at its printed
   precision.
2. Simulated CWRU signals (calibrated case files) against the real records, issue 9 targets.

Skipped, with the reason, when ../shared/realdata is absent.
"""
import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

from bearingsim.signals.lines import record_metrics

REPO = Path(__file__).resolve().parents[1]
DATA = REPO / ".." / "shared" / "realdata"
REFERENCE_MD = REPO / "docs/reference-data.md"
BPFO_ORDER = 3.5848                      # nominal CWRU multiplier (docs/reference-data.md)

pytestmark = pytest.mark.skipif(
    not (DATA / "analyze_real.py").is_file(),
    reason=f"real CWRU records not found in {DATA.resolve()} (they are never committed; "
           "see ../shared/realdata/README.md)")

OUTER = {  # docs/reference-data.md row label -> file stem
    "outer 0.007 in @6:00, 12 kHz (130)": "cwru_OR007_6_0hp_12k",
    "outer 0.021 in @6:00, 12 kHz (234)": "cwru_OR021_6_0hp_12k",
}


@pytest.fixture(scope="module")
def analyze_real():
    spec = importlib.util.spec_from_file_location("analyze_real", DATA / "analyze_real.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("stem", ["cwru_OR007_6_0hp_12k", "cwru_OR021_6_0hp_12k",
                                  "cwru_OR007_6_0hp_48k", "cwru_OR021_6_0hp_48k",
                                  "cwru_OR014_6_0hp_12k"])
def test_record_metrics_is_analyze_real(analyze_real, stem):
    """Same numbers as analyze_real.py's fixed 2.5-5.5 kHz band analysis (to 1e-9 relative)."""
    r = analyze_real.load(str(DATA), stem)
    x, fs, fr = r["x"], r["fs"], r["rpm"] / 60
    f, S, kf = analyze_real.ses(x, fs, (2500.0, 5500.0))
    f1, amps, snr = analyze_real.ses_report(f, S, fr, "BPFO")
    m = record_metrics(x, fs, fr, analyze_real.ORDERS["BPFO"])
    assert m.peak_hz == pytest.approx(f1, rel=1e-12)
    assert m.peak_over_local_db == pytest.approx(snr, rel=1e-9)
    assert m.a2_a1 == pytest.approx(amps[1] / amps[0], rel=1e-9)
    assert m.a3_a1 == pytest.approx(amps[2] / amps[0], rel=1e-9)
    assert m.band_kurtosis == pytest.approx(kf, rel=1e-9)
    assert m.rms == pytest.approx(np.sqrt(np.mean(x**2)), rel=1e-12)


def _reference_rows():
    rows = {}
    for line in REFERENCE_MD.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 7 and cells[0] in OUTER:
            rows[cells[0]] = cells[1:]
    return rows


@pytest.mark.parametrize("label", list(OUTER))
def test_reference_table_reproduced(label):
    """The docs/reference-data.md row (RMS, kurtosis, peak order, peak over the 30-600 Hz median,
    A2/A1, A3/A1) at its printed precision (half a unit of the last printed digit)."""
    if not REFERENCE_MD.is_file():
        pytest.skip(f"{REFERENCE_MD.resolve()} not found")
    rows = _reference_rows()
    assert label in rows, f"row {label!r} not found in docs/reference-data.md"
    d = np.load(DATA / f"{OUTER[label]}.npz")
    m = record_metrics(d["DE"].astype(np.float64), float(d["fs"]), float(d["rpm"]) / 60, BPFO_ORDER)
    got = [m.rms, m.kurtosis, m.peak_order, m.peak_over_median_db, m.a2_a1, m.a3_a1]
    for cell, value in zip(rows[label], got):
        txt = re.match(r"[-+]?\d+(\.\d+)?", cell).group(0)
        decimals = len(txt.split(".")[1]) if "." in txt else 0
        assert abs(value - float(txt)) <= 0.5 * 10.0**-decimals + 1e-12, (label, cell, value)


# --------------------------------------------------------------------------- simulated vs real
DURATION = 1.0          # s, the segment length: real and simulated records are cut into segments this long
SIM_SEGMENTS = 3        # simulated 1-s segments: both sides are the median over segments (one 1-s draw
                        # of A3/A1 spreads by ~0.1 from draw to draw: seeds 2 of the NumPy and of the
                        # key streams gave 0.459 and a pass at 0.021 in / 48 kHz against 0.306 real)
SEED = 2                # not the calibration's draw (docs/calibrate_cwru.py fits with seed 1)
SIM_CASES = {0.007: "cwru_6205_or007.toml", 0.021: "cwru_6205.toml"}
# The two real 0.007 in records differ by x1.9 in level (130: 0.67 g at 12 kHz, 135: 1.26 g at
# 48 kHz, both in the 2.5-5.5 kHz band); the fit on 130 cannot also be within x2 of 135.
KNOWN_MISSES = {(0.007, 48000, "rms"): "135 is 1.9x as strong as 130 (the 12 kHz record the fit used)"}


@pytest.fixture(scope="module")
def real_segments():
    from bearingsim.realism import calibration as cal

    out = {}
    for size in SIM_CASES:
        for fs in (12000, 48000):
            x, fs_, shaft = cal.load_record(DATA, cal.RECORDS[(size, fs)])
            out[size, fs] = cal.segment_metrics(x, fs_, shaft, DURATION)[0]
    return out


@pytest.fixture(scope="module")
def simulated():
    from bearingsim.realism import calibration as cal, rig_record as rl
    from bearingsim.case import load_case

    out = {}
    for size, name in SIM_CASES.items():
        case = load_case(REPO / "cases" / name)
        y, fs, res, _ = rl.simulate_record(case, duration=SIM_SEGMENTS * DURATION, sample_rate=48000.0, seed=SEED)
        y = y / cal.G
        shaft = res.frequencies.shaft
        out[size, 48000] = cal.segment_metrics(y, fs, shaft, DURATION)[0]
        y12, fs12 = rl.decimate_record(y, fs, 12000.0)
        out[size, 12000] = cal.segment_metrics(y12, fs12, shaft, DURATION)[0]
    return out


def _cases():
    from bearingsim.realism.calibration import TARGETS

    for size in SIM_CASES:
        for fs in (12000, 48000):
            for t in TARGETS:
                marks = []
                if (size, fs, t.field) in KNOWN_MISSES:
                    marks = [pytest.mark.xfail(strict=True, reason=KNOWN_MISSES[size, fs, t.field])]
                yield pytest.param(size, fs, t, id=f"{size}in-{fs // 1000}k-{t.field}", marks=marks)


@pytest.mark.parametrize("size, fs, target", list(_cases()))
def test_simulated_record_within_issue9_target(simulated, real_segments, size, fs, target):
    """Issue 9 targets (bearingsim.realism.calibration.TARGETS): BPFO order within 0.3 %, peak over
    median within +-8 dB, A2/A1 and A3/A1 within +-0.15, kurtosis and RMS within a factor 2;
    real and simulated = medians over the records' 1-s segments (equal length: the peak over
    median grows with the length).  The 12 kHz records (130, 234) were used by
    the calibration, the 48 kHz ones (135, 238) were not."""
    sim, real = getattr(simulated[size, fs], target.field), getattr(real_segments[size, fs], target.field)
    assert target.check(sim, real), f"{target.label}: simulated {sim:.4g}, real {real:.4g}"


# --------------------------------------------------------------------------- inner race and ball
# Issue 11: simulated CWRU inner-race (cases/cwru_6205_inner.toml) and ball (cwru_6205_ball.toml)
# records against 105/109 (IR 0.007 in) and 118/122 (B 0.007 in), 0 hp, 1797 rpm.  Both sides are
# measured with record_metrics (the reference analysis: band 2.5-5.5 kHz, squared envelope, Hann,
# x4 zero padding; fault line = the largest bin within +-5 % of order x f_r); real = median over
# the record's 1-s segments, simulated = one 1-s record (48 kHz, and decimated to 12 kHz), the
# case's realism (slip, speed fluctuation, noise) with seed SEED.  No pass-to-pass amplitude
# variation (pass_cv_max = 0: it was fitted on the outer-race record 130 only).
BPFI_ORDER, BSF2_ORDER, FTF_ORDER = 5.4152, 4.7135, 0.39828   # nominal CWRU multipliers
FAULT_RECORDS = {("inner", 12000): "cwru_IR007_0hp_12k", ("inner", 48000): "cwru_IR007_0hp_48k",
                 ("ball", 12000): "cwru_B007_0hp_12k", ("ball", 48000): "cwru_B007_0hp_48k"}
FAULT_CASES = {"inner": ("cwru_6205_inner.toml", BPFI_ORDER), "ball": ("cwru_6205_ball.toml", BSF2_ORDER)}
# a sideband is "present" at >= 12 dB over the median of the spectrum over 0.5-1.5 x the fault
# frequency (peak_over_local_db's floor): in 1-s segments of the normal record 97 and of the ball
# records the largest bin within +-1.5 Hz of an arbitrary frequency reaches up to ~10 dB by
# chance; the real IR sidebands stand 13-19 dB over it, the simulated ones 20-30 dB.
SIDEBAND_DB = 12.0


def _ses(x, fs, band=(2500.0, 5500.0)):
    """The squared-envelope spectrum of record_metrics (same band, window, padding, scale)."""
    import scipy.signal as ss
    from bearingsim.signals.envelope import bandpass

    e2 = np.abs(ss.hilbert(bandpass(x, fs, *band))) ** 2
    e2 -= e2.mean()
    w = np.hanning(e2.size)
    nfft = 1 << (int(np.ceil(np.log2(e2.size))) + 2)
    return np.fft.rfftfreq(nfft, 1.0 / fs), np.abs(np.fft.rfft(e2 * w, nfft)) * 2.0 / w.sum()


def sideband_db(x, fs, shaft_hz, order, side_order, k=(-1, 1), half_width=1.5):
    """dB over the 0.5-1.5 x order x f_r median of the largest bin within +-half_width Hz of the
    fault line (located as record_metrics does) + k x side_order x f_r, for each k."""
    f, S = _ses(x, fs)
    f_nom = order * shaft_hz
    m = (f > 0.95 * f_nom) & (f < 1.05 * f_nom)
    f1 = float(f[m][np.argmax(S[m])])
    floor = float(np.median(S[(f > 0.5 * f_nom) & (f < 1.5 * f_nom)]))
    out = []
    for kk in k:
        w = np.abs(f - (f1 + kk * side_order * shaft_hz)) <= half_width
        out.append(float(20 * np.log10(S[w].max() / floor)))
    return out


@pytest.fixture(scope="module")
def fault_real():
    """(kind, fs) -> (median RecordMetrics over 1-s segments, per-segment metrics, median
    sideband dB [-f, +f] over the segments)."""
    from bearingsim.realism import calibration as cal

    out = {}
    for (kind, fs), stem in FAULT_RECORDS.items():
        x, fs_, shaft = cal.load_record(DATA, stem)
        order = FAULT_CASES[kind][1]
        side = 1.0 if kind == "inner" else FTF_ORDER
        med, segs = cal.segment_metrics(x, fs_, shaft, DURATION, order=order)
        n = int(round(DURATION * fs_))
        sb = np.median([sideband_db(x[i * n:(i + 1) * n], fs_, shaft, order, side)
                        for i in range(len(x) // n)], axis=0)
        out[kind, fs] = med, segs, sb
    return out


@pytest.fixture(scope="module")
def fault_simulated():
    """(kind, fs) -> (RecordMetrics, sideband dB [-f, +f], DynamicsResult) of one simulated 1-s record."""
    from bearingsim.realism import calibration as cal, rig_record as rl
    from bearingsim.case import load_case

    out = {}
    for kind, (name, order) in FAULT_CASES.items():
        case = load_case(REPO / "cases" / name)
        y, fs, res, _ = rl.simulate_record(case, duration=DURATION, sample_rate=48000.0, seed=SEED)
        y = y / cal.G
        shaft = res.frequencies.shaft
        side = 1.0 if kind == "inner" else FTF_ORDER
        y12, fs12 = rl.decimate_record(y, fs, 12000.0)
        for f_s, yy in ((48000, y), (12000, y12)):
            out[kind, f_s] = (record_metrics(yy, float(f_s), shaft, order),
                              sideband_db(yy, float(f_s), shaft, order, side), res)
    return out


@pytest.mark.parametrize("fs", [12000, 48000])
def test_inner_race_bpfi_order_and_sidebands_match_the_rig(fault_real, fault_simulated, fs):
    """Issue 11: BPFI order of the simulated IR 0.007 in record within 0.3 % of the measured one
    (105/109: 5.398, i.e. the 5.40 of docs/reference-data.md; simulated 5.405, the case's axial load
    43.7 N fitted on the outer-race BPFO order), and the same sideband structure: BPFI +- f_r
    present (>= SIDEBAND_DB over the local median) in both."""
    real, segs, sb_real = fault_real["inner", fs]
    sim, sb_sim, _ = fault_simulated["inner", fs]
    assert abs(real.peak_order / 5.40 - 1) <= 0.003, f"real BPFI order {real.peak_order:.4f}, expected 5.40"
    assert abs(sim.peak_order / real.peak_order - 1) <= 0.003, (
        f"BPFI order: simulated {sim.peak_order:.4f}, real {real.peak_order:.4f} (expected within 0.3 %)")
    for who, sb in (("real", sb_real), ("simulated", sb_sim)):
        for sign, db in zip("-+", sb):
            assert db >= SIDEBAND_DB, (f"{who} {fs // 1000} kHz: expected a line at BPFI {sign} f_r "
                                       f">= {SIDEBAND_DB:g} dB over the local median, got {db:.1f} dB")


def test_ball_fault_as_measured(fault_real, fault_simulated):
    """Ball 0.007 in (118 at 12 kHz, 122 at 48 kHz) -- what matches and what does not.

    Matches (asserted): the simulated record has its 2 BSF line at the nominal order (within
    0.3 % of 4.7135 x the contact-angle correction the case's BPFI also carries) with +- FTF
    sidebands.  The real records have no stable 2 BSF line: the largest bin within +-5 % of
    2 BSF wanders over > 4 % in order from one 1-s segment to the next (4.50-4.81) and stands
    only ~6-7 dB over the local median, as on the normal record 97 (~6 dB at an arbitrary
    frequency) -- the rig's ball-fault line is weak (docs/reference-data.md: 4.60, weak), so the
    simulated line (~39 dB) is far stronger than the rig's: that is a known miss, asserted as
    such (the real line order scatters; the real peak is > 20 dB weaker than the simulated)."""
    for fs in (12000, 48000):
        sim, sb_sim, res = fault_simulated["ball", fs]
        real, segs, _ = fault_real["ball", fs]
        bsf2 = 2 * res.frequencies.bsf / res.frequencies.shaft
        assert abs(sim.peak_order / bsf2 - 1) <= 0.003, (
            f"simulated {fs // 1000} kHz: 2BSF order {sim.peak_order:.4f}, expected {bsf2:.4f} +- 0.3 %")
        for sign, db in zip("-+", sb_sim):
            assert db >= SIDEBAND_DB, (f"simulated {fs // 1000} kHz: expected 2BSF {sign} FTF "
                                       f">= {SIDEBAND_DB:g} dB over the local median, got {db:.1f} dB")
        orders = np.array([m.peak_order for m in segs])
        assert np.ptp(orders) / BSF2_ORDER > 0.02, (
            f"real {fs // 1000} kHz: the 2BSF peak order is stable over 1-s segments ({orders}); "
            "the rig's ball line was expected weak and unstable: update the note")
        assert sim.peak_over_local_db - real.peak_over_local_db > 20.0, (
            f"{fs // 1000} kHz: 2BSF peak over local median simulated {sim.peak_over_local_db:.1f} dB, "
            f"real {real.peak_over_local_db:.1f} dB: the simulated line was expected far stronger")
