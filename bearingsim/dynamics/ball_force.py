"""The balls' load on the rings in the right-hand side (its cost): a lean, transcendental-free
ball solve, and the check that picks its Newton step count.

Each ball's 2x2 Jones equilibrium (centrifugal force, gyroscopic moment, defect depths H_outer
and H_inner) is solved from the omega = 0 closed form
(:func:`bearingsim.physics.balls.static_ball_position`) by ``iterations`` Newton steps with the exact
Jacobian of the transcendental-free :func:`bearingsim.physics.balls.ball_state` (two forward-mode
directional derivatives, all element-wise over balls: XLA fuses them); the ball's loads on the
ring are linearised about the last iterate (their error is second order in the last step).
:func:`choose_ball_iterations` checks the count against the same solve iterated to convergence
(the exact ball equilibrium of :func:`bearingsim.physics.balls.balls_at`) over one ball pitch, with the
ring displaced +-5 %.  A ball over a defect without inner contact is carried at the orbital
speed of its undropped closed-form position.
"""
from __future__ import annotations

import threading

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from typing import NamedTuple

from ..errors import InputError
from ..physics.balls import (ball_balance, ball_state, contact_record, groove_centre_offsets, groove_centre_offsets_cs,
                     static_ball_position)
from ..physics.defect import advance, as_defects, contact_depths
from ..fastmath import norm2, recip
from ..physics.kinematics import Operation, ball_kinematics_cs
from ..programs import jit

__all__ = ["bearing_force", "BallCarry", "initial_ball_carry", "bearing_force_chord", "CHORD_TOL", "bearing_force_history", "RECORD_ROWS", "record_loads_angles", "ball_errors", "choose_ball_iterations", "precompile_ball_check",
           "next_iterations", "ITER_CHOICES", "ITER_TOL", "REF_ITERATIONS", "REF_TOL"]

#: Newton step counts the lean ball solver is checked with (a ball dropping into a deep spall at
#: speed, capped at 2e-3 D per step, can need 16: the demo case)
ITER_CHOICES = (1, 2, 3, 4, 8, 16)
#: ball loads vs balls_at, relative to the largest ball load: an error this size biases the
#: forces by ~1e-3, an order below the fixed step's error in the signal (1-2 %)
ITER_TOL = 1e-3


#: rows of the balls' per-sample record of a time loop: Q_inner, Q_outer (N) and the sines and
#: cosines of alpha_inner, alpha_outer (:func:`bearingsim.physics.balls.contact_record`)
RECORD_ROWS = 6


def record_loads_angles(rec):
    """(Q_inner, Q_outer, alpha_inner, alpha_outer) from records (..., RECORD_ROWS, Z) (host
    arrays; the angles in rad from the recorded sines and cosines)."""
    rec = np.asarray(rec)
    return (rec[..., 0, :], rec[..., 1, :], np.arctan2(rec[..., 2, :], rec[..., 3, :]),
            np.arctan2(rec[..., 4, :], rec[..., 5, :]))


def _zeros_like(H, psi):
    return jnp.zeros_like(psi) if H is None else H


