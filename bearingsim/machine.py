"""Calibrate a data set to your own machine (``bearingsim calibrate``; docs/realism.md,
"Calibrate to your own machine").

An ML user with another rig has a healthy record (and perhaps one record of a known fault) and
the bearing's geometry.  :func:`calibrate_machine` fits what such records determine and writes a
data set spec (the template's geometry, structure and [dataset] ranges, with the fitted values)
that ``bearingsim dataset`` runs.  Each quantity by one documented method:

shaft speed
    Given (``shaft_rpm``), or searched within +-10 % of a nominal speed: the frequency whose
    harmonics k = 1..6 stand highest over the local median of the record's amplitude spectrum
    (Hann window, zero-padded 4x; sum of the positive dB excesses), refined to 1/16 of a bin.
supply lines
    50 and 60 Hz are both tried: the mean dB excess of their harmonics l = 1..4 over the local
    median, leaving out harmonics within 3 resolution bins of a shaft harmonic (those cannot be
    told apart from the shaft's own lines and stay in them).  The better one is kept when its
    excess is >= 6 dB; otherwise no supply lines.
line amplitudes
    One linear least-squares fit of a cosine and a sine at every shaft harmonic k f_r (k = 1..6)
    and every kept supply harmonic (below 0.45 fs) to the whole record: amplitude sqrt(a^2 + b^2).
knocks
    The residual (record minus the fitted lines) is band-passed from 1 kHz to 0.45 fs; samples
    whose Hilbert envelope exceeds 7 robust standard deviations (1.4826 MAD of the band-passed
    signal; a Gaussian envelope exceeds it with probability e^-24.5) are knocks, merged when
    closer than 5 ms.  Rate = knocks / duration; amplitude = the median peak |band-passed
    residual|; frequency = the strongest resonance found (below), damping its fitted ratio.
    Knock segments (20 ms from the onset) are left out of the broadband estimates.
broadband part
    RMS of the residual outside the knock segments (``noise_rms_m_s2``); its shape: the Welch
    PSD (Hann, segments of ~0.1 s) averaged over 48 log-spaced bands from 50 Hz to 0.45 fs
    (``psd_frequencies_Hz`` = band centres, ``psd_levels_dB`` = 10 log10 of the band means).
modulation
    The squared envelope of the broadband part (band-passed from max(500 Hz, 8 f_r, 5 x supply)
    to 0.45 fs): a modulation (1 + m cos 2 pi k f_r t) of noise puts a line 2 m times the
    envelope's mean at k f_r.  The line is the magnitude of the envelope's projection on
    exp(-2 pi i k f_r t), its noise bias removed in power with the mean of six off-line
    projections ((k +- 0.23, 0.31, 0.37) f_r); m_k for k = 1..8, clipped to [0, 0.9].
resonances
    Peaks of the Welch PSD of the residual (~10 Hz bins, smoothed by a 100 Hz moving average)
    between 1 kHz and 0.45 fs with a prominence of at least 3 dB; the strongest (by prominence,
    at most as many as the template has sensor modes).  Damping from the half-power width:
    zeta = width / (2 f_n) at half the peak's prominence above its base (linear PSD), the
    smoothing's width removed in quadrature, clipped to [0.005, 0.3]; a peak no wider than the
    smoothing is a tone and skipped.  The data set draws every sensor mode's frequency in
    [0.85 min, 1.15 max] of the peaks (at most 0.45 fs) and its damping in [0.67, 1.5] x the mean
    fitted ratio; the [dynamics] modes become the peaks (with the template's strongest gains
    when there are fewer peaks than its modes).
levels
    With a fault record of a known class: a few items of that class (:data:`GAIN_ITEMS`) are
    simulated with the spec at the record's speed (no background, signal gain 1, the transfer
    paths drawn as in the data set); the gain is sqrt(max(rms_fault^2 - rms_healthy^2, 0)) /
    median(rms of the items), and ``dataset.signal_gain`` becomes [gain / 3, 3 gain]
    (:data:`GAIN_SPREAD`).  Without one the template's range stays.

The spec: the template case (geometry, materials, structure, [dataset] classes and size ranges)
with ``dynamics.sample_rate_Hz`` = the record's rate, the [dynamics] measurement noise off (the
machine's broadband part replaces it), ``dataset.background = "machine"``, the fitted
[background], ``dataset.speed_rpm`` = the measured speed +-2.5 % (:data:`SPEED_SPREAD`), and the
fitted resonance / gain ranges.  Records are accelerations in g or m/s^2 (``unit``: no default:
a factor 9.81 is not guessed).
"""
from __future__ import annotations

import copy
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.signal as ss

