"""Cage-angle sweeps (MODEL.md section 6): the quasi-static contact state as the ball set
rotates past the spall.

Two ways, same answer: ``scan`` (default) is continuation, one ``lax.scan`` over cage angles
in which each angle starts from the previous one, with a ``lax.cond`` fallback to the
rigid-ring static start for an angle whose warm start fails; ``vmap`` solves every angle at
once, Newton starting from the converged state at the first angle (failures are redone by
``scan``).  For the rectangular profile, whose state jumps when a ball enters or leaves
the spall, the angles just before and just after every edge are inserted into the grid.
"""
from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from .jones import JonesSolution, _initial_displacement, _solve, _traced_tolerances

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


def _sweep(bearing, op, loads, spall, angles, maxit, rtol, atol, hertz_method):
    def step(q_prev, angle):
        warm = _solve(bearing, op, loads, angle, spall, q_prev, 1, maxit, rtol, atol, hertz_method)

        def cold(_):
            return _solve(bearing, op, loads, angle, spall, None, 2, maxit, rtol, atol, hertz_method)

        sol = lax.cond(warm.result == 0, lambda _: warm, cold, None)
        q_next = jnp.where(sol.result == 0, sol.displacement, q_prev)
        return q_next, sol

    # the first angle starts from the axial-shift start; if that fails at speed, the cold
    # branch goes through the rigid-ring static solution
    q_start = _initial_displacement(bearing, loads, hertz_method)
    _, sols = lax.scan(step, q_start, angles)
    return sols


_sweep_jit = eqx.filter_jit(_sweep)


def _sweep_vmap(bearing, op, loads, spall, angles, maxit, rtol, atol, hertz_method):
    # every angle starts Newton from the converged state at the first angle (one cold solve),
    # all angles at once: the batch amortises the per-operation cost of the small ball problems
    first = _solve(bearing, op, loads, angles[0], spall, None, 1, maxit, rtol, atol, hertz_method)
    q0 = first.displacement

    def one(angle):
        return _solve(bearing, op, loads, angle, spall, q0, 1, maxit, rtol, atol, hertz_method)

    return jax.vmap(one)(angles)


_sweep_vmap_jit = eqx.filter_jit(_sweep_vmap)


def sweep(bearing, op, loads, spall=None, angles=None, start=0.0, stop=None, steps=181,
          resolve_edges=True, method="scan", maxit=60, rtol=1e-11, atol=1e-9,
          hertz_method="exact") -> JonesSolution:
    """Quasi-static states over cage angles: a JonesSolution whose arrays have a leading (N,) axis.

    Give ``angles`` (rad) or ``start``/``stop`` (rad, default one ball pitch)/``steps``.
    ``method="scan"`` (default, faster on CPU) is continuation (``lax.scan``, each angle from the
    previous one, cold restart where that fails); ``method="vmap"`` solves all angles at once
    from the converged first angle and redoes failures by continuation.  Never raises:
    ``result`` is per angle.
    """
    if angles is None:
        stop = start + 2 * np.pi / bearing.n_balls if stop is None else stop
        angles = sweep_angles(bearing, spall, start, stop, steps, resolve_edges)
    angles = jnp.asarray(angles, dtype=jnp.float64)
    maxit, rtol, atol = _traced_tolerances(maxit, rtol, atol)
    loads = jnp.asarray(loads, jnp.float64)
    if method == "scan":
        return _sweep_jit(bearing, op, loads, spall, angles, maxit, rtol, atol, hertz_method)
    if method != "vmap":
        raise ValueError(f"sweep method must be 'vmap' or 'scan', got {method!r}")
    sol = _sweep_vmap_jit(bearing, op, loads, spall, angles, maxit, rtol, atol, hertz_method)
    bad = np.flatnonzero(np.asarray(sol.result) != 0)
    if bad.size:
        redo = _sweep_jit(bearing, op, loads, spall, angles, maxit, rtol, atol, hertz_method)
        idx = jnp.asarray(bad)
        sol = jax.tree_util.tree_map(lambda a, r: a.at[idx].set(r[idx]), sol, redo)
    return sol


def sweep_chunked(bearing, op, loads, spall, angles, chunk=64, progress=None, **kw):
    """The same sweep in chunks (continuation carried across chunks), calling ``progress(n)``
    after each chunk: for progress bars on long sweeps.  One compilation per chunk length."""
    angles = np.asarray(angles, dtype=float)
    parts = []
    for k in range(0, len(angles), chunk):
        part = angles[k:k + chunk]
        if len(part) < chunk and len(angles) > chunk:   # keep one compiled shape: pad, then cut
            pad = np.concatenate([part, np.full(chunk - len(part), part[-1])])
            sol = sweep(bearing, op, loads, spall, angles=pad, **kw)
            sol = jax.tree_util.tree_map(lambda a: a[:len(part)], sol)
        else:
            sol = sweep(bearing, op, loads, spall, angles=part, **kw)
        parts.append(sol)
        if progress is not None:
            progress(len(part))
    return jax.tree_util.tree_map(lambda *a: jnp.concatenate(a, axis=0), *parts)
