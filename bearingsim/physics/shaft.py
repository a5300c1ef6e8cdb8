"""A rigid shaft on N bearings (docs/model.md section 10): preloaded sets (DB, DF, DT, triplex,
quadruplex, ...), rigid and spring preload, two-support rotors.

Model
-----
The shaft carries every inner ring.  Its displacement q_s = [dx, dy, dz, theta_x, theta_y] is taken
at the reference point O (z = 0 on the axis); the external loads F_s = [Fx, Fy, Fz, Mx, My] act
there.  Bearing k (its own :class:`~bearingsim.physics.geometry.Bearing`, axial position z_k of its inner
groove-centre plane, facing s_k = +1 / -1, preload) sees, in its own frame (docs/model.md sections 1 and 4
unchanged there):

    q_k = M_k T_k q_s + [0, 0, e_k - u_k, 0, 0]
    T_k q_s = [dx + z_k theta_y, dy - z_k theta_x, dz, theta_x, theta_y]
    M_k = I (s_k = +1), diag(1, -1, -1, 1, -1) (s_k = -1: a half turn about x)

and loads the shaft with T_k^T M_k R_k(q_k).  Equations: sum_k T_k^T M_k R_k = F_s (5), and for
every spring-preloaded bearing R_k,z = P_k with its floating outer ring's axial shift u_k as one
more unknown (u_k = 0 for the others).  A rigid preload is the offset e_k: the axial approach of
bearing k alone under the thrust P_k at standstill (:func:`preload_offset`, docs/model.md section 4 closed
form at omega = 0), which with balanced preloads (sum_k s_k P_k = 0) puts the set in equilibrium
at q_s = 0 with no external load; the offset is then held while speed and loads change.

Azimuths flip with the frame: ball j of bearing k sits at psi_j = theta_c + 2 pi j / Z in the
shaft frame, at s_k psi_j in its own frame (a defect's centre likewise); per-bearing solutions
(:class:`~bearingsim.physics.jones.JonesSolution`, own frame) keep that ball order, and
:meth:`SetSolution.shaft_azimuth` gives the shaft-frame azimuths.

Solver
------
One flat damped Newton on the shaft unknowns (+ the spring shifts) with every bearing's ball
blocks eliminated (each bearing's 2x2 ball blocks Schur-complemented into its 5x5 stiffness, as
:mod:`bearingsim.physics.jones` does for one bearing), the same step caps, acceptance rule (free steps,
then natural monotonicity or residual decrease) and result codes; a single ``lax.while_loop``
per speed stage (``lax.scan`` over the stages: the model is traced once).  Start: the rigid-ring
static (omega = 0) solution, from q_s = 0 when a rigid preload holds the balls in contact, else
from the displacement where every bearing's balls touch under its share of the load (linear
springs); then the operating speed.  At the solution one Newton correction with the Jacobian
frozen makes the state implicitly differentiable and gives the set stiffness
dF_s/dq_s = sum_k T_k^T M_k K_k M_k T_k (with spring bearings the floating rings condensed out).
Every bearing's converged state is re-checked by :func:`bearingsim.physics.jones.state_validity`, the
shaft's equilibrium from the per-ball output.

The preload closed forms live in :mod:`bearingsim.physics.preload`, the verdict on a failed set and
its hints in :mod:`bearingsim.physics.set_verdict`; their names are offered here too.
"""
from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from .balls import (KN, UM, ball_equations, ball_state, groove_centre_offsets, inverse2,
                    lift_onto_outer, offset_jacobian, orbital_speed, reaction_matrix,
                    reactions_from_balls, static_ball_position)
from .defect import as_defects, contact_depths
from ..errors import failed, InputError, succeeded
from ..hostarrays import host, xp
from .hertz import contact_ellipse, stiffness_curve
from .jones import PRESSURE_WARNING, RESULTS, JonesSolution, initial_displacement, state_validity
from .kinematics import Operation
from .life import rating_life, set_life
from .preload import (PRELOAD_CLASSES, STATIC_PRESSURE, preload_class_force, preload_offset, static_axial_capacity,
                      thrust_at_approach)
from .set_verdict import SET_NEWTON_HINT, raise_for_set, set_verdict, warn_set_overload
from .newton import (BALL_CAP, RING_CAP, accept_step, cap_step, converged_only, max_abs, retry_failed, speed_stages,
                     step_status, traced_tolerances)
from ..programs import jit
from ..xla import QUICK_COMPILE

__all__ = [
    "BearingSet",
    "SetSolution",
    "ARRANGEMENTS",
    "arrangement_facings",
    "arrangement_suggestion",
    "preload_offset",
    "thrust_at_approach",
    "frame_matrix",
    "transfer_matrix",
    "solve_set_state",
    "solve_set",
    "solve_set_batch",
    "raise_for_set",
    "set_verdict",
    "SET_NEWTON_HINT",
    "STATIC_PRESSURE",
    "PRELOAD_CLASSES",
    "static_axial_capacity",
    "preload_class_force",
    "set_lives",
]

#: facings of the named arrangements, bearings in order of increasing z (docs/model.md section 10):
#: B = a bearing carrying +Fz of the shaft (s = +1, "back" towards -z), F = the mirror
#: (s = -1); tandem groups repeat a facing.  DB = "O", DF = "X", DT = tandem.
ARRANGEMENTS = {
    "DB": (1, -1),
    "DF": (-1, 1),
    "DT": (1, 1),
    "TBT": (1, 1, -1),      # a tandem pair back to back with a third bearing
    "TFT": (-1, -1, 1),     # a tandem pair face to face with a third bearing
    "TT": (1, 1, 1),        # triplex tandem
    "QBC": (1, 1, -1, -1),  # quadruplex: two tandem pairs back to back
    "QFC": (-1, -1, 1, 1),  # quadruplex: two tandem pairs face to face
    "QBT": (1, 1, 1, -1),   # three in tandem back to back with a fourth
    "QFT": (-1, -1, -1, 1),
    "QT": (1, 1, 1, 1),     # quadruplex tandem
}


