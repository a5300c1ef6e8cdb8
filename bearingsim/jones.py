"""Jones (1960) quasi-static model in Harris' form, with an optional outer-raceway spall
(MODEL.md sections 4-5).

Structure of the solve
----------------------
* Per ball (vmapped): given the inner-ring displacement ``q`` the ball centre (X1, X2) solves
  its two equilibrium equations.  At omega = 0 this is the closed form (contacts collinear,
  delta_i / delta_o = (K_o / K_i)^(2/3)); at speed a damped Newton on the 2x2 problem starts
  from it.  The ball solve is wrapped in ``lax.custom_root`` so that derivatives with respect
  to ``q`` (and to every bearing / spall parameter) come from the implicit function theorem:
  this is the Schur complement of the 2Z+5 system on the 5 ring unknowns.
* Ring (5 unknowns): Newton with the exact Jacobian of the load-displacement map R(q)
  (``jax.jacfwd`` through the implicit ball solves) and a backtracking line search, first at
  omega = 0 (the rigid-ring static model) from a start where every ball touches, then at the
  operating speed (optionally in several speed steps).
* The 5x5 bearing stiffness is dR/dq at the solution.

Unknowns are scaled to micrometres (tilts as micrometres at the groove-centre radius R_i),
residuals to kN (moments divided by R_i), so one tolerance fits every DOF.

Balls out of contact: a ball with no contact at omega = 0 carries nothing and sits at the
closed-form mid-gap position (its equations hold identically); at speed the start pushes it
onto the outer raceway, where F_c keeps it.  The gyroscopic friction terms are those of
MODEL.md for every ball.  A ball that has lost its inner contact over the spall is carried
by the cage at the orbital speed of its undropped position (same q, no spall), see MODEL.md
section 5.
"""
from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax

from .defect import NO_SPALL, Spall, depth_profile
from .hertz import chebyshev_eval, hertz_contact, semi_axes, stiffness_curve
from .kinematics import Operation, ball_kinematics

UM = 1e-6          # unknown scale (m)
KN = 1e3           # residual scale (N)

RESULT_MESSAGES = {
    0: "converged",
    1: "maximum number of Newton iterations reached",
    2: "non-finite value in the residual or Jacobian",
    3: "line search could not reduce the residual (stagnated above tolerance)",
}


def load_vector(axial=0.0, radial_x=0.0, radial_y=0.0, moment_x=0.0, moment_y=0.0):
    """Applied inner-ring loads as the solver's vector [Fx, Fy, Fz, Mx, My] (N, N m)."""
    return jnp.stack([jnp.asarray(v, dtype=jnp.float64)
                      for v in (radial_x, radial_y, axial, moment_x, moment_y)])


Loads = load_vector


# ----------------------------------------------------------------------------------------
# Per-ball geometry and equilibrium
# ----------------------------------------------------------------------------------------
def groove_centre_offsets(bearing, q, psi):
    """(A1, A2): axial and radial distance from the outer to the inner groove-curvature centre."""
    BD = bearing.A
    a0 = bearing.free_contact_angle
    dx, dy, dz, tx, ty = q[0], q[1], q[2], q[3], q[4]
    A1 = BD * jnp.sin(a0) + dz + bearing.inner_groove_radius * (tx * jnp.sin(psi) - ty * jnp.cos(psi))
    A2 = BD * jnp.cos(a0) + dx * jnp.cos(psi) + dy * jnp.sin(psi)
    return A1, A2


class BallState(NamedTuple):
    X1: jnp.ndarray
    X2: jnp.ndarray
    alpha_i: jnp.ndarray
    alpha_o: jnp.ndarray
    delta_i: jnp.ndarray
    delta_o: jnp.ndarray
    Q_i: jnp.ndarray
    Q_o: jnp.ndarray
    K_i: jnp.ndarray
    K_o: jnp.ndarray
    Fc: jnp.ndarray
    Mg: jnp.ndarray
    omega_m: jnp.ndarray
    beta: jnp.ndarray
    G: jnp.ndarray          # axial force on the ball from the inner ring
    H: jnp.ndarray          # radial force on the ball from the inner ring
    moment: jnp.ndarray     # m_j = R_i G - lambda_i f_i M_g
    r_axial: jnp.ndarray    # ball equilibrium residuals (N)
    r_radial: jnp.ndarray


