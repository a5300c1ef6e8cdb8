"""Jones (1960) quasi-static model in Harris' form with raceway defects (docs/model.md sections 3-5):
one flat Newton on all 2Z + 5 unknowns.

Design
------
* Unknowns: the ring displacement q (5) and every ball centre (X1, X2) (Z x 2), plus, when a
  defect is present, every ball's undropped centre (its orbital speed is the one the cage
  carries a ball at when it loses inner contact over the defect, docs/model.md section 5).
* One Newton iteration evaluates every ball's residuals and loads on the ring together with
  their Jacobian with respect to (X1, X2, A1, A2) (``jax.jacfwd`` of one ball's equations from
  :mod:`bearingsim.physics.balls`, vmapped over balls), eliminates the 2x2 ball blocks (Schur complement
  on the 5 ring unknowns: one 5x5 solve) and back-substitutes the ball steps.  Steps are capped
  (200 um on the ring, 2e-3 D on a ball) and a ball at speed is never left off its outer raceway.
  A single ``lax.while_loop`` does Newton steps and backtracking (each pass evaluates one trial
  point), so the model is traced once; under ``vmap`` it runs as a masked fixed-shape loop.
* Start: the rigid-ring static solution (omega = 0; balls from the closed form, exact at rest),
  from an axial shift where every ball touches; then the operating speed (``speed_steps``
  stages).  Warm starts (a previous cage angle or load case) skip the static stage.
* At the converged state a last Newton correction with frozen Jacobian makes the solution
  implicitly differentiable (``jax.grad``/``jacfwd`` through :func:`solve_state` give the
  implicit-function-theorem derivatives) and gives the stiffness dR/dq (the Schur complement).
* Validity (never a silent wrong answer): a converged state is re-checked from its per-ball
  output -- finite, no loaded contact with |alpha| >= 90 deg, every ball and the ring in
  equilibrium, contact deformations <= 1 % of D and ring translations within twice the
  groove-centre distance plus that, no angular contact bearing loaded against its low shoulders
  (F_z < 0 or a loaded contact at or beyond a low shoulder), no loaded contact centred at or
  beyond any other groove edge (``over_shoulder``, healthy or with a defect: the one rule of
  :func:`shoulder_crossings`), not all loads zero at speed -- and otherwise carries its own
  result code.  Every solver (this one, :mod:`bearingsim.physics.shaft`, the sweeps) uses this check, so
  the Python API and the command line give the same verdict.  Contact pressures above 4.2 GPa
  are a warning (ISO 76 static-capacity stress: permanent deformation ~1e-4 D starts there).

* Tilt ``free`` or ``held`` (a static setting, one program each): ``free`` (the default) solves
  all 5 ring DOF under the applied [Fx, Fy, Fz, Mx, My] (a force-controlled inner ring: with no
  moment a radial load tilts it); ``held`` fixes the tilts at zero (displacement control, the
  usual spindle assumption: the shaft holds the ring square), solves the 3 translations under
  [Fx, Fy, Fz] -- the same Newton with the tilt unknowns and the moment equations left out (the
  3x3 translational block of the Schur complement) -- and reports in ``loads[3:5]`` the moments
  that hold the tilt (the moment sum of the contact forces about the ring centre).  The state is
  then a free state under those moments, so the same validity rule judges it.

Unknowns are scaled to micrometres (tilts as micrometres at the groove-centre radius R_i),
residuals to kN (moments divided by R_i), so one tolerance fits every DOF.
"""
from __future__ import annotations

import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from .balls import (KN, UM, BallState, ball_equations, ball_state, balls_at, groove_centre_offsets,
                    inverse2, lift_onto_outer, offset_jacobian, orbital_speed, reaction_matrix,
                    reactions_from_balls, static_ball_position)
from .defect import Spall, canonical_defects, contact_depths
from ..errors import failed, InputError, InputTypeError, InvalidStateError, NotConvergedError, ResultCode, succeeded
from .hertz import contact_ellipse, power_eval, stiffness_curve
from .kinematics import Operation
from .newton import (BALL_CAP, RING_CAP, accept_step, better, cap_step, max_abs, retry_failed, speed_stages,
                     step_status, traced_tolerances)
from ..hostarrays import f64, host, xp
from ..programs import jit
from ..xla import QUICK_COMPILE

__all__ = [
    "RESULTS",
    "JonesSolution",
    "NotConvergedError",
    "InvalidStateError",
    "OverloadWarning",
    "load_vector",
    "Loads",
    "initial_displacement",
    "ring_reactions",
    "solve_state",
    "solve",
    "solve_batch",
    "state_validity",
    "shoulder_crossings",
    "raise_for",
    "result_hint",
    "DEFORMATION_LIMIT",
    "PRESSURE_WARNING",
    "GROOVE_BOTTOM_ANGLE",
    "TILT_MODES",
    "tilt_held",
]

#: largest contact deformation a valid state may hold, as a fraction of the ball diameter D.
#: Hertz theory is a small-strain, half-space theory; at 1 % of D the peak pressure is 6-8 GPa
#: (Harris 218: 6.6 GPa), 1.5-2x the 4.2 GPa static-capacity stress: the steel has yielded.
DEFORMATION_LIMIT = 0.01
#: peak contact pressure (Pa) above which a state is flagged ``overloaded`` (a warning): the
#: ISO 76 basic static load rating stress of ball bearings, where permanent deformation of
#: ~1e-4 D begins.
PRESSURE_WARNING = 4.2e9
#: how the inner ring's tilt is treated (a static setting): "free" (force-controlled: the applied
#: moments Mx, My, tilts solved) or "held" (displacement-controlled tilt of zero: translations
#: solved under Fx, Fy, Fz, the holding moments reported in ``JonesSolution.loads[3:5]``)
TILT_MODES = ("free", "held")


