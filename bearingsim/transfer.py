"""Sim-to-real transfer benchmark: train fault classifiers on simulated data only, test them on
real records.

An ML user's question: *if I train only on bearingsim data, does my classifier recognise real
faults?*  This module answers it the way such a user would, with nothing tuned on the real
records:

* features: :func:`bearingsim.features.window_features` (scale-free envelope lines and
  impulsiveness; documented there), on non-overlapping windows (0.2 s by default) of every
  simulated item and of every real record;
* two classifiers fixed before any result was seen (scikit-learn, the field's standard; an
  optional extra): a random forest (300 trees, otherwise defaults, ``random_state=0``) and a
  logistic regression on standardised features (defaults, ``max_iter=5000``);
* trained on the simulated windows only (every window of an item in training: the real records
  are the test set, so no simulated item straddles anything); tested on the windows of the real
  records; per-class confusion matrix, per-record accuracy, balanced accuracy (the mean of the
  per-class recalls over the windows), worst class.

The real records are the six 0 hp drive-end 12 kHz CWRU records of ``../shared/realdata``
(:data:`REAL_RECORDS`); any other list of (file stem, class) can be given.  They are read, never
written or copied.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .defect import LOCATIONS
from .errors import InputError
from .features import FEATURE_NAMES, FaultOrders, cut_windows, window_features

__all__ = ["CLASSES", "REAL_RECORDS", "CLASSIFIERS", "TransferReport", "real_windows", "simulated_windows",
           "make_classifier", "evaluate", "transfer_benchmark", "transfer_text", "require_sklearn"]

#: class names (index = fault_class of the data sets)
CLASSES = ("healthy",) + LOCATIONS

#: the six 0 hp 12 kHz drive-end records of ../shared/realdata: file stem -> class
REAL_RECORDS = {
    "cwru_normal_0hp_12k_decimated": "healthy",
    "cwru_OR007_6_0hp_12k": "outer",
    "cwru_OR014_6_0hp_12k": "outer",
    "cwru_OR021_6_0hp_12k": "outer",
    "cwru_IR007_0hp_12k": "inner",
    "cwru_B007_0hp_12k": "ball",
}

#: the two classifiers of the benchmark (fixed before any result; never tuned on real records)
CLASSIFIERS = ("random_forest", "logistic_regression")


def require_sklearn():
    try:
        import sklearn  # noqa: F401
    except ImportError:
        raise InputError("the transfer benchmark needs scikit-learn: pip install 'bearingsim[ml]'") from None


def make_classifier(name: str):
    """A fresh, unfitted classifier of :data:`CLASSIFIERS`."""
    require_sklearn()
    from sklearn.ensemble import RandomForestClassifier
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    if name == "random_forest":
        return RandomForestClassifier(n_estimators=300, random_state=0, n_jobs=1)
    if name == "logistic_regression":
        return make_pipeline(StandardScaler(), LogisticRegression(max_iter=5000))
    raise InputError(f"unknown classifier {name!r}: one of {', '.join(CLASSIFIERS)}")


@dataclass
class Windows:
    """Feature rows of windows with their class, group (record or item) and shaft speed."""

    features: np.ndarray        # (N, F)
    label: np.ndarray           # (N,) class index
    group: np.ndarray           # (N,) record name or item index
    shaft_hz: np.ndarray        # (N,)


def real_windows(data_dir, orders: FaultOrders, window_s=0.2, records=None, channel="DE") -> Windows:
    """Windows of the real records (``records``: {file stem: class name}, default
    :data:`REAL_RECORDS`) of ``data_dir``; shaft speed from each record's rpm."""
    data_dir = Path(data_dir)
    records = REAL_RECORDS if records is None else records
    F, y, g, sh = [], [], [], []
    for stem, cls in records.items():
        p = data_dir / f"{stem}.npz"
        if not p.exists():
            raise InputError(f"real record {p} not found")
        with np.load(p, allow_pickle=False) as z:
            x = np.asarray(z[channel], float).ravel()
            fs = float(z["fs"])
            fr = float(z["rpm"]) / 60.0
        W = cut_windows(x, fs, window_s)
        F.append(window_features(W, fs, fr, orders))
        y += [CLASSES.index(cls)] * len(W)
        g += [stem] * len(W)
        sh += [fr] * len(W)
    return Windows(np.concatenate(F), np.asarray(y), np.asarray(g), np.asarray(sh))


