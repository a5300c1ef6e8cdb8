"""What real bearings add to a fault's clean signature: the ball fault as real balls show it, the
machine's nuisance mechanisms in every class, and randomised impulsiveness (issue 26).

Every function is pure JAX (float64), a function of one item's ``jax.random`` key and of that
item's traced scalars (shaft, cage, bearing frequencies in Hz; levels in m/s^2), with the record
length ``T`` and the sample rate ``fs`` static: ``jax.vmap`` over items, no host loop, no Python
control flow on traced values.  ``settings`` is a dict of ranges (tuples of floats, static);
missing keys take :data:`NUISANCE_DEFAULTS`.  Each function returns the signal and a dict of
scalar labels (what it drew), for the data set's label table.

Ingredients (docs/realism.md, "Issue 26"; the physics of the ball fault: docs/physics.md §8.3)

:func:`ball_fault_modulation`
    The engine's ball-pit signal (a clean impulse each time the pit meets a raceway, at 2 BSF)
    re-shaped as a real damaged ball shows it.  (1) The pit is on the rolling track only while
    the ball's wandering spin axis keeps it there: a smooth random gate ``g(t)`` (low-pass
    Gaussian process thresholded softly; its bandwidth ``ball_wander_per_cage`` x FTF, the
    fraction of time on the track ``ball_in_path``).  (2) Rolling over the pit's edge is not a
    clean impulse: a burst of contact noise (band noise at a structural resonance) under a
    Gaussian window of ``ball_edge_ms`` around every 2 BSF crossing, on a floor of rolling noise
    (``ball_roughness`` of the burst level).  (3) Its level rises with the ball's load: the
    pitted ball orbits with the cage through the load zone, ``q(psi) = max(0, 1 - (1 - cos psi)
    / (2 eps))^1.5`` (Stribeck; ``eps`` = ``ball_load_eps``, psi = 2 pi FTF t + psi0), and the
    noise amplitude goes as ``u + (1 - u) q^gamma`` (``gamma`` = ``ball_load_exponent``, ``u``
    = ``ball_unloaded``).  Output: ``g(t) [(1 - c) x_n + c r(t)]`` at the RMS of the input,
    ``x_n`` the engine's signal, ``r`` the load-modulated contact noise, ``c`` =
    ``ball_noise_share``.  With ``[dataset] ball_exposure = "kinematic"`` (issue 33) the gate is
    not drawn: it is the pit's exposure from the ball kinematics
    (:mod:`bearingsim.dynamics.exposure`), on the contact noise only (the engine's impacts carry
    it pass by pass), and the bursts sit on the pit's own passes.  (4) The ball's load also varies as the inner ring's runout and
    waviness turn under it, at n (f_r - FTF), n = 1..8: the level is multiplied by ``max(0, 1 +
    sum_n w_n cos(2 pi n (f_r - FTF) t + phi_n))``, ``w_n = w rho^(n - 1)``, ``w`` drawn from
    ``ball_ring_waviness``, ``rho`` from ``ball_ring_decay``.  With the load zone's cage
    harmonics k FTF this makes lines at n f_r + (k - n) FTF.
:func:`shaft_modulation`
    Multiplies a record by ``max(0, 1 + sum_k m_k cos(2 pi k f_r t + phi_k) + sum_j l_j cos(2 pi
    (j - 1/2) f_r t + ...))``: shaft-rate amplitude modulation (runout, unbalance: ``m_1``),
    misalignment (``m_2``), higher shaft harmonics, looseness half orders (``l_j``, present with
    probability ``looseness_probability``).  Applied to the whole record (fault, background,
    nuisance), every class.
:func:`nuisance_signal`
    Additive, every class, relative to the item's background RMS ``rms``: shaft lines at 1-3 f_r
    (unbalance, misalignment), looseness lines at half orders, rub (band noise gated once per
    revolution), lines near bearing orders that are not faults (band noise modulated at
    ``(1 + delta)`` x one of BPFO, BPFI, 2 BSF, present with ``near_line_probability``), and
    impulsive knocks at random times (Poisson, up to ``knock_max`` per record).
:func:`race_waviness`
    A healthy bearing's own orders: the background (its rolling noise) amplitude-modulated at
    BPFO, BPFI and 2 BSF and their second harmonics, each present with ``waviness_probability``
    at a depth drawn from ``waviness_depth`` (varying compliance, race and ball waviness), every
    class (issue 33: both rigs' healthy machines carry lines at bearing orders).
:func:`fault_level`
    The fault's RMS over the background's, ``fault_snr_dB`` (down to negative dB), as the gain of
    the fault signal.

Inside the data engine (per item, vmapped): :func:`bearingsim.signals.signal_stage.finish_item` applies
the ingredients named by ``[dataset] realism_ingredients`` in the order of :func:`item_signal`,
each from the item key's ``nuisance`` stream (:data:`bearingsim.keys.STREAMS`), with the item's
frequencies from the chunk program; :func:`item_signal` is the same composition for one item
given its parts (tests, notebooks).
"""
from __future__ import annotations

