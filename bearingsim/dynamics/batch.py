"""What a batch of items (a data set's chunk program, :mod:`bearingsim.dynamics.program`) needs
fixed before it runs: the defect *slots* (:func:`defect_slots`: one per location, outer, inner,
ball; a depth-0 slot is inactive, so items of every class share one compiled program), the
items that bound a batch (:func:`extreme_items`) and the substeps and Newton step count checked
on them (:func:`batch_settings`), so that chunks of a data set never recompile.
"""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from ..physics.defect import LOCATIONS, Spall
from ..errors import failed, InputError
from ..physics.hertz import stiffness_curve
from ..physics.jones import solve
from .ball_force import ITER_CHOICES, choose_ball_iterations
from .model import build_model, choose_substeps, linear_modes
from .parameters import DynamicsParameters
from .frequencies import characteristic_frequencies, spin_ratio

__all__ = ["defect_slots", "extreme_items", "batch_settings"]


def defect_slots(location, center, extent, depth, profile="rectangular", slots=None):
    """One :class:`Spall` per slot location (a tuple, batched arrays): item i's defect sits in the
    slot of ``location[i]`` ("outer", "inner", "ball"; a ball pit on ball 0 with ``center`` its
    spin angle), every other slot of item i has depth 0.  ``slots``: the locations the program
    carries (default: those in ``location``, in the order of ``LOCATIONS``)."""
    loc = np.asarray(location)
    bad = sorted(set(loc.ravel().tolist()) - set(LOCATIONS))
    if bad:
        raise InputError(f"defect location must be one of {LOCATIONS}, got {bad}")
    slots = tuple(L for L in LOCATIONS if L in set(loc.ravel().tolist())) if slots is None else tuple(slots)
    out = []
    for L in slots:
        mine = jnp.asarray(loc == L)
        out.append(Spall(jnp.where(mine, center, 0.0), jnp.where(mine, extent, 0.0),
                         jnp.where(mine, depth, 0.0), profile, L, 0))
    return tuple(out)


def extreme_items(groups, speed, load, size):
    """Indices of the items that bound a batch, per group (defect class or location): the
    fastest and the slowest, the most and the least loaded, the largest defect.  The ball Newton
    step count and the substeps checked on them hold for every item between them."""
    groups, speed, load, size = (np.asarray(a) for a in (groups, speed, load, size))
    out = set()
    for g in np.unique(groups):
        ii = np.flatnonzero(groups == g)
        for v in (speed, -speed, load, -load, size):
            out.add(int(ii[np.argmax(v[ii])]))
    return sorted(out)


def batch_settings(bearing, op, loads, spall, theta0, sample_rate, params=None, hertz_method="exact"):
    """(ball_iterations, substeps) for items like this one (a single item's quasi-static state
    checked with :func:`choose_ball_iterations` and :func:`choose_substeps`); fix them once for
    a data set so that no chunk recompiles.  ``spall``: None, a Spall or a tuple (slots)."""
    params = DynamicsParameters() if params is None else params
    curve = stiffness_curve(bearing, hertz_method)
    sol = solve(bearing, op, loads, cage_angle=theta0, spall=spall, hertz_method=hertz_method, throw=False)
    if failed(int(sol.result)):
        return None, None
    _, a_m = characteristic_frequencies(bearing, op, sol)
    k = spin_ratio(bearing, a_m)
    it, _ = choose_ball_iterations(bearing, op, sol.displacement, spall, curve, theta0, spin_ratio=k)
    it = it or ITER_CHOICES[-1]
    model = build_model(bearing, op, loads, (), sol, params, curve, it)
    lam = np.abs(linear_modes(model))
    return it, choose_substeps(np.max(lam[np.isfinite(lam)], initial=0.0), sample_rate)
