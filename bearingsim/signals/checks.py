"""The input checks of the signal-processing functions (:mod:`.envelope`, :mod:`.lines`): a
sample rate, a 1-D real finite record, a frequency, a band below Nyquist.  Each refusal is an
:class:`~bearingsim.errors.InputError` naming the argument, with a hint."""
from __future__ import annotations

from numbers import Real

import numpy as np

from ..errors import InputError, InputTypeError

__all__ = ["BAND_HINT", "check_fs", "check_signal", "check_freq", "check_band", "unpack_band"]

BAND_HINT = "the band is (f_lo, f_hi) in Hz with 0 < f_lo < f_hi < fs/2"


def check_fs(fs) -> float:
    if isinstance(fs, (bool, np.bool_)) or not isinstance(fs, (Real, np.integer, np.floating)):
        raise InputTypeError(f"fs must be a real number (sampling frequency in Hz), got {type(fs).__name__}",
                             "pass the sample rate as a float or int, e.g. fs=12000.0")
    fs = float(fs)
    if not np.isfinite(fs) or fs <= 0.0:
        raise InputError(f"fs must be a finite sampling frequency > 0 Hz, got {fs}",
                         "the sample rate of the record in Hz, e.g. 12000")
    return fs


def check_signal(x, name: str = "x", min_len: int = 2) -> np.ndarray:
    a = np.asarray(x)
    if np.iscomplexobj(a):
        raise InputError(f"{name} must be real-valued, got a complex array",
                         f"pass the real part (np.real({name})) or one real channel")
    if a.ndim != 1:
        raise InputError(f"{name} must be a 1-D array (one channel), got shape {a.shape}",
                         f"pass one channel, e.g. {name}[:, 0] of a (samples, channels) array")
    try:
        a = a.astype(float, copy=False)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be numeric, got dtype {a.dtype}",
                         "pass the samples as a float array") from exc
    if a.size < min_len:
        raise InputError(f"{name} needs at least {min_len} samples, got {a.size}", "pass a longer record")
    bad = ~np.isfinite(a)
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"{name} must be finite: {int(bad.sum())} NaN/inf value(s), first at index {i} ({a[i]})",
                         "remove or interpolate the non-finite samples before the analysis")
    return a


def check_freq(value, name: str) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (Real, np.integer, np.floating)):
        raise InputTypeError(f"{name} must be a real number (Hz), got {type(value).__name__}",
                             f"pass {name} as a float or int in Hz")
    value = float(value)
    if not np.isfinite(value):
        raise InputError(f"{name} must be finite, got {value}", f"pass {name} as a finite frequency in Hz")
    return value


def check_band(f_lo, f_hi, fs: float) -> tuple[float, float]:
    f_lo = check_freq(f_lo, "f_lo")
    f_hi = check_freq(f_hi, "f_hi")
    nyq = fs / 2.0
    if f_lo <= 0.0:
        raise InputError(f"f_lo must be > 0 Hz, got {f_lo:g}", BAND_HINT)
    if f_hi >= nyq:
        raise InputError(f"f_hi must be < fs/2 = {nyq:g} Hz (Nyquist), got {f_hi:g}", BAND_HINT)
    if f_lo >= f_hi:
        raise InputError(f"f_lo must be < f_hi, got f_lo = {f_lo:g} Hz >= f_hi = {f_hi:g} Hz", BAND_HINT)
    return f_lo, f_hi


def unpack_band(band, fs: float):
    if band is None:
        return None
    try:
        f_lo, f_hi = band
    except (TypeError, ValueError) as exc:
        raise InputError(f"band must be None or a pair (f_lo, f_hi) in Hz, got {band!r}", BAND_HINT) from exc
    return check_band(f_lo, f_hi, fs)