from .background import Background
from .case import case_from_dict, check_sampling, load_case, to_toml
from .case.units import to_si
from .errors import InputError

__all__ = ["MachineCalibration", "calibrate_machine", "read_record", "check_record", "shaft_speed",
           "fit_lines", "fit_knocks", "broadband_shape", "modulation_depths", "psd_resonances",
           "write_spec", "calibrated_transfer", "CalibratedTransfer", "UNITS", "MIN_SECONDS", "MIN_SAMPLE_RATE_HZ", "GAIN_ITEMS",
           "GAIN_SPREAD", "SPEED_SPREAD", "SHAFT_HARMONICS", "LINE_HARMONICS", "MODULATION_HARMONICS", "PSD_POINTS"]

#: record units: factor to m/s^2
UNITS = {"g": 9.80665, "m/s^2": 1.0}
#: shortest record (s): 1 Hz resolution of the lines, 30 revolutions of an 1800 rpm shaft
MIN_SECONDS = 1.0
#: lowest sample rate: the resonance search and the features start at 1 kHz and end at 0.45 fs
MIN_SAMPLE_RATE_HZ = 2400.0
SHAFT_HARMONICS = 6
LINE_HARMONICS = 4
#: shaft-rate modulation of the broadband part fitted at k f_r, k = 1..MODULATION_HARMONICS
MODULATION_HARMONICS = 8
PSD_POINTS = 48
#: items simulated to fit the signal gain to a fault record
GAIN_ITEMS = 6
#: the signal_gain range is [gain / GAIN_SPREAD, gain x GAIN_SPREAD]
GAIN_SPREAD = 3.0
#: dataset.speed_rpm = measured speed x (1 -+ SPEED_SPREAD)
SPEED_SPREAD = 0.025
#: resonance frequency range: [lo, hi] x the fitted peaks; damping range x the fitted ratio
RESONANCE_SPREAD = (0.85, 1.15)
DAMPING_SPREAD = (0.67, 1.5)
_KNOCK_SIGMA = 7.0
_FAULT_CLASSES = ("outer", "inner", "ball")


# ------------------------------------------------------------------------------ inputs
def check_record(x, fs, what="record", case=None, max_rpm=None) -> np.ndarray:
    """The record as a 1-D float64 array, or InputError saying what is wrong (every problem)."""
    problems = []
    try:
        fs_ok = fs is not None and math.isfinite(float(fs)) and float(fs) > 0
    except (TypeError, ValueError):
        fs_ok = False
    if not fs_ok:
        problems.append(f"{what}: sample rate {fs!r} Hz: give a finite sample rate > 0 "
                        "(--sample-rate-Hz, or the key fs of an .npz file)")
    elif float(fs) < MIN_SAMPLE_RATE_HZ:
        problems.append(f"{what}: sample rate {float(fs):g} Hz is too low: calibration needs at least "
                        f"{MIN_SAMPLE_RATE_HZ:g} Hz (resonances and envelope bands from 1 kHz up to 0.45 fs)")
    a = np.asarray(x)
    if a.dtype.kind not in "biuf":
        problems.append(f"{what}: samples of type {a.dtype} are not numbers")
        raise InputError("\n".join(problems))
    if a.ndim == 2 and 1 in a.shape:
        a = a.ravel()
    if a.ndim != 1:
        problems.append(f"{what}: shape {a.shape}: need one channel (a 1-D array or one column)")
    elif a.size == 0:
        problems.append(f"{what}: empty (no samples)")
    else:
        bad = int(np.sum(~np.isfinite(a)))
        if bad:
            problems.append(f"{what}: {bad} of {a.size} samples are NaN or infinite")
        if fs_ok and a.size / float(fs) < MIN_SECONDS:
            problems.append(f"{what}: {a.size} samples = {a.size / float(fs):.3g} s at {float(fs):g} Hz is "
                            f"too short: calibration needs at least {MIN_SECONDS:g} s")
        if not bad and a.size > 1 and np.ptp(a) == 0:
            problems.append(f"{what}: all samples are equal (no signal)")
    if fs_ok and case is not None and max_rpm is not None and float(fs) >= MIN_SAMPLE_RATE_HZ:
        from .case import characteristic_frequencies
        top = max(characteristic_frequencies(case, max_rpm).values())
        if float(fs) < 2.0 * top:
            problems.append(f"{what}: sample rate {float(fs):g} Hz is below twice the bearing's highest "
                            f"defect frequency ({top:.1f} Hz at {max_rpm:g} rpm)")
    if problems:
        raise InputError("\n".join(problems))
    return a.astype(np.float64)


