"""The sim-to-real transfer benchmark (issue 20): the metrics against hand counts, and the floor
of classifiers trained on the shipped spec's simulated data only, tested on the real CWRU
records of ../shared/realdata (skipped with the reason when absent).  The full-size figures
(1000 training items) are benchmarks/bench_transfer.py's; this test trains on a small set (120 items)."""
from pathlib import Path

import numpy as np
import pytest

from bearingsim.realism.calibration import find_realdata
from bearingsim.case import load_case
from bearingsim.errors import InputError
from bearingsim.signals.features import fault_orders
from bearingsim.realism.transfer import (CLASSES, DEV_RECORDS, REAL_RECORDS, Windows, composed_dataset, dev_figures,
                                 dev_records, dev_text, diagnosable, evaluate, real_windows, transfer_benchmark)

REPO = Path(__file__).resolve().parent.parent
DATA = find_realdata(REPO)
needs_data = pytest.mark.skipif(DATA is None, reason="the real CWRU records (../shared/realdata) are not here: "
                                "the transfer benchmark needs them (see ../shared/realdata/README.md)")

#: floors of the small-set test (120 items: measured 0.669 RF, 0.661 LR; the ceiling the two
#: signature-less records leave is 0.67, the issue measured 0.55-0.61 before): balanced
#: accuracy over the six records' windows, and the two unambiguous records (the rig's 0.007 in
#: outer and inner race faults: strong lines at their own frequency)
FLOOR_BALANCED = 0.60
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


#: the training set of both floors below: the shipped four-class spec at the benchmark's sampling
#: (0.2 s items at 12 kHz), DEV_COUNT items, every issue 26 ingredient (the shipped spec's own
#: ``realism_ingredients``: simulated once for the module)
DEV_COUNT = 120


@pytest.fixture(scope="module")
def train(tmp_path_factory):
    pytest.importorskip("sklearn", reason="the transfer benchmark needs scikit-learn (pip install 'bearingsim[ml]')")
    from bearingsim.signals.nuisance import INGREDIENTS

    spec = load_case("dataset_cwru_4class")
    assert tuple(spec.get("dataset.realism_ingredients")) == INGREDIENTS     # the shipped spec has them all
    spec = (spec.with_value("dynamics.sample_rate_Hz", 12000).with_value("dataset.duration_s", 0.2)
            .with_value("dataset.count", DEV_COUNT))
    path = tmp_path_factory.mktemp("transfer") / "train.h5"
    s = composed_dataset(spec, path)
    assert s.failed == 0
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
#: first DEV_WINDOWS windows (0.2 s) of every Y-graded record: measured 0.728 (RF) and 0.747 (LR)
#: (2026-11-25; ball recall 0.03 / 0.10: the target >= 0.95 is not met, docs/realism.md); set
#: just under it
DEV_WINDOWS = 10
FLOOR_DEV_Y = 0.70


@needs_data
@pytest.mark.slow
def test_dev_set_floor(train):
    spec, path = train
    reports = transfer_benchmark(path, DATA, fault_orders(spec.bearing()), 0.2, dev_records("Y"),
                                 max_windows=DEV_WINDOWS)
    for r in reports:
        f = dev_figures(r, dev_records("Y"))
        print(f"{r.classifier}: Y-graded balanced {f.balanced_accuracy:.3f}, recall {f.recall}")
        assert f.balanced_accuracy >= FLOOR_DEV_Y, f"{r.classifier}: {f}"