def _newton(bearing, op, curve, q, psi, H_outer, H_inner, iterations, record, jacobian=False, even=False):
    """The lean ball solve: (X1, X2, G, H, its closure for the ball state, the linearised (G, H)
    after every step stacked (iterations, ...) with ``record`` (else None), (A1, A2, H_outer,
    H_inner, the undropped orbital speed[, the last step's regularised inverse Jacobian (i11,
    i12, i21, i22) with ``jacobian``])) after ``iterations`` steps; (G, H) are linearised about
    the last iterate.  ``even``: psi are a bearing's azimuths theta + 2 pi j / Z (their sines and
    cosines by :func:`_azimuth_sin_cos`)."""
    Ho, Hi = _zeros_like(H_outer, psi), _zeros_like(H_inner, psi)
    A1, A2 = groove_centre_offsets_cs(bearing, q, *_azimuth_sin_cos(psi)) if even else groove_centre_offsets(bearing, q, psi)
    _, rL = norm2(A1, A2)
    s, c = A1 * rL, A2 * rL
    # undropped closed-form orbital speed: collinear contacts along (A1, A2)
    ws = ball_kinematics_cs(bearing, op, s, c, s, c)[2]
    x0, _ = static_ball_position(bearing, op, A1, A2, curve, Ho, Hi)
    X1, X2 = x0[0], x0[1]

    def state(X1, X2):
        return ball_state(bearing, op, (X1, X2), A1, A2, curve, Ho, Hi, ws)

    def f(X1, X2):          # ball_state's residuals and loads, both contacts as one stacked array
        r1, r2, G_, H_, _ = ball_balance(bearing, op, (X1, X2), A1, A2, curve, Ho, Hi, ws)
        return (r1, r2), (G_, H_)

    one, zero = jnp.ones_like(X1), jnp.zeros_like(X1)
    cap = 2e-3 * bearing.ball_diameter

    def linearised(lin, t1, t2, d1, d2):
        return jax.tree_util.tree_map(lambda v, a, b: v + a * d1 + b * d2, lin, t1, t2)

    def newton(c, _):
        X1, X2 = c[0] + c[5], c[1] + c[6]         # the previous iterate's step
        ((r1, r2), lin), ((a11, a21), t1) = jax.jvp(f, (X1, X2), (one, zero))
        _, ((a12, a22), t2) = jax.jvp(f, (X1, X2), (zero, one))
        # regularised 2x2 solve (a ball out of contact at rest: J = 0, r = 0, zero step)
        sc = jnp.maximum(jnp.maximum(jnp.abs(a11), jnp.abs(a12)), jnp.maximum(jnp.abs(a21), jnp.abs(a22)))
        mu = 1e-13 * sc + 1e-300
        b11, b22 = a11 + mu, a22 + mu
        det = b11 * b22 - a12 * a21
        idet = recip(jnp.where(jnp.abs(det) > 1e-300, det, 1e-300))
        d1 = -(b22 * r1 - a12 * r2) * idet
        d2 = -(b11 * r2 - a21 * r1) * idet
        n = jnp.maximum(jnp.abs(d1), jnp.abs(d2))
        k = jnp.where(n > cap, cap * recip(jnp.where(n > 0, n, 1.0)), 1.0)
        ok = jnp.isfinite(d1) & jnp.isfinite(d2)
        d1, d2 = jnp.where(ok, d1 * k, 0.0), jnp.where(ok, d2 * k, 0.0)
        out = linearised(lin[:2], t1[:2], t2[:2], d1, d2) if record else None
        inv = (b22 * idet, -a12 * idet, -a21 * idet, b11 * idet) if jacobian else ()
        return (X1, X2, lin, t1, t2, d1, d2) + inv, out

    lin0 = (zero, zero)
    init = (X1, X2, lin0, lin0, lin0, zero, zero) + ((zero,) * 4 if jacobian else ())
    if isinstance(iterations, (int, np.integer)):
        n = max(int(iterations), 1)
    else:           # a traced count (one program for every count: the data engine's time loop)
        if record:
            raise InputError("ball_iterations: a recorded ball solve needs a Python int count of Newton "
                             f"steps, got {iterations!r}")
        n = jnp.maximum(jnp.asarray(iterations, jnp.int32), 1)
    if record:
        c, hist = lax.scan(newton, init, None, length=n)
    else:
        c = lax.fori_loop(0, n, lambda _, c: newton(c, None)[0], init)
        hist = None
    X1, X2, lin, t1, t2, d1, d2 = c[:7]
    lin = linearised(lin, t1, t2, d1, d2)
    return X1 + d1, X2 + d2, lin[0], lin[1], state, hist, (A1, A2, Ho, Hi, ws) + tuple(c[7:])


def _ring_load(G, H, psi, even=False):
    sp, cp = _azimuth_sin_cos(psi) if even else (jnp.sin(psi), jnp.cos(psi))
    return jnp.stack([jnp.sum(H * cp, -1), jnp.sum(H * sp, -1), jnp.sum(G, -1)], -1)


def bearing_force(bearing, op: Operation, curve, q, psi, H_outer=None, H_inner=None, iterations=1,
                  full_state=False, record=False, even_azimuths=False):
    """Load [Fx, Fy, Fz] (N) the balls carry at ring displacement q (5,) and azimuths psi (Z,),
    each ball solved from the omega = 0 closed form by ``iterations`` Newton steps (exact
    Jacobian), its loads linearised about the last iterate.  ``H_outer``/``H_inner``: defect
    depths at each ball's outer / inner contact (m; None: 0).  Element-wise over balls (and any
    leading batch axes of psi and the depths); transcendental-free apart from the azimuths'
    sine and cosine.  Also returns the balls' (G, H) loads on the ring (``full_state``: their
    :class:`bearingsim.physics.balls.BallState` at the last iterate instead; ``record``: their
    (RECORD_ROWS, Z) record there, :func:`bearingsim.physics.balls.contact_record`).  ``even_azimuths``:
    psi are :meth:`bearingsim.Bearing.ball_azimuths` (theta + 2 pi j / Z), whose sines and cosines
    are then taken from theta's (the values to round-off, fewer kernels in a time step)."""
    X1, X2, G, H, state, _, (A1, A2, Ho, Hi, _) = _newton(bearing, op, curve, q, psi, H_outer, H_inner,
                                                      iterations, False, even=even_azimuths)
    R = _ring_load(G, H, psi, even_azimuths)
    if full_state:
        return R, state(X1, X2)
    if record:      # the contacts alone (no kinematics, no arctangents) at the last iterate
        return R, contact_record(bearing, curve, (X1, X2), A1, A2, Ho, Hi)
    return R, G, H


