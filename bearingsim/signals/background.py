"""The machine's own vibration, in healthy and faulty records alike (docs/realism.md).

A real accelerometer on a bearing housing does not record the bearing alone: the shaft's
unbalance and misalignment (lines at the shaft frequency and its harmonics), the motor's
electromagnetic forces (lines at the supply frequency and its harmonics; twice the supply
frequency for an induction motor), and the broadband vibration of the rig (flow, gears, the fan,
the coupling, electrical noise), shaped by the structure's resonances and partly modulated by the
shaft's rotation, plus occasional knocks that repeat at no bearing frequency.  A classifier that
has only seen clean simulated records learns that *any* structure means a fault; with this
background in every class it has to learn the fault's own signature.

:class:`Background` describes one machine's background (all amplitudes in m/s^2, frequencies in
Hz); :func:`draw_background` draws one from an item's key (from the ranges of
:data:`BACKGROUND_DEFAULTS`: domain randomisation) and :func:`background_record` synthesizes its
record (JAX, keyed; the signal stage, :mod:`bearingsim.signals.signal_stage`, calls both):

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

The NumPy synthesis of the same (seeded by a generator) is the tests' independent oracle
(tests/oracles/background_numpy.py).
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["Background", "BACKGROUND_DEFAULTS", "BackgroundDraws", "draw_background", "background_draws",
           "background_record", "synthesize_background", "background_labels", "poisson_capped", "shape_noise",
           "psd_grid"]


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


# --- background ----------------------------------------------------------------------------


def psd_grid(fs) -> np.ndarray:
    """The 48 log-spaced frequencies (Hz) of a drawn background's PSD table."""
    return np.geomspace(50.0, max(0.45 * float(fs), 100.0), 48)


class _Uniforms:
    """Consecutive slices of one vector of uniforms (one random-bits kernel for many draws)."""

    def __init__(self, key, n):
        self.u, self.i = jax.random.uniform(key, (n,), jnp.float64), 0

    def take(self, shape=()):
        k = int(np.prod(shape))
        v = self.u[self.i:self.i + k].reshape(shape)
        self.i += k
        return v

    def uniform(self, lo, hi, shape=()):
        lo, hi = float(lo), float(hi)
        return lo + (hi - lo) * self.take(shape)

    def logu(self, lo, hi, shape=()):
        return jnp.exp(self.uniform(np.log(float(lo)), np.log(float(hi)), shape))


def draw_background(key, fs, ranges=None) -> Background:
    """A :class:`~bearingsim.signals.background.Background` of JAX arrays drawn from ``ranges`` (default
    :data:`~bearingsim.signals.background.BACKGROUND_DEFAULTS`), with the distributions of
    ``random_background`` of the NumPy oracle (tests/oracles/background_numpy.py): levels log-uniform relative to the
    broadband RMS, 50 or 60 Hz supply with equal odds, a PSD table of a tilt plus 1-4
    log-Gaussian bumps (unused bump slots masked), modulation depths strong (uniform in
    ``modulation_depth``) with probability ``modulation_strong`` else uniform 0-0.03."""
    r = dict(BACKGROUND_DEFAULTS, **(ranges or {}))
    top = 0.45 * float(fs)
    K, L = int(r["shaft_harmonics"]), int(r["line_harmonics"])
    b_lo, b_hi = int(r["psd_bumps"][0]), int(r["psd_bumps"][1])
    Km, Lm = int(r["modulation_harmonics"]), int(r["line_modulation_harmonics"])
    u = _Uniforms(key, 9 + K + L + 3 * b_hi + 3 * (Km + Lm))
    rms = u.logu(*r["noise_rms_m_s2"])
    sa = rms * u.logu(*r["shaft_relative"], (K,))
    lfs = jnp.asarray(r["line_frequency_Hz"], jnp.float64)
    lf = lfs[jnp.minimum(jnp.floor(u.take() * lfs.shape[0]).astype(jnp.int32), lfs.shape[0] - 1)]
    la = rms * u.logu(*r["line_relative"], (L,))
    grid = psd_grid(fs)
    tilt = u.uniform(*r["psd_tilt_db_per_octave"])
    base = 10.0 ** (tilt * jnp.log2(grid / grid[0]) / 10.0)
    nb = b_lo + jnp.floor(u.take() * (b_hi - b_lo + 1))
    fc = u.logu(r["psd_bump_Hz"][0], min(r["psd_bump_Hz"][1], top), (b_hi,))
    h = 10.0 ** (u.uniform(*r["psd_bump_db"], (b_hi,)) / 10.0)
    w = u.uniform(*r["psd_bump_octaves"], (b_hi,))
    on = jnp.arange(b_hi) < nb
    bumps = jnp.sum(jnp.where(on[:, None], h[:, None] * jnp.exp(-0.5 * (jnp.log2(grid[None] / fc[:, None])
                                                                           / w[:, None]) ** 2), 0.0), 0)
    power = base * (1.0 + bumps)
    p_strong = float(r["modulation_strong"])

    def depths(n):
        strong = u.take((n,)) < p_strong
        return jnp.where(strong, u.uniform(*r["modulation_depth"], (n,)), u.uniform(0.0, 0.03, (n,)))
    md = depths(Km)
    lmd = depths(Lm)
    kr = u.uniform(*r["knock_rate_Hz"])
    ka = rms * u.logu(*r["knock_relative"])
    kf = u.logu(r["knock_Hz"][0], min(r["knock_Hz"][1], top))
    kz = u.uniform(*r["knock_damping"])
    return Background(sa, lf, la, rms, jnp.asarray(grid), 10.0 * jnp.log10(power), md, kr, ka, kf, kz, lmd)


