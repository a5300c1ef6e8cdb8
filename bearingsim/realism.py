"""Realism of simulated records against the CWRU rig (issue 9): the physics of an EDM pit under a
ball contact, pass-to-pass impact variability, the 12 kHz acquisition, and the record pipeline.

The engine (:mod:`bearingsim.dynamics`) supplies the housing acceleration, the spall pass times,
the sensor modes (:mod:`bearingsim.sensor`, applied exactly after the ODE), random slip, speed
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
    :func:`pass_variation`, to the sensor path of :func:`bearingsim.dynamics.simulate` and of the
    data sets).

Acquisition
    The 12 kHz CWRU records are acquired with an anti-alias filter (their spectra fall steeply
    above ~5.5 kHz): :func:`decimate_record` low-passes (zero-phase FIR) and down-samples a
    48 kHz simulated record the same way.

Everything is seeded; :func:`sensor_record` returns the record and the labels of its draws.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.signal as ss


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
    "pass_variation",
    "pass_cv",
    "pass_factors",
    "vary_passes",
    "decimate_record",
    "sensor_record",
]


# ------------------------------------------------------------------------------ pit physics
def pit_load_fraction(a, b, pit_diameter, offset=0.0, n=2001) -> float:
    """Fraction of a Hertz contact's load carried over a round pit.

    ``a`` semi-axis across the track, ``b`` along it, ``pit_diameter`` and ``offset`` (the
    distance across the track from the contact centre to the pit centre) in the same unit.  The
    Hertz pressure ``p0 sqrt(1 - x^2/a^2 - y^2/b^2)`` is integrated over the disc analytically in
    y and numerically in x (``n`` points, Simpson), divided by the load ``(2/3) pi a b p0``.
    Limits: 1 for a pit that covers the contact, ``3 r^2 / (2 a b)`` for a centred pit of radius
    r << b.
    """
    from scipy.integrate import simpson

    a, b, r, e = float(a), float(b), 0.5 * float(pit_diameter), abs(float(offset))
    if not (a > 0 and b > 0 and r >= 0):
        raise ValueError(f"need a, b > 0 and pit_diameter >= 0, got {a}, {b}, {pit_diameter}")
    lo, hi = max(e - r, -a), min(e + r, a)
    if r == 0.0 or lo >= hi:
        return 0.0
    x = np.linspace(lo, hi, n | 1)
    c = b * np.sqrt(np.clip(1.0 - (x / a) ** 2, 0.0, None))                 # ellipse half-chord
    y0 = np.minimum(np.sqrt(np.clip(r * r - (x - e) ** 2, 0.0, None)), c)    # disc within it
    ratio = np.divide(y0, c, out=np.zeros_like(c), where=c > 0)
    inner = y0 * np.sqrt(np.clip(c * c - y0 * y0, 0.0, None)) + c * c * np.arcsin(np.clip(ratio, 0, 1))
    return float(min(1.0, simpson(inner / b, x=x) / (2.0 / 3.0 * np.pi * a * b)))


class Contact(NamedTuple):
    """One contact of the ball at a given azimuth in the healthy quasi-static state (SI)."""

    delta: float            # approach delta (m)
    a: float                # semi-axis across the track (m)
    b: float                # semi-axis along the track (m)
    Q: float                # load (N)
    alpha: float            # contact angle (rad)
    offset: float           # contact centre to the groove bottom across the track, f D sin(alpha) (m)


#: where a pit sits: the outer or inner groove bottom, or a point of a ball's surface
PIT_LOCATIONS = ("outer", "inner", "ball")


def contact_of(sol, bearing, j, race="outer", centred=False) -> Contact:
    """:class:`Contact` of ball ``j`` of the (single, host) quasi-static solution ``sol`` at its
    ``race`` ("outer" or "inner") contact; ``offset`` is the contact centre's distance from the
    groove bottom, ``f D |sin alpha|`` (0 with ``centred``: a pit on the ball, which meets the
    contact on the ball's rolling circle)."""
    if race not in ("outer", "inner"):
        raise ValueError(f"race must be 'outer' or 'inner', got {race!r}")
    get = lambda name: float(np.asarray(getattr(sol, f"{name}_{race}"))[j])  # noqa: E731
    alpha = get("alpha")
    f = float(bearing.f_outer if race == "outer" else bearing.f_inner)
    offset = 0.0 if centred else f * float(bearing.ball_diameter) * abs(np.sin(alpha))
    return Contact(get("delta"), get("a"), get("b"), get("Q"), alpha, offset)


def contact_at(bearing, op, loads, center=0.0, hertz_method="exact", race="outer") -> Contact:
    """The ``race`` contact of the ball placed at azimuth ``center`` in the healthy bearing."""
    from .jones import solve

    sol = solve(bearing, op, loads, cage_angle=center, hertz_method=hertz_method)
    psi = np.asarray(sol.azimuth)
    j = int(np.argmin(np.abs(np.angle(np.exp(1j * (psi - center))))))
    return contact_of(sol, bearing, j, race)


class PitDepth(NamedTuple):
    """Result of :func:`pit_effective_depth` (SI)."""

    depth: float            # effective depth H for the Jones model (m)
    load_fraction: float    # phi: ball load lost over the pit at the ball's approach
    sag: float              # the ball's sag over the pit chord, D/2 - sqrt(D^2/4 - w^2/4) (m)
    contact: Contact        # the ball's healthy contact at the pit


def pit_depth(contact: Contact, pit_diameter, machined_depth, ball_diameter) -> PitDepth:
    """Effective depth of a round pit of ``pit_diameter`` (m) under the healthy ``contact``:
    the pit removes the fraction phi of the contact's load (:func:`pit_load_fraction`, the pit
    ``contact.offset`` away from the contact centre across the track) at its approach, which the
    Jones model reproduces with the depth ``delta (1 - (1 - phi)^(2/3))`` (Q ~ delta^1.5),
    capped by the ball's sag over the pit chord and by the machined depth."""
    D, w = float(ball_diameter), float(pit_diameter)
    sag = 0.5 * D - np.sqrt(max(0.0, 0.25 * D * D - 0.25 * w * w))
    phi = min(1.0, pit_load_fraction(contact.a, contact.b, w, contact.offset)) if contact.a > 0 else 0.0
    h = max(contact.delta, 0.0) * (1.0 - (1.0 - phi) ** (2.0 / 3.0))
    return PitDepth(float(min(h, sag, float(machined_depth))), phi, float(sag), contact)


def pit_effective_depth(bearing, op, loads, pit_diameter, machined_depth, center=0.0,
                        hertz_method="exact", location="outer") -> PitDepth:
    """Effective depth of a round EDM pit of ``pit_diameter`` (m), ``machined_depth`` deep, for
    the Jones model.

    ``location`` "outer" (default): the pit at the outer groove bottom at azimuth ``center``;
    the healthy quasi-static state with a ball there gives that ball's outer approach and contact
    ellipse (:func:`contact_at`), the contact centre ``f_o D sin(alpha_o)`` away from the groove
    bottom.  "inner": the pit at the inner groove bottom, met by the ball at azimuth ``center``
    (pass the load-zone centre: the pit turns with the shaft and its strongest impacts are
    there); its inner contact, offset ``f_i D sin(alpha_i)``.  "ball": a pit on the ball's
    rolling circle (no offset), met by the outer and the inner contact in turn: the mean of the
    two effective depths (the engine carries one depth per pit; :class:`PitDepth` reports the
    outer contact and the mean lost fraction).  The depth follows from :func:`pit_depth`.
    Neglected: the pressure redistribution around the pit (the remaining contact is not
    Hertzian) and the contact's entry/exit over the pit edges (the rectangular profile switches
    at the pit edges).
    """
    from .jones import solve

    if location not in PIT_LOCATIONS:
        raise ValueError(f"location must be one of {PIT_LOCATIONS}, got {location!r}")
    sol = solve(bearing, op, loads, cage_angle=center, hertz_method=hertz_method)
    psi = np.asarray(sol.azimuth)
    j = int(np.argmin(np.abs(np.angle(np.exp(1j * (psi - center))))))
    return pit_depth_of_solution(sol, bearing, j, location, pit_diameter, machined_depth)


def pit_depth_of_solution(sol, bearing, j, location, pit_diameter, machined_depth) -> PitDepth:
    """:func:`pit_effective_depth` for ball ``j`` of a healthy (single, host) quasi-static
    solution ``sol`` that is already at hand (the data sets solve their items in batches)."""
    D = float(bearing.ball_diameter)
    if location in ("outer", "inner"):
        return pit_depth(contact_of(sol, bearing, j, location), pit_diameter, machined_depth, D)
    if location != "ball":
        raise ValueError(f"location must be one of {PIT_LOCATIONS}, got {location!r}")
    po = pit_depth(contact_of(sol, bearing, j, "outer", centred=True), pit_diameter, machined_depth, D)
    pi = pit_depth(contact_of(sol, bearing, j, "inner", centred=True), pit_diameter, machined_depth, D)
    return PitDepth(0.5 * (po.depth + pi.depth), 0.5 * (po.load_fraction + pi.load_fraction), po.sag,
                    po.contact)


# ------------------------------------------------------------------------------ variability
def unbridged_fraction(pit_diameter, contact_semi_axis_b) -> float:
    """``max(0, 1 - 2 b / w)``: the fraction of the pit length ``w`` that the contact (length 2b)
    cannot bridge, i.e. over which its central strip runs free."""
    w, b = float(pit_diameter), float(contact_semi_axis_b)
    return max(0.0, 1.0 - 2.0 * b / w) if w > 0.0 else 0.0


def pit_unbridged_fraction(sol, bearing, j, location, pit_length) -> float:
    """:func:`unbridged_fraction` of a pit ``pit_length`` (m) long under ball ``j``'s contact in
    the healthy (single, host) quasi-static state ``sol``: its outer contact for an outer-race
    pit, its inner contact for an inner-race pit, the mean of the two for a pit on the ball
    (which meets both raceways in turn)."""
    if location in ("outer", "inner"):
        return unbridged_fraction(pit_length, contact_of(sol, bearing, j, location).b)
    if location != "ball":
        raise ValueError(f"location must be one of {PIT_LOCATIONS}, got {location!r}")
    return 0.5 * sum(unbridged_fraction(pit_length, contact_of(sol, bearing, j, r, centred=True).b)
                     for r in ("outer", "inner"))


def pass_cv(pit_diameter, contact_semi_axis_b, cv_max) -> float:
    """Coefficient of variation of the per-pass impact factor, ``cv_max`` times
    :func:`unbridged_fraction`."""
    return float(cv_max) * unbridged_fraction(pit_diameter, contact_semi_axis_b)


def pass_factors(rng: np.random.Generator, n, cv) -> np.ndarray:
    """``n`` log-normal factors with mean square 1 and coefficient of variation ``cv``
    (all 1 for cv = 0): ``exp(s xi - s^2)``, ``s^2 = ln(1 + cv^2)``, xi standard normal."""
    cv = float(cv)
    if cv < 0:
        raise ValueError(f"cv must be >= 0, got {cv}")
    xi = rng.standard_normal(int(n))
    s2 = np.log1p(cv * cv)
    return np.exp(np.sqrt(s2) * xi - s2)


def pass_variation(x, fs, pass_times, cv, jitter, seed):
    """(varied x, factors, delays): :func:`vary_passes` of ``x`` with log-normal factors of
    coefficient of variation ``cv`` (:func:`pass_factors`) and Gaussian delays of standard
    deviation ``jitter`` x the mean pass interval, drawn (factors first, then delays) from
    ``numpy.random.default_rng(SeedSequence([seed, 9]))``: stream 9 of the run's realism seed,
    apart from the engine's slip, fluctuation and noise streams.  ``cv = jitter = 0`` returns
    ``x`` itself (and the draws, unused)."""
    tp = np.asarray(pass_times, dtype=float)
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 9]))
    fac = pass_factors(rng, tp.size + 1, cv)
    T = float(np.mean(np.diff(tp))) if tp.size > 1 else 0.0
    shifts = float(jitter) * T * rng.standard_normal(tp.size + 1)
    if cv > 0 or jitter > 0:
        x = vary_passes(x, fs, tp, fac, shifts)
    return x, fac, shifts