def ball_state(bearing, op: Operation, x, A1, A2, H_def, curve, wm_undropped=None):
    """Everything about one ball whose centre is at x = (X1, X2) (m) from the outer groove centre."""
    D = bearing.ball_diameter
    X1, X2 = x[0], x[1]
    Lo = jnp.sqrt(X1 * X1 + X2 * X2)
    ui, vi = A1 - X1, A2 - X2
    Li = jnp.sqrt(ui * ui + vi * vi)
    delta_o = Lo - (bearing.f_outer - 0.5) * D - H_def
    delta_i = Li - (bearing.f_inner - 0.5) * D
    alpha_o = jnp.arctan2(X1, X2)
    alpha_i = jnp.arctan2(ui, vi)
    K_i = chebyshev_eval(curve.inner, vi / Li)
    K_o = chebyshev_eval(curve.outer, X2 / Lo)
    Q_i = K_i * jnp.maximum(delta_i, 0.0) ** 1.5
    Q_o = K_o * jnp.maximum(delta_o, 0.0) ** 1.5
    kin = ball_kinematics(bearing, op, alpha_i, alpha_o)
    wm, Fc, Mg = kin.orbital_speed, kin.centrifugal, kin.gyroscopic
    if wm_undropped is not None:
        # not driven by the inner ring over the spall: the cage carries it (MODEL.md 5)
        carried = (delta_i <= 0.0) & (H_def > 0.0)
        safe_wm = jnp.where(wm == 0.0, 1.0, wm)
        scale = jnp.where(carried & (wm != 0.0), (wm_undropped / safe_wm) ** 2, 1.0)
        wm = jnp.where(carried, wm_undropped, wm)
        Fc, Mg = Fc * scale, Mg * scale
    lam_i, lam_o = op.factors
    # gyroscopic friction terms exactly as MODEL.md writes them (for every ball)
    fi = lam_i * Mg / D
    fo = lam_o * Mg / D
    si, ci = jnp.sin(alpha_i), jnp.cos(alpha_i)
    so, co = jnp.sin(alpha_o), jnp.cos(alpha_o)
    G = Q_i * si + fi * ci
    Hr = Q_i * ci - fi * si
    r1 = G - Q_o * so - fo * co
    r2 = Hr - Q_o * co + fo * so + Fc
    moment = bearing.inner_groove_radius * G - bearing.f_inner * fi * D
    return BallState(X1, X2, alpha_i, alpha_o, delta_i, delta_o, Q_i, Q_o, K_i, K_o, Fc, Mg,
                     wm, kin.beta, G, Hr, moment, r1, r2)


def _static_ball_position(bearing, op, A1, A2, H_def, curve):
    """Closed-form ball centre at omega = 0 (collinear contacts); pushed onto the outer raceway
    when the ball would float at speed.  Exact solution when omega = 0."""
    D = bearing.ball_diameter
    L = jnp.sqrt(A1 * A1 + A2 * A2)
    alpha = jnp.arctan2(A1, A2)
    d_tot = L - bearing.A - H_def
    K_i = chebyshev_eval(curve.inner, A2 / L)
    K_o = chebyshev_eval(curve.outer, A2 / L)
    share_o = 1.0 / (1.0 + (K_o / K_i) ** (2.0 / 3.0))
    d_o = jnp.where(d_tot > 0.0, d_tot * share_o, 0.5 * d_tot)
    # at speed: at least the outer deflection that carries the ball's own centrifugal force
    Fc = ball_kinematics(bearing, op, alpha, alpha).centrifugal
    d_c = (Fc / K_o) ** (2.0 / 3.0)
    d_o = jnp.where(Fc > 0.0, jnp.maximum(d_o, d_c), d_o)
    Lo = (bearing.f_outer - 0.5) * D + H_def + d_o
    return jnp.stack([Lo * jnp.sin(alpha), Lo * jnp.cos(alpha)]), d_c