import jax
import jax.numpy as jnp

from ..errors import InputError
from ..names import CLASS_NUMBER
from ..keys import STREAMS, item_keys

__all__ = ["NUISANCE_DEFAULTS", "INGREDIENTS", "item_signal", "ball_fault_modulation", "shaft_modulation", "nuisance_signal",
           "race_waviness", "fault_level",
           "load_zone_factor", "band_noise", "item_key", "settings_of"]

#: ranges (lo, hi) of every draw; uniform unless the name says log.  Sources: docs/realism.md.
NUISANCE_DEFAULTS = {
    # ball fault (ball_fault_modulation)
    "ball_in_path": (0.7, 1.0),             # fraction of the time the pit is on the rolling track
    "ball_wander_per_cage": (0.5, 4.0),     # spin-axis wander bandwidth / FTF
    "ball_edge_ms": (0.5, 4.0),             # duration (2 sigma) of the rolling-over-the-edge burst
    "ball_roughness": (0.5, 1.0),           # rolling-noise floor / burst level
    "ball_load_eps": (0.5, 1.0),            # Stribeck load distribution factor: zone +-90..180 deg
    "ball_load_exponent": (0.5, 1.5),       # contact-noise amplitude ~ load^gamma
    "ball_unloaded": (0.3, 0.8),            # level outside the load zone / inside
    "ball_noise_share": (0.8, 1.0),         # contact noise share of the ball fault (1: no impulse)
    "ball_noise_Hz": (1500.0, 5500.0),      # contact-noise band centre (log)
    "ball_noise_damping": (0.03, 0.2),      # its damping ratio
    "ball_ring_waviness": (0.2, 0.8),       # load modulation by the inner ring turning under the ball
    "ball_ring_decay": (0.5, 1.0),          # ratio of successive ring orders' depths (n = 1..8)
    # shaft-synchronous modulation (shaft_modulation)
    "shaft_am_depth": (0.0, 0.5),           # m_1: shaft-rate AM depth
    "misalignment_depth": (0.0, 0.3),       # m_2: 2 x shaft
    "shaft_harmonic_depth": (0.0, 0.1),     # m_3..m_6
    "looseness_probability": 0.4,           # half orders present
    "looseness_depth": (0.0, 0.3),          # l_j, j = 1..4 (0.5, 1.5, 2.5, 3.5 f_r)
    # additive nuisance (nuisance_signal), relative to the background RMS
    "shaft_line_relative": (0.0, 1.0),      # 1-3 f_r lines (unbalance, misalignment)
    "looseness_line_relative": (0.0, 0.5),  # half-order lines when loose
    "rub_probability": 0.25,
    "rub_relative": (0.1, 1.0),             # rub burst RMS / background RMS
    "rub_duty": (0.05, 0.3),                # fraction of a revolution it lasts
    "near_line_probability": 0.3,
    "near_line_offset_percent": (0.3, 3.0), # |delta| of a non-fault line near a bearing order
    "near_line_depth": (0.2, 1.0),          # its modulation depth of a band noise ...
    "near_line_relative": (0.2, 1.0),       # ... at this RMS / background RMS
    "knock_probability": 0.3,               # impulsive knocks present (every class) ...
    "knock_rate_Hz": (0.0, 20.0),           # ... at this rate
    "knock_relative": (1.0, 10.0),          # knock peak / background RMS (log)
    "knock_Hz": (1000.0, 5500.0),           # ringing resonance (log)
    "knock_damping": (0.01, 0.08),
    "knock_max": 16,                        # static: the most knocks a record can hold
    # a healthy bearing's own orders (race_waviness): the rolling noise modulated at BPFO, BPFI, 2 BSF.
    # The depth's top is a range fitted to records: the HIT-MFS normal records (hit_mfs_normal_600rpm,
    # _900rpm, _1200rpm) carry a BPFI envelope line of 12.9 dB (median, at most 15.6) over the local
    # median in 1 s windows (1-2.5 kHz), which a depth of ~0.1-0.15 makes; 0.2 (~17 dB) holds them
    "waviness_probability": 0.5,            # each order present with this probability ...
    "waviness_depth": (0.02, 0.2),          # ... at this modulation depth (log)
    "waviness_second": (0.2, 1.0),          # its second harmonic's depth / the first's
    # fault level (fault_level)
    "fault_snr_dB": (-6.0, 25.0),
}


