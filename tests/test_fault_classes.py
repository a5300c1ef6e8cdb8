"""The four fault classes in the dynamics (docs/model.md section 9): envelope lines of an inner-race
and a ball defect, depth -> 0 gives the healthy bearing, and a four-class data set whose labels
match its classes.

Cost: one simulation per record, module-scoped and shared (CWRU 6205 cases, realism off,
0.5 s at 12 kHz: ~1 s each once compiled), and one 8-item data set (0.05 s at 12 kHz).

Envelope analysis as the rig comparison (tests/test_realdata.py): band 2.5-5.5 kHz (it holds the
two sensor modes of the CWRU cases, 2978 and 3356 Hz), squared envelope, Hann window, spectrum
zero-padded x2 (bearingsim.signals.envelope.envelope_spectrum).  0.5 s gives a native resolution of 2 Hz;
the shaft (29.95 Hz) and cage (11.96 Hz) sidebands are 15 and 6 resolution cells from the line.
"""
from pathlib import Path

import h5py
import json
import numpy as np
import pytest

import bearingsim as bs
from bearingsim.case import load_case
from bearingsim.dynamics import DynamicsParameters, Realism, characteristic_frequencies, simulate
from bearingsim.signals.envelope import envelope_spectrum, peak_frequency

REPO = Path(__file__).resolve().parents[1]
DURATION, FS = 0.5, 12000.0
BAND = (2500.0, 5500.0)
# A line "stands above the floor" when it is >= 10 dB over the median of the spectrum over
# 0.5-1.5 x the fault frequency (the local median of bearingsim.signals.lines.record_metrics).  With
# realism off the floor is only leakage and the impacts' own broadband content; the measured
# sidebands stand 25-28 dB over it (inner +-f_r) and 25-26 dB (ball +-FTF), so 10 dB separates
# "a line" from "no line" with a wide margin while not depending on the exact level.
LINE_DB = 10.0


def _setup(name):
    case = load_case(REPO / "cases" / f"{name}.toml")
    params = DynamicsParameters.from_settings(dict(case.dynamics_settings()))
    return case, params


def _run(case, params, spall):
    return simulate(case.bearing(), case.operation(), case.loads(), spall, params, DURATION, FS,
                    theta0=case.cage_angle, realism=Realism(), seed=0, record_balls=False)


@pytest.fixture(scope="module")
def records():
    """name -> DynamicsResult: the inner and ball CWRU cases as shipped, the healthy bearing, and
    both defects with depth 0 (same geometry, same defect slots)."""
    out = {}
    for name, loc in (("cwru_6205_inner", "inner"), ("cwru_6205_ball", "ball")):
        case, params = _setup(name)
        sp = case.spall()
        assert sp.location == loc, f"{name}: expected a defect on the {loc}, got {sp.location!r}"
        out[loc] = _run(case, params, sp)
        out[loc + "_depth0"] = _run(case, params, bs.Spall(sp.center, sp.extent, 0.0, sp.profile,
                                                            sp.location, sp.ball))
    out["healthy"] = _run(case, params, None)     # same bearing, loads and [dynamics] block
    return out


def _spectrum(res):
    x = np.asarray(res.sensor_acceleration)
    return envelope_spectrum(x, FS, band=BAND)


def _db_over_local(sp, f0, f):
    """(frequency, dB over the 0.5-1.5 f0 median) of the largest bin within +-1 resolution of f."""
    fr, A = np.asarray(sp.freqs), np.asarray(sp.amplitude)
    floor = np.median(A[(fr > 0.5 * f0) & (fr < 1.5 * f0)])
    m = np.abs(fr - f) <= sp.resolution
    i = int(np.argmax(A[m]))
    return float(fr[m][i]), float(20 * np.log10(A[m][i] / floor))


