"""Hertz point contact (docs/model.md section 3) against scipy, closed forms and its own equation
(the literature tables are in tests/validation/test_literature.py)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.special as sp

import bearingsim as bs
from bearingsim.physics import hertz

def test_elliptic_integrals_match_scipy_to_1e12():
    m = np.concatenate([[0.0, 1e-10, 1e-6], np.linspace(0.01, 0.99, 50), 1 - np.logspace(-3, -9, 7)])
    K, E = bs.ellipk_ellipe(jnp.asarray(m))
    assert np.max(np.abs(np.asarray(K) / sp.ellipk(m) - 1)) < 1e-12
    assert np.max(np.abs(np.asarray(E) / sp.ellipe(m) - 1)) < 1e-12


def test_elliptic_integral_derivatives_match_closed_form():
    m = np.array([1e-3, 0.2, 0.7, 0.999])
    dK = jax.vmap(jax.grad(lambda x: bs.ellipk_ellipe(x)[0]))(jnp.asarray(m))
    dE = jax.vmap(jax.grad(lambda x: bs.ellipk_ellipe(x)[1]))(jnp.asarray(m))
    h = 1e-6 * np.minimum(m, 1 - m)
    fdK = (sp.ellipk(m + h) - sp.ellipk(m - h)) / (2 * h)
    fdE = (sp.ellipe(m + h) - sp.ellipe(m - h)) / (2 * h)
    np.testing.assert_allclose(dK, fdK, rtol=1e-6)
    np.testing.assert_allclose(dE, fdE, rtol=1e-6)


def test_ellipticity_solves_its_equation_exactly():
    F = jnp.linspace(0.05, 0.9999, 40)
    kappa, K, E = bs.ellipticity(F)
    k2 = kappa ** 2
    np.testing.assert_allclose(((k2 + 1) * E - 2 * K) / ((k2 - 1) * E), F, rtol=0, atol=1e-13)
    np.testing.assert_allclose(K, sp.ellipk(1 - 1 / np.asarray(k2)), rtol=1e-12)


def test_brewe_hamrock_is_an_option_close_to_exact():
    F = jnp.array([0.9041, 0.9262])
    ke, Ke, Ee = bs.ellipticity(F)
    kb, Kb, Eb = bs.ellipticity(F, method="brewe-hamrock")
    assert np.all(np.abs(np.asarray(kb / ke) - 1) < 0.03)
    assert np.all(np.abs(np.asarray(Kb / Ke) - 1) < 0.03)
    assert not np.allclose(kb, ke, rtol=1e-6)          # really a different model
    with pytest.raises(ValueError):
        bs.ellipticity(0.9, method="nonsense")


def test_chebyshev_stiffness_curve_reproduces_exact_K(b218):
    """Both forms of the series -- Chebyshev (Clenshaw) and the power series the ball kernels
    evaluate (Horner) -- reproduce the exact Hertz K to 1e-13 at 721 angles."""
    curve = hertz.stiffness_curve(b218)
    a = jnp.linspace(-np.pi, np.pi, 721)
    for inner, coeffs, power in ((True, curve.inner, curve.inner_power), (False, curve.outer, curve.outer_power)):
        exact = bs.hertz_contact(b218, a, inner).K
        approx = hertz.chebyshev_eval(coeffs, jnp.cos(a))
        assert float(jnp.max(jnp.abs(approx / exact - 1))) < 1e-13
        assert float(jnp.max(jnp.abs(hertz.power_eval(power, jnp.cos(a)) / exact - 1))) < 1e-13


def test_K_depends_on_contact_angle(b218):
    """K is evaluated at each contact's own angle, not a constant at alpha_0."""
    K20 = float(bs.hertz_contact(b218, np.deg2rad(20.0), True).K)
    K60 = float(bs.hertz_contact(b218, np.deg2rad(60.0), True).K)
    assert K60 / K20 > 1.001


def test_contact_ellipse_series_reproduces_exact_semi_axes(b218):
    """a, b and p_max from the Chebyshev series equal hertz.semi_axes of the exact solution."""
    curve = hertz.stiffness_curve(b218)
    a = jnp.linspace(-1.5, 1.5, 301)
    Q = jnp.linspace(10.0, 5000.0, 301)
    for inner in (True, False):
        ea, eb, ep = hertz.semi_axes(bs.hertz_contact(b218, a, inner), Q, b218.effective_modulus)
        sa, sb, sp_ = hertz.contact_ellipse(curve, jnp.cos(a), Q, inner)
        for x, y in ((sa, ea), (sb, eb), (sp_, ep)):
            assert float(jnp.max(jnp.abs(x / y - 1))) < 1e-12