def _ramp(t, edge, width):
    u = np.clip((t - edge) / width + 0.5, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * u)


def vary_passes(x, fs, pass_times, factors, shifts=None, lead=0.15, taper=0.1) -> np.ndarray:
    """Scale (and delay) the part of ``x`` (sampled at ``fs``) that belongs to each spall pass.

    Pass k owns ``[t_k - lead T, t_{k+1} - lead T)`` (T the mean pass interval): the ball enters
    the spall shortly before its centre passes and the structure rings afterwards.  Neighbouring
    windows overlap in raised-cosine tapers ``taper T`` wide (a partition of unity).  Piece k is
    multiplied by ``factors[k]`` and delayed by ``shifts[k]`` seconds (linear interpolation;
    default none), and the pieces are added.  There is one factor/shift per pass time plus one
    (index 0) for the part before the first pass; ``x`` is de-meaned first and the mean added
    back.  All factors 1 and no shifts return ``x``.
    """
    x = np.asarray(x, dtype=float)
    tp = np.sort(np.asarray(pass_times, dtype=float))
    factors = np.asarray(factors, dtype=float)
    if factors.size != tp.size + 1:
        raise ValueError(f"need len(pass_times) + 1 = {tp.size + 1} factors, got {factors.size}")
    shifts = np.zeros(factors.size) if shifts is None else np.asarray(shifts, dtype=float)
    if shifts.size != factors.size:
        raise ValueError(f"need {factors.size} shifts (one per factor), got {shifts.size}")
    m = x.mean()
    xc = x - m
    t = np.arange(x.size) / float(fs)
    T = float(np.mean(np.diff(tp))) if tp.size > 1 else max(t[-1], 1.0 / float(fs))
    edges = tp - lead * T
    w = taper * T
    up = [np.zeros(x.size)] + [_ramp(t, e, w) for e in edges]       # 0, ramp_1, ..., ramp_K
    out = np.zeros(x.size)
    for k in range(factors.size):
        win = (1.0 if k == 0 else up[k]) - (up[k + 1] if k + 1 < len(up) else 0.0)
        piece = factors[k] * win * xc
        if shifts[k] != 0.0:
            piece = np.interp(t - shifts[k], t, piece, left=0.0, right=0.0)
        out += piece
    return out + m


