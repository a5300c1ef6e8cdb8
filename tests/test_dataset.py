"""bearingsim dataset: [dataset] schema rows, label draw, HDF5 layout, reproducibility, labels vs signals."""
import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from bearingsim.signals import background as bgm
from bearingsim.case import CaseError, load_case, parse_case, schema_reference_markdown
from bearingsim.app.cli import main
from bearingsim.datasets import LABEL_FIELDS, draw_labels, make_dataset
from bearingsim.errors import NotConvergedError
from bearingsim.app.signal_workflows import dataset_case, envelope_band
from bearingsim.signals.envelope import envelope_spectrum, peak_frequency

ROOT = Path(__file__).resolve().parent.parent
CWRU = (ROOT / "tests" / "data" / "cwru_like_6205.toml").read_text()      # fixed, not calibrated


def spec(duration=0.02, extra=""):
    return parse_case((CWRU + f"""
[dataset]
count = 6
chunk = 4
seed = 7
duration_s = {duration}
healthy_fraction = 0.34
speed_rpm = [1720, 1800]
radial_N = [500, 2000]
spall_length_mm = [0.3, 1.0]
spall_depth_mm = [0.2794, 0.2794]
spall_center_deg = [0, 0]
{extra}""").replace("sample_rate_Hz = 48000", "sample_rate_Hz = 24000"), "spec.toml")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("ds")
    case = spec()
    s1 = make_dataset(case, d / "a.h5", progress=False)
    s2 = make_dataset(case, d / "b.h5", progress=False)
    return case, d / "a.h5", d / "b.h5", s1, s2


def test_layout(files):
    case, a, _, s, _ = files
    assert s.count == 6 and s.samples == 480 and s.failed == 0
    assert [p.name for p in a.parent.iterdir() if p.name.startswith(".")] == []  # no temp files left
    with h5py.File(a, "r") as f:
        sig, t, lab = f["signals"], f["time"], f["labels"]
        assert sig.shape == (6, 480) and sig.dtype == np.float32 and sig.chunks == (1, 480)
        assert sig.compression is None and sig.attrs["units"] == "m/s^2"
        assert t.shape == (480,) and t.attrs["units"] == "s"
        assert np.isclose(t[1] - t[0], 1 / 24000)
        assert lab.shape == (6,) and list(lab.dtype.names) == list(LABEL_FIELDS)
        assert json.loads(lab.attrs["field_units"])["spall_length_mm"] == "mm"
        assert "units" in lab.attrs
        assert f.attrs["seed"] == 7 and f.attrs["case_toml"] == case.text
        assert "bearingsim_version" in f.attrs
        L = lab[()]
        assert np.all(np.isfinite(sig[()]))
    assert list(L["index"]) == list(range(6))
    assert list(L["healthy"]) == [True, True, False, False, False, False]   # round(0.34 * 6) = 2
    assert np.all(L["result"] == 0)
    assert np.all(L["spall_depth_mm"][:2] == 0) and np.all(L["spall_length_mm"][:2] == 0)
    assert np.all(L["spall_depth_mm"][2:] == 0.2794)
    assert np.all((L["spall_length_mm"][2:] >= 0.3) & (L["spall_length_mm"][2:] <= 1.0))
    assert np.all((L["speed_rpm"] >= 1720) & (L["speed_rpm"] <= 1800))
    assert np.all((L["radial_N"] >= 500) & (L["radial_N"] <= 2000)) and np.all(L["axial_N"] == 0)
    assert np.allclose(L["shaft_Hz"], L["speed_rpm"] / 60)
    assert np.allclose(L["bpfo_Hz"], 9 * L["ftf_Hz"])
    assert np.all((L["bpfo_Hz"] > 95) & (L["bpfo_Hz"] < 115))   # ~3.58 x shaft for the 6205


def test_reproducible(files):
    case, a, b, _, _ = files
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        assert np.array_equal(fa["signals"][()], fb["signals"][()])
        assert fa["labels"][()].tobytes() == fb["labels"][()].tobytes()
    assert draw_labels(case).tobytes() == draw_labels(case).tobytes()
    other = draw_labels(spec(extra="").with_value("dataset.seed", 8))
    assert not np.array_equal(other["speed_rpm"], draw_labels(case)["speed_rpm"])


def test_labels_match_signals(files):
    _, a, _, _, _ = files
    with h5py.File(a, "r") as f:
        x, L = f["signals"][()], f["labels"][()]
    rms = x.std(axis=1)
    assert rms[L["healthy"]].max() < 0.05 * rms[~L["healthy"]].min(), rms


def test_envelope_peak_at_labelled_bpfo(tmp_path):
    case = spec(duration=0.05)
    make_dataset(case, tmp_path / "e.h5", progress=False)
    with h5py.File(tmp_path / "e.h5", "r") as f:
        x, L, t = f["signals"][()], f["labels"][()], f["time"][()]
    fs = 1.0 / (t[1] - t[0])
    band = envelope_band(fs, case.dynamics_settings()["resonance_frequency"])
    for i in np.flatnonzero(~L["healthy"]):
        es = envelope_spectrum(x[i].astype(float), fs, band=band)
        fp = peak_frequency(es, L["bpfo_Hz"][i], rel_window=0.1)
        assert abs(fp - L["bpfo_Hz"][i]) / L["bpfo_Hz"][i] < 0.03, (i, fp, L["bpfo_Hz"][i])


