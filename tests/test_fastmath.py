"""bearingsim.fastmath: the same values and derivatives as the plain expressions (to round-off),
finite at the guarded points, and derivatives without extra divisions (the reason it exists)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.extend.core import Literal

from bearingsim import fastmath as fm
from bearingsim.physics.balls import ball_equations
from bearingsim.physics.kinematics import Operation

RNG = np.random.default_rng(7)
X = jnp.asarray(RNG.uniform(0.1, 30.0, 64))
Y = jnp.asarray(RNG.uniform(-30.0, 30.0, 64))
T = jnp.asarray(RNG.standard_normal(64))
# 4 ulp of float64: the rewritten expressions round differently from the plain ones
TOL = 4 * np.finfo(float).eps


def _jvp(f, *xs, ts):
    return jax.jvp(f, xs, ts)


@pytest.mark.parametrize("name, fast, plain, args", [
    ("recip", fm.recip, lambda b: 1.0 / b, (X,)),
    ("pow15", fm.pow15, lambda x: x ** 1.5, (X,)),
    ("rsqrt", fm.rsqrt, lambda x: 1.0 / jnp.sqrt(x), (X,)),
    ("safe_div", fm.safe_div, lambda a, b: a / b, (Y, X)),
    ("norm2 length", lambda a, b: fm.norm2(a, b)[0], lambda a, b: jnp.hypot(a, b), (X, Y)),
    ("norm2 reciprocal", lambda a, b: fm.norm2(a, b)[1], lambda a, b: 1.0 / jnp.hypot(a, b), (X, Y)),
    ("clamp", lambda x: fm.clamp(x, -1.0, 1.0), lambda x: jnp.clip(x, -1.0, 1.0), (Y / 20.0,)),
    ("kernel", lambda x: fm.kernel(x * x * x), lambda x: x * x * x, (Y,)),
])
def test_values_and_derivatives_are_the_plain_ones(name, fast, plain, args):
    ts = tuple(T * (k + 1) for k in range(len(args)))
    v, d = _jvp(fast, *args, ts=ts)
    v0, d0 = _jvp(plain, *args, ts=ts)
    np.testing.assert_allclose(v, v0, rtol=TOL, atol=0, err_msg=name)
    np.testing.assert_allclose(d, d0, rtol=TOL, atol=TOL * float(jnp.max(jnp.abs(d0))), err_msg=name)


def test_guarded_points_are_finite():
    """safe_div and norm2 give 0 (value and derivative) where the plain expression divides by 0."""
    z = jnp.zeros(3)
    for f in (lambda a: fm.safe_div(a, z), lambda a: fm.norm2(a, z)[1], lambda a: fm.norm2(a, a)[0]):
        v, d = jax.jvp(f, (z,), (jnp.ones(3),))
        assert np.all(np.asarray(v) == 0.0) and np.all(np.isfinite(np.asarray(d)))


def _count(jaxpr, names, shape=None):
    """Equations of ``names`` in a jaxpr (and its sub-jaxprs); with ``shape``: only those with an
    output of that shape and, for a division, a divisor of that shape (x / 1000.0 or a division
    by one scalar parameter is a scaling, not a per-ball division)."""
    n = 0
    for e in jaxpr.eqns:
        if e.primitive.name in names:
            if shape is None:
                n += 1
            elif e.outvars[0].aval.shape == shape and not (e.primitive.name == "div" and (
                    isinstance(e.invars[1], Literal) or e.invars[1].aval.shape != shape)):
                n += 1
        for p in e.params.values():
            sub = getattr(p, "jaxpr", None)
            if sub is not None:
                n += _count(getattr(sub, "jaxpr", sub), names, shape)
    return n


def test_recip_derivative_has_no_division():
    jp = jax.make_jaxpr(lambda b, t: jax.jvp(fm.recip, (b,), (t,)))(X, T)
    assert _count(jp.jaxpr, {"div"}) == 1          # the reciprocal itself


def test_ball_equations_derivatives_add_no_divisions(b218):
    """Both directional derivatives of the balls' equations (what each Newton step of the time
    loop computes, element-wise over 9 balls) hold only the primal's expensive operations: 3
    divisions (two distances' reciprocals, the orbital-speed denominator) plus 1 for the carried
    ball's speed ratio, 2 square roots (the distances) + 2 (delta**1.5), 1 reciprocal square
    root (the pitch angle), each traced once per derivative direction (XLA merges the copies);
    before fastmath the same jaxpr held 33 per-ball divisions per direction."""
    from bearingsim.physics.hertz import stiffness_curve

    op = Operation(1000.0)
    curve = stiffness_curve(b218)
    Z = 9
    v = jnp.stack([jnp.full(Z, 10.0), jnp.full(Z, 300.0), jnp.full(Z, 5.0), jnp.full(Z, 340.0)])

    def f(v):
        return ball_equations(b218, op, curve, v, 0.0, 0.0, jnp.full(Z, 900.0))[0]

    def both(v):
        e1, e2 = jnp.zeros((4, 1)).at[0].set(1.0), jnp.zeros((4, 1)).at[1].set(1.0)
        return jax.jvp(f, (v,), (e1 + 0 * v,)), jax.jvp(f, (v,), (e2 + 0 * v,))

    jp = jax.make_jaxpr(both)(v)
    assert _count(jp.jaxpr, {"div"}, (Z,)) <= 2 * 4
    assert _count(jp.jaxpr, {"sqrt", "rsqrt"}, (Z,)) <= 2 * 5
    assert _count(jp.jaxpr, {"pow", "atan2", "sin", "cos", "exp", "log", "cbrt"}, (Z,)) == 0


def _chain(x):
    """A 24-multiplication Horner chain (what K(alpha) is in the ball equations)."""
    r = jnp.ones_like(x)
    for k in range(12):
        r = r * x + (0.5 + 0.1 * k)
    return r


def _multiplies(f, x):
    """Multiplications in XLA's optimised program of ``f`` for this CPU (fusions included)."""
    txt = jax.jit(f).lower(x).compile().as_text()
    return sum(" multiply(" in line for line in txt.splitlines())


def test_kernel_computes_a_chain_once_for_every_consumer():
    """fastmath.kernel: a chain read by three consumers is computed once, where XLA's CPU backend
    otherwise copies it into each (the reason it exists: the dynamics' time step reads K(alpha)
    in its loads and both Newton tangents; 128 four-class items ran 7 % faster with it).  Values
    and reverse derivatives those of the plain chain to round-off (the kernel itself is exact;
    LLVM may contract a multiply-add differently in another kernel layout: seen at -O0).  If this fails because the
    plain chain is no longer copied, XLA changed and kernel() is no longer needed."""
    x = jnp.linspace(-0.9, 0.9, 64)

    def plain(x):
        p = _chain(x)
        return p * 2.0 - x, p * 3.0 + x, p * p

    def kept(x):
        p = fm.kernel(_chain(x))
        return p * 2.0 - x, p * 3.0 + x, p * p

    for a, b in zip(jax.jit(plain)(x), jax.jit(kept)(x)):
        np.testing.assert_allclose(b, a, rtol=TOL, atol=0)
    n_plain, n_kept = _multiplies(plain, x), _multiplies(kept, x)
    assert n_plain >= 3 * 12 and n_kept <= 12 + 6, (n_plain, n_kept)
    g = jax.grad(lambda x: jnp.sum(kept(x)[2]))(x)
    np.testing.assert_allclose(g, jax.grad(lambda x: jnp.sum(plain(x)[2]))(x), rtol=TOL, atol=0)