_BALL_MAXIT = 40


def ball_newton_step(bearing, op, A1, A2, H_def, curve, wm_undropped, d_c):
    """The damped Newton step of one ball's 2x2 equilibrium in micrometres, shared by the exact
    solve (:func:`solve_ball`) and the fixed-step solver of the dynamics: ``(f, step)`` with
    ``step(y) -> (y_new, |dy|_max, r)``.  The step is capped at ~ a contact deflection, and at
    speed (``d_c > 0``) a ball never leaves its outer raceway (F_c would bring it back)."""
    D = bearing.ball_diameter
    cap = 2e-3 * D / UM          # step cap (um): ~ a contact deflection

    def f(y):
        st = ball_state(bearing, op, y * UM, A1, A2, H_def, curve, wm_undropped)
        return jnp.stack([st.r_axial, st.r_radial]) / KN

    def step(y):
        J, r = jax.jacfwd(lambda v: (lambda rr: (rr, rr))(f(v)), has_aux=True)(y)
        mu = 1e-13 * (jnp.max(jnp.abs(J)) + 1e-30)
        dy = -jnp.linalg.solve(J + mu * jnp.eye(2), r)
        n = jnp.max(jnp.abs(dy))
        dy = jnp.where(n > cap, dy * (cap / n), dy)
        dy = jnp.where(jnp.all(jnp.isfinite(dy)), dy, 0.0)
        y_new = y + dy
        Lo = jnp.sqrt(y_new[0] ** 2 + y_new[1] ** 2) * UM
        d_o = Lo - (bearing.f_outer - 0.5) * D - H_def
        lift = (d_c > 0.0) & (d_o <= 0.0)
        target = ((bearing.f_outer - 0.5) * D + H_def + 0.5 * d_c) / jnp.where(Lo > 0, Lo, 1.0)
        return jnp.where(lift, y_new * target, y_new), n, r

    return f, step


def solve_ball(bearing, op, A1, A2, H_def, curve, wm_undropped=None, x_init=None):
    """Ball-centre position (m) in equilibrium for groove-centre offsets (A1, A2) and spall depth.

    Starts from the omega = 0 closed form, or from ``x_init`` (m; a nearby solution, e.g. the
    previous Newton iterate) where that keeps the ball on its outer raceway.  Differentiable
    (implicit function theorem via ``lax.custom_root``; the start does not enter derivatives).
    """
    D = bearing.ball_diameter
    x0, d_c = _static_ball_position(bearing, op, A1, A2, H_def, curve)
    if x_init is not None:
        Lo = jnp.sqrt(x_init[0] ** 2 + x_init[1] ** 2)
        usable = jnp.all(jnp.isfinite(x_init)) & (Lo > 0.0) & (
            (d_c <= 0.0) | (Lo - (bearing.f_outer - 0.5) * D - H_def > 0.0))
        x0 = jnp.where(usable, lax.stop_gradient(x_init), x0)
    f, step = ball_newton_step(bearing, op, A1, A2, H_def, curve, wm_undropped, d_c)

    def newton(f, y0):
        scale = jnp.maximum(jnp.max(jnp.abs(y0)), 1.0)

        def cond(c):
            y, it, done = c
            return (~done) & (it < _BALL_MAXIT)

        def body(c):
            y, it, _ = c
            y_new, n, r = step(y)
            done = (n <= 1e-10 * scale) | (jnp.max(jnp.abs(r)) <= 1e-15) | ~jnp.isfinite(n)
            return y_new, it + 1, done

        y, _, _ = lax.while_loop(cond, body, (y0, jnp.int32(0), jnp.bool_(False)))
        return y

    def tangent_solve(g, y):
        J = jax.jacfwd(g)(y)
        mu = 1e-13 * (jnp.max(jnp.abs(J)) + 1e-30)
        return jnp.linalg.solve(J + mu * jnp.eye(2), y)

    y = lax.custom_root(f, x0 / UM, newton, tangent_solve)
    return y * UM


