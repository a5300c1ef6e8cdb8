"""What ``bearingsim identify`` learns from its bank (:mod:`bearingsim.realism.identify_bank`): the
classifier, its calibration on items it never saw, and the size regressor with its conformal
interval.  The bank's label split decides who sees what:

* split 0 (train): the random forest of the class and the gradient-boosted regression of
  log(length);
* split 1 (validation): the temperature that calibrates the class probabilities (one number,
  fitted by likelihood on these items and on the training items' out-of-bag probabilities:
  items the trees that judge them never saw) and the split-conformal quantile of the size
  interval;
* split 2 (test): seen by nothing; the expected calibration error before and after the
  temperature and the size interval's coverage are measured there (``Identifier.calibration``).

Without scikit-learn: the family-contrast rule and no size.  Method: docs/identify.md.
"""
from __future__ import annotations

import math
import os
import pickle
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from .identify_bank import BANK_COUNT, BANK_SEED, bank_features, bank_name, build_bank, cache_dir, prior_range_mm
from ..signals.features import FEATURE_NAMES

__all__ = ["LEVEL", "ECE_BINS", "Identifier", "rule_proba", "temperature_scale", "fit_temperature",
           "expected_calibration_error", "train_identifier", "default_identifier", "MODEL_VERSION"]

#: the level of every interval
LEVEL = 0.90
#: bins of the expected calibration error (equal width in the top probability)
ECE_BINS = 10
#: the layout of a pickled identifier (bumped when the class changes: older pickles are retrained)
MODEL_VERSION = 2
#: the floor under a forest probability before its logarithm (a forest of 300 trees gives 1/300 steps)
_P_FLOOR = 1e-3


def _sklearn():
    try:
        import sklearn  # noqa: F401
        return True
    except ImportError:
        return False


def rule_proba(wf):
    """Class probabilities of the family-contrast rule (no scikit-learn): a family 6 dB over the
    others is that class; probabilities from a logistic of the contrast (scale 3 dB)."""
    col = {n: i for i, n in enumerate(FEATURE_NAMES)}
    c = np.stack([wf[:, col["outer_contrast"]], wf[:, col["inner_contrast"]], wf[:, col["ball_contrast"]]], 1)
    z = np.column_stack([np.zeros(len(wf)), (c - 6.0) / 3.0])
    z = np.exp(z - z.max(axis=1, keepdims=True))
    return z / z.sum(axis=1, keepdims=True)


def temperature_scale(p, temperature):
    """Probabilities ``p`` (N, K) through a temperature: softmax(log(max(p, floor)) / T); T > 1
    softens, T < 1 sharpens, T = 1 leaves them (up to the floor)."""
    z = np.log(np.maximum(np.asarray(p, float), _P_FLOOR)) / float(temperature)
    z = np.exp(z - z.max(axis=1, keepdims=True))
    return z / z.sum(axis=1, keepdims=True)


def fit_temperature(p, y) -> float:
    """The temperature (0.05-20) that maximises the likelihood of the labels ``y`` under
    :func:`temperature_scale` of ``p``: a grid of 241 log-spaced values (one parameter; the
    likelihood is smooth in it)."""
    y = np.asarray(y, int)
    if y.size == 0:
        return 1.0
    grid = np.geomspace(0.05, 20.0, 241)
    nll = [-np.mean(np.log(temperature_scale(p, t)[np.arange(y.size), y])) for t in grid]
    return float(grid[int(np.argmin(nll))])


def expected_calibration_error(p, y, bins=ECE_BINS) -> float:
    """Top-label expected calibration error of probabilities ``p`` (N, K) against labels ``y``:
    the items binned by their top probability (``bins`` equal-width bins), the mean over bins of
    |accuracy - mean top probability| weighted by the bin's share of the items."""
    p = np.asarray(p, float)
    y = np.asarray(y, int)
    if y.size == 0:
        return float("nan")
    top = p.max(axis=1)
    right = (p.argmax(axis=1) == y).astype(float)
    k = np.minimum((top * bins).astype(int), bins - 1)
    return float(sum(abs(right[k == b].mean() - top[k == b].mean()) * np.mean(k == b)
                     for b in range(bins) if np.any(k == b)))


@dataclass
class Identifier:
    """The trained parts: ``classifier`` (None: the rule), its ``temperature`` (fitted on the
    validation split), ``regressor`` (None: no size) and the conformal half-width ``q_log`` of
    log(length) at :data:`LEVEL`; ``prior_mm``: the bank's length range (lengths outside it are not
    identifiable); ``bank``: its file; ``calibration``: what was measured on held-out items."""

    classifier: object
    regressor: object
    q_log: float
    prior_mm: tuple
    bank: str = ""
    calibration: dict = field(default_factory=dict)
    temperature: float = 1.0

    def raw_proba(self, wf):
        """The classifier's own class probabilities (N, 4) of window features ``wf``."""
        if self.classifier is None:
            return rule_proba(wf)
        p = np.zeros((len(wf), 4))
        p[:, self.classifier.classes_] = self.classifier.predict_proba(wf)
        return p

    def class_proba(self, wf):
        """Calibrated class probabilities (N, 4): :meth:`raw_proba` through :attr:`temperature`."""
        p = self.raw_proba(wf)
        return p if self.classifier is None else temperature_scale(p, self.temperature)

    def log_length(self, pf, cls, wf):
        """log(length / mm) per window from its pass features, the class and its envelope features."""
        return self.regressor.predict(np.column_stack([pf, np.full(len(pf), cls), wf]))