class RESULTS(ResultCode):
    """Result codes of a quasi-static solve (``JonesSolution.result``)."""

    successful = (0, "converged", "")
    max_iterations = (1, "maximum number of Newton iterations reached",
                      "raise maxit, or approach the operating point in more speed_steps")
    nonfinite = (2, "non-finite value in the residual or Jacobian",
                 "check the inputs (geometry, loads) for NaN or extreme values")
    stagnated = (3, "line search could not reduce the residual (stagnated above tolerance)",
                 "a single-row angular contact bearing needs axial load in its contact direction "
                 "to carry radial load and moments; check the loads, or lower the speed")
    inverted_contact = (4, "a loaded contact has its normal pointing out of its raceway "
                        "(|alpha| >= 90 deg, docs/model.md section 3): a spurious root",
                        "the loads cannot be carried with every contact pressing into its raceway; "
                        "check the load directions and the defect depth")
    equilibrium = (5, "a ball or the ring is not in equilibrium when recomputed from the "
                   "per-ball output", "tighten rtol/atol, or report the case: this is a solver bug")
    beyond_bounds = (6, "contact deformation beyond 1 % of the ball diameter, or ring displacement "
                     "beyond the clearance: outside what Hertz theory and the steel can carry",
                     "the loads exceed the bearing's capacity by far; check their units (N, N m)")
    low_shoulder = (7, "the load pushes the balls of an angular contact bearing against its low shoulders "
                    "(axial load against the contact direction, or too little of it for the radial load "
                    "or moment: a loaded contact lies at or beyond a low shoulder, or the loaded balls sit "
                    "at the bottom of the groove)",
                    "a single angular contact bearing carries axial load in one direction only (+Fz, its "
                    "contact direction); for a negative or reversing axial load use a preloaded pair "
                    "(DB back-to-back or DF face-to-face), or turn the bearing round (Fz > 0)")
    over_shoulder = (8, "a loaded contact lies beyond the edge of its groove (contact angle above the "
                     "shoulder angle): the ball rides on the shoulder edge, outside the model",
                     "contact angles climb with the axial load and, at speed, on lightly loaded balls "
                     "(the centrifugal force moves the outer contact down, the inner one up): reduce the "
                     "axial load or the moment, keep the balls loaded at speed (a preloaded pair), or "
                     "check the shoulder angles ([shoulders] keys of the case)")
    no_load = (9, "no load on the inner ring at speed: the balls ride on the outer raceway under their "
               "centrifugal force alone, nothing drives them and the ring's position is undetermined",
               "give a load; at rest zero load is the unloaded bearing (q = 0, no ball load)")


def load_vector(axial=0.0, radial_x=0.0, radial_y=0.0, moment_x=0.0, moment_y=0.0):
    """Applied inner-ring loads as the solver's vector [Fx, Fy, Fz, Mx, My] (N, N m)."""
    v = (radial_x, radial_y, axial, moment_x, moment_y)
    return xp(*v).stack([f64(c) for c in v])


Loads = load_vector


class OverloadWarning(UserWarning):
    """Contact pressure above :data:`PRESSURE_WARNING`: valid for the model, not for the steel."""


def tilt_held(tilt) -> bool:
    """Whether ``tilt`` (one of :data:`TILT_MODES`) holds the ring's tilt at zero; anything else
    is an :class:`~bearingsim.errors.InputError` naming the allowed values."""
    if not isinstance(tilt, str) or tilt not in TILT_MODES:
        cls = InputError if isinstance(tilt, str) else InputTypeError
        raise cls(f"tilt = {tilt!r} is not a tilt mode: must be one of " + ", ".join(repr(t) for t in TILT_MODES),
                  "\"free\": the applied moments act and the tilts are solved (a force-controlled inner "
                  "ring); \"held\": the tilts are held at zero (a shaft that keeps the ring square) and the "
                  "moments that hold them are reported")
    return tilt == "held"


def _check_held_loads(loads, tilt):
    """A held tilt takes no applied moment (the moments are its outputs): refuse one."""
    if tilt_held(tilt) and np.any(np.asarray(loads)[..., 3:5] != 0.0):
        raise InputError("loads Mx, My must be 0 with tilt = 'held' (got "
                         f"{np.asarray(loads)[..., 3:5].tolist()} N m): a held tilt is displacement-"
                         "controlled, the moments are its result (JonesSolution.loads[3:5])",
                         "give Mx = My = 0 with tilt = 'held', or use tilt = 'free' to apply moments")


def _scales(bearing):
    Ri = bearing.inner_groove_radius
    qs = jnp.stack([UM, UM, UM, UM / Ri, UM / Ri])
    rs = jnp.stack([KN, KN, KN, KN * Ri, KN * Ri])
    return qs, rs


def initial_displacement(bearing, loads, curve):
    """A start where every ball touches: an axial shift giving each ball the deflection that
    would carry the whole load (no contact at all has a zero Jacobian)."""
    a0 = bearing.free_contact_angle
    BD = bearing.A
    Ri = bearing.inner_groove_radius
    Fz = loads[2]
    Fmag = jnp.abs(Fz) + jnp.hypot(loads[0], loads[1]) + 2.0 * jnp.hypot(loads[3], loads[4]) / Ri
    c0 = jnp.cos(a0)
    Ki, Ko = power_eval(curve.inner_power, c0), power_eval(curve.outer_power, c0)
    Kn = (Ki ** (-2.0 / 3.0) + Ko ** (-2.0 / 3.0)) ** (-1.5)
    d_n = (Fmag / (bearing.n_balls * Kn)) ** (2.0 / 3.0)
    sgn = jnp.where(Fz < 0.0, -1.0, 1.0)
    dz = sgn * jnp.sqrt(jnp.maximum((BD + d_n) ** 2 - (BD * c0) ** 2, 0.0)) - BD * jnp.sin(a0)
    dz = jnp.where(Fmag > 0.0, dz, 0.0)
    return jnp.array([0.0, 0.0, 1.0, 0.0, 0.0]) * dz


def _defect_depths(bearing, spall, psi):
    """(H_outer, H_inner) under each ball, or (None, None) when healthy: ``spall`` is None, a
    :class:`Spall` (outer, inner or ball, docs/model.md sections 5 and 9) or a tuple of them."""
    return contact_depths(bearing, spall, psi)


# ----------------------------------------------------------------------------- Newton system
class _Problem(eqx.Module):
    """Everything fixed during one solve (arrays; the defect depths are per ball)."""

    bearing: object
    op: Operation
    curve: object
    psi: jnp.ndarray
    H_outer: jnp.ndarray
    H_inner: jnp.ndarray
    Fn: jnp.ndarray                  # scaled applied loads
    qs: jnp.ndarray
    rs: jnp.ndarray
    defect: bool = eqx.field(static=True)
    held: bool = eqx.field(static=True, default=False)


def _per_ball(pb: _Problem, Y, a, ho, hi, ws, jac):
    v = jnp.concatenate([Y, a])
    if not jac:
        out, wm = ball_equations(pb.bearing, pb.op, pb.curve, v, ho, hi, ws)
        return out, None, wm

    def f(v):
        out, wm = ball_equations(pb.bearing, pb.op, pb.curve, v, ho, hi, ws)
        return out, (out, wm)

    J, (out, wm) = jax.jacfwd(f, has_aux=True)(v)
    return out, J, wm