def read_record(path, channel=None, sample_rate=None, unit=None):
    """(samples, sample rate Hz, unit, nominal rpm or None, channel) of a record file: .npz (keys
    like the CWRU files: a channel such as DE, fs, rpm, units), .npy, or .csv / .txt (one column;
    commas, semicolons or white space).  ``sample_rate`` / ``unit`` given override nothing: they
    must agree with the file's own when it has one."""
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such record file")
    if p.is_dir():
        raise InputError(f"{p}: is a directory, not a record file")
    suffix = p.suffix.lower()
    fs_file, unit_file, rpm = None, None, None
    try:
        if suffix == ".npz":
            with np.load(p, allow_pickle=False) as z:
                keys = list(z.files)
                arrays = [k for k in keys if z[k].ndim >= 1 and z[k].size > 16 and z[k].dtype.kind in "biuf"]
                if channel is None:
                    if "DE" in arrays:          # the CWRU convention: the drive-end channel
                        channel = "DE"
                    elif len(arrays) != 1:
                        raise InputError(f"{p}: name the channel (--channel): the file holds "
                                         f"{', '.join(arrays) or 'no signal arrays'}")
                    else:
                        channel = arrays[0]
                if channel not in keys:
                    raise InputError(f"{p}: no channel {channel!r}: the file holds "
                                     f"{', '.join(arrays) or 'no signal arrays'}")
                x = np.asarray(z[channel])
                if "fs" in keys:
                    fs_file = float(z["fs"])
                if "rpm" in keys:
                    rpm = float(z["rpm"])
                if "units" in keys:
                    u = str(z["units"]).strip().lower()
                    unit_file = "g" if u.startswith("g") else "m/s^2" if u.startswith("m/s") else None
        elif suffix == ".npy":
            x = np.load(p, allow_pickle=False)
        elif suffix in (".csv", ".txt"):
            text = p.read_text(encoding="utf-8")
            rows = [r for r in text.replace(";", ",").splitlines() if r.strip() and not r.lstrip().startswith("#")]
            try:
                x = np.array([[float(v) for v in r.replace(",", " ").split()] for r in rows])
            except ValueError:
                raise InputError(f"{p}: not a column of numbers (first row {rows[0][:40]!r})") from None
        else:
            raise InputError(f"{p}: unknown record format {suffix or '(no suffix)'}: use .npz, .npy, .csv or .txt")
    except InputError:
        raise
    except (OSError, ValueError, UnicodeDecodeError) as e:
        raise InputError(f"{p}: cannot read the record: {e}") from None
    if channel is not None and suffix != ".npz":
        raise InputError(f"{p}: --channel {channel} applies to .npz files only")
    if sample_rate is not None and fs_file is not None and not math.isclose(float(sample_rate), fs_file, rel_tol=1e-9):
        raise InputError(f"{p}: --sample-rate-Hz {sample_rate:g} disagrees with the file's fs = {fs_file:g} Hz")
    if unit is not None and unit_file is not None and unit != unit_file:
        raise InputError(f"{p}: --unit {unit} disagrees with the file's units ({unit_file})")
    fs = fs_file if fs_file is not None else sample_rate
    u = unit_file if unit_file is not None else unit
    if fs is None:
        raise InputError(f"{p}: no sample rate: give --sample-rate-Hz (Hz, > 0)")
    if u is None:
        raise InputError(f"{p}: the file does not say its unit: give --unit g or --unit m/s^2")
    if u not in UNITS:
        raise InputError(f"{p}: unit {u!r}: one of {', '.join(UNITS)}")
    return x, fs, u, rpm, channel


# ------------------------------------------------------------------------------ fits
def _amplitude_spectrum(x, fs, pad=4):
    n = x.size
    w = np.hanning(n)
    nfft = 1 << (int(np.ceil(np.log2(n))) + int(np.log2(pad)))
    A = 2.0 * np.abs(np.fft.rfft((x - x.mean()) * w, nfft)) / w.sum()
    return np.fft.rfftfreq(nfft, 1.0 / fs), A


def _excess_db(f, A, span_hz):
    """dB of A over its running median (window ``span_hz``)."""
    from scipy.ndimage import median_filter

    k = max(5, int(round(span_hz / (f[1] - f[0]))) | 1)
    med = median_filter(A, size=k, mode="nearest")
    return 20.0 * np.log10(np.maximum(A, 1e-300) / np.maximum(med, 1e-300))