#: a chord step is accepted when its balls' equilibrium residuals at the reported position are
#: within this fraction of the largest ball load (else the step is solved in full); the loads'
#: error is of the order of the residual (tests/test_dynamics.py measures it against the
#: converged solve), an order below :data:`ITER_TOL`
CHORD_TOL = 1e-5
#: ... and when the next chord correction (the estimated remaining error of the ball positions)
#: is within this fraction of the ball diameter: ~5e-7 rad of contact angle (L_o ~ 0.02 D)
CHORD_XTOL = 1e-8


class BallCarry(NamedTuple):
    """What a time loop carries from step to step for the chord solve
    (:func:`bearing_force_chord`): each ball's (estimated) equilibrium position, the groove-centre
    offsets it belongs to, the regularised inverse of its 2x2 Jacobian and its closed-form
    sensitivity to the offsets (both from the last full solve), whether they are usable, and
    run counters."""

    X1: jnp.ndarray             # (Z,) ball centres, axial (m)
    X2: jnp.ndarray             # (Z,) radial (m)
    A1: jnp.ndarray             # (Z,) the groove-centre offsets of that step (m)
    A2: jnp.ndarray
    inv: tuple                  # (i11, i12, i21, i22), each (Z,): the inverse Jacobian (m/N)
    sens: tuple                 # (n1, n2, along, across), each (Z,): see _sensitivity
    warm: jnp.ndarray           # () bool: False -- the next step solves in full
    full: jnp.ndarray           # () steps solved in full (start, defect edges, rejected chords)
    rejected: jnp.ndarray       # () chord steps rejected (residual above tolerance or not finite)
    worst: jnp.ndarray          # () largest accepted chord residual / largest ball load


def initial_ball_carry(n_balls):
    """A :class:`BallCarry` whose first step solves in full."""
    z = np.zeros(n_balls)          # NumPy: no eager operation on the host, constants in a trace
    return BallCarry(z, z, z, z, (z, z, z, z), (z, z, z, z), np.zeros((), bool), np.zeros(()), np.zeros(()),
                     np.zeros(()))


def _sensitivity(bearing, X1, X2, A1, A2, Ho, Hi):
    """How a ball's equilibrium follows its groove-centre offsets A, from the omega = 0 geometry
    (the ball on the line of centres, the deflections in a fixed ratio): along the line it moves
    by delta_o / (delta_o + delta_i) of A's change, across it by L_o / |A|; a ball without both
    contacts does not follow.  Returns (n1, n2, along, across), n the line's direction.  Only
    the prediction of the next chord step uses it (its error costs rejected steps, never
    accuracy)."""
    D = bearing.ball_diameter
    L, rL = norm2(A1, A2)
    Lo, _ = norm2(X1, X2)
    Li, _ = norm2(A1 - X1, A2 - X2)
    d_o = Lo - (bearing.f_outer - 0.5) * D - Ho
    d_i = Li - (bearing.f_inner - 0.5) * D - Hi
    both = (d_o > 0.0) & (d_i > 0.0)
    along = jnp.where(both, d_o * recip(jnp.where(both, d_o + d_i, 1.0)), 0.0)
    across = jnp.where(both, Lo * rL, 0.0)
    return A1 * rL, A2 * rL, along, across


