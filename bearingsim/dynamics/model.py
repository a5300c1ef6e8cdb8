"""The shaft/housing model (docs/model.md section 7): its right-hand side, its equilibrium at t = 0
and its linear modes.

Degrees of freedom (10 states, SI): shaft / inner-ring translations ``x_s, y_s, z_s`` (mass
``m_s``), housing / outer-ring translations ``x_h, y_h`` (mass ``m_h``) on a support of stiffness
``k_h`` and damping ``c_h``, and their velocities::

    m_s a_s = F_ext + F_u(t) - R - C_b v_rel                        (x, y, z)
    m_h a_h = R_xy + (C_b v_rel)_xy - k_h x_h - c_h v_h              (x, y)

``R`` is the load the balls carry (:func:`bearingsim.dynamics.bearing_force`) for the relative
ring displacement ``q_rel = [x_s - x_h, y_s - y_h, z_s, theta_x0, theta_y0]`` (tilts held at
their quasi-static values), the balls' azimuths and the defects where they are at that instant
(an inner spall turned with the shaft, a ball pit with its ball: :func:`bearingsim.physics.defect.advance`
with the run's shaft angle phi, so ``contact_depths(bearing, advance(spall, t, omega, omega_R),
psi)`` at constant speed); ``v_rel = v_s - [v_h, 0]``; ``C_b = diag(2 zeta_b sqrt(K_ii m_s))``
with K the quasi-static stiffness (contact damping); ``F_u = m_u e omega^2 [cos phi, sin phi,
0]`` an optional unbalance turning with the shaft.

Initial state: the model's own equilibrium at t = 0 by a quasi-Newton iteration from the
quasi-static displacement: the quasi-static stiffness as the first Jacobian, corrected by Broyden's
update at every step (no derivative of the ball solve is compiled).  The lean loads differ from the
exact ones by <= 1e-3 of the largest ball load, but the lean Jacobian can differ by far more: a
deep-groove bearing under a small axial load (10-25 N against 500-1000 N radial, issue 27) carries
it as the small difference of its contacts' axial components, and the lean axial stiffness was
10-80 % off the quasi-static one, so a plain chord iteration contracted by only 0.1-0.8 per step
(or stalled) and 6 steps left 1e-6 to 3 N.  Linear modes: the eigenvalues of the linearisation, assembled on the host from the same
stiffness, the masses and the damping.
"""
from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax import lax

from ..hostarrays import f64, host, xp
from ..physics.defect import advance, contact_depths
from ..physics.kinematics import Operation
from ..programs import jit
from ..xla import QUICK_COMPILE
from .ball_force import RECORD_ROWS, BallCarry, bearing_force, bearing_force_chord
from .parameters import DynamicsParameters

__all__ = ["DynamicModel", "build_model", "contact_damping", "damping_matrix", "initial_state", "linear_modes", "choose_substeps", "STEP_RHO"]

#: |lambda| h bound of substeps="auto"
STEP_RHO = 0.5
#: quasi-Newton (Broyden) steps of the initial equilibrium: superlinear once the Jacobian is
#: corrected; 8-11 steps on the hardest items measured (issue 27), each one lean ball solve
_INIT_STEPS = 16