def _conformal_q(r, level=LEVEL) -> float:
    n = r.size
    return float(np.quantile(r, min(1.0, math.ceil((n + 1) * level) / n))) if n else float("inf")


def train_identifier(feats: dict, bank="", prior_mm=None) -> Identifier:
    """Train on the bank's 'train' split, calibrate on its 'validation' split and measure on its
    'test' split (see the module's docstring).  ``prior_mm``: the length range of the bank's spec
    (default :func:`bearingsim.realism.identify_bank.prior_range_mm`)."""
    tr, va, te = (feats["split"] == s for s in (0, 1, 2))
    fault = feats["cls"] > 0
    prior = prior_range_mm() if prior_mm is None else tuple(prior_mm)
    if not _sklearn():
        return Identifier(None, None, float("nan"), prior, str(bank), {"note": "scikit-learn not installed"})
    from sklearn.ensemble import GradientBoostingRegressor, RandomForestClassifier

    wf, cls = feats["wf"], feats["cls"]
    clf = RandomForestClassifier(n_estimators=300, random_state=0, n_jobs=1, oob_score=True).fit(wf[tr], cls[tr])
    ident = Identifier(clf, None, float("nan"), prior, str(bank))
    # the temperature from items the trees never saw: the validation split and the training items'
    # out-of-bag probabilities (each from the ~37 % of trees that did not draw it)
    oob = np.zeros((int(np.sum(tr)), 4))
    oob[:, clf.classes_] = np.nan_to_num(clf.oob_decision_function_, nan=0.25)
    ident.temperature = fit_temperature(np.concatenate([oob, ident.raw_proba(wf[va])]),
                                        np.concatenate([cls[tr], cls[va]]))
    Xp = np.column_stack([feats["pf"], cls, wf])
    y = np.log(np.where(fault, feats["length_mm"], 1.0))
    ident.regressor = GradientBoostingRegressor(n_estimators=300, max_depth=3, learning_rate=0.05, subsample=0.8,
                                                random_state=0).fit(Xp[tr & fault], y[tr & fault])
    ident.q_log = _conformal_q(np.abs(ident.regressor.predict(Xp[va & fault]) - y[va & fault]))
    r_te = ident.regressor.predict(Xp[te & fault]) - y[te & fault]
    ident.calibration = {
        "calibration_items": int(np.sum(va)), "test_items": int(np.sum(te)), "temperature": ident.temperature,
        "ece_raw_test": expected_calibration_error(ident.raw_proba(wf[te]), cls[te]),
        "ece_test": expected_calibration_error(ident.class_proba(wf[te]), cls[te]),
        "class_accuracy_test": float(np.mean(clf.predict(wf[te]) == cls[te])) if te.any() else float("nan"),
        "size_calibration_items": int(np.sum(va & fault)),
        "size_coverage_test": float(np.mean(np.abs(r_te) <= ident.q_log)) if r_te.size else float("nan"),
        "size_test_items": int(r_te.size),
        "median_rel_error_test": float(np.median(np.abs(np.expm1(r_te)))) if r_te.size else float("nan")}
    return ident


_DEFAULT = {}


def default_identifier(count=BANK_COUNT, seed=BANK_SEED, progress=True) -> Identifier:
    """The identifier of the default bank: the file $BEARINGSIM_IDENTIFY_BANK when set, else
    ``identify_bank_<count>_<seed>_v<format>_<spec digest>.h5`` in :func:`bearingsim.realism.identify_bank.cache_dir`
    (simulated on first use, with an estimate and a progress bar)."""
    env = os.environ.get("BEARINGSIM_IDENTIFY_BANK")
    p = Path(env) if env else cache_dir() / bank_name(count, seed)
    key = str(p)
    if key not in _DEFAULT:
        if env and not p.exists():
            raise InputError(f"BEARINGSIM_IDENTIFY_BANK={env}: no such bank file",
                             hint="unset it to use (and build once) the default bank, or point it to a bank "
                                  "written by bearingsim.realism.identify_bank.build_bank")
        if not p.exists():
            build_bank(p, count, seed, progress)
        _DEFAULT[key] = cached_identifier(p)
    return _DEFAULT[key]


def cached_identifier(p: Path) -> Identifier:
    """The identifier trained on bank ``p``, pickled beside it (keyed by the scikit-learn version,
    :data:`MODEL_VERSION` and the bank's time stamp; retrained when any changes)."""
    try:
        import sklearn
        ver = sklearn.__version__
    except ImportError:
        ver = "none"
    p = Path(p)
    pk = p.with_suffix(f".identifier-{ver}-m{MODEL_VERSION}.pkl")
    if pk.exists() and pk.stat().st_mtime >= p.stat().st_mtime:
        try:
            with open(pk, "rb") as fh:
                return pickle.load(fh)
        except Exception:           # noqa: BLE001 - a stale or partial pickle: retrain
            pass
    ident = train_identifier(bank_features(p), p)
    tmp = pk.with_suffix(".tmp")
    with open(tmp, "wb") as fh:
        pickle.dump(ident, fh)
    os.replace(tmp, pk)
    return ident
