"""The defect frequencies of a run at its quasi-static state (docs/model.md section 8), written once
in JAX: :func:`state_frequencies` (one state; jit/vmap, inside a data set chunk's program) and
:func:`characteristic_frequencies` (its host values for one state or a batch)."""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from ..physics.kinematics import DefectFrequencies, defect_frequencies
from ..programs import jit

__all__ = ["state_frequencies", "characteristic_frequencies", "spin_ratio"]


def state_frequencies(bearing, speed, sol):
    """(:class:`DefectFrequencies` in Hz, mean loaded contact angle (rad), spin ratio) of one quasi-static state
    ``sol`` at shaft ``speed`` (rad/s): shaft = n/60; FTF = omega_c / 2 pi from the state's cage
    speed, BPFO = Z FTF; BPFI and BSF (once per ball revolution) from the docs/model.md section 8
    formulas at the mean loaded contact angle (mean of (alpha_i + alpha_o)/2 over the balls with
    Q_i > 1 % of the largest; every ball when none is loaded); the spin ratio omega_R / omega =
    2 pi BSF / omega at that angle (0 where it is not finite).  jit/vmap."""
    Qi = sol.Q_inner
    top = jnp.max(Qi)
    loaded = jnp.where(top > 0, Qi > 0.01 * top, True)
    alpha = 0.5 * (sol.alpha_inner + sol.alpha_outer)
    a_m = jnp.sum(alpha * loaded) / jnp.sum(loaded)
    shaft = speed / (2 * np.pi)
    f = defect_frequencies(bearing, shaft, a_m)
    ftf = sol.cage_speed / (2 * np.pi)
    k = defect_frequencies(bearing, 1.0, a_m).bsf
    k = jnp.where(jnp.isfinite(k), k, 0.0)
    return DefectFrequencies(shaft, ftf, bearing.n_balls * ftf, f.bpfi, f.bsf), a_m, k


def characteristic_frequencies(bearing, op, sol):
    """:func:`state_frequencies` on the host: (:class:`DefectFrequencies`, mean loaded contact
    angle in rad), floats for one state, arrays for a batch (``sol`` and ``op.speed`` with a leading item axis)."""
    Qi = np.shape(sol.Q_inner)
    if len(Qi) == 1:
        f, a_m = jax.device_get(_frequencies_jit(bearing, np.asarray(op.speed, np.float64), sol))
        return DefectFrequencies(*(float(v) for v in f)), float(a_m)
    speed = np.broadcast_to(np.asarray(op.speed, np.float64), Qi[:1])
    f, a_m = jax.device_get(_frequencies_batch_jit(bearing, speed, sol))
    return DefectFrequencies(*(np.asarray(v, float) for v in f)), np.asarray(a_m, float)


def _frequencies(bearing, speed, sol):
    f, a_m, _ = state_frequencies(bearing, speed, sol)
    return f, a_m


def _frequencies_batch(bearing, speed, sol):
    return jax.vmap(lambda w, s: _frequencies(bearing, w, s))(speed, sol)


#: kept programs (bearingsim.programs): a host call is one loaded program, not ~20 eager operations
_frequencies_jit = jit(_frequencies)
_frequencies_batch_jit = jit(_frequencies_batch)


def _spin_ratio(bearing, contact_angle):
    r = defect_frequencies(bearing, 1.0, contact_angle).bsf
    return jnp.where(jnp.isfinite(r), r, 0.0)


_spin_ratio_jit = jit(_spin_ratio)


def spin_ratio(bearing, contact_angle):
    """omega_R / omega: a ball's spin speed relative to the cage per unit shaft speed (2 pi BSF
    / omega, docs/model.md section 8) at the mean loaded contact angle (rad; a float or an array)."""
    r = np.asarray(_spin_ratio_jit(bearing, np.asarray(contact_angle, np.float64)), float)
    return float(r) if r.ndim == 0 else r
