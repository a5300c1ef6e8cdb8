"""The signal stage of a data set's items on the device: every per-item draw and every step from
the simulated housing / sensor acceleration to the stored record, as pure JAX (float64)
functions of the item's ``jax.random`` key, vmapped over the items of a chunk and compiled once.

What it does to one item (the order of :func:`finish_items`):

1. pass-to-pass variability of the defect's impacts (:func:`vary_passes`, the JAX twin of
   ``vary_passes`` of the NumPy oracle (tests/oracles/passes_numpy.py)): log-normal per-pass factors (c.v. = the [dynamics]
   maximum x the pit's unbridged fraction), Gaussian delays, and the intermittent strike of a
   ball pit (:func:`strike_factors`); a varied row is put through the item's sensor modes again
   (:func:`bearingsim.signals.sensor.sensor_filter`, :func:`~bearingsim.signals.sensor.run_filter`:
   the first-order-hold filter every simulation uses); :func:`pass_variability` is this step for
   one record (a single simulation applies it too);
2. the measurement noise (:func:`bearingsim.signals.sensor.measurement_noise`: white or
   band-limited, at an RMS);
3. the machine's background (:func:`draw_background`: the same ranges as
   ``random_background`` of the NumPy oracle (tests/oracles/background_numpy.py); :func:`background_record`: the same
   synthesis as ``background_signal`` of the NumPy oracle (tests/oracles/background_numpy.py): shaft and supply lines,
   broadband noise shaped in the FFT domain, amplitude modulation, knocks, the count capped at
   :attr:`SignalSettings.knock_max`);
4. the fault level (:func:`fault_level`): the record is ``gain a + background``, ``gain`` the
   item's drawn signal gain or, with a target ratio, ``10^(snr/20) rms(background) / rms(a)``
   for a fault class (label ``snr_dB``);
5. issue 26's ingredients where :attr:`SignalSettings.ingredients` names them
   (:mod:`bearingsim.signals.nuisance`, from the item key's ``nuisance`` stream): a ball item's fault
   part re-shaped as real damaged balls show it (before the noise and the fault level), the
   additive nuisance at the background's RMS (after it), the whole record modulated at shaft
   orders (last).

:func:`draw_items` gives the per-item domain-randomisation draws the dynamics needs first
(sensor modes, signal gain, target SNR, strike probability, outer-pit position).

Random streams: every draw comes from ``jax.random.fold_in(key, STREAMS[name])`` of the item's
key (:func:`item_keys`), so an item does not depend on its chunk, the chunk size or the device
count.  The stream numbers are those of :data:`bearingsim.keys.STREAMS` (one registry).
The draws are not NumPy's: a data set made this way is a new version of the random streams.

:class:`SignalSettings` holds everything static (hashable: a compiled program per settings and
shapes); build it with :meth:`SignalSettings.from_dataset` from a ``[dataset]`` table.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .. import keys as _keys
from . import nuisance as _nuisance
from ..errors import InputError
from ..names import CLASS_NUMBER
from .background import BACKGROUND_DEFAULTS, Background
from ..keys import item_keys, stream_key
from .sensor import measurement_noise, run_filter, sensor_filter
from ..programs import jit

__all__ = ["STREAMS", "SignalSettings", "ItemDraws", "BackgroundDraws", "item_keys", "stream_key",
           "draw_items", "draw_background", "background_draws", "background_record", "synthesize_background",
           "background_labels", "poisson_capped", "shape_noise", "psd_grid", "pass_factors", "pass_shifts",
           "strike_factors",
           "vary_passes", "measurement_noise", "fault_level", "pass_variability",
           "finish_item",
           "finish_items", "LABELS"]

#: the item key's sub-streams (``jax.random.fold_in(key, n)``): the one registry, :data:`bearingsim.keys.STREAMS`
STREAMS = _keys.STREAMS

#: label fields :func:`finish_items` returns, each (N,)
LABELS = ("signal_gain", "snr_dB", "pass_amplitude_cv_percent", "pass_delay_sd_percent",
          "background_noise_rms_m_s2", "background_shaft_rms_m_s2", "background_line_rms_m_s2",
          "background_knock_rate_Hz", "finite")

#: probability that an item draws more knocks than :attr:`SignalSettings.knock_max` (the rest dropped)
KNOCK_TAIL = 1e-12


def _hashable(v):
    if isinstance(v, (list, tuple, np.ndarray)):
        return tuple(_hashable(x) for x in v)
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    return v


@dataclass(frozen=True)
class SignalSettings:
    """Everything static of the signal stage (hashable: one compiled program per settings and
    shapes).  Frequencies in Hz, levels in m/s^2, fractions (not percent) unless named."""

    fs: float
    samples: int
    background: str = "none"                 # "none" | "random" | "machine"
    background_ranges: tuple = ()            # (key, value) pairs over BACKGROUND_DEFAULTS
    machine: tuple | None = None             # the fixed Background (tuples) of "machine"
    pass_cv_max: float = 0.0                 # c.v. of the pass factors at unbridged fraction 1
    pass_delay_max: float = 0.0              # delay s.d. / mean pass interval at fraction 1
    pass_lead: float = 0.15
    pass_taper: float = 0.1
    noise_rms: float = 0.0
    noise_band: tuple | None = None
    fault_snr_dB: tuple | None = None        # target fault/background ratio range; None: gain only
    signal_gain: tuple = (1.0, 1.0)
    strike_probability: tuple = (1.0, 1.0)
    outer_positions_deg: tuple = ()
    modes: tuple = ((), (), ())              # nominal (f Hz, zeta, gain), each (M,)
    resonance_frequency_Hz: tuple | None = None
    resonance_damping_ratio: tuple | None = None
    resonance_gain: tuple | None = None
    ingredients: tuple = ()                  # issue 26's ingredients on (names of bearingsim.signals.nuisance.INGREDIENTS)
    nuisance: tuple = ()                     # (key, value) overrides of bearingsim.signals.nuisance.NUISANCE_DEFAULTS

    def __post_init__(self):
        for name in self.__dataclass_fields__:
            object.__setattr__(self, name, _hashable(getattr(self, name)))
        if self.background not in ("none", "random", "machine"):
            raise InputError(f"background must be 'none', 'random' or 'machine', got {self.background!r}",
                             "'random' draws a background per record, 'machine' uses the machine's Background")
        bad = [k for k in self.ingredients if k not in _nuisance.INGREDIENTS]
        if bad:
            raise InputError(f"unknown realism ingredient(s) {', '.join(map(repr, bad))}: "
                             f"one of {', '.join(_nuisance.INGREDIENTS)}", "check the spelling of ingredients")
        if self.background == "machine" and self.machine is None:
            raise InputError("background 'machine' needs the machine's Background, got machine=None",
                             "pass the machine's Background (bearingsim.signals.background) as machine, or use "
                             "background='random'")

    @classmethod
    def from_dataset(cls, ds: dict, fs, samples, realism, modes, machine: Background | None = None):
        """From a ``[dataset]`` table ``ds`` (its keys as in the case file), the run's
        :class:`bearingsim.dynamics.Realism` and nominal sensor ``modes`` (f, zeta, g), and
        the machine's :class:`~bearingsim.signals.background.Background` for ``background = "machine"``."""
        kind = ds.get("background", "none")
        ranges = dict(BACKGROUND_DEFAULTS, noise_rms_m_s2=tuple(ds.get("background_rms_m_s2", (0.2, 2.0))))
        mach = None
        if kind == "machine":
            mach = Background(*(tuple(np.ravel(v).tolist()) if isinstance(v, (tuple, list, np.ndarray))
                                else float(v) for v in machine))
        f, z, g = (tuple(np.ravel(np.asarray(v, float)).tolist()) for v in modes)
        return cls(float(fs), int(samples), kind, tuple(sorted(ranges.items())), mach,
                   0.01 * float(realism.pass_amplitude_cv_max_percent), 0.01 * float(realism.pass_delay_sd_max_percent),
                   noise_rms=float(realism.noise_rms), noise_band=realism.noise_band,
                   fault_snr_dB=ds.get("fault_snr_dB"), signal_gain=ds.get("signal_gain", (1.0, 1.0)),
                   strike_probability=ds.get("ball_strike_probability", (1.0, 1.0)),
                   outer_positions_deg=ds.get("outer_center_positions_deg") or (), modes=(f, z, g),
                   resonance_frequency_Hz=ds.get("resonance_frequency_Hz"),
                   resonance_damping_ratio=ds.get("resonance_damping_ratio"), resonance_gain=ds.get("resonance_gain"),
                   ingredients=tuple(k for k in _nuisance.INGREDIENTS if k in (ds.get("realism_ingredients") or ())))

    @property
    def ranges(self) -> dict:
        return dict(BACKGROUND_DEFAULTS, **dict(self.background_ranges))

    @property
    def knock_max(self) -> int:
        """Knock slots per item: the count a Poisson draw at the largest rate over the record
        exceeds with probability <= :data:`KNOCK_TAIL` (at least 1)."""
        from scipy.stats import poisson

        machine = self.background == "machine"
        rate = float(Background(*self.machine).knock_rate) if machine else float(self.ranges["knock_rate_Hz"][1])
        lam = rate * self.samples / self.fs
        return max(1, int(poisson.isf(KNOCK_TAIL, lam)) + 1) if lam > 0 else 1