@pytest.mark.parametrize("row, key, what", [
    ("count = 0", "dataset.count", "out of range"),
    ("chunk = 1.5", "dataset.chunk", "wrong type"),
    ("healthy_fraction = 1.5", "dataset.healthy_fraction", "out of range"),
    ("speed_rpm = [1800, 1700]", "dataset.speed_rpm", "min > max"),
    ("radial_N = [500]", "dataset.radial_N", "exactly two elements"),
    ("radial_N = [500, 1000, 2000]", "dataset.radial_N", "exactly two elements"),
    ("axial_N = [0, \"a\"]", "dataset.axial_N", "two finite numbers"),
    ("axial_N = 5.0", "dataset.axial_N", "wrong type"),
    ("spall_length_mm = [0, 1]", "dataset.spall_length_mm", "out of range"),
    ("spall_depth_mm = [0.1, 9.0]", "dataset.spall_depth_mm", "less than bearing.ball_diameter_mm"),
    ("spall_length_mm = [0.5, 30.0]", "dataset.spall_length_mm", "ball pitch"),
    ("inner_fraction = 0.5\nball_fraction = 0.5", "dataset.healthy_fraction", "add up to 1"),
    ("outer_fraction = 0.5", "dataset.healthy_fraction", "add up to 1"),
    ("ball_fraction = -0.1", "dataset.ball_fraction", "out of range"),
    ("inner_fraction = 0.2\ninner_length_mm = [0.2, 20.0]", "dataset.inner_length_mm", "inner raceway"),
    ("ball_fraction = 0.2\nball_length_mm = [0.2, 14.0]", "dataset.ball_length_mm", "half the ball"),
    ("ball_fraction = 0.2\nball_depth_mm = [0.1, 9.0]", "dataset.ball_depth_mm", "less than bearing.ball_diameter_mm"),
    ("inner_fraction = 0.2\ninner_center_deg = [0, 400]", "dataset.inner_center_deg", "out of range"),
])
def test_bad_dataset_input(row, key, what):
    with pytest.raises(CaseError) as e:
        parse_case(CWRU + "\n[dataset]\ncount = 4\n" * (not row.startswith("count")) +
                   ("\n[dataset]\n" if row.startswith("count") else "") + row + "\n", "s.toml")
    assert len(e.value.problems) == 1, e.value.problems
    assert key in str(e.value) and what in str(e.value)


def test_dataset_defaults_and_requirements():
    c = parse_case(CWRU + "\n[dataset]\ncount = 4\n")
    ds = c.data["dataset"]
    assert ds["speed_rpm"] == [1797.0, 1797.0] and ds["radial_N"] == [1000.0, 1000.0]
    assert ds["spall_length_mm"] == [0.5334, 0.5334] and ds["chunk"] == 16 and ds["seed"] == 0
    assert ds["duration_s"] == 0.1 and ds["healthy_fraction"] == 0.2
    si = c.dataset_settings()
    assert np.isclose(si["speed"][0], 1797 * 2 * np.pi / 60) and np.isclose(si["spall_length"][1], 0.5334e-3)
    no_defect = CWRU.split("[defect]")[0] + "[dataset]\ncount = 4\n"
    with pytest.raises(CaseError) as e:
        parse_case(no_defect, "s.toml")
    assert "dataset.spall_length_mm" in str(e.value) and "dataset.spall_depth_mm" in str(e.value)
    with pytest.raises(CaseError, match="both allow 0"):
        parse_case(CWRU + "\n[dataset]\ncount = 4\nradial_N = [0, 10]\n")
    assert "## [dataset]" in schema_reference_markdown()
    assert parse_case(CWRU).dataset_settings() is None


def test_shipped_spec_is_valid():
    c = load_case(ROOT / "cases" / "dataset_cwru.toml")
    assert c.data["dataset"]["count"] == 1000 and c.data["dataset"]["chunk"] == 16


def test_failed_items_are_zero_and_flagged(tmp_path, monkeypatch):
    """A failed item (result != 0) or a non-finite signal is written as zeros with result != 0."""
    import jax.numpy as jnp

    import bearingsim.datasets as dsm
    import bearingsim.dynamics as dyn

    class FakeProgram:
        calls = 0

        def __call__(self, keys, speed_rpm, *a, **kw):
            n = speed_rpm.shape[0]
            x = np.ones((n, 480))
            x[[0, 3], 5] = np.nan              # items in slots 0 and 3: non-finite signal
            code = np.zeros(n, np.int32)
            code[[1, 4]] = 1                   # slots 1 and 4: max steps reached
            x[[1, 4]] = np.nan
            z = jnp.zeros(n)
            return dict(sensor=jnp.asarray(x), housing_acceleration=jnp.asarray(x), result=jnp.asarray(code),
                        pass_times=jnp.full((n, 1), 1e-3), pass_jitter_percent=z, shaft_Hz=z + 30.0,
                        ftf_Hz=z + 1.0, bpfo_Hz=z + 10.0, bpfi_Hz=z + 12.0, bsf_Hz=jnp.full(n, jnp.nan),
                        pit_depth=z, unbridged=z, pit_ok=jnp.ones(n, bool), ball_iterations=1)

    monkeypatch.setattr(dyn, "chunk_program", lambda *a, **kw: FakeProgram())
    monkeypatch.setattr(dsm.runner, "run_settings", lambda *a: 1)
    monkeypatch.setitem(dsm.program.MICRO_BATCH, "cpu", 8)     # the 6 items in one micro-batch: slots 0-4 are items 0-4
    with pytest.raises(NotConvergedError, match="spec.toml: 4 of 6 items of the data set failed"):
        dataset_case(spec(), tmp_path / "f.h5")
    s = dataset_case(spec(), tmp_path / "f.h5", throw=False)
    assert s.failed == 4 and s.failures == {1: 2, int(dsm.DatasetResult.nonfinite_signal): 2}
    with h5py.File(tmp_path / "f.h5", "r") as f:
        x, L = f["signals"][()], f["labels"][()]
    bad = L["result"] != 0
    assert bad.sum() == 4 and set(L["result"][bad]) == {1, int(dsm.DatasetResult.nonfinite_signal)}
    assert np.all(x[bad] == 0) and np.all(x[~bad] == 1)
    assert np.all(np.isfinite(L["bpfo_Hz"])) and np.all(L["bpfo_Hz"][bad] == 0) and np.all(L["bpfo_Hz"][~bad] == 10)
    assert np.all(L["bsf_Hz"] == 0)


