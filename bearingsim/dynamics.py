"""Dynamic layer (MODEL.md section 7): shaft, housing and a sensor resonator driven by the
Jones bearing forces of the balls as they roll over an outer-raceway spall.

Model
-----
Degrees of freedom (12 states, SI):

* shaft / inner ring translations ``x_s, y_s, z_s`` (mass ``m_s``),
* housing / outer ring translations ``x_h, y_h`` (mass ``m_h``) on a support of stiffness
  ``k_h`` and damping ``c_h`` (both directions; the housing is fixed axially),
* a resonator ``x_r`` (mass ``m_r``, natural frequency ``f_n``, damping ratio ``zeta``) on the
  housing in the load direction x.  Its absolute acceleration is the sensor signal (the
  structural resonance excited by the impacts, as in Sawalhi & Randall 2008),

and their velocities.  The cage turns at the constant speed ``omega_c`` = mean orbital speed of
the balls in the quasi-static solution (``JonesSolution.cage_speed``), so ball j sits at
``psi_j(t) = theta_c0 + omega_c t + 2 pi j / Z``.

Bearing force.  At each instant the relative ring displacement is
``q_rel = [x_s - x_h, y_s - y_h, z_s, theta_x0, theta_y0]``: the tilts are not degrees of
freedom and are held at their quasi-static values at ``theta_c0`` (moments are therefore not
balanced dynamically; for the radial / thrust cases of interest the tilts are ~0).  Every
ball's 2x2 Jones equilibrium (centrifugal force, gyroscopic moment, spall depth H(psi_j)) is
solved from the omega = 0 closed form by a fixed number of Newton steps per ball, vmapped over
balls (``balls_fixed``; the count is checked against :func:`bearingsim.jones.balls_at` by
``choose_iterations``, which falls back to ``balls_at``); the ring load ``R = [Fx, Fy, Fz]`` the bearing carries follows from
``_reactions_from_balls``.  Equations of motion::

    m_s a_s = F_ext + F_u(t) - R - C_b v_rel                        (x, y, z)
    m_h a_h = R_xy + (C_b v_rel)_xy - k_h x_h - c_h v_h + e_x F_r    (x, y)
    m_r a_r = -F_r,   F_r = k_r (x_r - x_h) + c_r (v_r - v_xh)

with ``v_rel = v_s - [v_h, 0]``, ``F_ext`` the constant applied loads [Fx, Fy, Fz],
``F_u = m_u e omega^2 [cos(omega t), sin(omega t), 0]`` an optional unbalance turning with the
shaft, ``k_r = m_r (2 pi f_n)^2`` and ``c_r = 2 zeta m_r 2 pi f_n``.

Contact damping ``C_b = diag(c_x, c_y, c_z)`` with ``c_i = 2 zeta_b sqrt(K_ii m_s)``, K the
quasi-static bearing stiffness (``JonesSolution.stiffness`` diagonal) at ``theta_c0``: a
viscous damping ratio ``zeta_b`` on the shaft-on-bearing mode in each direction.

Initial state = the quasi-static solution at ``theta_c0`` (with the spall), so there is no
start-up transient: ``x_h = F_x / k_h`` (static support deflection), shaft = ``q[:3]`` plus the
housing position, resonator at rest on the housing (its spring is unloaded), all velocities 0.

Integration: diffrax Tsit5 with a PID step-size controller wrapped in a
``ClipStepSizeController`` whose ``jump_ts`` are the times a ball enters or leaves a
rectangular spall (the force is discontinuous there); the state is scaled to um and mm/s so
that one absolute tolerance fits all states.  Output at the sample grid (dense
interpolation, ``SaveAt(ts=...)``); per-ball loads and angles are recomputed from the saved
states (vmapped ``balls_at``, in chunks).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .defect import Spall
from .hertz import stiffness_curve
from .jones import _reactions_from_balls, _solve, balls_at, solve
from .kinematics import Operation, defect_frequencies

__all__ = [
    "DynamicsParameters",
    "DynamicModel",
    "DynamicsResult",
    "DynamicsBatchResult",
    "DynamicsError",
    "RESULT_MESSAGES",
    "simulate",
    "simulate_batch",
    "spall_edge_times",
    "spall_pass_times",
    "characteristic_frequencies",
]

#: result codes of a simulation
RESULT_MESSAGES = {
    0: "successful",
    1: "maximum number of integrator steps reached",
    2: "integration failed (step size too small or non-finite state)",
    3: "the quasi-static initial state did not converge",
}

# state scaling: positions in um, velocities in mm/s
_POS, _VEL = 1e-6, 1e-3
_SCALE = jnp.array([_POS] * 6 + [_VEL] * 6)
_CHUNK = 2048          # samples per chunk when recomputing the ball states


class DynamicsError(RuntimeError):
    """A dynamic simulation failed."""


def _f64(x):
    return jnp.asarray(x, dtype=jnp.float64)


class DynamicsParameters(eqx.Module):
    """Structural parameters (SI).  Defaults are those of the case schema ([dynamics])."""

    shaft_mass: jnp.ndarray = eqx.field(converter=_f64, default=2.0)            # kg
    housing_mass: jnp.ndarray = eqx.field(converter=_f64, default=5.0)          # kg
    housing_stiffness: jnp.ndarray = eqx.field(converter=_f64, default=5e7)     # N/m
    housing_damping: jnp.ndarray = eqx.field(converter=_f64, default=2000.0)    # N s/m
    resonance_frequency: jnp.ndarray = eqx.field(converter=_f64, default=3000.0)  # Hz
    resonance_damping_ratio: jnp.ndarray = eqx.field(converter=_f64, default=0.05)
    resonator_mass: jnp.ndarray = eqx.field(converter=_f64, default=0.05)       # kg
    contact_damping_ratio: jnp.ndarray = eqx.field(converter=_f64, default=0.05)
    unbalance: jnp.ndarray = eqx.field(converter=_f64, default=0.0)             # kg m

    @classmethod
    def from_settings(cls, d: dict) -> "DynamicsParameters":
        """From ``Case.dynamics_settings()`` (SI keys without unit suffix)."""
        names = [f.name for f in cls.__dataclass_fields__.values()]
        return cls(**{k: d[k] for k in names if k in d})


class DynamicModel(eqx.Module):
    """Everything the right-hand side needs (arrays may carry a batch axis under vmap)."""

    bearing: object
    op: Operation
    spall: Spall | None
    curve: object
    loads: jnp.ndarray          # (5,) applied [Fx, Fy, Fz, Mx, My]
    tilts: jnp.ndarray          # (2,) quasi-static tilts held constant (rad)
    theta0: jnp.ndarray         # cage angle at t = 0 (rad)
    omega_c: jnp.ndarray        # cage speed (rad/s)
    contact_damping: jnp.ndarray  # (3,) c_b in x, y, axial (N s/m)
    params: DynamicsParameters
    iterations: int = eqx.field(static=True, default=0)   # 0: exact balls_at; n: n Newton steps

    def resonator(self):
        p = self.params
        wn = 2.0 * jnp.pi * p.resonance_frequency
        return p.resonator_mass * wn ** 2, 2.0 * p.resonance_damping_ratio * p.resonator_mass * wn

    def azimuths(self, t):
        return self.bearing.ball_azimuths(self.theta0 + self.omega_c * t)

    def balls(self, t, y, exact=False):
        """Ball states (BallState of (Z,)) and ring reactions R (5,) for the physical state y.
        ``exact`` (or ``iterations == 0``): ``jones.balls_at``; else ``balls_fixed``."""
        q = jnp.concatenate([jnp.stack([y[0] - y[3], y[1] - y[4], y[2]]), self.tilts])
        psi = self.azimuths(t)
        if exact or self.iterations == 0:
            st, _ = balls_at(self.bearing, self.op, q, psi, self.spall, self.curve)
        else:
            st = balls_fixed(self.bearing, self.op, q, psi, self.spall, self.curve, self.iterations)
        return st, _reactions_from_balls(st, psi)

    def derivative(self, t, y, R):
        """dy/dt (physical units) given the ring reactions R."""
        p = self.params
        xs, xh, xr = y[0:3], y[3:5], y[5]
        vs, vh, vr = y[6:9], y[9:11], y[11]
        k_r, c_r = self.resonator()
        w = self.op.speed
        Fu = p.unbalance * w ** 2 * jnp.stack([jnp.cos(w * t), jnp.sin(w * t), jnp.zeros_like(t)])
        v_rel = vs - jnp.concatenate([vh, jnp.zeros(1)])
        Fd = self.contact_damping * v_rel
        Rb = R[:3]
        a_s = (self.loads[:3] + Fu - Rb - Fd) / p.shaft_mass
        Fr = k_r * (xr - xh[0]) + c_r * (vr - vh[0])
        a_h = (Rb[:2] + Fd[:2] - p.housing_stiffness * xh - p.housing_damping * vh
               + jnp.stack([Fr, jnp.zeros_like(Fr)])) / p.housing_mass
        a_r = -Fr / p.resonator_mass
        return jnp.concatenate([vs, vh, vr[None], a_s, a_h, a_r[None]])


def _vector_field(t, u, model: DynamicModel):
    y = u * _SCALE
    _, R = model.balls(t, y)
    return model.derivative(t, y, R) / _SCALE


def build_model(bearing, op, loads, spall, sol, params: DynamicsParameters, theta0, curve,
                iterations=0):
    """DynamicModel and initial physical state y0 from a quasi-static solution at theta0."""
    q = sol.displacement
    K = jnp.diagonal(sol.stiffness)[:3]
    cb = 2.0 * params.contact_damping_ratio * jnp.sqrt(jnp.maximum(K, 0.0) * params.shaft_mass)
    loads = jnp.asarray(loads, jnp.float64)
    model = DynamicModel(bearing, op, spall, curve, loads, q[3:5], jnp.asarray(theta0, jnp.float64),
                         sol.cage_speed, cb, params, iterations)
    xh = loads[:2] / params.housing_stiffness
    y0 = jnp.concatenate([q[:2] + xh, q[2:3], xh, xh[:1], jnp.zeros(6)])
    return model, y0


# ----------------------------------------------------------------------------------- events
def _angle_times(bearing, angle, theta0, omega_c, duration):
    """Times in [0, duration] at which some ball is at azimuth ``angle`` (s, sorted)."""
    if omega_c <= 0.0:
        return np.zeros(0)
    Z = bearing.n_balls
    th1 = theta0 + omega_c * duration
    out = []
    for j in range(Z):
        base = angle - 2 * np.pi * j / Z
        k0 = np.ceil((theta0 - base) / (2 * np.pi))
        k1 = np.floor((th1 - base) / (2 * np.pi))
        out.extend(base + 2 * np.pi * np.arange(k0, k1 + 1))
    return np.sort((np.asarray(out, dtype=float) - theta0) / omega_c)


def spall_edge_times(bearing, spall, theta0, omega_c, duration):
    """Times (s) within [0, duration] at which a ball enters or leaves the spall."""
    if spall is None or float(spall.depth) <= 0.0:
        return np.zeros(0)
    lo, hi = (float(e) for e in spall.edges())
    t = np.concatenate([_angle_times(bearing, lo, float(theta0), float(omega_c), duration),
                        _angle_times(bearing, hi, float(theta0), float(omega_c), duration)])
    return np.unique(t)


def spall_pass_times(bearing, spall, theta0, omega_c, duration):
    """Times (s) within [0, duration] at which a ball centre passes the spall centre."""
    if spall is None or float(spall.depth) <= 0.0:
        return np.zeros(0)
    return _angle_times(bearing, float(spall.center), float(theta0), float(omega_c), duration)


def _pad_jumps(jumps, t1, size=None):
    n = max(1, len(jumps)) if size is None else size
    size = 1 << max(0, math.ceil(math.log2(n))) if size is None else size
    pad = float(t1) + 1.0 + np.arange(size - len(jumps), dtype=float)   # beyond t1: never hit
    return np.concatenate([np.asarray(jumps, float), pad])


def _max_steps(duration, params, rtol):
    """Generous bound on the number of steps: ~ 60 steps per period of the fastest mode at the
    default tolerance (measured: ~12-25), times 4; rounded up to a power of two."""
    f_hi = max(float(np.max(np.asarray(params.resonance_frequency))), 2000.0)
    tol_factor = max(1.0, (1e-6 / rtol) ** 0.2)
    n = 240 * f_hi * duration * tol_factor + 4096
    return 1 << math.ceil(math.log2(n))


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


# ------------------------------------------------------------------------------ integration
def _result_code(res):
    ok = res == diffrax.RESULTS.successful
    ms = res == diffrax.RESULTS.max_steps_reached
    return jnp.where(ok, 0, jnp.where(ms, 1, 2)).astype(jnp.int32)


def _integrate(model, y0, ts, jump_ts, dtmax, rtol, atol, max_steps, progress):
    ctrl = diffrax.ClipStepSizeController(
        diffrax.PIDController(rtol=rtol, atol=atol, pcoeff=0.2, icoeff=0.4, dtmax=dtmax),
        jump_ts=jump_ts)
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(_vector_field), diffrax.Tsit5(), t0=ts[0], t1=ts[-1], dt0=None,
        y0=y0 / _SCALE, args=model, saveat=diffrax.SaveAt(ts=ts), stepsize_controller=ctrl,
        max_steps=max_steps, throw=False,
        progress_meter=diffrax.TqdmProgressMeter(refresh_steps=2000) if progress else diffrax.NoProgressMeter())
    ys = jnp.where(jnp.isfinite(sol.ys), sol.ys, 0.0) * _SCALE
    return ys, _result_code(sol.result), sol.stats["num_steps"]


_integrate_jit = eqx.filter_jit(_integrate)


def _post(model, ts, ys):
    """Per sample: housing acceleration (2,), resonator acceleration, ball Q_i, Q_o, a_i, a_o."""
    def one(t, y):
        st, R = model.balls(t, y, exact=True)
        dy = model.derivative(t, y, R)
        return dy[9:11], dy[11], st.Q_i, st.Q_o, st.alpha_i, st.alpha_o

    return jax.vmap(one)(ts, ys)


_post_jit = eqx.filter_jit(_post)


def _post_chunked(model, ts, ys, chunk=_CHUNK):
    n = ts.shape[0]
    outs = []
    for k in range(0, n, chunk):
        tt, yy = ts[k:k + chunk], ys[k:k + chunk]
        m = tt.shape[0]
        if m < chunk:      # one compiled shape: pad with the last sample
            tt = jnp.concatenate([tt, jnp.repeat(tt[-1:], chunk - m)])
            yy = jnp.concatenate([yy, jnp.repeat(yy[-1:], chunk - m, axis=0)])
        outs.append(jax.tree_util.tree_map(lambda a: a[:m], _post_jit(model, tt, yy)))
    return jax.tree_util.tree_map(lambda *a: jnp.concatenate(a, axis=0), *outs)


class DynamicsResult(NamedTuple):
    """Output of :func:`simulate` (SI; T samples, Z balls)."""

    time: jnp.ndarray                   # (T,) s
    cage_angle: jnp.ndarray             # (T,) rad
    ring_displacement: jnp.ndarray      # (T, 3) shaft relative to housing x, y, axial (m)
    shaft_displacement: jnp.ndarray     # (T, 3) absolute (m)
    housing_displacement: jnp.ndarray   # (T, 2) m
    housing_acceleration: jnp.ndarray   # (T, 2) m/s^2
    sensor_acceleration: jnp.ndarray    # (T,) m/s^2 (resonator, plus noise)
    Q_inner: jnp.ndarray                # (T, Z) N
    Q_outer: jnp.ndarray                # (T, Z) N
    alpha_inner: jnp.ndarray            # (T, Z) rad
    alpha_outer: jnp.ndarray            # (T, Z) rad
    result: int                         # 0 = successful (RESULT_MESSAGES)
    num_steps: int
    frequencies: dict                   # shaft/ftf/bpfo/bpfi/bsf in Hz
    contact_angle: float                # mean loaded contact angle used for BPFI/BSF (rad)
    jump_times: np.ndarray              # spall entry/exit times (s)
    pass_times: np.ndarray              # times a ball centre passes the spall centre (s)
    quasi_static: object                # JonesSolution at theta_c0
    contact_damping: jnp.ndarray        # (3,) N s/m
    ball_iterations: int                # Newton steps per ball in the RHS (0: balls_at)


def _time_grid(duration, sample_rate):
    n = int(round(float(duration) * float(sample_rate)))
    if n < 2:
        raise ValueError(f"duration x sample rate gives {n} samples; need at least 2")
    return np.arange(n) / float(sample_rate)


def _dtmax(bearing, spall, omega_c, params):
    """Largest step: a quarter of the fastest mode's period is never limiting for accuracy;
    with a spall, also a quarter of the time a ball needs to cross it (never step over it)."""
    dt = 0.25 / max(float(np.max(np.asarray(params.resonance_frequency))), 1.0)
    if spall is not None and float(np.max(np.asarray(spall.depth))) > 0.0 and float(np.min(omega_c)) > 0:
        dt = min(dt, 0.25 * float(np.min(np.asarray(spall.extent))) / float(np.max(omega_c)))
    return dt


def simulate(bearing, op: Operation, loads, spall: Spall | None = None,
             params: DynamicsParameters | None = None, duration=0.1, sample_rate=48000.0,
             theta0=0.0, rtol=1e-6, atol=1e-6, noise_rms=0.0, seed=0, hertz_method="exact",
             progress=None, throw=True, max_steps=None, ball_iterations="auto") -> DynamicsResult:
    """Time simulation of MODEL.md section 7 (see the module docstring for the equations).

    ``loads`` [Fx, Fy, Fz, Mx, My] (N, N m), ``duration`` (s), ``sample_rate`` (Hz), ``theta0``
    the cage angle at t = 0 (rad).  ``rtol``/``atol`` of the step-size controller (atol on
    displacements in um and velocities in mm/s).  ``progress``: diffrax tqdm bar (default: when
    duration >= 0.2 s).  ``ball_iterations``: Newton steps per ball in the right-hand side
    ("auto": :func:`choose_iterations`; 0: the exact ``jones.balls_at``).  Raises :class:`DynamicsError` when the integration fails and
    ``throw`` (else check ``result.result``).
    """
    params = DynamicsParameters() if params is None else params
    loads = jnp.asarray(loads, jnp.float64)
    curve = stiffness_curve(bearing, hertz_method)
    sol = solve(bearing, op, loads, cage_angle=theta0, spall=spall, hertz_method=hertz_method,
                throw=throw)
    if ball_iterations == "auto":
        ball_iterations = choose_iterations(bearing, op, sol.displacement, spall, curve, theta0)
    model, y0 = build_model(bearing, op, loads, spall, sol, params, theta0, curve,
                            int(ball_iterations))
    omega_c = float(model.omega_c)
    ts = _time_grid(duration, sample_rate)
    t1 = float(ts[-1])
    jumps = spall_edge_times(bearing, spall, theta0, omega_c, t1) \
        if spall is not None and spall.profile == "rectangular" else np.zeros(0)
    jump_ts = jnp.asarray(_pad_jumps(jumps, t1))
    max_steps = _max_steps(t1, params, rtol) if max_steps is None else int(max_steps)
    progress = (float(duration) >= 0.2) if progress is None else bool(progress)
    ys, code, nsteps = _integrate_jit(model, y0, jnp.asarray(ts), jump_ts,
                                      jnp.float64(_dtmax(bearing, spall, omega_c, params)),
                                      jnp.float64(rtol), jnp.float64(atol), max_steps, progress)
    code = int(code) if int(sol.result) == 0 else 3
    if throw and code != 0:
        raise DynamicsError(f"dynamic simulation failed: {RESULT_MESSAGES[code]} "
                            f"({int(nsteps)} steps, max_steps {max_steps}). Hint: loosen rtol/atol, "
                            "or check the structural parameters (a very stiff or very light system "
                            "needs tiny steps).")
    a_h, a_r, Qi, Qo, ai, ao = _post_chunked(model, jnp.asarray(ts), ys)
    if noise_rms > 0.0:
        a_r = a_r + noise_rms * jax.random.normal(jax.random.PRNGKey(int(seed)), a_r.shape)
    freqs, a_m = characteristic_frequencies(bearing, op, sol)
    rel = jnp.stack([ys[:, 0] - ys[:, 3], ys[:, 1] - ys[:, 4], ys[:, 2]], axis=1)
    return DynamicsResult(
        time=jnp.asarray(ts), cage_angle=theta0 + model.omega_c * jnp.asarray(ts),
        ring_displacement=rel, shaft_displacement=ys[:, 0:3], housing_displacement=ys[:, 3:5],
        housing_acceleration=a_h, sensor_acceleration=a_r, Q_inner=Qi, Q_outer=Qo,
        alpha_inner=ai, alpha_outer=ao, result=code, num_steps=int(nsteps), frequencies=freqs,
        contact_angle=a_m, jump_times=jumps,
        pass_times=spall_pass_times(bearing, spall, theta0, omega_c, t1),
        quasi_static=sol, contact_damping=model.contact_damping, ball_iterations=int(ball_iterations))


def simulate_case(case, progress=None, throw=True, **kw) -> DynamicsResult:
    """:func:`simulate` with everything taken from a :class:`bearingsim.case.Case`."""
    d = case.dynamics_settings()
    return simulate(case.bearing(), case.operation(), case.loads(), case.spall(),
                    DynamicsParameters.from_settings(d), d["duration"], d["sample_rate"],
                    theta0=case.cage_angle, rtol=d["rtol"], atol=d["atol"],
                    noise_rms=d["noise_rms"], seed=d["seed"], hertz_method=case.hertz_method,
                    progress=progress, throw=throw, **kw)


# ------------------------------------------------------------------------------------ batch
class DynamicsBatchResult(NamedTuple):
    """Output of :func:`simulate_batch` (N items, T samples)."""

    time: np.ndarray                    # (T,) s
    sensor_acceleration: jnp.ndarray    # (N, T) m/s^2
    ring_displacement: jnp.ndarray      # (N, T, 3) m
    result: jnp.ndarray                 # (N,) codes (RESULT_MESSAGES)
    num_steps: jnp.ndarray              # (N,)
    cage_speed: jnp.ndarray             # (N,) rad/s
    bpfo_Hz: jnp.ndarray                # (N,)


def _qs_batch(bearing, op, loads, theta0, spall, hertz_method):
    maxit, rtol, atol = jnp.int32(60), jnp.float64(1e-11), jnp.float64(1e-9)

    def one(o, F, th, sp):
        return _solve(bearing, o, F, th, sp, None, 1, maxit, rtol, atol, hertz_method)

    return jax.vmap(one)(op, loads, theta0, spall)


_qs_batch_jit = eqx.filter_jit(_qs_batch)


def _batch_integrate(bearing, op, loads, spall, sols, params, theta0, curve, ts, jump_ts, dtmax,
                     rtol, atol, max_steps, noise_key, noise_rms, iterations):
    def one(o, F, sp, s, p, th, jt, key):
        model, y0 = build_model(bearing, o, F, sp, s, p, th, curve, iterations)
        ys, code, n = _integrate(model, y0, ts, jt, dtmax, rtol, atol, max_steps, False)
        y = ys * 1.0
        k_r, c_r = model.resonator()
        a_r = -(k_r * (y[:, 5] - y[:, 3]) + c_r * (y[:, 11] - y[:, 9])) / p.resonator_mass
        a_r = a_r + noise_rms * jax.random.normal(key, a_r.shape)
        rel = jnp.stack([y[:, 0] - y[:, 3], y[:, 1] - y[:, 4], y[:, 2]], axis=1)
        code = jnp.where(s.result == 0, code, 3)
        return a_r, rel, code, n, model.omega_c

    return jax.vmap(one)(op, loads, spall, sols, params, theta0, jump_ts, noise_key)


_batch_integrate_jit = eqx.filter_jit(_batch_integrate)


def simulate_batch(bearing, speed_rpm, loads, spall_center, spall_extent, spall_depth,
                   profile="rectangular", params: DynamicsParameters | None = None, duration=0.1,
                   sample_rate=48000.0, theta0=0.0, rtol=1e-6, atol=1e-6, noise_rms=0.0, seed=0,
                   control="outer", hertz_method="exact", max_steps=None,
                   ball_iterations="auto") -> DynamicsBatchResult:
    """N simulations at once (vmap), same bearing (Z), spall profile, duration and sample rate.

    ``speed_rpm`` (N,), ``loads`` (N, 5), ``spall_center``/``spall_extent`` (rad),
    ``spall_depth`` (m) (N,) each; ``params`` fields may be scalars or (N,).  Never raises:
    ``result`` is per item (0 = successful; see RESULT_MESSAGES).  Only the sensor signal and
    the ring displacement are kept (memory).  ``ball_iterations="auto"`` checks the lean ball
    solver (:func:`choose_iterations`) on the fastest item and the most heavily loaded one and
    adds one Newton step of margin.
    """
    loads = jnp.asarray(loads, jnp.float64)
    n = loads.shape[0]
    bc = lambda v: jnp.broadcast_to(jnp.asarray(v, jnp.float64), (n,))
    params = DynamicsParameters() if params is None else params
    params = jax.tree_util.tree_map(bc, params)
    op = Operation(bc(2 * np.pi * np.asarray(speed_rpm) / 60.0), control, bc(1.0), bc(1.0))
    spall = Spall(bc(spall_center), bc(spall_extent), bc(spall_depth), profile)
    th = bc(theta0)
    sols = _qs_batch_jit(bearing, op, loads, th, spall, hertz_method)
    omega_c = np.asarray(sols.cage_speed)
    curve = stiffness_curve(bearing, hertz_method)
    if ball_iterations == "auto":
        its = []
        for i in {int(np.argmax(np.asarray(op.speed))), int(np.argmax(np.abs(np.asarray(loads)).sum(1)))}:
            pick = lambda a: a[i]
            sp_i = Spall(float(spall.center[i]), float(spall.extent[i]), float(spall.depth[i]), profile)
            its.append(choose_iterations(bearing, jax.tree_util.tree_map(pick, op),
                                         sols.displacement[i], sp_i, curve, float(th[i])))
        ball_iterations = 0 if 0 in its else min(max(its) + 1, _MAX_ITER)
    ts = _time_grid(duration, sample_rate)
    t1 = float(ts[-1])
    jumps = [spall_edge_times(bearing, Spall(float(spall.center[i]), float(spall.extent[i]),
                                             float(spall.depth[i]), profile),
                              float(th[i]), omega_c[i], t1) if profile == "rectangular" else np.zeros(0)
             for i in range(n)]
    size = 1 << max(0, math.ceil(math.log2(max(1, max(len(j) for j in jumps)))))
    jump_ts = jnp.asarray(np.stack([_pad_jumps(j, t1, size) for j in jumps]))
    max_steps = _max_steps(t1, params, rtol) if max_steps is None else int(max_steps)
    omega_ok = np.where(np.isfinite(omega_c) & (omega_c > 0), omega_c, 1.0)
    dtmax = _dtmax(bearing, spall, omega_ok, params)
    keys = jax.random.split(jax.random.PRNGKey(int(seed)), n)
    a_r, rel, code, nsteps, wc = _batch_integrate_jit(
        bearing, op, loads, spall, sols, params, th, curve,
        jnp.asarray(ts), jump_ts, jnp.float64(dtmax), jnp.float64(rtol), jnp.float64(atol), max_steps, keys,
        jnp.float64(noise_rms), int(ball_iterations))
    return DynamicsBatchResult(ts, a_r, rel, code, nsteps, wc, bearing.n_balls * wc / (2 * np.pi))


# ------------------------------------------------------------------------- lean ball solver
def _newton_setup(bearing, op, A1, A2, H_def, curve, wm_undropped):
    """(start in um, Newton step) of the ball problem: the damped Newton step of
    ``jones.solve_ball`` (step cap, never leave the outer raceway at speed)."""
    from .jones import UM, _static_ball_position, ball_newton_step

    x0, d_c = _static_ball_position(bearing, op, A1, A2, H_def, curve)
    _, full_step = ball_newton_step(bearing, op, A1, A2, H_def, curve, wm_undropped, d_c)

    def step(y):
        return full_step(y)[0]

    return x0 / UM, step


def _solve_ball_fixed(bearing, op, A1, A2, H_def, curve, wm_undropped, iterations):
    """Ball-centre position (m) after ``iterations`` damped Newton steps from the omega = 0
    closed form (the Newton step of ``jones.solve_ball`` without its while loop and implicit
    differentiation): cheap enough for the right-hand side of the time integration."""
    from .jones import UM

    y0, step = _newton_setup(bearing, op, A1, A2, H_def, curve, wm_undropped)
    y = jax.lax.fori_loop(0, iterations, lambda _, y: step(y), y0, unroll=True)
    return y * UM


def _undropped_speed(bearing, op, a1, a2, curve):
    from .jones import _static_ball_position, ball_state

    xu, _ = _static_ball_position(bearing, op, a1, a2, 0.0, curve)
    return ball_state(bearing, op, xu, a1, a2, 0.0, curve).omega_m


def balls_fixed(bearing, op, q, psi, spall, curve, iterations=3):
    """Like ``jones.balls_at`` with a fixed number of Newton steps per ball.  A ball carried
    by the cage over the spall gets the orbital speed of its undropped omega = 0 closed-form
    position (``jones.balls_at`` solves the undropped ball exactly; the difference only enters
    the F_c / M_g of a ball that has lost its inner contact)."""
    from .defect import depth_profile
    from .jones import _static_ball_position, ball_state, groove_centre_offsets

    A1, A2 = groove_centre_offsets(bearing, q, psi)
    H_def = jnp.zeros_like(psi) if spall is None else depth_profile(bearing, spall, psi)

    def one(a1, a2, h):
        wm0 = None if spall is None else _undropped_speed(bearing, op, a1, a2, curve)
        x = _solve_ball_fixed(bearing, op, a1, a2, h, curve, wm0, iterations)
        return ball_state(bearing, op, x, a1, a2, h, curve, wm0)

    return jax.vmap(one)(A1, A2, H_def)


_MAX_ITER = 8
_ITER_TOL = 1e-7     # relative (to the largest ball load) accuracy required of the lean solver


def _lean_errors(bearing, op, q, spall, curve, angles, scales):
    """Max relative ball-load error of the lean solver after 1.._MAX_ITER Newton steps, over
    cage angles x displacement scalings (vs jones.balls_at)."""
    from .jones import _static_ball_position, ball_state, groove_centre_offsets
    from .defect import depth_profile

    def at(th, s):
        qq = q * s
        psi = bearing.ball_azimuths(th)
        ref, _ = balls_at(bearing, op, qq, psi, spall, curve)
        A1, A2 = groove_centre_offsets(bearing, qq, psi)
        H = jnp.zeros_like(psi) if spall is None else depth_profile(bearing, spall, psi)

        def hist(a1, a2, h):
            from .jones import UM
            wm0 = None if spall is None else _undropped_speed(bearing, op, a1, a2, curve)
            y0, step = _newton_setup(bearing, op, a1, a2, h, curve, wm0)
            _, ys = jax.lax.scan(lambda y, _: (lambda yn: (yn, yn))(step(y)), y0, None,
                                 length=_MAX_ITER)
            return jax.vmap(lambda x: ball_state(bearing, op, x * UM, a1, a2, h, curve, wm0))(ys)

        st = jax.vmap(hist)(A1, A2, H)         # (Z, N) fields
        scale = jnp.maximum(jnp.max(ref.Q_o), jnp.max(ref.Q_i)) + 1e-30
        err = jnp.maximum(jnp.max(jnp.abs(st.Q_o - ref.Q_o[:, None]), axis=0),
                          jnp.max(jnp.abs(st.Q_i - ref.Q_i[:, None]), axis=0))
        return err / scale

    errs = jax.vmap(lambda th: jax.vmap(lambda s: at(th, s))(scales))(angles)
    return jnp.max(errs, axis=(0, 1))


_lean_errors_jit = eqx.filter_jit(_lean_errors)


def choose_iterations(bearing, op, q, spall, curve, theta0=0.0, tol=_ITER_TOL):
    """Smallest number of lean Newton steps whose ball loads match ``jones.balls_at`` to ``tol``
    (relative to the largest load) over one ball pitch of cage angles (and with a ball over the
    spall centre) at displacements q x (0.95, 1, 1.05); 0 (use balls_at) if none <= 8 does."""
    Z = bearing.n_balls
    angles = theta0 + np.linspace(0.0, 2 * np.pi / Z, 12, endpoint=False)
    if spall is not None:
        angles = np.concatenate([angles, [float(spall.center)]])
    scales = jnp.array([0.95, 1.0, 1.05])
    errs = np.asarray(_lean_errors_jit(bearing, op, q, spall, curve, jnp.asarray(angles), scales))
    ok = np.flatnonzero(errs <= tol)
    return int(ok[0]) + 1 if ok.size else 0
