"""Dynamic layer (MODEL.md section 7): equilibrium, quasi-static limit, impulses at BPFO."""
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.signal as ss

import bearingsim as bs
from bearingsim import dynamics as dyn
from bearingsim.case import load_case
from bearingsim.signal import envelope_spectrum, peak_frequency, squared_envelope
from bearingsim.sweep import sweep

CASES = Path(__file__).resolve().parent.parent / "cases"
CWRU_BPFO_MULT = 3.5848


@pytest.fixture(scope="module")
def cwru():
    c = load_case(CASES / "cwru_6205.toml")
    return c, c.bearing(), c.operation(), c.loads(), c.spall()


@pytest.fixture(scope="module")
def cwru_run(cwru):
    """0.3 s of the CWRU 6205 with the 0.021 in spall, cage half a pitch before the spall."""
    c, b, op, F, sp = cwru
    d = c.dynamics_settings()
    theta0 = -np.pi / b.n_balls
    return dyn.simulate(b, op, F, sp, dyn.DynamicsParameters.from_settings(d), 0.3, 48000.0,
                        theta0=theta0, rtol=1e-5, atol=1e-5, progress=False)


def test_healthy_stays_at_quasi_static_equilibrium():
    """Pure thrust, no spall, no unbalance: every ball is identical at every instant, the
    quasi-static state is an exact equilibrium of the dynamic model, nothing moves."""
    c = load_case(CASES / "harris218_thrust.toml")
    b, op, F = c.bearing(), c.operation(), c.loads()
    r = dyn.simulate(b, op, F, None, dyn.DynamicsParameters(), 0.004, 20000.0, progress=False)
    assert r.result == 0
    qs = r.quasi_static
    Qo = np.asarray(r.Q_outer)
    Qi = np.asarray(r.Q_inner)
    assert np.max(np.abs(Qo - np.asarray(qs.Q_outer)[None])) <= 1e-3 * np.max(qs.Q_outer)
    assert np.max(np.abs(Qi - np.asarray(qs.Q_inner)[None])) <= 1e-3 * np.max(qs.Q_inner)
    dz = np.asarray(r.ring_displacement)[:, 2] - float(qs.displacement[2])
    assert np.max(np.abs(dz)) <= 1e-3 * abs(float(qs.displacement[2]))
    assert np.max(np.abs(np.asarray(r.sensor_acceleration))) < 1e-6


def test_slow_heavily_damped_follows_quasi_static_sweep(cwru):
    """6 rpm, a ball crossing a ball-path spall, heavy contact damping: the dynamic ball
    loads follow the quasi-static sweep at the same cage angles."""
    c, b, _, F, sp = cwru
    op = bs.Operation.from_rpm(6.0)
    spall = bs.Spall(sp.center, sp.extent, sp.depth, "ball-path")
    p = dyn.DynamicsParameters(contact_damping_ratio=0.7, housing_damping=2e4)
    theta0 = float(sp.center) - 0.9 * float(sp.extent)
    sol = bs.solve(b, op, F, theta0, spall)
    dur = 1.8 * float(sp.extent) / float(sol.cage_speed)
    r = dyn.simulate(b, op, F, spall, p, dur, 2000.0 / dur, theta0=theta0, rtol=1e-6, atol=1e-6,
                     progress=False)
    assert r.result == 0
    ref = sweep(b, op, F, spall, angles=np.asarray(r.cage_angle))
    assert np.all(np.asarray(ref.result) == 0)
    Qo, Qref = np.asarray(r.Q_outer), np.asarray(ref.Q_outer)
    err = np.max(np.abs(Qo - Qref)) / np.max(Qref)
    print("max relative ball-load difference dynamic vs sweep", err)
    assert err < 0.03, err
    # the ball over the spall really sheds load (the check is not trivial)
    assert Qref[:, 0].min() < 0.8 * Qref[:, 0].max()