def simulated_windows(path, orders: FaultOrders, window_s=None) -> Windows:
    """Windows of a data set file (``bearingsim dataset``): every item with result 0 cut into
    ``window_s`` windows (default: the whole item), grouped by item index."""
    import h5py

    with h5py.File(path, "r") as f:
        X = np.asarray(f["signals"], float)
        lab = np.asarray(f["labels"])
        fs = float(f.attrs["sample_rate_Hz"])
    ok = lab["result"] == 0
    X, lab = X[ok], lab[ok]
    T = X.shape[1] if window_s is None else int(round(window_s * fs))
    n = X.shape[1] // T
    W = X[:, :n * T].reshape(-1, T)
    rep = lambda a: np.repeat(a, n)
    fr = rep(lab["shaft_Hz"])
    return Windows(window_features(W, fs, fr, orders), rep(lab["fault_class"]).astype(int),
                   rep(lab["index"]), fr)


@dataclass
class TransferReport:
    """Result of one classifier on the real windows."""

    classifier: str
    confusion: np.ndarray              # (4, 4): rows true class, columns predicted
    per_record: dict                   # record -> (class, accuracy, {predicted class: fraction})
    balanced_accuracy: float
    recall: np.ndarray                 # (4,) per class
    trained_on: int                    # training windows
    tested_on: int                     # real windows
    feature_importance: dict = field(default_factory=dict)

    @property
    def worst_class(self) -> tuple:
        present = [c for c in range(len(CLASSES)) if self.confusion[c].sum() > 0]
        c = min(present, key=lambda c: self.recall[c])
        return CLASSES[c], float(self.recall[c])


def evaluate(model, name, train: Windows, test: Windows) -> TransferReport:
    """Fit ``model`` on ``train``, score it on ``test`` (windows)."""
    model.fit(train.features, train.label)
    pred = model.predict(test.features)
    K = len(CLASSES)
    cm = np.zeros((K, K), int)
    np.add.at(cm, (test.label, pred), 1)
    rows = cm.sum(1)
    recall = np.where(rows > 0, np.diag(cm) / np.maximum(rows, 1), np.nan)
    per = {}
    for rec in dict.fromkeys(test.group.tolist()):
        m = test.group == rec
        c = int(test.label[m][0])
        counts = np.bincount(pred[m], minlength=K) / m.sum()
        per[rec] = (CLASSES[c], float(counts[c]), {CLASSES[k]: float(v) for k, v in enumerate(counts) if v > 0})
    imp = {}
    est = model[-1] if hasattr(model, "steps") else model
    if hasattr(est, "feature_importances_"):
        imp = dict(sorted(zip(FEATURE_NAMES, map(float, est.feature_importances_)), key=lambda kv: -kv[1]))
    return TransferReport(name, cm, per, float(np.nanmean(recall)), recall, len(train.label), len(test.label), imp)


def transfer_benchmark(sim_path, data_dir, orders: FaultOrders, window_s=0.2, records=None,
                       classifiers=CLASSIFIERS) -> list:
    """Train each classifier on the windows of the data set file ``sim_path``, test on the real
    records: a :class:`TransferReport` per classifier."""
    require_sklearn()
    train = simulated_windows(sim_path, orders, window_s)
    test = real_windows(data_dir, orders, window_s, records)
    return [evaluate(make_classifier(c), c, train, test) for c in classifiers]


def transfer_text(reports) -> str:
    """The benchmark table: per classifier balanced accuracy, worst class, confusion matrix and
    per-record accuracy."""
    out = []
    for r in reports:
        wc, wv = r.worst_class
        out.append(f"{r.classifier}: balanced accuracy {r.balanced_accuracy:.3f}, worst class {wc} "
                   f"{wv:.3f} ({r.trained_on} simulated windows -> {r.tested_on} real windows)")
        out.append("  confusion (rows true, columns predicted): " + " ".join(f"{c:>8s}" for c in CLASSES))
        for c, row in zip(CLASSES, r.confusion):
            out.append(f"  {c:>42s} " + " ".join(f"{v:8d}" for v in row))
        for rec, (c, acc, pred) in r.per_record.items():
            calls = ", ".join(f"{k} {v:.2f}" for k, v in pred.items())
            out.append(f"  {rec:34s} {c:8s} accuracy {acc:.2f}   ({calls})")
    return "\n".join(out)