def _logu(key, lo, hi, shape=()):
    lo, hi = float(lo), float(hi)
    if lo == hi:
        return jnp.full(shape, lo)
    return jnp.exp(jax.random.uniform(key, shape, minval=np.log(lo), maxval=np.log(hi)))


def _uniform(key, lo, hi, shape=()):
    lo, hi = float(lo), float(hi)
    return jnp.full(shape, lo) if lo == hi else jax.random.uniform(key, shape, minval=lo, maxval=hi)


# --- per-item randomisation (before the dynamics) -------------------------------------------


class ItemDraws(NamedTuple):
    """An item's domain-randomisation draws (leading item axis when batched)."""

    modes: jnp.ndarray               # (M, 3) sensor modes: frequency Hz (ascending), damping ratio, gain
    signal_gain: jnp.ndarray         # ()
    snr_dB: jnp.ndarray              # () target fault/background ratio (0 for healthy or none)
    strike_probability: jnp.ndarray  # () the ball pit's strike probability (1 for other classes)
    outer_center_deg: jnp.ndarray    # () outer pit position (drawn for every item; nan: no positions)


def _draw_item(key, fault_class, s: SignalSettings) -> ItemDraws:
    kr = jax.random.split(stream_key(key, "randomisation"), 4)
    pos = np.asarray(s.outer_positions_deg, float)
    centre = (jnp.asarray(pos)[jax.random.randint(kr[0], (), 0, pos.size)] if pos.size else jnp.asarray(np.nan))
    gain = _logu(kr[1], *s.signal_gain)
    snr = (jnp.where(fault_class > 0, _uniform(kr[2], *s.fault_snr_dB), 0.0) if s.fault_snr_dB is not None
           else jnp.asarray(0.0))
    strike = jnp.where(fault_class == CLASS_NUMBER["ball"], _uniform(kr[3], *s.strike_probability), 1.0)
    f0, z0, g0 = (jnp.asarray(v, jnp.float64) for v in s.modes)
    M = f0.shape[0]
    kt = jax.random.split(stream_key(key, "transfer"), 3)
    f = jnp.sort(_logu(kt[0], *s.resonance_frequency_Hz, (M,))) if s.resonance_frequency_Hz else f0
    z = _uniform(kt[1], *s.resonance_damping_ratio, (M,)) if s.resonance_damping_ratio else z0
    g = _logu(kt[2], *s.resonance_gain, (M,)) if s.resonance_gain else g0
    return ItemDraws(jnp.stack([f, z, g], -1), gain, snr, strike, centre)


