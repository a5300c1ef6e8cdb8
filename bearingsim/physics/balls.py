"""The per-ball Jones kernel (docs/model.md sections 3-5): one home for the ball equations.

Everything here is about one ball (vmapped over balls by the callers):

* :func:`groove_centre_offsets` -- (A1, A2) from the ring displacement q and the azimuth psi,
  and :func:`offset_jacobian`, their (linear) derivative with respect to q;
* :func:`ball_equations` -- the ball's two equilibrium residuals and its loads on the inner ring
  (G, H, m) for a ball centre (X1, X2); free of transcendental functions (sines and cosines of
  the contact angles are ratios of the geometry, ``delta**1.5 = delta*sqrt(delta)``, K(alpha)
  is a power series in cos(alpha)), because the solvers evaluate it millions of times;
* :func:`ball_state` -- the full state of a ball (angles, loads, speeds) for reporting;
* :func:`static_ball_position` -- the omega = 0 closed form (collinear contacts; exact at rest),
  and at speed for a ball its raceways barely reach the corner of the raceways F_c rolls it to;
* :func:`ball_newton_step`, :func:`solve_ball_fixed` (a fixed number of damped Newton steps,
  the dynamics' solver) and :func:`solve_ball` (to convergence, implicitly differentiable);
* :func:`balls_at` -- every ball in equilibrium for a given q (the load-displacement map), and
  :func:`reactions_from_balls` -- the loads [Fx, Fy, Fz, Mx, My] they put on the inner ring.

Contact rule (docs/model.md section 3): a contact carries Q = K delta^1.5 only when delta > 0 AND its
normal points into its raceway (cos alpha > 0).  A ball pushed past the inner groove-curvature
centre (deep spall) has lost its inner contact; it never acts as a tie.

A ball that has lost its inner contact over a defect is carried by the cage: its orbital speed
(hence F_c and M_g) is that of its undropped position (same q, no defect), docs/model.md section 5.

Units: SI inside the physics; the solvers' unknowns are micrometres (``UM``) and residuals kN
(``KN``) so that one tolerance fits every ball.
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import lax

from .newton import inverse2, solve2  # noqa: F401  (re-exported: jones and shaft take them from here)
from ..fastmath import clamp, kernel, norm2, pow15, recip, safe_div
from .hertz import power_eval
from .kinematics import Operation, ball_kinematics_cs

__all__ = [
    "UM",
    "KN",
    "BallState",
    "groove_centre_offsets",
    "groove_centre_offsets_cs",
    "offset_jacobian",
    "ball_equations",
    "ball_state",
    "contact_record",
    "ball_balance",
    "orbital_speed",
    "static_ball_position",
    "ball_newton_step",
    "solve_ball_fixed",
    "solve_ball",
    "balls_at",
    "reactions_from_balls",
    "reaction_matrix",
]

UM = 1e-6          # unknown scale (m)
KN = 1e3           # residual scale (N)


class BallState(NamedTuple):
    """State of the balls (arrays of shape (Z,) or scalars; SI).  Field names are those of
    :class:`bearingsim.physics.jones.JonesSolution`."""

    X1: jnp.ndarray                 # ball centre, axial, from the outer groove centre (m)
    X2: jnp.ndarray                 # ball centre, radial (m)
    alpha_inner: jnp.ndarray        # rad
    alpha_outer: jnp.ndarray
    delta_inner: jnp.ndarray        # contact deformation (m; negative = gap)
    delta_outer: jnp.ndarray
    Q_inner: jnp.ndarray            # contact load (N)
    Q_outer: jnp.ndarray
    K_inner: jnp.ndarray            # Hertz constant at the contact's own angle (N/m^1.5)
    K_outer: jnp.ndarray
    centrifugal: jnp.ndarray        # F_c (N)
    gyroscopic_moment: jnp.ndarray  # M_g (N m)
    orbital_speed: jnp.ndarray      # omega_m (rad/s)
    beta: jnp.ndarray               # spin-axis pitch angle (rad)
    ball_G: jnp.ndarray             # axial force on the ball from the inner ring (N)
    ball_H: jnp.ndarray             # radial force on the ball from the inner ring (N)
    ball_moment: jnp.ndarray        # m_j = R_i G - lambda_i f_i M_g (N m)
    r_axial: jnp.ndarray            # ball equilibrium residuals (N)
    r_radial: jnp.ndarray


# ----------------------------------------------------------------------------- geometry
def groove_centre_offsets(bearing, q, psi):
    """(A1, A2): axial and radial distance from the outer to the inner groove-curvature centre
    of the ball at azimuth psi, for ring displacement q = [dx, dy, dz, theta_x, theta_y]."""
    return groove_centre_offsets_cs(bearing, q, jnp.sin(psi), jnp.cos(psi))


def groove_centre_offsets_cs(bearing, q, sin_psi, cos_psi):
    """:func:`groove_centre_offsets` from the azimuths' sines and cosines."""
    BD = bearing.A
    a0 = bearing.free_contact_angle
    Ri = bearing.inner_groove_radius
    s, c = sin_psi, cos_psi
    A1 = BD * jnp.sin(a0) + q[2] + Ri * (q[3] * s - q[4] * c)
    A2 = BD * jnp.cos(a0) + q[0] * c + q[1] * s
    return A1, A2


