"""The NumPy synthesis of a machine's background (the package's former host twin of
:mod:`bearingsim.signals.signal_stage`'s background: ``draw_background``, ``background_record``):
NumPy generators seeded by an integer.  An independent oracle for the tests only: the JAX
synthesis equals it for the same random numbers (tests/test_signal_stage.py), and its physical
properties are tested on it (tests/test_features_background.py, tests/test_machine.py)."""
from __future__ import annotations

import numpy as np

from bearingsim.errors import InputError
from bearingsim.signals.background import BACKGROUND_DEFAULTS, Background


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