def _azimuth_sin_cos(psi):
    """(sin psi, cos psi) of the ball azimuths psi (Z,), psi_j = theta + 2 pi j / Z
    (:meth:`bearingsim.Bearing.ball_azimuths`), from those of theta = psi_0 by the
    angle-addition formulas as a small matrix product with constant rotations: XLA's CPU backend
    keeps a dot out of its loop fusions, so the products are computed once, where the sines and
    cosines themselves would be recomputed in every kernel that reads them (~15 per time step).
    Equal to jnp.sin / jnp.cos of psi to round-off."""
    Z = psi.shape[-1]
    d = 2.0 * np.pi / Z * np.arange(Z)
    rot = jnp.asarray(np.stack([np.stack([np.cos(d), np.sin(d)], -1), np.stack([-np.sin(d), np.cos(d)], -1)], -2))
    th = psi[..., :1]
    out = jnp.einsum("zij,...j->...zi", rot, jnp.concatenate([jnp.sin(th), jnp.cos(th)], -1))
    return out[..., 0], out[..., 1]


def _chord(bearing, op, curve, q, psi, Ho, Hi, bc: BallCarry, tol):
    """One chord step from the carried state: (R, record, X1, X2, A1, A2, accepted, residual
    ratio)."""
    sp, cp = _azimuth_sin_cos(psi)
    A1, A2 = groove_centre_offsets_cs(bearing, q, sp, cp)
    ws = None
    if Ho is not None or Hi is not None:        # the undropped orbital speed, as in _newton
        _, rL = norm2(A1, A2)
        s, c = A1 * rL, A2 * rL
        ws = ball_kinematics_cs(bearing, op, s, c, s, c)[2]
    Ho, Hi = _zeros_like(Ho, psi), _zeros_like(Hi, psi)
    # predicted positions: the last equilibrium moved with the offsets' change
    n1, n2, along, across = bc.sens
    dA1, dA2 = A1 - bc.A1, A2 - bc.A2
    dn = dA1 * n1 + dA2 * n2
    P1 = bc.X1 + across * dA1 + (along - across) * dn * n1
    P2 = bc.X2 + across * dA2 + (along - across) * dn * n2
    i11, i12, i21, i22 = bc.inv
    r1, r2, *_ = ball_balance(bearing, op, (P1, P2), A1, A2, curve, Ho, Hi, ws)
    X1 = P1 - (i11 * r1 + i12 * r2)
    X2 = P2 - (i21 * r1 + i22 * r2)
    r1, r2, G, H, rec = ball_balance(bearing, op, (X1, X2), A1, A2, curve, Ho, Hi, ws)
    scale = jnp.max(jnp.sqrt(G * G + H * H))
    res = jnp.max(jnp.maximum(jnp.abs(r1), jnp.abs(r2)))
    ratio = res * recip(scale + 1e-30)
    # the remaining position error, estimated by the next chord correction (across the line of
    # centres a ball is ~100x softer than along it: the residuals alone would let its contact
    # angles drift)
    e1, e2 = i11 * r1 + i12 * r2, i21 * r1 + i22 * r2
    moved = jnp.max(jnp.maximum(jnp.abs(e1), jnp.abs(e2)))
    ok = (jnp.isfinite(ratio) & (ratio <= tol) & (moved <= CHORD_XTOL * bearing.ball_diameter)
          & jnp.all(jnp.isfinite(X1) & jnp.isfinite(X2)))
    # the next prediction's base: that correction (free: the residuals are at hand)
    R = jnp.stack([jnp.sum(H * cp, -1), jnp.sum(H * sp, -1), jnp.sum(G, -1)], -1)
    return R, rec, X1 - e1, X2 - e2, A1, A2, ok, ratio