def _evaluate(pb: _Problem, qz, Y, Yu, jac=True):
    """Residuals (and, with ``jac``, the Jacobian blocks) at (q, balls): a dict of pieces."""
    q = qz * pb.qs
    A1, A2 = groove_centre_offsets(pb.bearing, q, pb.psi)
    a = jnp.stack([A1, A2], axis=-1) / UM
    piece = {}
    if pb.defect:
        # the undropped balls (no defect) and the dropped ones in one vmapped evaluation over 2Z
        # balls (one copy of the ball equations' Jacobian in the program, not two); a dropped
        # ball without inner contact is carried at its undropped twin's orbital speed, which
        # depends on the contact angles only (no derivative flows through it); an undropped
        # ball (depth 0) is never carried, so the speed passed to it has no effect
        Z = pb.psi.shape[0]
        ws = lax.stop_gradient(jax.vmap(lambda y, aa: orbital_speed(
            pb.bearing, pb.op, y[0] * UM, y[1] * UM, aa[0] * UM, aa[1] * UM))(Yu, a))
        zero = jnp.zeros_like(pb.H_outer)
        out2, J2, _ = jax.vmap(lambda y, aa, ho, hi, w: _per_ball(pb, y, aa, ho, hi, w, jac))(
            jnp.concatenate([Yu, Y]), jnp.concatenate([a, a]), jnp.concatenate([zero, pb.H_outer]),
            jnp.concatenate([zero, pb.H_inner]), jnp.concatenate([ws, ws]))
        out_u, out = out2[:Z], out2[Z:]
        piece["rbu"] = out_u[:, :2]
        if jac:
            J_u, J = J2[:Z], J2[Z:]
            piece.update(Jbbu=J_u[:, :2, :2], Jbau=J_u[:, :2, 2:])
    else:
        out, J, _ = jax.vmap(lambda y, aa, ho, hi: _per_ball(pb, y, aa, ho, hi, None, jac))(
            Y, a, pb.H_outer, pb.H_inner)
    T = reaction_matrix(pb.psi)                                   # (Z, 5, 3)
    piece["rq"] = jnp.einsum("zij,zj->i", T, out[:, 2:]) - pb.Fn
    if pb.held:         # the moment equations are not equations of a held tilt: its moments are free
        piece["rq"] = jnp.concatenate([piece["rq"][:3], jnp.zeros(2)])
    piece["rb"] = out[:, :2]
    if jac:
        piece.update(Jbb=J[:, :2, :2], Jba=J[:, :2, 2:], Cx=J[:, 2:, :2], Ca=J[:, 2:, 2:])
    return piece


_JAC_KEYS = ("Jbb", "Jba", "Cx", "Ca", "Jbbu", "Jbau")


def _zero_piece(n_balls, defect):
    """Zeros shaped like :func:`_evaluate`'s pieces (with the Jacobian blocks), without tracing
    it again (each trace of the ball equations' Jacobian costs ~0.3 s of every compilation)."""
    Z = n_balls
    shapes = dict(rq=(5,), rb=(Z, 2), Jbb=(Z, 2, 2), Jba=(Z, 2, 2), Cx=(Z, 3, 2), Ca=(Z, 3, 2))
    if defect:
        shapes.update(rbu=(Z, 2), Jbbu=(Z, 2, 2), Jbau=(Z, 2, 2))
    return {k: jnp.zeros(v, jnp.float64) for k, v in shapes.items()}


def _merit(piece):
    return max_abs(piece["rq"], piece["rb"], piece.get("rbu"))


def _direction(pb: _Problem, piece, jac=None):
    """Newton step (dqz, dY, dYu) with the ball blocks eliminated, and the scaled stiffness S.
    ``jac``: Jacobian blocks to use instead of the piece's own (frozen, for the implicit
    derivative: then the derivative flows through the residuals only)."""
    jac = piece if jac is None else jac
    Jbb, Jba, Cx, Ca = (jac[k] for k in ("Jbb", "Jba", "Cx", "Ca"))
    T = reaction_matrix(pb.psi)                                   # (Z, 5, 3)
    P = offset_jacobian(pb.bearing, pb.psi) * (pb.qs / UM)        # (Z, 2, 5) dA(um)/dqz
    inv = inverse2(Jbb)                                           # (Z, 2, 2)
    M = Cx @ inv                                                  # (Z, 3, 2)
    S = jnp.einsum("zij,zjk,zkl->il", T, Ca - M @ Jba, P)         # (5, 5) scaled dR/dq
    rhs = piece["rq"] - jnp.einsum("zij,zjk,zk->i", T, M, piece["rb"])
    mu = 1e-13 * (jnp.max(jnp.abs(S)) + 1e-30)
    if pb.held:         # the 3 translations only (the translational block); the tilts stay at 0
        dq = jnp.concatenate([-jnp.linalg.solve(S[:3, :3] + mu * jnp.eye(3), rhs[:3]), jnp.zeros(2)])
    else:
        dq = -jnp.linalg.solve(S + mu * jnp.eye(5), rhs)
    dA = jnp.einsum("zij,j->zi", P, dq)
    dY = -jnp.einsum("zij,zj->zi", inv, piece["rb"] + jnp.einsum("zij,zj->zi", Jba, dA))
    dYu = None
    if "rbu" in piece:
        invu = inverse2(jac["Jbbu"])
        dYu = -jnp.einsum("zij,zj->zi", invu,
                          piece["rbu"] + jnp.einsum("zij,zj->zi", jac["Jbau"], dA))
    return dq, dY, dYu, S


def _closed_form_balls(pb: _Problem, qz, defect_free=False):
    """Closed-form (omega = 0) ball centres (um) and the outer deflection that carries each
    ball's centrifugal force (m)."""
    A1, A2 = groove_centre_offsets(pb.bearing, qz * pb.qs, pb.psi)
    Ho = jnp.zeros_like(pb.psi) if defect_free else pb.H_outer
    Hi = jnp.zeros_like(pb.psi) if defect_free else pb.H_inner
    x0, d_c = jax.vmap(lambda a1, a2, ho, hi: static_ball_position(
        pb.bearing, pb.op, a1, a2, pb.curve, ho, hi))(A1, A2, Ho, Hi)
    return x0 / UM, d_c