def _interrupting(monkeypatch, at_call, how):
    """device_program that stops the run (Ctrl-C or SIGTERM to this process) at its call
    number ``at_call`` (one call per chunk); the 6-item spec at chunk 4 (the CPU micro-batch
    width): two chunks, 4 and 2 items (the programs of the other tests of the spec:
    a width of its own compiled three more, ~20 s of the suite on 2 cores)."""
    import os
    import signal

    import bearingsim.datasets as dsm

    monkeypatch.setenv("BEARINGSIM_THREADS", "1")      # chunks in order: "call 2" is chunk 1's
    real = dsm.program.device_program
    calls = []

    def batch(*a, **kw):
        calls.append(1)
        if len(calls) == at_call:
            if how == "SIGTERM":
                os.kill(os.getpid(), signal.SIGTERM)
            raise KeyboardInterrupt
        return real(*a, **kw)

    monkeypatch.setattr(dsm.program, "device_program", batch)
    return calls


@pytest.mark.parametrize("how", ["SIGINT", "SIGTERM"])
def test_interrupted_run_resumes_to_the_same_file(files, tmp_path, monkeypatch, how):
    """An interrupted run keeps its finished chunk, leaves no temporary file, says so in one
    line; running again continues and gives a file bit-identical to an uninterrupted run."""
    from bearingsim.datasets import Interrupted, partial_path

    case, a, _, _, _ = files
    out = tmp_path / "r.h5"
    _interrupting(monkeypatch, 2, how)
    with pytest.raises(Interrupted) as e:
        make_dataset(case, out, progress=False)
    msg = str(e.value)
    assert "\n" not in msg and how in msg and "4 of 6 items finished" in msg and e.value.exit_code == 130
    assert not out.exists()
    kept = sorted(p.name for p in partial_path(out).iterdir())
    assert kept == ["chunk_000000", "spec.json"]
    assert not [p for p in tmp_path.rglob("*") if p.name.endswith(".tmp")]
    monkeypatch.undo()
    calls = _interrupting(monkeypatch, 99, how)
    s = make_dataset(case, out, progress=False)
    assert len(calls) == 1 and s.count == 6 and s.failed == 0     # only the missing chunk ran
    assert not partial_path(out).exists()
    ref = make_dataset(case, tmp_path / "ref.h5", progress=False)     # uninterrupted, the same width
    assert ref.chunk == 4
    assert out.read_bytes() == (tmp_path / "ref.h5").read_bytes()


def test_partial_folder_of_another_spec_is_refused(files, tmp_path):
    from bearingsim.datasets import partial_path
    from bearingsim.errors import InputError

    case, _, _, _, _ = files
    out = tmp_path / "x.h5"
    partial_path(out).mkdir()
    (partial_path(out) / "spec.json").write_text('{"seed": 123}')
    with pytest.raises(InputError, match="different spec"):
        make_dataset(case, out, progress=False)


def test_cli_interrupt_is_one_line(files, tmp_path, monkeypatch, capsys):
    case, _, _, _, _ = files
    p = tmp_path / "spec.toml"
    p.write_text(case.text)
    _interrupting(monkeypatch, 1, "SIGTERM")
    assert main(["dataset", str(p), "-o", str(tmp_path / "c.h5")]) == 130
    err = capsys.readouterr().err.strip()
    # stopped in the first chunk: nothing to continue from, so nothing is kept
    assert len(err.splitlines()) == 1 and "SIGTERM" in err and "nothing written" in err
    assert "Traceback" not in err and sorted(q.name for q in tmp_path.iterdir()) == ["spec.toml"]


def test_realism_labels(tmp_path):
    """Slip, speed fluctuation and noise from [dynamics] are in the signals and the labels."""
    case = spec(extra="").with_value("dynamics.slip_percent", 1.5).with_value(
        "dynamics.noise_rms_m_s2", 0.7)
    make_dataset(case, tmp_path / "n.h5", progress=False)
    with h5py.File(tmp_path / "n.h5", "r") as f:
        x, L = f["signals"][()], f["labels"][()]
    assert np.all(L["slip_percent"] == 1.5) and np.all(L["noise_rms_m_s2"] == 0.7)
    assert len(set(L["realism_seed"])) == 6
    assert np.all(x[L["healthy"]].std(axis=1) == pytest.approx(0.7, rel=0.02))  # noise only
    assert np.all(L["pass_jitter_percent"] > 0)          # each item's own slip draws


