"""Sim-to-real transfer benchmark: train fault classifiers on simulated data only, test them on
real records.

An ML user's question: *if I train only on bearingsim data, does my classifier recognise real
faults?*  This module answers it the way such a user would, with nothing tuned on the real
records:

* features: :func:`bearingsim.signals.features.window_features` (scale-free envelope lines and
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

Issue 33 adds a second development rig and a second feature set: :data:`RIGS` (``cwru``: the 26
records of :data:`DEV_RECORDS`; ``hit``: the 21 HIT-SM SpectraQuest MFS records of
:data:`HIT_RECORDS`, decimated to 12.8 kHz), each with the simulated training spec a user of the
rig would derive from the shipped four-class spec (:func:`rig_spec`: sample rate, speed range,
item duration; the randomisation unchanged), and :data:`FEATURE_SETS` (``own`` =
:func:`~bearingsim.signals.features.window_features`, ``plain`` =
:func:`~bearingsim.signals.plain_features.plain_features`).  benchmarks/bench_transfer.py runs
rig x feature set x classifier x window length.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..datasets import make_dataset
from ..errors import InputError, succeeded
from ..names import CLASSES
from ..physics.kinematics import DefectFrequencies
from ..signals.features import FEATURE_NAMES, cut_windows, window_features
from ..signals.plain_features import PLAIN_FEATURE_NAMES, plain_features

__all__ = ["CLASSES", "REAL_RECORDS", "DEV_RECORDS", "DEV_GRADES", "CLASSIFIERS", "dev_records", "diagnosable",
           "DevFigures", "dev_figures", "dev_text", "composed_dataset", "TransferReport", "real_windows", "simulated_windows",
           "make_classifier", "evaluate", "transfer_benchmark", "transfer_text", "require_sklearn",
           "FEATURE_SETS", "HIT_RECORDS", "hit_records", "Rig", "RIGS", "rig_spec", "rig_data_dir"]

#: the two feature sets of the benchmark (issue 33): name -> (function (windows, fs, shaft_hz,
#: orders) -> (N, F), feature names); "own" the project's scale-free extractor, "plain" the
#: textbook envelope lines in three fixed bands with kurtosis, crest factor and skewness
FEATURE_SETS = {"own": (window_features, FEATURE_NAMES), "plain": (plain_features, PLAIN_FEATURE_NAMES)}


def _feature_set(name):
    if name not in FEATURE_SETS:
        raise InputError(f"unknown feature set {name!r}: one of {', '.join(FEATURE_SETS)}")
    return FEATURE_SETS[name]

#: the six 0 hp 12 kHz drive-end records of ../shared/realdata: file stem -> class
REAL_RECORDS = {
    "cwru_normal_0hp_12k_decimated": "healthy",
    "cwru_OR007_6_0hp_12k": "outer",
    "cwru_OR014_6_0hp_12k": "outer",
    "cwru_OR021_6_0hp_12k": "outer",
    "cwru_IR007_0hp_12k": "inner",
    "cwru_B007_0hp_12k": "ball",
}

#: the development set (issue 26): every 12 kHz drive-end record of ../shared/realdata, 26 records:
#: the normal record 97 (its 12 kHz copy decimated from 48 kHz: content above ~4.8 kHz lost; the
#: rig has no 12 kHz normal record), the 0.007 and 0.021 in faults (outer at 6:00, inner, ball) at
#: 0-3 hp and the 0.014 in outer race at 0 hp.  The 48 kHz files (97, 109, 122, 135, 201, 238)
#: are other acquisitions of the same 0 hp bearings: left out (they would count 0 hp twice and
#: need another sample rate).  file stem -> (class, Smith & Randall 2015 grade, CWRU number);
#: the grade of the normal record is "-" (ungraded) and counts as diagnosable.
DEV_RECORDS = {
    "cwru_normal_0hp_12k_decimated": ("healthy", "-", 97),
    **{f"cwru_OR007_6_{h}hp_12k": ("outer", "Y1", 130 + h) for h in range(4)},
    "cwru_OR014_6_0hp_12k": ("outer", "Y2 (method 3 only)", 197),
    "cwru_OR021_6_0hp_12k": ("outer", "Y2", 234),
    "cwru_OR021_6_1hp_12k": ("outer", "Y2", 235),
    "cwru_OR021_6_2hp_12k": ("outer", "Y2 (clipped)", 236),
    "cwru_OR021_6_3hp_12k": ("outer", "Y2 (clipped)", 237),
    **{f"cwru_IR007_{h}hp_12k": ("inner", "Y2", 105 + h) for h in range(4)},
    **{f"cwru_IR021_{h}hp_12k": ("inner", "Y1", 209 + h) for h in range(4)},
    "cwru_B007_0hp_12k": ("ball", "N1", 118),
    "cwru_B007_1hp_12k": ("ball", "N1", 119),
    "cwru_B007_2hp_12k": ("ball", "N1", 120),
    "cwru_B007_3hp_12k": ("ball", "Y2 (method 3 only)", 121),
    "cwru_B021_0hp_12k": ("ball", "Y2 (method 2)", 222),
    "cwru_B021_1hp_12k": ("ball", "Y2", 223),
    "cwru_B021_2hp_12k": ("ball", "N1", 224),
    "cwru_B021_3hp_12k": ("ball", "N1", 225),
}
#: record stem -> grade
DEV_GRADES = {k: v[1] for k, v in DEV_RECORDS.items()}


def dev_records(graded=None) -> dict:
    """{file stem: class} of the development set; ``graded="Y"`` only the diagnosable records
    (normal included), ``"N"`` only the records graded not diagnosable."""
    if graded not in (None, "Y", "N"):
        raise InputError(f"graded must be None, 'Y' or 'N', not {graded!r}")
    return {k: c for k, (c, g, _) in DEV_RECORDS.items() if graded is None or diagnosable(g) == (graded == "Y")}


def diagnosable(grade: str) -> bool:
    """A Smith & Randall grade counts as diagnosable when it is Y (any method) or ungraded (the
    normal record)."""
    return grade == "-" or grade.startswith("Y")


#: the second development rig (issue 33): the 21 HIT-SM SpectraQuest MFS records of
#: ``../shared/realdata/hit_mfs`` (README there: 6205 deep-groove bearings, the faulty one at the
#: non-drive end; 51.2 kHz, 5.12 s; raceway faults of 2 / 5 / 8 deg of arc; no ball faults).
#: file stem -> (class, fault arc in deg, nominal rpm), read from each npz's ``fault``,
#: ``fault_arc_deg`` and ``rpm`` (``fault = "normal"`` is the class healthy).  No grades: every
#: record counts.  The three normal records are ~150x weaker than the fault records: only
#: level-free features may read them (both feature sets are).
HIT_RECORDS = {
    **{f"hit_mfs_normal_{n}rpm": ("healthy", 0.0, float(n)) for n in (600, 900, 1200)},
    **{f"hit_mfs_inner{a}_{n}rpm": ("inner", float(a), float(n)) for a in (2, 5, 8) for n in (600, 900, 1200)},
    **{f"hit_mfs_outer{a}_{n}rpm": ("outer", float(a), float(n)) for a in (2, 5, 8) for n in (600, 900, 1200)},
}


def hit_records() -> dict:
    """{file stem: class} of :data:`HIT_RECORDS`."""
    return {k: v[0] for k, v in HIT_RECORDS.items()}


@dataclass(frozen=True)
class Rig:
    """A development rig of the transfer benchmark: its real records and what a user of the rig
    knows for the simulated training spec (geometry: the spec's own 6205; speed range; the
    sample rate the records are analysed at).

    ``records``: {file stem: class}; ``grades``: {file stem: grade} ("-" counts as diagnosable);
    ``subdir``: the records' folder under the real-data folder; ``sample_rate_Hz``: the rate the
    simulated items are made at and the real records are resampled to (None: the records' own);
    ``speed_rpm``: the data set's speed range (None: the spec's own)."""

    name: str
    records: dict
    grades: dict
    subdir: str
    sample_rate_Hz: float
    speed_rpm: tuple = None


#: the two development rigs (issue 33).  CWRU: the 26 12 kHz drive-end records (DEV_RECORDS),
#: simulated at 12 kHz over the spec's own speed range (1720-1800 rpm).  HIT: the 21 MFS records,
#: decimated by 4 to 12.8 kHz (an integer factor, anti-aliased by scipy's polyphase filter) and
#: simulated at 12.8 kHz over 600-1200 rpm: the simulated sensor modes lie in 1.5-5.5 kHz (the
#: spec's randomisation, unchanged), so items at 51.2 kHz would cost 4x the samples and teach
#: nothing above 6.4 kHz; and the same analysis band (both feature sets stop below 0.45 x 12 kHz
#: or 0.45 fs) serves both rigs.
RIGS = {
    "cwru": Rig("cwru", dev_records(), DEV_GRADES, ".", 12000.0, None),
    "hit": Rig("hit", hit_records(), {k: "-" for k in HIT_RECORDS}, "hit_mfs", 12800.0, (600.0, 1200.0)),
}


def rig_spec(spec, rig: Rig, duration_s, count, seed=0):
    """The simulated training spec of ``rig``, derived from ``spec`` (the shipped four-class spec):
    the rig's sample rate and speed range, ``count`` items of ``duration_s``, data set seed
    ``seed``; everything else (geometry, classes, every randomised range) unchanged."""
    s = spec.with_value("dynamics.sample_rate_Hz", rig.sample_rate_Hz)
    if rig.speed_rpm is not None:
        lo, hi = (float(v) for v in rig.speed_rpm)
        s = s.with_value("operation.speed_rpm", 0.5 * (lo + hi)).with_value("dataset.speed_rpm", [lo, hi])
    return (s.with_value("dataset.duration_s", float(duration_s)).with_value("dataset.count", int(count))
            .with_value("dataset.seed", int(seed)))


def rig_data_dir(realdata, rig: Rig):
    """The folder of ``rig``'s records under the real-data folder ``realdata`` (None when absent)."""
    if realdata is None:
        return None
    p = Path(realdata) / rig.subdir
    return p if p.is_dir() and all((p / f"{k}.npz").exists() for k in rig.records) else None


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
    feature_names: tuple = FEATURE_NAMES