def balls_at(bearing, op, q, psi, spall: Spall | None, curve, x_init=None):
    """Per-ball equilibrium states (a BallState of (Z,) arrays) for ring displacement q."""
    A1, A2 = groove_centre_offsets(bearing, q, psi)
    if spall is None:
        H_def = jnp.zeros_like(psi)
    else:
        H_def = depth_profile(bearing, spall, psi)

    def one(a1, a2, h, xi):
        if spall is None:
            x = solve_ball(bearing, op, a1, a2, h, curve, None, xi)
            return ball_state(bearing, op, x, a1, a2, h, curve)

        # two passes through one traced ball solve: first without the spall (the undropped
        # position gives the orbital speed of a ball the cage carries), then with it
        def passage(wm0, hh):
            start = xi
            if xi is not None:   # the warm start is the dropped position: lift it by h - hh
                Lo = jnp.sqrt(xi[0] ** 2 + xi[1] ** 2)
                start = xi * (Lo - (h - hh)) / jnp.where(Lo > 0.0, Lo, 1.0)
            x = solve_ball(bearing, op, a1, a2, hh, curve, wm0, start)
            st = ball_state(bearing, op, x, a1, a2, hh, curve, wm0)
            return st.omega_m, st

        _, sts = lax.scan(passage, jnp.zeros_like(a1), jnp.stack([jnp.zeros_like(h), h]))
        return jax.tree_util.tree_map(lambda a: a[1], sts)

    if x_init is None:
        return jax.vmap(lambda a1, a2, h: one(a1, a2, h, None))(A1, A2, H_def), H_def
    return jax.vmap(one)(A1, A2, H_def, x_init), H_def


def _reactions_from_balls(st: BallState, psi):
    c, s = jnp.cos(psi), jnp.sin(psi)
    return jnp.stack([jnp.sum(st.H * c), jnp.sum(st.H * s), jnp.sum(st.G),
                      jnp.sum(st.moment * s), -jnp.sum(st.moment * c)])


def ring_reactions(bearing, op, q, cage_angle=0.0, spall: Spall | None = None, hertz_method="exact",
                   curve=None):
    """Load-displacement map: the loads [Fx, Fy, Fz, Mx, My] (N, N m) the bearing carries at
    inner-ring displacement q = [dx, dy, dz, theta_x, theta_y] (m, rad), balls in equilibrium."""
    psi = bearing.ball_azimuths(cage_angle)
    curve = stiffness_curve(bearing, hertz_method) if curve is None else curve
    st, _ = balls_at(bearing, op, q, psi, spall, curve)
    return _reactions_from_balls(st, psi)


# ----------------------------------------------------------------------------------------
# Ring Newton
# ----------------------------------------------------------------------------------------
def _scales(bearing):
    Ri = bearing.inner_groove_radius
    qs = jnp.array([UM, UM, UM, 1.0, 1.0]) * jnp.array([1.0, 1.0, 1.0, UM / Ri, UM / Ri])
    rs = jnp.array([KN, KN, KN, KN * Ri, KN * Ri])
    return qs, rs


def _initial_displacement(bearing, loads, hertz_method):
    """A start where every ball touches: an axial shift giving each ball the deflection that
    would carry the whole load (no contact at all has a zero Jacobian)."""
    a0 = bearing.free_contact_angle
    BD = bearing.A
    Ri = bearing.inner_groove_radius
    Fz = loads[2]
    Fmag = jnp.abs(Fz) + jnp.hypot(loads[0], loads[1]) + 2.0 * jnp.hypot(loads[3], loads[4]) / Ri
    Ki = hertz_contact(bearing, a0, True, hertz_method).K
    Ko = hertz_contact(bearing, a0, False, hertz_method).K
    Kn = (Ki ** (-2.0 / 3.0) + Ko ** (-2.0 / 3.0)) ** (-1.5)
    d_n = (Fmag / (bearing.n_balls * Kn)) ** (2.0 / 3.0)
    sgn = jnp.where(Fz < 0.0, -1.0, 1.0)
    dz = sgn * jnp.sqrt(jnp.maximum((BD + d_n) ** 2 - (BD * jnp.cos(a0)) ** 2, 0.0)) - BD * jnp.sin(a0)
    dz = jnp.where(Fmag > 0.0, dz, 0.0)
    return jnp.array([0.0, 0.0, 1.0, 0.0, 0.0]) * dz