def settings_of(settings=None) -> dict:
    """:data:`NUISANCE_DEFAULTS` updated with ``settings`` (unknown keys refused)."""
    s = dict(NUISANCE_DEFAULTS)
    if settings:
        bad = sorted(set(settings) - set(s))
        if bad:
            raise InputError(f"unknown nuisance settings {', '.join(bad)}: one of {', '.join(sorted(s))}",
                             "the settings and their defaults are bearingsim.signals.nuisance.NUISANCE_DEFAULTS")
        s.update(settings)
    return s


def item_key(seed, index):
    """The nuisance stream of item ``index`` of a data set seeded ``seed``: the item's key
    (:func:`bearingsim.keys.item_keys`) folded with ``STREAMS["nuisance"]``, independent of every
    other stream of the item (:data:`bearingsim.keys.STREAMS`)."""
    return jax.random.fold_in(item_keys(seed, jnp.reshape(index, (1,)))[0], STREAMS["nuisance"])


def _u(key, r):
    lo, hi = r
    return jax.random.uniform(key, (), jnp.float64, lo, hi)


def _logu(key, r):
    lo, hi = r
    return jnp.exp(jax.random.uniform(key, (), jnp.float64, jnp.log(lo), jnp.log(hi)))


def _rms(x):
    return jnp.sqrt(jnp.mean(x * x) + 1e-300)


def band_noise(key, T, fs, f0, zeta):
    """(T,) unit-RMS Gaussian noise shaped by a single-degree-of-freedom resonance at ``f0`` Hz
    (damping ratio ``zeta``), circular (FFT), zero mean."""
    w = jax.random.normal(key, (T,), jnp.float64)
    f = jnp.fft.rfftfreq(T, 1.0 / fs)
    r = f / f0
    H = 1.0 / (1.0 - r * r + 2j * zeta * r)
    y = jnp.fft.irfft(jnp.fft.rfft(w) * H * (f > 0), T)
    return y / _rms(y)


def _lowpass_noise(key, T, fs, fc):
    """(T,) unit-RMS Gaussian noise low-passed (Gaussian filter of cut-off ``fc`` Hz)."""
    w = jax.random.normal(key, (T,), jnp.float64)
    f = jnp.fft.rfftfreq(T, 1.0 / fs)
    y = jnp.fft.irfft(jnp.fft.rfft(w) * jnp.exp(-0.5 * (f / fc) ** 2) * (f > 0), T)
    return y / _rms(y)


def load_zone_factor(psi, eps):
    """Stribeck's load distribution: a ball's load over the most loaded ball's at azimuth ``psi``
    (0 = load-zone centre), ``max(0, 1 - (1 - cos psi) / (2 eps))^1.5``."""
    return jnp.maximum(1.0 - (1.0 - jnp.cos(psi)) / (2.0 * eps), 0.0) ** 1.5


