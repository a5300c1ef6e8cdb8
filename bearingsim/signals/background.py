"""The machine's own vibration, in healthy and faulty records alike (docs/realism.md).

A real accelerometer on a bearing housing does not record the bearing alone: the shaft's
unbalance and misalignment (lines at the shaft frequency and its harmonics), the motor's
electromagnetic forces (lines at the supply frequency and its harmonics; twice the supply
frequency for an induction motor), and the broadband vibration of the rig (flow, gears, the fan,
the coupling, electrical noise), shaped by the structure's resonances and partly modulated by the
shaft's rotation, plus occasional knocks that repeat at no bearing frequency.  A classifier that
has only seen clean simulated records learns that *any* structure means a fault; with this
background in every class it has to learn the fault's own signature.

:func:`background_signal` draws one record of it from a :class:`Background` (all amplitudes
in m/s^2, frequencies in Hz) and a NumPy generator:

``shaft_amplitudes``  (K,) amplitudes of the lines at k f_r, k = 1..K (random phases)
``line_frequency``, ``line_amplitudes``  (L,) amplitudes at l x the supply frequency
``noise_rms``  RMS of the broadband part
``psd_frequencies``, ``psd_levels_db``  its spectral shape: the power spectral density's
    level (dB, any reference: only the shape counts; the RMS sets the level) at these
    frequencies, interpolated linearly in dB over log-frequency and held flat outside them;
    empty: white
``modulation_depths``  (K,) amplitude modulation of the broadband part at k f_r (0-1)
``line_modulation_depths``  (L,) its modulation at l x the supply frequency (an induction
    motor's magnetic forces pulse at twice the supply frequency)
``knock_rate``, ``knock_amplitude``, ``knock_frequency``, ``knock_damping``  Poisson knocks
    (per second; peak amplitude; the ringing resonance and its damping ratio)

:func:`random_background` draws a :class:`Background` from ranges (domain randomisation).
Everything is NumPy and seeded by the caller's generator.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import InputError

__all__ = ["Background", "background_signal", "shaped_noise", "random_background", "BACKGROUND_DEFAULTS"]


class Background(NamedTuple):
    """One machine's background vibration (see the module docstring)."""

    shaft_amplitudes: tuple = ()
    line_frequency: float = 60.0
    line_amplitudes: tuple = ()
    noise_rms: float = 0.0
    psd_frequencies: tuple = ()
    psd_levels_db: tuple = ()
    modulation_depths: tuple = ()
    knock_rate: float = 0.0
    knock_amplitude: float = 0.0
    knock_frequency: float = 3000.0
    knock_damping: float = 0.05
    line_modulation_depths: tuple = ()

    def as_labels(self) -> dict:
        """Scalar summaries for a data set's labels."""
        sa = np.asarray(self.shaft_amplitudes, float)
        la = np.asarray(self.line_amplitudes, float)
        return {"background_noise_rms_m_s2": float(self.noise_rms),
                "background_shaft_rms_m_s2": float(np.sqrt(0.5 * np.sum(sa * sa))),
                "background_line_rms_m_s2": float(np.sqrt(0.5 * np.sum(la * la))),
                "background_knock_rate_Hz": float(self.knock_rate)}


def shaped_noise(rng: np.random.Generator, n, fs, rms, frequencies=(), levels_db=()) -> np.ndarray:
    """``n`` samples of Gaussian noise with RMS ``rms`` and the spectral shape of the PSD table
    (``levels_db`` at ``frequencies``, linear in dB over log f; white when empty)."""
    x = rng.standard_normal(int(n))
    f_tab = np.asarray(frequencies, float)
    if f_tab.size and n > 1:
        if f_tab.size != np.asarray(levels_db).size:
            raise InputError("psd_frequencies and psd_levels_db need the same length, got "
                             f"{f_tab.size} and {np.asarray(levels_db).size}",
                             "one level (dB) per frequency (Hz) of the PSD table")
        X = np.fft.rfft(x)
        f = np.fft.rfftfreq(int(n), 1.0 / float(fs))
        lf = np.log(np.maximum(f, f_tab.min() if f_tab.min() > 0 else 1.0))
        o = np.argsort(f_tab)
        db = np.interp(lf, np.log(np.maximum(f_tab[o], 1e-9)), np.asarray(levels_db, float)[o])
        X *= 10.0 ** (db / 20.0)
        X[0] = 0.0
        x = np.fft.irfft(X, int(n))
    s = float(np.sqrt(np.mean(x * x))) if n else 0.0
    return x * (float(rms) / s) if s > 0 else x * 0.0