_LS_STEPS = 12


def _ring_newton(RJ, q0, F, qs, rs, maxit, rtol, atol, x_init_shape, ball_positions):
    """Damped Newton on R(q) = F in scaled variables.

    ``RJ(q, x_init) -> (J, (R, aux))`` evaluates the load-displacement map, its Jacobian and
    the ball states in one pass (ball solves warm-started from ``x_init``, the accepted iterate's
    ball positions ``ball_positions(aux)``; NaN = use the closed-form start).  A single loop does both Newton steps and backtracking: each pass
    evaluates one trial point; an accepted trial brings the Jacobian for the next step (one
    trace of the model, so compile time stays small).
    Returns (q, J, aux, result, iterations, residual max-norm in N).
    """
    Fn = F / rs
    tol = atol / KN + rtol * jnp.max(jnp.abs(Fn))
    cap = 200.0   # um (or um at R_i) per Newton step

    def evaluate(z, x_init):
        J, (R, aux) = RJ(z * qs, x_init)
        return R / rs - Fn, J * (qs[None, :] / rs[:, None]), J, aux

    def direction(Js, r):
        mu = 1e-13 * (jnp.max(jnp.abs(Js)) + 1e-30)
        dz = -jnp.linalg.solve(Js + mu * jnp.eye(5), r)
        n = jnp.max(jnp.abs(dz))
        return jnp.where(n > cap, dz * (cap / jnp.where(n > 0, n, 1.0)), dz)

    def cond(c):
        return c["code"] < 0

    def body(c):
        zt = c["z"] + c["t"] * c["dz"]
        first = c["it"] < 0
        rt, Jst, Jt, auxt = evaluate(zt, jnp.where(first, jnp.nan, ball_positions(c["aux"])))
        rn = jnp.max(jnp.abs(rt))
        r0 = jnp.max(jnp.abs(c["r"]))
        finite = jnp.isfinite(rn) & jnp.all(jnp.isfinite(Jst))
        ok = first | (finite & (rn <= (1.0 - 1e-4 * c["t"]) * r0))
        sel = lambda new, old: jax.tree_util.tree_map(lambda u, v: jnp.where(ok, u, v), new, old)
        z, r, Js, J, aux = sel((zt, rt, Jst, Jt, auxt), (c["z"], c["r"], c["Js"], c["J"], c["aux"]))
        it = jnp.where(ok, c["it"] + 1, c["it"])
        ls = jnp.where(ok, 0, c["ls"] + 1)
        rnow = jnp.max(jnp.abs(r))
        conv = rnow <= tol
        # at the round-off floor a failed line search with a tiny residual is convergence
        stalled = ls >= _LS_STEPS
        code = jnp.where(first & ~finite, 2,
               jnp.where(conv | (stalled & (rnow <= 1e3 * tol)), 0,
               jnp.where(stalled, 3, jnp.where(ok & (it >= maxit), 1, -1))))
        dz = jnp.where(ok, direction(Js, r), c["dz"])
        t = jnp.where(ok, 1.0, 0.5 * c["t"])
        return dict(z=z, r=r, Js=Js, J=J, aux=aux, dz=dz, t=t, it=it, ls=ls,
                    code=code.astype(jnp.int32))

    z0 = q0 / qs
    # shapes of the evaluation's outputs, without tracing the model a second time
    x_shape = jax.ShapeDtypeStruct(x_init_shape, jnp.float64)
    shapes = jax.eval_shape(evaluate, z0, x_shape)
    zeros = jax.tree_util.tree_map(lambda s: jnp.zeros(s.shape, s.dtype), shapes)
    init = dict(z=z0, r=zeros[0], Js=zeros[1], J=zeros[2], aux=zeros[3], dz=jnp.zeros(5),
                t=jnp.float64(0.0), it=jnp.int32(-1), ls=jnp.int32(0), code=jnp.int32(-1))
    c = lax.while_loop(cond, body, init)
    return c["z"] * qs, c["J"], c["aux"], c["code"], c["it"], jnp.max(jnp.abs(c["r"])) * KN


