"""The sim-to-real transfer benchmark (issue 20): the metrics against hand counts, and the floor
of classifiers trained on the shipped spec's simulated data only, tested on the real CWRU
records of ../shared/realdata (skipped with the reason when absent).  The full-size figures
(1000 training items) are benchmarks/bench_transfer.py's; this test trains on a small set (120 items).
Issue 33: the plain feature set on a synthetic impulse train, the two rigs' training specs, the
HIT-SM MFS records' table and a floor per rig (CWRU: the plain features on the same 120 items;
HIT: 64 items of its own spec; skipped when ../shared/realdata or its hit_mfs folder is absent)."""
from pathlib import Path

import numpy as np
import pytest

from bearingsim.realism.calibration import find_realdata
from bearingsim.case import load_case
from bearingsim.errors import InputError
from bearingsim.signals.features import fault_orders
from bearingsim.datasets.cached import cached_dataset
from bearingsim.realism.transfer import (CLASSES, DEV_RECORDS, REAL_RECORDS, Windows, dev_figures,
                                 dev_records, dev_text, diagnosable, evaluate, real_windows, transfer_benchmark)

REPO = Path(__file__).resolve().parent.parent
DATA = find_realdata(REPO)
needs_data = pytest.mark.skipif(DATA is None, reason="the real CWRU records (../shared/realdata) are not here: "
                                "the transfer benchmark needs them (see ../shared/realdata/README.md)")

#: floors of the small-set test (120 items: measured 0.669 RF, 0.661 LR; with race_waviness in
#: the shipped spec, 2026-11-28, LR 0.593: its outer recall on OR014 / OR021 fell; the 300-item
#: benchmark's 0.2 s figures moved inside their seed spread, docs/realism.md; the ceiling the two
#: signature-less records leave is 0.67, the issue measured 0.55-0.61 before): balanced
#: accuracy over the six records' windows, and the two unambiguous records (the rig's 0.007 in
#: outer and inner race faults: strong lines at their own frequency)
FLOOR_BALANCED = 0.58
FLOOR_CLEAR = 0.90


class _Fixed:
    """A 'classifier' that predicts a fixed sequence (to check the metrics by hand)."""

    def __init__(self, pred):
        self.pred = np.asarray(pred)

    def fit(self, X, y):
        return self

    def predict(self, X):
        return self.pred


def test_metrics_by_hand():
    y = np.array([0, 0, 1, 1, 1, 1, 2, 3])
    pred = np.array([0, 1, 1, 1, 0, 1, 2, 2])
    w = Windows(np.zeros((8, 3)), y, np.array(["a", "a", "b", "b", "c", "c", "d", "e"]), np.ones(8))
    r = evaluate(_Fixed(pred), "fixed", w, w)
    assert r.confusion.tolist() == [[1, 1, 0, 0], [1, 3, 0, 0], [0, 0, 1, 0], [0, 0, 1, 0]]
    # recalls 1/2, 3/4, 1, 0 -> balanced accuracy 0.5625; worst class ball
    assert r.balanced_accuracy == pytest.approx((0.5 + 0.75 + 1.0 + 0.0) / 4)
    assert r.worst_class == ("ball", 0.0)
    assert r.per_record["c"][1] == 0.5 and r.per_record["e"] == ("ball", 0.0, {"inner": 1.0})


def test_a_missing_record_is_named(tmp_path):
    o = fault_orders(load_case("dataset_cwru_4class").bearing())
    with pytest.raises(InputError, match="not found"):
        real_windows(tmp_path, o, records={"cwru_nothing": "healthy"})


@needs_data
def test_real_windows_are_the_six_records():
    o = fault_orders(load_case("dataset_cwru_4class").bearing())
    w = real_windows(DATA, o, 0.2)
    counts = {r: int(np.sum(w.group == r)) for r in REAL_RECORDS}
    assert counts["cwru_normal_0hp_12k_decimated"] == 25          # 5.08 s -> 25 windows of 0.2 s
    assert all(v in (50, 51) for k, v in counts.items() if "normal" not in k)   # 10.1-10.2 s records
    assert np.all(np.isfinite(w.features))
    assert [CLASSES[c] for c in np.unique(w.label)] == list(CLASSES)