@jit
def draw_items(keys, fault_class, settings: SignalSettings) -> ItemDraws:
    """Every item's :class:`ItemDraws` (N leading) from its key (N, 2) and class (N,) (0 healthy,
    1 outer, 2 inner, 3 ball): modes frequency and gain log-uniform (frequencies sorted),
    damping uniform, per ``resonance_*`` range given (else the nominal modes); signal gain
    log-uniform; the target SNR uniform for fault classes; the strike probability uniform for
    ball items; the outer-pit position one of ``outer_positions_deg`` with equal odds."""
    return jax.vmap(lambda k, c: _draw_item(k, c, settings))(keys, fault_class)


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


# --- pass-to-pass variability ---------------------------------------------------------------


def _mean_interval(tp):
    """Mean interval of the finite (sorted, +inf padded) pass times; 0 for fewer than two."""
    ok = jnp.isfinite(tp)
    k = jnp.sum(ok)
    d = jnp.where(ok[1:], tp[1:] - tp[:-1], 0.0)
    return jnp.where(k > 1, jnp.sum(d) / jnp.maximum(k - 1, 1), 0.0)


def pass_factors(key, n, cv):
    """``pass_factors`` of the NumPy oracle (tests/oracles/passes_numpy.py) from a key: ``exp(s xi - s^2)``, ``s^2 = ln(1 + cv^2)``."""
    s2 = jnp.log1p(cv * cv)
    return jnp.exp(jnp.sqrt(s2) * jax.random.normal(key, (n,), jnp.float64) - s2)


