"""Cage-angle sweeps (MODEL.md section 6): the quasi-static contact state as the ball set
rotates past the defect.

The angles fall into runs over which the same balls are over the defect.  One angle of each run
(its middle) is solved cold (the compiled single solve); then all angles are solved at once
(``vmap`` of :func:`bearingsim.jones.solve_state`), each warm started from its run's solution
(ring displacement and every ball's centre, ball by ball).  That is one fixed-shape batched
Newton -- a handful of large kernels instead of one small solve per angle -- whose starts are
all a fraction of a ball pitch from a converged state with the same balls in the defect, so
the lockstep loop needs few iterations.  Angles that fail from the warm start are solved again
from the rigid-ring static solution in 8 speed steps (a second compiled program, only when
needed).  For the rectangular
profile, whose state jumps when a ball enters or leaves the spall, the angles just before and
just after every edge are inserted into the grid.
"""
from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .hertz import stiffness_curve
from .defect import depth_profile
from .jones import JonesSolution, raise_for, solve, solve_state

__all__ = ["EDGE_EPS", "spall_edge_angles", "sweep_angles", "defect_occupancy", "representatives",
           "sweep", "sweep_chunked"]

EDGE_EPS = 1e-7   # rad: the inserted angles sit this far either side of a spall edge


def spall_edge_angles(bearing, spall, start, stop):
    """Cage angles in [start, stop] at which some ball crosses a spall edge (rad, sorted)."""
    if spall is None or float(spall.depth) <= 0.0:
        return np.zeros(0)
    lo, hi = sorted((float(start), float(stop)))
    Z = bearing.n_balls
    pitch = 2 * np.pi / Z
    out = []
    for edge in (float(spall.center) - 0.5 * float(spall.extent), float(spall.center) + 0.5 * float(spall.extent)):
        for j in range(Z):
            base = edge - j * pitch
            k0 = np.ceil((lo - base) / (2 * np.pi))
            k1 = np.floor((hi - base) / (2 * np.pi))
            for k in np.arange(k0, k1 + 1):
                out.append(base + 2 * np.pi * k)
    return np.unique(np.asarray(out))


def sweep_angles(bearing, spall, start, stop, steps, resolve_edges=True):
    """Uniform grid from start to stop (inclusive) with both sides of every rectangular-spall
    edge inserted (sorted in the sweep direction)."""
    grid = np.linspace(float(start), float(stop), int(steps))
    if resolve_edges and spall is not None and spall.profile == "rectangular":
        edges = spall_edge_angles(bearing, spall, start, stop)
        extra = np.concatenate([edges - EDGE_EPS, edges + EDGE_EPS])
        lo, hi = sorted((float(start), float(stop)))
        extra = extra[(extra >= lo) & (extra <= hi)]
        grid = np.unique(np.concatenate([grid, extra]))
        if stop < start:
            grid = grid[::-1]
    return grid


def defect_occupancy(bearing, spall, angles):
    """(N, Z) bool: which balls are over the defect at each cage angle (numpy)."""
    angles = np.asarray(angles, dtype=float)
    if spall is None:
        return np.zeros((angles.size, bearing.n_balls), bool)
    psi = jax.vmap(bearing.ball_azimuths)(jnp.asarray(angles))
    return np.asarray(jax.vmap(lambda p: depth_profile(bearing, spall, p))(psi)) > 0.0