def shaft_speed(x, fs, nominal_hz, harmonics=SHAFT_HARMONICS, search=0.10) -> float:
    """Shaft frequency (Hz) of a record: harmonic search within +-``search`` of ``nominal_hz``."""
    fmax = min((harmonics + 1) * nominal_hz * (1 + search), 0.45 * fs)
    f, A = _amplitude_spectrum(x, fs)
    m = f <= fmax + 10.0
    f, E = f[m], _excess_db(f[m], A[m], max(4.0, 0.3 * nominal_hz))
    df = f[1] - f[0]
    cand = np.arange(nominal_hz * (1 - search), nominal_hz * (1 + search), df / 16.0)
    ks = np.arange(1, harmonics + 1)
    tot = np.zeros(cand.size)
    for k in ks:
        tot += np.maximum(np.interp(k * cand, f, E), 0.0)
    return float(cand[int(np.argmax(tot))])


def _supply(x, fs, shaft_hz, T):
    """(line frequency, kept harmonic numbers, dB excess) of the better of 50 / 60 Hz."""
    f, A = _amplitude_spectrum(x, fs)
    E = _excess_db(f, A, 8.0)
    res = 1.0 / T
    best = (60.0, [], -np.inf)
    for F in (50.0, 60.0):
        kept, ex = [], []
        for l in range(1, LINE_HARMONICS + 1):
            fl = l * F
            if fl >= 0.45 * fs:
                break
            k = max(1, round(fl / shaft_hz))
            if abs(fl - k * shaft_hz) < 3.0 * res:
                continue
            kept.append(l)
            m = np.abs(f - fl) <= max(2.0 * res, 0.002 * fl)
            ex.append(float(E[m].max()))
        score = float(np.mean(ex)) if ex else -np.inf
        if score > best[2]:
            best = (F, kept, score)
    return best


def fit_lines(x, fs, shaft_hz, line_hz=None, line_harmonics=()):
    """Least-squares amplitudes (m/s^2 if ``x`` is) of the shaft harmonics k = 1..6 and the given
    supply harmonics; returns (shaft amplitudes, line amplitudes (one per harmonic 1..max,
    0 where left out), the fitted lines as a record)."""
    n = x.size
    t = np.arange(n) / fs
    freqs = [k * shaft_hz for k in range(1, SHAFT_HARMONICS + 1)]
    nl = max(line_harmonics, default=0)
    freqs += [l * line_hz for l in line_harmonics]
    use = [i for i, fk in enumerate(freqs) if fk < 0.45 * fs]
    cols = [np.ones(n)]
    for i in use:
        w = 2 * np.pi * freqs[i] * t
        cols += [np.cos(w), np.sin(w)]
    M = np.column_stack(cols)
    c, *_ = np.linalg.lstsq(M, x, rcond=None)
    amps = np.zeros(len(freqs))
    for j, i in enumerate(use):
        amps[i] = math.hypot(c[1 + 2 * j], c[2 + 2 * j])
    lines = M[:, 1:] @ c[1:]
    shaft = amps[:SHAFT_HARMONICS]
    line = np.zeros(nl)
    for l, a in zip(line_harmonics, amps[SHAFT_HARMONICS:]):
        line[l - 1] = a
    return shaft, line, lines


def fit_knocks(r, fs, sigma=_KNOCK_SIGMA):
    """(rate Hz, median peak amplitude, mask of the samples outside knock segments) of a residual."""
    sos = ss.butter(4, [1000.0, 0.45 * fs], btype="bandpass", fs=fs, output="sos")
    y = ss.sosfiltfilt(sos, r)
    s = 1.4826 * np.median(np.abs(y - np.median(y)))
    env = np.abs(ss.hilbert(y))
    over = np.flatnonzero(env > sigma * s)
    keep = np.ones(r.size, bool)
    if over.size == 0 or s == 0:
        return 0.0, 0.0, keep
    gap = int(0.005 * fs)
    starts = [over[0]] + [over[i + 1] for i in np.flatnonzero(np.diff(over) > gap)]
    ends = [over[i] for i in np.flatnonzero(np.diff(over) > gap)] + [over[-1]]
    peaks = []
    for a, b in zip(starts, ends):
        peaks.append(float(np.max(np.abs(y[a:b + 1]))))
        keep[max(0, a - int(0.002 * fs)):a + int(0.020 * fs)] = False
    return len(starts) / (r.size / fs), float(np.median(peaks)), keep


def broadband_shape(r, fs, points=PSD_POINTS):
    """(frequencies Hz, levels dB) of the residual's Welch PSD averaged over ``points``
    log-spaced bands from 50 Hz to 0.45 fs."""
    nper = 1 << int(round(np.log2(fs / 10.0)))
    f, P = ss.welch(r, fs=fs, nperseg=min(nper, r.size))
    edges = np.geomspace(50.0 / 2 ** (1 / 8), 0.45 * fs, points + 1)
    centres = np.sqrt(edges[:-1] * edges[1:])
    lev = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (f >= lo) & (f < hi)
        v = P[m].mean() if m.any() else np.interp(np.sqrt(lo * hi), f, P)
        lev.append(10.0 * np.log10(max(v, 1e-300)))
    return centres, np.asarray(lev)


