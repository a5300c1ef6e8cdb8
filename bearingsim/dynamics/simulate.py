"""One dynamic simulation (docs/model.md section 7): :func:`simulate` and its
:class:`DynamicsResult`.  The model is in :mod:`bearingsim.dynamics.model`, the ball forces in
:mod:`~bearingsim.dynamics.ball_force`, the drawn motion in :mod:`~bearingsim.dynamics.motion`,
the time loop in :mod:`~bearingsim.dynamics.integrate`.

A quasi-static state that did not converge, or an equilibrium that cannot be found, is flagged
in ``result`` (:class:`RESULTS`), never used silently.
"""
from __future__ import annotations

import threading
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..physics.defect import Spall, as_defects
from ..errors import failed, InputError, succeeded
from ..physics.hertz import stiffness_curve
from ..physics.jones import result_hint, solve
from ..physics.kinematics import DefectFrequencies, Operation
from .passes import PassSettings, pass_variability
from .sensor import host_measurement_noise
from ..physics.pit import pit_unbridged_fraction
from ..programs import jit
from .. import warm
from ..xla import QUICK_COMPILE
from .ball_force import ITER_CHOICES, RECORD_ROWS, bearing_force, choose_ball_iterations, precompile_ball_check, record_loads_angles
from .integrate import CHUNK, check_scheme, precompile_fixed, run_adaptive, run_fixed, time_grid
from .frequencies import characteristic_frequencies, spin_ratio
from .model import DynamicModel, build_model, choose_substeps, initial_state_jit, linear_modes
from ..keys import item_keys
from .motion import (MOTION_STREAM, defect_edge_times, defect_pass_times, draw_motion, knot_count, motion_realism,
                     run_labels, run_motion_at)
from .parameters import RESULTS, DynamicsError, DynamicsParameters, Realism

__all__ = ["DynamicsResult", "slip_reference",
           "rectangular", "ball_records", "load_zone_centre", "unbridged_of", "finish_record", "simulate"]


def slip_reference(defects):
    """The azimuth slip pitches start from: the first outer spall's centre (0 without one)."""
    for sp in defects:
        if sp.location == "outer":
            return float(sp.center)
    return 0.0


def rectangular(defects):
    """The defects with a rectangular profile (their edges are integrated exactly)."""
    return tuple(sp for sp in defects if sp.profile == "rectangular")


def load_zone_centre(loads) -> float:
    """Azimuth (rad) of the radial load [Fx, Fy] (0 for a purely axial load): where an inner-race
    pit meets its strongest contacts."""
    F = np.asarray(loads, float)
    return float(np.arctan2(F[1], F[0])) if np.hypot(F[0], F[1]) > 0.0 else 0.0


def unbridged_of(bearing, op, loads, defects, hertz_method="exact"):
    """(unbridged fraction, ok) of the one defect in ``defects``, taken as a round pit of its
    arc length under the healthy contact (:func:`bearingsim.physics.pit.pit_unbridged_fraction`):
    the outer contact of the ball at an outer pit, the inner contact of the ball at the load
    zone's centre for an inner pit, both for a ball pit.  The healthy state is the defective
    solve's own program with depth 0 (no compilation).  ``ok`` False: it did not converge."""
    if len(defects) != 1:
        raise InputError("the pass-to-pass variability ([dynamics] pass_amplitude_cv_max_percent, "
                         f"pass_delay_sd_max_percent) is defined for one defect, got {len(defects)}; "
                         "set both to 0 for several defects")
    sp = defects[0]
    centre = float(sp.center) if sp.location == "outer" else load_zone_centre(loads)
    healthy = Spall(sp.center, sp.extent, 0.0, sp.profile, sp.location, sp.ball)
    sol = solve(bearing, op, loads, cage_angle=centre, spall=healthy, hertz_method=hertz_method, throw=False)
    if failed(int(sol.result)):
        return 0.0, False
    host = jax.tree_util.tree_map(np.asarray, sol)
    j = int(np.argmin(np.abs(np.angle(np.exp(1j * (host.azimuth - centre))))))
    return pit_unbridged_fraction(host, bearing, j, sp.location, float(sp.length(bearing))), True