def arrangement_facings(name: str) -> tuple:
    """Facings (s_k) of a named arrangement (:data:`ARRANGEMENTS`), bearings by increasing z."""
    key = str(name).upper()
    if key not in ARRANGEMENTS:
        close = arrangement_suggestion(key)
        hint = f" (did you mean {close!r}?)" if close else ""
        raise InputError(f"unknown arrangement {name!r}{hint}; known: {', '.join(ARRANGEMENTS)}")
    return ARRANGEMENTS[key]


def arrangement_suggestion(name: str):
    """The known arrangement a misspelt name most likely means (same letters first), or None."""
    import difflib
    key = str(name).upper()
    same = [k for k in ARRANGEMENTS if sorted(k) == sorted(key)]
    if same:
        return same[0]
    close = difflib.get_close_matches(key, list(ARRANGEMENTS), n=1, cutoff=0.4)
    return close[0] if close else None


def frame_matrix(facing):
    """M_k: diag(1, 1, 1, 1, 1) for s = +1, diag(1, -1, -1, 1, -1) for s = -1 (docs/model.md section 10);
    ``facing`` may be traced."""
    return jnp.diag(_frame_diag(facing))


def _frame_diag(facing):
    s = jnp.asarray(facing, jnp.float64)
    one = jnp.ones_like(s)
    return jnp.stack([one, s, s, one, s], axis=-1)


def transfer_matrix(z):
    """T_k: the displacement of the shaft at axial position z from q_s at O (docs/model.md section 10)."""
    z = jnp.asarray(z, jnp.float64)
    T = jnp.eye(5, dtype=jnp.float64)
    return T.at[0, 4].set(z).at[1, 3].set(-z)


# ----------------------------------------------------------------------------- the set
class BearingSet(eqx.Module):
    """N bearings on one rigid shaft (docs/model.md section 10).

    ``bearings``: one :class:`~bearingsim.physics.geometry.Bearing` per position (different ones allowed);
    ``positions``: z_k (m) of each inner groove-centre plane; ``facings`` (static): s_k = +1 (the
    bearing of docs/model.md section 1, carries +Fz of the shaft) or -1 (mirrored); ``preload`` (N): the
    bearing's preload force P_k (N): for a rigid preload the thrust that fixes its offset e_k
    at standstill (0: a plain support), for a spring preload the constant force of its floating
    outer ring; ``springs``: True (1.0) for a spring-preloaded bearing.
    """

    bearings: tuple
    positions: jnp.ndarray
    preload: jnp.ndarray
    facings: jnp.ndarray        # (N,) +1.0 / -1.0 } data: sets that differ only in these
    springs: jnp.ndarray        # (N,) 1.0 / 0.0   } share one compiled program

    def __init__(self, bearings, positions, facings, preload=None, springs=None):
        bearings = tuple(bearings)
        n = len(bearings)
        self.bearings = bearings
        self.positions = jnp.asarray(positions, jnp.float64).reshape(n)
        facings = tuple(int(s) for s in np.asarray(facings).reshape(-1))
        self.preload = (jnp.zeros(n) if preload is None
                        else jnp.broadcast_to(jnp.asarray(preload, jnp.float64), (n,)))
        springs = tuple(bool(s) for s in (springs if springs is not None else (False,) * n))
        if len(facings) != n or len(springs) != n:
            raise InputError(f"a set of {n} bearings needs {n} facings and {n} spring flags, got "
                             f"{len(facings)} and {len(springs)}")
        bad = [s for s in facings if s not in (1, -1)]
        if bad:
            raise InputError(f"facings must be +1 or -1, got {bad}")
        self.facings = jnp.asarray(facings, jnp.float64)
        self.springs = jnp.asarray(springs, jnp.float64)
        if n and all(springs):
            raise InputError("every bearing of the set has a spring preload: nothing holds the shaft "
                             "axially; give at least one bearing a rigid preload (or none)")

    @classmethod
    def arrangement(cls, name, bearing, spacing, preload=0.0, first_position=0.0):
        """Identical bearings in a named arrangement (:data:`ARRANGEMENTS`), ``spacing`` (m)
        apart from ``first_position``, with the set preload ``preload`` (N, rigid): each bearing
        of a facing group carries its share P / (bearings facing that way) at standstill."""
        facings = arrangement_facings(name)
        n = len(facings)
        plus = sum(1 for s in facings if s > 0)
        minus = n - plus
        if preload and (plus == 0 or minus == 0):
            raise InputError(f"arrangement {name!r} has every bearing facing the same way: it "
                             "cannot carry a preload (nothing opposes it); use DB, DF, TBT, ...")
        share = [preload / (plus if s > 0 else minus) if preload else 0.0 for s in facings]
        z = first_position + spacing * np.arange(n)
        return cls((bearing,) * n, z, facings, share)

    @property
    def n(self):
        return len(self.bearings)

    def check_balance(self, rtol=1e-9):
        """Raise :class:`InputError` unless the preloads balance axially (sum_k s_k P_k = 0),
        the condition for q_s = 0 at standstill with no external load (docs/model.md section 10)."""
        P = np.asarray(self.preload)
        net = float(np.dot(np.asarray(self.facings, float), P))
        if abs(net) > rtol * max(float(np.sum(np.abs(P))), 1.0):
            raise InputError(
                f"the preloads do not balance: sum of facing x preload = {net:.6g} N (bearings "
                f"facing +1 carry {float(np.sum(P[np.asarray(self.facings) > 0])):.6g} N, facing -1 "
                f"{float(np.sum(P[np.asarray(self.facings) < 0])):.6g} N); a preload needs an "
                "opposed bearing that carries the same force")


def set_lives(bset, sol, C, rows=1):
    """ISO/TS 16281 basic reference rating lives (10^6 revolutions, docs/model.md section 11; bearingsim.physics.life)
    of every bearing of a solved set from its per-ball loads, and of the set (bearings fail
    independently): ``(L_k (..., N), L_set (...))``.  ``C``: basic dynamic load rating (N),
    scalar or (N,) (one per bearing)."""
    C = jnp.broadcast_to(jnp.asarray(C, jnp.float64), (bset.n,))
    L = jnp.stack([rating_life(b, C[k], s.Q_inner, s.Q_outer, rows)
                   for k, (b, s) in enumerate(zip(bset.bearings, sol.bearings))], axis=-1)
    return L, set_life(L)