# ----------------------------------------------------------------------------------------
# Public solve
# ----------------------------------------------------------------------------------------
class JonesSolution(eqx.Module):
    """Quasi-static solution.  Arrays are SI (m, rad, N, N m, rad/s); per-ball arrays are (Z,)
    (with a leading batch axis after ``solve_batch``).

    ``result`` is 0 when converged (see ``RESULT_MESSAGES``); ``residual_norm`` is the max-norm
    of the ring equilibrium residual in N (moments divided by R_i).
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
    spall_depth: jnp.ndarray
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
    stiffness: jnp.ndarray          # dR/dq (5, 5): N/m, N/rad, N m/m, N m/rad

    @property
    def converged(self):
        return self.result == 0

    @property
    def cage_speed(self):
        """Cage speed omega_c (rad/s): the mean of the balls' orbital speeds."""
        return jnp.mean(self.orbital_speed, axis=-1)

    def message(self):
        import numpy as np
        codes = np.atleast_1d(np.asarray(self.result))
        return [RESULT_MESSAGES.get(int(c), f"unknown result {int(c)}") for c in codes]


def _solve(bearing, op, loads, cage_angle, spall, q0, speed_steps, maxit, rtol, atol, hertz_method):
    qs, rs = _scales(bearing)
    psi = bearing.ball_azimuths(cage_angle)
    F = jnp.asarray(loads, dtype=jnp.float64)
    curve = stiffness_curve(bearing, hertz_method)

    if q0 is None:
        q0 = _initial_displacement(bearing, F, hertz_method)
        fracs = [0.0] + [k / speed_steps for k in range(1, speed_steps + 1)]
    else:
        q0 = jnp.asarray(q0, dtype=jnp.float64)
        fracs = [k / speed_steps for k in range(1, speed_steps + 1)]

    def stage(q, frac):
        o = eqx.tree_at(lambda p: p.speed, op, op.speed * frac)

        def R_aux(qq, x_init):
            st, H_def = balls_at(bearing, o, qq, psi, spall, curve, x_init)
            R = _reactions_from_balls(st, psi)
            return R, (R, (st, H_def))

        RJ = jax.jacfwd(R_aux, has_aux=True)
        q, J, aux, code, it, res = _ring_newton(
            RJ, q, F, qs, rs, maxit, rtol, atol, (bearing.n_balls, 2),
            lambda aux: jnp.stack([aux[0].X1, aux[0].X2], axis=-1))
        return q, (J, aux, code, it, res)

    # later stages start from the last iterate of the one before; the final stage decides
    q, (Js, auxs, codes, its, ress) = lax.scan(stage, q0, jnp.asarray(fracs))
    last = lambda a: a[-1]
    K, (st, H_def), code, res = jax.tree_util.tree_map(last, (Js, auxs, codes, ress))
    total_it = jnp.sum(its)
    hi = hertz_contact(bearing, st.alpha_i, True, hertz_method)
    ho = hertz_contact(bearing, st.alpha_o, False, hertz_method)
    Ep = bearing.effective_modulus
    a_i, b_i, p_i = semi_axes(hi, st.Q_i, Ep)
    a_o, b_o, p_o = semi_axes(ho, st.Q_o, Ep)
    finite = jnp.all(jnp.isfinite(q)) & jnp.all(jnp.isfinite(st.Q_i)) & jnp.all(jnp.isfinite(st.Q_o))
    code = jnp.where(finite, code, 2)
    return JonesSolution(q, F, code, total_it, res, jnp.asarray(cage_angle, jnp.float64), psi,
                         st.alpha_i, st.alpha_o, st.Q_i, st.Q_o, st.delta_i, st.delta_o, st.Fc,
                         st.Mg, st.omega_m, st.beta, H_def, st.G, st.H, st.moment, st.K_i, st.K_o,
                         p_i, p_o, a_i, b_i, a_o, b_o, K)