def offset_jacobian(bearing, psi):
    """d(A1, A2)/dq: (..., 2, 5) for azimuths psi (the offsets are linear in q)."""
    Ri = bearing.inner_groove_radius
    s, c = jnp.sin(psi), jnp.cos(psi)
    z, o = jnp.zeros_like(psi), jnp.ones_like(psi)
    dA1 = jnp.stack([z, z, o, Ri * s, -Ri * c], axis=-1)
    dA2 = jnp.stack([c, s, z, z, z], axis=-1)
    return jnp.stack([dA1, dA2], axis=-2)


def reaction_matrix(psi):
    """T (..., 5, 3): the ring loads [Fx, Fy, Fz, Mx, My] from one ball's (G, H, m)."""
    s, c = jnp.sin(psi), jnp.cos(psi)
    z, o = jnp.zeros_like(psi), jnp.ones_like(psi)
    rows = [jnp.stack(r, axis=-1) for r in ([z, c, z], [z, s, z], [o, z, z], [z, z, s], [z, z, -c])]
    return jnp.stack(rows, axis=-2)


def _quotient(a, b):
    """a / b where b > 0, else 0, rounded as a division (the closed form is not differentiated)."""
    ok = b > 0.0
    return jnp.where(ok, a / jnp.where(ok, b, 1.0), 0.0)


def _pow15(loaded, delta):
    """delta^1.5 where ``loaded``, else 0, with finite derivatives everywhere (no pow)."""
    return jnp.where(loaded, pow15(jnp.where(loaded, delta, 1.0)), 0.0)


# ------------------------------------------------------------------------ ball equations
class _Contacts(NamedTuple):
    so: jnp.ndarray
    co: jnp.ndarray
    si: jnp.ndarray
    ci: jnp.ndarray
    delta_i: jnp.ndarray
    delta_o: jnp.ndarray
    K_i: jnp.ndarray
    K_o: jnp.ndarray
    Q_i: jnp.ndarray
    Q_o: jnp.ndarray


def _contacts_geometry(X1, X2, A1, A2):
    """(sin a_o, cos a_o, sin a_i, cos a_i, L_o, L_i): the contact directions and the centre
    distances of a ball at (X1, X2)."""
    ui, vi = A1 - X1, A2 - X2
    Lo, ro = norm2(X1, X2)            # a length and its reciprocal: one sqrt, one division
    Li, ri = norm2(ui, vi)
    return X1 * ro, X2 * ro, ui * ri, vi * ri, Lo, Li


def _contacts(bearing, curve, X1, X2, A1, A2, H_outer, H_inner):
    D = bearing.ball_diameter
    so, co, si, ci, Lo, Li = _contacts_geometry(X1, X2, A1, A2)
    delta_o = Lo - (bearing.f_outer - 0.5) * D - H_outer
    delta_i = Li - (bearing.f_inner - 0.5) * D - H_inner
    K_i = power_eval(curve.inner_power, ci)
    K_o = power_eval(curve.outer_power, co)
    # docs/model.md section 3: load only with overlap AND a normal that points into the raceway
    Q_i = K_i * _pow15((delta_i > 0.0) & (ci > 0.0), delta_i)
    Q_o = K_o * _pow15((delta_o > 0.0) & (co > 0.0), delta_o)
    return _Contacts(so, co, si, ci, delta_i, delta_o, K_i, K_o, Q_i, Q_o)