def real_windows(data_dir, orders: DefectFrequencies, window_s=0.2, records=None, channel="DE", max_windows=None,
                 features="own", sample_rate_Hz=None) -> Windows:
    """Windows of the real records (``records``: {file stem: class name}, default
    :data:`REAL_RECORDS`) of ``data_dir``; shaft speed from each record's rpm; at most
    ``max_windows`` (the first ones) per record when given; ``features`` a name of
    :data:`FEATURE_SETS`; ``sample_rate_Hz``: resample every record to it first (polyphase,
    anti-aliased; default: each record's own rate)."""
    from fractions import Fraction

    import scipy.signal as ss

    fn, names = _feature_set(features)
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
        if sample_rate_Hz is not None and float(sample_rate_Hz) != fs:
            q = Fraction(float(sample_rate_Hz) / fs).limit_denominator(1000)
            x = ss.resample_poly(x, q.numerator, q.denominator)
            fs = fs * q.numerator / q.denominator
        W = cut_windows(x, fs, window_s)[:max_windows]
        F.append(fn(W, fs, fr, orders))
        y += [CLASSES.index(cls)] * len(W)
        g += [stem] * len(W)
        sh += [fr] * len(W)
    return Windows(np.concatenate(F), np.asarray(y), np.asarray(g), np.asarray(sh), names)