_solve_jit = eqx.filter_jit(_solve)


def _traced_tolerances(maxit, rtol, atol):
    # arrays, not Python scalars: changing a tolerance must not recompile
    return jnp.asarray(maxit, jnp.int32), jnp.asarray(rtol, jnp.float64), jnp.asarray(atol, jnp.float64)


class NotConvergedError(RuntimeError):
    """A quasi-static solve did not converge."""


def solve(bearing, op: Operation, loads, cage_angle=0.0, spall: Spall | None = None, q0=None,
          speed_steps: int = 1, maxit: int = 60, rtol: float = 1e-11, atol: float = 1e-9,
          hertz_method: str = "exact", throw: bool = True) -> JonesSolution:
    """Solve the Jones model for one load case.

    ``loads`` = [Fx, Fy, Fz, Mx, My] (N, N m) on the inner ring (see :func:`load_vector`).
    Starts from the rigid-ring static solution (omega = 0) unless ``q0`` is given, then goes
    to speed in ``speed_steps`` steps; if that fails it retries once with 8 speed steps.
    Raises :class:`NotConvergedError` (``throw=True``) with the residual and a hint.
    """
    loads = jnp.asarray(loads, dtype=jnp.float64)
    cage_angle = jnp.asarray(cage_angle, dtype=jnp.float64)
    q0 = None if q0 is None else jnp.asarray(q0, dtype=jnp.float64)
    maxit, rtol, atol = _traced_tolerances(maxit, rtol, atol)
    sol = _solve_jit(bearing, op, loads, cage_angle, spall, q0, speed_steps, maxit, rtol, atol,
                     hertz_method)
    if int(sol.result) != 0 and speed_steps < 8:
        retry = _solve_jit(bearing, op, loads, cage_angle, spall, None, 8, maxit, rtol, atol,
                           hertz_method)
        if int(retry.result) == 0:
            sol = retry
    if throw and int(sol.result) != 0:
        raise NotConvergedError(
            f"Jones solve did not converge: {RESULT_MESSAGES.get(int(sol.result))} after "
            f"{int(sol.iterations)} iterations, ring residual {float(sol.residual_norm):.3g} N. "
            "Hint: check that the loads can be carried by this bearing (a single-row angular "
            "contact bearing needs axial load in its contact direction to carry moments and "
            "radial load), or lower the speed.")
    return sol


def _solve_batch(bearing, op, loads, cage_angle, spall, speed_steps, maxit, rtol, atol, hertz_method):
    def one(o, F, c):
        return _solve(bearing, o, F, c, spall, None, speed_steps, maxit, rtol, atol, hertz_method)

    return jax.vmap(one)(op, loads, cage_angle)


_solve_batch_jit = eqx.filter_jit(_solve_batch)


def solve_batch(bearing, op: Operation, loads, cage_angle=0.0, spall: Spall | None = None,
                speed_steps: int = 1, maxit: int = 60, rtol: float = 1e-11, atol: float = 1e-9,
                hertz_method: str = "exact") -> JonesSolution:
    """vmapped solve over N load cases ``loads`` (N, 5); ``op.speed`` may be (N,) or scalar.

    Never raises: check ``solution.result`` per item (0 = converged).
    """
    loads = jnp.asarray(loads, dtype=jnp.float64)
    n = loads.shape[0]
    op_b = eqx.tree_at(lambda p: (p.speed, p.centrifugal, p.gyroscopic), op,
                       (jnp.broadcast_to(op.speed, (n,)), jnp.broadcast_to(op.centrifugal, (n,)),
                        jnp.broadcast_to(op.gyroscopic, (n,))))
    cage = jnp.broadcast_to(jnp.asarray(cage_angle, dtype=jnp.float64), (n,))
    maxit, rtol, atol = _traced_tolerances(maxit, rtol, atol)
    return _solve_batch_jit(bearing, op_b, loads, cage, spall, speed_steps, maxit, rtol, atol,
                            hertz_method)