def _gate(key, T, fs, fc, fraction):
    """A smooth 0-1 gate on for about ``fraction`` of the time, switching at bandwidth ``fc``."""
    s = _lowpass_noise(key, T, fs, fc)
    thr = jax.scipy.special.ndtri(jnp.clip(1.0 - fraction, 1e-6, 1.0 - 1e-6))
    return jax.nn.sigmoid((s - thr) / 0.15)


def ball_fault_modulation(key, fault, fs, shaft_hz, ftf_hz, bsf_hz, settings=None, exposure=None):
    """The ball-pit signal ``fault`` (T,) of the engine as a real damaged ball shows it (module
    docstring); same RMS as ``fault``.  Returns (signal, labels).

    ``exposure``: None (the drawn gate ``g(t)``, issue 26), or ``(e, d)`` (T,) each: the pit's
    kinematic exposure in time and the time to its nearest pass (issue 33:
    :func:`bearingsim.dynamics.exposure.exposure_at`, :func:`~bearingsim.dynamics.exposure.pass_distance`).
    Then the gate is ``e`` and acts on the contact noise only (the engine's impacts in ``fault``
    carry the exposure pass by pass already), and the edge bursts sit on the pit's own passes
    instead of a drawn phase; the other draws are the same."""
    s = settings_of(settings)
    T = fault.shape[-1]
    ks = jax.random.split(key, 12)
    t = jnp.arange(T) / fs
    in_path = _u(ks[0], s["ball_in_path"])
    wander = _u(ks[1], s["ball_wander_per_cage"]) * ftf_hz
    edge = _u(ks[2], s["ball_edge_ms"]) * 1e-3
    rough = _u(ks[3], s["ball_roughness"])
    eps = _u(ks[4], s["ball_load_eps"])
    gamma = _u(ks[5], s["ball_load_exponent"])
    unloaded = _u(ks[6], s["ball_unloaded"])
    share = _u(ks[7], s["ball_noise_share"])
    f0 = _logu(ks[8], s["ball_noise_Hz"])
    zeta = _u(ks[9], s["ball_noise_damping"])
    psi0, phi0 = jax.random.uniform(ks[10], (2,), jnp.float64, 0.0, 1.0)
    if exposure is None:
        g = _gate(ks[11], T, fs, wander, in_path)
        # rolling over the edge: a Gaussian window of 2 sigma = edge around each 2 BSF crossing
        ph = jnp.mod(2.0 * bsf_hz * t + phi0, 1.0)
        d = jnp.minimum(ph, 1.0 - ph) / (2.0 * bsf_hz)
    else:
        e, d = exposure
        in_path = jnp.mean(e)
    burst = jnp.exp(-0.5 * (d / (0.5 * edge)) ** 2)
    q = load_zone_factor(2.0 * jnp.pi * (ftf_hz * t + psi0), eps)
    level = unloaded + (1.0 - unloaded) * q ** gamma
    kw = jax.random.split(jax.random.fold_in(key, 2), 3)
    nn = jnp.arange(1, 9.0)
    wn = _u(kw[0], s["ball_ring_waviness"]) * _u(kw[2], s["ball_ring_decay"]) ** (nn - 1.0)
    pw = jax.random.uniform(kw[1], (8,), jnp.float64, 0.0, 2 * jnp.pi)
    wav = 1.0 + jnp.sum(wn[:, None] * jnp.cos(2 * jnp.pi * nn[:, None] * (shaft_hz - ftf_hz) * t + pw[:, None]), 0)
    level = level * jnp.maximum(wav, 0.0)
    noise = band_noise(jax.random.fold_in(key, 1), T, fs, f0, zeta)
    r = level * (rough + (1.0 - rough) * burst) * noise
    x = fault - jnp.mean(fault)
    xr = _rms(x)
    if exposure is None:
        out = g * ((1.0 - share) * x / xr + share * r / _rms(r))
    else:
        r = e * r
        out = (1.0 - share) * x / xr + share * r / _rms(r)
    out = out * xr / _rms(out)
    return out, {"ball_in_path": in_path, "ball_edge_ms": edge * 1e3, "ball_noise_share": share,
                 "ball_load_exponent": gamma}