def _forces(bearing, op: Operation, c: _Contacts, H_outer, H_inner, carried_speed):
    """Kinematics and the ball's equilibrium: (r1, r2, G, H, m, omega_m, Fc, Mg, sin b, cos b)."""
    D = bearing.ball_diameter
    sb, cb, wm, _, Fc, Mg = ball_kinematics_cs(bearing, op, c.si, c.ci, c.so, c.co)
    if carried_speed is not None:
        # not driven by the inner ring over a defect: the cage carries it (docs/model.md section 5)
        carried = (c.Q_i <= 0.0) & ((H_outer + H_inner) > 0.0)
        ratio = carried_speed * recip(jnp.where(wm != 0.0, wm, 1.0))
        scale = jnp.where(carried & (wm != 0.0), ratio * ratio, 1.0)
        wm = jnp.where(carried, carried_speed, wm)
        Fc, Mg = Fc * scale, Mg * scale
    lam_i, lam_o = op.factors
    fi = (lam_i / D) * Mg
    fo = (lam_o / D) * Mg
    G = c.Q_i * c.si + fi * c.ci
    H = c.Q_i * c.ci - fi * c.si
    r1 = G - c.Q_o * c.so - fo * c.co
    r2 = H - c.Q_o * c.co + fo * c.so + Fc
    m = bearing.inner_groove_radius * G - bearing.f_inner * fi * D
    return r1, r2, G, H, m, wm, Fc, Mg, sb, cb


def ball_equations(bearing, op: Operation, curve, v, H_outer=0.0, H_inner=0.0, carried_speed=None):
    """One ball in scaled units.  ``v = [X1, X2, A1, A2]`` in micrometres; returns
    ``(out, omega_m)`` with ``out = [r_axial, r_radial, G, H, m / R_i]`` in kN (residuals of the
    ball's equilibrium and its loads on the inner ring) and the orbital speed (rad/s)."""
    X1, X2, A1, A2 = v[0] * UM, v[1] * UM, v[2] * UM, v[3] * UM
    c = _contacts(bearing, curve, X1, X2, A1, A2, H_outer, H_inner)
    r1, r2, G, H, m, wm, *_ = _forces(bearing, op, c, H_outer, H_inner, carried_speed)
    out = jnp.stack([r1, r2, G, H, m / bearing.inner_groove_radius]) / KN
    return out, wm


def orbital_speed(bearing, op: Operation, X1, X2, A1, A2):
    """The orbital speed omega_m (rad/s) of a ball centred at (X1, X2) (m) with the inner
    groove-curvature centre at (A1, A2): that of :func:`ball_state` (it depends on the contact
    angles only, not on the loads)."""
    c = _contacts_geometry(X1, X2, A1, A2)
    return ball_kinematics_cs(bearing, op, c[2], c[3], c[0], c[1])[2]


def ball_state(bearing, op: Operation, x, A1, A2, curve, H_outer=0.0, H_inner=0.0,
               carried_speed=None) -> BallState:
    """Everything about one ball whose centre is at x = (X1, X2) (m) from the outer groove centre."""
    X1, X2 = x[0], x[1]
    c = _contacts(bearing, curve, X1, X2, A1, A2, H_outer, H_inner)
    r1, r2, G, H, m, wm, Fc, Mg, sb, cb = _forces(bearing, op, c, H_outer, H_inner, carried_speed)
    return BallState(X1, X2, jnp.arctan2(A1 - X1, A2 - X2), jnp.arctan2(X1, X2), c.delta_i,
                     c.delta_o, c.Q_i, c.Q_o, c.K_i, c.K_o, Fc, Mg, wm, jnp.arctan2(sb, cb), G, H,
                     m, r1, r2)


def contact_record(bearing, curve, x, A1, A2, H_outer=0.0, H_inner=0.0):
    """(Q_inner, Q_outer, sin a_i, cos a_i, sin a_o, cos a_o) of a ball centred at x = (X1, X2)
    stacked on a leading axis: the loads and contact directions of :func:`ball_state` without
    its kinematics and angles (a time loop records these and takes the arctangents afterwards:
    alpha = arctan2(sin, cos))."""
    c = _contacts(bearing, curve, x[0], x[1], A1, A2, H_outer, H_inner)
    return jnp.stack([c.Q_i, c.Q_o, c.si, c.ci, c.so, c.co])


