"""Hertz point contact (docs/model.md section 3), pure JAX and differentiable.

Complete elliptic integrals come from the arithmetic-geometric mean (quadratic
convergence, exact to machine precision in a fixed number of steps); the
ellipticity kappa = a/b solves the curvature-difference relation by Newton in
log(kappa) from the Brewe-Hamrock start.  Unrolled fixed iterations keep
everything jit/vmap/grad friendly.
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np
import jax.numpy as jnp
from jax import lax

from ..errors import InputError
from ..fastmath import clamp
from ..programs import jit

_AGM_STEPS = 12      # m <= 1 - 1e-8 converges to 1 ulp in <= 7 steps
_KAPPA_NEWTON = 8    # Brewe-Hamrock start is within ~3 %; Newton is quadratic


def _agm(m):
    a = jnp.ones_like(m)
    b = jnp.sqrt(1.0 - m)

    def step(_, c):
        a, b, w, s = c
        cn = 0.5 * (a - b)
        w = 2.0 * w
        return 0.5 * (a + b), jnp.sqrt(a * b), w, s + w * cn * cn

    a, b, w, s = lax.fori_loop(0, _AGM_STEPS, step, (a, b, 0.5 * jnp.ones_like(m), 0.5 * m))
    K = jnp.pi / (2.0 * a)
    return K, K * (1.0 - s)


@jax.custom_jvp
def ellipk_ellipe(m):
    """Complete elliptic integrals K(m), E(m) of parameter m (scipy convention), 0 <= m < 1.

    Arithmetic-geometric mean: K = pi / (2 AGM(1, sqrt(1-m))),
    E = K (1 - sum_n 2^(n-1) c_n^2) with c_0^2 = m.  Derivatives from the closed forms
    dK/dm = (E - (1-m) K) / (2 m (1-m)), dE/dm = (E - K) / (2 m).
    """
    return _agm(jnp.asarray(m, dtype=jnp.float64))


@ellipk_ellipe.defjvp
def _ellipk_ellipe_jvp(primals, tangents):
    (m,), (dm,) = primals, tangents
    m = jnp.asarray(m, dtype=jnp.float64)
    K, E = _agm(m)
    small = jnp.abs(m) < 1e-8
    ms = jnp.where(small, 0.5, m)
    dK = jnp.where(small, jnp.pi / 8.0, (E - (1.0 - ms) * K) / (2.0 * ms * (1.0 - ms)))
    dE = jnp.where(small, -jnp.pi / 8.0, (E - K) / (2.0 * ms))
    return (K, E), (dK * dm, dE * dm)


def _curvature_difference_of_kappa(kappa):
    """F(rho) as a function of the ellipticity kappa (> 1)."""
    m = 1.0 - 1.0 / kappa ** 2
    K, E = ellipk_ellipe(m)
    k2 = kappa ** 2
    return ((k2 + 1.0) * E - 2.0 * K) / ((k2 - 1.0) * E)


def brewe_hamrock(F):
    """Brewe-Hamrock (1977) approximations: (kappa, K, E) from F(rho).  Optional, never the default."""
    ratio = (1.0 + F) / (1.0 - F)   # R_y / R_x
    kappa = 1.0339 * ratio ** 0.636
    E = 1.0003 + 0.5968 / ratio
    K = 1.5277 + 0.6023 * jnp.log(ratio)
    return kappa, K, E


def _F_of_t(t):
    return _curvature_difference_of_kappa(jnp.exp(t))


@jax.custom_jvp
def _log_kappa(F):
    """ln(kappa) solving F(rho) = F(kappa), Newton from Brewe-Hamrock (F > 0)."""
    t0 = jnp.log(brewe_hamrock(F)[0])

    def step(_, t):
        r, dr = jax.jvp(_F_of_t, (t,), (jnp.ones_like(t),))
        return t - (r - F) / dr

    return lax.fori_loop(0, _KAPPA_NEWTON, step, t0)


@_log_kappa.defjvp
def _log_kappa_jvp(primals, tangents):
    (F,), (dF,) = primals, tangents
    t = _log_kappa(F)
    _, dFdt = jax.jvp(_F_of_t, (t,), (jnp.ones_like(t),))
    return t, dF / dFdt


def _ellipticity_exact(F):
    tiny = F < 1e-7                       # circular contact: kappa = 1, K = E = pi/2
    Fs = jnp.where(tiny, 0.5, F)
    kappa = jnp.exp(_log_kappa(Fs))
    K, E = ellipk_ellipe(1.0 - 1.0 / kappa ** 2)
    half_pi = jnp.pi / 2.0
    return (jnp.where(tiny, 1.0, kappa), jnp.where(tiny, half_pi, K), jnp.where(tiny, half_pi, E))


def ellipticity(F, method: str = "exact"):
    """Ellipticity kappa = a/b and elliptic integrals (K, E) for curvature difference F(rho).

    ``method="exact"`` (default) solves F(rho) = [(k^2+1)E - 2K]/[(k^2-1)E] to machine
    precision (derivative by the implicit function theorem); ``"brewe-hamrock"`` uses the
    closed-form approximations.
    """
    F = jnp.asarray(F, dtype=jnp.float64)
    if method == "brewe-hamrock":
        return brewe_hamrock(F)
    if method != "exact":
        raise InputError(f"ellipticity method must be 'exact' or 'brewe-hamrock', got {method!r}",
                         "'exact' (default) solves to machine precision; 'brewe-hamrock' uses the "
                         "closed-form approximations")
    return _ellipticity_exact(F)


class HertzContact(NamedTuple):
    """Hertz constants of one ball-raceway contact (SI)."""

    sum_rho: jnp.ndarray      # curvature sum (1/m)
    F_rho: jnp.ndarray        # curvature difference (-)
    kappa: jnp.ndarray        # ellipticity a/b (-)
    K_ell: jnp.ndarray        # complete elliptic integral of the first kind
    E_ell: jnp.ndarray        # complete elliptic integral of the second kind
    K: jnp.ndarray            # load-deflection constant, Q = K delta^1.5 (N/m^1.5)


def curvature(D, f, gamma, inner: bool):
    """Curvature sum (1/m) and difference (-) of a ball-raceway contact, gamma = D cos(alpha)/d_m."""
    conf = 2.0 * gamma / (1.0 - gamma) if inner else -2.0 * gamma / (1.0 + gamma)
    sum_rho = (4.0 - 1.0 / f + conf) / D
    F = (1.0 / f + conf) / (D * sum_rho)
    return sum_rho, F


def contact_constant(kappa, K_ell, E_ell, sum_rho, E_eff):
    """K = pi kappa E' sqrt(2 E R / (9 K^3)) with R = 1/sum_rho (N/m^1.5)."""
    R = 1.0 / sum_rho
    return jnp.pi * kappa * E_eff * jnp.sqrt(2.0 * E_ell * R / (9.0 * K_ell ** 3))