def shaft_modulation(key, x, fs, shaft_hz, settings=None):
    """``x`` (T,) amplitude-modulated at the shaft harmonics and (when loose) at half orders
    (module docstring).  Returns (signal, labels)."""
    s = settings_of(settings)
    T = x.shape[-1]
    ks = jax.random.split(key, 8)
    t = jnp.arange(T) / fs
    m = jnp.stack([_u(ks[0], s["shaft_am_depth"]), _u(ks[1], s["misalignment_depth"])]
                  + [_u(k, s["shaft_harmonic_depth"]) for k in jax.random.split(ks[2], 4)])
    loose = jax.random.uniform(ks[3], ()) < s["looseness_probability"]
    lj = jnp.where(loose, jax.random.uniform(ks[4], (4,), jnp.float64, *s["looseness_depth"]), 0.0)
    ph = jax.random.uniform(ks[5], (10,), jnp.float64, 0.0, 2.0 * jnp.pi)
    kk = jnp.arange(1, 7.0)
    jj = jnp.arange(1, 5.0) - 0.5
    env = (1.0 + jnp.sum(m[:, None] * jnp.cos(2 * jnp.pi * kk[:, None] * shaft_hz * t + ph[:6, None]), 0)
           + jnp.sum(lj[:, None] * jnp.cos(2 * jnp.pi * jj[:, None] * shaft_hz * t + ph[6:, None]), 0))
    return x * jnp.maximum(env, 0.0), {"shaft_am_depth": m[0], "misalignment_depth": m[1],
                                       "looseness": loose.astype(jnp.float64)}


def _ring(t, f, zeta):
    wn = 2 * jnp.pi * f
    tt = jnp.maximum(t, 0.0)
    return jnp.where(t >= 0, jnp.exp(-zeta * wn * tt) * jnp.sin(wn * jnp.sqrt(1 - zeta * zeta) * tt), 0.0)


