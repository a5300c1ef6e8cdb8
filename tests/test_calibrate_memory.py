"""`bearingsim calibrate` on a long record (issue 35: a 1-hour 12 kHz record asked for 6.8 GiB in
background_fit.fit_lines and crashed): the line fit's memory is one block, not a design matrix of
the whole record, and the machine fits analyse at most MAX_ANALYSIS_SAMPLES samples, saying so."""
import tracemalloc

import numpy as np
import pytest

from bearingsim.output.report import calibration_text
from bearingsim.realism import background_fit as bf
from bearingsim.realism.machine import calibrate_machine

FS = 12000.0
SHAFT = 29.95


def record(seconds, seed=0):
    t = np.arange(int(seconds * FS)) / FS
    rng = np.random.default_rng(seed)
    return (0.3 * np.sin(2 * np.pi * SHAFT * t) + 0.1 * np.cos(2 * np.pi * 2 * SHAFT * t + 1.0)
            + 0.05 * np.sin(2 * np.pi * 60.0 * t) + rng.normal(0.0, 1.0, t.size))


def peak_bytes(fn, *args, **kw):
    tracemalloc.start()
    try:
        out = fn(*args, **kw)
        return tracemalloc.get_traced_memory()[1], out
    finally:
        tracemalloc.stop()


def test_fit_lines_is_the_least_squares_fit_of_the_whole_record():
    """Blocks of normal equations = one least-squares solve of the whole design matrix (2 s,
    3 blocks of 8192): amplitudes and lines to 1e-9 (the columns are nearly orthogonal; measured
    ~1e-15)."""
    x = record(2.0)
    n, t = x.size, np.arange(x.size) / FS
    f = [k * SHAFT for k in range(1, bf.SHAFT_HARMONICS + 1)] + [60.0 * l for l in (1, 2)]
    M = np.column_stack([np.ones(n)] + [g(2 * np.pi * fk * t) for fk in f for g in (np.cos, np.sin)])
    c = np.linalg.lstsq(M, x, rcond=None)[0]
    shaft, line, lines = bf.fit_lines(x, FS, SHAFT, 60.0, (1, 2), block=8192)
    assert np.allclose(np.hypot(c[1::2], c[2::2]), np.r_[shaft, line], rtol=0, atol=1e-9)
    assert np.allclose(lines, M[:, 1:] @ c[1:], rtol=0, atol=1e-9)
    assert shaft[0] == pytest.approx(0.3, abs=0.02) and line[0] == pytest.approx(0.05, abs=0.02)


def test_fit_lines_memory_grows_only_with_its_output():
    """Peak allocation (tracemalloc) at 2^18 and 2^19 samples: the difference per added sample
    is the fitted lines' 8 bytes (bound 16); the whole design matrix took 21 columns x 8 bytes
    and lstsq's copies (measured 360 bytes per sample before)."""
    peaks = []
    for n in (1 << 18, 1 << 19):
        x = record(n / FS)
        peaks.append(peak_bytes(bf.fit_lines, x, FS, SHAFT, 60.0, (1, 2, 3, 4))[0])
    per_sample = (peaks[1] - peaks[0]) / (1 << 18)
    assert per_sample < 16.0, per_sample


def test_a_long_record_is_analysed_up_to_the_cap_and_the_output_says_so(monkeypatch):
    """A 60 s record with the cap lowered to 2^17 samples (10.92 s; the real cap, 2^22, is 349.5 s
    at 12 kHz: the same code path, 32x cheaper here): the fits see the first 2^17 samples, the
    report and the spec's description say which part, and the peak allocation stays that of the
    analysed part plus the record's copies."""
    monkeypatch.setattr(bf, "MAX_ANALYSIS_SAMPLES", 1 << 17)
    x = record(60.0)
    peak, cal = peak_bytes(calibrate_machine, x, FS, "dataset_cwru_4class", unit="m/s^2", shaft_rpm=60 * SHAFT)
    assert cal.duration_s == pytest.approx((1 << 17) / FS, rel=1e-12) and cal.record_s == pytest.approx(60.0)
    text = calibration_text(cal)
    assert "record: 60.00 s at 12000 Hz, the first 10.92 s analysed (at most 131072 samples" in text
    assert "the first 10.92 s of 60.00 s" in cal.case.data["description"]
    assert peak < 60e6, peak / 1e6         # measured 32 MB; 92 MB without the cap, ~350 MB before
    assert "analysed" not in calibration_text(calibrate_machine(x[:1 << 16], FS, "dataset_cwru_4class",
                                                                unit="m/s^2", shaft_rpm=60 * SHAFT))
