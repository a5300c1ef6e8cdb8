"""Element-wise arithmetic whose derivatives cost no extra divisions (the ball equations' inner
loop, differentiated in every Newton step).

JAX differentiates ``a / b`` into ``t_a / b - t_b a / b**2``: two more divisions per tangent
direction, and XLA's CPU backend does not duplicate a division into several consumers, so every
one of them becomes its own compiled kernel.  In the dynamics' time step (a few hundred
element-wise operations over 9 balls, run 48 000 times per simulated second) the step time is
the number of kernels (~0.15 us each), not arithmetic.  Here a quotient is ``a * recip(b)`` with
``recip``'s derivative ``-t r**2`` built from the one reciprocal ``r`` (multiplications fuse
freely); a length and its reciprocal come from one square root and one division
(:func:`norm2`), ``x**1.5`` from
one ``sqrt`` whose derivative reuses it (:func:`pow15`); ``clamp`` has the derivative of a
select instead of ``jnp.clip``'s tie-splitting rule (two selects and a division).  The values
are those of the plain expressions to round-off.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import lax

__all__ = ["recip", "rsqrt", "safe_div", "safe_recip", "norm2", "pow15", "clamp", "kernel"]


@jax.custom_jvp
def recip(b):
    """1 / b, whose derivative is -t / b**2 computed from the one reciprocal."""
    return 1.0 / b


@recip.defjvp
def _recip_jvp(primals, tangents):
    (b,), (t,) = primals, tangents
    r = 1.0 / b
    return r, -t * r * r


def safe_recip(b):
    """1 / b where b > 0, else 0 (finite derivatives everywhere)."""
    ok = b > 0.0
    return jnp.where(ok, recip(jnp.where(ok, b, 1.0)), 0.0)


def safe_div(a, b):
    """a / b where b > 0, else 0 (finite derivatives everywhere)."""
    return a * safe_recip(b)


def clamp(x, lo, hi):
    """x limited to [lo, hi]; derivative 1 inside, 0 where limited (a select)."""
    return jnp.where(x > hi, hi, jnp.where(x < lo, lo, x))


@jax.custom_jvp
def rsqrt(x):
    """1 / sqrt(x), whose derivative -t r**3 / 2 is computed from r (no division)."""
    return lax.rsqrt(x)


@rsqrt.defjvp
def _rsqrt_jvp(primals, tangents):
    (x,), (t,) = primals, tangents
    r = lax.rsqrt(x)
    return r, (-0.5 * t) * (r * r * r)


@jax.custom_jvp
def _hypot(a, b):
    L = jnp.sqrt(a * a + b * b)
    return L, 1.0 / L


@_hypot.defjvp
def _hypot_jvp(primals, tangents):
    (a, b), (ta, tb) = primals, tangents
    L = jnp.sqrt(a * a + b * b)
    r = 1.0 / L
    dL = (a * ta + b * tb) * r
    return (L, r), (dL, -dL * r * r)


def norm2(a, b):
    """(sqrt(a**2 + b**2), its reciprocal), both 0 at the origin: one square root and one
    division, derivatives from them by multiplications."""
    ok = (a * a + b * b) > 0.0
    L, r = _hypot(jnp.where(ok, a, 1.0), jnp.where(ok, b, 0.0))
    return jnp.where(ok, L, 0.0), jnp.where(ok, r, 0.0)


@jax.custom_jvp
def pow15(x):
    """x**1.5 for x >= 0 as x sqrt(x); derivative 1.5 sqrt(x) t (no division)."""
    return x * jnp.sqrt(x)


@pow15.defjvp
def _pow15_jvp(primals, tangents):
    (x,), (t,) = primals, tangents
    r = jnp.sqrt(x)
    return x * r, (1.5 * r) * t


@jax.custom_jvp
def kernel(x):
    """``x`` itself (exactly, for finite ``x``), computed once in a kernel of its own.

    XLA's CPU backend copies a chain of cheap element-wise operations (multiplications,
    additions, selects) into every kernel that consumes it, and recomputes it there; only an
    expensive operation (a division, a square root) ends a kernel that several consumers read.
    So a long chain with several consumers (K(alpha)'s 16-term Horner, read by the loads and by
    both tangent directions of a Newton step) runs once per consumer.  This ends the chain in a
    division by ``x * 0 + 1`` (exactly 1 for finite ``x``; XLA folds neither ``x * 0`` nor the
    quotient for floating point); the tangent is divided by the same one (a kernel of its own
    too, and linear in the tangent: reverse mode transposes it)."""
    return x / (x * 0.0 + 1.0)


@kernel.defjvp
def _kernel_jvp(primals, tangents):
    (x,), (t,) = primals, tangents
    one = x * 0.0 + 1.0
    return x / one, t / one