def modulation_depths(r, fs, shaft_hz, lo_hz, orders=(1, 2), keep=None):
    """Shaft-rate modulation depths of a broadband residual (see the module docstring); ``keep``:
    mask of the samples that count (outside knocks)."""
    sos = ss.butter(4, [lo_hz, 0.45 * fs], btype="bandpass", fs=fs, output="sos")
    e = np.abs(ss.hilbert(ss.sosfiltfilt(sos, r))) ** 2
    t = np.arange(e.size) / fs
    if keep is not None:
        e, t = e[keep], t[keep]
    mean = e.mean()
    ec = e - mean

    def proj(fq):
        return 2.0 * abs(np.mean(ec * np.exp(-2j * np.pi * fq * t)))

    out = []
    for k in orders:
        line = proj(k * shaft_hz)
        off = [proj((k + s * d) * shaft_hz) for d in (0.23, 0.31, 0.37) for s in (-1, 1)]
        a = math.sqrt(max(line ** 2 - float(np.mean(np.square(off))), 0.0))
        out.append(min(a / (2.0 * mean), 0.9) if mean > 0 else 0.0)
    return np.asarray(out)


def psd_resonances(r, fs, count, lo_hz=1000.0, smooth_hz=100.0):
    """[(frequency Hz, damping ratio, prominence dB)] of the strongest PSD peaks (at most
    ``count``) between ``lo_hz`` and 0.45 fs (see the module docstring)."""
    nper = 1 << int(round(np.log2(fs / 10.0)))
    f, P = ss.welch(r, fs=fs, nperseg=min(nper, r.size))
    from scipy.ndimage import median_filter

    df = f[1] - f[0]
    k = max(1, int(round(smooth_hz / df)))
    Pm = median_filter(P, size=max(3, int(round(1.5 * smooth_hz / df)) | 1), mode="nearest")
    Ps = np.convolve(Pm, np.ones(k) / k, mode="same")
    m = (f >= lo_hz) & (f <= 0.45 * fs)
    fb, Pb = f[m], Ps[m]
    L = 10.0 * np.log10(np.maximum(Pb, 1e-300))
    pk, prop = ss.find_peaks(L, prominence=3.0)
    if pk.size == 0:
        return []
    order = np.argsort(prop["prominences"])[::-1]
    widths = ss.peak_widths(Pb, pk[order], rel_height=0.5)[0] * df
    out = []
    for j, w in zip(order, widths):
        fn = float(fb[pk[j]])
        w_true = math.sqrt(max(w * w - (k * df) ** 2, 0.0))
        if w_true < 2.0 * df:         # no wider than the smoothing: a tone, not a resonance
            continue
        zeta = float(np.clip(w_true / (2.0 * fn), 0.005, 0.3))
        out.append((fn, zeta, float(prop["prominences"][j])))
        if len(out) == count:
            break
    return sorted(out)


# ------------------------------------------------------------------------------ calibration
@dataclass
class MachineCalibration:
    """What :func:`calibrate_machine` fitted, the spec's TOML text and the validated case."""

    case: object
    text: str
    sample_rate_Hz: float
    duration_s: float
    shaft_hz: float
    shaft_source: str                  # "given" or "spectrum"
    background: Background
    line_detected: bool
    line_excess_db: float
    resonances: list                   # [(Hz, damping ratio, prominence dB)]
    resonance_range_Hz: tuple | None
    damping_range: tuple | None
    signal_gain: float | None          # fitted to the fault record (None: template's range)
    signal_gain_range: tuple
    fault: dict = field(default_factory=dict)   # class, rpm, rms, healthy rms, simulated rms


def _record_rms(x):
    x = x - x.mean()
    return float(np.sqrt(np.mean(x * x)))


def _fit_gain(raw, fault_class, rpm, excess, fs, items=GAIN_ITEMS, seed=0, tmpdir=None):
    """(gain, median simulated rms) making items of ``fault_class`` at ``rpm`` match ``excess``."""
    import h5py

    from .dataset import make_dataset

    r = copy.deepcopy(raw)
    ds = r["dataset"]
    for c in ("healthy", "outer", "inner", "ball"):
        ds[f"{c}_fraction"] = 1.0 if c == fault_class else 0.0
    ds.update(count=int(items), chunk=int(items), speed_rpm=[float(rpm), float(rpm)], background="none",
              signal_gain=[1.0, 1.0], seed=int(seed))
    case = case_from_dict(r, "<signal gain fit>")
    with tempfile.TemporaryDirectory(dir=tmpdir) as d:
        path = Path(d) / "gain.h5"
        make_dataset(case, path, progress=False)
        with h5py.File(path, "r") as f:
            X = np.asarray(f["signals"], float)
            ok = np.asarray(f["labels"])["result"] == 0
    if not ok.any():
        raise InputError(f"the simulated {fault_class} items for the signal-gain fit all failed")
    X = X[ok] - X[ok].mean(axis=1, keepdims=True)
    sim = float(np.median(np.sqrt(np.mean(X * X, axis=1))))
    return excess / sim, sim