def _newton(pb: _Problem, qz0, Y0, Yu0, d_c, d_cu, maxit, tol):
    """Damped Newton from (qz0, Y0, Yu0): one while loop whose every pass evaluates one trial
    point (the first pass: the start); an accepted trial brings the next direction.
    Returns (qz, Y, Yu, Jacobian blocks at the accepted point, code, iterations)."""
    bearing = pb.bearing
    ball_cap = BALL_CAP * bearing.ball_diameter / UM
    defect = pb.defect

    def direction(piece):
        dq, dY, dYu, _ = _direction(pb, piece)
        # length of the full Newton step (scaled um): the natural-monotonicity measure
        sn = max_abs(dq, dY, dYu)
        return cap_step(dq, RING_CAP), cap_step(dY, ball_cap), (
            None if dYu is None else cap_step(dYu, ball_cap)), sn

    def body(c):
        first = c["it"] < 0
        t = c["t"]
        qz = c["qz"] + t * c["dq"]
        Y = lift_onto_outer(bearing, c["Y"] + t * c["dY"], d_c, pb.H_outer)
        Yu = lift_onto_outer(bearing, c["Yu"] + t * c["dYu"], d_cu, 0.0) if defect else None
        piece = _evaluate(pb, qz, Y, Yu)
        m = _merit(piece)
        dq, dY, dYu, sn = direction(piece)
        finite = jnp.isfinite(m) & jnp.isfinite(sn)
        # natural monotonicity (Deuflhard): the simplified Newton correction (old Jacobian, new
        # residual) must shrink; or the residual must.  The residual alone mixes ball and ring
        # scales and rejects good full steps.
        sq, sY, sYu, _ = _direction(pb, piece, c["jac"])
        ss = max_abs(sq, sY, sYu if defect else None)
        ok = accept_step(c, first, finite, t, m, ss)
        sel = lambda new, old: jax.tree_util.tree_map(lambda u, v: jnp.where(ok, u, v), new, old)
        jac = {k: piece[k] for k in _JAC_KEYS if k in piece}
        new = dict(qz=qz, Y=Y, dq=dq, dY=dY, m=m, sn=sn, jac=jac)
        if defect:
            new.update(Yu=Yu, dYu=dYu)
        out = step_status(sel(new, {k: c[k] for k in new}), c, ok, t, first, finite, tol, maxit)
        if not defect:
            out.update(Yu=c["Yu"], dYu=c["dYu"])
        return out

    zeros = _zero_piece(bearing.n_balls, defect)
    init = dict(qz=qz0, Y=Y0, Yu=Y0 if Yu0 is None else Yu0, dq=jnp.zeros_like(qz0),
                dY=jnp.zeros_like(Y0), dYu=jnp.zeros_like(Y0), m=jnp.float64(jnp.inf),
                sn=jnp.float64(jnp.inf), t=jnp.float64(1.0), it=jnp.int32(-1), ls=jnp.int32(0),
                code=jnp.int32(-1), jac={k: zeros[k] for k in _JAC_KEYS if k in zeros})
    c = lax.while_loop(lambda c: c["code"] < 0, body, init)
    return c["qz"], c["Y"], c["Yu"], c["jac"], c["code"], c["it"]


# -------------------------------------------------------------------------------- solution
class JonesSolution(eqx.Module):
    """Quasi-static solution.  Arrays are SI (m, rad, N, N m, rad/s); per-ball arrays are (Z,)
    (with a leading batch axis after ``solve_batch`` or a sweep).

    ``result`` is a :class:`RESULTS` code (0 = converged and valid); ``residual_norm`` is the
    max-norm of the equilibrium residual in N (moments divided by R_i), balls included.
    ``stiffness`` is dR/dq (5, 5): rows the loads [Fx, Fy, Fz, Mx, My], columns the ring
    displacements [x, y, axial, tilt_x, tilt_y] (N/m, N/rad, N m/m, N m/rad).
    ``tilt`` (static): "free" (``loads`` as applied, tilts solved) or "held" (tilts 0;
    ``loads[3:5]`` are the moments that hold them, the moment sum of the contact forces about the
    ring centre; the translational 3x3 block ``stiffness[:3, :3]`` is the stiffness of the held
    ring, the full 5x5 the tangent of the 5-DOF bearing at that state).
    """

    displacement: jnp.ndarray       # q = [dx, dy, dz, theta_x, theta_y]
    loads: jnp.ndarray              # applied [Fx, Fy, Fz, Mx, My]
    result: jnp.ndarray
    iterations: jnp.ndarray
    residual_norm: jnp.ndarray
    cage_angle: jnp.ndarray
    azimuth: jnp.ndarray
    alpha_inner: jnp.ndarray
    alpha_outer: jnp.ndarray
    Q_inner: jnp.ndarray
    Q_outer: jnp.ndarray
    delta_inner: jnp.ndarray
    delta_outer: jnp.ndarray
    centrifugal: jnp.ndarray
    gyroscopic_moment: jnp.ndarray
    orbital_speed: jnp.ndarray
    beta: jnp.ndarray
    spall_depth: jnp.ndarray        # H_outer: defect depth at each ball's outer contact (m)
    ball_G: jnp.ndarray
    ball_H: jnp.ndarray
    ball_moment: jnp.ndarray
    K_inner: jnp.ndarray
    K_outer: jnp.ndarray
    p_max_inner: jnp.ndarray
    p_max_outer: jnp.ndarray
    a_inner: jnp.ndarray
    b_inner: jnp.ndarray
    a_outer: jnp.ndarray
    b_outer: jnp.ndarray
    stiffness: jnp.ndarray
    ball_position: jnp.ndarray      # (Z, 2) ball centres (X1, X2) from the outer groove centre (m)
    undropped_position: jnp.ndarray  # (Z, 2) the same without the defect (warm starts)
    spall_depth_inner: jnp.ndarray  # H_inner: defect depth at each ball's inner contact (m)
    tilt: str = eqx.field(static=True, default="free")  # TILT_MODES: "held": loads[3:5] hold it at 0

    @property
    def converged(self):
        """True where the state converged and passed every validity check."""
        return succeeded(self.result)

    @property
    def cage_speed(self):
        """Cage speed omega_c (rad/s): the mean of the balls' orbital speeds."""
        w = host(self.orbital_speed)
        return xp(w).mean(w, axis=-1)

    @property
    def max_pressure(self):
        """Largest Hertz peak pressure over both contacts of every ball (Pa)."""
        pi, po = host(self.p_max_inner), host(self.p_max_outer)
        x = xp(pi, po)
        return x.maximum(x.max(pi, axis=-1), x.max(po, axis=-1))

    @property
    def overloaded(self):
        """True where a contact pressure exceeds :data:`PRESSURE_WARNING` (a warning)."""
        return host(self.max_pressure) > PRESSURE_WARNING

    def message(self):
        """One message per item (a list, also for a single solve)."""
        codes = np.atleast_1d(np.asarray(self.result))
        return [RESULTS.of(c).message for c in codes]