def background_labels(bg: Background) -> dict:
    """The data set's background labels of ``bg`` (JAX scalars): broadband RMS, the RMS of the
    shaft lines and of the supply lines, the knock rate (Hz)."""
    sa, la = jnp.asarray(bg.shaft_amplitudes, jnp.float64), jnp.asarray(bg.line_amplitudes, jnp.float64)
    return {"background_noise_rms_m_s2": jnp.asarray(bg.noise_rms, jnp.float64),
            "background_shaft_rms_m_s2": jnp.sqrt(0.5 * jnp.sum(sa * sa)),
            "background_line_rms_m_s2": jnp.sqrt(0.5 * jnp.sum(la * la)),
            "background_knock_rate_Hz": jnp.asarray(bg.knock_rate, jnp.float64)}


class BackgroundDraws(NamedTuple):
    """The random numbers one background record consumes (see :func:`background_draws`)."""

    shaft_phases: jnp.ndarray        # (K,)
    line_phases: jnp.ndarray         # (L,)
    noise: jnp.ndarray               # (T,) standard normal
    modulation_phases: jnp.ndarray   # (Km,)
    line_modulation_phases: jnp.ndarray  # (Lm,)
    knock_times: jnp.ndarray         # (Kmax,) s
    knock_signs: jnp.ndarray         # (Kmax,) +-1, 0 in unused slots


def poisson_capped(u, lam, cap):
    """The Poisson(``lam``) count of the uniform ``u`` by inverting its CDF, capped at ``cap``
    (exact below the cap; no rejection loop to compile)."""
    k = jnp.arange(cap, dtype=jnp.float64)
    cdf = jnp.cumsum(jnp.exp(jax.scipy.special.xlogy(k, lam) - lam - jax.scipy.special.gammaln(k + 1.0)))
    return jnp.sum(cdf < u)


def background_draws(key, bg: Background, n, fs, knock_max) -> BackgroundDraws:
    """The random numbers of one record of ``bg``: uniform phases, ``n`` standard normals, a
    Poisson knock count at ``knock_rate n / fs`` (capped at ``knock_max``), uniform knock times
    and signs."""
    kn, ku = jax.random.split(key)
    size = lambda v: len(v) if isinstance(v, tuple) else jnp.shape(v)[0]  # noqa: E731
    sizes = [size(v) for v in (bg.shaft_amplitudes, bg.line_amplitudes, bg.modulation_depths,
                               bg.line_modulation_depths)]
    u = _Uniforms(ku, sum(sizes) + 1 + 2 * knock_max)
    sp, lp, mp, lmp = (u.uniform(0.0, 2 * np.pi, (m,)) for m in sizes)
    count = poisson_capped(u.take(), jnp.asarray(bg.knock_rate, jnp.float64) * (n / float(fs)), knock_max)
    times = u.uniform(0.0, n / float(fs), (knock_max,))
    signs = jnp.where(u.take((knock_max,)) < 0.5, 1.0, -1.0)
    signs = jnp.where(jnp.arange(knock_max) < count, signs, 0.0)
    return BackgroundDraws(sp, lp, jax.random.normal(kn, (int(n),), jnp.float64), mp, lmp, times, signs)


def shape_noise(x, fs, rms, frequencies, levels_db):
    """``shaped_noise`` of the NumPy oracle (tests/oracles/background_numpy.py) of the normals ``x``: the spectrum shaped by the
    PSD table (dB linear over log f, flat outside; the mean removed) in the FFT domain, then
    scaled to ``rms``.  An empty table: white."""
    n = x.shape[-1]
    f_tab = jnp.asarray(frequencies, jnp.float64)
    if f_tab.shape[0] and n > 1:
        o = jnp.argsort(f_tab)
        f_tab, lv = f_tab[o], jnp.asarray(levels_db, jnp.float64)[o]
        X = jnp.fft.rfft(x)
        f = jnp.fft.rfftfreq(n, 1.0 / float(fs))
        fmin = f_tab[0]
        lf = jnp.log(jnp.maximum(f, jnp.where(fmin > 0, fmin, 1.0)))
        db = jnp.interp(lf, jnp.log(jnp.maximum(f_tab, 1e-9)), lv)
        X = (X * 10.0 ** (db / 20.0)).at[0].set(0.0)
        x = jnp.fft.irfft(X, n)
    s = jnp.sqrt(jnp.mean(x * x))
    return jnp.where(s > 0, x * (rms / jnp.where(s > 0, s, 1.0)), 0.0)


