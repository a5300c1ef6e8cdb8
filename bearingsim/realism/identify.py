"""Identify a fault from a measured record (``bearingsim identify``): class and location, defect
length, operating contact angle, shaft speed, each with its uncertainty, and a simulated twin.
Method and what is (not) identifiable: docs/identify.md.

Everything learned is learned from simulations only: a *bank* of items of the shipped four-class
spec (``cases/dataset_cwru_4class.toml`` at 12 kHz, 0.2 s items; seeds of its own) is simulated
once with :func:`bearingsim.datasets.make_dataset` and cached; its windows give

* the class: a random forest on the scale-free envelope features of :mod:`bearingsim.signals.features`
  (probability = the forest's class probability averaged over the record's 0.2 s windows); without
  scikit-learn, the family-contrast rule (the strongest fault family 6 dB over the others);
* the length: a gradient-boosted regression of log(length) on the pass features of
  :mod:`bearingsim.realism.fault_size` (entry/exit event spacing on a length grid through the kinematics)
  and the envelope features,
  with a split-conformal 90 % interval (the residual quantile on bank items the regressor never
  saw).

The contact angle comes from physics alone: the fault line's frequency in the record's squared-
envelope spectrum (:func:`bearingsim.realism.fault_size.line_frequency`) inverted through the kinematics
(:func:`bearingsim.realism.fault_size.angle_from_order`), with the resolution interval and the interval a
mean cage slip of up to :data:`SLIP_MAX` adds.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np

from .background_fit import shaft_speed
from ..case import case_from_dict, load_case
from ..datasets.runner import make_dataset
from ..datasets.writer import CHUNK_FORMAT
from ..errors import InputError
from .fault_size import (PASS_FEATURE_NAMES, angle_from_order, line_frequency, pass_features,
                         surface_speed)
from ..names import CLASSES, noun_module
from ..signals.envelope import envelope_spectrum
from ..signals.features import FEATURE_NAMES, cut_windows, fault_orders, octave_bands, window_features
from .records import MIN_SECONDS, check_record, read_record

__all__ = ["bank_name", "BANK_FS", "BANK_WINDOW_S", "BANK_SEED", "BANK_COUNT", "SLIP_MAX", "LEVEL", "CLASSES",
           "Identification", "Identifier", "bank_spec", "build_bank", "bank_features", "train_identifier",
           "default_identifier", "identify", "identify_file", "clipped_fraction", "identification_to_dict",
           "identification_text", "twin_spec", "twin_record", "bank_twins", "plot_identification",
           "measured_shaft_speed", "fault_kinematics", "cache_dir"]

#: the bank's sample rate (Hz) and window (s): records are resampled to it and cut into windows of it
BANK_FS = 12000.0
BANK_WINDOW_S = 0.2
#: the bank's seed and size (never the seeds of a test set: bench_identify uses 9001)
BANK_SEED = 7001
BANK_COUNT = 400
#: the largest mean cage slip (fraction) the angle interval allows for
SLIP_MAX = 0.02
#: the level of every interval
LEVEL = 0.90
#: a record with at least this many samples within 0.1 % of its largest magnitude is clipped
CLIP_SAMPLES = 3
#: the class must be this probable for a size to be given
MIN_PROBABILITY = 0.6


# ----------------------------------------------------------------------------------- the bank

def bank_spec(count=BANK_COUNT, seed=BANK_SEED, template="dataset_cwru_4class"):
    """The bank's data set spec: the shipped four-class spec at 12 kHz, 0.2 s items."""
    spec = load_case(template) if not hasattr(template, "with_value") else template
    return (spec.with_value("dynamics.sample_rate_Hz", BANK_FS).with_value("dataset.duration_s", BANK_WINDOW_S)
            .with_value("dataset.count", int(count)).with_value("dataset.seed", int(seed)))


def cache_dir() -> Path:
    """Where banks are kept: $BEARINGSIM_CACHE, else ~/.cache/bearingsim."""
    d = os.environ.get("BEARINGSIM_CACHE")
    return Path(d) if d else Path.home() / ".cache" / "bearingsim"