def calibrate_machine(healthy, sample_rate, case, *, unit, shaft_rpm=None, nominal_rpm=None, fault=None,
                      fault_class=None, fault_sample_rate=None, fault_rpm=None, count=None, duration_s=None,
                      seed=None, title=None, gain_items=GAIN_ITEMS, source="healthy record",
                      fault_source="fault record") -> MachineCalibration:
    """Fit the machine's background (and, with a fault record, the signal gain) and build the spec.

    ``healthy`` / ``fault``: 1-D accelerations in ``unit`` ("g" or "m/s^2") at ``sample_rate`` /
    ``fault_sample_rate`` (default: the same); ``case``: the template (a Case or a case name /
    path) with a [dataset]; ``shaft_rpm``: the healthy record's speed when known (else searched
    near ``nominal_rpm``, default the template's operation.speed_rpm); ``fault_rpm`` likewise for
    the fault record (default: searched near the healthy speed); ``count``, ``duration_s``,
    ``seed``: override the template's [dataset] values.  Returns a :class:`MachineCalibration`
    (``.case`` validated, ``.text`` its TOML)."""
    tpl = load_case(case) if isinstance(case, (str, Path)) else case
    if "dataset" not in tpl.raw:
        raise InputError(f"{tpl.source}: the template has no [dataset] section (use e.g. dataset_cwru_4class)")
    if unit not in UNITS:
        raise InputError(f"unit {unit!r}: one of {', '.join(UNITS)}")
    if (fault is None) != (fault_class is None):
        raise InputError("a fault record needs its class (--fault-class outer|inner|ball) and a class its record")
    if fault_class is not None and fault_class not in _FAULT_CLASSES:
        raise InputError(f"fault class {fault_class!r}: one of {', '.join(_FAULT_CLASSES)}")
    nominal = float(nominal_rpm if nominal_rpm is not None else tpl.data["operation"]["speed_rpm"])
    top_rpm = 1.1 * float(shaft_rpm if shaft_rpm is not None else nominal)
    x = check_record(healthy, sample_rate, source, tpl, top_rpm) * UNITS[unit]
    fs = float(sample_rate)
    x = x - x.mean()
    T = x.size / fs
    if shaft_rpm is not None:
        if not (math.isfinite(float(shaft_rpm)) and float(shaft_rpm) > 0):
            raise InputError(f"shaft speed {shaft_rpm!r} rpm: give a finite speed > 0")
        fr, how = float(shaft_rpm) / 60.0, "given"
    else:
        fr, how = shaft_speed(x, fs, nominal / 60.0), "spectrum"
    F, kept, excess_db = _supply(x, fs, fr, T)
    detected = bool(kept) and excess_db >= 6.0
    shaft_amp, line_amp, lines = fit_lines(x, fs, fr, F, kept if detected else ())
    r = x - lines
    M = len(tpl.dynamics_settings().get("resonance_frequencies") or [1])
    res = psd_resonances(r, fs, M)
    kr, ka, keep = fit_knocks(r, fs)
    rb = r[keep]
    noise_rms = _record_rms(rb)
    pf, pl = broadband_shape(rb, fs)
    lo = min(max(500.0, 8.0 * fr, 5.0 * F), 0.3 * fs)
    md = modulation_depths(r, fs, fr, lo, orders=tuple(range(1, MODULATION_HARMONICS + 1)), keep=keep)
    noise_rms /= math.sqrt(1.0 + 0.5 * float(np.sum(md * md)))   # the RMS before the modulation
    kf, kz = (res[int(np.argmax([p[2] for p in res]))][:2] if res else (min(3000.0, 0.3 * fs), 0.05))
    bg = Background(tuple(shaft_amp), F, tuple(line_amp), noise_rms, tuple(pf), tuple(pl), tuple(md),
                    kr, ka if kr > 0 else 0.0, kf, kz)

    raw = copy.deepcopy(tpl.raw)
    raw["title"] = title or f"Data set calibrated to the machine of {Path(source).name}"
    raw["description"] = (f"Written by bearingsim calibrate from {source} ({T:.2f} s at {fs:g} Hz, shaft "
                          f"{60 * fr:.1f} rpm from the {how})" + (f" and a {fault_class} fault record" if fault_class else "")
                          + f"; template {tpl.source}.")
    dyn = raw.setdefault("dynamics", {})
    dyn["sample_rate_Hz"] = fs
    dyn["noise_rms_m_s2"] = 0.0
    dyn.pop("noise_band_Hz", None)
    ds = raw["dataset"]
    rpm = 60.0 * fr
    ds["speed_rpm"] = [round(rpm * (1 - SPEED_SPREAD), 3), round(rpm * (1 + SPEED_SPREAD), 3)]
    raw.setdefault("operation", {})["speed_rpm"] = round(rpm, 3)
    if count is not None:
        ds["count"] = int(count)
    if duration_s is not None:
        ds["duration_s"] = float(duration_s)
    if seed is not None:
        ds["seed"] = int(seed)
    ds["chunk"] = min(int(ds.get("chunk", 16)), int(ds["count"]))
    ds["background"] = "machine"
    ds.pop("background_rms_m_s2", None)
    fr_range = z_range = None
    if res:
        fk = [p[0] for p in res]
        zk = [p[1] for p in res]
        fr_range = (round(max(RESONANCE_SPREAD[0] * min(fk), 200.0), 1),
                    round(min(RESONANCE_SPREAD[1] * max(fk), 0.45 * fs), 1))
        zm = float(np.mean(zk))
        z_range = (round(max(DAMPING_SPREAD[0] * zm, 1e-3), 5), round(min(DAMPING_SPREAD[1] * zm, 0.9), 5))
        ds["resonance_frequency_Hz"] = list(fr_range)
        ds["resonance_damping_ratio"] = list(z_range)
        # the [dynamics] modes: the peaks (in frequency order); fewer peaks than the template's
        # modes keep the template's strongest gains
        g = dyn.get("resonance_gains")
        dyn["resonance_frequencies_Hz"] = [round(v, 1) for v in fk]
        dyn["resonance_damping_ratios"] = [round(v, 5) for v in zk]
        if g is not None and len(g) > 1 and len(g) != len(fk):
            dyn["resonance_gains"] = sorted(float(v) for v in g)[-len(fk):]
        dyn.pop("resonance_frequency_Hz", None)
        dyn.pop("resonance_damping_ratio", None)
    raw["background"] = _background_table(bg)
    gain, fault_info = None, {}
    gain_range = tuple(ds.get("signal_gain", (1.0, 1.0)))
    if fault is not None:
        ffs = float(fault_sample_rate if fault_sample_rate is not None else fs)
        if not math.isclose(ffs, fs, rel_tol=1e-9):
            raise InputError(f"{fault_source}: sample rate {ffs:g} Hz differs from the healthy record's "
                             f"{fs:g} Hz: the data set has one rate")
        y = check_record(fault, ffs, fault_source, tpl, top_rpm) * UNITS[unit]
        frf = float(fault_rpm) / 60.0 if fault_rpm is not None else shaft_speed(y, fs, fr, search=0.03)
        rms_f, rms_h = _record_rms(y), _record_rms(x)
        excess = math.sqrt(max(rms_f ** 2 - rms_h ** 2, 0.0))
        if excess <= 0.05 * rms_h:
            raise InputError(f"{fault_source}: its RMS ({rms_f:.4g} m/s^2) is not above the healthy record's "
                             f"({rms_h:.4g} m/s^2): no fault level to fit the signal gain to")
        probe = case_from_dict(raw, "<calibrated spec>")      # validates before simulating
        gain, sim = _fit_gain(probe.raw, fault_class, 60.0 * frf, excess, fs, gain_items)
        gain_range = (round(gain / GAIN_SPREAD, 5), round(gain * GAIN_SPREAD, 5))
        ds["signal_gain"] = list(gain_range)
        fault_info = {"class": fault_class, "rpm": 60.0 * frf, "rms_m_s2": rms_f, "healthy_rms_m_s2": rms_h,
                      "excess_rms_m_s2": excess, "simulated_rms_m_s2": sim, "items": int(gain_items)}
    header = ("Data set spec calibrated to a machine by `bearingsim calibrate` (docs/realism.md,\n"
              "\"Calibrate to your own machine\"): run it with `bearingsim dataset SPEC.toml -o data.h5`.")
    text = to_toml(raw, header=header)
    out = case_from_dict(raw, "<calibrated spec>")
    check_sampling(out, out.data["dataset"]["speed_rpm"][1], "dataset.speed_rpm max")
    return MachineCalibration(out, text, fs, T, fr, how, bg, detected, float(excess_db), res, fr_range, z_range,
                              gain, tuple(gain_range), fault_info)