def finish_record(key, housing, sensor, pass_times, unbridged, modes, realism, fs):
    """A simulation's sensor record after the time loop, as a data set item's signal stage makes
    it (:mod:`bearingsim.signals.signal_stage`, every draw from the run's ``key``): the
    pass-to-pass variability of a pit's impacts (:func:`~bearingsim.dynamics.passes.pass_variability`:
    c.v. and delay s.d. the realism's maxima times the pit's ``unbridged`` fraction; the housing
    acceleration ``housing`` (T,) varied pass by pass and put through the sensor ``modes`` (f, zeta,
    g) again; displacements and housing acceleration stay the ODE's) and the measurement noise
    (:func:`~bearingsim.signals.signal_stage.measurement_noise`, the key's ``noise`` stream).
    ``pass_times`` (n,) s.  Returns (record without noise, noise, labels: ``unbridged_fraction``,
    ``pass_amplitude_cv_percent``, ``pass_delay_sd_percent``, ``pass_factors`` and ``pass_shifts``
    (n + 1,) when the variability is on)."""
    T = int(np.shape(sensor)[0])
    labels = {}
    out = np.asarray(sensor, float)
    if realism.pass_variation:
        n = int(np.size(pass_times))
        args, st = _pass_arguments(key, housing, sensor, pass_times, unbridged, modes, realism, fs)
        a, fac, shifts, cv, jit_ = pass_variability(*args, st)
        out = np.asarray(a, float)
        labels.update(unbridged_fraction=float(unbridged), pass_amplitude_cv_percent=100.0 * float(cv),
                      pass_delay_sd_percent=100.0 * float(jit_), pass_factors=np.asarray(fac)[:n + 1],
                      pass_shifts=np.asarray(shifts)[:n + 1])
    noise = np.zeros(T)
    if realism.noise_rms > 0.0:
        noise = np.asarray(host_measurement_noise(key, T, realism.noise_rms, fs,
                                             realism.noise_band), float)
    return out, noise, labels


def _pass_arguments(key, housing, sensor, pass_times, unbridged, modes, realism, fs):
    """The arguments of :func:`pass_variability` for one record (NumPy: the kept program takes
    them as they are, no eager operation) and its static settings."""
    n = int(np.size(pass_times))
    P = max(n, 1 << max(n, 1).bit_length())          # a few padded shapes: one program per power of two
    tp = np.concatenate([np.asarray(pass_times, float), np.full(P - n, np.inf)])
    st = PassSettings(float(fs), pass_cv_max=0.01 * float(realism.pass_amplitude_cv_max_percent),
                      pass_delay_max=0.01 * float(realism.pass_delay_sd_max_percent))
    return (np.asarray(key, np.uint32), np.asarray(housing, np.float64), np.asarray(sensor, np.float64), tp,
            np.float64(unbridged), np.stack([np.asarray(v, np.float64) for v in modes], -1), np.float64(1.0)), st


_PRECOMPILED: set = set()


def precompile_passes(T, pass_times, modes, realism, fs, after=None):
    """Compile the pass-to-pass program of :func:`finish_record` for a record of ``T`` samples in
    a background thread once the thread ``after`` (the time loop's compilation) is done, so that
    it compiles while the time loop runs (a first simulation compiled it after the loop: 1.0-1.4
    s on a 2-core CPU; started beside the time loop's compilation it delayed that one instead).
    None when this configuration was compiled before in this process or the variability is off.
    The thread runs it once on zeros and discards the result (an error there is the program's
    own and is raised by the real call)."""
    if not realism.pass_variation:
        return None
    z = np.zeros(int(T))
    args, st = _pass_arguments(np.zeros(2, np.uint32), z, z, pass_times, 0.0, modes, realism, fs)
    key = (tuple(np.shape(a) for a in args), st)
    if key in _PRECOMPILED:
        return None
    _PRECOMPILED.add(key)

    def run():
        try:
            if after is not None:
                after.join()
            pass_variability(*args, st)
        except Exception:       # noqa: BLE001 -- the real call raises it
            pass

    th = threading.Thread(target=run, name="bearingsim-precompile", daemon=True)
    th.start()
    return th