def test_one_impulse_per_spall_pass(cwru, cwru_run):
    r = cwru_run
    fs = 48000.0
    t = np.asarray(r.time)
    band = (2625.0, 3375.0)
    env = squared_envelope(np.asarray(r.sensor_acceleration), fs, band)
    env = env - env.min()
    bpfo = r.frequencies["bpfo_Hz"]
    peaks, _ = ss.find_peaks(env, height=0.2 * env.max(), distance=int(0.6 * fs / bpfo))
    passes = r.pass_times[(r.pass_times > 0.0) & (r.pass_times < t[-1] - 2e-3)]
    assert len(passes) >= 30
    assert len(peaks) == len(passes)
    # each impulse follows its pass within a millisecond or two
    lag = t[peaks] - passes
    assert np.all((lag > -1e-3) & (lag < 3e-3)), lag


def test_envelope_peak_at_bpfo(cwru_run):
    r = cwru_run
    es = envelope_spectrum(np.asarray(r.sensor_acceleration), 48000.0, band=(2625.0, 3375.0))
    bpfo = r.frequencies["bpfo_Hz"]
    fp = peak_frequency(es, bpfo, rel_window=0.05)
    assert abs(fp - bpfo) / bpfo < 5e-3, (fp, bpfo)


def test_reported_bpfo_matches_cwru(cwru_run):
    fr = cwru_run.frequencies
    assert fr["shaft_Hz"] == pytest.approx(1797 / 60)
    ratio = fr["bpfo_Hz"] / fr["shaft_Hz"]
    # quasi-static cage speed at the loaded contact angle vs the alpha = 0 CWRU multiplier
    assert ratio == pytest.approx(CWRU_BPFO_MULT, rel=0.02)
    assert fr["bpfo_Hz"] == pytest.approx(9 * fr["ftf_Hz"])


def test_cli_simulate_and_spectrum(tmp_path, capsys):
    from bearingsim.cli import main

    text = (CASES / "cwru_6205.toml").read_text()
    text = text.replace("cage_angle_deg = 0.0", "cage_angle_deg = -20.0")
    text = text.replace("duration_s = 1.0", "duration_s = 0.3\nrtol = 1e-5\natol = 1e-5")
    case = tmp_path / "cwru.toml"
    case.write_text(text)
    out = tmp_path / "sim.h5"
    assert main(["simulate", str(case), "-o", str(out), "--plot", str(tmp_path / "plots")]) == 0
    with h5py.File(out) as f:
        g = f["dynamics"]
        T = g["time"].shape[0]
        assert T == 14400
        assert g["ring_displacement"].shape == (T, 3)
        assert g["housing_acceleration"].shape == (T, 2)
        assert g["sensor_acceleration"].shape == (T,)
        for k in ("Q_inner", "Q_outer", "alpha_inner", "alpha_outer"):
            assert g[k].shape == (T, 9)
        for k in g:
            assert "units" in g[k].attrs
        for k in ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz"):
            assert k in g.attrs
        assert "bearingsim_version" in f.attrs and "case_toml" in f.attrs
    for name in ("sensor_acceleration.png", "sensor_acceleration_zoom.png", "ball_loads.png",
                 "envelope_spectrum.png"):
        assert (tmp_path / "plots" / name).is_file()
    capsys.readouterr()
    assert main(["spectrum", str(out)]) == 0
    txt = capsys.readouterr().out
    assert "relative difference" in txt


def test_cli_compare_static_vs_dynamic(tmp_path, capsys):
    """compare: the quasi-static sweep at the dynamic run's cage angles, with a table of peaks
    and dynamic amplification; the dynamic peak load exceeds the quasi-static one (impacts)."""
    from bearingsim import cli

    text = (CASES / "cwru_6205.toml").read_text()
    text = text.replace("duration_s = 1.0", "duration_s = 0.02")
    assert "duration_s = 0.02" in text
    case = tmp_path / "c.toml"
    case.write_text(text)
    assert cli.main(["compare", str(case), "--plot", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "max Q_outer" in out and "dynamic / static" in out
    c = load_case(case)
    res, idx, qs, rows = cli.compare_static_dynamic(c)
    assert np.all(np.asarray(qs.result) == 0)
    row = {r[0]: r for r in rows}
    qs_peak, dyn_peak, amp = row["max Q_outer"][2:]
    assert dyn_peak > qs_peak and amp == pytest.approx(dyn_peak / qs_peak)
    assert np.isnan(row["max alpha_outer"][4])          # alpha ~ 0 in a deep groove: no ratio
    assert (tmp_path / "compare.png").stat().st_size > 10000