def bearing_force_chord(bearing, op: Operation, curve, q, psi, H_outer, H_inner, iterations, carry: BallCarry,
                        refresh, tol=CHORD_TOL):
    """:func:`bearing_force` with ``record=True`` for a time loop that carries the balls'
    positions (``carry``, a :class:`BallCarry`): returns (R, record (RECORD_ROWS, Z), new carry).
    ``psi``: :meth:`bearingsim.Bearing.ball_azimuths` (theta + 2 pi j / Z; their sines and cosines
    are taken from theta's).

    One plain evaluation of the ball equations (:func:`bearingsim.physics.balls.ball_balance`) at
    positions predicted from the last step's equilibria (moved with the change of the
    groove-centre offsets, :func:`_sensitivity`): the loads (not linearised) and the record are
    those of that position, and its residuals are those of exactly the reported state; a chord
    step with the carried inverse Jacobian then estimates the equilibrium the next prediction
    starts from.  The step is accepted when every ball's residual is within ``tol`` of the
    largest ball load (and finite); otherwise -- and where ``refresh`` (a scalar: a defect edge
    in the step, whose jump in depth the prediction does not follow) or the carry is not
    ``warm`` -- the step is the full solve of :func:`bearing_force` (closed form +
    ``iterations`` Newton steps), which also gives the positions, inverse Jacobians and
    sensitivities carried on.  A single item only: under ``vmap`` the ``lax.cond`` runs both
    branches."""
    R_c, rec_c, X1c, X2c, A1c, A2c, ok, ratio = _chord(bearing, op, curve, q, psi, H_outer, H_inner, carry, tol)
    need = refresh | ~carry.warm | ~ok

    def full():
        X1, X2, G, H, _, _, ex = _newton(bearing, op, curve, q, psi, H_outer, H_inner, iterations, False,
                                         jacobian=True, even=True)
        A1, A2, Ho, Hi = ex[:4]
        rec = contact_record(bearing, curve, (X1, X2), A1, A2, Ho, Hi)
        sens = _sensitivity(bearing, X1, X2, A1, A2, Ho, Hi)
        return _ring_load(G, H, psi, True), rec, X1, X2, A1, A2, tuple(ex[5:9]), sens

    def chord():
        return R_c, rec_c, X1c, X2c, A1c, A2c, carry.inv, carry.sens

    R, rec, X1, X2, A1, A2, inv, sens = lax.cond(need, full, chord)
    new = BallCarry(X1, X2, A1, A2, inv, sens, jnp.bool_(True), carry.full + need,
                    carry.rejected + (carry.warm & ~refresh & ~ok),
                    jnp.where(need, carry.worst, jnp.maximum(carry.worst, ratio)))
    return R, rec, new


def bearing_force_history(bearing, op: Operation, curve, q, psi, H_outer=None, H_inner=None,
                          iterations=ITER_CHOICES[-1]):
    """The balls' (G, H) after 1, 2, ..., ``iterations`` Newton steps, stacked on a leading axis:
    row n-1 equals :func:`bearing_force` with ``iterations=n`` (one solve checks every count)."""
    return _newton(bearing, op, curve, q, psi, H_outer, H_inner, iterations, True)[5]


#: Newton steps of the reference in :func:`ball_errors` (the lean solve iterated to convergence)
REF_ITERATIONS = 32
#: the reference counts as converged when its last step changes the ball loads by at most this
#: (relative to the largest ball load)
REF_TOL = 1e-10


def ball_errors(bearing, op, q, spall, curve, angles, scales, shaft_angles=None, spin_ratio=0.0):
    """Max over cage angles x displacement scalings of the lean ball loads' error, relative to
    the largest ball load, for each of :data:`ITER_CHOICES` Newton steps; ``inf`` for every count
    where the reference did not converge.

    The reference is the same ball solve iterated to convergence (:data:`REF_ITERATIONS` steps,
    the last changing the loads by <= :data:`REF_TOL`): the ball equations are those of
    :func:`bearingsim.physics.balls.balls_at`, so its fixed point is the exact ball state except for a
    ball carried over a defect, whose orbital speed is that of its undropped closed-form position
    (tests/test_dynamics.py measures that difference against ``balls_at``).  One scan of Newton
    steps compiles in a fraction of the time of the exact solver's loops.
    ``shaft_angles`` (same shape as ``angles``, default 0) place a turning defect (inner spall:
    centre + phi; ball pit: spin angle + spin_ratio phi)."""
    phis = jnp.zeros_like(angles) if shaft_angles is None else shaft_angles
    sel = jnp.asarray(ITER_CHOICES) - 1
    A, S = angles.shape[0], scales.shape[0]

    def depths(th, ph):
        psi = bearing.ball_azimuths(th)
        Ho, Hi = contact_depths(bearing, None if spall is None else advance(spall, ph, 1.0, spin_ratio), psi)
        return psi, _zeros_like(Ho, psi), _zeros_like(Hi, psi)

    # every (cage angle, scaling) at once on leading axes (A, S, Z): the lean solve is
    # element-wise, and a vmapped scan would re-trace its body in the batching rule (~1.5 s)
    psi, Ho, Hi = (jnp.broadcast_to(a[:, None, :], (A, S, a.shape[-1]))
                   for a in jax.vmap(depths)(angles, phis))
    qq = q[:, None, None, None] * scales[None, None, :, None]           # (5, 1, S, 1)
    G, H = bearing_force_history(bearing, op, curve, qq, psi, Ho, Hi, REF_ITERATIONS)
    # the largest ball load (the inner contact's, |(G, H)|), per cage angle and scaling
    scale = jnp.max(jnp.sqrt(G[-1] * G[-1] + H[-1] * H[-1]), -1) + 1e-30
    err = jnp.maximum(jnp.max(jnp.abs(G - G[-1]), -1), jnp.max(jnp.abs(H - H[-1]), -1)) / scale
    conv = jnp.maximum(jnp.max(jnp.abs(G[-1] - G[-2]), -1), jnp.max(jnp.abs(H[-1] - H[-2]), -1)) / scale
    return jnp.max(jnp.where(conv <= REF_TOL, err[sel], jnp.inf), axis=(1, 2))