# ------------------------------------------------------------------------- one bearing
class _Bearing(eqx.Module):
    """Everything fixed about bearing k during one solve (own frame)."""

    bearing: object
    curve: object
    psi: jnp.ndarray            # own-frame azimuths (Z,)
    H_outer: jnp.ndarray
    H_inner: jnp.ndarray
    G: jnp.ndarray              # M_k T_k (5, 5), its axial row zeroed for a spring bearing
                                # (q_k = G q_s + (e_k + v_k) e_z; see _System)
    L: jnp.ndarray              # T_k^T M_k (5, 5): its loads on the shaft
    rs: jnp.ndarray             # reaction scales [KN, KN, KN, KN R_i, KN R_i]
    defect: bool = eqx.field(static=True)


def _flip(spall, facing):
    """A defect given in the shaft frame, in a bearing's own frame (azimuths flip when s = -1)."""
    if spall is None:
        return spall
    out = []
    for sp in as_defects(spall):
        out.append(sp if sp.location == "ball" else eqx.tree_at(lambda p: p.center, sp, facing * sp.center))
    return tuple(out)


def _ball_pieces(bk: _Bearing, op, qk, Y, Yu, jac):
    """Ball residuals (kN), the bearing's reactions (N, N m; own frame) and the Jacobian blocks
    of bearing k at displacement qk (m) and balls Y (um); as jones' evaluation of one bearing."""
    b = bk.bearing
    A1, A2 = groove_centre_offsets(b, qk, bk.psi)
    a = jnp.stack([A1, A2], axis=-1) / UM

    def per_ball(y, aa, ho, hi, ws):
        v = jnp.concatenate([y, aa])
        if not jac:
            out, _ = ball_equations(b, op, bk.curve, v, ho, hi, ws)
            return out, None

        def f(v):
            out, _ = ball_equations(b, op, bk.curve, v, ho, hi, ws)
            return out, out

        J, out = jax.jacfwd(f, has_aux=True)(v)
        return out, J

    piece = {}
    if bk.defect:
        Z = bk.psi.shape[0]
        ws = lax.stop_gradient(jax.vmap(lambda y, aa: orbital_speed(
            b, op, y[0] * UM, y[1] * UM, aa[0] * UM, aa[1] * UM))(Yu, a))
        zero = jnp.zeros_like(bk.H_outer)
        out2, J2 = jax.vmap(per_ball)(jnp.concatenate([Yu, Y]), jnp.concatenate([a, a]),
                                      jnp.concatenate([zero, bk.H_outer]),
                                      jnp.concatenate([zero, bk.H_inner]), jnp.concatenate([ws, ws]))
        out_u, out = out2[:Z], out2[Z:]
        piece["rbu"] = out_u[:, :2]
        if jac:
            piece.update(Jbbu=J2[:Z, :2, :2], Jbau=J2[:Z, :2, 2:])
            J = J2[Z:]
    else:
        out, J = jax.vmap(lambda y, aa, ho, hi: per_ball(y, aa, ho, hi, None))(
            Y, a, bk.H_outer, bk.H_inner)
    T = reaction_matrix(bk.psi)
    piece["R"] = jnp.einsum("zij,zj->i", T, out[:, 2:]) * bk.rs
    piece["rb"] = out[:, :2]
    if jac:
        piece.update(Jbb=J[:, :2, :2], Jba=J[:, :2, 2:], Cx=J[:, 2:, :2], Ca=J[:, 2:, 2:])
    return piece


def _jac_keys(defect):
    return ("Jbb", "Jba", "Cx", "Ca") + (("Jbbu", "Jbau") if defect else ())


def _zero_jac(bk: _Bearing):
    Z = bk.psi.shape[0]
    shapes = dict(Jbb=(Z, 2, 2), Jba=(Z, 2, 2), Cx=(Z, 3, 2), Ca=(Z, 3, 2))
    if bk.defect:
        shapes.update(Jbbu=(Z, 2, 2), Jbau=(Z, 2, 2))
    return {k: jnp.zeros(v, jnp.float64) for k, v in shapes.items()}


def _condense(bk: _Bearing, piece, jac):
    """Bearing k with its balls eliminated: stiffness K (dR/dq_k, N/m...) and the reduced
    reaction g (the reaction after the balls' Newton correction at fixed q_k)."""
    T = reaction_matrix(bk.psi)
    P = offset_jacobian(bk.bearing, bk.psi) / UM                  # dA(um)/dq(m)
    inv = inverse2(jac["Jbb"])
    Mx = jac["Cx"] @ inv
    K = bk.rs[:, None] * jnp.einsum("zij,zjk,zkl->il", T, jac["Ca"] - Mx @ jac["Jba"], P)
    g = piece["R"] - bk.rs * jnp.einsum("zij,zjk,zk->i", T, Mx, piece["rb"])
    return K, g, inv, P


def _ball_steps(bk: _Bearing, piece, jac, inv, P, dqk):
    dA = jnp.einsum("zij,j->zi", P, dqk)
    dY = -jnp.einsum("zij,zj->zi", inv, piece["rb"] + jnp.einsum("zij,zj->zi", jac["Jba"], dA))
    dYu = None
    if bk.defect:
        invu = inverse2(jac["Jbbu"])
        dYu = -jnp.einsum("zij,zj->zi", invu, piece["rbu"] + jnp.einsum("zij,zj->zi", jac["Jbau"], dA))
    return dY, dYu


# --------------------------------------------------------------------------- the system
# Bearings of one structure (ball count, defect layout) form a group whose arrays are stacked on
# a leading axis: each group's ball equations are traced once and vmapped over its bearings.
class _System(eqx.Module):
    groups: tuple               # stacked _Bearing per group
    index: tuple = eqx.field(static=True)   # bearing indices of each group
    sp: jnp.ndarray             # (N,) 1.0 for a spring bearing, 0.0 for a rigid one
    e: jnp.ndarray              # (N,) rigid offsets (m; 0 for spring bearings)
    P: jnp.ndarray              # (N,) preloads (N)
    F: jnp.ndarray              # (5,) external loads
    xs: jnp.ndarray             # unknown scales (5 + N)
    fs: jnp.ndarray             # residual scales (5 + N)

    def take(self, a, g):
        return a[jnp.asarray(self.index[g])]