def simulated_windows(path, orders: DefectFrequencies, window_s=None, features="own") -> Windows:
    """Windows of a data set file (``bearingsim dataset``): every item with result 0 cut into
    ``window_s`` windows (default: the whole item), grouped by item index; ``features`` a name
    of :data:`FEATURE_SETS`."""
    import h5py

    fn, names = _feature_set(features)
    with h5py.File(path, "r") as f:
        X = np.asarray(f["signals"], float)
        lab = np.asarray(f["labels"])
        fs = float(f.attrs["sample_rate_Hz"])
    ok = succeeded(lab["result"])
    X, lab = X[ok], lab[ok]
    T = X.shape[1] if window_s is None else int(round(window_s * fs))
    n = X.shape[1] // T
    W = X[:, :n * T].reshape(-1, T)
    rep = lambda a: np.repeat(a, n)
    fr = rep(lab["shaft_Hz"])
    if n < 1:
        raise InputError(f"items of {X.shape[1] / fs:g} s hold no window of {window_s:g} s")
    return Windows(fn(W, fs, fr, orders), rep(lab["fault_class"]).astype(int), rep(lab["index"]), fr, names)


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
    predicted: np.ndarray = None       # (N,) predicted class per real window
    true: np.ndarray = None            # (N,) true class per real window
    group: np.ndarray = None           # (N,) record per real window

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
        imp = dict(sorted(zip(train.feature_names, map(float, est.feature_importances_)), key=lambda kv: -kv[1]))
    return TransferReport(name, cm, per, float(np.nanmean(recall)), recall, len(train.label), len(test.label), imp,
                          pred, np.asarray(test.label), np.asarray(test.group))


@dataclass
class DevFigures:
    """The development-set figures of one :class:`TransferReport` (windows of a subset of
    records): balanced accuracy (mean of the per-class window recalls), per-class recall, worst
    class, and per record its accuracy and its majority vote."""

    classifier: str
    records: tuple                     # the records counted
    balanced_accuracy: float
    recall: dict                       # class -> recall (classes present only)
    worst_class: tuple                 # (class, recall)
    majority_right: float              # fraction of the records whose majority vote is right
    votes: dict                        # record -> (class, accuracy, majority class)


