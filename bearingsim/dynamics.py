"""Dynamic layer (MODEL.md section 7): shaft and housing driven by the Jones forces of the balls
as they roll over an outer-raceway spall; the sensor path applied exactly afterwards.

Model
-----
Degrees of freedom (10 states, SI): shaft / inner-ring translations ``x_s, y_s, z_s`` (mass
``m_s``), housing / outer-ring translations ``x_h, y_h`` (mass ``m_h``) on a support of stiffness
``k_h`` and damping ``c_h``, and their velocities::

    m_s a_s = F_ext + F_u(t) - R - C_b v_rel                        (x, y, z)
    m_h a_h = R_xy + (C_b v_rel)_xy - k_h x_h - c_h v_h              (x, y)

``R`` is the load the balls carry for the relative ring displacement ``q_rel = [x_s - x_h, y_s -
y_h, z_s, theta_x0, theta_y0]`` (tilts held at their quasi-static values) and the balls'
azimuths; ``v_rel = v_s - [v_h, 0]``; ``C_b = diag(2 zeta_b sqrt(K_ii m_s))`` with K the
quasi-static stiffness (contact damping); ``F_u = m_u e omega^2 [cos phi, sin phi, 0]`` an
optional unbalance turning with the shaft (angle phi).

The sensor path (one or more structural modes, :mod:`bearingsim.sensor`) is linear and one-way
coupled: it is applied exactly to the housing acceleration ``a_h,x`` on the integrator's step
grid (first-order-hold discretisation), not integrated, so it never limits the step.

Ball forces (the right-hand side's cost).  Each ball's 2x2 Jones equilibrium (centrifugal force,
gyroscopic moment, spall depth H) is solved from the omega = 0 closed form
(:func:`bearingsim.balls.static_ball_position`) by ``ball_iterations`` Newton steps with the
exact Jacobian of the transcendental-free :func:`bearingsim.balls.ball_state` (two forward-mode
directional derivatives, all element-wise over balls: XLA fuses them); the ball's loads on the
ring are linearised about the last iterate (their error is second order in the last step).
:func:`choose_ball_iterations` checks the count against :func:`bearingsim.balls.balls_at`
(exact) over one ball pitch, with the ring displaced +-5 %.  A ball over the spall without
inner contact is carried at the orbital speed of its undropped closed-form position.

Motion of the balls (:class:`Motion`).  The cage angle theta_c(t), shaft angle and shaft speed
are drawn once per run (seeded):

* speed fluctuation: omega(t) = omega_0 (1 + a s(t)), s a unit-RMS sum of 8 random-phase
  sinusoids with frequencies uniform in (0, B] (``speed_fluctuation_percent`` = 100 a,
  ``speed_fluctuation_bandwidth_Hz`` = B); the cage follows at the quasi-static ratio
  omega_c / omega_0;
* random slip: the cage advances one ball pitch (2 pi / Z) in (1 + eps_k) times its nominal
  time, eps_k ~ N(0, (slip_percent / 100)^2) independent per pitch; pitches start when a ball is
  at the spall centre, so successive ball passes over the spall are (1 + eps_k) T_BPFO apart
  (Randall & Antoni 2011: 1-2 %).  The cage angle is piecewise linear in the nominal progress;
  the phase is a random walk (the envelope's BPFO harmonics broaden as k^2).

Integration: fixed steps ``h = 1 / (substeps * sample_rate)`` in a ``lax.scan`` over chunks of
:data:`CHUNK` samples; the stage azimuths are precomputed per chunk (host, float64) and h is an
array, so no duration, sample rate or chunk recompiles.  The default scheme ``"newmark"``:
central difference in x, trapezoidal in v for the (linear) damping -- one bearing-force
evaluation per step, second order.  A ball crossing a rectangular spall edge inside a step
(times known in advance from the motion) is integrated exactly: the force step weights the
velocity update by where it falls (theta, 1 - theta instead of 1/2, 1/2) and the sensor modes
see a step at that instant (:func:`bearingsim.sensor.filter_update`), so an edge costs nothing
extra (no step rejection, no lax.cond: batches stay in lockstep).  ``"heun"``/``"rk4"`` are
explicit Runge-Kutta alternatives without edge handling (first order at rectangular edges).
The state at each step's start gives the outputs and the sensor filter's input at no extra
cost.  ``substeps="auto"``: the smallest count with |lambda| h <= 0.5 for every eigenvalue
lambda of the linearised shaft/housing model at t = 0 (1 for the CWRU case at 48 kHz).
``integrator="adaptive"``: the reference -- diffrax Tsit5 with a PID controller, the spall edges
as ``jump_ts``, and the sensor modes integrated in the ODE (optionally with their reaction on
the housing, ``sensor_coupling=True``, resonator mass ``m_r g_k`` per mode).

Initial state: the dynamic model's own equilibrium at t = 0 (Newton on the lean bearing force
from the quasi-static solution; the housing at its static support deflection), so a healthy
bearing starts exactly at rest.  A quasi-static state that did not converge, or an equilibrium
that cannot be found, is flagged in ``result`` (:class:`RESULTS`), never used silently.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from . import sensor as sensor_mod
from .balls import ball_state, balls_at, groove_centre_offsets, static_ball_position
from .defect import NO_SPALL, Spall, depth_profile
from .errors import InputError, NotConvergedError, ResultCode
from .hertz import stiffness_curve
from .jones import solve, solve_state
from .kinematics import Operation, ball_kinematics_cs, defect_frequencies

__all__ = [
    "RESULTS",
    "DynamicsError",
    "DynamicsParameters",
    "Realism",
    "Motion",
    "draw_motion",
    "motion_at",
    "DynamicsResult",
    "DynamicsBatchResult",
    "bearing_force",
    "choose_ball_iterations",
    "next_iterations",
    "choose_substeps",
    "simulate",
    "simulate_case",
    "simulate_batch",
    "spall_edge_times",
    "spall_pass_times",
    "characteristic_frequencies",
    "SCHEMES",
    "CHUNK",
]


class RESULTS(ResultCode):
    """Result codes of a dynamic simulation (``DynamicsResult.result``)."""

    successful = (0, "successful", "")
    nonfinite = (1, "the state became non-finite (the integration is unstable)",
                 "use more substeps (a smaller step than the fastest mode needs), or check the "
                 "structural parameters")
    initial_state = (2, "the quasi-static initial state did not converge or is not valid",
                     "check the loads and the spall (the quasi-static result code says why)")
    initial_equilibrium = (3, "the dynamic model's own equilibrium at t = 0 was not found from "
                           "the quasi-static state", "raise ball_iterations; report the case")
    ball_solver = (4, "the lean ball solver does not reach the required accuracy with at most "
                   "16 Newton steps", "pass ball_iterations explicitly, or report the case")


class DynamicsError(NotConvergedError):
    """A dynamic simulation failed (``code``: a :class:`RESULTS` member)."""


#: explicit Runge-Kutta schemes: (c, a, b)
SCHEMES = {
    "heun": ((0.0, 1.0), ((), (1.0,)), (0.5, 0.5)),
    "rk4": ((0.0, 0.5, 0.5, 1.0), ((), (0.5,), (0.0, 0.5), (0.0, 0.0, 1.0)),
            (1 / 6, 1 / 3, 1 / 3, 1 / 6)),
    # Newmark average acceleration in v / central difference in x (velocity Verlet with the
    # linear damping trapezoidal): second order, one bearing-force evaluation per step
    "newmark": ((0.0, 1.0), None, None),
}
#: samples per compiled chunk of the time loop
CHUNK = 1024
#: Newton step counts the lean ball solver is checked with (a ball dropping into a deep spall at
#: speed, capped at 2e-3 D per step, can need 16: the demo case)
_ITER_CHOICES = (1, 2, 3, 4, 8, 16)
_MAX_ITER = _ITER_CHOICES[-1]
#: ball loads vs balls_at, relative to the largest ball load: an error this size biases the
#: forces by ~1e-3, an order below the fixed step's error in the signal (1-2 %)
_ITER_TOL = 1e-3
_STEP_RHO = 0.5         # |lambda| h bound of substeps="auto"
_FLUCT_TERMS = 8


def _f64(x):
    return jnp.asarray(x, dtype=jnp.float64)


def _vec(x):
    return jnp.atleast_1d(jnp.asarray(x, dtype=jnp.float64))


class DynamicsParameters(eqx.Module):
    """Structural parameters (SI).  Defaults are those of the case schema ([dynamics]).

    The sensor modes are ``resonance_frequency`` (Hz), ``resonance_damping_ratio`` and
    ``resonance_gain``: scalars (one mode) or equal-length arrays (several modes).
    ``resonator_mass`` only enters the adaptive reference with ``sensor_coupling=True`` (the
    back-coupling the exact sensor filter neglects)."""

    shaft_mass: jnp.ndarray = eqx.field(converter=_f64, default=2.0)            # kg
    housing_mass: jnp.ndarray = eqx.field(converter=_f64, default=5.0)          # kg
    housing_stiffness: jnp.ndarray = eqx.field(converter=_f64, default=5e7)     # N/m
    housing_damping: jnp.ndarray = eqx.field(converter=_f64, default=2000.0)    # N s/m
    resonance_frequency: jnp.ndarray = eqx.field(converter=_vec, default=3000.0)  # Hz
    resonance_damping_ratio: jnp.ndarray = eqx.field(converter=_vec, default=0.05)
    resonance_gain: jnp.ndarray = eqx.field(converter=_vec, default=1.0)
    resonator_mass: jnp.ndarray = eqx.field(converter=_f64, default=0.05)       # kg
    contact_damping_ratio: jnp.ndarray = eqx.field(converter=_f64, default=0.05)
    unbalance: jnp.ndarray = eqx.field(converter=_f64, default=0.0)             # kg m

    def __check_init__(self):
        n = self.resonance_frequency.shape[-1]
        if self.resonance_damping_ratio.shape[-1] not in (1, n) or \
                self.resonance_gain.shape[-1] not in (1, n):
            raise InputError("resonance_damping_ratio and resonance_gain need one value per "
                             f"resonance frequency ({n})")

    def modes(self):
        """(frequencies, damping ratios, gains) broadcast to one shape (..., M)."""
        f = self.resonance_frequency
        return f, jnp.broadcast_to(self.resonance_damping_ratio, f.shape), \
            jnp.broadcast_to(self.resonance_gain, f.shape)

    @classmethod
    def from_settings(cls, d: dict) -> "DynamicsParameters":
        """From ``Case.dynamics_settings()`` (SI keys without unit suffix).  The list keys
        ``resonance_frequencies`` / ``resonance_damping_ratios`` / ``resonance_gains``, when
        present, override the single-mode ``resonance_frequency`` / ``resonance_damping_ratio``."""
        names = [f.name for f in cls.__dataclass_fields__.values()]
        kw = {k: d[k] for k in names if k in d}
        for key, name in (("resonance_frequencies", "resonance_frequency"),
                          ("resonance_damping_ratios", "resonance_damping_ratio"),
                          ("resonance_gains", "resonance_gain")):
            if d.get(key) is not None:
                kw[name] = d[key]
        return cls(**kw)


# ------------------------------------------------------------------------------ realism
class Realism(NamedTuple):
    """Seeded ingredients of real records (all off by default).  ``noise_rms`` in m/s^2 (the
    CWRU normal drive-end baseline is 0.07 g = 0.686 m/s^2); ``noise_band`` (lo, hi) Hz or None
    (white)."""

    slip_percent: float = 0.0
    speed_fluctuation_percent: float = 0.0
    speed_fluctuation_bandwidth_Hz: float = 5.0
    noise_rms: float = 0.0
    noise_band: tuple | None = None

    @classmethod
    def from_settings(cls, d: dict) -> "Realism":
        """From ``Case.dynamics_settings()`` (missing keys: off)."""
        band = d.get("noise_band")
        return cls(float(d.get("slip_percent", 0.0)), float(d.get("speed_fluctuation_percent", 0.0)),
                   float(d.get("speed_fluctuation_bandwidth", 5.0)), float(d.get("noise_rms", 0.0)),
                   None if band is None else tuple(float(v) for v in band))


class Motion(NamedTuple):
    """One run's drawn cage and shaft motion (host arrays; see the module docstring)."""

    theta0: float               # cage angle at t = 0 (rad)
    omega_c: float              # nominal cage speed (rad/s)
    omega0: float               # nominal shaft speed (rad/s)
    Z: int
    fluct: float                # RMS speed fluctuation (fraction)
    fluct_freqs: np.ndarray     # (K,) Hz
    fluct_phases: np.ndarray    # (K,) rad
    knots_u: np.ndarray         # nominal progress (ball pitches) at the slip knots
    knots_p: np.ndarray         # actual progress at the slip knots
    slip_draws: np.ndarray      # eps_k of the pitches within the run
    seed: int