def _validity(bearing, op, st: BallState, psi, q, F, H_total, rtol):
    """Result code of a converged state, re-checked from its per-ball output (docs/model.md sections 3-4)."""
    D = bearing.ball_diameter
    lam_i, lam_o = op.factors
    si, ci = jnp.sin(st.alpha_inner), jnp.cos(st.alpha_inner)
    so, co = jnp.sin(st.alpha_outer), jnp.cos(st.alpha_outer)
    fi, fo = lam_i * st.gyroscopic_moment / D, lam_o * st.gyroscopic_moment / D
    G = st.Q_inner * si + fi * ci
    H = st.Q_inner * ci - fi * si
    r1 = G - st.Q_outer * so - fo * co
    r2 = H - st.Q_outer * co + fo * so + st.centrifugal
    m = bearing.inner_groove_radius * G - bearing.f_inner * fi * D
    c, s = jnp.cos(psi), jnp.sin(psi)
    R = jnp.stack([jnp.sum(H * c), jnp.sum(H * s), jnp.sum(G), jnp.sum(m * s), -jnp.sum(m * c)])
    Ri = bearing.inner_groove_radius
    w = jnp.stack([1.0, 1.0, 1.0, 1.0 / Ri, 1.0 / Ri])
    scale = jnp.maximum(jnp.max(jnp.abs(F * w)),
                        jnp.max(jnp.stack([jnp.max(st.Q_inner), jnp.max(st.Q_outer),
                                           jnp.max(jnp.abs(st.centrifugal))]))) + 1.0
    tol = jnp.maximum(1e-7, 100.0 * rtol) * scale
    ball_bad = jnp.max(jnp.maximum(jnp.abs(r1), jnp.abs(r2))) > tol
    ring_bad = jnp.max(jnp.abs((R - F) * w)) > tol
    inverted = jnp.any(((st.Q_inner > 0.0) & (ci <= 0.0)) | ((st.Q_outer > 0.0) & (co <= 0.0)))
    # the groove edges (docs/model.md section 11, the rule of bearingsim.physics.limits.contact_limits): a loaded
    # contact centred at or beyond an edge has the ball riding on the shoulder, outside the model.
    # A ball over a defect (defect depth under it > 0) is exempt: its contact angles jump as it
    # drops into the spall or pit (the seed paper's subject, docs/model.md section 5), the groove it runs in
    # there is the defect's, and a lightly loaded contact of that ball (~10 N at 79 deg for a
    # 0.3 mm spall in the 218 at 10 krpm) is what the defective Jones model predicts; the limits
    # still flag it (ContactLimits.over_shoulder).  Every other ball follows the rule.
    # An angular contact bearing (low shoulders) carries axial load in +z only: a loaded contact at
    # or beyond a low shoulder, or F_z < 0, is ``low_shoulder`` (a contact a few degrees below 0
    # under a combined load is still on the groove, inside the low shoulder angle); any other
    # edge (a high shoulder; either edge of a deep groove) is ``over_shoulder``.  The ellipse's
    # half-width running over an edge (truncation) is a flag of the limits, not a refusal.
    healthy_ball = H_total <= 0.0
    high_edge, low_edge = shoulder_crossings(bearing, st.alpha_inner, st.alpha_outer,
                                             jnp.where(healthy_ball, st.Q_inner, 0.0),
                                             jnp.where(healthy_ball, st.Q_outer, 0.0))
    acbb = bearing.angular_contact
    low_shoulder = acbb & (low_edge | (F[2] < 0.0))
    over_shoulder = high_edge | (~acbb & low_edge)
    d_lim = DEFORMATION_LIMIT * D
    deform = jnp.maximum(jnp.where(st.Q_inner > 0.0, st.delta_inner, 0.0),
                         jnp.where(st.Q_outer > 0.0, st.delta_outer, 0.0))
    # the inner groove centre can travel across the whole clearance (contact on the far side of a
    # deep groove: |A1|, |A2| up to 2A), plus the deformations and a defect's depth
    room = 2.0 * bearing.A + jnp.max(H_total) + 2.0 * d_lim
    ring = jnp.maximum(jnp.hypot(q[0], q[1]), jnp.abs(q[2]))
    ring = jnp.maximum(ring, 0.5 * bearing.pitch_diameter * jnp.hypot(q[3], q[4]))
    bounds = (jnp.max(deform) > d_lim) | (ring > room)
    finite = jnp.all(jnp.isfinite(q)) & jnp.all(jnp.isfinite(st.Q_inner)) & jnp.all(
        jnp.isfinite(st.Q_outer)) & jnp.all(jnp.isfinite(st.alpha_inner)) & jnp.all(
        jnp.isfinite(st.alpha_outer))
    return jnp.where(~finite, RESULTS.nonfinite, jnp.where(
        inverted, RESULTS.inverted_contact, jnp.where(
            low_shoulder, RESULTS.low_shoulder, jnp.where(
                bounds, RESULTS.beyond_bounds, jnp.where(
                    ball_bad | ring_bad, RESULTS.equilibrium, jnp.where(
                        over_shoulder, RESULTS.over_shoulder, RESULTS.successful)))))).astype(jnp.int32)


def shoulder_crossings(bearing, alpha_inner, alpha_outer, Q_inner, Q_outer):
    """(high, low): whether a loaded contact (Q > 0) is centred at or beyond a high shoulder's
    edge (alpha >= theta_high) or a low one's (alpha <= -theta_low) of ``bearing.shoulders``;
    per-ball arrays (..., Z) are reduced over the balls.  The one rule of every solve's validity
    (result codes 7 and 8) and of :func:`bearingsim.physics.limits.contact_limits`' ``over_shoulder``."""
    sh = bearing.shoulders
    li, lo = Q_inner > 0.0, Q_outer > 0.0
    high = (li & (alpha_inner >= sh[..., 0, None])) | (lo & (alpha_outer >= sh[..., 2, None]))
    low = (li & (alpha_inner <= -sh[..., 1, None])) | (lo & (alpha_outer <= -sh[..., 3, None]))
    return jnp.any(high, axis=-1), jnp.any(low, axis=-1)


#: a single angular contact bearing whose most loaded inner contact lies below this angle (rad)
#: carries its load at the bottom of the groove: the axial load is too small for the radial load
#: or the moment (tan alpha ~ F_z / F_r with one ball loaded), a degenerate state (issue 27)
GROOVE_BOTTOM_ANGLE = np.radians(1.0)


def _load_cause(bearing, op, F, st, code, settled=True):
    """The cause that the loads name, whatever the Newton iteration did: no load at speed (9); on
    a single angular contact bearing a negative axial load, or none (or too little) under a radial
    load or a moment (7): each loaded contact's axial component pushes the inner ring against the
    contact direction until the loaded balls sit at the bottom of the groove, where one or two
    balls carry the load (the most loaded inner contact below :data:`GROOVE_BOTTOM_ANGLE`; tan
    alpha ~ F_z / F_r), a degenerate state, not the bearing's; else ``code``.  Single bearings
    only: in a set the other bearings hold the ring (:mod:`bearingsim.physics.shaft`)."""
    no_load = jnp.all(F == 0.0) & (op.speed > 0.0)
    side = jnp.any(F[jnp.asarray([0, 1, 3, 4])] != 0.0)
    k = jnp.argmax(st.Q_inner)
    flat = (st.Q_inner[k] > 0.0) & (st.alpha_inner[k] < GROOVE_BOTTOM_ANGLE)
    # F_z = 0 names the cause whatever the iteration did; the groove-bottom state only where the
    # iteration converged on it (``settled``: a failed iteration's last iterate says nothing); it
    # is the cause of what else that state breaks (a lightly loaded ball over a shoulder)
    unpropped = side & ((F[2] == 0.0) | ((F[2] > 0.0) & flat & settled))
    reverse = bearing.angular_contact & ((F[2] < 0.0) | unpropped)
    return jnp.where(no_load, RESULTS.no_load, jnp.where(reverse, RESULTS.low_shoulder, code))