_EZ = np.array([0.0, 0.0, 1.0, 0.0, 0.0])


def _group_q(sy: _System, x, g):
    """q_k (m) of the bearings of group g, (n_g, 5), from the physical unknowns x.

    A spring bearing's unknown is its own axial approach v_k = q_k,z (its floating ring's shift
    is u_k = (M_k T_k q_s)_z - v_k): a linear change of variables from (q_s, u) (the Newton
    direction is the same), with which the step caps act on the approach as in jones."""
    bk = sy.groups[g]
    shift = sy.take(sy.e, g) + sy.take(sy.sp * x[5:], g)
    return jnp.einsum("gij,j->gi", bk.G, x[:5]) + shift[:, None] * _EZ


def _evaluate(sy: _System, op, x, Ys, Yus, jac=True):
    return [jax.vmap(lambda bk, q, y, yu: _ball_pieces(bk, op, q, y, yu if bk.defect else None, jac))(
        bk, _group_q(sy, x, g), Ys[g], Yus[g]) for g, bk in enumerate(sy.groups)]


def _reduced(sy: _System, gs):
    """Scaled residual of the set from each group's (reduced) reactions g (n_g, 5)."""
    r = -sy.F
    # one more equation per bearing: R_k,z = P_k for a spring bearing (its unknown: its axial
    # approach v_k); v_k = 0 for a rigid one (its unknown unused)
    ru = jnp.zeros_like(sy.P)   # rigid bearings: v_k stays 0 (start 0, decoupled unit row)
    for g, (bk, gg) in enumerate(zip(sy.groups, gs)):
        r = r + jnp.einsum("gij,gj->i", bk.L, gg)
        ix = jnp.asarray(sy.index[g])
        ru = ru.at[ix].add(sy.sp[ix] * (gg[:, 2] - sy.P[ix]))
    return jnp.concatenate([r, ru]) / sy.fs


def _jacobian(sy: _System, Ks):
    """d(residual)/d(unknowns), physical units."""
    N = sy.sp.shape[0]
    Jss = jnp.zeros((5, 5))
    Jsu = jnp.zeros((5, N))
    Jus = jnp.zeros((N, 5))
    # a rigid bearing's unused unknown: residual v_k (scaled like a spring's), derivative 1
    Juu = jnp.diag((1.0 - sy.sp) * sy.fs[5:] / sy.xs[5:])
    for g, (bk, K) in enumerate(zip(sy.groups, Ks)):
        ix = jnp.asarray(sy.index[g])
        sp = sy.sp[ix]
        KG = K @ bk.G
        Jss = Jss + jnp.einsum("gij,gjk->ik", bk.L, KG)
        Jsu = Jsu.at[:, ix].add(jnp.einsum("gij,gj->ig", bk.L, K[:, :, 2]) * sp)
        Jus = Jus.at[ix, :].add(KG[:, 2, :] * sp[:, None])
        Juu = Juu.at[ix, ix].add(K[:, 2, 2] * sp)
    return jnp.concatenate([jnp.concatenate([Jss, Jsu], 1), jnp.concatenate([Jus, Juu], 1)], 0)


def _merit(sy, pieces):
    return max_abs(_reduced(sy, [p["R"] for p in pieces]), *[p["rb"] for p in pieces],
                   *[p.get("rbu") for p in pieces])


def _direction(sy: _System, pieces, jacs):
    """Newton step: (dx scaled, [dY_g], [dYu_g], physical Jacobian)."""
    conds = [jax.vmap(_condense)(bk, p, j) for bk, p, j in zip(sy.groups, pieces, jacs)]
    J = _jacobian(sy, [c[0] for c in conds])
    Js = J * (sy.xs[None, :] / sy.fs[:, None])
    r = _reduced(sy, [c[1] for c in conds])
    mu = 1e-13 * (jnp.max(jnp.abs(Js)) + 1e-30)
    dxs = -jnp.linalg.solve(Js + mu * jnp.eye(Js.shape[0]), r)
    dx = dxs * sy.xs
    dYs, dYus = [], []
    for g, (bk, p, j, c) in enumerate(zip(sy.groups, pieces, jacs, conds)):
        dq = _group_q(sy, dx, g) - sy.take(sy.e, g)[:, None] * _EZ
        dY, dYu = jax.vmap(_ball_steps)(bk, p, j, c[2], c[3], dq)
        dYs.append(dY)
        dYus.append(dYu)
    return dxs, dYs, dYus, J


def _closed_form_one(bk: _Bearing, op, qk, defect_free):
    A1, A2 = groove_centre_offsets(bk.bearing, qk, bk.psi)
    Ho = jnp.zeros_like(bk.psi) if defect_free else bk.H_outer
    Hi = jnp.zeros_like(bk.psi) if defect_free else bk.H_inner
    x0, d_c = jax.vmap(lambda a1, a2, ho, hi: static_ball_position(
        bk.bearing, op, a1, a2, bk.curve, ho, hi))(A1, A2, Ho, Hi)
    return x0 / UM, d_c


def _closed_form(sy: _System, op, x, g, defect_free=False):
    return jax.vmap(lambda bk, q: _closed_form_one(bk, op, q, defect_free))(
        sy.groups[g], _group_q(sy, x, g))


def _lift(bk, y, dc, undropped):
    return jax.vmap(lambda b, yy, d: lift_onto_outer(b.bearing, yy, d, 0.0 if undropped else b.H_outer))(
        bk, y, dc)