def _seeds(seed):
    ss = np.random.SeedSequence(int(seed))
    return [np.random.default_rng(s) for s in ss.spawn(4)]     # slip+, slip-, speed, noise


def draw_motion(seed, Z, theta0, omega_c, omega0, duration, spall_center=0.0,
                realism: Realism = Realism()) -> Motion:
    """Draw the cage and shaft motion of one run (reproducible from ``seed``; a longer run with
    the same seed starts with the same draws)."""
    r_fwd, r_bwd, r_speed, _ = _seeds(seed)
    a = float(realism.speed_fluctuation_percent) / 100.0
    if a > 0.0:
        K = _FLUCT_TERMS
        f = r_speed.uniform(0.0, 1.0, K) * float(realism.speed_fluctuation_bandwidth_Hz)
        f = np.maximum(f, 1e-3)
        ph = r_speed.uniform(0.0, 2 * np.pi, K)
    else:
        f, ph = np.ones(1), np.zeros(1)
    m = Motion(float(theta0), float(omega_c), float(omega0), int(Z), a, f, ph,
               np.array([-1e12, 1e12]), np.array([-1e12, 1e12]), np.zeros(0), int(seed))
    sigma = float(realism.slip_percent) / 100.0
    if sigma <= 0.0 or omega_c <= 0.0:
        return m
    p0 = Z * float(spall_center) / (2 * np.pi)
    tt = np.linspace(0.0, float(duration), 257)
    u = _progress(m, tt, np)
    lo, hi = float(u.min()) - 2.0, float(u.max()) + 2.0

    def walk(rng, limit, sign):
        steps = []
        total = 0.0
        while total < limit:
            e = np.clip(rng.standard_normal(64) * sigma, -0.5, 0.5)
            steps.append(e)
            total += float(np.sum(1.0 + e))
        e = np.concatenate(steps)
        return e, sign * np.cumsum(1.0 + e)

    e_f, U_f = walk(r_fwd, max(hi - p0, 0.0) + 2.0, 1.0)
    e_b, U_b = walk(r_bwd, max(p0 - lo, 0.0) + 2.0, -1.0)
    ku = np.concatenate([p0 + U_b[::-1], [p0], p0 + U_f])
    kp = np.concatenate([p0 - np.arange(len(U_b), 0, -1), [p0], p0 + np.arange(1, len(U_f) + 1)])
    inside = (ku[1:] > lo) & (ku[:-1] < hi)
    eps = np.concatenate([e_b[::-1], e_f])[inside]
    return m._replace(knots_u=ku, knots_p=kp.astype(float), slip_draws=eps)