class DynamicsResult(NamedTuple):
    """Output of :func:`simulate` (SI; T samples, Z balls)."""

    time: np.ndarray                    # (T,) s
    cage_angle: np.ndarray              # (T,) rad
    shaft_speed: np.ndarray             # (T,) rad/s
    ring_displacement: np.ndarray       # (T, 3) shaft relative to housing x, y, axial (m)
    shaft_displacement: np.ndarray      # (T, 3) absolute (m)
    housing_displacement: np.ndarray    # (T, 2) m
    housing_acceleration: np.ndarray    # (T, 2) m/s^2
    sensor_acceleration: np.ndarray     # (T,) m/s^2 (sensor path, plus noise)
    noise: np.ndarray                   # (T,) m/s^2, the noise part of sensor_acceleration
    Q_inner: np.ndarray                 # (T, Z) N (None with record_balls=False)
    Q_outer: np.ndarray
    alpha_inner: np.ndarray             # (T, Z) rad
    alpha_outer: np.ndarray
    result: int                         # RESULTS code (0 = successful)
    num_steps: int
    frequencies: DefectFrequencies      # shaft, ftf, bpfo, bpfi, bsf in Hz (nominal speed)
    contact_angle: float                # rad, mean loaded contact angle (quasi-static)
    jump_times: np.ndarray              # defect entry/exit times (rectangular profile) (s)
    pass_times: np.ndarray              # times a ball meets a defect's centre (s)
    quasi_static: object                # JonesSolution at t = 0
    contact_damping: np.ndarray         # (3,) N s/m
    ball_iterations: int
    substeps: int
    scheme: str
    realism: dict                       # labels of the realism draws (seed, slip draws, ...)
    shaft_angle: np.ndarray = None      # (T,) rad (an inner spall sits at centre + shaft angle)
    spin_ratio: float = 0.0             # omega_R / omega (a ball pit's spin angle: centre + ratio x shaft angle)
    ball_solver_stats: dict = None      # the chord method's counters (full_steps, rejected_steps,
                                        # worst_residual); None: every step solved in full



def _ball_record(model: DynamicModel, q, psi, phi, omega, iterations):
    def one(qq, ps, ph, w):
        op = eqx.tree_at(lambda o: o.speed, model.op, w)
        Ho, Hi = model.depths(ps, ph)
        st = bearing_force(model.bearing, op, model.curve, qq, ps, Ho, Hi, iterations, full_state=True)[1]
        return st.Q_inner, st.Q_outer, st.alpha_inner, st.alpha_outer

    return jax.vmap(one)(q, psi, phi, omega)


_ball_record_jit = jit(_ball_record)


def ball_records(model, rel, theta, phi, omega, iterations):
    """Per-sample ball loads and angles (Q_inner, Q_outer, alpha_inner, alpha_outer), each
    (T, Z): the lean solver at the recorded ring displacement ``rel`` (T, 3), cage angle, shaft
    angle and speed (T,), in chunks of :data:`CHUNK` (one compilation).  The fixed-step
    integrator records them in its time loop; this is for a run without them (the adaptive
    reference)."""
    T = rel.shape[0]
    tilts = np.broadcast_to(np.asarray(model.tilts), (CHUNK, 2))
    outs = []
    for k in range(0, T, CHUNK):
        n = min(CHUNK, T - k)
        pad = lambda a: np.concatenate([a[k:k + n], np.repeat(a[k + n - 1:k + n], CHUNK - n, axis=0)])
        q = np.concatenate([pad(rel), tilts], axis=1)
        psi = np.asarray(model.bearing.ball_azimuths(jnp.asarray(pad(theta))[:, None]))
        o = _ball_record_jit(model, jnp.asarray(q), jnp.asarray(psi), jnp.asarray(pad(phi)),
                             jnp.asarray(pad(omega)), iterations)
        outs.append([np.asarray(a)[:n] for a in o])
    return [np.concatenate(a) for a in zip(*outs)]


def _draw_from_key(key, Z, theta0, omega_c, omega0, duration, center, realism, n_knots):
    return draw_motion(jax.random.fold_in(key, MOTION_STREAM), Z, theta0, omega_c, omega0, duration, center,
                              realism, n_knots)


_draw_from_key_jit = jit(_draw_from_key, options=QUICK_COMPILE)     # once per simulation: -O0


def _motion_from_key(key, Z, theta0, omega_c, omega0, duration, center, realism, n_knots):
    wc = omega_c if np.isfinite(omega_c) and omega_c > 0 else 0.0
    if n_knots is None:
        n_knots = knot_count(Z, wc / (2 * np.pi), duration, realism.speed_fluctuation_percent / 100.0)
    return _draw_from_key_jit(np.asarray(key, np.uint32), Z, np.float64(theta0), np.float64(wc),
                              np.float64(omega0), float(duration), np.float64(center), motion_realism(realism),
                              int(n_knots))