def bank_name(count, seed) -> str:
    """The cached bank's file name: its size and seed, and the data set format it was simulated
    with (a bank from an older engine, whose random streams or physics differ, is not reused)."""
    return f"identify_bank_{count}_{seed}_v{CHUNK_FORMAT}.h5"


def build_bank(path=None, count=BANK_COUNT, seed=BANK_SEED, progress=True) -> Path:
    """Simulate the bank (``count`` items, ``seed``) into ``path`` (HDF5; None: the bank cache,
    :func:`cache_dir`) unless it is there.  Processes that need the same bank at once (test
    workers, notebooks, two shells) build it once: the others wait on a lock file beside it and
    then read it."""
    path = Path(path) if path is not None else cache_dir() / bank_name(count, seed)
    if path.exists():
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    with _exclusive(path.with_name(path.name + ".lock")):
        if not path.exists():
            make_dataset(bank_spec(count, seed), path, progress=progress)
    return path


class _exclusive:
    """An exclusive lock on ``path`` (``fcntl.flock``: released when the holder exits, even by a
    crash); where the platform has no ``fcntl``, no lock (the bank file is written atomically, so
    two builders only waste time)."""

    def __init__(self, path):
        self.path, self.fd = Path(path), None

    def __enter__(self):
        try:
            import fcntl
        except ImportError:         # Windows
            return self
        self.fd = os.open(self.path, os.O_CREAT | os.O_RDWR, 0o644)
        fcntl.flock(self.fd, fcntl.LOCK_EX)
        return self

    def __exit__(self, *exc):
        if self.fd is not None:
            import fcntl

            fcntl.flock(self.fd, fcntl.LOCK_UN)
            os.close(self.fd)
        return False


def measured_shaft_speed(x, fs, nominal_hz) -> float:
    """The shaft frequency (Hz) of a record: the harmonic search of
    :func:`bearingsim.realism.background_fit.shaft_speed` within +-10 % of ``nominal_hz``."""
    return float(shaft_speed(np.asarray(x, float) - np.mean(x), fs, nominal_hz))


def fault_kinematics(x, fs, bearing, fr, location, orders=None):
    """(the fault line of ``location`` measured in ``x``, the contact's surface speed over the
    defect in m/s from the measured line): FTF = BPFO / Z (outer), f_r - BPFI / Z (inner),
    BSF = line / 2 (ball)."""
    o = orders if orders is not None else fault_orders(bearing)
    f_nom = {"outer": o.bpfo, "inner": o.bpfi, "ball": o.two_bsf}[location] * fr
    line = line_frequency(np.asarray(x, float), fs, f_nom, octave_bands(fs), rel=0.03)
    Z = int(bearing.n_balls)
    ftf = {"outer": line.hz / Z, "inner": fr - line.hz / Z}.get(location, o.ftf * fr)
    bsf = 0.5 * line.hz if location == "ball" else 0.5 * o.two_bsf * fr
    return line, surface_speed(bearing, fr, location, ftf, bsf)


def bank_features(path, bearing=None) -> dict:
    """The bank's features (cached as ``<path>.features.npz``): ``wf`` (window features), ``pf``
    (pass features, fault items), ``cls``, ``length_mm``, ``split``, ``fr``."""
    import h5py

    path = Path(path)
    cache = path.with_suffix(".features.npz")
    if cache.exists() and cache.stat().st_mtime >= path.stat().st_mtime:
        with np.load(cache) as z:
            return {k: z[k] for k in z.files}
    if bearing is None:
        bearing = bank_spec(10).bearing()
    with h5py.File(path, "r") as h:
        X = h["signals"][:].astype(float)
        lab = h["labels"][:]
        fs = float(h.attrs.get("sample_rate_Hz", BANK_FS))
    ok = lab["result"] == 0
    X, lab = X[ok], lab[ok]
    cls = np.asarray(lab["fault_class"], int)
    nominal = float(bank_spec(10).data["operation"]["speed_rpm"]) / 60.0
    o = fault_orders(bearing)
    fr = np.array([measured_shaft_speed(x, fs, nominal) for x in X])
    wf = window_features(X, fs, fr, o)
    pf = np.zeros((len(X), len(PASS_FEATURE_NAMES)))
    for i in np.flatnonzero(cls > 0):
        line, v = fault_kinematics(X[i], fs, bearing, fr[i], CLASSES[cls[i]], o)
        pf[i] = pass_features(X[i][None], fs, 1.0 / line.hz, v)[0]
    out = {"wf": wf, "pf": pf, "cls": cls, "length_mm": np.asarray(lab["spall_length_mm"], float),
           "split": np.asarray(lab["split"], int), "fr": fr, "fr_true": np.asarray(lab["shaft_Hz"], float),
           "bpfo_Hz": np.asarray(lab["bpfo_Hz"], float), "bpfi_Hz": np.asarray(lab["bpfi_Hz"], float)}
    np.savez(cache, **out)
    return out