def _ring(t, f, zeta):
    wn = 2 * np.pi * f
    wd = wn * np.sqrt(max(1.0 - zeta * zeta, 1e-12))
    return np.where(t >= 0, np.exp(-zeta * wn * np.maximum(t, 0.0)) * np.sin(wd * np.maximum(t, 0.0)), 0.0)


def background_signal(rng: np.random.Generator, n, fs, shaft_hz, bg: Background) -> np.ndarray:
    """One record (``n`` samples at ``fs``) of the background ``bg`` on a shaft turning at
    ``shaft_hz``; draws, in this order: shaft phases, line phases, broadband noise, modulation
    phases, knock times and signs."""
    n = int(n)
    fs = float(fs)
    t = np.arange(n) / fs
    x = np.zeros(n)
    sa = np.asarray(bg.shaft_amplitudes, float)
    ph = rng.uniform(0, 2 * np.pi, sa.size)
    for k, (a, p) in enumerate(zip(sa, ph), start=1):
        if k * shaft_hz < 0.5 * fs:
            x += a * np.cos(2 * np.pi * k * shaft_hz * t + p)
    la = np.asarray(bg.line_amplitudes, float)
    ph = rng.uniform(0, 2 * np.pi, la.size)
    for k, (a, p) in enumerate(zip(la, ph), start=1):
        if k * bg.line_frequency < 0.5 * fs:
            x += a * np.cos(2 * np.pi * k * bg.line_frequency * t + p)
    noise = shaped_noise(rng, n, fs, bg.noise_rms, bg.psd_frequencies, bg.psd_levels_db)
    md = np.asarray(bg.modulation_depths, float)
    ph = rng.uniform(0, 2 * np.pi, md.size)
    lm = np.asarray(bg.line_modulation_depths, float)
    phl = rng.uniform(0, 2 * np.pi, lm.size) if lm.size else ()
    if md.size or lm.size:
        env = 1.0 + sum(m * np.cos(2 * np.pi * k * shaft_hz * t + p) for k, (m, p) in enumerate(zip(md, ph), start=1))
        env = env + sum(m * np.cos(2 * np.pi * k * bg.line_frequency * t + p)
                        for k, (m, p) in enumerate(zip(lm, phl), start=1))
        noise = noise * np.maximum(env, 0.0)
    x += noise
    if bg.knock_rate > 0.0 and bg.knock_amplitude > 0.0:
        m = rng.poisson(bg.knock_rate * n / fs)
        times = rng.uniform(0.0, n / fs, m)
        signs = rng.choice([-1.0, 1.0], m)
        for tk, s in zip(times, signs):
            i0 = int(tk * fs)
            seg = slice(i0, min(n, i0 + int(20.0 / (bg.knock_damping * 2 * np.pi * bg.knock_frequency) * fs) + 1))
            x[seg] += s * bg.knock_amplitude * _ring(t[seg] - tk, bg.knock_frequency, bg.knock_damping)
    return x


