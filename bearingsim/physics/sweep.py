"""Cage-angle sweeps (docs/model.md section 6): the quasi-static contact state as the ball set
rotates past the defect.

The angles fall into runs over which the same balls are over the defect.  One angle of each run
(its middle) is solved cold (the compiled single solve); then all angles are solved at once
(``vmap`` of :func:`bearingsim.physics.jones.solve_state`), each warm started from its run's solution
(ring displacement and every ball's centre, ball by ball).  That is one fixed-shape batched
Newton -- a handful of large kernels instead of one small solve per angle -- whose starts are
all a fraction of a ball pitch from a converged state with the same balls in the defect, so
the lockstep loop needs few iterations.  Angles that fail from the warm start are solved again
from the rigid-ring static solution in 8 speed steps (a second compiled program, only when
needed).  For the rectangular
profile, whose state jumps when a ball enters or leaves the spall, the angles just before and
just after every edge are inserted into the grid.

:func:`sweep_defect_angle` sweeps the centre of one defect at a fixed cage angle instead (the
inner-raceway spall's azimuth psi_di = phi_d + omega t, a ball pit's spin angle; docs/model.md section 9),
with the same strategy: the quasi-static state of an inner spall depends on both the cage
angle and the spall azimuth, and either may be swept with the other held.
"""
from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .hertz import stiffness_curve
from .defect import Spall, as_defects, canonical_defects, contact_depths
from .jones import JonesSolution, raise_for, solve, solve_state
from ..names import noun_module
from .newton import retry_failed, traced_tolerances
from ..programs import jit
from ..errors import failed, succeeded

__all__ = ["EDGE_EPS", "spall_edge_angles", "sweep_angles", "defect_occupancy", "representatives",
           "sweep", "sweep_chunked", "defect_centre_edges", "defect_angles", "sweep_defect_angle"]

EDGE_EPS = 1e-7   # rad: the inserted angles sit this far either side of a spall edge


def _periodic_hits(bases, lo, hi):
    """Every base + 2 pi k within [lo, hi]."""
    out = []
    for base in bases:
        k0 = np.ceil((lo - base) / (2 * np.pi))
        k1 = np.floor((hi - base) / (2 * np.pi))
        out.extend(base + 2 * np.pi * np.arange(k0, k1 + 1))
    return out


def spall_edge_angles(bearing, spall, start, stop):
    """Cage angles in [start, stop] at which some ball crosses the edge of a raceway spall
    (outer or inner; ``spall`` may be a tuple of defects; a ball pit has no edge in the cage
    angle) (rad, sorted)."""
    lo, hi = sorted((float(start), float(stop)))
    pitch = 2 * np.pi / bearing.n_balls
    out = []
    for sp in as_defects(spall):
        if sp.location == "ball" or float(sp.depth) <= 0.0:
            continue
        for edge in (float(sp.center) - 0.5 * float(sp.extent), float(sp.center) + 0.5 * float(sp.extent)):
            out += _periodic_hits([edge - j * pitch for j in range(bearing.n_balls)], lo, hi)
    return np.unique(np.asarray(out, dtype=float))


def _rectangular(spall):
    return any(sp.profile == "rectangular" for sp in as_defects(spall))


def sweep_angles(bearing, spall, start, stop, steps, resolve_edges=True):
    """Uniform grid from start to stop (inclusive) with both sides of every rectangular-spall
    edge inserted (sorted in the sweep direction)."""
    edges = spall_edge_angles(bearing, spall, start, stop) if resolve_edges and _rectangular(spall) \
        else np.zeros(0)
    return _grid_with_edges(start, stop, steps, edges)


def _grid_with_edges(start, stop, steps, edges):
    """Uniform grid from start to stop (inclusive) with the angles EDGE_EPS either side of every
    edge inserted, sorted in the sweep direction."""
    grid = np.linspace(float(start), float(stop), int(steps))
    if len(edges):
        extra = np.concatenate([edges - EDGE_EPS, edges + EDGE_EPS])
        lo, hi = sorted((float(start), float(stop)))
        extra = extra[(extra >= lo) & (extra <= hi)]
        grid = np.unique(np.concatenate([grid, extra]))
        if stop < start:
            grid = grid[::-1]
    return grid


def _with_center(spall, which, center):
    """The defects with defect ``which``'s centre replaced (a Spall stays a Spall)."""
    if isinstance(spall, Spall):
        return eqx.tree_at(lambda s: s.center, spall, jnp.asarray(center, jnp.float64))
    d = list(as_defects(spall))
    d[which] = eqx.tree_at(lambda s: s.center, d[which], jnp.asarray(center, jnp.float64))
    return tuple(d)