def pass_shifts(key, pass_times, jitter):
    """Gaussian pass delays (s), one per pass slot plus one: ``jitter`` x the mean pass interval
    (0 with fewer than two passes) x standard normals."""
    n = pass_times.shape[0] + 1
    return jitter * _mean_interval(pass_times) * jax.random.normal(key, (n,), jnp.float64)


def strike_factors(key, n, probability):
    """``strike_mask`` of the NumPy oracle (tests/oracles/passes_numpy.py) from a key: 1 where a pass strikes (probability
    ``probability``), else 0."""
    return (jax.random.uniform(key, (n,)) < probability).astype(jnp.float64)


def _ramp(t, sin_a, cos_a, edge, width):
    """The raised-cosine ramp 0 -> 1 of ``width`` centred on ``edge`` (+inf: 0) at the samples
    ``t``: ``0.5 + 0.5 sin(pi (t - e) / w)`` inside, by the angle-difference formula from
    ``sin_a``, ``cos_a`` = sin, cos of ``pi t / w`` (no transcendental per sample and edge)."""
    fin = jnp.isfinite(edge)
    e = jnp.where(fin, edge, 0.0)
    b = np.pi * e / width
    inner = 0.5 + 0.5 * (sin_a * jnp.cos(b) - cos_a * jnp.sin(b))
    d = t - e
    r = jnp.where(d <= -0.5 * width, 0.0, jnp.where(d >= 0.5 * width, 1.0, inner))
    return jnp.where(fin, r, 0.0)


def _delay(y, d):
    """``y`` (uniformly sampled) delayed by ``d`` samples, linear between samples, 0 outside
    (``numpy.interp(t - d / fs, t, y, left=0, right=0)``)."""
    n = y.shape[0]
    p = jnp.arange(n, dtype=jnp.float64) - d
    j = jnp.clip(jnp.floor(p), 0, n - 2).astype(jnp.int32)
    frac = p - j
    v = y[j] + frac * (y[j + 1] - y[j])
    return jnp.where((p >= 0) & (p <= n - 1), v, 0.0)


def vary_passes(x, fs, pass_times, factors, shifts, lead=0.15, taper=0.1):
    """``vary_passes`` of the NumPy oracle (tests/oracles/passes_numpy.py) in JAX: ``pass_times`` (P,) padded with +inf (their
    windows vanish), ``factors`` and ``shifts`` (P + 1,) (index 0: before the first pass)."""
    x = jnp.asarray(x, jnp.float64)
    n = x.shape[0]
    tp = jnp.sort(jnp.asarray(pass_times, jnp.float64))
    t = jnp.arange(n) / float(fs)
    k = jnp.sum(jnp.isfinite(tp))
    T = jnp.where(k > 1, _mean_interval(tp), jnp.maximum(t[-1], 1.0 / float(fs)))
    m = jnp.mean(x)
    xc = x - m
    edges, w = tp - lead * T, taper * T
    P = tp.shape[0]
    sin_a, cos_a = jnp.sin(np.pi * t / w), jnp.cos(np.pi * t / w)
    if P:
        up = lambda j: jnp.where(j < P, _ramp(t, sin_a, cos_a, edges[jnp.minimum(j, P - 1)], w), 0.0)  # noqa: E731
    else:
        up = lambda j: jnp.zeros(n)  # noqa: E731

    def piece(j, carry):            # pieces one at a time: memory O(n) per item
        acc, prev = carry
        nxt = up(j)
        y = factors[j] * (prev - nxt) * xc
        y = jnp.where(shifts[j] != 0.0, _delay(y, shifts[j] * float(fs)), y)
        return acc + y, nxt
    # the pieces after the last finite pass are 0: the loop stops there
    acc, _ = jax.lax.fori_loop(0, k + 1, piece, (jnp.zeros(n), jnp.ones(n)))
    return acc + m