def test_dev_set_is_the_26_records_with_their_grades():
    assert len(DEV_RECORDS) == 26
    y, n = dev_records("Y"), dev_records("N")
    assert len(y) == 21 and len(n) == 5 and set(y) | set(n) == set(DEV_RECORDS)
    # graded N by every method (Smith & Randall Table B2): 118, 119, 120, 224, 225
    assert sorted(DEV_RECORDS[k][2] for k in n) == [118, 119, 120, 224, 225]
    assert [c for c in y.values()].count("ball") == 3 and y["cwru_normal_0hp_12k_decimated"] == "healthy"
    assert diagnosable("-") and diagnosable("Y2 (method 3 only)") and not diagnosable("N1")
    with pytest.raises(InputError, match="graded"):
        dev_records("P")


def test_dev_figures_by_hand():
    # records a (healthy, 3 windows), b (outer, 2), c (ball, 3)
    y = np.array([0, 0, 0, 1, 1, 3, 3, 3])
    pred = np.array([0, 0, 1, 1, 0, 3, 2, 2])
    g = np.array(["a", "a", "a", "b", "b", "c", "c", "c"])
    w = Windows(np.zeros((8, 2)), y, g, np.ones(8))
    r = evaluate(_Fixed(pred), "fixed", w, w)
    f = dev_figures(r, ["a", "b", "c"])
    assert f.recall == pytest.approx({"healthy": 2 / 3, "outer": 0.5, "ball": 1 / 3})
    assert f.balanced_accuracy == pytest.approx((2 / 3 + 0.5 + 1 / 3) / 3)
    assert f.worst_class == ("ball", pytest.approx(1 / 3))
    # majority: a healthy (right), b a tie outer/healthy -> the lower class index (healthy: wrong), c inner (wrong)
    assert f.votes["a"][2] == "healthy" and f.votes["c"][2] == "inner" and f.majority_right == pytest.approx(1 / 3)
    f2 = dev_figures(r, ["a"])
    assert f2.balanced_accuracy == pytest.approx(2 / 3) and f2.majority_right == 1.0
    assert "every record" in dev_text([r], {"a": "-", "b": "Y1", "c": "N1"})


def no_failed_item(path):
    """No item of the set failed (as DatasetSummary.failed counts: an item whose fault is not
    excited is excluded, not failed)."""
    import h5py

    from bearingsim.datasets import DatasetResult

    with h5py.File(path, "r") as h:
        r = h["labels"]["result"][:]
    return bool(np.all((r == 0) | (r == int(DatasetResult.fault_not_excited))))


#: the training set of both floors below: the shipped four-class spec at the benchmark's sampling
#: (0.2 s items at 12 kHz), DEV_COUNT items, the shipped spec's own ``realism_ingredients``
#: (race_waviness since 2026-11-28, docs/realism.md; simulated once for the module)
DEV_COUNT = 120


@pytest.fixture(scope="module")
def train(tmp_path_factory):
    pytest.importorskip("sklearn", reason="the transfer benchmark needs scikit-learn (pip install 'bearingsim[ml]')")
    spec = load_case("dataset_cwru_4class")
    assert tuple(spec.get("dataset.realism_ingredients")) == ("race_waviness",)     # the shipped spec (docs/realism.md)
    spec = (spec.with_value("dynamics.sample_rate_Hz", 12000).with_value("dataset.duration_s", 0.2)
            .with_value("dataset.count", DEV_COUNT))
    # the session's data cache (tests/conftest.py): notebook 07 reads the same set
    path = cached_dataset(spec, "transfer_cwru", progress=False)
    assert no_failed_item(path)
    return spec, path


@needs_data
@pytest.mark.slow
def test_classifiers_trained_on_simulation_recognise_real_faults(train):
    spec, path = train
    reports = transfer_benchmark(path, DATA, fault_orders(spec.bearing()), 0.2)
    for r in reports:
        msg = f"{r.classifier}: {r.balanced_accuracy:.3f}, per record {r.per_record}"
        assert r.balanced_accuracy >= FLOOR_BALANCED, msg
        for rec in ("cwru_OR007_6_0hp_12k", "cwru_IR007_0hp_12k"):
            assert r.per_record[rec][1] >= FLOOR_CLEAR, msg