def solve_state(bearing, op: Operation, loads, *, cage_angle=0.0, spall: Spall | tuple | None = None,
                q0=None, x0=None, xu0=None, speed_steps: int = 1, maxit=60, rtol=1e-11, atol=1e-9,
                hertz_method: str = "exact", curve=None, tilt: str = "free") -> JonesSolution:
    """The quasi-static state as a pure JAX function (jit/vmap/grad; never raises, except an
    InputError for a ``tilt`` outside :data:`TILT_MODES` when it is traced).

    Cold start (``q0=None``): the rigid-ring static solution (omega = 0) from an axial shift,
    then the operating speed in ``speed_steps`` stages.  Warm start: ``q0`` (and optionally the
    ball centres ``x0`` and undropped centres ``xu0``, (Z, 2) m) at the full speed.
    ``tilt``: "free" (the moments loads[3:5] applied, tilts solved) or "held" (tilts 0, the
    moments of ``loads`` ignored; the returned ``loads[3:5]`` are the moments that hold the tilt).
    """
    held = tilt_held(tilt)
    F = jnp.asarray(loads, dtype=jnp.float64)
    if held:
        F = jnp.concatenate([F[:3], jnp.zeros(2)])
    cage_angle = jnp.asarray(cage_angle, dtype=jnp.float64)
    curve = stiffness_curve(bearing, hertz_method) if curve is None else curve
    qs, rs = _scales(bearing)
    psi = bearing.ball_azimuths(cage_angle)
    Ho, Hi = _defect_depths(bearing, spall, psi)
    defect = Ho is not None or Hi is not None
    Ho = jnp.zeros_like(psi) if Ho is None else Ho
    Hi = jnp.zeros_like(psi) if Hi is None else Hi
    Fn = F / rs
    tol = jnp.asarray(atol, jnp.float64) / KN + jnp.asarray(rtol, jnp.float64) * jnp.max(jnp.abs(Fn))

    def problem(frac):
        o = eqx.tree_at(lambda p: p.speed, op, op.speed * frac)
        return _Problem(bearing, o, curve, psi, Ho, Hi, Fn, qs, rs, defect, held)

    if q0 is None:
        qz = initial_displacement(bearing, F, curve) / qs
        Y = Yu = None
    else:
        qz = jnp.asarray(q0, jnp.float64) / qs
        qz = jnp.concatenate([qz[:3], jnp.zeros(2)]) if held else qz
        Y = None if x0 is None else jnp.asarray(x0, jnp.float64) / UM
        Yu = None if xu0 is None else jnp.asarray(xu0, jnp.float64) / UM

    def stage(carry, frac):
        qz, Y, Yu, _ = carry
        pb = problem(frac)
        Yc, d_c = _closed_form_balls(pb, qz)
        Yuc, d_cu = _closed_form_balls(pb, qz, True)
        # closed-form balls where no start is given (NaN); a start off the outer raceway at speed
        # is lifted onto it
        Y = lift_onto_outer(bearing, jnp.where(jnp.isfinite(Y), Y, Yc), d_c, pb.H_outer)
        Yu = lift_onto_outer(bearing, jnp.where(jnp.isfinite(Yu), Yu, Yuc), d_cu, 0.0)
        qz, Y, Yu, jac, code, it = _newton(pb, qz, Y, Yu if defect else None, d_c, d_cu, maxit, tol)
        return (qz, Y, Yu, jac), (code, it)

    nan = jnp.full((bearing.n_balls, 2), jnp.nan)
    Y = nan if Y is None else Y
    Yu = nan if Yu is None else Yu
    pb = problem(1.0)
    jac0 = {k: v for k, v in _zero_piece(bearing.n_balls, defect).items() if k in _JAC_KEYS}
    (qz, Y, Yu, jac), code, total_it = speed_stages(stage, (qz, Y, Yu, jac0), speed_steps, q0 is None)
    # at rest the closed form is every ball's exact equilibrium for the converged q (rigid-ring
    # static model): it places the balls that carry (next to) nothing, whose position the
    # residual tolerance leaves open
    at_rest = op.speed == 0.0
    Y = jnp.where(at_rest, _closed_form_balls(pb, qz)[0], Y)
    Yu = jnp.where(at_rest, _closed_form_balls(pb, qz, True)[0], Yu)

    # implicit differentiation: one Newton correction at the solution with the Jacobian of the
    # last accepted iterate frozen; the derivative flows through the residuals only (IFT)
    qz, Y, Yu, jac = lax.stop_gradient((qz, Y, Yu, jac))
    piece = _evaluate(pb, qz, Y, Yu if defect else None, jac=False)
    dq, dY, dYu, S = _direction(pb, piece, jac)
    res = _merit(piece) * KN
    qz, Y = qz + dq, Y + dY
    Yu = Yu + dYu if defect else Y
    q = qz * qs
    K = S * rs[:, None] / qs[None, :]

    A1, A2 = groove_centre_offsets(bearing, q, psi)
    x = Y * UM
    ws = None
    if defect:
        ws = jax.vmap(lambda xx, a1, a2: ball_state(bearing, op, xx, a1, a2, curve).orbital_speed)(
            Yu * UM, A1, A2)
    st = jax.vmap(lambda xx, a1, a2, ho, hi, w: ball_state(bearing, op, xx, a1, a2, curve, ho, hi, w),
                  in_axes=(0, 0, 0, 0, 0, None if ws is None else 0))(x, A1, A2, Ho, Hi, ws)
    a_i, b_i, p_i = contact_ellipse(curve, jnp.cos(st.alpha_inner), st.Q_inner, True)
    a_o, b_o, p_o = contact_ellipse(curve, jnp.cos(st.alpha_outer), st.Q_outer, False)
    F_in = F
    if held:            # the moments that hold the tilt: the balls' moment sum about the ring centre
        F = jnp.concatenate([F[:3], reactions_from_balls(st, psi)[3:]])
    valid = _validity(bearing, op, st, psi, q, F, Ho + Hi, rtol)
    code = _load_cause(bearing, op, F_in, st, jnp.where(succeeded(code), valid, code), succeeded(code)).astype(jnp.int32)
    if held:            # a refused state holds nothing: its loads are the applied ones (moments 0)
        F = jnp.where(succeeded(code), F, F_in)
    return JonesSolution(q, F, code, total_it, res, cage_angle, psi, st.alpha_inner,
                         st.alpha_outer, st.Q_inner, st.Q_outer, st.delta_inner, st.delta_outer,
                         st.centrifugal, st.gyroscopic_moment, st.orbital_speed, st.beta, Ho,
                         st.ball_G, st.ball_H, st.ball_moment, st.K_inner, st.K_outer, p_i, p_o,
                         a_i, b_i, a_o, b_o, K, x, Yu * UM, Hi, tilt)