# ----------------------------------------------------------------------------------- the model

def _sklearn():
    try:
        import sklearn  # noqa: F401
        return True
    except ImportError:
        return False


def _rule_proba(wf):
    """Class probabilities of the family-contrast rule (no scikit-learn): a family 6 dB over the
    others is that class; probabilities from a logistic of the contrast (scale 3 dB)."""
    col = {n: i for i, n in enumerate(FEATURE_NAMES)}
    c = np.stack([wf[:, col["outer_contrast"]], wf[:, col["inner_contrast"]], wf[:, col["ball_contrast"]]], 1)
    z = np.column_stack([np.zeros(len(wf)), (c - 6.0) / 3.0])
    z = np.exp(z - z.max(axis=1, keepdims=True))
    return z / z.sum(axis=1, keepdims=True)


@dataclass
class Identifier:
    """The trained parts: ``classifier`` (None: the rule), ``regressor`` (None: no size) and the
    conformal half-width ``q_log`` of log(length) at :data:`LEVEL`; ``prior_mm``: the bank's
    length range (lengths outside it are not identifiable); ``bank``: its file."""

    classifier: object
    regressor: object
    q_log: float
    prior_mm: tuple
    bank: str = ""
    calibration: dict = field(default_factory=dict)

    def class_proba(self, wf):
        if self.classifier is None:
            return _rule_proba(wf)
        p = np.zeros((len(wf), 4))
        p[:, self.classifier.classes_] = self.classifier.predict_proba(wf)
        return p

    def log_length(self, pf, cls, wf):
        """log(length / mm) per window from its pass features, the class and its envelope features."""
        return self.regressor.predict(np.column_stack([pf, np.full(len(pf), cls), wf]))


def prior_range_mm(spec=None) -> tuple:
    """The bank spec's range of defect lengths (mm) over its fault classes: the prior, outside of
    which a length is not identifiable."""
    ds = (spec if spec is not None else bank_spec(10)).data["dataset"]
    keys = ("spall_length_mm", "inner_length_mm", "ball_length_mm")
    return (float(min(ds[k][0] for k in keys if k in ds)), float(max(ds[k][1] for k in keys if k in ds)))