def _check_line_and_sidebands(res, f0, f_side, what, side):
    sp = _spectrum(res)
    # the spectral peak nearest the fault frequency, interpolated (peak_frequency): within one
    # native resolution cell (fs / n = 2 Hz) of the frequency the run reports
    f_pk = peak_frequency(sp, f0)
    assert abs(f_pk - f0) <= sp.resolution, (
        f"{what}: expected the envelope peak at {f0:.3f} Hz (+-{sp.resolution:g} Hz), got {f_pk:.3f} Hz")
    # ... and it is the largest line over 0.5-1.5 f0 (where the sidebands also lie)
    fr, A = np.asarray(sp.freqs), np.asarray(sp.amplitude)
    m = (fr > 0.5 * f0) & (fr < 1.5 * f0)
    f_max = float(fr[m][np.argmax(A[m])])
    assert abs(f_max - f0) <= sp.resolution, (
        f"{what}: expected the largest envelope line over {0.5 * f0:.0f}-{1.5 * f0:.0f} Hz at "
        f"{f0:.2f} Hz, got {f_max:.2f} Hz")
    for k in (-1, 1):
        f, db = _db_over_local(sp, f0, f0 + k * f_side)
        assert db >= LINE_DB, (
            f"{what}: expected a sideband at {what} {'+-'[k < 0]} {side} = {f0 + k * f_side:.2f} Hz "
            f">= {LINE_DB:g} dB over the local median, got {db:.1f} dB at {f:.2f} Hz")


def test_inner_race_envelope_peaks_at_bpfi_with_shaft_sidebands(records):
    """docs/model.md section 9: a ball meets the inner spall at BPFI; the spall crosses the fixed load zone
    once per shaft turn, so the impacts are amplitude-modulated at f_r: BPFI +- f_r."""
    res = records["inner"]
    fq = res.frequencies
    _check_line_and_sidebands(res, fq.bpfi, fq.shaft, "BPFI", "f_r")


def test_ball_pit_envelope_peaks_at_2bsf_with_cage_sidebands(records):
    """docs/model.md section 9: the pit meets the outer and the inner raceway once per ball turn each (2 BSF
    impacts); the pitted ball orbits with the cage through the load zone: 2 BSF +- FTF."""
    res = records["ball"]
    fq = res.frequencies
    _check_line_and_sidebands(res, 2.0 * fq.bsf, fq.ftf, "2BSF", "FTF")


@pytest.mark.parametrize("loc", ["inner", "ball"])
def test_depth_zero_is_the_healthy_bearing(records, loc):
    """A defect of depth 0 (any location) is the healthy bearing.  Ring displacements agree to
    1e-12 relative (measured ~1e-15: round-off); the sensor and housing accelerations of the
    healthy run are themselves only round-off of the static equilibrium (~1e-7 m/s^2 against
    ~19 m/s^2 RMS of the defect record), so their difference is bounded by 1e-9 x the RMS of
    the record with the defect (measured difference ~2e-11 m/s^2, ~1e-12 of that RMS)."""
    h, z, d = records["healthy"], records[loc + "_depth0"], records[loc]
    scale = float(np.sqrt(np.mean(np.asarray(d.sensor_acceleration) ** 2)))
    assert scale > 1.0, f"{loc}: expected a defect record of RMS > 1 m/s^2, got {scale:.3g}"
    u_h, u_z = np.asarray(h.ring_displacement), np.asarray(z.ring_displacement)
    du = np.max(np.abs(u_z - u_h)) / np.max(np.abs(u_h))
    assert du <= 1e-12, f"{loc} depth 0: ring displacement differs from healthy by {du:.3g} (expected <= 1e-12)"
    for key in ("housing_acceleration", "sensor_acceleration"):
        diff = float(np.max(np.abs(np.asarray(getattr(z, key)) - np.asarray(getattr(h, key)))))
        assert diff <= 1e-9 * scale, (f"{loc} depth 0: {key} differs from healthy by {diff:.3g} m/s^2 "
                                      f"(expected <= {1e-9 * scale:.3g})")


# ------------------------------------------------------------------------------ data set
@pytest.fixture(scope="module")
def four_class_dataset(tmp_path_factory):
    from bearingsim.app.signal_workflows import dataset_case

    spec = load_case(REPO / "cases" / "dataset_cwru.toml")
    # outer_fraction defaults to the rest: set inner and ball before healthy so every
    # intermediate spec is valid
    for key, value in {"dataset.count": 8, "dataset.chunk": 8, "dataset.duration_s": 0.05,
                       "dataset.inner_fraction": 0.25, "dataset.ball_fraction": 0.25,
                       "dataset.healthy_fraction": 0.25, "dynamics.sample_rate_Hz": 12000}.items():
        spec = spec.with_value(key, value)
    out = tmp_path_factory.mktemp("fourclass") / "four.h5"
    dataset_case(spec, out)
    with h5py.File(out) as f:
        return spec, f["labels"][()], json.loads(f["labels"].attrs["class_names"]), f["signals"][()]