def _r(v, d=6):
    return float(f"{float(v):.{d}g}")


def _background_table(bg: Background) -> dict:
    t = {"noise_rms_m_s2": _r(bg.noise_rms),
         "psd_frequencies_Hz": [_r(v, 5) for v in bg.psd_frequencies],
         "psd_levels_dB": [round(float(v), 2) for v in bg.psd_levels_db],
         "shaft_amplitudes_m_s2": [_r(v, 4) for v in bg.shaft_amplitudes],
         "line_frequency_Hz": float(bg.line_frequency),
         "modulation_depths": [round(float(v), 4) for v in bg.modulation_depths],
         "knock_rate_Hz": _r(bg.knock_rate, 4),
         "knock_amplitude_m_s2": _r(bg.knock_amplitude, 4),
         "knock_frequency_Hz": round(float(bg.knock_frequency), 1),
         "knock_damping_ratio": _r(bg.knock_damping, 4)}
    if len(bg.line_amplitudes):
        t["line_amplitudes_m_s2"] = [_r(v, 4) for v in bg.line_amplitudes]
    return t


def write_spec(cal: MachineCalibration, path) -> Path:
    """Write the calibrated spec (TOML) atomically."""
    from .io import atomic_path

    path = Path(path)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(cal.text, encoding="utf-8")
    return path