def _fluct(m: Motion, t, xp):
    """(s(t), integral of s from 0 to t) of the unit-RMS fluctuation."""
    if m.fluct == 0.0:
        z = xp.zeros_like(t)
        return z, z
    f = xp.asarray(m.fluct_freqs)
    ph = xp.asarray(m.fluct_phases)
    arg = 2 * np.pi * f * t[..., None] + ph
    c = math.sqrt(2.0 / len(m.fluct_freqs))
    s = c * xp.sum(xp.cos(arg), axis=-1)
    S = c * xp.sum((xp.sin(arg) - xp.sin(ph)) / (2 * np.pi * f), axis=-1)
    return s, S


def _progress(m: Motion, t, xp):
    """Nominal cage progress u(t) in ball pitches (no slip)."""
    _, S = _fluct(m, t, xp)
    return m.Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))


def motion_at(m: Motion, t, xp=np):
    """(cage angle, shaft angle, shaft speed) at times t (``xp``: numpy or jax.numpy)."""
    s, S = _fluct(m, t, xp)
    u = m.Z / (2 * np.pi) * (m.theta0 + m.omega_c * (t + m.fluct * S))
    p = xp.interp(u, xp.asarray(m.knots_u), xp.asarray(m.knots_p))
    return 2 * np.pi / m.Z * p, m.omega0 * (t + m.fluct * S), m.omega0 * (1.0 + m.fluct * s)


def _times_at_angle(m: Motion, angle, duration):
    """Times in [0, duration] at which some ball is at azimuth ``angle`` (sorted)."""
    if m.omega_c <= 0.0:
        return np.zeros(0)
    tt = np.linspace(0.0, float(duration), max(2049, int(duration * 20000)))
    th = motion_at(m, tt)[0]
    pitch = 2 * np.pi / m.Z
    k0 = np.ceil((th[0] - angle) / pitch)
    k1 = np.floor((th[-1] - angle) / pitch)
    targets = angle + pitch * np.arange(k0, k1 + 1)
    return np.interp(targets, th, tt)


def spall_edge_times(m: Motion, spall, duration):
    """Times (s) within [0, duration] at which a ball enters or leaves the spall."""
    if spall is None or float(spall.depth) <= 0.0:
        return np.zeros(0)
    lo, hi = (float(e) for e in spall.edges())
    return np.unique(np.concatenate([_times_at_angle(m, lo, duration),
                                     _times_at_angle(m, hi, duration)]))


def spall_pass_times(m: Motion, spall, duration):
    """Times (s) within [0, duration] at which a ball centre passes the spall centre."""
    if spall is None or float(spall.depth) <= 0.0:
        return np.zeros(0)
    return _times_at_angle(m, float(spall.center), duration)


def _motion_labels(m: Motion, realism: Realism) -> dict:
    eps = np.asarray(m.slip_draws)
    return dict(seed=int(m.seed), slip_percent=float(realism.slip_percent),
                slip_draws=eps, pass_jitter_percent=float(100.0 * eps.std()) if eps.size > 1 else 0.0,
                speed_fluctuation_percent=float(realism.speed_fluctuation_percent),
                speed_fluctuation_bandwidth_Hz=float(realism.speed_fluctuation_bandwidth_Hz),
                speed_fluctuation_frequencies_Hz=np.asarray(m.fluct_freqs) if m.fluct else np.zeros(0),
                noise_rms=float(realism.noise_rms),
                noise_band=(np.asarray(realism.noise_band, float) if realism.noise_band else np.zeros(0)))


# --------------------------------------------------------------------------- ball forces
def bearing_force(bearing, op: Operation, curve, q, psi, H_outer, iterations=1, full_state=False):
    """Load [Fx, Fy, Fz] (N) the balls carry at ring displacement q (5,) and azimuths psi (Z,),
    each ball solved from the omega = 0 closed form by ``iterations`` Newton steps (exact
    Jacobian), its loads linearised about the last iterate.  Element-wise over balls (and any
    leading batch axes of psi / H_outer); transcendental-free apart from the azimuths'
    sine and cosine.  Also returns the balls' (G, H) loads on the ring (``full_state``: their
    :class:`bearingsim.balls.BallState` at the last iterate instead)."""
    A1, A2 = groove_centre_offsets(bearing, q, psi)
    L = jnp.sqrt(A1 * A1 + A2 * A2)
    s, c = A1 / L, A2 / L
    # undropped closed-form orbital speed: collinear contacts along (A1, A2)
    ws = ball_kinematics_cs(bearing, op, s, c, s, c)[2]
    x0, _ = static_ball_position(bearing, op, A1, A2, curve, H_outer, 0.0)
    X1, X2 = x0[0], x0[1]

    def f(X1, X2):
        st = ball_state(bearing, op, (X1, X2), A1, A2, curve, H_outer, 0.0, ws)
        return st.r_axial, st.r_radial, st.ball_G, st.ball_H

    one, zero = jnp.ones_like(X1), jnp.zeros_like(X1)
    cap = 2e-3 * bearing.ball_diameter

    def newton(_, c):
        X1, X2 = c[0] + c[8], c[1] + c[9]         # the previous iterate's step
        (r1, r2, G, H), (a11, a21, g1, h1) = jax.jvp(f, (X1, X2), (one, zero))
        _, (a12, a22, g2, h2) = jax.jvp(f, (X1, X2), (zero, one))
        # regularised 2x2 solve (a ball out of contact at rest: J = 0, r = 0, zero step)
        sc = jnp.maximum(jnp.maximum(jnp.abs(a11), jnp.abs(a12)), jnp.maximum(jnp.abs(a21), jnp.abs(a22)))
        mu = 1e-13 * sc + 1e-300
        b11, b22 = a11 + mu, a22 + mu
        det = b11 * b22 - a12 * a21
        det = jnp.where(jnp.abs(det) > 1e-300, det, 1e-300)
        d1 = -(b22 * r1 - a12 * r2) / det
        d2 = -(b11 * r2 - a21 * r1) / det
        n = jnp.maximum(jnp.abs(d1), jnp.abs(d2))
        k = jnp.where(n > cap, cap / jnp.where(n > 0, n, 1.0), 1.0)
        ok = jnp.isfinite(d1) & jnp.isfinite(d2)
        d1, d2 = jnp.where(ok, d1 * k, 0.0), jnp.where(ok, d2 * k, 0.0)
        return (X1, X2, G, H, g1, g2, h1, h2, d1, d2)

    init = (X1, X2) + (zero,) * 8
    X1, X2, G, H, g1, g2, h1, h2, d1, d2 = lax.fori_loop(0, max(int(iterations), 1), newton, init)
    X1, X2 = X1 + d1, X2 + d2
    G = G + g1 * d1 + g2 * d2
    H = H + h1 * d1 + h2 * d2
    cp, sp = jnp.cos(psi), jnp.sin(psi)
    R = jnp.stack([jnp.sum(H * cp, -1), jnp.sum(H * sp, -1), jnp.sum(G, -1)], -1)
    if full_state:
        return R, ball_state(bearing, op, (X1, X2), A1, A2, curve, H_outer, 0.0, ws)
    return R, G, H