#: ranges of :func:`random_background` (domain randomisation), relative to the broadband RMS
BACKGROUND_DEFAULTS = {
    "noise_rms_m_s2": (0.2, 2.0),              # m/s^2: 0.02-0.2 g (the CWRU baseline is 0.07 g)
    "shaft_harmonics": 6,                      # lines at k f_r, k = 1..6
    "shaft_relative": (0.01, 1.0),             # each line's amplitude / noise RMS (log-uniform)
    "line_frequency_Hz": (50.0, 60.0),         # one of the two supply frequencies
    "line_harmonics": 4,
    "line_relative": (0.003, 0.3),
    "psd_bumps": (1, 4),                       # resonances shaping the broadband part
    "psd_bump_Hz": (300.0, 5500.0),
    "psd_bump_db": (0.0, 25.0),
    "psd_bump_octaves": (0.1, 0.7),
    "psd_tilt_db_per_octave": (-6.0, 3.0),
    "modulation_harmonics": 8,                 # shaft-synchronous modulation at k f_r, k = 1..8
    "modulation_depth": (0.0, 0.4),            # a harmonic's depth where it is strong ...
    "modulation_strong": 0.4,                  # ... with this probability; else up to 0.03
    "line_modulation_harmonics": 2,            # at the supply frequency and twice it
    "knock_rate_Hz": (0.0, 20.0),
    "knock_relative": (0.5, 8.0),              # knock peak / noise RMS
    "knock_Hz": (1000.0, 5500.0),
    "knock_damping": (0.01, 0.08),
}


def _logu(rng, lo, hi, size=None):
    return np.exp(rng.uniform(np.log(lo), np.log(hi), size))


def random_background(rng: np.random.Generator, fs, ranges=None) -> Background:
    """A :class:`Background` drawn from ``ranges`` (default :data:`BACKGROUND_DEFAULTS`):
    levels log-uniform, frequencies of the PSD's resonance bumps log-uniform below 0.45 fs."""
    r = dict(BACKGROUND_DEFAULTS, **(ranges or {}))
    rms = float(_logu(rng, *r["noise_rms_m_s2"]))
    sa = rms * _logu(rng, *r["shaft_relative"], int(r["shaft_harmonics"]))
    lf = float(rng.choice(np.asarray(r["line_frequency_Hz"], float)))
    la = rms * _logu(rng, *r["line_relative"], int(r["line_harmonics"]))
    top = 0.45 * float(fs)
    grid = np.geomspace(50.0, max(top, 100.0), 48)
    tilt = rng.uniform(*r["psd_tilt_db_per_octave"])
    level = tilt * np.log2(grid / grid[0])
    nb = int(rng.integers(r["psd_bumps"][0], r["psd_bumps"][1] + 1))
    power = 10.0 ** (level / 10.0)
    for _ in range(nb):
        fc = float(_logu(rng, r["psd_bump_Hz"][0], min(r["psd_bump_Hz"][1], top)))
        h = 10.0 ** (rng.uniform(*r["psd_bump_db"]) / 10.0)
        w = rng.uniform(*r["psd_bump_octaves"])
        power = power + h * np.exp(-0.5 * (np.log2(grid / fc) / w) ** 2) * 10.0 ** (level / 10.0)
    K = int(r["modulation_harmonics"])
    strong = rng.random(K) < float(r["modulation_strong"])
    md = np.where(strong, rng.uniform(*r["modulation_depth"], K), rng.uniform(0.0, 0.03, K))
    L = int(r["line_modulation_harmonics"])
    strong_l = rng.random(L) < float(r["modulation_strong"])
    lmd = np.where(strong_l, rng.uniform(*r["modulation_depth"], L), rng.uniform(0.0, 0.03, L))
    kr = float(rng.uniform(*r["knock_rate_Hz"]))
    return Background(tuple(sa), lf, tuple(la), rms, tuple(grid), tuple(10.0 * np.log10(power)), tuple(md),
                      kr, rms * float(_logu(rng, *r["knock_relative"])),
                      float(_logu(rng, r["knock_Hz"][0], min(r["knock_Hz"][1], top))),
                      float(rng.uniform(*r["knock_damping"])), tuple(lmd))