def test_pit_depth_rule_reproduces_the_calibrated_depths(tmp_path):
    """depth_rule = "pit": each fault item enters the simulation with the effective depth of a
    round EDM pit at its own speed and loads, computed inside the chunk program.  Items at the
    calibrated CWRU operating point (1797 rpm, 100 N radial, 43.7 N axial) with the 0.007 and
    0.021 in pits get the depths that docs/calibrate_cwru.py wrote into
    cases/cwru_6205_or007.toml and cwru_6205.toml (stage B, 4 significant digits: rel 1e-3); the
    data set's batched healthy solve and the single solve of realism.pit_effective_depth are
    independent routes to the same contact.  The unbridged fraction is 1 - 2b/w with b from the
    single healthy solve (1e-9).  The machined rule keeps the drawn depth and takes the same
    unbridged fractions (the pass variability's scale), also from inside the program."""
    import h5py

    from bearingsim.realism import rig_record as rl
    from bearingsim.app.signal_workflows import dataset_case

    spec = load_case(ROOT / "cases" / "dataset_cwru.toml")
    for k, v in {"dataset.count": 1, "dataset.chunk": 1, "dataset.healthy_fraction": 0.0,
                 "dataset.speed_rpm": [1797, 1797], "dataset.radial_N": [100, 100],
                 "dataset.axial_N": [43.7, 43.7], "dataset.duration_s": 0.02,
                 "dynamics.sample_rate_Hz": 12000}.items():
        spec = spec.with_value(k, v)
    want = [load_case(ROOT / "cases" / n).spall().depth for n in ("cwru_6205_or007.toml", "cwru_6205.toml")]
    cal = load_case(ROOT / "cases" / "cwru_6205.toml")
    b = rl.contact_at(cal.bearing(), cal.operation(), cal.loads(), 0.0).b
    for inch, depth in zip((0.007, 0.021), want):
        mm = inch * 25.4
        one = spec.with_value("dataset.spall_length_mm", [mm, mm])
        labels = {}
        for rule in ("pit", "machined"):
            dataset_case(one.with_value("dataset.depth_rule", rule), tmp_path / f"{rule}.h5")
            with h5py.File(tmp_path / f"{rule}.h5") as f:
                labels[rule] = f["labels"][()]
        P, M = labels["pit"], labels["machined"]
        assert np.all(P["result"] == 0) and np.all(M["result"] == 0)
        np.testing.assert_allclose(P["effective_depth_mm"] * 1e-3, depth, rtol=1e-3)
        assert np.all(P["effective_depth_mm"] < 1e-2 * P["spall_depth_mm"])       # far below the machined 0.2794 mm
        np.testing.assert_allclose(P["unbridged_fraction"], 1.0 - 2.0 * b / (mm * 1e-3), rtol=1e-9)
        assert np.array_equal(M["effective_depth_mm"], M["spall_depth_mm"])
        np.testing.assert_allclose(M["unbridged_fraction"], P["unbridged_fraction"], rtol=1e-12)


def test_the_four_class_spec_is_domain_randomised():
    """The ML spec keeps of the rig's calibration only the slip and the pass-to-pass variability
    (docs/calibrate_cwru.py --write keeps them in step); its transfer paths, levels and
    background are drawn per item (docs/realism.md), around the calibrated point."""
    spec, cal = load_case(ROOT / "cases" / "dataset_cwru_4class.toml"), load_case(ROOT / "cases" / "cwru_6205.toml")
    a, b = spec.dynamics_settings(), cal.dynamics_settings()
    for k in ("slip_percent", "pass_amplitude_cv_max_percent", "pass_delay_sd_max_percent"):
        assert a[k] == b[k], k
    assert a["noise_rms"] == 0.0 and spec.data["bearing"] == cal.data["bearing"]
    ds = spec.data["dataset"]
    assert ds["depth_rule"] == "pit" and ds["background"] == "random" and "fault_snr_dB" in ds
    lo, hi = ds["resonance_frequency_Hz"]          # the calibrated modes lie inside the ranges
    assert all(lo <= f <= hi for f in b["resonance_frequencies"])
    lo, hi = ds["background_rms_m_s2"]
    assert lo <= b["noise_rms"] <= hi
    assert ds["radial_N"][0] <= cal.data["load"]["radial_x_N"] <= ds["radial_N"][1]


@pytest.mark.parametrize("name", ["dataset_cwru.toml"])
def test_shipped_specs_share_the_calibrated_structure(name):
    """The CWRU data set specs carry the calibrated sensor modes, contact damping, slip, noise,
    pass-to-pass variability, geometry and clearance of cases/cwru_6205.toml (docs/calibrate_cwru.py --write keeps them in
    step) and the pit depth rule."""
    spec, cal = load_case(ROOT / "cases" / name), load_case(ROOT / "cases" / "cwru_6205.toml")
    a, b = spec.dynamics_settings(), cal.dynamics_settings()
    for k in ("resonance_frequencies", "resonance_damping_ratios", "resonance_gains", "noise_band"):
        assert np.array_equal(np.asarray(a[k]), np.asarray(b[k])), k
    for k in ("contact_damping_ratio", "slip_percent", "speed_fluctuation_percent", "noise_rms",
              "pass_amplitude_cv_max_percent", "pass_delay_sd_max_percent"):
        assert a[k] == b[k], k
    assert spec.data["bearing"] == cal.data["bearing"]
    assert spec.data["dataset"]["depth_rule"] == "pit"