def dev_figures(report: TransferReport, records) -> DevFigures:
    """The figures of ``report`` restricted to the windows of ``records`` (iterable of stems)."""
    records = tuple(r for r in records if np.any(report.group == r))
    if not records:
        raise InputError("dev_figures: none of the records is in the report")
    m = np.isin(report.group, records)
    y, p = report.true[m], report.predicted[m]
    K = len(CLASSES)
    rec = {CLASSES[c]: float(np.mean(p[y == c] == c)) for c in range(K) if np.any(y == c)}
    votes = {}
    for r in records:
        k = report.group == r
        c = int(report.true[k][0])
        counts = np.bincount(report.predicted[k], minlength=K)
        votes[r] = (CLASSES[c], float(counts[c] / k.sum()), CLASSES[int(np.argmax(counts))])
    worst = min(rec.items(), key=lambda kv: kv[1])
    right = np.mean([v[0] == v[2] for v in votes.values()])
    return DevFigures(report.classifier, records, float(np.mean(list(rec.values()))), rec, worst, float(right), votes)


def dev_text(reports, grades=None) -> str:
    """The development-set table: per classifier the figures over every record, over the
    diagnosable (Y-graded, normal included) and the N-graded records, per class, and the list of
    records with grade, accuracy and majority vote."""
    grades = DEV_GRADES if grades is None else grades
    out = []
    for r in reports:
        present = [g for g in dict.fromkeys(r.group.tolist())]
        sets = {"every record": present,
                "Y-graded (normal incl.)": [g for g in present if diagnosable(grades.get(g, "-"))],
                "N-graded (reported, not targeted)": [g for g in present if not diagnosable(grades.get(g, "-"))]}
        out.append(f"{r.classifier} ({r.trained_on} simulated windows -> {r.tested_on} real windows)")
        out.append(f"  {'records':36s} {'n':>3s} {'balanced':>8s} {'worst class':>16s} {'majority':>8s}   "
                   + " ".join(f"{c:>7s}" for c in CLASSES))
        figs = {}
        for name, recs in sets.items():
            if not recs:
                continue
            f = figs[name] = dev_figures(r, recs)
            out.append(f"  {name:36s} {len(recs):3d} {f.balanced_accuracy:8.3f} {f.worst_class[0]:>8s} {f.worst_class[1]:.3f}"
                       f" {f.majority_right:8.2f}   " + " ".join(f"{f.recall[c]:7.2f}" if c in f.recall else "      -"
                                                            for c in CLASSES))
        allf = figs["every record"]
        for rec, (c, acc, maj) in allf.votes.items():
            calls = ", ".join(f"{k} {v:.2f}" for k, v in r.per_record[rec][2].items())
            out.append(f"    {rec:32s} {grades.get(rec, '-'):20s} {c:8s} {acc:5.2f} vote {maj:8s}"
                       f"{'' if maj == c else ' (wrong)':8s} ({calls})")
    return "\n".join(out)


def transfer_benchmark(sim_path, data_dir, orders: DefectFrequencies, window_s=0.2, records=None,
                       classifiers=CLASSIFIERS, max_windows=None, features="own", sample_rate_Hz=None) -> list:
    """Train each classifier on the windows of the data set file ``sim_path``, test on the real
    records (resampled to ``sample_rate_Hz`` when given: the data set's rate); ``features`` a
    name of :data:`FEATURE_SETS`: a :class:`TransferReport` per classifier."""
    require_sklearn()
    train = simulated_windows(sim_path, orders, window_s, features)
    test = real_windows(data_dir, orders, window_s, records, max_windows=max_windows, features=features,
                        sample_rate_Hz=sample_rate_Hz)
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


def composed_dataset(spec, path, ingredients=None):
    """Simulate the data set of ``spec`` into ``path`` with issue 26's ``ingredients`` (of
    :data:`bearingsim.signals.nuisance.INGREDIENTS`; ``()``: none; default None: the spec's own
    ``[dataset] realism_ingredients``, none in the shipped four-class spec since issue 33's
    measurement, docs/realism.md): the data engine builds each inside its device program
    (:func:`bearingsim.signals.signal_stage.finish_items`).  Returns the data set's summary."""
    if ingredients is not None:
        spec = spec.with_value("dataset.realism_ingredients", list(ingredients))
    return make_dataset(spec, path)