def _depths(bearing, spall, psi):
    return depth_profile(bearing, NO_SPALL if spall is None else spall, psi)


def _ball_errors(bearing, op, q, spall, curve, angles, scales):
    """Max over cage angles x displacement scalings of the lean ball loads' error (vs
    balls_at), relative to the largest ball load, for each of _ITER_CHOICES Newton steps."""
    def at(th, s):
        qq = q * s
        psi = bearing.ball_azimuths(th)
        H = _depths(bearing, spall, psi)
        ref = balls_at(bearing, op, qq, psi, curve, H_outer=H)
        scale = jnp.maximum(jnp.max(ref.Q_outer), jnp.max(ref.Q_inner)) + 1e-30
        errs = []
        for n in _ITER_CHOICES:
            _, G, Hh = bearing_force(bearing, op, curve, qq, psi, H, n)
            errs.append(jnp.maximum(jnp.max(jnp.abs(G - ref.ball_G)), jnp.max(jnp.abs(Hh - ref.ball_H))))
        return jnp.stack(errs) / scale

    return jnp.max(jax.vmap(lambda th: jax.vmap(lambda s: at(th, s))(scales))(angles), axis=(0, 1))


_ball_errors_jit = eqx.filter_jit(_ball_errors)


def next_iterations(its):
    """A batch's Newton step count: one choice above the largest checked item's (its: counts)."""
    top = max(its, default=_ITER_CHOICES[-2])
    return _ITER_CHOICES[min(_ITER_CHOICES.index(top) + 1, len(_ITER_CHOICES) - 1)]


def choose_ball_iterations(bearing, op, q, spall, curve, theta0=0.0, tol=_ITER_TOL):
    """Smallest number of Newton steps (of 1, 2, 3, 4, 8, 16) whose ball loads match ``balls.balls_at`` to
    ``tol`` (relative to the largest ball load) over one ball pitch of cage angles (and with a
    ball over the spall centre), the ring displacement q scaled by 0.95, 1, 1.05.  Returns
    (count, error); count 0 when none does."""
    Z = bearing.n_balls
    angles = float(theta0) + np.linspace(0.0, 2 * np.pi / Z, 12, endpoint=False)
    if spall is not None and float(spall.depth) > 0:
        c, e = float(spall.center), float(spall.extent)
        angles = np.concatenate([angles, [c, c - 0.4 * e, c + 0.4 * e]])
    errs = np.asarray(_ball_errors_jit(bearing, op, jnp.asarray(q), spall, curve, jnp.asarray(angles),
                                       jnp.array([0.95, 1.0, 1.05])))
    ok = np.flatnonzero(errs <= tol)
    return (_ITER_CHOICES[int(ok[0])], float(errs[ok[0]])) if ok.size else (0, float(errs.min()))


# -------------------------------------------------------------------------------- model
class DynamicModel(eqx.Module):
    """Everything the right-hand side needs (every array may carry a batch axis under vmap)."""

    bearing: object
    op: Operation
    spall: Spall
    curve: object
    loads: jnp.ndarray          # (5,) applied [Fx, Fy, Fz, Mx, My]
    tilts: jnp.ndarray          # (2,) quasi-static tilts held constant (rad)
    contact_damping: jnp.ndarray  # (3,) c_b in x, y, axial (N s/m)
    params: DynamicsParameters
    iterations: int = eqx.field(static=True, default=1)

    def ring_load(self, xrel, theta, omega):
        psi = self.bearing.ball_azimuths(theta)
        q = jnp.concatenate([xrel, self.tilts])
        op = eqx.tree_at(lambda o: o.speed, self.op, omega)
        H = depth_profile(self.bearing, self.spall, psi)
        return bearing_force(self.bearing, op, self.curve, q, psi, H, self.iterations)[0]

    def masses(self):
        """(5,) masses of [x_s, y_s, z_s, x_h, y_h]."""
        p = self.params
        return jnp.stack([p.shaft_mass] * 3 + [p.housing_mass] * 2)

    def damping_matrix(self):
        """(5, 5) linear damping: contact damping C_b on v_rel and the support damping c_h."""
        cb, ch = self.contact_damping, self.params.housing_damping
        C = jnp.zeros((5, 5)).at[jnp.arange(3), jnp.arange(3)].set(cb)
        C = C.at[0, 3].set(-cb[0]).at[1, 4].set(-cb[1]).at[3, 0].set(-cb[0]).at[4, 1].set(-cb[1])
        return C.at[3, 3].set(cb[0] + ch).at[4, 4].set(cb[1] + ch)

    def forces(self, x, stage, extra_x=0.0):
        """(5,) position- and time-dependent forces on [shaft (3), housing (2)]: applied loads,
        unbalance, bearing load R, support spring; ``extra_x`` adds to the housing along x.
        stage = (cage angle, shaft angle, shaft speed)."""
        p = self.params
        th, ph, w = stage[0], stage[1], stage[2]
        R = self.ring_load(jnp.stack([x[0] - x[3], x[1] - x[4], x[2]]), th, w)
        Fu = p.unbalance * w * w * jnp.stack([jnp.cos(ph), jnp.sin(ph), jnp.zeros_like(ph)])
        Fs = self.loads[:3] + Fu - R
        Fh = R[:2] - p.housing_stiffness * x[3:5] + jnp.stack([extra_x, 0.0 * extra_x])
        return jnp.concatenate([Fs, Fh])

    def rhs(self, y, stage, extra_x=0.0):
        """dy/dt for y = [x_s (3), x_h (2), v_s (3), v_h (2)]."""
        x, v = y[:5], y[5:]
        a = (self.forces(x, stage, extra_x) - self.damping_matrix() @ v) / self.masses()
        return jnp.concatenate([v, a])


def build_model(bearing, op, loads, spall, sol, params: DynamicsParameters, curve, iterations):
    """DynamicModel and the quasi-static initial state y0 (housing at its static deflection)."""
    q = sol.displacement
    K = jnp.diagonal(sol.stiffness, axis1=-2, axis2=-1)[..., :3]
    cb = 2.0 * params.contact_damping_ratio[..., None] * jnp.sqrt(
        jnp.maximum(K, 0.0) * params.shaft_mass[..., None])
    loads = jnp.asarray(loads, jnp.float64)
    model = DynamicModel(bearing, op, NO_SPALL if spall is None else spall, curve, loads, q[..., 3:5],
                         cb, params, int(iterations))
    return model