def test_dataset_items_carry_the_pass_to_pass_variability_of_a_single_run(tmp_path):
    """The shipped CWRU spec applies the calibrated pass-to-pass variability to every fault item
    (scaled by the unbridged fraction of its pit, drawn on the device from the item's key).  With
    the variability and the measurement noise off, an item at the calibrated operating point with the 0.021 in pit equals,
    to float32 storage (rel 1e-6 of its peak), the single simulation of that pit with the item's
    key (``simulate(key=)``: the same motion), depth, Newton steps and substeps (full ball solve);
    with it on, the item differs from that run by more than 10 % of the peak and its labels carry
    the calibrated maxima x the unbridged fraction.  (The variability's own random numbers come
    from the signal stage's streams, bearingsim.keys.STREAMS, not NumPy's: data set version 5.)"""
    from bearingsim import dynamics as dyn
    from bearingsim.datasets import chunk_keys
    from bearingsim.physics.defect import Spall

    spec = load_case(ROOT / "cases" / "dataset_cwru.toml")
    for k, v in {"dataset.count": 2, "dataset.chunk": 2, "dataset.healthy_fraction": 0.0,
                 "dataset.speed_rpm": [1797, 1797], "dataset.radial_N": [100, 100],
                 "dataset.axial_N": [43.7, 43.7], "dataset.spall_length_mm": [0.5334, 0.5334],
                 "dataset.duration_s": 0.04, "dynamics.sample_rate_Hz": 12000}.items():
        spec = spec.with_value(k, v)
    off = spec.with_value("dynamics.pass_amplitude_cv_max_percent", 0.0).with_value(
        "dynamics.pass_delay_sd_max_percent", 0.0).with_value("dynamics.noise_rms_m_s2", 0.0)
    dataset_case(spec, tmp_path / "v.h5")
    dataset_case(off, tmp_path / "o.h5")
    with h5py.File(tmp_path / "v.h5") as f, h5py.File(tmp_path / "o.h5") as g:
        X, L, X0 = f["signals"][()], f["labels"][()], g["signals"][()]
        it, sub = int(g.attrs["ball_iterations"]), int(g.attrs["substeps"])
    assert np.all(L["result"] == 0) and np.all(L["unbridged_fraction"] > 0.5)
    np.testing.assert_allclose(L["pass_delay_sd_percent"], 9.089 * L["unbridged_fraction"], rtol=1e-12)
    np.testing.assert_allclose(L["pass_amplitude_cv_percent"], 2.334 * L["unbridged_fraction"], rtol=1e-12)
    cal = load_case(ROOT / "cases" / "cwru_6205.toml")
    b, d = cal.bearing(), cal.dynamics_settings()
    on = dyn.Realism.from_settings(d)
    i = 1
    sp = Spall.from_length(b, 0.0, 0.5334e-3, L["effective_depth_mm"][i] * 1e-3, "rectangular", "outer")
    r0 = dyn.simulate(b, cal.operation(), cal.loads(), sp, dyn.DynamicsParameters.from_settings(d), 0.04, 12000.0,
                      realism=on._replace(pass_amplitude_cv_max_percent=0.0, pass_delay_sd_max_percent=0.0,
                                          noise_rms=0.0),
                      key=chunk_keys(L["key"][i:i + 1])[0], ball_iterations=it, substeps=sub, ball_solver="full",
                      record_balls=False)
    peak = np.abs(X0[i]).max()
    np.testing.assert_allclose(X0[i], r0.sensor_acceleration, rtol=0, atol=1e-6 * peak)
    assert np.abs(X[i] - r0.sensor_acceleration).max() > 0.1 * peak


# ------------------------------------------------------------------ domain randomisation (issue 20)
RANDOMISED = """
signal_gain = [2.0, 2.0]
background = "random"
background_rms_m_s2 = [0.5, 0.5]
resonance_frequency_Hz = [2000, 4000]
resonance_damping_ratio = [0.02, 0.05]
resonance_gain = [0.5, 2.0]
outer_center_positions_deg = [0, 90, 180]
split_fractions = [0.5, 0.25, 0.25]
"""


def test_randomised_labels_are_drawn_apart_from_the_old_ones():
    from bearingsim.datasets import transfer_paths
    base, rnd = draw_labels(spec()), draw_labels(spec(extra=RANDOMISED))
    same = [k for k in LABEL_FIELDS if k not in ("spall_center_deg", "signal_gain", "split")]
    for k in same:                       # the draws every spec made before stay what they were
        assert np.array_equal(base[k], rnd[k]), k
    outer = rnd["fault_class"] == 1
    assert set(rnd["spall_center_deg"][outer]) <= {0.0, 90.0, 180.0}
    assert np.all(rnd["signal_gain"] == 2.0) and np.all(base["signal_gain"] == 1.0)
    assert np.all(rnd["strike_probability"] == 1.0)
    for c in range(2):                    # every class split per item: train first, by fractions
        parts = np.bincount(rnd["split"][rnd["fault_class"] == c], minlength=3)
        n = parts.sum()
        assert parts[0] == int(np.round(0.5 * n))
    tp = transfer_paths(spec(extra=RANDOMISED), rnd)
    assert tp.shape == (6, 1, 3)
    assert np.all((tp[..., 0] >= 2000) & (tp[..., 0] <= 4000))
    assert np.all((tp[..., 1] >= 0.02) & (tp[..., 1] <= 0.05)) and np.all((tp[..., 2] >= 0.5) & (tp[..., 2] <= 2.0))
    fixed = transfer_paths(spec(), base)  # no ranges: the [dynamics] modes for every item
    assert np.all(fixed == fixed[:1])


