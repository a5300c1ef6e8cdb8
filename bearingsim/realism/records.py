"""Record files of an ML user's machine (``bearingsim calibrate``, ``bearingsim spectrum``): reading
.npz (the CWRU layout: a channel such as DE, fs, rpm, units), .npy, .csv / .txt (one column) and
.wav (PCM or float; the sample rate from the file, integer samples scaled to +-1 full scale,
``--channel`` a channel number of a multi-channel file), and the checks a
record must pass before anything is fitted to it (sample rate, length, finite samples, one
channel), every problem in one :class:`~bearingsim.errors.InputError` (exit code 2)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..case import highest_frequency, nominal_frequencies
from ..errors import InputError

__all__ = ["UNITS", "MIN_SECONDS", "MIN_SAMPLE_RATE_HZ", "RECORD_SUFFIXES", "check_record", "read_record"]

#: record units: factor to m/s^2
UNITS = {"g": 9.80665, "m/s^2": 1.0}
#: shortest record (s): 1 Hz resolution of the lines, 30 revolutions of an 1800 rpm shaft
MIN_SECONDS = 1.0
#: lowest sample rate: the resonance search and the features start at 1 kHz and end at 0.45 fs
MIN_SAMPLE_RATE_HZ = 2400.0


def check_record(x, fs, what="record", case=None, max_rpm=None,
                 needs=("calibration", None, "resonances and envelope bands from 1 kHz up to 0.45 fs")) -> np.ndarray:
    """The record as a 1-D float64 array, or InputError saying what is wrong (every problem).
    ``needs``: (the command, its lowest sample rate in Hz (None: :data:`MIN_SAMPLE_RATE_HZ`), why),
    for the message of a sample rate too low."""
    purpose, min_fs, why = needs
    min_fs = MIN_SAMPLE_RATE_HZ if min_fs is None else float(min_fs)
    problems = []
    try:
        fs_ok = fs is not None and math.isfinite(float(fs)) and float(fs) > 0
    except (TypeError, ValueError):
        fs_ok = False
    if not fs_ok:
        problems.append(f"{what}: sample rate {fs!r} Hz: give a finite sample rate > 0 "
                        "(--sample-rate-Hz, or the key fs of an .npz file)")
    elif float(fs) < min_fs - 1e-6:
        problems.append(f"{what}: sample rate {float(fs):g} Hz is too low: {purpose} needs at least "
                        f"{min_fs:g} Hz ({why})")
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
                            f"too short: {purpose} needs at least {MIN_SECONDS:g} s")
        if not bad and a.size > 1 and np.ptp(a) == 0:
            problems.append(f"{what}: all samples are equal (no signal)")
    if fs_ok and case is not None and max_rpm is not None and float(fs) >= MIN_SAMPLE_RATE_HZ:
        top = highest_frequency(nominal_frequencies(case, max_rpm))[1]
        if float(fs) < 2.0 * top:
            problems.append(f"{what}: sample rate {float(fs):g} Hz is below twice the bearing's highest "
                            f"defect frequency ({top:.1f} Hz at {max_rpm:g} rpm)")
    if problems:
        raise InputError("\n".join(problems))
    return a.astype(np.float64)


#: the record formats :func:`read_record` reads
RECORD_SUFFIXES = (".npz", ".npy", ".csv", ".txt", ".wav")


def _read_wav(p, channel):
    """(samples, sample rate) of a .wav file: integer PCM scaled to +-1 full scale."""
    from scipy.io import wavfile

    fs, x = wavfile.read(p)
    if x.dtype.kind in "iu":
        info = np.iinfo(x.dtype)
        x = (x.astype(np.float64) - (0.0 if x.dtype.kind == "i" else (info.max + 1) / 2.0)) / (info.max + 1.0)
    if x.ndim == 2:
        if channel is None and x.shape[1] > 1:
            raise InputError(f"{p}: name the channel (--channel 0..{x.shape[1] - 1}): the file has "
                             f"{x.shape[1]} channels")
        try:
            k = 0 if channel is None else int(channel)
            x = x[:, k]
        except (ValueError, IndexError):
            raise InputError(f"{p}: --channel {channel}: a channel number 0..{x.shape[1] - 1}") from None
    return x, float(fs)


def read_record(path, channel=None, sample_rate=None, unit=None, default_unit=None):
    """(samples, sample rate Hz, unit, nominal rpm or None, channel) of a record file: .npz (keys
    like the CWRU files: a channel such as DE, fs, rpm, units), .npy, .csv / .txt (one column;
    commas, semicolons or white space) or .wav.  ``sample_rate`` / ``unit`` given override
    nothing: they must agree with the file's own when it has one.  ``default_unit``: the unit
    when neither the file nor ``unit`` says (None: that is an error)."""
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
        elif suffix == ".wav":
            x, fs_file = _read_wav(p, channel)
        elif suffix in (".csv", ".txt"):
            text = p.read_text(encoding="utf-8")
            rows = [r for r in text.replace(";", ",").splitlines() if r.strip() and not r.lstrip().startswith("#")]
            try:
                x = np.array([[float(v) for v in r.replace(",", " ").split()] for r in rows])
            except ValueError:
                raise InputError(f"{p}: not a column of numbers (first row {rows[0][:40]!r})") from None
        else:
            raise InputError(f"{p}: unknown record format {suffix or '(no suffix)'}: use .npz, .npy, .csv, .txt or .wav")
    except InputError:
        raise
    except (OSError, ValueError, UnicodeDecodeError) as e:
        raise InputError(f"{p}: cannot read the record: {e}") from None
    if channel is not None and suffix not in (".npz", ".wav"):
        raise InputError(f"{p}: --channel {channel} applies to .npz and .wav files only")
    if sample_rate is not None and fs_file is not None and not math.isclose(float(sample_rate), fs_file, rel_tol=1e-9):
        raise InputError(f"{p}: --sample-rate-Hz {sample_rate:g} disagrees with the file's fs = {fs_file:g} Hz")
    if unit is not None and unit_file is not None and unit != unit_file:
        raise InputError(f"{p}: --unit {unit} disagrees with the file's units ({unit_file})")
    fs = fs_file if fs_file is not None else sample_rate
    u = unit_file if unit_file is not None else unit if unit is not None else default_unit
    if fs is None:
        raise InputError(f"{p}: no sample rate: give --sample-rate-Hz (Hz, > 0)")
    if u is None:
        raise InputError(f"{p}: the file does not say its unit: give --unit g or --unit m/s^2")
    if u not in UNITS:
        raise InputError(f"{p}: unit {u!r}: one of {', '.join(UNITS)}")
    return x, fs, u, rpm, channel