class DynamicModel(eqx.Module):
    """Everything the right-hand side needs (every array may carry a batch axis under vmap).

    ``defects``: a tuple of :class:`bearingsim.Spall` at t = 0 (empty: healthy; a depth-0 member
    is inactive, so items of different classes can share one compiled program);
    ``spin_ratio``: the pit's spin speed relative to the cage per unit shaft speed."""

    bearing: object
    op: Operation
    defects: tuple
    curve: object
    loads: jnp.ndarray          # (5,) applied [Fx, Fy, Fz, Mx, My]
    tilts: jnp.ndarray          # (2,) quasi-static tilts held constant (rad)
    contact_damping: jnp.ndarray  # (3,) c_b in x, y, axial (N s/m)
    stiffness: jnp.ndarray      # (3, 3) quasi-static dR/dq of the translations (N/m)
    spin_ratio: jnp.ndarray     # omega_R / omega (-)
    params: DynamicsParameters
    iterations: int = eqx.field(static=True, default=1)
    #: a traced Newton step count in place of ``iterations`` (None: ``iterations``): the data
    #: engine compiles one time loop for every count of its menu
    iteration_count: jnp.ndarray | None = None

    @property
    def newton_steps(self):
        return self.iterations if self.iteration_count is None else self.iteration_count

    def depths(self, psi, phi):
        """(H_outer, H_inner) per ball at azimuths psi and shaft angle phi (None, None: healthy)."""
        if not self.defects:
            return None, None
        return contact_depths(self.bearing, advance(self.defects, phi, 1.0, self.spin_ratio), psi)

    def ring_load(self, xrel, stage, full_state=False):
        """[Fx, Fy, Fz] the balls carry at relative translations xrel (3,) and stage = (cage
        angle, shaft angle, shaft speed); ``full_state``: also the balls' per-ball record
        (RECORD_ROWS, Z) at the solve's last iterate: Q_inner, Q_outer and the sines and cosines
        of alpha_inner, alpha_outer (:func:`bearingsim.dynamics.record_loads_angles` gives the
        angles)."""
        th, phi, omega = stage[0], stage[1], stage[2]
        psi = self.bearing.ball_azimuths(th)
        q = jnp.concatenate([xrel, self.tilts])
        op = eqx.tree_at(lambda o: o.speed, self.op, omega)
        Ho, Hi = self.depths(psi, phi)
        out = bearing_force(self.bearing, op, self.curve, q, psi, Ho, Hi, self.newton_steps, record=full_state,
                            even_azimuths=True)
        return (out[0], out[1]) if full_state else out[0]

    def ring_load_chord(self, xrel, stage, carry: BallCarry, refresh):
        """:meth:`ring_load` with ``full_state`` by the chord method from the balls' carried
        state (:func:`bearingsim.dynamics.bearing_force_chord`): ([Fx, Fy, Fz], the balls'
        record (RECORD_ROWS, Z), the new carry); ``refresh``: solve in full (a defect edge)."""
        th, phi, omega = stage[0], stage[1], stage[2]
        psi = self.bearing.ball_azimuths(th)
        q = jnp.concatenate([xrel, self.tilts])
        op = eqx.tree_at(lambda o: o.speed, self.op, omega)
        Ho, Hi = self.depths(psi, phi)
        return bearing_force_chord(self.bearing, op, self.curve, q, psi, Ho, Hi, self.newton_steps, carry, refresh)

    def masses(self):
        """(5,) masses of [x_s, y_s, z_s, x_h, y_h]."""
        p = self.params
        ms, mh = f64(p.shaft_mass), f64(p.housing_mass)
        return xp(ms, mh).stack([ms] * 3 + [mh] * 2)

    def damping_matrix(self):
        """(5, 5) linear damping: contact damping C_b on v_rel and the support damping c_h."""
        return damping_matrix(self.contact_damping, self.params.housing_damping)

    def forces(self, x, stage, extra_x=0.0, full_state=False, chord=None):
        """(5,) position- and time-dependent forces on [shaft (3), housing (2)]: applied loads,
        unbalance, bearing load R, support spring; ``extra_x`` adds to the housing along x.
        ``full_state``: (forces, the balls' record (RECORD_ROWS, Z), see :meth:`ring_load`).
        ``chord``: (carry, refresh) -- the balls by :meth:`ring_load_chord`; returns (forces,
        record, new carry)."""
        p = self.params
        ph, w = stage[1], stage[2]
        xrel = jnp.stack([x[0] - x[3], x[1] - x[4], x[2]])
        if chord is not None:
            R, rec, bc = self.ring_load_chord(xrel, stage, *chord)
        else:
            R = self.ring_load(xrel, stage, full_state)
            R, rec = R if full_state else (R, None)
        Fu = p.unbalance * w * w * jnp.stack([jnp.cos(ph), jnp.sin(ph), jnp.zeros_like(ph)])
        Fs = self.loads[:3] + Fu - R
        Fh = R[:2] - p.housing_stiffness * x[3:5] + jnp.stack([extra_x, 0.0 * extra_x])
        F = jnp.concatenate([Fs, Fh])
        if chord is not None:
            return F, rec, bc
        return (F, rec) if full_state else F

    def rhs(self, y, stage, extra_x=0.0):
        """dy/dt for y = [x_s (3), x_h (2), v_s (3), v_h (2)]."""
        x, v = y[:5], y[5:]
        a = (self.forces(x, stage, extra_x) - self.damping_matrix() @ v) / self.masses()
        return jnp.concatenate([v, a])


def damping_matrix(cb, ch):
    """(5, 5) damping of [x_s, y_s, z_s, x_h, y_h] from the contact damping cb (3,) on the
    shaft-housing motion and the support damping ch (NumPy on the host, JAX in a trace:
    :mod:`bearingsim.hostarrays`; negations and one sum, the same values either way)."""
    xn = xp(cb, ch)
    cb, ch = f64(cb), f64(ch)
    c0, c1, c2 = cb[..., 0], cb[..., 1], cb[..., 2]
    z = xn.zeros_like(c0)
    rows = ((c0, z, z, -c0, z), (z, c1, z, z, -c1), (z, z, c2, z, z), (-c0, z, z, c0 + ch, z), (z, -c1, z, z, c1 + ch))
    return xn.stack([xn.stack(r, -1) for r in rows], -2)


def contact_damping(Kt, ratio, mass):
    """Contact damping 2 zeta sqrt(K m) per shaft direction from the bearing stiffness (NumPy
    on the host, JAX in a trace; correctly rounded operations, the same values either way)."""
    xn = xp(Kt, ratio, mass)
    Kt, ratio, mass = f64(Kt), f64(ratio), f64(mass)
    K = xn.diagonal(Kt, axis1=-2, axis2=-1)
    return 2.0 * ratio[..., None] * xn.sqrt(xn.maximum(K, 0.0) * mass[..., None])