def test_signal_gain_and_background_enter_the_signals_exactly(files, tmp_path):
    case, a, *_ = files
    # gain 2, background off: exactly twice the signals of the gain-1 data set (float32 rounding)
    s2 = make_dataset(spec(extra="signal_gain = [2.0, 2.0]\n"), tmp_path / "g2.h5", progress=False)
    assert s2.failed == 0
    with h5py.File(a, "r") as f1, h5py.File(tmp_path / "g2.h5", "r") as f2:
        x1, x2 = f1["signals"][()].astype(float), f2["signals"][()].astype(float)
        assert np.allclose(x2, 2.0 * x1, rtol=2e-7, atol=1e-7 * np.abs(x1).max())
    # background: the difference to the gain-2 data set is each item's drawn background
    s3 = make_dataset(spec(extra='signal_gain = [2.0, 2.0]\nbackground = "random"\n'
                          'background_rms_m_s2 = [0.5, 0.5]\n'), tmp_path / "bg.h5", progress=False)
    assert s3.failed == 0
    with h5py.File(tmp_path / "bg.h5", "r") as f3:
        x3 = f3["signals"][()].astype(float)
        lab = f3["labels"][()]
        fs = float(f3.attrs["sample_rate_Hz"])
    # each item's background: the signal stage's draw from its key's "background" stream
    import jax

    from bearingsim.signals import signal_stage as ss
    from bearingsim.datasets import Physics, chunk_keys, signal_settings
    bsc = spec(extra='signal_gain = [2.0, 2.0]\nbackground = "random"\nbackground_rms_m_s2 = [0.5, 0.5]\n').build()
    st = signal_settings(bsc, bsc.dataset, fs, x3.shape[1], Physics.of_scenario(bsc))
    keys = chunk_keys(lab["key"])

    @jax.jit                    # one program, not one per operation (eager: ~250 programs)
    def background(key, shaft_hz):
        kb = jax.random.split(ss.stream_key(key, "background"))
        return bgm.background_record(kb[1], bgm.draw_background(kb[0], fs, st.ranges), x3.shape[1], fs, shaft_hz,
                                     st.knock_max)

    for i in range(6):
        want = np.asarray(background(jax.numpy.asarray(keys[i]), lab["speed_rpm"][i] / 60.0))
        assert np.allclose(x3[i] - x2[i], want, atol=3e-6 * max(1.0, np.abs(x3[i]).max()))
        assert lab["background_noise_rms_m_s2"][i] == pytest.approx(0.5)


# ----------------------------------------------------------------- the ML reader (bearingsim.datasets.mldata)
def test_load_dataset_reads_arrays_labels_and_metadata(files, tmp_path):
    import bearingsim
    from bearingsim.datasets import CLASSES, SPLITS
    from bearingsim.datasets.mldata import SPLITS as READER_SPLITS

    _, a, _, _, _ = files
    X, L, meta = bearingsim.load_dataset(a)
    with h5py.File(a, "r") as f:
        assert np.array_equal(X, f["signals"][()]) and L.tobytes() == f["labels"][()].tobytes()
    assert X.dtype == np.float32 and X.shape == (6, 480)
    assert meta["sample_rate_Hz"] == 24000.0 and meta["duration_s"] == pytest.approx(0.02)
    assert meta["class_names"] == list(CLASSES) and isinstance(meta["class_names"], list)
    assert READER_SPLITS == SPLITS and meta["split_names"] == list(SPLITS)
    assert meta["field_units"]["speed_rpm"] == "rpm" and meta["signal_units"] == "m/s^2"
    assert meta["count"] == 6 and meta["seed"] == 7 and meta["failed_dropped"] == 0
    # the splits partition the items: every item in exactly one, the rows are the file's rows
    parts = [bearingsim.load_dataset(a, split=s) for s in SPLITS]
    rows = np.concatenate([m["rows"] for _, _, m in parts])
    assert sorted(rows) == list(range(6))
    for code, (x, lab, m) in enumerate(parts):
        assert np.all(lab["split"] == code) and np.array_equal(x, X[m["rows"]])
    with pytest.raises(bearingsim.InputError, match="split 'val'"):
        bearingsim.load_dataset(a, split="val")
    bad = tmp_path / "x.h5"
    bad.write_text("not hdf5")
    with pytest.raises(bearingsim.InputError, match="not an HDF5 data set"):
        bearingsim.load_dataset(bad)
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = np.zeros(3)
    with pytest.raises(bearingsim.InputError, match="not a bearingsim data set"):
        bearingsim.load_dataset(tmp_path / "other.h5")


def test_load_dataset_leaves_failed_items_out(files, tmp_path):
    import shutil

    from bearingsim import load_dataset

    _, a, _, _, _ = files
    c = tmp_path / "c.h5"
    shutil.copy(a, c)
    with h5py.File(c, "r+") as f:
        lab = f["labels"][()]
        lab["result"][1] = 3
        f["labels"][...] = lab
    X, L, meta = load_dataset(c)
    assert len(X) == 5 and 1 not in L["index"] and meta["failed_dropped"] == 1
    assert len(load_dataset(c, include_failed=True)[0]) == 6