def _contacts_stacked(bearing, curve, X1, X2, A1, A2, H_outer, H_inner):
    """:func:`_contacts` with the outer and the inner contact stacked on a leading axis (2, ...):
    the same operations per element (the same values), but one square root, one division and
    one ``delta**1.5`` for both contacts -- each of them is a kernel of its own in a compiled
    time step (XLA does not duplicate them into their consumers)."""
    D = bearing.ball_diameter
    z = jnp.zeros_like(X1 + A1)
    L, rL = norm2(jnp.stack([X1 + z, A1 - X1]), jnp.stack([X2 + z, A2 - X2]))
    sn, cs = jnp.stack([X1 + z, A1 - X1]) * rL, jnp.stack([X2 + z, A2 - X2]) * rL
    free = jnp.stack([(bearing.f_outer - 0.5) * D + H_outer + z, (bearing.f_inner - 0.5) * D + H_inner + z])
    delta = L - free
    # K(alpha) of each contact: power_eval's Horner with the row's own coefficients
    coeffs = jnp.stack([curve.outer_power, curve.inner_power])
    x = clamp(cs, -1.0, 1.0)
    sh = (2,) + (1,) * (x.ndim - 1)
    K = jnp.reshape(coeffs[:, -1], sh) + jnp.zeros_like(x)
    for k in range(coeffs.shape[-1] - 2, -1, -1):
        K = K * x + jnp.reshape(coeffs[:, k], sh)
    K = kernel(K)           # read by Q, the record and every tangent: computed once (fastmath.kernel)
    Q = K * _pow15((delta > 0.0) & (cs > 0.0), delta)
    return _Contacts(sn[0], cs[0], sn[1], cs[1], delta[1], delta[0], K[1], K[0], Q[1], Q[0])


def ball_balance(bearing, op: Operation, x, A1, A2, curve, H_outer=0.0, H_inner=0.0, carried_speed=None):
    """One plain evaluation of a ball centred at x = (X1, X2) (m): its equilibrium residuals
    (r_axial, r_radial) (N), its loads (G, H) on the inner ring (N) and its contact record
    (:func:`contact_record`, stacked on a leading axis), all from the same contacts -- what the
    dynamics' chord step needs (no derivatives, no arctangents; both contacts evaluated as one
    stacked array, the values of :func:`ball_state`)."""
    c = _contacts_stacked(bearing, curve, x[0], x[1], A1, A2, H_outer, H_inner)
    r1, r2, G, H, *_ = _forces(bearing, op, c, H_outer, H_inner, carried_speed)
    return r1, r2, G, H, jnp.stack([c.Q_i, c.Q_o, c.si, c.ci, c.so, c.co])


#: :func:`static_ball_position` starts a barely reached ball at speed in the raceways' corner
#: (False: the collinear start of earlier versions; tests/test_balls.py compares the two)
LENS_START = True