def hertz_contact(bearing, alpha, inner: bool, method: str = "exact") -> HertzContact:
    """Hertz constants of the inner (``inner=True``) or outer contact at contact angle ``alpha`` (rad).

    Evaluated at the contact's own angle (gamma = D cos(alpha)/d_m), as docs/model.md requires.
    """
    D = bearing.ball_diameter
    gamma = D * jnp.cos(alpha) / bearing.pitch_diameter
    f = bearing.f_inner if inner else bearing.f_outer
    sum_rho, F = curvature(D, f, gamma, inner)
    kappa, K_ell, E_ell = ellipticity(F, method)
    K = contact_constant(kappa, K_ell, E_ell, sum_rho, bearing.effective_modulus)
    return HertzContact(sum_rho, F, kappa, K_ell, E_ell, K)


def semi_axes(contact: HertzContact, Q, E_eff):
    """Contact semi-axes a (major), b (minor) in m and peak pressure p_max in Pa for load Q (N)."""
    Qp = jnp.maximum(Q, 0.0)
    R = 1.0 / contact.sum_rho
    kap, E = contact.kappa, contact.E_ell
    a = (6.0 * kap ** 2 * E * Qp * R / (jnp.pi * E_eff)) ** (1.0 / 3.0)
    b = (6.0 * E * Qp * R / (jnp.pi * kap * E_eff)) ** (1.0 / 3.0)
    ab = a * b
    p_max = jnp.where(ab > 0, 3.0 * Qp / (2.0 * jnp.pi * jnp.where(ab > 0, ab, 1.0)), 0.0)
    return a, b, p_max


def dimensionless_hertz(F, method: str = "exact"):
    """Harris Table 6.1 dimensionless parameters (a*, b*, delta*) for curvature difference F(rho)."""
    kappa, K, E = ellipticity(F, method)
    a_star = (2.0 * kappa ** 2 * E / jnp.pi) ** (1.0 / 3.0)
    b_star = (2.0 * E / (jnp.pi * kappa)) ** (1.0 / 3.0)
    d_star = (2.0 * K / jnp.pi) * (jnp.pi / (2.0 * kappa ** 2 * E)) ** (1.0 / 3.0)
    return a_star, b_star, d_star