def test_plot_transfer_writes_the_figure(tmp_path):
    from bearingsim.output.plots_signal import plot_transfer
    y = np.array([0, 1, 1, 2, 3])
    w = Windows(np.zeros((5, 2)), y, np.array(["n", "o1", "o2", "i", "b"]), np.ones(5))
    reps = [evaluate(_Fixed([0, 1, 0, 2, 0]), name, w, w) for name in ("a", "b")]
    out = plot_transfer(reps, path=tmp_path / "t.png")
    assert out is not None and (tmp_path / "t.png").stat().st_size > 10_000


#: floor of the development set (issue 26), Y-graded records (normal included), both classifiers,
#: trained on DEV_COUNT items of the shipped spec with every issue 26 ingredient, tested on the
#: first DEV_WINDOWS windows (0.2 s) of every Y-graded record: measured 0.719 (RF) and 0.664 (LR)
#: (2026-11-27, chunk format 7, the shipped spec without issue 26's ingredients; with them 0.731 /
#: 0.761: a 120-item set moves by more than that between specs, the 300-item benchmark with two
#: seeds measures RF 0.734 / 0.738 and LR 0.739 / 0.712 without them, docs/realism.md; ball recall
#: 0.03 / 0.10: the target >= 0.95 is not met); with race_waviness in the shipped spec
#: (2026-11-28): RF 0.717, LR 0.636 (outer recall 0.48); set just under it, per classifier
DEV_WINDOWS = 10
FLOOR_DEV_Y = {"random_forest": 0.70, "logistic_regression": 0.62}


@needs_data
@pytest.mark.slow
def test_dev_set_floor(train):
    spec, path = train
    reports = transfer_benchmark(path, DATA, fault_orders(spec.bearing()), 0.2, dev_records("Y"),
                                 max_windows=DEV_WINDOWS)
    for r in reports:
        f = dev_figures(r, dev_records("Y"))
        print(f"{r.classifier}: Y-graded balanced {f.balanced_accuracy:.3f}, recall {f.recall}")
        assert f.balanced_accuracy >= FLOOR_DEV_Y[r.classifier], f"{r.classifier}: {f}"


# ---------------------------------------------------------------------------------------------
# Issue 33: the plain feature set, the two development rigs and their floors
# ---------------------------------------------------------------------------------------------

def _impulse_train(fs, seconds, rate_hz, fn=3000.0, zeta=0.05, noise=0.05, seed=0):
    """Impulses at ``rate_hz`` ringing a mode at ``fn`` (damping ``zeta``), plus white noise."""
    t = np.arange(int(round(fs * seconds))) / fs
    x = np.zeros_like(t)
    wd = 2 * np.pi * fn * np.sqrt(1 - zeta ** 2)
    for t0 in np.arange(0.003, seconds, 1.0 / rate_hz):
        m = t >= t0
        x[m] += np.exp(-zeta * 2 * np.pi * fn * (t[m] - t0)) * np.sin(wd * (t[m] - t0))
    return x + noise * np.random.default_rng(seed).standard_normal(t.size)


@pytest.mark.parametrize("seconds", [1.0, 0.2])
def test_plain_features_find_bpfo_and_ignore_the_level(seconds):
    from bearingsim.signals.plain_features import PLAIN_BANDS_HZ, PLAIN_FEATURE_NAMES, PLAIN_LINES, plain_features

    o = fault_orders(load_case("dataset_cwru_4class").bearing())
    fs, fr = 12000.0, 1797 / 60.0
    x = _impulse_train(fs, seconds, o.bpfo * fr)                # outer-race impulses ringing 3 kHz
    F = plain_features(x[None], fs, fr, o)
    assert F.shape == (1, len(PLAIN_FEATURE_NAMES)) and np.all(np.isfinite(F))
    # level-free: the same record 150x louder (the HIT normal/fault gain gap) gives the same features
    np.testing.assert_allclose(plain_features(150.0 * x[None], fs, fr, o), F, rtol=1e-9, atol=1e-9)
    band = [i for i, (lo, hi) in enumerate(PLAIN_BANDS_HZ) if lo <= 3000.0 < hi][0]
    lines = dict(zip(PLAIN_LINES, F[0, band * len(PLAIN_LINES):(band + 1) * len(PLAIN_LINES)]))
    assert max(lines, key=lines.get) == "BPFO", lines
    assert lines["BPFO"] > 25.0, lines
    # every line of another fault family is far below (2 BPFI is left out: for Z = 9, BPFO + BPFI = 9 f_r,
    # so 2 BPFI = 10.83 f_r sits 0.7 % from 3 BPFO = 10.75 f_r, inside its +-1.5 % window)
    for k in ("BPFI", "BPFI-fr", "BPFI+fr", "2BSF", "4BSF", "2BSF-FTF", "2BSF+FTF"):
        assert lines["BPFO"] - lines[k] > 15.0, (k, lines)
    assert F[0, -3] > 5.0          # kurtosis of an impulse train