# --- sensor path and noise ------------------------------------------------------------------


# --- fault level ----------------------------------------------------------------------------


def fault_level(a, background, gain, snr_dB, use_snr):
    """(record, gain, snr label) of fault signal ``a`` over ``background``: ``gain a + background``;
    where ``use_snr`` (a fault item with a target) and ``a`` is not flat, the gain that puts
    ``rms(a - mean a)`` at ``snr_dB`` over ``rms(background)``.  The label is the ratio the
    record has (0 where either part is 0)."""
    rms = lambda v: jnp.sqrt(jnp.mean(v * v))  # noqa: E731
    s, rb = rms(a - jnp.mean(a)), rms(background)
    ok = s > 0.0
    gain = jnp.where(use_snr & ok, 10.0 ** (snr_dB / 20.0) * rb / jnp.where(ok, s, 1.0), gain)
    good = ok & (rb > 0.0)
    snr = jnp.where(good, 20.0 * jnp.log10(jnp.where(good, gain * s / jnp.where(good, rb, 1.0), 1.0)), 0.0)
    return gain * a + background, gain, snr


# --- one item, all items --------------------------------------------------------------------


@jit
def pass_variability(key, housing, sensor, pass_times, unbridged, modes, strike_probability, s: SignalSettings):
    """One record's pass-to-pass variability (the first step of :func:`finish_item`; a single
    simulation, :func:`bearingsim.dynamics.simulate`, applies the same): the housing acceleration
    ``housing`` (T,) varied pass by pass (:func:`vary_passes`: factors of c.v. ``s.pass_cv_max``
    x ``unbridged``, delays of s.d. ``s.pass_delay_max`` x ``unbridged`` mean pass intervals, the
    strikes of probability ``strike_probability``, all drawn from the key's ``passes`` and
    ``strike`` streams) and put through the sensor ``modes`` (M, 3) (f Hz, zeta, gain) again;
    a record whose pit is bridged and always strikes keeps ``sensor``.  ``pass_times`` (P,) s,
    sorted, +inf padded.  Returns (sensor record, factors (P + 1,), shifts (P + 1,) s, c.v.,
    delay fraction).  One compiled program per settings and shapes (pass arrays, not Python
    floats, for ``unbridged`` and ``strike_probability``)."""
    fs = s.fs
    P = pass_times.shape[0]
    cv = s.pass_cv_max * unbridged
    jitter = s.pass_delay_max * unbridged
    p = strike_probability
    kp = jax.random.split(stream_key(key, "passes"))
    fac = pass_factors(kp[0], P + 1, cv)
    shifts = pass_shifts(kp[1], pass_times, jitter)
    fac = fac.at[1:].multiply(strike_factors(stream_key(key, "strike"), P, p))
    active = (cv > 0) | (jitter > 0) | (p < 1.0)
    varied = jnp.where(active, vary_passes(housing, fs, pass_times, fac, shifts, s.pass_lead, s.pass_taper),
                       housing)
    if s.pass_cv_max > 0 or s.pass_delay_max > 0 or s.strike_probability[0] < 1.0:
        f, z, g = modes[:, 0], modes[:, 1], modes[:, 2]
        y = run_filter(sensor_filter(f, z, g, 1.0 / fs), varied)
        a = jnp.where((unbridged > 0.0) | (p < 1.0), y, sensor)
    else:
        a = sensor
    return a, fac, shifts, cv, jitter


