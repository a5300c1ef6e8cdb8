"""The verdict on a set's state (docs/model.md section 10), for the exceptions and warnings of
:func:`bearingsim.physics.shaft.solve_set` and the workflows: which code and which bearing a failed
set is refused for (:func:`set_verdict`: a bearing outside the model names why the iteration
failed), the error with a hint that is true for a set (:func:`raise_for_set`) and the overload
warning (:func:`warn_set_overload`).  Reads a ``SetSolution``; imports no set model.
"""
from __future__ import annotations

import warnings

import numpy as np

from ..errors import BearingsimError, failed
from .jones import PRESSURE_WARNING, RESULTS, OverloadWarning, raise_for
from .preload import static_axial_capacity

__all__ = ["set_verdict", "raise_for_set", "warn_set_overload", "SET_NEWTON_HINT", "SET_SHOULDER_HINT"]


#: a bearing's own codes that name why a set's iteration failed: a state outside the model
_BEARING_CAUSES = (RESULTS.inverted_contact, RESULTS.beyond_bounds, RESULTS.low_shoulder, RESULTS.over_shoulder,
                   RESULTS.no_load)


def set_verdict(sol):
    """Per item (flat C order): ``(code, bearing)``: the set's verdict and the 0-based bearing it
    names (-1: none).  Where the set's Newton iteration failed (maximum iterations, stalled) and a
    bearing's own check at its last iterate finds a state outside the model (a contact beyond its
    groove edge, against its low shoulder, beyond the bounds, inverted), that bearing's code is the
    verdict: the iteration failed because the state it approaches lies outside the model, and the
    hint must be that code's, not one to raise an iteration count (issue 35)."""
    codes = np.ravel(np.asarray(sol.result)).astype(int)
    per = np.asarray(sol.bearing_result).reshape(codes.size, -1)
    verdict, which = codes.copy(), np.full(codes.size, -1)
    causes = [int(c) for c in _BEARING_CAUSES]
    for i in np.flatnonzero(failed(codes)):
        bad = np.flatnonzero(per[i] != 0)
        if bad.size:
            which[i] = int(bad[0])
        if codes[i] in (int(RESULTS.max_iterations), int(RESULTS.stagnated)):
            named = [int(j) for j in np.flatnonzero(np.isin(per[i], causes))]
            if named:
                which[i] = named[0]
                verdict[i] = int(per[i][named[0]])
    return verdict, which


#: the hint of a set whose iteration failed with every bearing inside the model: what a case can
#: change (the solver's options maxit / speed_steps are no case keys)
SET_NEWTON_HINT = ("the set's equilibrium was not reached (every bearing inside the model at the last iterate): "
                   "check that the loads and the preload are of the bearings' size (N, N m; a preload of the order "
                   "of 1 % of C_0a); from Python, solve_set(..., speed_steps=..., maxit=...) takes more speed "
                   "stages and iterations (no case key does)")


#: the hint of a set refused for a bearing's contact over its groove edge (the single bearing's
#: hint suggests "a preloaded pair", which a set already is)
SET_SHOULDER_HINT = ("in a set a bearing's contact angles climb with the axial load it carries (the external load "
                     "plus its operating preload, which grows with speed under a rigid preload) and, at speed, on "
                     "its lightly loaded balls: lower the axial load or the moment, or the preload (a lighter class, "
                     "or a spring preload, which stays constant at speed), or check the shoulder angles ([shoulders] "
                     "keys of the case)")


class _Verdict:
    """What :func:`bearingsim.physics.jones.raise_for` reads of a set's solution, with the verdict of
    :func:`set_verdict` as its result codes."""

    def __init__(self, sol, result):
        self.result, self.loads = result, sol.loads
        self.residual_norm, self.iterations = sol.residual_norm, sol.iterations


def raise_for_set(sol, what: str = "set solve"):
    """Raise for the first failed item (see :func:`bearingsim.physics.jones.raise_for`: the set's
    verdict (:func:`set_verdict`), its external loads), naming the bearing whose own check failed
    where one did and the axial load it carries, with the hint for a bearing in a set.  A set's
    hints name what the case can change (loads, preload, arrangement), never a solver option."""
    codes = np.ravel(np.asarray(sol.result))
    bad = np.flatnonzero(failed(codes))
    if not bad.size:
        return
    verdict, which = set_verdict(sol)
    k = int(bad[0])
    j = int(which[k])
    if j >= 0:
        Fk = float(np.ravel(np.asarray(sol.bearings[j].loads[..., 2]))[k])
        what = f"{what} (bearing {j + 1} of {sol.n}, carrying {Fk:.6g} N axially in its contact direction)"
    if verdict[k] != codes[k]:
        what = (f"{what}: the Newton iteration stopped ({RESULTS.of(codes[k]).message}) at a state outside "
                f"the model for bearing {j + 1}, so the set")
    try:
        raise_for(_Verdict(sol, verdict.reshape(np.shape(np.asarray(sol.result)))), what, in_set=True)
    except BearingsimError as e:
        hint = {int(RESULTS.max_iterations): SET_NEWTON_HINT, int(RESULTS.stagnated): SET_NEWTON_HINT,
                int(RESULTS.over_shoulder): SET_SHOULDER_HINT}.get(int(verdict[k]))
        if hint is None:
            raise
        raise type(e)(e.message, hint, e.code) from None


def warn_set_overload(bset, sol):
    """Warn (:class:`~bearingsim.physics.jones.OverloadWarning`, as a single bearing's solve does) when a
    converged set has a contact above :data:`~bearingsim.physics.jones.PRESSURE_WARNING`, naming the
    bearing, and its preload where that alone exceeds its static axial capacity C_0a."""
    if failed(int(sol.result)):
        return
    p = np.asarray(sol.max_pressure)
    for k in np.flatnonzero(p > PRESSURE_WARNING):
        k = int(k)
        P = float(np.asarray(sol.preload)[k])
        extra = ""
        if P > 0.0:
            C0a = float(static_axial_capacity(bset.bearings[k]))
            if P > C0a:
                extra = (f"; its preload {P:.6g} N is above its static axial capacity C_0a = {C0a:.6g} N "
                         "(the thrust that alone gives 4.2 GPa at standstill): lower the preload")
        warnings.warn(f"bearing {k + 1} of {sol.n}: contact pressure {p[k] / 1e9:.2f} GPa exceeds "
                      f"{PRESSURE_WARNING / 1e9:.1f} GPa (ISO 76 static-capacity stress): the steel deforms "
                      f"permanently; the Hertz result is an elastic idealisation{extra}", OverloadWarning,
                      stacklevel=3)