def test_plain_features_refuse_what_they_cannot_read():
    from bearingsim.signals.plain_features import plain_features

    o = fault_orders(load_case("dataset_cwru_4class").bearing())
    with pytest.raises(ValueError, match="sample rate"):
        plain_features(np.ones((1, 1000)), 8000.0, 30.0, o)
    with pytest.raises(ValueError, match="shaft_hz"):
        plain_features(np.random.default_rng(0).standard_normal((1, 2400)), 12000.0, 0.0, o)


def test_rig_specs_change_only_what_the_rig_user_knows():
    from bearingsim.realism.transfer import RIGS, rig_spec

    spec = load_case("dataset_cwru_4class")
    c = rig_spec(spec, RIGS["cwru"], 1.0, 40, 3)
    h = rig_spec(spec, RIGS["hit"], 0.2, 40, 3)
    assert c.get("dynamics.sample_rate_Hz") == 12000 and h.get("dynamics.sample_rate_Hz") == 12800
    assert list(c.get("dataset.speed_rpm")) == list(spec.get("dataset.speed_rpm")) == [1720, 1800]
    assert list(h.get("dataset.speed_rpm")) == [600, 1200]
    assert (c.get("dataset.duration_s"), c.get("dataset.count"), c.get("dataset.seed")) == (1.0, 40, 3)
    assert h.get("dataset.duration_s") == 0.2
    for key in ("dataset.resonance_frequency_Hz", "dataset.fault_snr_dB", "dataset.radial_N",
                "dataset.realism_ingredients", "dataset.spall_length_mm", "bearing.balls", "bearing.ball_diameter_mm",
                "bearing.pitch_diameter_mm"):
        assert h.get(key) == spec.get(key) == c.get(key), key
    assert fault_orders(h.bearing()) == fault_orders(spec.bearing())     # the 6205 geometry of both rigs


@pytest.mark.skipif(DATA is None or not (DATA / "hit_mfs").is_dir(),
                    reason="the HIT-SM MFS records (../shared/realdata/hit_mfs) are not here")
def test_hit_records_are_the_npz_metadata():
    from bearingsim.realism.transfer import HIT_RECORDS

    files = sorted(p.stem for p in (DATA / "hit_mfs").glob("*.npz"))
    assert sorted(HIT_RECORDS) == files and len(files) == 21
    for stem, (cls, arc, rpm) in HIT_RECORDS.items():
        with np.load(DATA / "hit_mfs" / f"{stem}.npz", allow_pickle=False) as z:
            fault = str(z["fault"])
            assert ("healthy" if fault == "normal" else fault) == cls
            assert float(z["fault_arc_deg"]) == arc and float(z["rpm"]) == rpm and float(z["fs"]) == 51200.0


#: floors of the plain feature set on CWRU (issue 33): the module's ``train`` set (DEV_COUNT items
#: of 0.2 s at 12 kHz), the first DEV_WINDOWS windows of every Y-graded record; balanced accuracy
#: per classifier, set just under the figure measured with this configuration (docstring below)
FLOOR_DEV_Y_PLAIN = {"random_forest": 0.665, "logistic_regression": 0.71}