def _initial_state(model: DynamicModel, q_rel0, stage0):
    """Equilibrium of the lean model at t = 0 from the quasi-static displacement (3 Newton
    steps on the 3 translations): (y0, converged)."""
    F = model.loads[:3]

    def res(x):
        return model.ring_load(x, stage0[0], stage0[2]) - F

    def newton(_, x):
        J, r = jax.jacfwd(lambda v: (lambda rr: (rr, rr))(res(v)), has_aux=True)(x)
        dx = -jnp.linalg.solve(J + 1e-12 * jnp.max(jnp.abs(J)) * jnp.eye(3), r)
        return x + jnp.where(jnp.all(jnp.isfinite(dx)), dx, 0.0)

    x = lax.fori_loop(0, 4, newton, q_rel0)
    r = res(x)
    scale = jnp.max(jnp.abs(F)) + 1.0
    ok = jnp.all(jnp.isfinite(x)) & (jnp.max(jnp.abs(r)) <= 1e-9 * scale)
    xh = model.loads[:2] / model.params.housing_stiffness
    y0 = jnp.concatenate([x[:2] + xh, x[2:3], xh, jnp.zeros(5)])
    return y0, ok


_initial_state_jit = eqx.filter_jit(_initial_state)


def _linear_modes(model: DynamicModel, y0, stage0):
    """Eigenvalues of the linearised shaft/housing model at y0 (rad/s, complex)."""
    J = jax.jacfwd(lambda y: model.rhs(y, stage0))(y0)
    return jnp.linalg.eigvals(J)


_linear_modes_jit = eqx.filter_jit(_linear_modes)


def choose_substeps(lam_max, sample_rate, rho=_STEP_RHO):
    """Smallest number of steps per sample with |lambda|_max h <= rho."""
    return max(1, int(math.ceil(float(lam_max) / (rho * float(sample_rate)))))


# --------------------------------------------------------------------------- integration
def _advance(model: DynamicModel, carry, stages, jumps, h, flt, scheme: str):
    """Advance over a chunk: ``stages`` (N, S, n_c, 3) motion at the non-zero stage points of
    every step, ``jumps`` (N, S) the fraction of the step at which a ball crosses a rectangular
    spall edge (-1: none).  carry = (y, dy, s): state, its derivative, sensor-mode states.
    Returns the new carry and per sample (y, a_h (2), sensor) at the sample instant."""
    c, a, b = SCHEMES[scheme]
    cs = sorted(set(c) - {0.0})
    idx = [None if ci == 0.0 else cs.index(ci) for ci in c]
    last = cs.index(1.0)
    if scheme == "newmark":
        mass = model.masses()
        MC = model.damping_matrix() / mass[:, None]
        P = jnp.linalg.inv(jnp.eye(5) + 0.5 * h * MC)

    def step(carry, st, th):
        y, k1, s = carry
        if scheme == "newmark":
            # x: central difference; v: the damping trapezoidal (implicit, linear), the forces
            # weighted by where they jump (a step at theta h: weights theta, 1 - theta; none:
            # 1/2, 1/2) -- one bearing-force evaluation per step
            x, v, acc = y[:5], y[5:], k1[5:]
            F0 = acc + MC @ v
            wgt = jnp.where(th >= 0.0, th, 0.5)
            x1 = x + h * v + 0.5 * h * h * acc
            F1 = model.forces(x1, st[last]) / mass
            v1 = P @ (v - 0.5 * h * (MC @ v) + h * (wgt * F0 + (1.0 - wgt) * F1))
            acc1 = F1 - MC @ v1
            y1, k1n = jnp.concatenate([x1, v1]), jnp.concatenate([v1, acc1])
            s = sensor_mod.filter_update(flt, s, k1[8], k1n[8], th, h)
        else:
            ks = [k1]
            for i in range(1, len(c)):
                yi = y + h * sum(a[i][j] * ks[j] for j in range(i) if a[i][j] != 0.0)
                ks.append(model.rhs(yi, st[idx[i]]))
            y1 = y + h * sum(bi * ki for bi, ki in zip(b, ks))
            k1n = model.rhs(y1, st[last])
            s = sensor_mod.filter_update(flt, s, k1[8], k1n[8])
        return (y1, k1n, s), None

    def sample(carry, xs):
        st_sample, th_sample = xs
        y, k1, s = carry
        out = (y, k1[8:10], sensor_mod.filter_output(flt, s, k1[8]))
        for j in range(st_sample.shape[0]):         # substeps: a static, small count
            carry, _ = step(carry, st_sample[j], th_sample[j])
        return carry, out

    return lax.scan(sample, carry, (stages, jumps))


_advance_jit = eqx.filter_jit(_advance)


def _advance_batch(model, carry, stages, jumps, h, flt, scheme):
    return jax.vmap(lambda m, cr, st, jp, hh, fl: _advance(m, cr, st, jp, hh, fl, scheme))(
        model, carry, stages, jumps, h, flt)


_advance_batch_jit = eqx.filter_jit(_advance_batch)


_filter_jit = jax.jit(sensor_mod.sensor_filter)
_filter_batch_jit = jax.jit(jax.vmap(sensor_mod.sensor_filter, in_axes=(0, 0, 0, None)))
_rhs_jit = eqx.filter_jit(lambda model, y, st: model.rhs(y, st))
_rhs_batch_jit = eqx.filter_jit(jax.vmap(lambda model, y, st: model.rhs(y, st)))


def _stage_grid(scheme, substeps):
    c = SCHEMES[scheme][0]
    cs = np.array(sorted(set(c) - {0.0}))
    j = np.arange(substeps)
    return (j[:, None] + cs[None, :]) / substeps          # (S, n_c) in samples


def _chunk_jumps(edges, k0, n, substeps, h):
    """(n, S) fraction of each step at which a spall edge is crossed (-1: none)."""
    steps = (np.arange(k0, k0 + n)[:, None] * substeps + np.arange(substeps)[None, :]).astype(float)
    out = np.full(steps.shape, -1.0)
    if len(edges):
        t0 = steps * h
        i = np.searchsorted(edges, t0.ravel(), side="left").reshape(steps.shape)
        ok = i < len(edges)
        te = np.where(ok, np.asarray(edges)[np.minimum(i, len(edges) - 1)], np.inf)
        frac = (te - t0) / h
        out = np.where(ok & (frac < 1.0), frac, -1.0)
    return out


def _chunk_stages(m: Motion, grid, k0, n, fs):
    """Motion at the stage points of samples k0..k0+n-1: (n, S, n_c, 3)."""
    t = (np.arange(k0, k0 + n, dtype=float)[:, None, None] + grid[None]) / fs
    return np.stack(motion_at(m, t), axis=-1)


def _time_grid(duration, sample_rate):
    n = int(round(float(duration) * float(sample_rate)))
    if n < 2:
        raise InputError(f"duration {duration} s at {sample_rate} Hz gives {n} samples; need at least 2")
    return np.arange(n) / float(sample_rate)


