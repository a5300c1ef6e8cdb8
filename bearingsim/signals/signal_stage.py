"""The signal stage of a data set's items on the device: every per-item draw and every step from
the simulated housing / sensor acceleration to the stored record, as pure JAX (float64)
functions of the item's ``jax.random`` key, vmapped over the items of a chunk and compiled once.

What it does to one item (the order of :func:`finish_items`):

1. pass-to-pass variability of the defect's impacts (:func:`vary_passes`, the JAX twin of
   ``vary_passes`` of the NumPy oracle (tests/oracles/passes_numpy.py)): log-normal per-pass factors (c.v. = the [dynamics]
   maximum x the pit's unbridged fraction), Gaussian delays, and the intermittent strike of a
   ball pit (:func:`strike_factors`) or, with ``ball_exposure = "kinematic"`` (issue 33), its
   exposure pass by pass from the ball kinematics (:func:`bearingsim.dynamics.exposure.pass_exposure`,
   the item key's ``ball_exposure`` stream); a varied row is put through the item's sensor modes again
   (:func:`bearingsim.dynamics.sensor.sensor_filter`, :func:`~bearingsim.dynamics.sensor.run_filter`:
   the first-order-hold filter every simulation uses); :func:`pass_variability` is this step for
   one record (a single simulation applies it too);
2. the measurement noise (:func:`bearingsim.dynamics.sensor.measurement_noise`: white or
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
from .background import BACKGROUND_DEFAULTS, Background, background_labels, background_record, draw_background
from ..keys import item_keys, stream_key
from ..dynamics.exposure import EXPOSURE_DEFAULTS, draw_exposure, exposure_at, pass_distance, pass_exposure
from ..dynamics.passes import PassSettings, pass_variability
from ..dynamics.sensor import measurement_noise
from ..programs import jit

__all__ = ["STREAMS", "SignalSettings", "ItemDraws", "item_keys", "stream_key", "draw_items", "fault_level",
           "finish_item",
           "finish_items", "LABELS"]

#: the item key's sub-streams (``jax.random.fold_in(key, n)``): the one registry, :data:`bearingsim.keys.STREAMS`
STREAMS = _keys.STREAMS

#: label fields :func:`finish_items` returns, each (N,)
LABELS = ("signal_gain", "snr_dB", "pass_amplitude_cv_percent", "pass_delay_sd_percent",
          "background_noise_rms_m_s2", "background_shaft_rms_m_s2", "background_line_rms_m_s2",
          "background_knock_rate_Hz", "finite", "struck")

#: the values of ``[dataset] ball_exposure``
BALL_EXPOSURES = ("gate", "kinematic")

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
    ball_exposure: str = "gate"              # "gate" | "kinematic" (issue 33: bearingsim.dynamics.exposure)
    exposure_ranges: tuple = ()              # (key, (lo, hi)) over bearingsim.dynamics.exposure.EXPOSURE_DEFAULTS (SI)

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
        if self.ball_exposure not in BALL_EXPOSURES:
            raise InputError(f"ball_exposure must be one of {', '.join(map(repr, BALL_EXPOSURES))}, got "
                             f"{self.ball_exposure!r}", "'gate': the drawn gate and strikes (issue 26); 'kinematic': "
                             "the pit's exposure from the ball kinematics (bearingsim.dynamics.exposure)")
        bad = sorted(set(dict(self.exposure_ranges)) - set(EXPOSURE_DEFAULTS))
        if bad:
            raise InputError(f"unknown exposure range(s) {', '.join(bad)}: one of {', '.join(EXPOSURE_DEFAULTS)}",
                             "the ranges and their defaults are bearingsim.dynamics.exposure.EXPOSURE_DEFAULTS")
        if self.background == "machine" and self.machine is None:
            raise InputError("background 'machine' needs the machine's Background, got machine=None",
                             "pass the machine's Background (bearingsim.signals.background) as machine, or use "
                             "background='random'")

    def passes(self) -> PassSettings:
        """The settings of the pass-to-pass variability step (:func:`bearingsim.dynamics.pass_variability`)."""
        return PassSettings(self.fs, self.pass_cv_max, self.pass_delay_max, self.pass_lead, self.pass_taper,
                            bool(self.strike_probability[0] < 1.0), self.ball_exposure == "kinematic")

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
                   ingredients=tuple(k for k in _nuisance.INGREDIENTS if k in (ds.get("realism_ingredients") or ())),
                   ball_exposure=ds.get("ball_exposure", "gate"), exposure_ranges=_exposure_ranges(ds))

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


def _exposure_ranges(ds: dict) -> tuple:
    """The kinematic exposure's ranges of a ``[dataset]`` table (its keys in degrees and cage
    revolutions) in SI, as (key, (lo, hi)) pairs of :data:`EXPOSURE_DEFAULTS` (absent: the defaults)."""
    out = {}
    for key, name, scale in (("ball_pit_latitude_deg", "pit_latitude", np.pi / 180.0),
                             ("ball_axis_wander_deg", "wander_sd", np.pi / 180.0),
                             ("ball_axis_correlation_cage_rev", "wander_correlation", 1.0)):
        if ds.get(key) is not None:
            lo, hi = ds[key]
            out[name] = (float(lo) * scale, float(hi) * scale)
    return tuple(sorted(out.items()))


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


def _ball_exposure(key, pass_times, fault_class, draws: ItemDraws, frequencies, track, s: SignalSettings):
    """A ball item's per-pass kinematic exposure (P,) (1 for every other class): the pit's
    latitude and the axis wander drawn from the key's ``ball_exposure`` stream
    (:func:`bearingsim.dynamics.exposure.draw_exposure`), the pit's spin angle at t = 0 the item's
    ``spall_center_deg`` (:class:`ItemDraws`), FTF from ``frequencies``."""
    if frequencies is None or track is None:
        raise InputError("ball_exposure 'kinematic' needs every item's frequencies and ball track",
                         "pass frequencies (N, 4) and track (N, 7) (bearingsim.dynamics.exposure.ball_track) to "
                         "finish_items, as the data set's device program does")
    kd, kw = jax.random.split(stream_key(key, "ball_exposure"))
    lat, sd, corr = draw_exposure(kd, s.exposure_ranges)
    e = pass_exposure(kw, pass_times, frequencies[0], jnp.deg2rad(draws.outer_center_deg), track, lat, sd, corr)
    return jnp.where(fault_class == CLASS_NUMBER["ball"], e, 1.0)


def finish_item(key, housing, sensor, pass_times, unbridged, fault_class, shaft_hz, draws: ItemDraws,
                s: SignalSettings, frequencies=None, track=None):
    """One item's record and labels (see the module docstring; :func:`finish_items`).
    ``frequencies``: the item's (FTF, BPFO, BPFI, BSF) in Hz (needed by issue 26's
    ingredients, :attr:`SignalSettings.ingredients`, and the kinematic exposure); ``track``: its
    (7,) :func:`bearingsim.dynamics.exposure.ball_track` (``ball_exposure = "kinematic"``)."""
    T = housing.shape[0]
    fs = s.fs
    exposure = None
    if s.ball_exposure == "kinematic":
        exposure = _ball_exposure(key, pass_times, fault_class, draws, frequencies, track, s)
    a, fac, _, cv, jitter = pass_variability(key, housing, sensor, pass_times, unbridged, draws.modes,
                                           draws.strike_probability, s.passes(), exposure)
    on = set(s.ingredients)
    if on:
        ns = _nuisance.settings_of(dict(s.nuisance))
        ftf, bpfo, bpfi, bsf = (jnp.zeros(()),) * 4 if frequencies is None else tuple(frequencies)
        kn = jax.random.split(stream_key(key, "nuisance"), 3)
    if "ball_fault_model" in on:     # a ball pit as real damaged balls show it (the fault part only)
        track_gate = None
        if exposure is not None:     # the kinematic exposure in time and the passes, for the gate and the bursts
            t = jnp.arange(T) / fs
            track_gate = (exposure_at(t, pass_times, exposure), pass_distance(t, pass_times))
        xb, _ = _nuisance.ball_fault_modulation(kn[0], a - jnp.mean(a), fs, shaft_hz, ftf, jnp.where(bsf > 0, bsf, 1.0),
                                                ns, track_gate)
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
        if "race_waviness" in on:    # the healthy bearing's own orders in the rolling noise, every class
            x = x * _nuisance.race_waviness(jax.random.fold_in(stream_key(key, "nuisance"), 4), T, fs, ftf, bpfo,
                                            bpfi, bsf, ns)[0]
        out, gain, snr = fault_level(a, x, draws.signal_gain, draws.snr_dB,
                                     (fault_class > 0) & (s.fault_snr_dB is not None))
        labels.update(background_labels(bg))
        if "nuisance" in on:         # every class, at the background's RMS
            out = out + _nuisance.nuisance_signal(kn[1], T, fs, shaft_hz, ftf, bpfo, bpfi, bsf,
                                                  jnp.sqrt(jnp.mean(x * x)), ns)[0]
    if "shaft_modulation" in on:     # the whole record (fault, background, nuisance)
        out = _nuisance.shaft_modulation(kn[2], out, fs, shaft_hz, ns)[0]
    # whether the defect struck at all inside the record (a pass at >= 1 % of its impact): a ball pit
    # that missed every pass leaves a healthy record (the caller flags a fault item without one)
    struck = jnp.any(jnp.isfinite(pass_times) & (pass_times < T / fs) & (fac[1:] >= 0.01))
    labels.update(signal_gain=gain, snr_dB=snr, finite=jnp.all(jnp.isfinite(out)), struck=struck)
    return out, labels


@jit
def finish_items(keys, housing, sensor, pass_times, unbridged, fault_class, shaft_hz, draws: ItemDraws,
                 settings: SignalSettings, frequencies=None, track=None):
    """The stored records (N, T) and labels (dict of (N,) arrays, :data:`LABELS`) of N items, one
    compiled program: ``keys`` (N, 2) uint32 (:func:`item_keys`), the simulated ``housing``
    acceleration and ``sensor`` signal (N, T) m/s^2, ``pass_times`` (N, P) s of the item's
    defect (+inf padded), the pit's ``unbridged`` fraction (N,), ``fault_class`` (N,),
    ``shaft_hz`` (N,), the items' :class:`ItemDraws` (:func:`draw_items`).  A row whose pit is
    not bridged (unbridged > 0) or strikes intermittently is varied pass by pass and put
    through its modes again; the others keep ``sensor``.  ``finite`` is False where the record
    is not finite (the caller flags and zeroes it); ``struck`` is False where the defect struck on
    none of the record's passes (a ball pit that missed them all: the caller flags a fault item).  ``frequencies``: (N, 4) FTF, BPFO, BPFI,
    BSF in Hz of every item (the chunk program's outputs), for issue 26's ingredients
    (:attr:`SignalSettings.ingredients`: a ball item's fault part re-shaped by
    :func:`bearingsim.signals.nuisance.ball_fault_modulation` before the noise and the fault level; the
    additive :func:`bearingsim.signals.nuisance.nuisance_signal` at the background's RMS after it; the
    whole record through :func:`bearingsim.signals.nuisance.shaft_modulation` last, the order of
    :func:`bearingsim.signals.nuisance.item_signal`), each from the item key's ``nuisance`` stream.
    ``track``: (N, 7) every item's :func:`bearingsim.dynamics.exposure.ball_track` (the chunk
    program's ``ball_track``), needed with ``ball_exposure = "kinematic"``: a ball item's impacts
    are then scaled pass by pass by their kinematic exposure instead of the drawn strikes, and
    the ball fault model's gate is that exposure (:func:`bearingsim.signals.nuisance.ball_fault_modulation`)."""
    if track is not None:
        return jax.vmap(lambda *a: finish_item(*a[:-2], settings, a[-2], a[-1]))(
            keys, housing, sensor, pass_times, unbridged, fault_class, shaft_hz, draws, frequencies, track)
    if frequencies is None:
        return jax.vmap(lambda *a: finish_item(*a, settings))(keys, housing, sensor, pass_times, unbridged,
                                                              fault_class, shaft_hz, draws)
    return jax.vmap(lambda *a: finish_item(*a[:-1], settings, a[-1]))(keys, housing, sensor, pass_times, unbridged,
                                                                       fault_class, shaft_hz, draws, frequencies)