_ball_errors_jit = jit(ball_errors)


def next_iterations(its):
    """A batch's Newton step count: the largest of the checked items' counts (its), or the
    largest choice when none was checked.  The items checked are the extremes of the batch
    (:func:`bearingsim.dynamics.extreme_items`), so every item lies inside what was checked."""
    return max(its, default=ITER_CHOICES[-1])


#: cage angles every :func:`choose_ball_iterations` checks at least (12 over a ball pitch and six
#: per defect): the list is padded to this length so that the check compiles once
CHECK_ANGLES = 18


_PRECOMPILED = set()


def precompile_ball_check(bearing, op, spall, curve, theta0=0.0):
    """Compile the program of :func:`choose_ball_iterations` in a background thread and return
    the thread (join it before the check), or None when this configuration was compiled before
    in this process.  XLA releases the GIL while it compiles, so on a second core this overlaps
    the quasi-static solve's compilation (a first simulation: ~0.9 s of its ~10 s).  The thread
    runs the check once on a zero displacement and discards the result (an error there is the
    check's own and is raised by the real call)."""
    defects = as_defects(spall)
    key = (bearing.n_balls, tuple((d.profile, d.location, d.ball) for d in defects))
    if key in _PRECOMPILED:
        return None
    _PRECOMPILED.add(key)

    def run():
        try:
            choose_ball_iterations(bearing, op, np.zeros(5), defects, curve, theta0, spin_ratio=0.5)
        except Exception:       # noqa: BLE001 -- the real call raises it
            pass

    th = threading.Thread(target=run, name="bearingsim-precompile", daemon=True)
    th.start()
    return th


def choose_ball_iterations(bearing, op, q, spall, curve, theta0=0.0, tol=ITER_TOL, spin_ratio=0.0):
    """Smallest number of Newton steps (of 1, 2, 3, 4, 8, 16) whose ball loads match the
    converged ball solve (:func:`ball_errors`) to ``tol`` (relative to the largest ball load) over one ball pitch of
    cage angles (and with a ball over each defect: its centre and 40 % of its half-extent to
    either side), the ring displacement q scaled by 0.95, 1, 1.05.  ``spall``: None, a Spall or
    a tuple.  Returns (count, error); count 0 when none does."""
    Z = bearing.n_balls
    pitch = 2 * np.pi / Z
    angles = list(float(theta0) + np.linspace(0.0, pitch, 12, endpoint=False))
    phis = [0.0] * len(angles)
    for sp in as_defects(spall):
        if float(sp.depth) <= 0:
            continue
        c, e = float(sp.center), float(sp.extent)
        for u in (0.0, -0.4 * e, 0.4 * e):
            if sp.location == "outer":          # a ball at azimuth c + u
                angles.append(c + u), phis.append(0.0)
            elif sp.location == "inner":        # ball 0 at theta0, the spall turned to meet it
                angles.append(float(theta0)), phis.append(float(theta0) - c - u)
            elif spin_ratio > 0:                # the pit turned into the outer and the inner contact
                for target in (0.0, np.pi):
                    angles.append(float(theta0)), phis.append((target - c - u) / spin_ratio)
    # one program per bearing and defect slots: the angle list padded to a fixed length (a
    # repeated angle does not change the max) and the spin ratio traced, not static
    pad = CHECK_ANGLES - len(angles)
    if pad > 0:
        angles, phis = angles + [angles[-1]] * pad, phis + [phis[-1]] * pad
    errs = np.asarray(_ball_errors_jit(bearing, op, np.asarray(q, np.float64), spall, curve,
                                       np.asarray(angles, np.float64), np.array([0.95, 1.0, 1.05]),
                                       np.asarray(phis, np.float64), np.float64(spin_ratio)))
    ok = np.flatnonzero(errs <= tol)
    return (ITER_CHOICES[int(ok[0])], float(errs[ok[0]])) if ok.size else (0, float(errs.min()))