# ------------------------------------------------------------------------------ acquisition
def decimate_record(x, fs, fs_out):
    """(y, fs_out): ``x`` low-passed by a zero-phase FIR anti-alias filter and down-sampled by
    the integer ratio ``fs / fs_out`` (``scipy.signal.decimate``, cut-off 0.8 x the new
    Nyquist frequency), as a 12 kHz acquisition of a 48 kHz signal."""
    q = float(fs) / float(fs_out)
    k = int(round(q))
    if k < 1 or abs(q - k) > 1e-9:
        raise ValueError(f"fs / fs_out must be an integer, got {fs} / {fs_out}")
    if k == 1:
        return np.asarray(x, dtype=float), float(fs)
    return ss.decimate(np.asarray(x, dtype=float), k, ftype="fir", zero_phase=True), float(fs_out)


# ------------------------------------------------------------------------------ pipeline
def sensor_record(result, params, cv=0.0, seed=0, fs_out=None, jitter=0.0):
    """(record in m/s^2, sample rate, labels) of a :class:`bearingsim.dynamics.DynamicsResult`.

    The housing acceleration (x) gets the pass-to-pass factors and delays (:func:`vary_passes`;
    factors of coefficient of variation ``cv``, Gaussian delays of standard deviation ``jitter``
    times the mean pass interval, both drawn from ``seed``), goes through the sensor modes of ``params`` (:func:`bearingsim.sensor.apply_sensor`,
    exact first-order hold at the sample interval) and gets the run's own measurement noise
    (``result.noise``); then it is decimated to ``fs_out`` when given.  With ``cv = 0`` this is
    the engine's ``sensor_acceleration`` (up to the filter's discretisation step).
    """
    from .sensor import apply_sensor

    t = np.asarray(result.time)
    fs = 1.0 / float(t[1] - t[0])
    a_h = np.asarray(result.housing_acceleration)[:, 0]
    tp = np.asarray(result.pass_times, dtype=float)
    a, fac, shifts = pass_variation(a_h, fs, tp, cv, jitter, seed)
    f, z, g = (np.asarray(v) for v in params.modes())
    y = np.asarray(apply_sensor(a, 1.0 / fs, f, z, g))
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
    """Simulate a case and return (record in m/s^2, sample rate, DynamicsResult, labels).

    The [dynamics] settings of ``case`` (engine keys: modes, slip, speed fluctuation, noise and
    the pass-to-pass variability), updated by ``overrides`` (SI names as in
    ``Case.dynamics_settings()``), drive :func:`bearingsim.dynamics.simulate`; ``pass_cv_max``
    / ``pass_jitter_max`` (fractions; None: the case's ``pass_amplitude_cv_max_percent`` /
    ``pass_delay_sd_max_percent``) override the variability maxima.  The record is the run's
    sensor acceleration, decimated to ``fs_out`` when given; ``labels`` are the run's realism
    labels (``result.realism``).  ``duration``/``sample_rate``/``seed`` default to the case's.
    """
    from .dynamics import DynamicsParameters, Realism, simulate

    d = dict(case.dynamics_settings())
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
    r = simulate(case.bearing(), case.operation(), case.loads(), case.spall(), params, duration, sample_rate,
                 theta0=case.cage_angle, realism=realism, seed=seed, hertz_method=case.hertz_method,
                 record_balls=False, progress=progress)
    y, fs = np.asarray(r.sensor_acceleration), float(sample_rate)
    if fs_out is not None and float(fs_out) != fs:
        y, fs = decimate_record(y, fs, fs_out)
    labels = dict(r.realism)
    labels.setdefault("unbridged_fraction", 0.0)
    return y, fs, r, labels
