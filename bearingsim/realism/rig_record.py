"""Realism of simulated records against the CWRU rig (issue 9): the physics of an EDM pit under a
ball contact, pass-to-pass impact variability, the 12 kHz acquisition, and the record pipeline.

The engine (:mod:`bearingsim.dynamics`) supplies the housing acceleration, the spall pass times,
the sensor modes (:mod:`bearingsim.dynamics.sensor`, applied exactly after the ODE), random slip, speed
fluctuation and measurement noise.  This module adds what the engine does not model:

Pit under a contact (amplitude physics)
    The CWRU faults are round EDM pits (diameter w = 0.007-0.040 in, depth 0.011 in) at the
    bottom of the outer groove.  The outer contact ellipse of a loaded 6205 ball is 2a ~ 1-2 mm
    across the track and 2b ~ 0.15-0.3 mm along it, so a pit is much narrower than the contact:
    the ball does not drop into it as into a full-width groove (the rectangular profile's drop,
    the ball's sag over the chord, ~ w^2 / (4 D) = 1.0 um for 0.007 in and 9.0 um for 0.021 in,
    x 9).  It keeps rolling on the raceway beside the pit and only loses the Hertz pressure over
    the pit's area.  :func:`pit_effective_depth` turns that lost fraction phi of the ball load
    (at the ball's approach) into the depth the Jones model needs for the same load loss,
    ``H = delta_o (1 - (1 - phi)^(2/3))`` (Q ~ delta^1.5), capped by the sag and the machined
    depth (x 3.1 from 0.007 to 0.021 in at the calibrated CWRU operating point).

Pass-to-pass variability
    Successive impacts of one record differ; the rig's 0.021 in records show it clearly
    (kurtosis 21 against 7.6, a BPFO line 16 dB lower over its floor at equal length, impact
    intervals 5.5 % apart against 0.9 %).  :func:`vary_passes` scales and delays the housing
    acceleration of each pass (factors log-normal with mean square 1 and coefficient of
    variation ``cv``; Gaussian delays of ``jitter`` x the pass interval) before the sensor path;
    in the small-depth regime the response is proportional to the depth, so this is a per-pass
    effective depth and exit time.  Both scale with :func:`unbridged_fraction`,
    ``max(0, 1 - 2 b / w)``: a pit shorter than the contact length is bridged (the load change is
    set by geometry, the same every pass); over a longer pit the contact's central strip runs
    free and re-engages at the exit edge with the ball's momentary lateral position and spin.
    One fitted constant each: the [dynamics] keys ``pass_amplitude_cv_max_percent`` and
    ``pass_delay_sd_max_percent`` of the CWRU cases (the engine applies them,
    :func:`bearingsim.dynamics.passes.pass_variability`, to the sensor path of
    :func:`bearingsim.dynamics.simulate` and of the data sets).

Acquisition
    The 12 kHz CWRU records are acquired with an anti-alias filter (their spectra fall steeply
    above ~5.5 kHz): :func:`decimate_record` low-passes (zero-phase FIR) and down-samples a
    48 kHz simulated record the same way.

Everything is seeded; :func:`sensor_record` returns the record and the labels of its draws.
"""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import scipy.signal as ss

from ..case import as_scenario
from ..dynamics import DynamicsParameters, Realism, simulate
from ..errors import InputError
from ..physics.pit import (  # noqa: F401  (re-exported: the record pipeline's vocabulary)
    Contact, PIT_LOCATIONS, contact_of, contact_at, PitDepth, pit_load_fraction, pit_depth,
    pit_effective_depth, pit_depth_of_solution, unbridged_fraction, pit_unbridged_fraction, pass_cv)
from ..keys import item_keys
from ..dynamics.passes import PassSettings, pass_variability
from ..dynamics.sensor import apply_sensor

__all__ = [
    "Contact",
    "PIT_LOCATIONS",
    "contact_of",
    "contact_at",
    "PitDepth",
    "pit_load_fraction",
    "pit_depth",
    "pit_effective_depth",
    "pit_depth_of_solution",
    "unbridged_fraction",
    "pit_unbridged_fraction",
    "pass_cv",
    "decimate_record",
    "sensor_record",
]


# ------------------------------------------------------------------------------ acquisition
def decimate_record(x, fs, fs_out):
    """(y, fs_out): ``x`` low-passed by a zero-phase FIR anti-alias filter and down-sampled by
    the integer ratio ``fs / fs_out`` (``scipy.signal.decimate``, cut-off 0.8 x the new
    Nyquist frequency), as a 12 kHz acquisition of a 48 kHz signal."""
    q = float(fs) / float(fs_out) if float(fs_out) > 0 else float("nan")
    k = int(round(q)) if np.isfinite(q) else 0
    if k < 1 or abs(q - k) > 1e-9:
        raise InputError(f"fs / fs_out must be an integer >= 1, got {fs} / {fs_out}",
                         "choose an output rate fs_out > 0 that divides the input rate, e.g. 48000 -> 12000 Hz")
    if k == 1:
        return np.asarray(x, dtype=float), float(fs)
    return ss.decimate(np.asarray(x, dtype=float), k, ftype="fir", zero_phase=True), float(fs_out)