def test_four_class_dataset_labels(four_class_dataset):
    """8 items, a quarter per class: fault_class 0-3 two each, class_names, healthy items with
    no defect, every result 0, and the labelled frequencies equal to
    dynamics.characteristic_frequencies of the item's own quasi-static solution (rel 1e-9:
    the same computation, round-off only)."""
    spec, lab, names, sig = four_class_dataset
    assert names == {"0": "healthy", "1": "outer", "2": "inner", "3": "ball"}, names
    assert np.bincount(lab["fault_class"], minlength=4).tolist() == [2, 2, 2, 2], (
        f"expected 2 items per class, got fault_class {lab['fault_class'].tolist()}")
    assert np.all(lab["result"] == 0), f"expected every result 0, got {lab['result'].tolist()}"
    assert np.array_equal(lab["healthy"], lab["fault_class"] == 0), "healthy must be fault_class == 0"
    h = lab["fault_class"] == 0
    assert np.all(lab["spall_depth_mm"][h] == 0) and np.all(lab["spall_length_mm"][h] == 0)
    assert np.all(lab["spall_depth_mm"][~h] > 0) and np.all(lab["spall_length_mm"][~h] > 0)
    np.testing.assert_allclose(lab["shaft_Hz"], lab["speed_rpm"] / 60.0, rtol=1e-12)

    from bearingsim.physics.jones import load_vector
    from bearingsim.physics.kinematics import Operation

    b = spec.bearing()
    control = spec.data["operation"]["raceway_control"]
    loc_of = {1: "outer", 2: "inner", 3: "ball"}
    for row in lab:
        c = int(row["fault_class"])
        op = Operation.from_rpm(float(row["speed_rpm"]), control, True, True)
        F = load_vector(axial=float(row["axial_N"]), radial_x=float(row["radial_N"]))
        sp = None
        if c:
            # the depth the item was simulated with (the pit's effective depth, depth_rule "pit")
            sp = bs.Spall.from_length(b, np.deg2rad(row["spall_center_deg"]), row["spall_length_mm"] * 1e-3,
                                      row["effective_depth_mm"] * 1e-3, spec.spall().profile, loc_of[c], 0)
        sol = bs.solve(b, op, F, cage_angle=spec.cage_angle, spall=sp, hertz_method=spec.hertz_method)
        fq, _ = characteristic_frequencies(b, op, sol)
        for k in ("ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz"):
            assert row[k] == pytest.approx(fq.hz()[k], rel=1e-9), (
                f"item {row['index']} ({names[str(c)]}): {k} labelled {row[k]:.6f}, "
                f"characteristic_frequencies gives {fq.hz()[k]:.6f}")
    # the CWRU orders (docs/reference-data.md, alpha = 0): BPFI 5.4152, 2 BSF 4.7135, within 1 %
    # (the dataset bearing has clearance and a load-dependent contact angle near 0)
    for k, order in (("bpfi_Hz", 5.4152), ("bsf_Hz", 4.7135 / 2)):
        got = lab[k] / lab["shaft_Hz"]
        assert np.all(np.abs(got / order - 1) < 0.01), f"{k} / shaft_Hz: expected ~{order}, got {got}"
    # healthy items carry only the noise floor (the spec's noise_rms_m_s2, 0.71 m/s^2 RMS, less
    # above the 6 kHz Nyquist frequency of this 12 kHz run); every defect item rings at its
    # impacts, well above it (at least 4x the noise RMS)
    noise = spec.dynamics_settings()["noise_rms"]
    rms = sig.astype(float).std(axis=1)
    assert np.all(rms[h] < 1.1 * noise), f"healthy items: expected <= {noise:.2f} m/s^2 RMS (noise), got {rms[h]}"
    assert np.all(rms[~h] > 4.0 * noise), f"defect items: expected RMS well above the noise, got {rms[~h]}"