def _newton(sy: _System, op, xz0, Y0, Yu0, dcs, dcus, maxit, tol):
    """Damped Newton on the set (jones' loop with the set's unknowns): returns
    (xz, Ys, Yus, jacs, code, iterations)."""
    groups = sy.groups
    caps = [BALL_CAP * bk.bearing.ball_diameter[:, None, None] / UM for bk in groups]

    def lift(Ys, Yus):
        Ys = [_lift(bk, y, dc, False) for bk, y, dc in zip(groups, Ys, dcs)]
        Yus = [_lift(bk, y, dc, True) if bk.defect else y for bk, y, dc in zip(groups, Yus, dcus)]
        return Ys, Yus

    def body(c):
        first = c["it"] < 0
        t = c["t"]
        xz = c["xz"] + t * c["dx"]
        Ys = [y + t * d for y, d in zip(c["Y"], c["dY"])]
        Yus = [y + t * d for y, d in zip(c["Yu"], c["dYu"])]
        Ys, Yus = lift(Ys, Yus)
        x = xz * sy.xs
        pieces = _evaluate(sy, op, x, Ys, Yus)
        jacs = [{kk: p[kk] for kk in _jac_keys(bk.defect)} for bk, p in zip(groups, pieces)]
        m = _merit(sy, pieces)
        dx, dYs, dYus, _ = _direction(sy, pieces, jacs)
        sn = max_abs(dx, *dYs, *dYus)
        finite = jnp.isfinite(m) & jnp.isfinite(sn)
        sx, sY, sYu, _ = _direction(sy, pieces, c["jac"])
        ss = max_abs(sx, *sY, *sYu)
        ok = accept_step(c, first, finite, t, m, ss)
        dYs = [cap_step(d, cap) for d, cap in zip(dYs, caps)]
        dYus = [cap_step(d, cap) if bk.defect else jnp.zeros_like(y)
                for d, cap, bk, y in zip(dYus, caps, groups, Ys)]
        new = dict(xz=xz, Y=Ys, Yu=Yus, dx=cap_step(dx, RING_CAP), dY=dYs, dYu=dYus, m=m, sn=sn,
                   jac=jacs)
        out = jax.tree_util.tree_map(lambda u, v: jnp.where(ok, u, v), new, {k: c[k] for k in new})
        return step_status(out, c, ok, t, first, finite, tol, maxit)

    init = dict(xz=xz0, Y=list(Y0), Yu=list(Yu0), dx=jnp.zeros_like(xz0),
                dY=[jnp.zeros_like(y) for y in Y0], dYu=[jnp.zeros_like(y) for y in Y0],
                m=jnp.float64(jnp.inf), sn=jnp.float64(jnp.inf), t=jnp.float64(1.0),
                it=jnp.int32(-1), ls=jnp.int32(0), code=jnp.int32(-1),
                jac=[jax.vmap(_zero_jac)(bk) for bk in groups])
    c = lax.while_loop(lambda c: c["code"] < 0, body, init)
    return c["xz"], c["Y"], c["Yu"], c["jac"], c["code"], c["it"]


# -------------------------------------------------------------------------------- solution
class SetSolution(eqx.Module):
    """Quasi-static state of a shaft on N bearings (SI; a leading batch axis after
    :func:`solve_set_batch`).

    ``displacement`` q_s and ``loads`` F_s at the reference point O (shaft frame);
    ``stiffness`` dF_s/dq_s (5, 5) of the set; ``offset`` e_k (rigid preload offsets, m),
    ``spring_shift`` u_k (floating outer rings, m; 0 for rigid bearings), ``preload`` P_k (N);
    ``bearings``: one :class:`~bearingsim.physics.jones.JonesSolution` per bearing in its own frame
    (its ``loads`` are the loads it carries, its ``result`` its own validity code, its
    ``stiffness`` its 5x5 dR/dq).  ``result``: the set's :class:`~bearingsim.physics.jones.RESULTS` code
    (0 = converged and every bearing valid).
    """

    displacement: jnp.ndarray
    loads: jnp.ndarray
    result: jnp.ndarray
    iterations: jnp.ndarray
    residual_norm: jnp.ndarray
    stiffness: jnp.ndarray
    offset: jnp.ndarray
    spring_shift: jnp.ndarray
    preload: jnp.ndarray
    positions: jnp.ndarray
    bearings: tuple
    facings: jnp.ndarray
    springs: jnp.ndarray

    @property
    def converged(self):
        return succeeded(self.result)

    @property
    def n(self):
        return len(self.bearings)

    @property
    def axial_load(self):
        """(..., N): the axial load each bearing carries in its own contact direction (N): its
        operating preload (positive: loaded as it should be)."""
        return jnp.stack([b.loads[..., 2] for b in self.bearings], axis=-1)

    @property
    def bearing_result(self):
        """(..., N) each bearing's own validity code."""
        return jnp.stack([b.result for b in self.bearings], axis=-1)

    @property
    def lift_off_margin(self):
        """(..., N): each bearing's axial load over its standstill preload P_k (1 at standstill
        with no external load, 0 when the bearing has unloaded); NaN where P_k = 0."""
        P = self.preload
        return jnp.where(P > 0, self.axial_load / jnp.where(P > 0, P, 1.0), jnp.nan)

    @property
    def ball_load_ratio(self):
        """(..., N): min over balls of the smaller contact load over the largest ball load of the
        bearing (0: a ball has lost contact)."""
        out = []
        for b in self.bearings:
            q = jnp.minimum(b.Q_inner, b.Q_outer)
            top = jnp.max(jnp.maximum(b.Q_inner, b.Q_outer), axis=-1)
            out.append(jnp.where(top > 0, jnp.min(q, axis=-1) / jnp.where(top > 0, top, 1.0), 0.0))
        return jnp.stack(out, axis=-1)

    @property
    def max_pressure(self):
        """(..., N): the largest Hertz peak pressure of each bearing (Pa)."""
        return jnp.stack([b.max_pressure for b in self.bearings], axis=-1)

    @property
    def overloaded(self):
        """(..., N) bool: a contact of the bearing above
        :data:`~bearingsim.physics.jones.PRESSURE_WARNING` (4.2 GPa): solved and returned, flagged
        (as ``JonesSolution.overloaded``), never refused."""
        return self.max_pressure > PRESSURE_WARNING

    def shaft_reactions(self):
        """(..., N, 5): each bearing's loads on the shaft at O in the shaft frame, T^T M R."""
        out = []
        for s, z, b in zip(jnp.moveaxis(self.facings, -1, 0), jnp.moveaxis(self.positions, -1, 0),
                           self.bearings):
            R = b.loads * _frame_diag(s)
            Fx, Fy, Fz, Mx, My = (R[..., i] for i in range(5))
            zz = z
            out.append(jnp.stack([Fx, Fy, Fz, Mx - zz * Fy, My + zz * Fx], axis=-1))
        return jnp.stack(out, axis=-2)

    def shaft_azimuth(self, k):
        """Ball azimuths of bearing k in the shaft frame (rad)."""
        return self.facings[..., k, None] * self.bearings[k].azimuth

    def message(self):
        codes = np.atleast_1d(np.asarray(self.result))
        return [RESULTS.of(c).message for c in codes]