# ------------------------------------------------------------------------------ transfer check
@dataclass
class CalibratedTransfer:
    """Result of :func:`calibrated_transfer`."""

    calibration: MachineCalibration
    reports: list                      # bearingsim.transfer.TransferReport per classifier
    used: tuple                        # the records the calibration used (file stems)
    tested: tuple                      # the records the benchmark tested on
    count: int
    seconds: float                     # the data set's simulation (compilation included)

    def text(self) -> str:
        from .report import calibration_text
        from .transfer import transfer_text

        return "\n".join([f"calibrated on {', '.join(self.used)} only; tested on the other records: "
                          f"{', '.join(self.tested)}",
                          calibration_text(self.calibration),
                          f"{self.count} items of {self.calibration.case.data['dataset']['duration_s']:g} s "
                          f"at {self.calibration.sample_rate_Hz:g} Hz simulated in {self.seconds:.0f} s",
                          transfer_text(self.reports)])


def calibrated_transfer(template, data_dir, count=400, *, duration_s=0.2, out_dir=None,
                        healthy="cwru_normal_0hp_12k_decimated", fault=None, fault_class=None, seed=0,
                        channel="DE", records=None, progress=False) -> CalibratedTransfer:
    """The issue's check, end to end: calibrate ``template`` (a Case or a name / path) on the
    ``healthy`` record of ``data_dir`` (and at most one ``fault`` record of ``fault_class``),
    simulate ``count`` items of ``duration_s`` at the record's rate, run the transfer benchmark
    (:func:`bearingsim.transfer.transfer_benchmark`, 0.2 s windows) on the real records
    (``records``, default :data:`bearingsim.transfer.REAL_RECORDS`) that the calibration did not
    use.  ``out_dir``: where the spec and the data set go (default: a temporary folder, removed)."""
    from .dataset import make_dataset
    from .features import fault_orders
    from .transfer import REAL_RECORDS, transfer_benchmark

    data_dir = Path(data_dir)
    tpl = load_case(template) if isinstance(template, (str, Path)) else template
    x, fs, unit, rpm, _ = read_record(data_dir / f"{healthy}.npz", channel)
    kw = {}
    if fault is not None:
        y, ffs, _, _, _ = read_record(data_dir / f"{fault}.npz", channel, unit=unit)
        kw = dict(fault=y, fault_class=fault_class, fault_sample_rate=ffs)
    used = (healthy,) + ((fault,) if fault else ())
    tested = {k: v for k, v in (REAL_RECORDS if records is None else records).items() if k not in used}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(out_dir) if out_dir is not None else Path(tmp)
        cal = calibrate_machine(x, fs, tpl, unit=unit, nominal_rpm=rpm, count=count, duration_s=duration_s,
                                seed=seed, source=f"{healthy}.npz", fault_source=f"{fault}.npz", **kw)
        spec = write_spec(cal, out / "calibrated_spec.toml")
        h5 = out / "calibrated.h5"
        s = make_dataset(load_case(spec), h5, progress=progress)
        reports = transfer_benchmark(h5, data_dir, fault_orders(cal.case.bearing()), 0.2, tested)
    return CalibratedTransfer(cal, reports, used, tuple(tested), int(count), s.seconds)