def static_ball_position(bearing, op: Operation, A1, A2, curve, H_outer=0.0, H_inner=0.0):
    """Closed-form ball centre at omega = 0 (collinear contacts, delta_i/delta_o =
    (K_o/K_i)^(2/3)), exact at rest; at speed it is pushed out to at least the outer deflection
    that carries the ball's own centrifugal force (returned as ``d_c``, m), and where the
    raceways barely reach it (d_tot share_o < d_c) it starts in their corner (see below: the
    start from which a lightly loaded ball's Newton steps converge quadratically)."""
    D = bearing.ball_diameter
    L = jnp.sqrt(A1 * A1 + A2 * A2)
    s, c = _quotient(A1, L), _quotient(A2, L)
    d_tot = L - bearing.A - H_outer - H_inner
    K_i = power_eval(curve.inner_power, c)
    K_o = power_eval(curve.outer_power, c)
    share_o = 1.0 / (1.0 + jnp.cbrt(K_o / K_i) ** 2)
    d_o = jnp.where(d_tot > 0.0, d_tot * share_o, 0.5 * d_tot)
    Fc = ball_kinematics_cs(bearing, op, s, c, s, c)[4]
    d_c = jnp.cbrt(jnp.maximum(Fc, 0.0) / K_o) ** 2
    d_o = jnp.where(Fc > 0.0, jnp.maximum(d_o, d_c), d_o)
    Lo = (bearing.f_outer - 0.5) * D + H_outer + d_o
    X1, X2 = Lo * s, Lo * c
    if LENS_START:
        # A ball at speed that its raceways barely reach (d_tot share_o < d_c: at the edge of the
        # load zone, over a shallow pit) rests where F_c puts it, not on the line of the groove
        # centres: on the outer raceway at the overlap d_c that carries F_c, rolled towards the
        # groove bottom (alpha_o -> 0) until it meets the inner raceway -- the corner where the
        # circles of overlap d_c (outer) and d_c (1 - share_o) / share_o (inner) around the two
        # groove centres intersect, or alpha_o = 0 if it gets there first.  The collinear start
        # lies where both contacts are nearly unloaded: Newton's first step from that (zero-
        # stiffness) point overshoots along the groove and then creeps back over 5-8 steps.
        # Continuous: at d_tot share_o = d_c the corner is the collinear start (h = 0).
        lens = (Fc > 0.0) & (d_tot * share_o < d_c)
        ro = (bearing.f_outer - 0.5) * D + H_outer + d_c
        ri = (bearing.f_inner - 0.5) * D + H_inner + d_c * (1.0 - share_o) * _quotient(1.0, share_o)
        a = (L * L + ro * ro - ri * ri) * _quotient(0.5, L)
        h = jnp.sqrt(jnp.maximum(ro * ro - a * a, 0.0))
        sg = jnp.where(s >= 0.0, 1.0, -1.0)
        Y1 = a * s - sg * h * c
        past = sg * Y1 < 0.0                    # the corner lies beyond alpha_o = 0
        Y1 = jnp.where(past, 0.0, Y1)
        Y2 = jnp.where(past, ro, a * c + sg * h * s)
        X1, X2 = jnp.where(lens, Y1, X1), jnp.where(lens, Y2, X2)
    return jnp.stack([X1, X2]), d_c


def lift_onto_outer(bearing, y, d_c, H_outer):
    """At speed (``d_c > 0``) a ball never leaves its outer raceway (F_c brings it back): a
    position ``y`` (um) with no outer overlap is moved out to half the deflection d_c."""
    D = bearing.ball_diameter
    Lo = jnp.sqrt(y[..., 0] ** 2 + y[..., 1] ** 2) * UM
    d_o = Lo - (bearing.f_outer - 0.5) * D - H_outer
    lift = (d_c > 0.0) & (d_o <= 0.0)
    target = safe_div((bearing.f_outer - 0.5) * D + H_outer + 0.5 * d_c, Lo)
    return jnp.where(lift[..., None], y * target[..., None], y)


def ball_newton_step(bearing, op, A1, A2, curve, H_outer, H_inner, carried_speed, d_c):
    """The damped Newton step of one ball's 2x2 equilibrium (q fixed) in micrometres:
    ``step(y) -> (y_new, |dy|_max, r)``.  The step is capped at ~ a contact deflection (2e-3 D)
    and a ball at speed never leaves its outer raceway."""
    cap = 2e-3 * bearing.ball_diameter / UM
    a = jnp.stack([A1, A2]) / UM

    def f(y):
        out, _ = ball_equations(bearing, op, curve, jnp.concatenate([y, a]), H_outer, H_inner,
                                carried_speed)
        return out[:2]

    def step(y):
        J, r = jax.jacfwd(lambda v: (lambda rr: (rr, rr))(f(v)), has_aux=True)(y)
        dy = -solve2(J, r)
        n = jnp.max(jnp.abs(dy))
        dy = jnp.where(n > cap, dy * (cap / n), dy)
        dy = jnp.where(jnp.all(jnp.isfinite(dy)), dy, 0.0)
        return lift_onto_outer(bearing, y + dy, d_c, H_outer), n, r

    return f, step


def solve_ball_fixed(bearing, op, A1, A2, curve, H_outer=0.0, H_inner=0.0, carried_speed=None,
                     iterations=3, x_init=None):
    """Ball centre (m) after a fixed number of Newton steps from the omega = 0 closed form (or
    ``x_init``): no while loop, a fixed cost (the dynamics' solver)."""
    x0, d_c = static_ball_position(bearing, op, A1, A2, curve, H_outer, H_inner)
    if x_init is not None:
        x0 = _usable_start(bearing, x_init, x0, d_c, H_outer)
    _, step = ball_newton_step(bearing, op, A1, A2, curve, H_outer, H_inner, carried_speed, d_c)
    y = lax.fori_loop(0, iterations, lambda _, yy: step(yy)[0], x0 / UM)
    return y * UM