def ring_reactions(bearing, op, q, cage_angle=0.0, spall: Spall | tuple | None = None, hertz_method="exact",
                   curve=None):
    """Load-displacement map: the loads [Fx, Fy, Fz, Mx, My] (N, N m) the bearing carries at
    inner-ring displacement q = [dx, dy, dz, theta_x, theta_y] (m, rad), balls in equilibrium
    (each iterated to convergence; differentiable)."""
    psi = bearing.ball_azimuths(cage_angle)
    curve = stiffness_curve(bearing, hertz_method) if curve is None else curve
    Ho, Hi = _defect_depths(bearing, spall, psi)
    st = balls_at(bearing, op, q, psi, curve, Ho, Hi)
    return reactions_from_balls(st, psi)


# ------------------------------------------------------------------------------ entry points
_solve_jit = jit(solve_state, options=QUICK_COMPILE)     # a single state: compiled at -O0 (bearingsim.xla)


def raise_for(sol, what: str = "Jones solve", *, bearing=None, in_set=False):
    """Raise :class:`NotConvergedError` / :class:`InvalidStateError` for a failed solution
    (single or batched, any batch shape: the first failed item in flat (C) order is described,
    the count is given).  ``sol``: anything with ``result``, ``residual_norm``, ``iterations`` and
    ``loads`` (a :class:`JonesSolution`, a set's :class:`~bearingsim.physics.shaft.SetSolution`); the hint
    fits the case (:func:`result_hint`: ``bearing``, ``in_set``)."""
    codes = np.ravel(np.asarray(sol.result))          # any batch shape, flattened
    bad = np.flatnonzero(failed(codes))
    if not bad.size:
        return
    k = int(bad[0])
    r = RESULTS.of(codes[k])
    res = float(np.ravel(np.asarray(sol.residual_norm))[k])
    it = int(np.ravel(np.asarray(sol.iterations))[k])
    where = f" (item {k}; {bad.size} of {codes.size} failed)" if codes.size > 1 else ""
    cls = InvalidStateError if r in (RESULTS.inverted_contact, RESULTS.equilibrium, RESULTS.beyond_bounds,
                                     RESULTS.low_shoulder, RESULTS.over_shoulder,
                                     RESULTS.no_load) else NotConvergedError
    loads = ""
    F = None
    if r in (RESULTS.low_shoulder, RESULTS.over_shoulder, RESULTS.no_load, RESULTS.beyond_bounds):
        Fs = np.reshape(np.asarray(sol.loads), (-1, 5))
        F = Fs[min(k, len(Fs) - 1)]
        loads = ("; loads: axial Fz = {:.6g} N, radial Fx = {:.6g} N, Fy = {:.6g} N, moments Mx = {:.6g} N m, "
                 "My = {:.6g} N m").format(F[2], F[0], F[1], F[3], F[4])
    raise cls(f"{what} failed{where}: {r.message}{loads} (after {it} iterations, residual {res:.3g} N)",
              result_hint(r, F, bearing=bearing, in_set=in_set), r)


def result_hint(code, loads=None, *, bearing=None, in_set=False) -> str:
    """The hint for result ``code`` that fits the case: the loads ``[Fx, Fy, Fz, Mx, My]`` (N, N m;
    None: unknown), the ``bearing`` (its free contact angle) and whether it is one bearing of a
    set (``in_set``: a preloaded pair already).  The code's own hint where nothing more is known."""
    r = RESULTS.of(code)
    F = None if loads is None else np.asarray(loads, float).reshape(-1)[:5]
    Fr = None if F is None else float(np.hypot(F[0], F[1]))
    M = None if F is None else float(np.hypot(F[3], F[4]))
    acbb_angle = None
    if bearing is not None and bool(np.all(np.asarray(bearing.angular_contact))):
        acbb_angle = float(np.ravel(np.asarray(bearing.free_contact_angle))[0])
    if r == RESULTS.low_shoulder:
        if in_set:
            return ("in a set a bearing is pushed against its low shoulders when the axial load (or the "
                    "moment) against its contact direction exceeds what the preload and the bearings "
                    "facing the other way hold: turn or add bearings to face the load (DB, DF, TBT carry "
                    "both directions, a DT pair one only), raise the preload, or lower the axial load")
        if F is not None and F[2] < 0.0:
            return r.hint
        if F is not None and (Fr > 0.0 or M > 0.0):
            least = None if acbb_angle is None else 1.25 * Fr * np.tan(acbb_angle)
            if least is not None and F[2] >= least:         # the axial load is not what is short
                return (f"the axial load Fz = {F[2]:.4g} N already exceeds ~1.25 Fr tan(alpha_0) = {least:.4g} N "
                        f"for Fr = {Fr:.4g} N; what leaves a loaded contact at or beyond a low shoulder here is "
                        f"the moment ({M:.4g} N m: it unloads the balls on one side) or the speed (centrifugal "
                        "force turns a lightly loaded ball's outer contact towards the groove bottom): lower the "
                        "moment or the speed, or raise the axial load (or preload) well above that figure")
            need = "" if least is None else (
                f"; at least ~1.25 Fr tan(alpha_0) = {least:.4g} N keeps half the balls loaded")
            return (f"an angular contact bearing without enough axial load (here Fz = {F[2]:.4g} N against "
                    f"Fr = {Fr:.4g} N and a moment of {M:.4g} N m) cannot carry radial load or a moment: "
                    "each loaded contact's axial component pushes the inner ring against the contact "
                    "direction until the loaded balls sit at the bottom of the groove (or beyond a low "
                    "shoulder) and one or two balls carry the load, outside the model; give more axial "
                    f"load in the contact direction{need}, or use a preloaded pair (DB or DF)")
        return r.hint
    if r == RESULTS.beyond_bounds and in_set:
        return ("the loads or the set's preload exceed a bearing's capacity by far: check their values "
                "and units (N, N m); a preload is of the order of 1 % of the bearing's static axial "
                "capacity C_0a (the preload classes light / medium / heavy)")
    if r in (RESULTS.beyond_bounds, RESULTS.stagnated, RESULTS.max_iterations) and F is not None \
            and acbb_angle is not None and Fr > 0.0 and F[2] < 1.25 * Fr * np.tan(acbb_angle):
        return (f"an angular contact bearing carries radial load only with an axial load in its "
                f"contact direction: here Fz = {F[2]:.4g} N against Fr = {Fr:.4g} N; at least "
                f"~1.25 Fr tan(alpha_0) = {1.25 * Fr * np.tan(acbb_angle):.4g} N keeps half the balls "
                "loaded (give more axial load or use a preloaded pair); else " + r.hint)
    return r.hint


