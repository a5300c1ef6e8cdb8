"""The sim-to-real transfer benchmark (issue 20): the metrics against hand counts, and the floor
of classifiers trained on the shipped spec's simulated data only, tested on the real CWRU
records of ../shared/realdata (skipped with the reason when absent).  The full-size figures
(1000 training items) are benchmarks/bench_transfer.py's; this test trains on a small set (120 items)."""
from pathlib import Path

import numpy as np
import pytest

from bearingsim.calibration import find_realdata
from bearingsim.case import load_case
from bearingsim.errors import InputError
from bearingsim.features import fault_orders
from bearingsim.transfer import CLASSES, REAL_RECORDS, Windows, evaluate, real_windows, transfer_benchmark

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


@needs_data
@pytest.mark.slow
def test_classifiers_trained_on_simulation_recognise_real_faults(tmp_path):
    from bearingsim.workflows import dataset_case

    pytest.importorskip("sklearn", reason="the transfer benchmark needs scikit-learn (pip install 'bearingsim[ml]')")
    spec = load_case("dataset_cwru_4class")
    spec = (spec.with_value("dynamics.sample_rate_Hz", 12000).with_value("dataset.duration_s", 0.2)
            .with_value("dataset.count", 120))
    s = dataset_case(spec, tmp_path / "train.h5")
    assert s.failed == 0
    reports = transfer_benchmark(tmp_path / "train.h5", DATA, fault_orders(spec.bearing()), 0.2)
    for r in reports:
        msg = f"{r.classifier}: {r.balanced_accuracy:.3f}, per record {r.per_record}"
        assert r.balanced_accuracy >= FLOOR_BALANCED, msg
        for rec in ("cwru_OR007_6_0hp_12k", "cwru_IR007_0hp_12k"):
            assert r.per_record[rec][1] >= FLOOR_CLEAR, msg


def test_plot_transfer_writes_the_figure(tmp_path):
    from bearingsim.plots_signal import plot_transfer
    y = np.array([0, 1, 1, 2, 3])
    w = Windows(np.zeros((5, 2)), y, np.array(["n", "o1", "o2", "i", "b"]), np.ones(5))
    reps = [evaluate(_Fixed([0, 1, 0, 2, 0]), name, w, w) for name in ("a", "b")]
    out = plot_transfer(reps, path=tmp_path / "t.png")
    assert out is not None and (tmp_path / "t.png").stat().st_size > 10_000