def _bearing_output(bk: _Bearing, op, qk, Y, Yu, piece, jac, cage, total_it, res, rtol):
    """One bearing's JonesSolution (own frame) and its validity code."""
    b = bk.bearing
    A1, A2 = groove_centre_offsets(b, qk, bk.psi)
    xb = Y * UM
    ws = None
    if bk.defect:
        ws = jax.vmap(lambda xx, a1, a2: ball_state(b, op, xx, a1, a2, bk.curve).orbital_speed)(
            Yu * UM, A1, A2)
    st = jax.vmap(lambda xx, a1, a2, ho, hi, w: ball_state(b, op, xx, a1, a2, bk.curve, ho, hi, w),
                  in_axes=(0, 0, 0, 0, 0, None if ws is None else 0))(xb, A1, A2, bk.H_outer,
                                                                       bk.H_inner, ws)
    R = reactions_from_balls(st, bk.psi)
    a_i, b_i, p_i = contact_ellipse(bk.curve, jnp.cos(st.alpha_inner), st.Q_inner, True)
    a_o, b_o, p_o = contact_ellipse(bk.curve, jnp.cos(st.alpha_outer), st.Q_outer, False)
    qmax = jnp.maximum(jnp.max(st.Q_inner), jnp.max(st.Q_outer))
    # the loads it carries; an axial load at round-off level (a bearing at lift-off) is zero,
    # not a (refused) reverse load
    Rv = R.at[2].set(jnp.where(jnp.abs(R[2]) <= 1e-9 * (qmax + 1.0), 0.0, R[2]))
    vk = state_validity(b, op, st, bk.psi, qk, Rv, bk.H_outer + bk.H_inner, rtol)
    Kk = _condense(bk, piece, jac)[0]
    return JonesSolution(qk, R, vk, total_it, res, cage, bk.psi, st.alpha_inner,
                         st.alpha_outer, st.Q_inner, st.Q_outer, st.delta_inner,
                         st.delta_outer, st.centrifugal, st.gyroscopic_moment,
                         st.orbital_speed, st.beta, bk.H_outer, st.ball_G, st.ball_H,
                         st.ball_moment, st.K_inner, st.K_outer, p_i, p_o, a_i, b_i, a_o,
                         b_o, Kk, xb, (Yu if bk.defect else Y) * UM, bk.H_inner), qmax


def _equilibrium_bad(sy: _System, sols, qmax, F, P, rtol):
    """Shaft equilibrium (and the springs' R_z = P) recomputed from the per-ball output."""
    Rs = [s.loads for s in sols]
    r = _reduced(sy, Rs) * sy.fs
    w = jnp.concatenate([KN / sy.fs[:5], jnp.ones(sy.sp.shape[0])])
    scale = jnp.maximum(jnp.max(jnp.abs(F * w[:5])), jnp.maximum(qmax, jnp.max(jnp.abs(P)))) + 1.0
    tol = jnp.maximum(1e-7, 100.0 * rtol) * scale
    return jnp.max(jnp.abs(r * w)) > tol


def _groups(bset, spalls):
    """Bearing indices grouped by structure (ball count, defect layout)."""
    keys = {}
    for k, b in enumerate(bset.bearings):
        sp = spalls[k]
        key = (b.n_balls, jax.tree_util.tree_structure(sp) if sp is not None else None)
        keys.setdefault(key, []).append(k)
    return tuple(tuple(v) for v in keys.values())


def _stack(items):
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *items)


def _split(tree, n):
    return [jax.tree_util.tree_map(lambda a: a[i], tree) for i in range(n)]