def _warn_overload(sol):
    over = np.atleast_1d(np.asarray(sol.overloaded)) & np.atleast_1d(np.asarray(sol.converged))
    if over.any():
        p = float(np.max(np.atleast_1d(np.asarray(sol.max_pressure))[over]))
        warnings.warn(f"contact pressure {p / 1e9:.2f} GPa exceeds {PRESSURE_WARNING / 1e9:.1f} GPa "
                      "(ISO 76 static-capacity stress): the steel deforms permanently; the Hertz "
                      "result is an elastic idealisation", OverloadWarning, stacklevel=3)


def solve(bearing, op: Operation, loads, *, cage_angle=0.0, spall: Spall | tuple | None = None, q0=None,
          speed_steps: int = 1, maxit: int = 60, rtol: float = 1e-11, atol: float = 1e-9,
          hertz_method: str = "exact", throw: bool = True, tilt: str = "free") -> JonesSolution:
    """Solve the Jones model for one load case.

    ``loads`` = [Fx, Fy, Fz, Mx, My] (N, N m) on the inner ring (see :func:`load_vector`).
    Starts from the rigid-ring static solution (omega = 0) unless ``q0`` is given, then goes
    to speed in ``speed_steps`` steps; if that fails it retries once with 8 speed steps (off
    the hot path).  ``throw=True`` raises :class:`NotConvergedError` or
    :class:`InvalidStateError` with the reason and a hint; pressures above 4.2 GPa warn
    (:class:`OverloadWarning`).  ``spall``: None (healthy), a :class:`Spall` on the outer or
    inner raceway or a pit on one ball (docs/model.md sections 5 and 9), or a tuple of them (several defects).
    ``tilt``: "free" (default: the moments Mx, My applied, the tilts solved) or "held" (the tilts
    held at 0, Mx = My = 0 required; ``sol.loads[3:5]`` are the moments that hold them).
    """
    _check_held_loads(loads, tilt)
    loads = f64(loads)
    cage_angle = f64(cage_angle)
    q0 = None if q0 is None else f64(q0)
    maxit, rtol, atol = traced_tolerances(maxit, rtol, atol)
    kw = dict(cage_angle=cage_angle, spall=canonical_defects(spall), maxit=maxit, rtol=rtol, atol=atol,
              hertz_method=hertz_method, tilt=tilt)
    # the stage count traced (newton.speed_stages): the retry is the same compiled program
    sol = _solve_jit(bearing, op, loads, q0=q0, speed_steps=np.int32(speed_steps), **kw)
    if failed(int(sol.result)) and (speed_steps < 8 or q0 is not None):
        retry = _solve_jit(bearing, op, loads, q0=None, speed_steps=np.int32(8), **kw)
        if bool(better(retry.result, sol.result)):
            sol = retry
    if throw:
        raise_for(sol, bearing=bearing)
    _warn_overload(sol)
    return sol


def _solve_batch(bearing, op, loads, cage_angle, spall, speed_steps, maxit, rtol, atol, hertz_method,
                 tilt="free"):
    curve = stiffness_curve(bearing, hertz_method)

    def one(o, F, c):
        return solve_state(bearing, o, F, cage_angle=c, spall=spall, speed_steps=speed_steps,
                           maxit=maxit, rtol=rtol, atol=atol, hertz_method=hertz_method, curve=curve,
                           tilt=tilt)

    return jax.vmap(one)(op, loads, cage_angle)


_solve_batch_jit = jit(_solve_batch)


def solve_batch(bearing, op: Operation, loads, *, cage_angle=0.0, spall: Spall | tuple | None = None,
                speed_steps: int = 1, maxit: int = 60, rtol: float = 1e-11, atol: float = 1e-9,
                hertz_method: str = "exact", throw: bool = False, tilt: str = "free") -> JonesSolution:
    """vmapped solve over N load cases ``loads`` (N, 5); ``op.speed`` and ``cage_angle`` may be
    (N,) or scalar.  Items that fail are retried once with 8 speed steps (only those).
    ``tilt``: "free" or "held", for every item (as :func:`solve`).

    ``throw=False`` (default): check ``solution.result`` per item (0 = converged and valid);
    ``throw=True`` raises for the first failed item, naming how many failed.
    """
    _check_held_loads(loads, tilt)
    loads = f64(loads)
    n = loads.shape[0]
    x = xp(bearing, op, loads, cage_angle)     # the batch laid out in NumPy outside a program
    op_b = eqx.tree_at(lambda p: (p.speed, p.centrifugal, p.gyroscopic), op,
                       (x.broadcast_to(host(op.speed), (n,)), x.broadcast_to(host(op.centrifugal), (n,)),
                        x.broadcast_to(host(op.gyroscopic), (n,))))
    cage = x.broadcast_to(x.asarray(host(cage_angle), dtype=x.float64), (n,))
    maxit, rtol, atol = traced_tolerances(maxit, rtol, atol)
    spall = canonical_defects(spall)
    sol = _solve_batch_jit(bearing, op_b, loads, cage, spall, speed_steps, maxit, rtol, atol,
                           hertz_method, tilt)
    if speed_steps < 8:
        def run(idx):   # the failed items again with 8 speed steps (only them)
            op_r = eqx.tree_at(lambda p: (p.speed, p.centrifugal, p.gyroscopic), op_b,
                               (op_b.speed[idx], op_b.centrifugal[idx], op_b.gyroscopic[idx]))
            return _solve_batch_jit(bearing, op_r, loads[idx], cage[idx], spall, 8, maxit, rtol, atol,
                                    hertz_method, tilt)

        sol = retry_failed(sol, run, better)
    if throw:
        raise_for(sol, "Jones batch solve", bearing=bearing)
    return sol


# ----------------------------------------------------------- entry points for other solvers
def state_validity(bearing, op: Operation, balls: BallState, psi, q, loads, defect_depth, rtol):
    """Result code (:class:`RESULTS`) of a converged state re-checked from its per-ball output
    (docs/model.md sections 3-4): finite, no inverted loaded contact, every ball and the ring in equilibrium
    with ``loads``, deformations and ring displacement within bounds.  ``defect_depth``: the
    total defect depth under each ball (H_outer + H_inner, (Z,)).  The checks of
    :func:`solve_state`, for solvers that hold the balls themselves (:mod:`bearingsim.physics.shaft`)."""
    return _validity(bearing, op, balls, psi, q, loads, defect_depth, rtol)