def _run_fixed(model, y0, motions, edges, fs, T, scheme, substeps, batch, progress):
    """Chunked fixed-step integration of one model (batch=False) or a batch (motions and the
    rectangular spall edge times ``edges`` lists).  Returns host arrays y (.., T, 10),
    a_h (.., T, 2), sensor (.., T) and the number of steps."""
    h = 1.0 / (substeps * fs)
    grid = _stage_grid(scheme, substeps)
    f, z, g = model.params.modes()
    flt = (_filter_batch_jit if batch else _filter_jit)(f, z, g, jnp.float64(h))
    ms = motions if batch else [motions]
    es = edges if batch else [edges]
    st0 = np.stack([np.stack(motion_at(m, np.zeros(1)), -1)[0] for m in ms])
    k10 = (_rhs_batch_jit if batch else _rhs_jit)(model, y0, jnp.asarray(st0 if batch else st0[0]))
    carry = (y0, k10, jnp.zeros(f.shape + (2,)))
    outs = []
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=T, desc="simulate", unit="sample", unit_scale=True, dynamic_ncols=True)
    for k0 in range(0, T, CHUNK):
        stg = np.stack([_chunk_stages(m, grid, k0, CHUNK, fs) for m in ms])
        jmp = np.stack([_chunk_jumps(e, k0, CHUNK, substeps, h) for e in es])
        if batch:
            carry, out = _advance_batch_jit(model, carry, jnp.asarray(stg), jnp.asarray(jmp),
                                            jnp.full(len(ms), h), flt, scheme)
        else:
            carry, out = _advance_jit(model, carry, jnp.asarray(stg[0]), jnp.asarray(jmp[0]),
                                      jnp.float64(h), flt, scheme)
        n = min(CHUNK, T - k0)
        outs.append(jax.tree_util.tree_map(lambda a: np.asarray(a)[..., :n, :] if a.ndim > (1 + batch)
                                           else np.asarray(a)[..., :n], out))
        if bar is not None:
            bar.update(n)
    if bar is not None:
        bar.close()
    y = np.concatenate([o[0] for o in outs], axis=-2)
    ah = np.concatenate([o[1] for o in outs], axis=-2)
    sens = np.concatenate([o[2] for o in outs], axis=-1)
    return y, ah, sens, T * substeps


def _run_adaptive(model, y0, m: Motion, ts, jumps, rtol, atol, coupling):
    """Reference: diffrax Tsit5 + PID (+ spall edges as jump_ts), sensor modes in the ODE."""
    import diffrax

    f, z, g = (np.asarray(v) for v in model.params.modes())
    w = 2 * np.pi * jnp.asarray(f)
    zz, gg = jnp.asarray(z), jnp.asarray(g)
    mr = model.params.resonator_mass * gg if coupling else jnp.zeros_like(gg)
    M = len(f)
    mj = jax.tree_util.tree_map(lambda a: jnp.asarray(a) if isinstance(a, np.ndarray) else a, m)
    scale = jnp.concatenate([jnp.full(5, 1e-6), jnp.full(5, 1e-3), jnp.full(M, 1e-9), jnp.full(M, 1e-6)])

    def full(t, u):
        y = u * scale
        st = jnp.stack(motion_at(mj, t, jnp))
        zk, vk = y[10:10 + M], y[10 + M:]
        Fk = mr * (w * w * zk + 2 * zz * w * vk)
        dy = model.rhs(y[:10], st, jnp.sum(Fk))
        ah = dy[8]
        ak = -2 * zz * w * vk - w * w * zk - ah
        return jnp.concatenate([dy, vk, ak]), ah, ak

    term = diffrax.ODETerm(lambda t, u, args: full(t, u)[0] / scale)
    ctrl = diffrax.PIDController(rtol=rtol, atol=atol, pcoeff=0.2, icoeff=0.4)
    if len(jumps):
        ctrl = diffrax.ClipStepSizeController(ctrl, jump_ts=jnp.asarray(jumps))
    u0 = jnp.concatenate([y0, jnp.zeros(2 * M)]) / scale
    sol = diffrax.diffeqsolve(term, diffrax.Tsit5(), ts[0], ts[-1], None, u0,
                              saveat=diffrax.SaveAt(ts=jnp.asarray(ts)), stepsize_controller=ctrl,
                              max_steps=1 << 24, throw=False)
    us = sol.ys

    def post(t, u):
        du, ah, ak = full(t, u)
        return u[:10] * scale[:10], du[8:10], ah + jnp.sum(gg * ak)

    y, ah, sens = jax.jit(jax.vmap(post))(jnp.asarray(ts), us)
    return np.asarray(y), np.asarray(ah), np.asarray(sens), int(sol.stats["num_steps"])


# ------------------------------------------------------------------------------- results
def characteristic_frequencies(bearing, op, sol):
    """Defect frequencies (Hz) at the operating point: shaft = n/60; FTF = omega_c / 2 pi from
    the quasi-static cage speed, BPFO = Z FTF; BPFI and BSF (once per ball revolution) from the
    MODEL.md section 8 formulas at the mean loaded contact angle (mean of (alpha_i + alpha_o)/2
    over the balls with Q_i > 1 % of the largest).  Returns (dict, contact angle in rad)."""
    Qi = np.asarray(sol.Q_inner)
    loaded = Qi > 0.01 * Qi.max() if Qi.max() > 0 else np.ones_like(Qi, bool)
    alpha = 0.5 * (np.asarray(sol.alpha_inner) + np.asarray(sol.alpha_outer))
    a_m = float(np.mean(alpha[loaded]))
    shaft = float(op.speed) / (2 * np.pi)
    f = defect_frequencies(bearing, shaft, a_m)
    ftf = float(sol.cage_speed) / (2 * np.pi)
    return dict(shaft_Hz=shaft, ftf_Hz=ftf, bpfo_Hz=bearing.n_balls * ftf, bpfi_Hz=float(f.bpfi),
                bsf_Hz=float(f.bsf)), a_m


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
    frequencies: dict                   # shaft/ftf/bpfo/bpfi/bsf in Hz (nominal speed)
    contact_angle: float                # rad, mean loaded contact angle (quasi-static)
    jump_times: np.ndarray              # spall entry/exit times (s)
    pass_times: np.ndarray              # times a ball centre passes the spall centre (s)
    quasi_static: object                # JonesSolution at t = 0
    contact_damping: np.ndarray         # (3,) N s/m
    ball_iterations: int
    substeps: int
    scheme: str
    realism: dict                       # labels of the realism draws (seed, slip draws, ...)


def _ball_record(model: DynamicModel, q, psi, omega, iterations):
    def one(qq, ps, w):
        op = eqx.tree_at(lambda o: o.speed, model.op, w)
        H = depth_profile(model.bearing, model.spall, ps)
        st = bearing_force(model.bearing, op, model.curve, qq, ps, H, iterations, full_state=True)[1]
        return st.Q_inner, st.Q_outer, st.alpha_inner, st.alpha_outer

    return jax.vmap(one)(q, psi, omega)


_ball_record_jit = eqx.filter_jit(_ball_record)


def _record_balls(model, rel, theta, omega, iterations):
    """Per-sample ball loads and angles (the lean solver with one more Newton step, at the
    iterate), in chunks."""
    T = rel.shape[0]
    tilts = np.broadcast_to(np.asarray(model.tilts), (CHUNK, 2))
    outs = []
    for k in range(0, T, CHUNK):
        n = min(CHUNK, T - k)
        pad = lambda a: np.concatenate([a[k:k + n], np.repeat(a[k + n - 1:k + n], CHUNK - n, axis=0)])
        q = np.concatenate([pad(rel), tilts], axis=1)
        psi = np.asarray(model.bearing.ball_azimuths(jnp.asarray(pad(theta))[:, None]))
        o = _ball_record_jit(model, jnp.asarray(q), jnp.asarray(psi), jnp.asarray(pad(omega)), iterations)
        outs.append([np.asarray(a)[:n] for a in o])
    return [np.concatenate(a) for a in zip(*outs)]


def _check_scheme(scheme):
    if scheme not in SCHEMES:
        raise InputError(f"scheme must be one of {sorted(SCHEMES)}, got {scheme!r}")


