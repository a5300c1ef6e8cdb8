"""The damped Newton machinery the quasi-static solvers share: :mod:`bearingsim.physics.jones` (one
bearing, 2Z + 5 unknowns) and :mod:`bearingsim.physics.shaft` (a shaft on N bearings) run the same loop
with their own unknowns, and both, with the dynamics' quasi-static batch and the sweeps, retry
the failed items of a batch the same way.

* Step constants: the first :data:`FREE_STEPS` full steps are taken unless they blow up, a line
  search gives up after :data:`LS_STEPS` halvings, a step moves the ring by at most
  :data:`RING_CAP` um (tilts: um at the reference radius) and a ball by :data:`BALL_CAP` x D.
* :func:`cap_step`: one step block scaled down to its cap (non-finite entries to 0).
* :func:`accept_step`: the descent test (the residual falls, or Deuflhard's natural
  monotonicity: the simplified Newton correction shrinks).
* :func:`step_status`: the bookkeeping of one step and the loop's status code (0 converged, 1
  out of iterations, 2 non-finite first step, 3 stalled, -1 go on) -- the Newton codes of
  ``jones.RESULTS`` (:data:`NEWTON_FAILURES`: the iteration ended on no state).
* :func:`retry_failed`: the failed items of a batch solved again (a caller's ``run`` of the
  padded indices: the padding to a power of two keeps one compiled shape for any number of
  failures), merged where the caller's rule (:func:`better`, :func:`converged_only`) takes them.

Pure JAX inside the loop helpers; :func:`retry_failed` is host orchestration (it reads the
result codes) and runs outside any trace.  Knows nothing of bearings.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from ..errors import failed
from ..hostarrays import xp
from ..programs import jit

__all__ = ["LS_STEPS", "FREE_STEPS", "RING_CAP", "BALL_CAP", "NEWTON_FAILURES", "traced_tolerances",
           "max_abs", "cap_step", "accept_step", "step_status", "better", "converged_only", "retry_failed",
           "speed_stages", "solve2", "inverse2"]

#: line-search halvings before a step is declared stalled
LS_STEPS = 12
#: full Newton steps accepted without a descent test (unless the residual grows 1e6-fold)
FREE_STEPS = 12
#: cap of one step on the ring (um, or um at the reference radius for tilts)
RING_CAP = 200.0
#: cap of one step on a ball centre (x the ball diameter D)
BALL_CAP = 2e-3
#: status codes of the loop that mean it ended on no state (max_iterations, nonfinite, stagnated;
#: the other codes of ``jones.RESULTS`` judge a state it ended on)
NEWTON_FAILURES = (1, 2, 3)


def traced_tolerances(maxit, rtol, atol):
    """``(maxit, rtol, atol)`` as arrays, not Python scalars: changing a tolerance must not
    recompile."""
    x = xp(maxit, rtol, atol)
    return x.asarray(maxit, x.int32), x.asarray(rtol, x.float64), x.asarray(atol, x.float64)


def max_abs(*arrays):
    """The largest absolute entry of the arrays (None entries skipped): a merit or a step length."""
    m = jnp.float64(0.0)
    for a in arrays:
        if a is not None:
            m = jnp.maximum(m, jnp.max(jnp.abs(a)))
    return m


def cap_step(d, cap):
    """``d`` scaled so that the max-norm of its last axis is at most ``cap``; non-finite entries 0."""
    n = jnp.max(jnp.abs(d), axis=-1, keepdims=True)
    d = jnp.where(n > cap, d * (cap / jnp.where(n > 0, n, 1.0)), d)
    return jnp.where(jnp.isfinite(d), d, 0.0)


def accept_step(c, first, finite, t, m, ss):
    """Whether the trial point at step length ``t`` (merit ``m``, simplified Newton correction
    length ``ss``) is accepted from the carry ``c`` (its merit ``m``, full-step length ``sn``,
    iteration ``it``): always the first evaluation; else a finite point that is one of the first
    :data:`FREE_STEPS` full steps without a 1e6-fold rise (far from the root, a static start at
    speed, the residual rises on the way), or lowers the residual, or shrinks the simplified
    correction (natural monotonicity, Deuflhard: the residual alone mixes ball and ring scales
    and rejects good full steps)."""
    free = (c["it"] < FREE_STEPS) & (t == 1.0) & (m <= 1e6 * c["m"])
    return first | (finite & (free | (m <= (1.0 - 1e-4 * t) * c["m"])
                              | (ss <= (1.0 - 0.25 * t) * c["sn"])))


def step_status(out, c, ok, t, first, finite, tol, maxit, ls_steps=LS_STEPS):
    """The bookkeeping of one damped Newton step: ``out`` (the accepted or kept iterate, with its
    merit ``m``) gets the next step length ``t`` (full after an accepted step, halved after a
    rejected one), the iteration and line-search counters ``it`` and ``ls`` from the previous
    carry ``c``, and ``code``: 0 converged (or stalled within 1e3 x tol), 1 out of iterations,
    2 a non-finite first step, 3 stalled, -1 go on."""
    out.update(t=jnp.where(ok, 1.0, 0.5 * t), it=jnp.where(ok, c["it"] + 1, c["it"]),
               ls=jnp.where(ok, 0, c["ls"] + 1))
    conv = out["m"] <= tol
    stalled = out["ls"] >= ls_steps
    code = jnp.where(first & ~finite, 2,
           jnp.where(conv | (stalled & (out["m"] <= 1e3 * tol)), 0,
           jnp.where(stalled, 3, jnp.where(out["it"] >= maxit, 1, -1))))
    out["code"] = code.astype(jnp.int32)
    return out


def better(retry, first):
    """Take the retry when it converged, or when it reached a state whose validity check names
    the cause (a shoulder, the bounds...) where the first attempt's Newton iteration failed."""
    retry, first = np.asarray(retry), np.asarray(first)
    newton = lambda c: np.isin(c, NEWTON_FAILURES)
    return (retry == 0) | (newton(first) & ~newton(retry))