def train_identifier(feats: dict, bank="", prior_mm=None) -> Identifier:
    """Train on the bank's 'train' split; the conformal quantile on the rest (never trained on).
    ``prior_mm``: the length range of the bank's spec (default :func:`prior_range_mm`)."""
    tr = feats["split"] == 0
    cal = ~tr
    fault = feats["cls"] > 0
    prior = prior_range_mm() if prior_mm is None else tuple(prior_mm)
    if not _sklearn():
        return Identifier(None, None, float("nan"), prior, str(bank), {"note": "scikit-learn not installed"})
    from sklearn.ensemble import GradientBoostingRegressor, RandomForestClassifier

    clf = RandomForestClassifier(n_estimators=300, random_state=0, n_jobs=1).fit(feats["wf"][tr], feats["cls"][tr])
    Xp = np.column_stack([feats["pf"], feats["cls"], feats["wf"]])
    y = np.log(np.where(fault, feats["length_mm"], 1.0))
    reg = GradientBoostingRegressor(n_estimators=300, max_depth=3, learning_rate=0.05, subsample=0.8,
                                    random_state=0).fit(Xp[tr & fault], y[tr & fault])
    r = np.abs(reg.predict(Xp[cal & fault]) - y[cal & fault])
    n = r.size
    q = float(np.quantile(r, min(1.0, math.ceil((n + 1) * LEVEL) / n))) if n else float("inf")
    acc = float(np.mean(clf.predict(feats["wf"][cal]) == feats["cls"][cal])) if cal.any() else float("nan")
    return Identifier(clf, reg, q, prior, str(bank),
                      {"calibration_items": int(n), "class_accuracy_held_out": acc,
                       "median_rel_error_held_out": float(np.median(np.abs(np.expm1(
                           reg.predict(Xp[cal & fault]) - y[cal & fault])))) if n else float("nan")})


_DEFAULT = {}


def default_identifier(count=BANK_COUNT, seed=BANK_SEED, progress=True) -> Identifier:
    """The identifier of the default bank: the file $BEARINGSIM_IDENTIFY_BANK when set, else
    ``identify_bank_<count>_<seed>_v<format>.h5`` in :func:`cache_dir` (simulated on first use: a few
    minutes, with a progress bar)."""
    env = os.environ.get("BEARINGSIM_IDENTIFY_BANK")
    p = Path(env) if env else cache_dir() / bank_name(count, seed)
    key = str(p)
    if key not in _DEFAULT:
        if env and not p.exists():
            raise InputError(f"BEARINGSIM_IDENTIFY_BANK={env}: no such bank file")
        if not p.exists():
            build_bank(p, count, seed, progress)
        _DEFAULT[key] = _cached_identifier(p)
    return _DEFAULT[key]


def _cached_identifier(p: Path) -> Identifier:
    """The identifier trained on bank ``p``, pickled beside it (keyed by the scikit-learn version
    and the bank's time stamp; retrained when either changes)."""
    import pickle

    try:
        import sklearn
        ver = sklearn.__version__
    except ImportError:
        ver = "none"
    pk = p.with_suffix(f".identifier-{ver}.pkl")
    if pk.exists() and pk.stat().st_mtime >= p.stat().st_mtime:
        try:
            with open(pk, "rb") as fh:
                return pickle.load(fh)
        except Exception:           # a stale or partial pickle: retrain
            pass
    ident = train_identifier(bank_features(p), p)
    tmp = pk.with_suffix(".tmp")
    with open(tmp, "wb") as fh:
        pickle.dump(ident, fh)
    os.replace(tmp, pk)
    return ident


# ----------------------------------------------------------------------------------- identify

@dataclass
class Identification:
    """What :func:`identify` found.  Values SI-free engineering units as named; intervals at
    :data:`LEVEL`; None where not identifiable (``messages`` says why)."""

    fault_class: str
    probabilities: dict
    shaft_hz: float
    rpm: float
    line_hz: float | None = None
    line_db: float | None = None
    order: float | None = None
    contact_angle_deg: float | None = None
    contact_angle_interval_deg: tuple | None = None
    contact_angle_interval_slip_deg: tuple | None = None
    length_mm: float | None = None
    length_interval_mm: tuple | None = None
    resolvable_mm: float | None = None
    windows: int = 0
    clipped: bool = False
    sample_rate_hz: float = 0.0
    messages: list = field(default_factory=list)
    identifiable: dict = field(default_factory=dict)


def clipped_fraction(x) -> float:
    """Fraction of samples within 0.1 % of the record's largest magnitude.  A clipped channel holds
    several samples on its rails (CWRU 236 and 237: 3-4 samples at +-6.653 g); an unclipped one has
    one largest sample (a few in 10^5 samples of noise fall within 0.1 % of it by chance, rarely 3)."""
    a = np.abs(np.asarray(x, float))
    top = float(np.max(a))
    if top <= 0:
        return 1.0
    return float(np.mean(a >= 0.999 * top))