def defect_occupancy(bearing, spall, angles, centers=None, which=0):
    """(N, 2Z) bool: which balls have a defect in their outer contact (columns 0..Z-1) and in
    their inner contact (Z..2Z-1) at each cage angle (numpy).  With ``centers`` (N,), defect
    ``which``'s centre takes those values (a sweep of the defect angle)."""
    angles = np.asarray(angles, dtype=float)
    if not as_defects(spall):
        return np.zeros((angles.size, 2 * bearing.n_balls), bool)
    psi = jax.vmap(bearing.ball_azimuths)(jnp.asarray(angles))
    if centers is None:
        Ho, Hi = jax.vmap(lambda p: contact_depths(bearing, spall, p))(psi)
    else:
        Ho, Hi = jax.vmap(lambda p, c: contact_depths(bearing, _with_center(spall, which, c), p))(
            psi, jnp.asarray(centers, jnp.float64))
    return np.concatenate([np.asarray(Ho) > 0.0, np.asarray(Hi) > 0.0], axis=1)


def representatives(occupancy):
    """Index of the middle angle of every run of equal defect occupancy, and each angle's run."""
    change = np.any(occupancy[1:] != occupancy[:-1], axis=1)
    run = np.concatenate([[0], np.cumsum(change)])
    reps = np.array([int(np.flatnonzero(run == r)[len(np.flatnonzero(run == r)) // 2])
                     for r in range(run[-1] + 1)])
    return reps, run


def _sweep_warm(bearing, op, loads, spall, angles, q0, x0, xu0, maxit, rtol, atol, hertz_method,
                centers=None, which=0):
    curve = stiffness_curve(bearing, hertz_method)
    at_rest = op.speed <= 0.0            # at rest the closed form is the exact ball start

    def one(angle, q, x, xu, c):
        x, xu = (jnp.where(at_rest, jnp.nan, v) for v in (x, xu))
        sp = spall if c is None else _with_center(spall, which, c)
        return solve_state(bearing, op, loads, cage_angle=angle, spall=sp, q0=q, x0=x, xu0=xu,
                           maxit=maxit, rtol=rtol, atol=atol, hertz_method=hertz_method,
                           curve=curve)

    if centers is None:
        return jax.vmap(lambda a, q, x, xu: one(a, q, x, xu, None))(angles, q0, x0, xu0)
    return jax.vmap(one)(angles, q0, x0, xu0, centers)


_sweep_warm_jit = jit(_sweep_warm)


def _sweep_cold(bearing, op, loads, spall, angles, maxit, rtol, atol, hertz_method, centers=None,
                which=0):
    curve = stiffness_curve(bearing, hertz_method)

    def one(a, c):
        sp = spall if c is None else _with_center(spall, which, c)
        return solve_state(bearing, op, loads, cage_angle=a, spall=sp, speed_steps=8, maxit=maxit,
                           rtol=rtol, atol=atol, hertz_method=hertz_method, curve=curve)

    if centers is None:
        return jax.vmap(lambda a: one(a, None))(angles)
    return jax.vmap(one)(angles, centers)


_sweep_cold_jit = jit(_sweep_cold)


def sweep(bearing, op, loads, spall=None, *, angles=None, start=0.0, stop=None, steps=181,
          resolve_edges=True, maxit=60, rtol=1e-11, atol=1e-9,
          hertz_method="exact", throw=False, centers=None, which=0) -> JonesSolution:
    """Quasi-static states over cage angles: a JonesSolution whose arrays have a leading (N,) axis.

    Give ``angles`` (rad) or ``start``/``stop`` (rad, default one ball pitch)/``steps``.
    ``centers`` (N,) with ``angles``: defect ``which``'s centre at each angle too (a path in
    (cage angle, defect angle): an inner spall or a ball pit turning while the cage turns, e.g.
    the instants of a dynamic run).
    ``throw=False`` (default): ``result`` is per angle; ``throw=True`` raises for the
    first angle that failed (naming how many did).
    """
    if angles is None:
        stop = start + 2 * np.pi / bearing.n_balls if stop is None else stop
        angles = sweep_angles(bearing, spall, start, stop, steps, resolve_edges)
    cs = None if centers is None else jnp.asarray(centers, dtype=jnp.float64)
    sol = _run(bearing, op, loads, spall, jnp.asarray(angles, dtype=jnp.float64), cs, which, maxit,
               rtol, atol, hertz_method)
    if throw:
        raise_for(sol, "cage-angle sweep", bearing=bearing)
    return sol


def _run(bearing, op, loads, spall, angles, centers, which, maxit, rtol, atol, hertz_method):
    """The sweep over (cage angle, defect centre) pairs: angles (N,), centers (N,) or None."""
    loads = jnp.asarray(loads, jnp.float64)
    tol = traced_tolerances(maxit, rtol, atol)
    kw = dict(maxit=maxit, rtol=rtol, atol=atol, hertz_method=hertz_method, throw=False)
    spall = canonical_defects(spall)
    at = (lambda k: spall) if centers is None else (lambda k: _with_center(spall, which, centers[k]))
    extra = {} if centers is None else dict(centers=centers, which=which)
    # one cold solve per run of equal defect occupancy (the same compiled single solve), then
    # every angle warm started from its run's solution, all at once
    reps, run = representatives(defect_occupancy(bearing, spall, angles, centers, which))
    rep_sols = [solve(bearing, op, loads, cage_angle=angles[int(r)], spall=at(int(r)), **kw)
                for r in reps]
    ok_rep = np.array([succeeded(int(r.result)) for r in rep_sols])
    start = jax.tree_util.tree_map(lambda *a: np.stack([np.asarray(v) for v in a])[np.asarray(run)], *[
        (r.displacement, r.ball_position, r.undropped_position) for r in rep_sols])     # on the host: no eager programs
    sol = _sweep_warm_jit(bearing, op, loads, spall, angles, *start, *tol, hertz_method, **extra)
    # the failed angles (and those whose run's cold solve failed) again from cold starts; a redo
    # replaces a failed angle, or a converged one only when it converged too
    bad = failed(np.asarray(sol.result)) | ~ok_rep[run]

    def redo(idx):
        ex = extra if centers is None else dict(centers=centers[idx], which=which)
        return _sweep_cold_jit(bearing, op, loads, spall, angles[idx], *tol, hertz_method, **ex)

    return retry_failed(sol, redo, lambda r, first: (r == 0) | (first != 0), bad=bad)


def defect_centre_edges(bearing, spall, start, stop, cage_angle=0.0, which=0):
    """Centres of defect ``which`` in [start, stop] at which one of its edges meets a ball
    (raceway spall: an edge at a ball azimuth psi_j; ball pit: an edge at the outer (0) or inner
    (pi) contact) (rad, sorted): where a rectangular profile steps."""
    sp = as_defects(spall)[which]
    lo, hi = sorted((float(start), float(stop)))
    if float(sp.depth) <= 0.0:
        return np.zeros(0)
    if sp.location == "ball":
        targets = [0.0, np.pi]
    else:
        targets = list(np.asarray(bearing.ball_azimuths(float(cage_angle)), dtype=float))
    half = 0.5 * float(sp.extent)
    out = _periodic_hits([t + e for t in targets for e in (-half, half)], lo, hi)
    return np.unique(np.asarray(out, dtype=float))


def defect_angles(bearing, spall, start, stop, steps, cage_angle=0.0, which=0, resolve_edges=True):
    """Uniform grid of defect centres from start to stop (inclusive), with both sides of every
    rectangular edge inserted (sorted in the sweep direction)."""
    sp = as_defects(spall)[which]
    edges = defect_centre_edges(bearing, spall, start, stop, cage_angle, which) \
        if resolve_edges and sp.profile == "rectangular" else np.zeros(0)
    return _grid_with_edges(start, stop, steps, edges)


def sweep_defect_angle(bearing, op, loads, spall, centers=None, *, which=0, cage_angle=0.0,
                       start=None, stop=None, steps=181, resolve_edges=True, maxit=60, rtol=1e-11,
                       atol=1e-9, hertz_method="exact", throw=False) -> JonesSolution:
    """Quasi-static states over the centre of one defect at a fixed cage angle: a JonesSolution
    with a leading (N,) axis (``cage_angle`` is the same for every item).

    The swept ``center`` is that of defect ``which`` (``spall`` a Spall or a tuple of them):
    for an inner-raceway spall its azimuth psi_di = phi_d + omega t in the fixed frame (docs/model.md
    9: the spall turns with the inner ring while the balls stand at the given cage angle); for
    a ball pit its spin angle theta_b (0: in the outer contact, pi: in the inner contact); for an
    outer spall its azimuth.  Give ``centers`` (rad) or ``start``/``stop`` (rad; default one ball
    pitch around the defect's own centre for a raceway spall, one ball turn for a pit)/``steps``.
    Same strategy as :func:`sweep` (cold solve per run of equal occupancy, warm-started batch).
    """
    sp = as_defects(spall)[which]
    if centers is None:
        c0 = float(sp.center)
        span = 2 * np.pi if sp.location == "ball" else 2 * np.pi / bearing.n_balls
        start = c0 - 0.5 * span if start is None else start
        stop = start + span if stop is None else stop
        centers = defect_angles(bearing, spall, start, stop, steps, cage_angle, which, resolve_edges)
    centers = jnp.asarray(centers, dtype=jnp.float64)
    angles = jnp.full(centers.shape, float(cage_angle), dtype=jnp.float64)
    sol = _run(bearing, op, loads, spall, angles, centers, which, maxit, rtol, atol, hertz_method)
    if throw:
        raise_for(sol, "defect-angle sweep", bearing=bearing)
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



# ``bearingsim.sweep(...)`` calls :func:`sweep` (the package exports this module as its noun)
noun_module(__name__, "sweep")