def test_window_dataset_windows_items_of_one_split(files):
    from bearingsim import WindowDataset, load_dataset
    from bearingsim.signals.features import FEATURE_NAMES

    _, a, _, _, _ = files
    X, L, _ = load_dataset(a)
    ds = WindowDataset(a, split=None, window=200, hop=100)
    assert ds.per_item == 3 and len(ds) == 18          # starts 0, 100, 200 (+200 <= 480)
    x, y = ds[4]                                         # item 1, window 1
    assert x.shape == (1, 200) and x.dtype == np.float32 and y == int(L["fault_class"][1])
    assert np.array_equal(x[0], X[1, 100:300])
    assert np.array_equal(ds[-1][0][0], X[5, 200:400])
    with pytest.raises(IndexError):
        ds[18]
    Xw, yw = ds.arrays()
    assert Xw.shape == (18, 200) and np.array_equal(yw, np.repeat(L["fault_class"], 3))
    assert np.array_equal(ds.groups(), np.repeat(L["index"], 3))
    # windows in seconds, and the splits: no item in two of them
    per = {s: WindowDataset(a, split=s, window_s=0.01) for s in ("train", "validation", "test")}
    assert sum(len(d) for d in per.values()) == 12
    seen = [set(d.groups()) for d in per.values()]
    assert not (seen[0] & seen[1] or seen[0] & seen[2] or seen[1] & seen[2])
    # features: window_features of the same windows at each item's labelled shaft speed
    f = WindowDataset(a, split=None, window=480, features=True)
    v, y = f[2]
    assert v.shape == (len(FEATURE_NAMES),) and v.dtype == np.float32 and np.all(np.isfinite(v))
    from bearingsim.case import parse_case
    from bearingsim.signals.features import fault_orders, window_features

    _, _, meta = load_dataset(a)
    ref = window_features(X[2:3].astype(float), 24000.0, L["shaft_Hz"][2],
                          fault_orders(parse_case(meta["case_toml"]).bearing()))[0]
    assert np.allclose(v, ref, rtol=1e-5, atol=1e-4)
    from bearingsim import InputError
    with pytest.raises(InputError, match="window 481 samples"):
        WindowDataset(a, split=None, window=481)


def test_cli_dataset_flags_override_the_spec(monkeypatch, tmp_path, capsys):
    from bearingsim.app import signal_workflows

    seen = []

    class Stop(Exception):
        pass

    def fake(case, out, **kw):
        seen.append(case)
        raise Stop

    monkeypatch.setattr(signal_workflows, "dataset_case", fake)
    p = tmp_path / "spec.toml"
    p.write_text(spec().text)
    with pytest.raises(Stop):
        main(["dataset", str(p), "-o", str(tmp_path / "d.h5"), "--count", "4", "--seed", "11",
              "--duration-s", "0.01", "--sample-rate-Hz", "12000"])
    ds = seen[0].data["dataset"]
    assert (ds["count"], ds["seed"], ds["duration_s"]) == (4, 11, 0.01)
    assert seen[0].dynamics_settings()["sample_rate"] == 12000.0          # issue 34: the records' rate
    assert main(["dataset", str(p), "-o", str(tmp_path / "d.h5"), "--sample-rate-Hz", "0"]) == 2
    assert "--sample-rate-Hz 0" in capsys.readouterr().err
    assert main(["dataset", str(p), "-o", str(tmp_path / "d.h5"), "--count", "0"]) == 2
    assert "--count 0" in capsys.readouterr().err
    assert main(["dataset", str(p), "-o", str(tmp_path / "d.h5"), "--duration-s", "-1"]) == 2
    assert "--duration-s -1" in capsys.readouterr().err


def test_a_fault_that_makes_no_impact_is_excluded_not_rescaled(tmp_path, capsys):
    """fault_snr_dB scales a fault item's bearing signal to a drawn level over the background.  A
    fault item whose defect makes no impact in the record (an outer pit at 12:00, where under a
    radial load with little axial load the ball is off the raceway: effective depth 0; a ball
    pit that strikes none of the record's passes) has only the healthy bearing's signal, and the
    scaling would turn it into a healthy record under a fault label (gains up to 1e8 before).
    Such items are flagged ``fault_not_excited``: zero signal, counted apart from failures (the
    data set does not raise), dropped by load_dataset, named by the CLI.  The depths are checked
    against the independent single healthy solve (realism.pit_effective_depth); the 6:00 items
    of the same run (load-zone centre) are kept.  (A ball pit that struck on no pass:
    tests/test_signal_stage.py, ``struck``.)"""
    from bearingsim import load_dataset
    from bearingsim.datasets import DatasetResult
    from bearingsim.physics.pit import EXCITED_DEPTH_MIN
    from bearingsim.realism import rig_record as rl

    case = load_case(ROOT / "cases" / "dataset_cwru.toml")      # the programs of the pit-depth test above
    for k, v in {"dataset.count": 8, "dataset.chunk": 8, "dataset.healthy_fraction": 0.0,
                 "dataset.speed_rpm": [1797, 1797], "dataset.radial_N": [400, 400], "dataset.axial_N": [10, 10],
                 "dataset.duration_s": 0.02, "dataset.outer_center_positions_deg": [0, 180],
                 "dynamics.sample_rate_Hz": 12000}.items():
        case = case.with_value(k, v)
    s = dataset_case(case, tmp_path / "d.h5")          # throw=True: an excluded item is no failure
    with h5py.File(tmp_path / "d.h5") as f:
        L, X = f["labels"][()], f["signals"][()]
    out = L["result"] == int(DatasetResult.fault_not_excited)
    top, bottom = L["spall_center_deg"] == 180, L["spall_center_deg"] == 0
    assert top.any() and bottom.any() and np.all(top | bottom)
    assert np.array_equal(out, top) and np.all(L["result"][~out] == 0)
    assert np.all(X[out] == 0.0) and np.all(np.abs(X[~out]).max(axis=1) > 0)
    assert s.failed == 0 and s.excluded == int(out.sum()) and s.failures == {int(DatasetResult.fault_not_excited): s.excluded}
    # the independent single solve: the ball at 12:00 carries no load, the one at 6:00 does
    sc = case.with_value("load.radial_x_N", 400.0).with_value("load.axial_N", 10.0)
    w, h = 0.5334e-3, 0.2794e-3
    up = rl.pit_effective_depth(sc.bearing(), sc.operation(), sc.loads(), w, h, center=np.pi)
    down = rl.pit_effective_depth(sc.bearing(), sc.operation(), sc.loads(), w, h, center=0.0)
    assert up.depth < EXCITED_DEPTH_MIN < down.depth
    assert np.all(L["effective_depth_mm"][top] * 1e-3 < EXCITED_DEPTH_MIN)
    assert np.all(L["effective_depth_mm"][bottom] * 1e-3 > 10 * EXCITED_DEPTH_MIN)
    X2, L2, meta = load_dataset(tmp_path / "d.h5")
    assert len(X2) == int((~out).sum()) and meta["failed_dropped"] == int(out.sum())
    # the CLI names them apart from failures (its summary of this run)
    from bearingsim.app import signal_workflows

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(signal_workflows, "dataset_case", lambda *a, **k: s)
        assert main(["dataset", str(ROOT / "cases" / "dataset_cwru_4class.toml"), "-o", str(tmp_path / "d.h5")]) == 0
    cap = capsys.readouterr()
    assert f"{s.excluded} of 8 fault items excluded: the fault makes no impact" in cap.out
    assert "all other items simulated successfully" in cap.out and "failed" not in cap.err