def build_model(bearing, op, loads, defects, sol, params: DynamicsParameters, curve, iterations,
                spin_ratio=0.0):
    """DynamicModel from the quasi-static solution ``sol`` (its tilts, stiffness and the contact
    damping built from it); ``defects``: a tuple of Spall (see :class:`DynamicModel`)."""
    # a concrete solution's arrays read into NumPy: no eager operation on the host
    q = host(sol.displacement)
    Kt = host(sol.stiffness)[..., :3, :3]
    cb = contact_damping(Kt, params.contact_damping_ratio, params.shaft_mass)
    loads = f64(host(loads))
    spin = f64(host(spin_ratio))
    return DynamicModel(bearing, op, tuple(defects), curve, loads, q[..., 3:5], cb, Kt,
                        spin + xp(spin, q).zeros(np.shape(q)[:-1]),
                        params, *((int(iterations), None) if isinstance(iterations, (int, np.integer))
                                  else (1, jnp.asarray(iterations, jnp.int32))))


def initial_state(model: DynamicModel, q_rel0, stage0):
    """Equilibrium of the lean model at t = 0 from the quasi-static displacement (quasi-Newton on
    the 3 translations: the quasi-static stiffness as the first Jacobian, Broyden's update after
    every step): (y0, converged, dy/dt at y0, the
    balls' record (RECORD_ROWS, Z) there, see :meth:`DynamicModel.ring_load`).

    The housing sits at its static support deflection and everything is at rest, so dy/dt at
    y0 follows from the last residual r = R - F (shaft: -r plus the unbalance; housing: r_xy):
    the ball solve is compiled once."""
    F = model.loads[:3]
    J = model.stiffness
    J = J + 1e-12 * jnp.max(jnp.abs(J)) * jnp.eye(3)

    scale = jnp.max(jnp.abs(F)) + 1.0
    tol = 1e-9 * scale

    def newton(_, c):
        x0, r0, dx, J, _ = c
        x = x0 + dx                               # the previous iterate's step
        R, rec = model.ring_load(x, stage0, full_state=True)
        r = R - F
        # Broyden's (good) update with the step just taken; none before the first step, nor once
        # converged (a step at round-off level would fill J with noise)
        dd = jnp.dot(dx, dx)
        upd = (dd > 0.0) & (jnp.max(jnp.abs(r0)) > tol)
        Jn = J + jnp.outer(r - r0 - J @ dx, dx) / jnp.where(dd > 0.0, dd, 1.0)
        J = jnp.where(upd & jnp.all(jnp.isfinite(Jn)), Jn, J)
        step = -jnp.linalg.solve(J, r)
        return x, r, jnp.where(jnp.all(jnp.isfinite(step)), step, 0.0), J, rec

    # the balls' record rides along (it is the last evaluation's, at the returned x): one ball
    # solve in the program instead of a second one after the loop
    Z = model.bearing.n_balls
    x, r, _, _, rec = lax.fori_loop(0, _INIT_STEPS, newton,
                                    (q_rel0, jnp.zeros(3), jnp.zeros(3), J, jnp.zeros((RECORD_ROWS, Z))))
    ok = jnp.all(jnp.isfinite(x)) & jnp.all(jnp.isfinite(r)) & (jnp.max(jnp.abs(r)) <= tol)
    p = model.params
    xh = model.loads[:2] / p.housing_stiffness
    y0 = jnp.concatenate([x[:2] + xh, x[2:3], xh, jnp.zeros(5)])
    ph, w = stage0[1], stage0[2]
    Fu = p.unbalance * w * w * jnp.stack([jnp.cos(ph), jnp.sin(ph), jnp.zeros_like(ph)])
    acc = jnp.concatenate([(Fu - r) / p.shaft_mass, r[:2] / p.housing_mass])
    return y0, ok, jnp.concatenate([jnp.zeros(5), acc]), rec


initial_state_jit = jit(initial_state, options=QUICK_COMPILE)     # once per simulation: -O0 (bearingsim.xla)


def linear_modes(model: DynamicModel):
    """Eigenvalues (rad/s, complex) of the shaft/housing model linearised at its equilibrium, on
    the host: K the quasi-static translational stiffness of the bearing, k_h the support."""
    K = np.asarray(model.stiffness, float)
    kh = float(model.params.housing_stiffness)
    Kf = np.zeros((5, 5))
    Kf[:3, :3] = K
    Kf[:3, 3:] = -K[:, :2]
    Kf[3:, :3] = -K[:2, :]
    Kf[3:, 3:] = K[:2, :2] + kh * np.eye(2)
    m = np.asarray(model.masses(), float)
    C = np.asarray(model.damping_matrix(), float)
    A = np.block([[np.zeros((5, 5)), np.eye(5)], [-Kf / m[:, None], -C / m[:, None]]])
    return np.linalg.eigvals(A)


def choose_substeps(lam_max, sample_rate, rho=STEP_RHO):
    """Smallest number of steps per sample with |lambda|_max h <= rho."""
    return max(1, int(math.ceil(float(lam_max) / (rho * float(sample_rate)))))