def nuisance_signal(key, T, fs, shaft_hz, ftf_hz, bpfo_hz, bpfi_hz, bsf_hz, rms, settings=None):
    """(T,) additive nuisance of one item (module docstring) at the scale of its background RMS
    ``rms`` (m/s^2); ``T`` static.  Returns (signal, labels)."""
    s = settings_of(settings)
    ks = jax.random.split(key, 20)
    t = jnp.arange(T) / fs
    # shaft lines (unbalance, misalignment) and looseness half orders
    a = jax.random.uniform(ks[0], (3,), jnp.float64, *s["shaft_line_relative"]) * jnp.array([1.0, 0.7, 0.3])
    loose = jax.random.uniform(ks[1], ()) < s["looseness_probability"]
    al = jnp.where(loose, jax.random.uniform(ks[2], (4,), jnp.float64, *s["looseness_line_relative"]), 0.0)
    ph = jax.random.uniform(ks[3], (7,), jnp.float64, 0.0, 2 * jnp.pi)
    orders = jnp.array([1.0, 2.0, 3.0, 0.5, 1.5, 2.5, 3.5])
    amp = jnp.concatenate([a, al]) * jnp.sqrt(2.0)
    lines = jnp.sum(amp[:, None] * jnp.cos(2 * jnp.pi * orders[:, None] * shaft_hz * t + ph[:, None]), 0)
    # rub: band noise gated once per revolution
    rub_on = jax.random.uniform(ks[4], ()) < s["rub_probability"]
    duty = _u(ks[5], s["rub_duty"])
    rph = jnp.mod(shaft_hz * t + jax.random.uniform(ks[6], ()), 1.0)
    rub_gate = jnp.exp(-0.5 * (jnp.minimum(rph, 1 - rph) / (0.5 * duty)) ** 2)
    rub = rub_gate * band_noise(ks[7], T, fs, _logu(ks[8], s["knock_Hz"]), 0.1)
    rub = jnp.where(rub_on, _u(ks[9], s["rub_relative"]) * rub / _rms(rub), 0.0)
    # a line near a bearing order that is no fault: band noise modulated there
    near_on = jax.random.uniform(ks[10], ()) < s["near_line_probability"]
    which = jax.random.randint(ks[11], (), 0, 3)
    f_near = jnp.array([bpfo_hz, bpfi_hz, 2.0 * bsf_hz])[which]
    delta = _u(ks[12], s["near_line_offset_percent"]) * 1e-2 * jnp.where(jax.random.uniform(ks[13], ()) < 0.5, -1, 1)
    carrier = band_noise(ks[14], T, fs, _logu(ks[15], s["knock_Hz"]), 0.05)
    near = (1.0 + _u(ks[16], s["near_line_depth"]) * jnp.cos(2 * jnp.pi * f_near * (1 + delta) * t)) * carrier
    near = jnp.where(near_on, _u(ks[17], s["near_line_relative"]) * near / _rms(near), 0.0)
    # impulsive knocks (every class)
    kk = jax.random.split(ks[18], 5)
    K = int(s["knock_max"])
    rate = _u(kk[0], s["knock_rate_Hz"]) * (jax.random.uniform(jax.random.fold_in(key, 8), ()) < s["knock_probability"])
    on = jax.random.uniform(kk[1], (K,)) < jnp.minimum(rate * T / fs / K, 1.0)
    tk = jax.random.uniform(kk[2], (K,), jnp.float64, 0.0, T / fs)
    pk = jnp.exp(jax.random.uniform(kk[3], (K,), jnp.float64, *jnp.log(jnp.array(s["knock_relative"]))))
    fk = _logu(kk[4], s["knock_Hz"])
    zk = _u(ks[19], s["knock_damping"])
    sign = jnp.where(jax.random.uniform(jax.random.fold_in(key, 7), (K,)) < 0.5, -1.0, 1.0)
    knocks = jnp.sum(jnp.where(on, sign * pk, 0.0)[:, None] * _ring(t[None, :] - tk[:, None], fk, zk), 0)
    x = rms * (lines + rub + near + knocks)
    return x, {"looseness": loose.astype(jnp.float64), "rub": rub_on.astype(jnp.float64),
               "near_line_Hz": jnp.where(near_on, f_near * (1 + delta), 0.0), "knock_rate_Hz": rate}


def race_waviness(key, T, fs, ftf_hz, bpfo_hz, bpfi_hz, bsf_hz, settings=None):
    """(T,) the factor ``max(0, 1 + sum_j p_j [d_j cos(2 pi f_j t + a_j) + d_j r_j cos(4 pi f_j t
    + b_j)])`` by which a healthy bearing's own imperfections modulate its rolling noise, at f_j =
    BPFO, BPFI, 2 BSF: varying compliance and outer-race waviness of Z waves (BPFO), inner-race
    waviness of Z waves turning under the balls (BPFI), ball waviness of even order (2 BSF)
    (Wardle 1988; Harris & Kotzalas, vol. 2, ch. 27); each present (``p_j``) with
    ``waviness_probability``, depth ``d_j`` log-uniform in ``waviness_depth``, second harmonic
    ``r_j`` in ``waviness_second``.  Every class: a line at a bearing order is then no proof of a
    fault.  Returns (factor, labels: the three depths, 0 where absent)."""
    s = settings_of(settings)
    ks = jax.random.split(key, 4)
    t = jnp.arange(T) / fs
    on = jax.random.uniform(ks[0], (3,)) < s["waviness_probability"]
    lo, hi = s["waviness_depth"]
    d = jnp.where(on, jnp.exp(jax.random.uniform(ks[1], (3,), jnp.float64, jnp.log(lo), jnp.log(hi))), 0.0)
    r = jax.random.uniform(ks[2], (3,), jnp.float64, *s["waviness_second"])
    ph = jax.random.uniform(ks[3], (2, 3), jnp.float64, 0.0, 2.0 * jnp.pi)
    f = jnp.stack([bpfo_hz, bpfi_hz, 2.0 * bsf_hz])
    w = 2.0 * jnp.pi * f[:, None] * t[None, :]
    env = 1.0 + jnp.sum(d[:, None] * (jnp.cos(w + ph[0, :, None]) + r[:, None] * jnp.cos(2.0 * w + ph[1, :, None])), 0)
    return jnp.maximum(env, 0.0), {"waviness_bpfo_depth": d[0], "waviness_bpfi_depth": d[1], "waviness_2bsf_depth": d[2]}