def finish_item(key, housing, sensor, pass_times, unbridged, fault_class, shaft_hz, draws: ItemDraws,
                s: SignalSettings, frequencies=None):
    """One item's record and labels (see the module docstring; :func:`finish_items`).
    ``frequencies``: the item's (FTF, BPFO, BPFI, BSF) in Hz (needed by issue 26's
    ingredients, :attr:`SignalSettings.ingredients`)."""
    T = housing.shape[0]
    fs = s.fs
    a, _, _, cv, jitter = pass_variability(key, housing, sensor, pass_times, unbridged, draws.modes,
                                           draws.strike_probability, s)
    on = set(s.ingredients)
    if on:
        ns = _nuisance.settings_of(dict(s.nuisance))
        ftf, bpfo, bpfi, bsf = (jnp.zeros(()),) * 4 if frequencies is None else tuple(frequencies)
        kn = jax.random.split(stream_key(key, "nuisance"), 3)
    if "ball_fault_model" in on:     # a ball pit as real damaged balls show it (the fault part only)
        xb, _ = _nuisance.ball_fault_modulation(kn[0], a - jnp.mean(a), fs, shaft_hz, ftf, jnp.where(bsf > 0, bsf, 1.0),
                                                ns)
        a = jnp.where(fault_class == CLASS_NUMBER["ball"], xb, a)
    if s.noise_rms > 0.0:
        a = a + measurement_noise(stream_key(key, "noise"), T, s.noise_rms, fs, s.noise_band)
    labels = {"pass_amplitude_cv_percent": 100.0 * cv, "pass_delay_sd_percent": 100.0 * jitter}
    if s.background == "none":
        out, gain, snr = a * draws.signal_gain, draws.signal_gain, jnp.asarray(0.0)
        labels.update({k: jnp.asarray(0.0) for k in LABELS if k.startswith("background_")})
    else:
        kb = jax.random.split(stream_key(key, "background"))
        if s.background == "random":
            bg = draw_background(kb[0], fs, s.ranges)
        else:
            bg = Background(*(jnp.asarray(v, jnp.float64) for v in s.machine))
        x = background_record(kb[1], bg, T, fs, shaft_hz, s.knock_max)
        out, gain, snr = fault_level(a, x, draws.signal_gain, draws.snr_dB,
                                     (fault_class > 0) & (s.fault_snr_dB is not None))
        labels.update(background_labels(bg))
        if "nuisance" in on:         # every class, at the background's RMS
            out = out + _nuisance.nuisance_signal(kn[1], T, fs, shaft_hz, ftf, bpfo, bpfi, bsf,
                                                  jnp.sqrt(jnp.mean(x * x)), ns)[0]
    if "shaft_modulation" in on:     # the whole record (fault, background, nuisance)
        out = _nuisance.shaft_modulation(kn[2], out, fs, shaft_hz, ns)[0]
    labels.update(signal_gain=gain, snr_dB=snr, finite=jnp.all(jnp.isfinite(out)))
    return out, labels


@jit
def finish_items(keys, housing, sensor, pass_times, unbridged, fault_class, shaft_hz, draws: ItemDraws,
                 settings: SignalSettings, frequencies=None):
    """The stored records (N, T) and labels (dict of (N,) arrays, :data:`LABELS`) of N items, one
    compiled program: ``keys`` (N, 2) uint32 (:func:`item_keys`), the simulated ``housing``
    acceleration and ``sensor`` signal (N, T) m/s^2, ``pass_times`` (N, P) s of the item's
    defect (+inf padded), the pit's ``unbridged`` fraction (N,), ``fault_class`` (N,),
    ``shaft_hz`` (N,), the items' :class:`ItemDraws` (:func:`draw_items`).  A row whose pit is
    not bridged (unbridged > 0) or strikes intermittently is varied pass by pass and put
    through its modes again; the others keep ``sensor``.  ``finite`` is False where the record
    is not finite (the caller flags and zeroes it).  ``frequencies``: (N, 4) FTF, BPFO, BPFI,
    BSF in Hz of every item (the chunk program's outputs), for issue 26's ingredients
    (:attr:`SignalSettings.ingredients`: a ball item's fault part re-shaped by
    :func:`bearingsim.signals.nuisance.ball_fault_modulation` before the noise and the fault level; the
    additive :func:`bearingsim.signals.nuisance.nuisance_signal` at the background's RMS after it; the
    whole record through :func:`bearingsim.signals.nuisance.shaft_modulation` last, the order of
    :func:`bearingsim.signals.nuisance.item_signal`), each from the item key's ``nuisance`` stream."""
    if frequencies is None:
        return jax.vmap(lambda *a: finish_item(*a, settings))(keys, housing, sensor, pass_times, unbridged,
                                                              fault_class, shaft_hz, draws)
    return jax.vmap(lambda *a: finish_item(*a[:-1], settings, a[-1]))(keys, housing, sensor, pass_times, unbridged,
                                                                       fault_class, shaft_hz, draws, frequencies)