def simulate(bearing, op: Operation, loads, spall: Spall | tuple | None = None,
             params: DynamicsParameters | None = None, duration=0.1, sample_rate=48000.0, *,
             theta0=0.0, realism: Realism | None = None, seed=0, hertz_method="exact",
             scheme="newmark", substeps="auto", ball_iterations="auto", record_balls=True,
             integrator="fixed", rtol=1e-8, atol=1e-8, sensor_coupling=False, progress=None,
             throw=True, ball_solver="chord", key=None, n_knots=None) -> DynamicsResult:
    """Time simulation of docs/model.md section 7 (the model: :mod:`bearingsim.dynamics.model`).

    ``loads`` [Fx, Fy, Fz, Mx, My] (N, N m), ``spall`` None (healthy), a :class:`Spall` on the
    outer or inner raceway or a ball, or a tuple of them (at t = 0: an inner spall then turns
    with the shaft, a ball pit with its ball), ``duration`` (s), ``sample_rate`` (Hz),
    ``theta0`` the cage angle at t = 0 (rad); ``realism`` (:class:`Realism`, seeded by
    ``seed``): slip, speed fluctuation, noise, and the pass-to-pass variability of a pit's
    impacts (:func:`finish_record`, the data set's signal stage, scaled by :func:`unbridged_of`; in the sensor path).  ``scheme`` "newmark" | "heun" | "rk4",
    ``substeps`` steps per sample (or "auto"), ``ball_iterations`` Newton steps per ball (or
    "auto": :func:`choose_ball_iterations`).  ``integrator="adaptive"``: the diffrax reference
    (``rtol``/``atol`` on displacements in um and velocities in mm/s; sensor modes in the ODE,
    with their reaction on the housing when ``sensor_coupling``).  ``record_balls``: per-sample
    ball loads and angles.  ``ball_solver``: "chord" (default; the Newmark scheme carries the
    balls' positions from step to step and solves them in full only at defect edges and where a
    chord step misses its tolerance, :func:`bearingsim.dynamics.bearing_force_chord`; its
    counters in ``result.ball_solver_stats``) or "full" (every step from the closed form).
    ``key``: a ``jax.random`` key (raw (2,) uint32): the motion is drawn from it as a data set
    chunk's program draws it (:func:`bearingsim.dynamics.draw_motion`, stream ``MOTION_STREAM``;
    ``n_knots`` the program's ``n_knots``, default the count this run needs), so one item of a
    chunk can be re-run alone; None: the key of item 0 of a data set seeded ``seed``
    (:func:`bearingsim.keys.item_keys`; issue 32 changed this random stream: a run's slip and
    speed fluctuation draws are JAX's, no longer NumPy's).
    ``progress``: a tqdm bar (default: duration >= 1 s).  Raises
    :class:`DynamicsError` when the run fails and ``throw`` (else check ``result.result``).
    """
    check_scheme(scheme)
    if ball_solver not in ("chord", "full"):
        raise InputError(f"ball_solver must be 'chord' or 'full', got {ball_solver!r}")
    if integrator not in ("fixed", "adaptive"):
        raise InputError(f"integrator must be 'fixed' or 'adaptive', got {integrator!r}")
    params = DynamicsParameters() if params is None else params
    realism = Realism() if realism is None else realism
    defects = as_defects(spall)
    loads = np.asarray(loads, np.float64)
    fs = float(sample_rate)
    ts = time_grid(duration, fs)
    T = ts.size
    curve = stiffness_curve(bearing, hertz_method)
    # the Newton count of the ball solve is a function of the quasi-static problem: a warm start
    # reads it (bearingsim.warm.memo) instead of loading and running the check's program
    check = ("ball_iterations", (bearing, op, loads, defects, float(theta0), hertz_method))
    known = warm.recall(*check) if ball_iterations == "auto" else None
    # the ball-step check's program compiles on another core while the quasi-static solve's does
    pre = precompile_ball_check(bearing, op, defects, curve, theta0) if ball_iterations == "auto" and known is None else None
    sol = solve(bearing, op, loads, cage_angle=theta0, spall=defects or None, hertz_method=hertz_method,
                throw=False)
    code = RESULTS.successful if succeeded(int(sol.result)) else RESULTS.initial_state
    u = 0.0
    if realism.pass_variation and defects:
        u, u_ok = unbridged_of(bearing, op, loads, defects, hertz_method)
        code = code if u_ok else (code or RESULTS.initial_state)
    freqs, a_m = characteristic_frequencies(bearing, op, sol)
    k_spin = spin_ratio(bearing, a_m)
    err = 0.0
    if pre is not None:
        pre.join()
    if ball_iterations == "auto":
        ball_iterations, err = known or warm.memo(*check, lambda: list(choose_ball_iterations(
            bearing, op, sol.displacement, defects, curve, theta0, spin_ratio=k_spin)))
        if ball_iterations == 0:
            ball_iterations = ITER_CHOICES[-1]
            code = code or RESULTS.ball_solver
    model = build_model(bearing, op, loads, defects, sol, params, curve, int(ball_iterations), k_spin)
    key = np.asarray(item_keys(seed, [0]))[0] if key is None else key
    Z = bearing.n_balls
    m = _motion_from_key(key, Z, theta0, float(sol.cage_speed), float(op.speed), ts[-1],
                         slip_reference(defects), realism, n_knots)
    st0 = np.stack([np.asarray(v) for v in run_motion_at(m, Z, np.zeros(1))], -1)[0]
    if substeps == "auto":
        lam = np.abs(linear_modes(model))
        substeps = choose_substeps(np.max(lam[np.isfinite(lam)], initial=0.0), fs)
    substeps = int(substeps)
    jumps = defect_edge_times(m, Z, rectangular(defects), ts[-1] + 1.0 / fs, k_spin)
    pass_times = defect_pass_times(m, Z, defects, ts[-1], k_spin)      # of the drawn motion only
    pre = None
    if integrator == "fixed" and code == RESULTS.successful:
        # the time loop's program compiles on another core while the equilibrium's does
        y_rest = np.concatenate([np.asarray(sol.displacement)[:3], np.zeros(7)])
        rec_like = np.zeros((RECORD_ROWS, bearing.n_balls)) if record_balls else None
        pre = precompile_fixed(model, y_rest, m, jumps, fs, scheme, substeps, rec_like, ball_solver)
        precompile_passes(T, pass_times, params.modes(), realism, fs, pre)
    y0, ok, dy0, rec0 = initial_state_jit(model, np.asarray(sol.displacement)[:3], st0)
    if not bool(ok):
        code = code or RESULTS.initial_equilibrium
    if pre is not None:
        pre.join()
    progress = (float(duration) >= 1.0) if progress is None else bool(progress)
    solver_stats = None
    if code == RESULTS.successful:
        recs = None
        if integrator == "fixed":
            y, ah, sens, nsteps, recs, solver_stats = run_fixed(model, y0, dy0, m, jumps, fs, T, scheme, substeps,
                                                                progress, rec0 if record_balls else None,
                                                                ball_solver)
        else:
            y, ah, sens, nsteps = run_adaptive(model, y0, m, ts, jumps, rtol, atol, sensor_coupling)
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(sens))):
            code = RESULTS.nonfinite
    else:
        y, ah, sens, nsteps = np.zeros((T, 10)), np.zeros((T, 2)), np.zeros(T), 0
    if throw and code != RESULTS.successful:
        q_code = int(sol.result)
        extra = f" (quasi-static: {sol.message()[0]}, result {q_code})" if q_code else ""
        hint = result_hint(q_code, loads, bearing=bearing) if q_code else code.hint
        raise DynamicsError(f"dynamic simulation failed: {code.message}{extra}", hint, code)
    theta, phi, omega = (np.asarray(v) for v in run_motion_at(m, Z, np.asarray(ts, np.float64)))
    rel = np.stack([y[:, 0] - y[:, 3], y[:, 1] - y[:, 4], y[:, 2]], axis=1)
    balls = [None] * 4
    if record_balls and code == RESULTS.successful:
        if integrator == "fixed":          # recorded in the time loop, from its own ball solves
            balls = list(record_loads_angles(recs))
        else:
            balls = ball_records(model, rel, theta, phi, omega, int(ball_iterations) + 1)
    labels = run_labels(m, realism, seed)
    labels["ball_solver_error"] = float(err)
    noise = np.zeros(T)
    if code == RESULTS.successful:
        sens, noise, more = finish_record(key, ah[:, 0], sens, pass_times, u, params.modes(), realism, fs)
        labels.update(more)
    return DynamicsResult(
        time=ts, cage_angle=theta, shaft_speed=omega, ring_displacement=rel,
        shaft_displacement=y[:, 0:3], housing_displacement=y[:, 3:5], housing_acceleration=ah,
        sensor_acceleration=sens + noise, noise=noise, Q_inner=balls[0], Q_outer=balls[1],
        alpha_inner=balls[2], alpha_outer=balls[3], result=int(code), num_steps=int(nsteps),
        frequencies=freqs, contact_angle=a_m, jump_times=jumps,
        pass_times=pass_times, quasi_static=sol,
        contact_damping=np.asarray(model.contact_damping), ball_iterations=int(ball_iterations),
        substeps=substeps, scheme=scheme, realism=labels, shaft_angle=phi, spin_ratio=k_spin,
        ball_solver_stats=solver_stats)
