"""Where to look in an envelope spectrum and what a record shows there: the marker lines of a
plot (:func:`defect_markers`), a defect class's line and sidebands (:func:`fault_lines`,
docs/model.md sections 8-9), and the headline metrics of a record (:func:`record_metrics`, the
reference analysis of the real-record table in docs/reference-data.md)."""
from __future__ import annotations

from dataclasses import asdict, dataclass
from numbers import Integral

import numpy as np

from ..errors import InputError, InputTypeError
from ..physics.kinematics import DefectFrequencies
from .checks import BAND_HINT, check_fs, check_freq, check_signal, unpack_band
from .envelope import bandpass

__all__ = ["defect_markers", "fault_lines", "RecordMetrics", "record_metrics"]


# --------------------------------------------------------------------------- markers
def defect_markers(freqs: dict, n_harmonics: int = 5, harmonics_of=("BPFO",)):
    """Marker lines for an envelope-spectrum plot.

    ``freqs`` maps label -> frequency (Hz).  Lines whose label is in
    ``harmonics_of`` (default BPFO) are expanded to ``n_harmonics`` harmonics
    labelled ``"BPFO", "2xBPFO", ..., "5xBPFO"``; all other lines appear once.
    Returns a list of ``(label, frequency)`` in the order of ``freqs``.
    """
    if not isinstance(freqs, dict):
        raise InputTypeError(f"freqs must be a dict label -> frequency (Hz), got {type(freqs).__name__}",
                             "e.g. {'BPFO': 107.4, 'FTF': 11.9, 'shaft': 29.95}")
    if isinstance(n_harmonics, (bool, np.bool_)) or not isinstance(n_harmonics, Integral) or n_harmonics < 1:
        raise InputError(f"n_harmonics must be an integer >= 1, got {n_harmonics!r}",
                         "n_harmonics is the number of harmonics drawn of each line in harmonics_of, e.g. 5")
    expand = {str(h).upper() for h in harmonics_of}
    out = []
    for label, f in freqs.items():
        f = check_freq(f, f"freqs[{label!r}]")
        if f <= 0.0:
            raise InputError(f"freqs[{label!r}] must be > 0 Hz, got {f:g}",
                             "every marker is a positive frequency in Hz")
        if str(label).upper() in expand:
            out.extend((str(label) if k == 1 else f"{k}x{label}", k * f) for k in range(1, int(n_harmonics) + 1))
        else:
            out.append((str(label), f))
    return out


def fault_lines(frequencies: DefectFrequencies, location: str | None = "outer") -> tuple[str, float, dict]:
    """(name, frequency in Hz, envelope-spectrum markers) of a defect class (docs/model.md sections 8, 9).

    ``frequencies``: a simulation's :class:`~bearingsim.physics.kinematics.DefectFrequencies`
    (``DefectFrequencies.from_hz`` reads the ``*_Hz`` fields of a file).  ``location``
    "outer" (or None: healthy, analysed at BPFO): BPFO with FTF and shaft; "inner": BPFI with its
    shaft-rate sidebands BPFI -/+ f_r; "ball": 2 BSF (the pit meets a raceway twice per ball
    turn) with its cage-rate sidebands 2 BSF -/+ FTF."""
    if not isinstance(frequencies, DefectFrequencies):
        raise InputTypeError(f"frequencies must be a DefectFrequencies, got {type(frequencies).__name__}",
                             "DefectFrequencies.from_hz(d) reads a mapping of shaft_Hz, ftf_Hz, bpfo_Hz, bpfi_Hz, bsf_Hz")
    fr, fc, sh = frequencies, float(frequencies.ftf), float(frequencies.shaft)
    if location == "inner":
        f = float(fr.bpfi)
        return "BPFI", f, {"BPFI": f, "BPFI-fr": f - sh, "BPFI+fr": f + sh, "shaft": sh}
    if location == "ball":
        f = 2.0 * float(fr.bsf)
        return "2BSF", f, {"2BSF": f, "2BSF-FTF": f - fc, "2BSF+FTF": f + fc, "FTF": fc}
    if location not in (None, "outer"):
        raise InputError(f"defect location must be 'outer', 'inner', 'ball' or None, got {location!r}",
                         "None analyses a healthy bearing at BPFO")
    f = float(fr.bpfo)
    return "BPFO", f, {"BPFO": f, "FTF": fc, "shaft": sh}


# --------------------------------------------------------------------------- record metrics
@dataclass(frozen=True)
class RecordMetrics:
    """Headline metrics of one vibration record (see :func:`record_metrics`).

    rms                 : RMS of the de-meaned record (its unit, g for the CWRU records)
    kurtosis            : kurtosis E[x^4]/E[x^2]^2 of the de-meaned record (3 for Gaussian noise)
    band_kurtosis       : the same of the band-passed signal
    peak_hz             : squared-envelope-spectrum peak within +-5 % of the fault frequency (Hz)
    peak_order          : peak_hz / shaft_hz
    peak_over_median_db : 20 log10(peak / median of the spectrum over 30-600 Hz)
    peak_over_local_db  : 20 log10(peak / median over 0.5-1.5 x the nominal fault frequency)
    a2_a1, a3_a1        : largest lines within +-1 % of 2 and 3 x peak_hz over the first
    """

    rms: float
    kurtosis: float
    band_kurtosis: float
    peak_hz: float
    peak_order: float
    peak_over_median_db: float
    peak_over_local_db: float
    a2_a1: float
    a3_a1: float

    def as_dict(self) -> dict:
        return asdict(self)