def solve_set_state(bset: BearingSet, op: Operation, loads, *, cage_angle=0.0, spalls=None,
                    x0=None, speed_steps: int = 1, maxit=60, rtol=1e-11, atol=1e-9,
                    hertz_method: str = "exact", curves=None, offsets=None) -> SetSolution:
    """The set's quasi-static state as a pure JAX function (jit/vmap/grad; never raises).

    ``loads``: F_s = [Fx, Fy, Fz, Mx, My] at O (N, N m, shaft frame).  ``cage_angle``: scalar or
    (N,) (shaft frame).  ``spalls``: None or a tuple of N entries (None or defects, azimuths in
    the shaft frame).  ``offsets``: the rigid offsets e_k (m) to hold; default: from the
    preloads at standstill (:func:`preload_offset`).  ``x0``: a warm start [q_s (5), u (N)]
    at full speed (cold: the static start, then ``speed_steps`` speed stages).
    """
    N = bset.n
    F = jnp.asarray(loads, jnp.float64)
    cage = jnp.broadcast_to(jnp.asarray(cage_angle, jnp.float64), (N,))
    if curves is None:
        curves = tuple(stiffness_curve(b, hertz_method) for b in bset.bearings)
    spalls = (None,) * N if spalls is None else tuple(spalls)
    P = bset.preload
    sp = bset.springs
    approach = jnp.stack([preload_offset(b, P[k], curves[k]) for k, b in enumerate(bset.bearings)])
    if offsets is None:
        e = (1.0 - sp) * approach
    else:
        e = (1.0 - sp) * jnp.asarray(offsets, jnp.float64)
    bks = []
    for k, b in enumerate(bset.bearings):
        s = bset.facings[k]
        psi = s * b.ball_azimuths(cage[k])
        Ho, Hi = contact_depths(b, _flip(spalls[k], s), psi)
        defect = Ho is not None or Hi is not None
        Ho = jnp.zeros_like(psi) if Ho is None else Ho
        Hi = jnp.zeros_like(psi) if Hi is None else Hi
        M = frame_matrix(s)
        T = transfer_matrix(bset.positions[k])
        Ri = b.inner_groove_radius
        G = (M @ T).at[2].multiply(1.0 - sp[k])
        bks.append(_Bearing(b, curves[k], psi, Ho, Hi, G, T.T @ M,
                            jnp.stack([KN, KN, KN, KN * Ri, KN * Ri]), defect))
    index = _groups(bset, spalls)
    groups = tuple(_stack([bks[k] for k in ix]) for ix in index)
    Lr = jnp.maximum(jnp.max(jnp.stack([b.inner_groove_radius for b in bset.bearings])),
                     jnp.max(jnp.abs(bset.positions)))
    xs = jnp.concatenate([jnp.stack([UM, UM, UM, UM / Lr, UM / Lr]), jnp.full(N, UM)])
    fs = jnp.concatenate([jnp.stack([KN, KN, KN, KN * Lr, KN * Lr]), jnp.full(N, KN)])
    sy = _System(groups, index, sp, e, P, F, xs, fs)
    load_scale = jnp.maximum(jnp.max(jnp.abs(F / fs[:5])), jnp.max(jnp.abs(P)) / KN)
    tol = jnp.asarray(atol, jnp.float64) / KN + jnp.asarray(rtol, jnp.float64) * load_scale

    def with_speed(frac):
        return eqx.tree_at(lambda p: p.speed, op, op.speed * frac)

    if x0 is None:
        x = _static_start(sy, bset, bks, curves, e, approach)
    else:
        x0 = jnp.asarray(x0, jnp.float64)
        # the spring bearings' unknowns are their approaches (x0 holds the ring shifts u)
        Gz = jnp.stack([(frame_matrix(bset.facings[k]) @ transfer_matrix(bset.positions[k]))[2]
                        for k in range(N)])
        x = jnp.concatenate([x0[:5], sp * (Gz @ x0[:5] - x0[5:])])

    nan = [jnp.full((len(ix), bset.bearings[ix[0]].n_balls, 2), jnp.nan) for ix in index]

    def stage(carry, frac):
        xz, Ys, Yus, _ = carry
        o = with_speed(frac)
        Ys2, Yus2, dcs, dcus = [], [], [], []
        for g, bk in enumerate(sy.groups):
            Yc, dc = _closed_form(sy, o, xz * sy.xs, g)
            Yuc, dcu = _closed_form(sy, o, xz * sy.xs, g, True)
            Ys2.append(_lift(bk, jnp.where(jnp.isfinite(Ys[g]), Ys[g], Yc), dc, False))
            Yus2.append(_lift(bk, jnp.where(jnp.isfinite(Yus[g]), Yus[g], Yuc), dcu, True))
            dcs.append(dc)
            dcus.append(dcu)
        xz, Ys, Yus, jacs, code, it = _newton(sy, o, xz, Ys2, Yus2, dcs, dcus, maxit, tol)
        return (xz, Ys, Yus, jacs), (code, it)

    jac0 = [jax.vmap(_zero_jac)(bk) for bk in sy.groups]
    (xz, Ys, Yus, jacs), code, total_it = speed_stages(stage, (x / xs, nan, nan, jac0), speed_steps, x0 is None)
    at_rest = op.speed == 0.0
    Ys = [jnp.where(at_rest, _closed_form(sy, op, xz * xs, g)[0], Ys[g]) for g in range(len(index))]
    Yus = [jnp.where(at_rest, _closed_form(sy, op, xz * xs, g, True)[0], Yus[g])
           for g in range(len(index))]

    # implicit differentiation: one correction with the Jacobian frozen (jones does the same)
    xz, Ys, Yus, jacs = lax.stop_gradient((xz, Ys, Yus, jacs))
    pieces = _evaluate(sy, op, xz * xs, Ys, Yus, jac=False)
    res = _merit(sy, pieces) * KN
    dxs, dYs, dYus, J = _direction(sy, pieces, jacs)
    xz = xz + dxs
    Ys = [y + d for y, d in zip(Ys, dYs)]
    Yus = [y + d if bk.defect else y for y, d, bk in zip(Yus, dYus, sy.groups)]
    x = xz * xs
    # set stiffness: the Jacobian with the floating rings condensed out
    Kss = J[:5, :5] - J[:5, 5:] @ jnp.linalg.solve(J[5:, 5:], J[5:, :5])

    sols = [None] * N
    qmax = jnp.float64(0.0)
    for g, (bk, ix) in enumerate(zip(sy.groups, index)):
        out, qm = jax.vmap(lambda b, q, y, yu, p, j, c: _bearing_output(
            b, op, q, y, yu, p, j, c, total_it, res, rtol))(
            bk, _group_q(sy, x, g), Ys[g], Yus[g], pieces[g], jacs[g], cage[jnp.asarray(ix)])
        qmax = jnp.maximum(qmax, jnp.max(qm))
        for i, sol in zip(ix, _split(out, len(ix))):
            sols[i] = sol
    worst = jnp.int32(0)
    for sol in sols:
        worst = jnp.where(worst == 0, sol.result, worst)
    eq_bad = _equilibrium_bad(sy, [_stack([sols[k] for k in ix]) for ix in index], qmax, F, P, rtol)
    valid = jnp.where(worst != 0, worst, jnp.where(eq_bad, RESULTS.equilibrium, RESULTS.successful))
    code = jnp.where(succeeded(code), valid, code).astype(jnp.int32)
    Gz = jnp.stack([(frame_matrix(bset.facings[k]) @ transfer_matrix(bset.positions[k]))[2]
                    for k in range(N)])
    u = sp * (Gz @ x[:5] - x[5:])
    return SetSolution(x[:5], F, code, total_it, res, Kss, e, u, P, bset.positions, tuple(sols),
                       bset.facings, sp)