def fault_level(key, fault, background, settings=None):
    """The gain that puts ``fault`` (T,) at a drawn ``fault_snr_dB`` over ``background`` (T,)
    (RMS ratio).  Returns (gain, snr_dB)."""
    s = settings_of(settings)
    snr = _u(key, s["fault_snr_dB"])
    gain = 10.0 ** (snr / 20.0) * _rms(background - jnp.mean(background)) / _rms(fault - jnp.mean(fault))
    return gain, snr


#: the ingredients item_signal applies (settings keys, booleans, static)
INGREDIENTS = ("ball_fault_model", "nuisance", "shaft_modulation", "race_waviness")


def item_signal(key, fault, background, fault_class, fs, shaft_hz, ftf_hz, bpfo_hz, bpfi_hz, bsf_hz, settings=None):
    """One item's record from its parts, every ingredient drawn from ``key``: the engine's bearing
    signal ``fault`` (T,) (sensor output of the defect's impacts; any level) and the item's
    background ``background`` (T,); ``fault_class`` 0-3 (healthy, outer, inner, ball; traced).

    1. a ball fault (class 3) re-shaped by :func:`ball_fault_modulation` (``ball_fault_model``);
    2. a fault (class > 0) scaled to ``fault_snr_dB`` over the background (:func:`fault_level`);
       a healthy item's ``fault`` is dropped;
    3. plus :func:`nuisance_signal` at the background's RMS (``nuisance``);
    4. the sum modulated by :func:`shaft_modulation` (``shaft_modulation``);

    before 2, the background times :func:`race_waviness` (``race_waviness``).

    ``settings``: :data:`NUISANCE_DEFAULTS` keys and the switches of :data:`INGREDIENTS` (booleans,
    default on).  Returns (record, labels: snr_dB and each ingredient's draws)."""
    on = {k: bool((settings or {}).get(k, True)) for k in INGREDIENTS}
    s = settings_of({k: v for k, v in (settings or {}).items() if k not in INGREDIENTS})
    T = fault.shape[-1]
    k = jax.random.split(key, 4)
    x = fault - jnp.mean(fault)
    labels = {}
    if on["ball_fault_model"]:
        xb, lb = ball_fault_modulation(k[0], x, fs, shaft_hz, ftf_hz, bsf_hz, s)
        x = jnp.where(fault_class == CLASS_NUMBER["ball"], xb, x)
        labels.update({n: jnp.where(fault_class == CLASS_NUMBER["ball"], v, 0.0) for n, v in lb.items()})
    if on["race_waviness"]:
        wv, lw = race_waviness(jax.random.fold_in(key, 4), T, fs, ftf_hz, bpfo_hz, bpfi_hz, bsf_hz, s)
        background = background * wv
        labels.update(lw)
    g, snr = fault_level(k[1], x, background, s)
    y = jnp.where(fault_class > 0, g, 0.0) * x + background
    labels["snr_dB"] = jnp.where(fault_class > 0, snr, 0.0)
    if on["nuisance"]:
        n, ln = nuisance_signal(k[2], T, fs, shaft_hz, ftf_hz, bpfo_hz, bpfi_hz, bsf_hz, _rms(background), s)
        y = y + n
        labels.update({f"nuisance_{a}": v for a, v in ln.items()})
    if on["shaft_modulation"]:
        y, lm = shaft_modulation(k[3], y, fs, shaft_hz, s)
        labels.update({f"modulation_{a}": v for a, v in lm.items()})
    return y, labels
