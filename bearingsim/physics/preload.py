"""Preload of a bearing at standstill (docs/model.md sections 4 and 10): the thrust at an axial
approach and its inverse, the rigid-preload offset (the closed form at omega = 0), the static
axial capacity C_0a (ISO 76: 4.2 GPa) and the preload classes as shares of it.  Used by the set
model (:mod:`bearingsim.physics.shaft`, which offers these names too) and its reports.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import lax

from ..errors import InputError
from ..hostarrays import f64
from ..programs import jit
from .hertz import contact_ellipse, power_eval, stiffness_curve
from .jones import initial_displacement

__all__ = ["thrust_at_approach", "preload_offset", "PRELOAD_CLASSES", "STATIC_PRESSURE", "static_axial_capacity",
           "preload_class_force", "PRELOAD_NEWTON"]

#: Newton steps of :func:`preload_offset` (a fixed count: traced once)
PRELOAD_NEWTON = 40


def thrust_at_approach(bearing, approach, curve=None):
    """The thrust (N) one bearing carries at axial approach ``approach`` (m) at omega = 0
    (docs/model.md section 4 closed form: Z K_n (L - BD)^1.5 sin alpha, K at the loaded contact angle)."""
    curve = stiffness_curve(bearing) if curve is None else curve
    BD = bearing.A
    a0 = bearing.free_contact_angle
    A1 = BD * jnp.sin(a0) + approach
    A2 = BD * jnp.cos(a0)
    L = jnp.sqrt(A1 * A1 + A2 * A2)
    c, s = A2 / L, A1 / L
    Ki, Ko = power_eval(curve.inner_power, c), power_eval(curve.outer_power, c)
    Kn = (Ki ** (-2.0 / 3.0) + Ko ** (-2.0 / 3.0)) ** (-1.5)
    dn = jnp.maximum(L - BD, 0.0)
    return bearing.n_balls * Kn * dn * jnp.sqrt(dn) * s


def preload_offset(bearing, preload, curve=None):
    """The axial approach e (m) at which one bearing carries the thrust ``preload`` (N) at
    omega = 0: the rigid-preload offset of docs/model.md section 10 (0 for a preload <= 0).
    One kept program (its Newton loop eager was traced and compiled again at every call)."""
    curve = stiffness_curve(bearing) if curve is None else curve
    return _preload_offset_jit(bearing, f64(preload), curve)


def _preload_offset(bearing, preload, curve):
    P = jnp.maximum(jnp.asarray(preload, jnp.float64), 0.0)
    P23 = jnp.cbrt(P) ** 2
    start = initial_displacement(bearing, jnp.stack([0.0, 0.0, jnp.where(P > 0, P, 1.0), 0.0, 0.0]),
                                 curve)[2]
    BD = bearing.A
    a0 = bearing.free_contact_angle
    lo = jnp.sqrt(jnp.maximum(BD ** 2 - (BD * jnp.cos(a0)) ** 2, 0.0)) * 0.0 - BD * jnp.sin(a0)

    def g(x):
        return jnp.cbrt(thrust_at_approach(bearing, x, curve)) ** 2 - P23

    def body(_, x):
        v, d = jax.jvp(g, (x,), (jnp.ones_like(x),))
        step = jnp.where(d > 0, v / jnp.where(d > 0, d, 1.0), 0.0)
        xn = x - step
        # stay where the balls touch (thrust > 0): halfway back towards the last point
        return jnp.where(xn > lo, xn, 0.5 * (x + lo))

    x = lax.fori_loop(0, PRELOAD_NEWTON, body, start)
    return jnp.where(P > 0, x, 0.0)


_preload_offset_jit = jit(_preload_offset)


#: preload classes as fractions of the static axial capacity C_0a (:func:`static_axial_capacity`):
#: the 1 : 2 : 4 steps of the light / medium / heavy classes of spindle-bearing catalogues, scaled
#: so that the Harris 218 (40 deg, C_0a = 436 kN in this model) gets 1.3 / 2.6 / 5.2 kN, the order
#: of the catalogue classes of 40 deg bearings of that size (a project choice, not a standard)
PRELOAD_CLASSES = {"light": 0.003, "medium": 0.006, "heavy": 0.012}
#: ISO 76 static-capacity contact pressure of ball bearings (Pa)
STATIC_PRESSURE = 4.2e9


def static_axial_capacity(bearing, curve=None, pressure=STATIC_PRESSURE):
    """C_0a (N): the thrust at which the peak contact pressure at omega = 0 reaches ``pressure``
    (ISO 76: 4.2 GPa for ball bearings) in the docs/model.md section 4 closed form (the larger of the inner
    and outer contacts' p_max; bisection on the axial approach).  One kept program."""
    curve = stiffness_curve(bearing) if curve is None else curve
    return _capacity_jit(bearing, curve, f64(pressure))


def _static_axial_capacity(bearing, curve, pressure):
    BD = bearing.A
    a0 = bearing.free_contact_angle

    def pmax(x):
        F = thrust_at_approach(bearing, x, curve)
        A1 = BD * jnp.sin(a0) + x
        L = jnp.sqrt(A1 ** 2 + (BD * jnp.cos(a0)) ** 2)
        s, c = A1 / L, BD * jnp.cos(a0) / L
        Q = F / (bearing.n_balls * jnp.maximum(s, 1e-12))
        return jnp.maximum(contact_ellipse(curve, c, Q, True)[2], contact_ellipse(curve, c, Q, False)[2])

    def body(_, lohi):
        lo, hi = lohi
        mid = 0.5 * (lo + hi)
        big = pmax(mid) > pressure
        return jnp.where(big, lo, mid), jnp.where(big, mid, hi)

    lo, hi = lax.fori_loop(0, 80, body, (jnp.float64(0.0), 0.02 * bearing.ball_diameter))
    return thrust_at_approach(bearing, 0.5 * (lo + hi), curve)


_capacity_jit = jit(_static_axial_capacity)


def preload_class_force(bearing, name: str):
    """The preload (N) of a class "light" / "medium" / "heavy": :data:`PRELOAD_CLASSES` x C_0a."""
    key = str(name).lower()
    if key not in PRELOAD_CLASSES:
        raise InputError(f"unknown preload class {name!r}; known: {', '.join(PRELOAD_CLASSES)}")
    return float(PRELOAD_CLASSES[key] * static_axial_capacity(bearing))