# ------------------------------------------------------------------------------ pipeline
def sensor_record(result, params, cv=0.0, seed=0, fs_out=None, jitter=0.0):
    """(record in m/s^2, sample rate, labels) of a :class:`bearingsim.dynamics.DynamicsResult`.

    The housing acceleration (x) goes through the sensor modes of ``params``
    (:func:`bearingsim.dynamics.sensor.apply_sensor`, exact first-order hold at the sample
    interval), with the pass-to-pass factors and delays of the signal stage
    (:func:`bearingsim.dynamics.passes.pass_variability`: factors of coefficient of variation
    ``cv``, Gaussian delays of standard deviation ``jitter`` times the mean pass interval, both
    drawn from the key of item 0 of a run seeded ``seed``), and gets the run's own measurement
    noise (``result.noise``); then it is decimated to ``fs_out`` when given.  With ``cv = 0`` and
    ``jitter = 0`` this is the engine's ``sensor_acceleration`` (up to the filter's
    discretisation step).
    """
    t = np.asarray(result.time)
    fs = 1.0 / float(t[1] - t[0])
    a_h = np.asarray(result.housing_acceleration)[:, 0]
    tp = np.asarray(result.pass_times, dtype=float)
    if not (np.isfinite(cv) and cv >= 0 and np.isfinite(jitter) and jitter >= 0):
        raise InputError(f"cv and jitter must be >= 0, got {cv}, {jitter}",
                         "cv: coefficient of variation of the pass factors; jitter: delay s.d. / pass interval")
    f, z, g = (np.asarray(v, float) for v in params.modes())
    y = np.asarray(apply_sensor(a_h, 1.0 / fs, f, z, g))
    n = tp.size
    P = 1 << max(n, 1).bit_length()                     # a few padded shapes: one program per power of two
    tpp = np.concatenate([tp, np.full(P - n, np.inf)])
    st = PassSettings(float(fs), pass_cv_max=float(cv), pass_delay_max=float(jitter))
    modes = np.stack(np.broadcast_arrays(f, z, g), -1)
    y, fac, shifts, _, _ = pass_variability(item_keys(seed, [0])[0], jnp.asarray(a_h), jnp.asarray(y),
                                            jnp.asarray(tpp), jnp.float64(1.0), jnp.asarray(modes), jnp.float64(1.0), st)
    y = np.asarray(y, float)
    fac, shifts = np.asarray(fac)[:n + 1], np.asarray(shifts)[:n + 1]
    noise = getattr(result, "noise", None)
    if noise is not None:
        y = y + np.asarray(noise)
    labels = {"pass_cv": float(cv), "pass_jitter": float(jitter), "pass_factors": fac,
              "pass_shifts": shifts, "pass_times": tp, "seed": int(seed)}
    if fs_out is not None and float(fs_out) != fs:
        y, fs = decimate_record(y, fs, fs_out)
    return y, fs, labels


def simulate_record(case, *, duration=None, sample_rate=None, seed=None, pass_cv_max=None,
                    pass_jitter_max=None, overrides=None, fs_out=None, progress=False):
    """Simulate a case (or its built scenario) and return (record in m/s^2, sample rate, DynamicsResult, labels).

    The [dynamics] settings of ``case`` (engine keys: modes, slip, speed fluctuation, noise and
    the pass-to-pass variability), updated by ``overrides`` (SI names as in
    ``Case.dynamics_settings()``), drive :func:`bearingsim.dynamics.simulate`; ``pass_cv_max``
    / ``pass_jitter_max`` (fractions; None: the case's ``pass_amplitude_cv_max_percent`` /
    ``pass_delay_sd_max_percent``) override the variability maxima.  The record is the run's
    sensor acceleration, decimated to ``fs_out`` when given; ``labels`` are the run's realism
    labels (``result.realism``).  ``duration``/``sample_rate``/``seed`` default to the case's.
    """
    sc = as_scenario(case)
    d = dict(sc.dynamics)
    d.update(overrides or {})
    if pass_cv_max is not None:
        d["pass_amplitude_cv_max_percent"] = 100.0 * float(pass_cv_max)
    if pass_jitter_max is not None:
        d["pass_delay_sd_max_percent"] = 100.0 * float(pass_jitter_max)
    duration = d["duration"] if duration is None else float(duration)
    sample_rate = d["sample_rate"] if sample_rate is None else float(sample_rate)
    seed = int(d.get("seed", 0)) if seed is None else int(seed)
    params = DynamicsParameters.from_settings(d)
    realism = Realism.from_settings(d)
    r = simulate(sc.bearing, sc.operation, sc.loads, sc.spall, params, duration, sample_rate,
                 theta0=sc.cage_angle, realism=realism, seed=seed, hertz_method=sc.hertz_method,
                 record_balls=False, progress=progress)
    y, fs = np.asarray(r.sensor_acceleration), float(sample_rate)
    if fs_out is not None and float(fs_out) != fs:
        y, fs = decimate_record(y, fs, fs_out)
    labels = dict(r.realism)
    labels.setdefault("unbridged_fraction", 0.0)
    return y, fs, r, labels