def simulate(bearing, op: Operation, loads, spall: Spall | None = None,
             params: DynamicsParameters | None = None, duration=0.1, sample_rate=48000.0, *,
             theta0=0.0, realism: Realism | None = None, seed=0, hertz_method="exact",
             scheme="newmark", substeps="auto", ball_iterations="auto", record_balls=True,
             integrator="fixed", rtol=1e-8, atol=1e-8, sensor_coupling=False, progress=None,
             throw=True) -> DynamicsResult:
    """Time simulation of MODEL.md section 7 (see the module docstring for the model).

    ``loads`` [Fx, Fy, Fz, Mx, My] (N, N m), ``duration`` (s), ``sample_rate`` (Hz), ``theta0``
    the cage angle at t = 0 (rad); ``realism`` (:class:`Realism`, seeded by ``seed``): slip,
    speed fluctuation, noise.  ``scheme`` "heun" | "rk4", ``substeps`` steps per sample (or
    "auto"), ``ball_iterations`` Newton steps per ball (or "auto": :func:`choose_ball_iterations`).
    ``integrator="adaptive"``: the diffrax reference (``rtol``/``atol`` on displacements in um
    and velocities in mm/s; sensor modes in the ODE, with their reaction on the housing when
    ``sensor_coupling``).  ``record_balls``: per-sample ball loads and angles.  ``progress``: a
    tqdm bar (default: duration >= 1 s).  Raises :class:`DynamicsError` when the run fails and
    ``throw`` (else check ``result.result``).
    """
    _check_scheme(scheme)
    params = DynamicsParameters() if params is None else params
    realism = Realism() if realism is None else realism
    loads = jnp.asarray(loads, jnp.float64)
    fs = float(sample_rate)
    ts = _time_grid(duration, fs)
    T = ts.size
    curve = stiffness_curve(bearing, hertz_method)
    sol = solve(bearing, op, loads, cage_angle=theta0, spall=spall, hertz_method=hertz_method,
                throw=False)
    code = RESULTS.successful if int(sol.result) == 0 else RESULTS.initial_state
    err = 0.0
    if ball_iterations == "auto":
        ball_iterations, err = choose_ball_iterations(bearing, op, sol.displacement, spall, curve, theta0)
        if ball_iterations == 0:
            ball_iterations = _MAX_ITER
            code = code or RESULTS.ball_solver
    model = build_model(bearing, op, loads, spall, sol, params, curve, int(ball_iterations))
    m = draw_motion(seed, bearing.n_balls, theta0, float(sol.cage_speed), float(op.speed), ts[-1],
                    0.0 if spall is None else float(spall.center), realism)
    st0 = jnp.asarray(np.stack(motion_at(m, np.zeros(1)), -1)[0])
    y0, ok = _initial_state_jit(model, sol.displacement[:3], st0)
    if not bool(ok):
        code = code or RESULTS.initial_equilibrium
    if substeps == "auto":
        lam = np.abs(np.asarray(_linear_modes_jit(model, y0, st0)))
        substeps = choose_substeps(np.max(lam[np.isfinite(lam)], initial=0.0), fs)
    substeps = int(substeps)
    progress = (float(duration) >= 1.0) if progress is None else bool(progress)
    jumps = spall_edge_times(m, spall, ts[-1] + 1.0 / fs) \
        if spall is not None and spall.profile == "rectangular" else np.zeros(0)
    if code == RESULTS.successful:
        if integrator == "fixed":
            y, ah, sens, nsteps = _run_fixed(model, y0, m, jumps, fs, T, scheme, substeps, False, progress)
        elif integrator == "adaptive":
            y, ah, sens, nsteps = _run_adaptive(model, y0, m, ts, jumps, rtol, atol, sensor_coupling)
        else:
            raise InputError(f"integrator must be 'fixed' or 'adaptive', got {integrator!r}")
        if code == RESULTS.successful and not (np.all(np.isfinite(y)) and np.all(np.isfinite(sens))):
            code = RESULTS.nonfinite
    else:
        y, ah, sens, nsteps = np.zeros((T, 10)), np.zeros((T, 2)), np.zeros(T), 0
    if throw and code != RESULTS.successful:
        q_code = int(sol.result)
        extra = f" (quasi-static: {sol.message()[0]})" if q_code else ""
        raise DynamicsError(f"dynamic simulation failed: {code.message}{extra}", code.hint, code)
    rng_noise = _seeds(seed)[3]
    noise = np.zeros(T)
    if realism.noise_rms > 0.0:
        noise = sensor_mod.measurement_noise(rng_noise, T, realism.noise_rms, fs, realism.noise_band)
    theta, _, omega = motion_at(m, ts)
    rel = np.stack([y[:, 0] - y[:, 3], y[:, 1] - y[:, 4], y[:, 2]], axis=1)
    balls = [None] * 4
    if record_balls and code == RESULTS.successful:
        balls = _record_balls(model, rel, theta, omega, int(ball_iterations) + 1)
    freqs, a_m = characteristic_frequencies(bearing, op, sol)
    labels = _motion_labels(m, realism)
    labels["ball_solver_error"] = float(err)
    return DynamicsResult(
        time=ts, cage_angle=theta, shaft_speed=omega, ring_displacement=rel,
        shaft_displacement=y[:, 0:3], housing_displacement=y[:, 3:5], housing_acceleration=ah,
        sensor_acceleration=sens + noise, noise=noise, Q_inner=balls[0], Q_outer=balls[1],
        alpha_inner=balls[2], alpha_outer=balls[3], result=int(code), num_steps=int(nsteps),
        frequencies=freqs, contact_angle=a_m, jump_times=jumps,
        pass_times=spall_pass_times(m, spall, ts[-1]), quasi_static=sol,
        contact_damping=np.asarray(model.contact_damping), ball_iterations=int(ball_iterations),
        substeps=substeps, scheme=scheme, realism=labels)


def simulate_case(case, progress=None, throw=True, **kw) -> DynamicsResult:
    """:func:`simulate` with everything taken from a :class:`bearingsim.case.Case`."""
    d = case.dynamics_settings()
    kw.setdefault("realism", Realism.from_settings(d))
    return simulate(case.bearing(), case.operation(), case.loads(), case.spall(),
                    DynamicsParameters.from_settings(d), d["duration"], d["sample_rate"],
                    theta0=case.cage_angle, seed=d.get("seed", 0), hertz_method=case.hertz_method,
                    progress=progress, throw=throw, **kw)


# ------------------------------------------------------------------------------------ batch
class DynamicsBatchResult(NamedTuple):
    """Output of :func:`simulate_batch` (N items, T samples; host arrays)."""

    time: np.ndarray                    # (T,) s
    sensor_acceleration: np.ndarray     # (N, T) m/s^2 (with noise)
    ring_displacement: np.ndarray       # (N, T, 3) m
    result: np.ndarray                  # (N,) RESULTS codes
    num_steps: np.ndarray               # (N,)
    cage_speed: np.ndarray              # (N,) rad/s (quasi-static, nominal)
    bpfo_Hz: np.ndarray                 # (N,)
    realism: list                       # (N,) dicts: labels of the realism draws


def _qs_batch(bearing, op, loads, theta0, spall, hertz_method, speed_steps):
    curve = stiffness_curve(bearing, hertz_method)

    def one(o, F, th, sp):
        return solve_state(bearing, o, F, cage_angle=th, spall=sp, speed_steps=speed_steps, curve=curve,
                           hertz_method=hertz_method)

    return jax.vmap(one)(op, loads, theta0, spall)