def test_a_cached_data_set_is_simulated_once_per_spec(files, tmp_path, monkeypatch, capsys):
    """bearingsim.datasets.cached: the first call simulates the spec's set into the data cache
    (byte-identical to make_dataset's file of the same spec), a later call reads it without
    simulating; another spec (here its seed) is another file; a purpose that is no plain name is
    refused."""
    from bearingsim.datasets import cached

    case, a, _, _, _ = files
    p = cached.cached_dataset(case, "unit", directory=tmp_path, progress=True)
    assert p.parent == tmp_path and p.name.startswith("unit_6_v") and p.read_bytes() == a.read_bytes()
    assert "simulated into the data cache" in capsys.readouterr().err

    def refuse(*a, **k):
        raise AssertionError("simulated again")
    monkeypatch.setattr(cached, "make_dataset", refuse)
    assert cached.cached_dataset(case, "unit", directory=tmp_path, progress=True) == p
    assert "read from the data cache" in capsys.readouterr().err
    other = case.with_value("dataset.seed", 8)
    assert cached.cached_name(other, "unit") != p.name
    with pytest.raises(AssertionError, match="simulated again"):
        cached.cached_dataset(other, "unit", directory=tmp_path, progress=False)
    monkeypatch.setenv("BEARINGSIM_CACHE", str(tmp_path / "c"))
    assert cached.cache_dir() == tmp_path / "c"
    with pytest.raises(ValueError, match="purpose"):
        cached.cached_name(case, "../x")


def test_the_ball_class_draws_its_fault_level_from_its_own_range():
    """``ball_fault_snr_dB`` (issue 33: the CWRU ball records' periodic signature, whitened, reads as
    the model's ball items ~20 dB weaker than the race faults', docs/realism.md): the ball items'
    ``snr_dB`` labels lie in its range, the race items' in ``fault_snr_dB``, healthy items 0.  The
    same stream draws both, so absent (or equal to ``fault_snr_dB``) it leaves every label as
    before, bit for bit.  Without ``fault_snr_dB`` it is refused, naming both keys."""
    base = load_case(ROOT / "cases" / "dataset_cwru_4class.toml").with_value("dataset.count", 40)
    lab0 = draw_labels(base)
    assert draw_labels(base.with_value("dataset.ball_fault_snr_dB", [-6, 25])).tobytes() == lab0.tobytes()
    lab = draw_labels(base.with_value("dataset.ball_fault_snr_dB", [-25, -20]))
    c, s = lab["fault_class"], lab["snr_dB"]
    assert np.all((s[c == 3] >= -25) & (s[c == 3] <= -20)) and (c == 3).sum() == 10
    assert np.array_equal(s[c != 3], lab0["snr_dB"][c != 3]) and np.all(s[c == 0] == 0)
    assert np.all((s[(c == 1) | (c == 2)] >= -6) & (s[(c == 1) | (c == 2)] <= 25))
    names = [f for f in lab.dtype.names if f != "snr_dB"]
    assert all(np.array_equal(lab[f], lab0[f]) for f in names)
    with pytest.raises(CaseError, match="ball_fault_snr_dB.*fault_snr_dB"):
        load_case(ROOT / "cases" / "dataset_cwru.toml").with_value("dataset.ball_fault_snr_dB", [-25, 6])


def test_label_draw_is_one_program_for_every_count(tmp_path, monkeypatch):
    """Every count draws its labels on blocks of one fixed width: a new count traces no new program (a width per power of two traced one on every new power: a warm 10^5-item run
    still traced one, 2026-11-28), and an item's draws do not depend on the count's block split
    (items 0-99 of the outer class block are the same whether 5000 or 9000 items are drawn)."""
    from bearingsim import programs
    monkeypatch.setattr(programs, "program_dir", lambda: tmp_path / "p")
    programs.forget()
    c = load_case("dataset_cwru_4class")
    draw_labels(c.with_value("dataset.count", 16))
    before = programs.counts()["traced"]
    a = draw_labels(c.with_value("dataset.count", 5000))
    b = draw_labels(c.with_value("dataset.count", 9000))
    assert programs.counts()["traced"] == before
    assert np.array_equal(a["key"][:1000], b["key"][:1000])
    same = a["fault_class"][:1000] == b["fault_class"][:1000]
    assert same.sum() > 500
    for f in ("speed_rpm", "spall_length_mm"):
        assert np.array_equal(a[f][:1000][same], b[f][:1000][same]), f