# ------------------------------------------------------------------------------------------
# K(alpha) as a Chebyshev series in cos(alpha) on [-1, 1] (every angle), built once per
# solve from the exact Hertz solution at 16 Chebyshev nodes.  The Jones residual evaluates K at
# each contact's angle many times; the series reproduces the exact K to ~1e-14 relative (tested)
# at a fraction of the cost and compile time of the nested elliptic-integral iterations.
# ------------------------------------------------------------------------------------------
_CHEB_N = 16
_CHEB_THETA = np.pi * (np.arange(_CHEB_N) + 0.5) / _CHEB_N
_CHEB_NODES = np.cos(_CHEB_THETA)                                     # cos(alpha) at the nodes
_CHEB_T = (2.0 / _CHEB_N) * np.cos(np.outer(np.arange(_CHEB_N), _CHEB_THETA))
_CHEB_T[0] *= 0.5
#: Chebyshev -> power-series coefficients (a = _CHEB_TO_POWER @ c): K's series decay ~7x per
#: order, so the power form is as well conditioned as the Chebyshev one (Horner vs Clenshaw
#: 2e-16, measured) and costs one multiply-add per term in the ball kernels
_CHEB_TO_POWER = np.zeros((_CHEB_N, _CHEB_N))
for _k in range(_CHEB_N):
    _p = np.polynomial.chebyshev.cheb2poly(np.eye(_CHEB_N)[_k])
    _CHEB_TO_POWER[:_p.size, _k] = _p


class StiffnessCurve(NamedTuple):
    """Chebyshev coefficients in cos(alpha) on [-1, 1] of the inner and outer contacts' K
    (Q = K delta^1.5) and of the contact-ellipse coefficients c_a, c_b (a = c_a Q^(1/3),
    b = c_b Q^(1/3)); ``inner_power``/``outer_power``: K's series as power series in
    cos(alpha) (:func:`power_eval`, the ball kernels' form)."""

    inner: jnp.ndarray
    outer: jnp.ndarray
    inner_a: jnp.ndarray
    inner_b: jnp.ndarray
    outer_a: jnp.ndarray
    outer_b: jnp.ndarray
    inner_power: jnp.ndarray
    outer_power: jnp.ndarray


def _ellipse_coefficients(contact: HertzContact, E_eff):
    a, b, _ = semi_axes(contact, jnp.ones_like(contact.K), E_eff)
    return a, b


def _stiffness_curve(bearing, method: str = "exact") -> StiffnessCurve:
    """The contact constants of both raceways at every angle, as Chebyshev series built once
    from the exact Hertz solution at 16 nodes (reproduce it to ~1e-13, tested)."""
    alpha = jnp.arccos(jnp.asarray(_CHEB_NODES))
    T = jnp.asarray(_CHEB_T)
    ci = hertz_contact(bearing, alpha, True, method)
    co = hertz_contact(bearing, alpha, False, method)
    Ep = bearing.effective_modulus
    ai, bi = _ellipse_coefficients(ci, Ep)
    ao, bo = _ellipse_coefficients(co, Ep)
    Ki, Ko = T @ ci.K, T @ co.K
    P = jnp.asarray(_CHEB_TO_POWER)
    return StiffnessCurve(Ki, Ko, T @ ai, T @ bi, T @ ao, T @ bo, P @ Ki, P @ Ko)


#: :func:`_stiffness_curve` compiled once per bearing structure and method (called eagerly, its
#: AGM and Newton loops would compile again on every call)
stiffness_curve = jit(_stiffness_curve)


def contact_ellipse(curve: StiffnessCurve, cos_alpha, Q, inner: bool):
    """Semi-axes a, b (m) and peak pressure p_max (Pa) of a contact at angle alpha carrying Q,
    from the series (no elliptic-integral iterations)."""
    ca = chebyshev_eval(curve.inner_a if inner else curve.outer_a, cos_alpha)
    cb = chebyshev_eval(curve.inner_b if inner else curve.outer_b, cos_alpha)
    q3 = jnp.cbrt(jnp.maximum(Q, 0.0))
    a, b = ca * q3, cb * q3
    ab = a * b
    p = jnp.where(ab > 0, 3.0 * jnp.maximum(Q, 0.0) / (2.0 * jnp.pi * jnp.where(ab > 0, ab, 1.0)), 0.0)
    return a, b, p


def power_eval(coeffs, cos_alpha):
    """K at contact angle alpha from its cosine: a power series (Horner), e.g.
    ``StiffnessCurve.inner_power``; the same values as :func:`chebyshev_eval` of the Chebyshev
    form to ~1e-16 relative."""
    x = clamp(cos_alpha, -1.0, 1.0)
    r = coeffs[-1] + jnp.zeros_like(x)
    for k in range(coeffs.shape[-1] - 2, -1, -1):
        r = r * x + coeffs[k]
    return r


def chebyshev_eval(coeffs, cos_alpha):
    """K at contact angle alpha from its cosine (Clenshaw)."""
    x = jnp.clip(cos_alpha, -1.0, 1.0)
    b1 = jnp.zeros_like(x)
    b2 = jnp.zeros_like(x)
    for k in range(_CHEB_N - 1, 0, -1):
        b1, b2 = 2.0 * x * b1 - b2 + coeffs[k], b1
    return x * b1 - b2 + coeffs[0]