@needs_data
@pytest.mark.slow
def test_dev_set_floor_plain_features(train):
    """Measured (2026-11-27, 2-core CPU, make test's XLA flags), chunk format 7 and the shipped spec
    without issue 26's ingredients: RF 0.681, LR 0.731 (with them 0.694 / 0.619; before format 7
    0.714 / 0.639; Y-graded balanced; the own features on the same set: 0.719 / 0.664).  With
    race_waviness in the shipped spec (2026-11-28): RF 0.678, LR 0.722."""
    spec, path = train
    reports = transfer_benchmark(path, DATA, fault_orders(spec.bearing()), 0.2, dev_records("Y"),
                                 max_windows=DEV_WINDOWS, features="plain")
    for r in reports:
        f = dev_figures(r, dev_records("Y"))
        print(f"plain {r.classifier}: Y-graded balanced {f.balanced_accuracy:.3f}, recall {f.recall}")
        assert f.balanced_accuracy >= FLOOR_DEV_Y_PLAIN[r.classifier], f"{r.classifier}: {f}"


#: the HIT floor's training set: the HIT rig's spec (transfer.rig_spec: 600-1200 rpm, 12.8 kHz, the
#: shipped spec's randomisation), HIT_COUNT items of 0.2 s, data set seed 0 (a program of its own:
#: the HIT speed bound sizes it); tested on the first HIT_WINDOWS windows (0.2 s) of all 21 records
HIT_COUNT = 64
HIT_WINDOWS = 10
#: balanced accuracy (three classes) per (feature set, classifier), set just under the figure
#: measured with this configuration (test docstring)
FLOOR_HIT = {("own", "random_forest"): 0.95, ("own", "logistic_regression"): 0.89,
             ("plain", "random_forest"): 0.97, ("plain", "logistic_regression"): 0.89}
HIT_DATA = None if DATA is None or not (DATA / "hit_mfs").is_dir() else DATA / "hit_mfs"


@pytest.mark.skipif(HIT_DATA is None, reason="the HIT-SM MFS records (../shared/realdata/hit_mfs) are not here: "
                    "the HIT floor needs them (see ../shared/realdata/hit_mfs/README.md)")
@pytest.mark.slow
def test_hit_floor():
    """Measured under make test's XLA_FLAGS=--xla_backend_optimization_level=0 (2026-11-27, 2-core
    CPU), chunk format 7 and the shipped spec without issue 26's ingredients: own RF 0.978, own LR
    0.811, plain RF 0.985, plain LR 0.844 (with them 0.881 / 0.900 / 0.952 / 0.870; before format 7
    0.926 / 0.841 / 0.930 / 0.819), balanced over the three classes; the LR's weak classes are
    healthy (recall 0.73 / 0.53) and, own, inner (0.70).  With race_waviness in the shipped spec
    (2026-11-28): 0.963 / 0.907 / 0.989 / 0.911 (LR healthy recall 0.93 / 0.73).  The floors sit
    0.01-0.02 under.
    42-46 s on the shared 2-core machine,
    cold or with a filled compilation cache (the HIT speed bound sizes a program of its own; the
    module's CWRU fixture costs 80-240 s the same way)."""
    pytest.importorskip("sklearn", reason="the transfer benchmark needs scikit-learn (pip install 'bearingsim[ml]')")
    from bearingsim.realism.transfer import RIGS, rig_spec

    rig = RIGS["hit"]
    spec = rig_spec(load_case("dataset_cwru_4class"), rig, 0.2, HIT_COUNT, 0)
    path = cached_dataset(spec, "transfer_hit", progress=False)     # notebook 07 reads it too
    assert no_failed_item(path)
    for feats in ("own", "plain"):
        reports = transfer_benchmark(path, HIT_DATA, fault_orders(spec.bearing()), 0.2, rig.records,
                                     max_windows=HIT_WINDOWS, features=feats, sample_rate_Hz=rig.sample_rate_Hz)
        for r in reports:
            f = dev_figures(r, rig.records)
            print(f"HIT {feats} {r.classifier}: balanced {f.balanced_accuracy:.3f}, recall {f.recall}, "
                  f"vote right {f.majority_right:.2f}")
            assert f.balanced_accuracy >= FLOOR_HIT[feats, r.classifier], f"{feats} {r.classifier}: {f}"