_qs_batch_jit = eqx.filter_jit(_qs_batch)


def _init_batch(model, q0, st0):
    return jax.vmap(_initial_state)(model, q0, st0)


_init_batch_jit = eqx.filter_jit(_init_batch)


def _take(tree, i):
    return jax.tree_util.tree_map(lambda a: a[i], tree)


def batch_settings(bearing, op, loads, spall, theta0, sample_rate, params=None, hertz_method="exact"):
    """(ball_iterations, substeps) for items like this one (a single item's quasi-static state
    checked with :func:`choose_ball_iterations` and :func:`choose_substeps`); fix them once for
    a data set so that no chunk recompiles."""
    params = DynamicsParameters() if params is None else params
    curve = stiffness_curve(bearing, hertz_method)
    sol = solve(bearing, op, loads, cage_angle=theta0, spall=spall, hertz_method=hertz_method, throw=False)
    if int(sol.result) != 0:
        return None, None
    it, _ = choose_ball_iterations(bearing, op, sol.displacement, spall, curve, theta0)
    it = it or _MAX_ITER
    model = build_model(bearing, op, loads, spall, sol, params, curve, it)
    st0 = jnp.asarray([theta0, 0.0, float(op.speed)])
    y0, _ = _initial_state_jit(model, sol.displacement[:3], st0)
    lam = np.abs(np.asarray(_linear_modes_jit(model, y0, st0)))
    return it, choose_substeps(np.max(lam[np.isfinite(lam)], initial=0.0), sample_rate)


def simulate_batch(bearing, speed_rpm, loads, spall_center, spall_extent, spall_depth,
                   profile="rectangular", params: DynamicsParameters | None = None, duration=0.1,
                   sample_rate=48000.0, theta0=0.0, *, realism: Realism | None = None, seeds=None,
                   control="outer", hertz_method="exact", scheme="newmark", substeps=None,
                   ball_iterations=None) -> DynamicsBatchResult:
    """N simulations in lockstep (vmap over items of the fixed-step loop): same bearing (Z),
    spall profile, duration and sample rate.

    ``speed_rpm`` (N,), ``loads`` (N, 5), ``spall_center``/``spall_extent`` (rad),
    ``spall_depth`` (m) (N,) each; ``params`` fields may be scalars or (N,) ((N, M) for the
    modes); ``seeds`` (N,) the items' realism seeds (default 0..N-1).  Never raises: ``result``
    is per item.  ``ball_iterations``/``substeps`` None: :func:`batch_settings` on the fastest
    and the most heavily loaded item (one more Newton step of margin)."""
    _check_scheme(scheme)
    realism = Realism() if realism is None else realism
    loads = jnp.asarray(loads, jnp.float64)
    n = loads.shape[0]
    bc = lambda v: jnp.broadcast_to(jnp.asarray(v, jnp.float64), (n,))
    params = DynamicsParameters() if params is None else params
    f, z, g = params.modes()
    M = f.shape[-1]
    params = eqx.tree_at(lambda p: (p.resonance_frequency, p.resonance_damping_ratio, p.resonance_gain),
                         params, tuple(jnp.broadcast_to(v, (n, M)) for v in (f, z, g)))
    params = jax.tree_util.tree_map(lambda a: a if a.ndim == 2 else bc(a), params)
    speed = np.broadcast_to(np.asarray(speed_rpm, float), (n,))
    op = Operation(bc(2 * np.pi * speed / 60.0), control, bc(1.0), bc(1.0))
    spall = Spall(bc(spall_center), bc(spall_extent), bc(spall_depth), profile)
    th = bc(theta0)
    fs = float(sample_rate)
    ts = _time_grid(duration, fs)
    T = ts.size
    seeds = np.arange(n) if seeds is None else np.asarray(seeds)
    if ball_iterations is None or substeps is None:
        its, subs = [], []
        for i in {int(np.argmax(speed)), int(np.argmax(np.abs(np.asarray(loads)).sum(1)))}:
            it_i, s_i = batch_settings(bearing, _take(op, i), loads[i], _take(spall, i), float(th[i]), fs,
                                       _take(params, i), hertz_method)
            if it_i is not None:
                its.append(it_i)
                subs.append(s_i)
        ball_iterations = ball_iterations or next_iterations(its)
        substeps = substeps or max(subs, default=1)
    sols = _qs_batch_jit(bearing, op, loads, th, spall, hertz_method, 1)
    bad = np.flatnonzero(np.asarray(sols.result) != 0)
    if bad.size:    # retry those with 8 speed stages (only them)
        idx = jnp.asarray(bad)
        retry = _qs_batch_jit(bearing, _take(op, idx), loads[idx], th[idx], _take(spall, idx),
                              hertz_method, 8)
        take = jnp.asarray(np.asarray(retry.result) == 0)

        def merge(a, r):
            mk = take.reshape(take.shape + (1,) * (r.ndim - 1))
            return a.at[idx].set(jnp.where(mk, r, a[idx]))

        sols = jax.tree_util.tree_map(merge, sols, retry)
    curve = stiffness_curve(bearing, hertz_method)
    bearing_b = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (n,) + jnp.shape(a)), bearing)
    curve_b = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (n,) + jnp.shape(a)), curve)
    model = build_model(bearing_b, op, loads, spall, sols, params, curve_b, int(ball_iterations))
    omega_c = np.asarray(sols.cage_speed)
    okc = np.isfinite(omega_c) & (omega_c > 0)
    motions = [draw_motion(int(seeds[i]), bearing.n_balls, float(th[i]), float(omega_c[i]) if okc[i] else 0.0,
                           float(op.speed[i]), ts[-1], float(spall.center[i]), realism) for i in range(n)]
    st0 = jnp.asarray(np.stack([np.stack(motion_at(m, np.zeros(1)), -1)[0] for m in motions]))
    y0, ok = _init_batch_jit(model, sols.displacement[:, :3], st0)
    edges = [spall_edge_times(mm, _take(spall, i), ts[-1] + 1.0 / fs) if profile == "rectangular"
             else np.zeros(0) for i, mm in enumerate(motions)]
    y, ah, sens, nsteps = _run_fixed(model, y0, motions, edges, fs, T, scheme, int(substeps), True, False)
    code = np.where(np.asarray(sols.result) != 0, int(RESULTS.initial_state),
                    np.where(~np.asarray(ok), int(RESULTS.initial_equilibrium), int(RESULTS.successful)))
    finite = np.all(np.isfinite(y), axis=(1, 2)) & np.all(np.isfinite(sens), axis=1)
    code = np.where((code == 0) & ~finite, int(RESULTS.nonfinite), code)
    sens = np.where(code[:, None] == 0, sens, 0.0)        # a failed item is flagged, never used
    labels = []
    for i, m in enumerate(motions):
        if realism.noise_rms > 0.0:
            sens[i] += sensor_mod.measurement_noise(_seeds(int(seeds[i]))[3], T, realism.noise_rms, fs,
                                                    realism.noise_band)
        labels.append(_motion_labels(m, realism))
    rel = np.stack([y[..., 0] - y[..., 3], y[..., 1] - y[..., 4], y[..., 2]], axis=-1)
    wc = np.where(okc, omega_c, np.nan)
    return DynamicsBatchResult(ts, sens, rel, code.astype(np.int32), np.full(n, nsteps), wc,
                               bearing.n_balls * wc / (2 * np.pi), labels)
