"""Identify a fault from a measured record (``bearingsim identify``): class and location, defect
length, operating contact angle, shaft speed, each with its uncertainty, or the statement that
the record does not resolve it.  Method and what is (not) identifiable: docs/identify.md.

Everything learned is learned from simulations only (:mod:`bearingsim.realism.identify_bank`: the
bank; :mod:`bearingsim.realism.identify_model`: the calibrated classifier and the size regressor
with its conformal interval).  This module is the estimate:

* the class: the calibrated class probability averaged over the record's 0.2 s windows; below
  :data:`UNCERTAIN_BELOW` the answer is "uncertain" (no size, no angle); the classes known to be
  weak on real records (:data:`WEAK_ON_REAL`) are named in every answer;
* the contact angle from physics alone: the fault line's frequency in the record's squared-
  envelope spectrum (:func:`bearingsim.realism.fault_size.line_frequency`) inverted through the
  kinematics (:func:`bearingsim.realism.fault_size.angle_from_order`), with the resolution interval
  and the interval a mean cage slip of up to :data:`SLIP_MAX` adds;
* the length with its 90 % interval, or "size not resolved" (:func:`size_resolution`) where the
  entry and exit events are closer than the record resolves or the interval spans most of the
  bank's range.

Rendering (text, JSON, figure): :mod:`bearingsim.output.identify_report`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np
import scipy.signal as ss

from ..case import as_scenario, load_case
from ..errors import InputError
from .fault_size import angle_from_order, pass_features
from .identify_bank import BANK_FS, BANK_WINDOW_S, fault_kinematics, measured_shaft_speed
from .identify_model import LEVEL, default_identifier
from ..names import CLASSES, noun_module
from ..signals.features import cut_windows, fault_orders, window_features
from .records import MIN_SECONDS, check_record, read_record

__all__ = ["SLIP_MAX", "CLIP_SAMPLES", "UNCERTAIN_BELOW", "RESOLVE_SPAN", "WEAK_ON_REAL", "Identification",
           "identify", "identify_file", "clipped_fraction", "size_resolution"]

#: the largest mean cage slip (fraction) the angle interval allows for
SLIP_MAX = 0.02
#: a record with at least this many samples within 0.1 % of its largest magnitude is clipped
CLIP_SAMPLES = 3
#: below this calibrated probability of its most probable class a record's class is "uncertain"
#: (no size, no angle): a class given at p >= 0.8 is wrong at most 1 time in 5 on simulated
#: records (the probabilities are calibrated on held-out ones), and the transfer to a real machine
#: only lowers that; below it, a class is closer to a guess between two classes than an answer
UNCERTAIN_BELOW = 0.8
#: a size interval that spans at least this fraction of the bank's length range (in log) says
#: little more than the range itself: "size not resolved"
RESOLVE_SPAN = 0.75
#: classes known to be weak on real records, with what was measured (named in every answer)
WEAK_ON_REAL = {"ball": "ball faults: recall on the real CWRU ball records is ~0.1-0.3 in the transfer "
                        "benchmark (docs/realism.md); a ball fault is often called healthy or inner race"}

@dataclass
class Identification:
    """What :func:`identify` found.  Values in engineering units as named; intervals at
    :data:`LEVEL`; None where not identifiable (``messages`` says why).  ``fault_class`` is
    "uncertain" when the most probable class (``most_probable``) has a probability under
    ``uncertain_below``; ``size_resolved`` False: ``length_mm`` is None and the interval is what the
    data allow; ``weak_classes``: classes known to be weak on real records, with why."""

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
    most_probable: str = ""
    uncertain: bool = False
    size_resolved: bool | None = None
    weak_classes: dict = field(default_factory=dict)
    uncertain_below: float = UNCERTAIN_BELOW
    level: float = LEVEL
    slip_max: float = SLIP_MAX
    window_s: float = BANK_WINDOW_S


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
    how messages name the record (its file name, from :func:`identify_file`).  ``location_hint``:
    a class taken as known (never "uncertain"; the size and angle of that class), e.g. to measure
    the size interval's coverage apart from class errors."""
    if location_hint is not None and location_hint not in CLASSES:
        raise InputError(f"location_hint {location_hint!r}: must be one of {', '.join(CLASSES)} (or None)",
                         hint="give the class the record is known to have, or None to identify it")
    sc = as_scenario(load_case(case) if isinstance(case, (str, Path)) else case)
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
    b = sc.bearing
    nominal = float(rpm) if rpm is not None else sc.speed_rpm
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
    top = CLASSES[int(np.argmax(proba))]
    cls = top if location_hint is None else location_hint
    c = CLASSES.index(cls)
    uncertain = location_hint is None and float(proba[c]) < UNCERTAIN_BELOW
    res = Identification("uncertain" if uncertain else cls, {k: float(p) for k, p in zip(CLASSES, proba)},
                         float(fr), 60.0 * float(fr), windows=int(len(W)), clipped=clipped, sample_rate_hz=fs,
                         messages=msgs, most_probable=top, uncertain=uncertain, weak_classes=dict(WEAK_ON_REAL))
    res.identifiable = {"class": not uncertain, "length": False, "contact_angle": False, "depth": False,
                        "axial_load": False}
    msgs.append("depth: not identifiable from one record (the bank's pits are all 0.011 in deep; "
                "the depth changes the level, which the unknown transfer path hides)")
    msgs += [f"weak on real records: {why}" for why in WEAK_ON_REAL.values()]
    if uncertain:
        second = sorted(range(len(CLASSES)), key=lambda k: -proba[k])[1]
        msgs.append(f"class uncertain: the most probable class, {top}, has p = {proba[c]:.2f} < {UNCERTAIN_BELOW:g} "
                    f"(next: {CLASSES[second]}, p = {proba[second]:.2f}); size and contact angle not given")
        return res
    if cls == "healthy":
        msgs.append("no fault signature: healthy (size and contact angle not identifiable)")
        return res
    # the fault line: its frequency gives the contact angle
    line, v, _ = fault_kinematics(x, fs, b, fr, cls, o)
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
    res.length_interval_mm = (max(lo, ident.prior_mm[0]) if hi > ident.prior_mm[0] else lo,
                              min(hi, ident.prior_mm[1]) if lo < ident.prior_mm[1] else hi)
    resolved, why = size_resolution(math.exp(logL), res.length_interval_mm, ident.prior_mm, res.resolvable_mm)
    res.size_resolved = bool(resolved and not clipped)
    iv = f"{res.length_interval_mm[0]:.2f}-{res.length_interval_mm[1]:.2f} mm"
    if clipped:
        msgs.append(f"size: bounds only ({iv}): the record is clipped")
    elif not resolved:
        msgs.append(f"size not resolved: {why}; the {LEVEL:.0%} interval is {iv}")
    else:
        res.length_mm = math.exp(logL)
        res.identifiable["length"] = True
    msgs.append(f"size: {LEVEL:.0%} interval from simulated records the estimator never saw; lengths outside "
                f"{ident.prior_mm[0]:.2f}-{ident.prior_mm[1]:.2f} mm (the bank's range) are not identifiable; "
                f"entry and exit events closer than {res.resolvable_mm:.2f} mm (v / 0.45 fs at 12 kHz) are not "
                "resolved in time")
    return res


def size_resolution(length_mm, interval_mm, prior_mm, resolvable_mm, span=RESOLVE_SPAN):
    """(resolved, why not) of a length estimate: not resolved when the estimate is under
    ``resolvable_mm`` (its entry and exit events are closer than the record's sample rate
    separates at the measured surface speed: the number would rest on the events' spectral shape
    through an unknown transfer path), or when the interval spans at least ``span`` of the prior
    ``prior_mm`` in log (it says little more than the bank's range)."""
    if length_mm < resolvable_mm:
        return False, (f"the estimate ({length_mm:.2f} mm) is under the {resolvable_mm:.2f} mm whose entry and exit "
                       "events this sample rate and speed separate")
    lo, hi = interval_mm
    frac = math.log(hi / lo) / math.log(prior_mm[1] / prior_mm[0])
    if frac >= span:
        return False, (f"the interval spans {100 * frac:.0f} % of the bank's range {prior_mm[0]:.2f}-{prior_mm[1]:.2f} mm "
                       f"(log scale; at least {100 * span:.0f} % says little beyond it)")
    return True, ""


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




# ``bearingsim.identify(...)`` calls :func:`identify` (the package exports this module as its noun)
noun_module(__name__, "identify")