def _lines(t, f0, amps, phases, fs):
    """sum_k a_k cos(2 pi k f0 t + p_k) over the harmonics k = 1..K below ``fs`` / 2."""
    K = jnp.shape(amps)[0]
    x = jnp.zeros_like(t)
    if not K:
        return x
    th = 2 * np.pi * f0 * t
    c1, s1 = jnp.cos(th), jnp.sin(th)
    c, s, c_prev, s_prev = c1, s1, jnp.ones_like(t), jnp.zeros_like(t)
    for k in range(1, K + 1):   # cos k th, sin k th by the Chebyshev recurrence: one fused kernel
        a = jnp.where(k * f0 < 0.5 * fs, amps[k - 1], 0.0)
        x = x + a * (c * jnp.cos(phases[k - 1]) - s * jnp.sin(phases[k - 1]))
        c, s, c_prev, s_prev = 2.0 * c1 * c - c_prev, 2.0 * c1 * s - s_prev, c, s
    return x


def _knocks(n, fs, times, amplitudes, f, zeta):
    """sum_j a_j exp(-zeta w tau) sin(w_d tau), tau = t - t_j, over the samples i0_j <= i <
    i0_j + L (i0 = floor(t_j fs), L = floor(20 / (zeta w) fs) + 1): a complex one-pole recursion
    y_i = exp(lambda / fs) y_{i-1} + u_i (lambda = -zeta w + i w_d) with each knock entering at
    its first sample after t_j and leaving at i0 + L; its imaginary part (an associative scan)."""
    wn = 2 * np.pi * f
    lam = -zeta * wn + 1j * wn * jnp.sqrt(jnp.maximum(1.0 - zeta * zeta, 1e-12))
    i0 = jnp.floor(times * fs)
    L = jnp.floor(20.0 / (zeta * wn) * fs) + 1.0
    on, off = i0 + 1.0, i0 + L
    ins = amplitudes * jnp.exp(lam * (on / fs - times))
    outs = -amplitudes * jnp.exp(lam * (off / fs - times))
    idx = jnp.concatenate([on, jnp.where(L > 1.0, off, n + 1.0)])
    idx = jnp.where(idx < n, idx, n).astype(jnp.int32)           # n: dropped
    u = jnp.zeros(n, lam.dtype).at[idx].add(jnp.concatenate([ins, outs]), mode="drop")
    a = jnp.broadcast_to(jnp.exp(lam / fs), (n,))

    def combine(x, y):
        return x[0] * y[0], y[0] * x[1] + y[1]
    _, y = jax.lax.associative_scan(combine, (a, u))
    return jnp.imag(y)


def synthesize_background(bg: Background, draws: BackgroundDraws, fs, shaft_hz):
    """The record of ``bg`` from its random numbers ``draws`` (the synthesis of
    ``background_signal`` of the NumPy oracle (tests/oracles/background_numpy.py)): lines at k f_r and l x the supply
    frequency (below fs/2), the shaped broadband noise times ``max(1 + sum m_k cos(.), 0)``,
    and each knock ``s A exp(-zeta w t) sin(w_d t)`` for 20 time constants."""
    fs = float(fs)
    n = draws.noise.shape[0]
    t = jnp.arange(n) / fs
    sa, la = jnp.asarray(bg.shaft_amplitudes, jnp.float64), jnp.asarray(bg.line_amplitudes, jnp.float64)
    md, lm = jnp.asarray(bg.modulation_depths, jnp.float64), jnp.asarray(bg.line_modulation_depths, jnp.float64)
    x = _lines(t, shaft_hz, sa, draws.shaft_phases, fs) + _lines(t, bg.line_frequency, la, draws.line_phases, fs)
    noise = shape_noise(draws.noise, fs, bg.noise_rms, bg.psd_frequencies, bg.psd_levels_db)
    if md.shape[0] or lm.shape[0]:
        env = 1.0 + _lines(t, shaft_hz, md, draws.modulation_phases, np.inf) \
            + _lines(t, bg.line_frequency, lm, draws.line_modulation_phases, np.inf)
        noise = noise * jnp.maximum(env, 0.0)
    knocks = _knocks(n, fs, draws.knock_times, draws.knock_signs * bg.knock_amplitude, bg.knock_frequency,
                     bg.knock_damping)
    return x + noise + knocks


def background_record(key, bg: Background, n, fs, shaft_hz, knock_max):
    """One record (``n`` samples at ``fs``) of ``bg`` on a shaft at ``shaft_hz``, from ``key``."""
    return synthesize_background(bg, background_draws(key, bg, n, fs, knock_max), fs, shaft_hz)