def representatives(occupancy):
    """Index of the middle angle of every run of equal defect occupancy, and each angle's run."""
    change = np.any(occupancy[1:] != occupancy[:-1], axis=1)
    run = np.concatenate([[0], np.cumsum(change)])
    reps = np.array([int(np.flatnonzero(run == r)[len(np.flatnonzero(run == r)) // 2])
                     for r in range(run[-1] + 1)])
    return reps, run


def _sweep_warm(bearing, op, loads, spall, angles, q0, x0, xu0, maxit, rtol, atol, hertz_method):
    curve = stiffness_curve(bearing, hertz_method)
    at_rest = op.speed <= 0.0            # at rest the closed form is the exact ball start

    def one(angle, q, x, xu):
        x, xu = (jnp.where(at_rest, jnp.nan, v) for v in (x, xu))
        return solve_state(bearing, op, loads, cage_angle=angle, spall=spall, q0=q, x0=x, xu0=xu,
                           maxit=maxit, rtol=rtol, atol=atol, hertz_method=hertz_method,
                           curve=curve)

    return jax.vmap(one)(angles, q0, x0, xu0)


_sweep_warm_jit = eqx.filter_jit(_sweep_warm)


def _sweep_cold(bearing, op, loads, spall, angles, maxit, rtol, atol, hertz_method):
    curve = stiffness_curve(bearing, hertz_method)
    return jax.vmap(lambda a: solve_state(
        bearing, op, loads, cage_angle=a, spall=spall, speed_steps=8, maxit=maxit, rtol=rtol,
        atol=atol, hertz_method=hertz_method, curve=curve))(angles)


_sweep_cold_jit = eqx.filter_jit(_sweep_cold)


def _tolerances(maxit, rtol, atol):
    return jnp.asarray(maxit, jnp.int32), jnp.asarray(rtol, jnp.float64), jnp.asarray(atol, jnp.float64)


def sweep(bearing, op, loads, spall=None, *, angles=None, start=0.0, stop=None, steps=181,
          resolve_edges=True, maxit=60, rtol=1e-11, atol=1e-9,
          hertz_method="exact", throw=False) -> JonesSolution:
    """Quasi-static states over cage angles: a JonesSolution whose arrays have a leading (N,) axis.

    Give ``angles`` (rad) or ``start``/``stop`` (rad, default one ball pitch)/``steps``.
    ``throw=False`` (default): ``result`` is per angle; ``throw=True`` raises for the
    first angle that failed (naming how many did).
    """
    if angles is None:
        stop = start + 2 * np.pi / bearing.n_balls if stop is None else stop
        angles = sweep_angles(bearing, spall, start, stop, steps, resolve_edges)
    angles = jnp.asarray(angles, dtype=jnp.float64)
    loads = jnp.asarray(loads, jnp.float64)
    tol = _tolerances(maxit, rtol, atol)
    kw = dict(spall=spall, maxit=maxit, rtol=rtol, atol=atol, hertz_method=hertz_method, throw=False)
    # one cold solve per run of equal defect occupancy (the same compiled single solve), then
    # every angle warm started from its run's solution, all at once
    reps, run = representatives(defect_occupancy(bearing, spall, angles))
    rep_sols = [solve(bearing, op, loads, cage_angle=angles[int(r)], **kw) for r in reps]
    ok_rep = np.array([int(r.result) == 0 for r in rep_sols])
    start = jax.tree_util.tree_map(lambda *a: jnp.stack(a)[jnp.asarray(run)], *[
        (r.displacement, r.ball_position, r.undropped_position) for r in rep_sols])
    sol = _sweep_warm_jit(bearing, op, loads, spall, angles, *start, *tol, hertz_method)
    bad = np.flatnonzero((np.asarray(sol.result) != 0) | ~ok_rep[run])
    if bad.size:
        # pad to a power of two: one compiled shape for any number of failures
        n = 1 << int(np.ceil(np.log2(bad.size)))
        idx = np.concatenate([bad, np.full(n - bad.size, bad[0])])
        redo = _sweep_cold_jit(bearing, op, loads, spall, angles[idx], *tol, hertz_method)
        redo = jax.tree_util.tree_map(lambda r: r[:bad.size], redo)
        ok = (np.asarray(redo.result) == 0) | (np.asarray(sol.result)[bad] != 0)
        take = jnp.asarray(bad[ok])
        sol = jax.tree_util.tree_map(lambda a, r: a.at[take].set(r[jnp.asarray(ok)]), sol, redo)
    if throw:
        raise_for(sol, "cage-angle sweep")
    return sol


def sweep_chunked(bearing, op, loads, spall, angles, chunk=256, progress=None, **kw):
    """The same sweep in chunks of ``chunk`` angles, calling ``progress(n)`` after each chunk:
    for progress bars on long sweeps.  One compilation for every chunk (the last is padded)."""
    angles = np.asarray(angles, dtype=float)
    parts = []
    for k in range(0, len(angles), chunk):
        part = angles[k:k + chunk]
        pad = part if len(angles) <= chunk else np.concatenate(
            [part, np.full(chunk - len(part), part[-1])])
        sol = sweep(bearing, op, loads, spall, angles=pad, **kw)
        parts.append(jax.tree_util.tree_map(lambda a: a[:len(part)], sol))
        if progress is not None:
            progress(len(part))
    return jax.tree_util.tree_map(lambda *a: jnp.concatenate(a, axis=0), *parts)