def _static_start(sy: _System, bset: BearingSet, bks, curves, e, approach):
    """Physical start x = [q_s, u]: q_s = 0 when a rigid preload holds balls in contact; else
    the displacement where every bearing's balls touch under its share of the load (shares from
    linear point springs, one per bearing, with a light tilt stiffness so that one bearing alone
    carries moments), fitted over the bearings by least squares; spring bearings start at the
    axial approach of their preload."""
    F = sy.F
    Ws = [jnp.stack([1.0, 1.0, 1.0, 0.01 * b.inner_groove_radius ** 2, 0.01 * b.inner_groove_radius ** 2])
          for b in bset.bearings]
    Klin = sum(bk.L @ (W[:, None] * bk.G) for bk, W in zip(bks, Ws))
    qlin = jnp.linalg.solve(Klin, F)
    A = jnp.zeros((5, 5))
    rhs = jnp.zeros(5)
    for k, (bk, W, b) in enumerate(zip(bks, Ws, bset.bearings)):
        Fk = W * (bk.G @ qlin)
        qk = initial_displacement(b, Fk, curves[k])
        Ri = b.inner_groove_radius
        V = jnp.stack([1.0, 1.0, 1.0 - sy.sp[k], Ri, Ri]) ** 2
        d = qk - e[k] * _EZ
        A = A + bk.G.T @ (V[:, None] * bk.G)
        rhs = rhs + bk.G.T @ (V * d)
    q_lsq = jnp.linalg.solve(A, rhs)
    rigid_preload = jnp.any(e > 0)
    q = jnp.where(rigid_preload, jnp.zeros(5), q_lsq)
    return jnp.concatenate([q, sy.sp * approach])


# ------------------------------------------------------------------------------ entry points
_solve_jit = jit(solve_set_state, options=QUICK_COMPILE)     # a single state of a set: -O0 (bearingsim.xla)


def solve_set(bset: BearingSet, op: Operation, loads, *, cage_angle=0.0, spalls=None,
              speed_steps: int = 1, maxit: int = 60, rtol: float = 1e-11, atol: float = 1e-9,
              hertz_method: str = "exact", offsets=None, throw: bool = True) -> SetSolution:
    """Solve the set for one load case (see :func:`solve_set_state`); a failed solve is retried
    once with 8 speed steps; ``throw=True`` raises for a failed one."""
    loads = jnp.asarray(loads, jnp.float64)
    maxit, rtol, atol = traced_tolerances(maxit, rtol, atol)
    kw = dict(cage_angle=jnp.asarray(cage_angle, jnp.float64), spalls=spalls, maxit=maxit,
              rtol=rtol, atol=atol, hertz_method=hertz_method, offsets=offsets)
    # the stage count traced (newton.speed_stages): the retry is the same compiled program
    sol = _solve_jit(bset, op, loads, speed_steps=jnp.int32(speed_steps), **kw)
    if failed(int(sol.result)) and speed_steps < 8:
        retry = _solve_jit(bset, op, loads, speed_steps=jnp.int32(8), **kw)
        if succeeded(int(retry.result)):
            sol = retry
    if throw:
        raise_for_set(sol)
    warn_set_overload(bset, sol)
    return sol


def _solve_batch(bset, op, loads, cage_angle, spalls, preload, facings, positions, springs,
                 speed_steps, maxit, rtol, atol, hertz_method, offsets):
    curves = tuple(stiffness_curve(b, hertz_method) for b in bset.bearings)

    def one(o, F, c, P, s, z, sp, e):
        st = eqx.tree_at(lambda b: (b.preload, b.facings, b.positions, b.springs), bset, (P, s, z, sp))
        return solve_set_state(st, o, F, cage_angle=c, spalls=spalls, speed_steps=speed_steps,
                               maxit=maxit, rtol=rtol, atol=atol, hertz_method=hertz_method,
                               curves=curves, offsets=e)

    return jax.vmap(one)(op, loads, cage_angle, preload, facings, positions, springs, offsets)


_solve_batch_jit = jit(_solve_batch)


def solve_set_batch(bset: BearingSet, op: Operation, loads, *, cage_angle=0.0, spalls=None,
                    preload=None, facings=None, positions=None, springs=None, offsets=None,
                    speed_steps: int = 1,
                    maxit: int = 60, rtol: float = 1e-11, atol: float = 1e-9,
                    hertz_method: str = "exact", throw: bool = False) -> SetSolution:
    """vmapped set solve over n cases: ``loads`` (n, 5); ``op.speed`` scalar or (n,);
    ``cage_angle`` scalar, (n,) or (n, N); ``preload``, ``facings``, ``positions``, ``springs``:
    None (the set's), (N,) or (n, N) (sets that differ in these share one compiled program; not
    checked here: facings +1 / -1, springs 1 / 0, not all springs); ``offsets`` None (from the preloads) or (n, N) rigid offsets to
    hold (e.g. those fixed at standstill while the speed changes).  Failed items are retried
    once with 8 speed steps."""
    # the batch is laid out in NumPy outside a program (bearingsim.hostarrays: no eager programs)
    x = xp(bset, op, loads, cage_angle, preload, facings, positions, springs, offsets)
    loads = x.asarray(loads, x.float64)
    n, N = loads.shape[0], bset.n
    op_b = eqx.tree_at(lambda p: (p.speed, p.centrifugal, p.gyroscopic), op,
                       (x.broadcast_to(host(op.speed), (n,)), x.broadcast_to(host(op.centrifugal), (n,)),
                        x.broadcast_to(host(op.gyroscopic), (n,))))
    cage = x.asarray(host(cage_angle), x.float64)
    cage = x.broadcast_to(cage[..., None] if cage.ndim == 1 else cage, (n, N))

    def per_item(v, default):
        return x.broadcast_to(host(default) if v is None else x.asarray(host(v), x.float64), (n, N))

    P = per_item(preload, bset.preload)
    S = per_item(facings, bset.facings)
    Z = per_item(positions, bset.positions)
    SP = per_item(springs, bset.springs)
    e = None if offsets is None else per_item(offsets, None)
    maxit, rtol, atol = traced_tolerances(maxit, rtol, atol)

    def run(sel, steps):
        o = eqx.tree_at(lambda p: (p.speed, p.centrifugal, p.gyroscopic), op_b,
                        (op_b.speed[sel], op_b.centrifugal[sel], op_b.gyroscopic[sel]))
        return _solve_batch_jit(bset, o, loads[sel], cage[sel], spalls, P[sel], S[sel], Z[sel],
                                SP[sel], steps, maxit, rtol, atol, hertz_method, None if e is None else e[sel])

    sol = run(slice(None), speed_steps)
    if speed_steps < 8:     # the failed items again with 8 speed steps (only them)
        sol = retry_failed(sol, lambda idx: run(idx, 8), converged_only)
    if throw:
        raise_for_set(sol, "set batch solve")
    return sol