def converged_only(retry, first):
    """Take the retry only where it converged."""
    return np.asarray(retry) == 0


def retry_failed(sol, run, take=better, bad=None):
    """``sol`` (a batched solution with ``result``) with its failed items solved again:
    ``run(idx)`` solves the items ``idx`` (a NumPy int array padded to a power of two with
    copies of the first failed item: one compiled shape for any number of failures) and
    ``take(retry_result, first_result)`` says, per failed item, whether its retry replaces it.
    ``bad``: the items to retry (a boolean mask; default: ``result != 0``).  Host orchestration
    (reads the codes): call it outside ``jit``."""
    mask = failed(np.asarray(sol.result)) if bad is None else np.asarray(bad)
    bad = np.flatnonzero(mask)
    if not bad.size:
        return sol
    n_pad = 1 << int(np.ceil(np.log2(bad.size)))
    idx = np.concatenate([bad, np.full(n_pad - bad.size, bad[0])])
    retry = run(idx)
    # the padding's rows are the first failed item solved again (the same values): merged with the
    # rest, one program per padded count instead of one small program per field and operation
    keep = np.asarray(take(np.asarray(retry.result), np.asarray(sol.result)[idx]))
    return _merge_retries(sol, retry, jnp.asarray(idx), jnp.asarray(keep))


def _merge(sol, retry, idx, keep):
    def merge(a, r):
        m = keep.reshape(keep.shape + (1,) * (r.ndim - 1))
        return a.at[idx].set(jnp.where(m, r, a[idx]))

    return jax.tree_util.tree_map(merge, sol, retry)


_merge_retries = jit(_merge)


def speed_stages(stage, carry, speed_steps, cold):
    """Run ``stage(carry, frac) -> (carry, (code, iterations))`` (int32 code and count) at the
    speed fractions k / speed_steps, k = 0 (``cold``: the rest state first) or 1, ..., speed_steps;
    returns ``(carry, the last stage's code, the iterations of all stages)``.

    A Python int ``speed_steps``: a ``lax.scan`` of that many stages.  A traced one (an integer
    array, as :func:`bearingsim.physics.jones.solve` passes it): one ``while`` loop for any count,
    so a solve and its 8-step retry are one compiled program, not two; the same fractions
    (k / speed_steps in float64) and the same stages, so the same iterations and codes and the
    same state to round-off (the two programs fuse differently: ~1e-16 of each quantity;
    tests/test_jones.py)."""
    if isinstance(speed_steps, (int, np.integer)):
        steps = int(speed_steps)
        fracs = ([0.0] if cold else []) + [k / steps for k in range(1, steps + 1)]
        carry, (codes, its) = jax.lax.scan(stage, carry, jnp.asarray(fracs))
        return carry, codes[-1], jnp.sum(its)
    n = jnp.asarray(speed_steps).astype(jnp.int32)

    def body(k, c):
        carry, _, total = c
        carry, (code, it) = stage(carry, k.astype(jnp.float64) / n.astype(jnp.float64))
        return carry, code, total + it.astype(total.dtype)

    start = jnp.int32(0 if cold else 1)
    # the count's dtype is that of jnp.sum of int32 iterations (the scan form's)
    return jax.lax.fori_loop(start, n + 1, body, (carry, jnp.int32(-1), jnp.sum(jnp.zeros(1, jnp.int32))))


# ------------------------------------------------------------ 2x2 solves (a ball's Newton step)
def solve2(J, r):
    """J^-1 r for 2x2 J (batched on leading axes), regularised where J is singular (a ball with
    no contact at rest: J = 0 and r = 0 give a zero step)."""
    a, b, c, d = J[..., 0, 0], J[..., 0, 1], J[..., 1, 0], J[..., 1, 1]
    scale = jnp.maximum(jnp.maximum(jnp.abs(a), jnp.abs(b)), jnp.maximum(jnp.abs(c), jnp.abs(d)))
    mu = 1e-13 * scale + 1e-300
    a, d = a + mu, d + mu
    det = a * d - b * c
    det = jnp.where(jnp.abs(det) > 1e-300, det, 1e-300)
    x0 = (d * r[..., 0] - b * r[..., 1]) / det
    x1 = (a * r[..., 1] - c * r[..., 0]) / det
    return jnp.stack([x0, x1], axis=-1)


def inverse2(J):
    """Regularised inverse of 2x2 matrices (batched on leading axes), as :func:`solve2`."""
    eye = jnp.eye(2)
    cols = [solve2(J, jnp.broadcast_to(eye[k], J.shape[:-1])) for k in range(2)]
    return jnp.stack(cols, axis=-1)