def _resample(x, fs):
    if abs(fs - BANK_FS) < 1e-6:
        return x
    import scipy.signal as ss

    fr = Fraction(BANK_FS / fs).limit_denominator(2000)
    return ss.resample_poly(x, fr.numerator, fr.denominator)


#: what identify asks of a record's sample rate (check_record's ``needs``)
_NEEDS = ("identify", BANK_FS, "the bank of simulated records it learned from is sampled at 12 kHz")


def identify(x, fs, case, *, rpm=None, identifier=None, location_hint=None,
             min_seconds=MIN_SECONDS, what="record") -> Identification:
    """Identify the fault of record ``x`` (m/s^2 or g: the scale does not matter) sampled at ``fs``
    (Hz, >= 12 kHz) on the bearing of ``case`` (a Case or a shipped name; its geometry is used, its
    operating point is what is estimated).  ``rpm``: the nominal shaft speed (search +-10 %; default
    the case's speed).  ``identifier``: a trained :class:`Identifier` (default: the cached bank's).
    ``min_seconds``: the shortest record accepted (the benchmark's round trip passes the bank's
    own 0.2 s; a record file must hold :data:`bearingsim.realism.records.MIN_SECONDS`).  ``what``:
    how messages name the record (its file name, from :func:`identify_file`)."""
    case = load_case(case) if isinstance(case, (str, Path)) else case
    a = np.asarray(x)
    short = a.ndim == 1 and fs is not None and a.size < MIN_SECONDS * float(fs)
    x = check_record(np.tile(a, int(math.ceil(MIN_SECONDS * float(fs) / max(a.size, 1)))) if short else a, fs,
                     what=what, needs=_NEEDS)
    x = x[:a.size] if short else x
    fs = float(fs)
    if x.size < max(float(min_seconds), BANK_WINDOW_S) * fs:
        raise InputError(f"{what}: {x.size} samples = {x.size / fs:.3g} s at {fs:g} Hz is too short: "
                         f"identify needs at least {max(float(min_seconds), BANK_WINDOW_S):g} s")
    if fs < BANK_FS - 1e-6:
        raise InputError(f"{what}: sample rate {fs:g} Hz is too low: identify needs at least {BANK_FS:g} Hz "
                         "(the bank of simulated records it learned from is sampled at 12 kHz)")
    b = case.bearing()
    nominal = float(rpm) if rpm is not None else float(case.data["operation"]["speed_rpm"])
    if not (math.isfinite(nominal) and nominal > 0):
        raise InputError(f"--rpm {nominal!r}: give the nominal shaft speed in rpm (> 0)")
    ident = identifier if identifier is not None else default_identifier()
    msgs = []
    clip = clipped_fraction(x)
    clipped = clip * x.size >= CLIP_SAMPLES
    if clipped:
        msgs.append(f"the record is clipped ({100 * clip:.3f} % of samples on its rails): the class is "
                    "given, the size is not identifiable (the impulses are cut)")
    x = x - x.mean()
    fr = measured_shaft_speed(x, fs, nominal / 60.0)
    y = _resample(x, fs)
    W = cut_windows(y, BANK_FS, BANK_WINDOW_S)
    o = fault_orders(b)
    wf = window_features(W, BANK_FS, fr, o)
    proba = ident.class_proba(wf).mean(axis=0)
    c = int(np.argmax(proba))
    cls = CLASSES[c] if location_hint is None else location_hint
    c = CLASSES.index(cls)
    res = Identification(cls, {k: float(p) for k, p in zip(CLASSES, proba)}, float(fr), 60.0 * float(fr),
                         windows=int(len(W)), clipped=clipped, sample_rate_hz=fs, messages=msgs)
    res.identifiable = {"class": True, "length": False, "contact_angle": False, "depth": False,
                        "axial_load": False}
    msgs.append("depth: not identifiable from one record (the bank's pits are all 0.011 in deep; "
                "the depth changes the level, which the unknown transfer path hides)")
    if cls == "healthy":
        msgs.append("no fault signature: healthy (size and contact angle not identifiable)")
        return res
    if proba[c] < MIN_PROBABILITY:
        msgs.append(f"the class is uncertain (p = {proba[c]:.2f} < {MIN_PROBABILITY}): size not identifiable")
    # the fault line: its frequency gives the contact angle
    line, v = fault_kinematics(x, fs, b, fr, cls, o)
    res.line_hz, res.line_db = line.hz, line.db
    res.order = line.hz / fr
    if line.db < 6.0:
        msgs.append(f"the {cls} line is only {line.db:.1f} dB over the floor: no clear fault signature; "
                    "size and angle not identifiable")
        return res
    z = 1.6449
    sd_fr = 0.1 * fs / x.size           # shaft speed: a tenth of a bin (harmonic search on a 4x padded spectrum)
    sd_order = math.hypot(line.sd_hz / fr, line.hz * sd_fr / fr ** 2)
    if cls in ("outer", "inner"):
        a = angle_from_order(b, cls, res.order)
        lo_o, hi_o = res.order - z * sd_order, res.order + z * sd_order
        ends = np.degrees(angle_from_order(b, cls, np.array([lo_o, hi_o])))
        ends_slip = np.degrees(angle_from_order(b, cls, np.array([lo_o, hi_o]), SLIP_MAX))
        if np.isfinite(a):
            res.contact_angle_deg = float(np.degrees(a))
            res.identifiable["contact_angle"] = True
        else:
            msgs.append(f"the measured order {res.order:.4f} is outside the kinematic range of this bearing "
                        "(a cage slip or a wrong geometry): contact angle not identifiable")

        def _iv(e):
            e = np.where(np.isfinite(e), e, 0.0)       # NaN: beyond cos a = 1, i.e. angle 0
            return (float(np.min(e)), float(np.max(e)))
        res.contact_angle_interval_deg = _iv(ends)
        both = np.concatenate([ends, ends_slip])
        res.contact_angle_interval_slip_deg = _iv(both)
        msgs.append(f"contact angle: {LEVEL:.0%} interval from the line's resolution assumes no mean cage slip; "
                    f"a cage that lags by up to {100 * SLIP_MAX:g} % widens it to "
                    f"{res.contact_angle_interval_slip_deg[0]:.1f}-{res.contact_angle_interval_slip_deg[1]:.1f} deg "
                    "(slip and angle are not separable from one order)")
    else:
        msgs.append("contact angle: not identifiable from a ball fault (2 BSF depends on the ball's own spin, "
                    "whose slip is unknown)")
    # the size
    if ident.regressor is None:
        msgs.append("size: not identifiable without scikit-learn (pip install 'bearingsim[ml]')")
        return res
    period = 1.0 / line.hz
    pf = pass_features(W, BANK_FS, period, v)
    res.resolvable_mm = float(v / (0.45 * BANK_FS) * 1e3)
    logL = float(np.median(ident.log_length(pf, c, wf)))
    lo, hi = math.exp(logL - ident.q_log), math.exp(logL + ident.q_log)
    res.length_mm = math.exp(logL)
    res.length_interval_mm = (max(lo, ident.prior_mm[0]) if hi > ident.prior_mm[0] else lo,
                              min(hi, ident.prior_mm[1]) if lo < ident.prior_mm[1] else hi)
    if clipped or proba[c] < MIN_PROBABILITY:
        res.length_mm = None
        msgs.append(f"size: bounds only ({res.length_interval_mm[0]:.2f}-{res.length_interval_mm[1]:.2f} mm)")
    else:
        res.identifiable["length"] = True
    msgs.append(f"size: {LEVEL:.0%} interval from simulated records the estimator never saw; lengths outside "
                f"{ident.prior_mm[0]:.2f}-{ident.prior_mm[1]:.2f} mm (the bank's range) are not identifiable; "
                f"entry and exit events closer than {res.resolvable_mm:.2f} mm (v / 0.45 fs at 12 kHz) are not "
                "resolved in time: below it the length rests on the events' spectral shape")
    return res


