"""NumPy for concrete values, JAX for traced ones: the host side of the user's nouns.

A ``jax.numpy`` operation on a concrete array outside a compiled program is a program of its own:
traced, lowered, then compiled or read from the compilation cache, once per shape and process.
Each costs ~25-45 ms on a 2-core CPU (2026-12-07, jax 0.10.2), where NumPy takes microseconds;
a ``bearingsim static`` call made 20 of them around its one solve (making its bearing, operation
and loads, then reading the solution's pressures, verdict and limits), and the test suite ~2400.
The constructors of the bearing, operation, loads and defects, and the properties a user reads
off a solution, go through :func:`f64` / :func:`xp`: the same float64 arithmetic in the same
order (the same values), in NumPy where nothing is traced and in JAX inside ``jit`` / ``vmap`` /
``grad``.  The compiled programs take NumPy and JAX arrays alike (the same abstract values, the
same kept programs).
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["traced", "xp", "f64", "opt_f64", "host"]


def traced(*values) -> bool:
    """True where any leaf of ``values`` is a JAX tracer (inside jit, vmap, grad)."""
    return any(isinstance(v, jax.core.Tracer) for v in jax.tree_util.tree_leaves(values))


def xp(*values):
    """The array module for ``values``: :mod:`jax.numpy` where one is traced, else :mod:`numpy`."""
    return jnp if traced(*values) else np


def f64(x):
    """``x`` as a float64 array: a NumPy array where it is concrete, a JAX array where traced."""
    return jnp.asarray(x, dtype=jnp.float64) if traced(x) else np.asarray(x, dtype=np.float64)


def opt_f64(x):
    """:func:`f64`, or None for None."""
    return None if x is None else f64(x)


def host(x):
    """A concrete JAX array as a NumPy array (its element-wise operators then run in NumPy); a
    tracer or anything else as it is."""
    if isinstance(x, jax.Array) and not isinstance(x, jax.core.Tracer):
        return np.asarray(x)
    return x