def _usable_start(bearing, x_init, x0, d_c, H_outer):
    D = bearing.ball_diameter
    Lo = jnp.sqrt(x_init[0] ** 2 + x_init[1] ** 2)
    usable = jnp.all(jnp.isfinite(x_init)) & (Lo > 0.0) & (
        (d_c <= 0.0) | (Lo - (bearing.f_outer - 0.5) * D - H_outer > 0.0))
    return jnp.where(usable, lax.stop_gradient(x_init), x0)


_BALL_MAXIT = 40


def solve_ball(bearing, op, A1, A2, curve, H_outer=0.0, H_inner=0.0, carried_speed=None,
               x_init=None):
    """Ball-centre position (m) in equilibrium, iterated to convergence (at most 40 damped Newton
    steps).  Differentiable: the implicit function theorem via ``lax.custom_root``."""
    x0, d_c = static_ball_position(bearing, op, A1, A2, curve, H_outer, H_inner)
    if x_init is not None:
        x0 = _usable_start(bearing, x_init, x0, d_c, H_outer)
    f, step = ball_newton_step(bearing, op, A1, A2, curve, H_outer, H_inner, carried_speed, d_c)

    def newton(f, y0):
        scale = jnp.maximum(jnp.max(jnp.abs(y0)), 1.0)

        def cond(c):
            return (~c[2]) & (c[1] < _BALL_MAXIT)

        def body(c):
            y_new, n, r = step(c[0])
            done = (n <= 1e-10 * scale) | (jnp.max(jnp.abs(r)) <= 1e-15) | ~jnp.isfinite(n)
            return y_new, c[1] + 1, done

        return lax.while_loop(cond, body, (y0, jnp.int32(0), jnp.bool_(False)))[0]

    def tangent_solve(g, y):
        return solve2(jax.jacfwd(g)(y), y)

    return lax.custom_root(f, x0 / UM, newton, tangent_solve) * UM


def balls_at(bearing, op, q, psi, curve, H_outer=None, H_inner=None, x_init=None, iterations=None):
    """Every ball in equilibrium for ring displacement q (a :class:`BallState` of (Z,) arrays).

    ``H_outer``/``H_inner``: defect depth under each ball (m, (Z,); None = healthy).  Balls over
    a defect are solved twice (first without it: the cage carries a ball that lost its inner
    contact at the orbital speed of its undropped position).  ``iterations=None`` iterates each
    ball to convergence (:func:`solve_ball`); an integer uses that many Newton steps."""
    A1, A2 = groove_centre_offsets(bearing, q, psi)
    defect = H_outer is not None or H_inner is not None
    Ho = jnp.zeros_like(psi) if H_outer is None else H_outer
    Hi = jnp.zeros_like(psi) if H_inner is None else H_inner
    xi = jnp.full(psi.shape + (2,), jnp.nan) if x_init is None else x_init

    def solve_one(a1, a2, ho, hi, ws, start):
        if iterations is None:
            return solve_ball(bearing, op, a1, a2, curve, ho, hi, ws, start)
        return solve_ball_fixed(bearing, op, a1, a2, curve, ho, hi, ws, iterations, start)

    def one(a1, a2, ho, hi, x0):
        ws = None
        if defect:
            z = jnp.zeros_like(ho)
            xu = solve_one(a1, a2, z, z, None, None)
            ws = ball_state(bearing, op, xu, a1, a2, curve).orbital_speed
        x = solve_one(a1, a2, ho, hi, ws, None if x_init is None else x0)
        return ball_state(bearing, op, x, a1, a2, curve, ho, hi, ws)

    return jax.vmap(one)(A1, A2, Ho, Hi, xi)


def reactions_from_balls(st: BallState, psi):
    """Loads [Fx, Fy, Fz, Mx, My] (N, N m) the balls put on the inner ring (docs/model.md section 4)."""
    c, s = jnp.cos(psi), jnp.sin(psi)
    return jnp.stack([jnp.sum(st.ball_H * c), jnp.sum(st.ball_H * s), jnp.sum(st.ball_G),
                      jnp.sum(st.ball_moment * s), -jnp.sum(st.ball_moment * c)])