def identify_file(path, case, *, channel=None, rpm=None, sample_rate=None, identifier=None):
    """(Identification, record in its unit, fs) of a record file (the readers of ``calibrate``)."""
    try:                                # the scale does not matter: a file without units is read as is
        x, fs, _, rpm_file, _ = read_record(path, channel=channel, sample_rate=sample_rate)
    except InputError as e:
        if "does not say its unit" not in str(e):
            raise
        x, fs, _, rpm_file, _ = read_record(path, channel=channel, sample_rate=sample_rate, unit="g")
    x = check_record(x, fs, what=str(path), needs=_NEEDS)
    return identify(x, fs, case, rpm=rpm if rpm is not None else rpm_file, identifier=identifier,
                    what=str(path)), x, fs


# ----------------------------------------------------------------------------------- output

def identification_to_dict(r: Identification) -> dict:
    d = {k: getattr(r, k) for k in r.__dataclass_fields__}
    return json.loads(json.dumps(d, default=lambda v: list(v) if isinstance(v, tuple) else float(v)))


def _f(v, fmt="{:.3f}"):
    return "not identifiable" if v is None else fmt.format(v)


def identification_text(r: Identification) -> str:
    p = ", ".join(f"{k} {v:.2f}" for k, v in r.probabilities.items())
    rows = [f"class: {r.fault_class}  (probabilities: {p}; {r.windows} windows of {BANK_WINDOW_S:g} s)",
            f"shaft speed: {r.shaft_hz:.3f} Hz = {r.rpm:.1f} rpm (from the record's spectrum)"]
    if r.line_hz is not None:
        rows.append(f"fault line: {r.line_hz:.3f} Hz = {r.order:.4f} x f_r, {r.line_db:.1f} dB over the floor")
    if r.fault_class != "healthy":
        ci = r.contact_angle_interval_deg
        rows.append("contact angle: " + _f(r.contact_angle_deg, "{:.1f} deg") +
                    (f"  ({LEVEL:.0%}: {ci[0]:.1f}-{ci[1]:.1f} deg; with up to {100 * SLIP_MAX:g} % slip "
                     f"{r.contact_angle_interval_slip_deg[0]:.1f}-{r.contact_angle_interval_slip_deg[1]:.1f} deg)"
                     if ci else ""))
        li = r.length_interval_mm
        rows.append("defect length: " + _f(r.length_mm, "{:.3f} mm") +
                    (f"  ({LEVEL:.0%}: {li[0]:.3f}-{li[1]:.3f} mm = {li[0] / 25.4:.4f}-{li[1] / 25.4:.4f} in)"
                     if li else ""))
    rows += [f"note: {m}" for m in r.messages]
    return "\n".join(rows)