def _largest_near(f, S, f0, rel):
    m = (f > f0 * (1.0 - rel)) & (f < f0 * (1.0 + rel))
    if not m.any():
        raise InputError(f"no spectrum bin within {f0:g} Hz +- {100 * rel:g} %",
                         "the line (fault_order x shaft_hz and its harmonics) must lie below fs/2, and the "
                         "record must be long enough to resolve it")
    i = int(np.argmax(S[m]))
    return float(f[m][i]), float(S[m][i])


def record_metrics(x, fs, shaft_hz, fault_order, band=(2500.0, 5500.0),
                   median_window=(30.0, 600.0)) -> RecordMetrics:
    """RMS, kurtosis and squared-envelope metrics of a record, exactly as the reference analysis.

    This is the procedure of ``../shared/realdata/analyze_real.py`` (fixed band) that produced the
    real-record table of ``docs/reference-data.md``, so simulated and measured records are compared
    with one analysis:

    * ``x`` is de-meaned; RMS and kurtosis (non-excess) of the whole record;
    * band-pass ``band`` (Butterworth order 4, zero phase), squared envelope ``|hilbert|**2``
      minus its mean (:func:`squared_envelope`), symmetric Hann window (``np.hanning``),
      zero-padded to ``nfft = 2**(ceil(log2 n) + 2)``, amplitude ``|rfft| * 2 / sum(w)``;
    * the fault line is the largest bin within ``fault_order * shaft_hz * (1 +- 5 %)`` (no
      interpolation); A2, A3 are the largest bins within ``k * peak_hz * (1 +- 1 %)``;
    * peak over median: against the median of the spectrum over ``median_window`` (30-600 Hz,
      as in docs/reference-data.md) and, as analyze_real.py prints it, over 0.5-1.5 x the nominal
      fault frequency.

    Both peak-over-median figures grow with record length (the line is coherent, the floor is
    not: about +10 log10(T2/T1) dB), so compare records of equal duration.
    """
    import scipy.signal as ss

    fs = check_fs(fs)
    x = check_signal(x, min_len=16)
    shaft_hz = check_freq(shaft_hz, "shaft_hz")
    fault_order = check_freq(fault_order, "fault_order")
    if shaft_hz <= 0.0 or fault_order <= 0.0:
        raise InputError(f"shaft_hz and fault_order must be > 0, got {shaft_hz:g}, {fault_order:g}",
                         "shaft_hz is the shaft speed in Hz (rpm / 60); fault_order the fault line over it "
                         "(e.g. BPFO / f_r)")
    b = unpack_band(band, fs)
    if b is None:
        raise InputError("band must be a pair (f_lo, f_hi) in Hz, got None", BAND_HINT)
    lo, hi = (check_freq(v, "median_window") for v in median_window)
    if not 0.0 <= lo < hi:
        raise InputError(f"median_window must be (lo, hi) with 0 <= lo < hi, got {median_window!r}",
                         "the frequency range (Hz) of the spectrum's floor, default (30, 600)")
    x = x - x.mean()
    m2 = float(np.mean(x * x))
    if m2 == 0.0:
        raise InputError(f"x is constant (all {x.size} samples equal): RMS and kurtosis are undefined",
                         "check the channel and the file of the record")
    y = bandpass(x, fs, *b)
    yc = y - y.mean()
    e2 = np.abs(ss.hilbert(y)) ** 2
    e2 -= e2.mean()
    w = np.hanning(e2.size)
    nfft = 1 << (int(np.ceil(np.log2(e2.size))) + 2)
    S = np.abs(np.fft.rfft(e2 * w, nfft)) * 2.0 / w.sum()
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    f_nom = fault_order * shaft_hz
    f1, a1 = _largest_near(f, S, f_nom, 0.05)
    _, a2 = _largest_near(f, S, 2.0 * f1, 0.01)
    _, a3 = _largest_near(f, S, 3.0 * f1, 0.01)
    med = float(np.median(S[(f > lo) & (f < hi)]))
    loc = float(np.median(S[(f > 0.5 * f_nom) & (f < 1.5 * f_nom)]))
    return RecordMetrics(
        rms=float(np.sqrt(m2)),
        kurtosis=float(np.mean(x**4) / m2**2),
        band_kurtosis=float(np.mean(yc**4) / np.mean(yc * yc) ** 2),
        peak_hz=f1,
        peak_order=f1 / shaft_hz,
        peak_over_median_db=float(20.0 * np.log10(a1 / med)),
        peak_over_local_db=float(20.0 * np.log10(a1 / loc)),
        a2_a1=a2 / a1,
        a3_a1=a3 / a1,
    )