# ----------------------------------------------------------------------------------- the twin

def twin_spec(r: Identification, count=16, seed=8001):
    """The bank's spec narrowed to the estimate: every item at the identified speed, class and
    length (the transfer path, background, fault level and loads drawn as in the bank): the
    twin is ``count`` machines like the bank's with this fault.  Same shapes as the bank's chunks,
    so the compiled program is the bank's (the JAX compilation cache)."""
    import copy

    raw = copy.deepcopy(bank_spec(count, seed).raw)
    ds = raw["dataset"]
    ds["speed_rpm"] = [float(r.rpm), float(r.rpm)]
    for k in CLASSES:
        ds[f"{k}_fraction"] = 1.0 if k == r.fault_class else 0.0
    if r.fault_class != "healthy":
        L = r.length_mm if r.length_mm is not None else (float(np.sqrt(np.prod(r.length_interval_mm)))
                                                          if r.length_interval_mm else 0.5334)
        key = {"outer": "spall_length_mm", "inner": "inner_length_mm", "ball": "ball_length_mm"}[r.fault_class]
        ds[key] = [float(L), float(L)]
    return case_from_dict(raw, "identify twin")


def twin_record(case, r: Identification, count=16, progress=False):
    """(records (count, T) in m/s^2, fs) of the simulated twin at the estimate (:func:`twin_spec`,
    0.2 s each at 12 kHz)."""
    import tempfile

    import h5py

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "twin.h5"
        make_dataset(twin_spec(r, count), p, progress=progress)
        with h5py.File(p, "r") as h:
            return h["signals"][:].astype(float), BANK_FS


def bank_twins(identifier: Identifier, r: Identification, k=8):
    """(records (k, T), fs) of the ``k`` bank records nearest the estimate (its class; nearest in
    log length and speed): simulations by the engine near the estimate, at no new cost (the
    notebook's twin; ``twin_record`` simulates the estimate itself)."""
    import h5py

    with h5py.File(identifier.bank, "r") as h:
        lab = h["labels"][:]
        c = CLASSES.index(r.fault_class)
        idx = np.flatnonzero((lab["fault_class"] == c) & (lab["result"] == 0))
        if c and r.length_interval_mm:
            L = r.length_mm or float(np.sqrt(np.prod(r.length_interval_mm)))
            d = np.abs(np.log(lab["spall_length_mm"][idx] / L)) + np.abs(lab["speed_rpm"][idx] / r.rpm - 1.0) * 10
        else:
            d = np.abs(lab["speed_rpm"][idx] / r.rpm - 1.0)
        pick = np.sort(idx[np.argsort(d)[:k]])
        return h["signals"][pick].astype(float), float(h.attrs.get("sample_rate_Hz", BANK_FS))


def plot_identification(x, fs, r: Identification, twin=None, path=None, title=""):
    """The record's squared-envelope spectrum with the twins' (their mean, mirrored; each scaled to
    its own peak) and four passes in time of the record and the first twin; returns the figure
    (saved to ``path`` when given).  ``twin``: (records (N, T) or (T,), fs)."""
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 7))
    band = (2000.0, min(5500.0, 0.45 * fs))
    es = envelope_spectrum(np.asarray(x, float), fs, band=band)
    m = es.freqs <= 600
    a1.plot(es.freqs[m], es.amplitude[m] / es.amplitude[m][1:].max(), lw=0.8, label="measured")
    if twin is not None:
        acc = None
        for y in np.atleast_2d(twin[0]):
            et = envelope_spectrum(y, twin[1], band=(band[0], min(band[1], 0.45 * twin[1])))
            a = np.interp(es.freqs[m], et.freqs, et.amplitude)
            a = a / max(a[1:].max(), 1e-300)
            acc = a if acc is None else acc + a
        acc = acc / len(np.atleast_2d(twin[0]))
        a1.plot(es.freqs[m], -acc / max(acc[1:].max(), 1e-300), lw=0.8,
                label=f"simulated twin, mean of {len(np.atleast_2d(twin[0]))} (mirrored)")
    if r.line_hz:
        for k in (1, 2, 3):
            a1.axvline(k * r.line_hz, color="r", ls=":", lw=0.8)
    a1.set_xlabel("frequency (Hz)")
    a1.set_ylabel("squared envelope (normalised)")
    a1.legend(loc="upper right")
    a1.set_title(title or f"identified: {r.fault_class}")
    P = 1.0 / r.line_hz if r.line_hz else 0.05
    n = int(min(4 * P, 0.2) * fs)
    t = np.arange(n) / fs * 1e3
    xs = np.asarray(x, float)[:n]
    a2.plot(t, xs / np.max(np.abs(xs)), lw=0.7, label="measured")
    if twin is not None:
        nt = int(min(4 * P, 0.2) * twin[1])
        tt = np.arange(nt) / twin[1] * 1e3
        ys = np.atleast_2d(twin[0])[0][:nt]
        a2.plot(tt, ys / np.max(np.abs(ys)) - 2.2, lw=0.7, label="twin (offset)")
    a2.set_xlabel("time (ms)")
    a2.set_ylabel("acceleration (normalised)")
    a2.legend(loc="upper right")
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig




# ``bearingsim.identify(...)`` calls :func:`identify` (the package exports this module as its noun)
noun_module(__name__, "identify")
