"""Hertz point contact against scipy and Harris & Kotzalas Table 6.1 (reference-data.md)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.special as sp

import bearingsim as bs
from bearingsim import hertz

# F(rho), a*, b*, delta*  (Harris & Kotzalas 2006, vol. 1, Table 6.1)
TABLE_6_1 = [
    (0, 1, 1, 1), (0.1075, 1.0760, 0.9318, 0.9974), (0.3204, 1.2623, 0.8114, 0.9761),
    (0.4795, 1.4556, 0.7278, 0.9429), (0.5916, 1.6440, 0.6687, 0.9077),
    (0.6716, 1.8258, 0.6245, 0.8733), (0.7332, 2.011, 0.5881, 0.8394),
    (0.7948, 2.265, 0.5480, 0.7961), (0.83495, 2.494, 0.5186, 0.7602),
    (0.87366, 2.800, 0.4863, 0.7169), (0.90999, 3.233, 0.4499, 0.6636),
    (0.93657, 3.738, 0.4166, 0.6112), (0.95738, 4.395, 0.3830, 0.5551),
    (0.97290, 5.267, 0.3490, 0.4960), (0.983797, 6.448, 0.3150, 0.4352),
    (0.990902, 8.062, 0.2814, 0.3745), (0.995112, 10.222, 0.2497, 0.3176),
    (0.997300, 12.789, 0.2232, 0.2705), (0.9981847, 14.839, 0.2072, 0.2427),
    (0.9989156, 17.974, 0.18822, 0.2106), (0.9994785, 23.55, 0.16442, 0.17167),
    (0.9998527, 37.38, 0.13050, 0.11995),
]


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


@pytest.mark.parametrize("row", TABLE_6_1)
def test_harris_table_6_1_to_1e3(row):
    F, a_ref, b_ref, d_ref = row
    a, b, d = (float(v) for v in bs.dimensionless_hertz(F))
    assert abs(a / a_ref - 1) < 1e-3
    assert abs(b / b_ref - 1) < 1e-3
    assert abs(d / d_ref - 1) < 1e-3


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


def test_harris_218_contact_constants(b218):
    """reference-data.md: inner K 1.297e6, outer K 1.349e6 N/mm^1.5, F(rho) 0.9262 / 0.9041,
    kappa 8.155 / 6.897 at alpha = 40 deg (4 significant digits as published)."""
    a = np.deg2rad(40.0)
    ci = bs.hertz_contact(b218, a, True)
    co = bs.hertz_contact(b218, a, False)
    to_mm = 1e3 ** 1.5
    assert abs(float(ci.K) / to_mm / 1.297e6 - 1) < 5e-4
    assert abs(float(co.K) / to_mm / 1.349e6 - 1) < 5e-4
    assert abs(float(ci.F_rho) - 0.9262) < 5e-5 and abs(float(co.F_rho) - 0.9041) < 5e-5
    assert abs(float(ci.kappa) - 8.155) < 5e-4 * 8.155 and abs(float(co.kappa) - 6.897) < 5e-4 * 6.897


def test_steel_dimensional_formulas_of_reference_data(b218):
    """a = 0.0236 a* (Q/sum_rho)^(1/3), delta = 2.79e-4 delta* Q^(2/3) sum_rho^(1/3) (mm, N, 1/mm);
    the printed constants have 3 digits, so agreement to 0.5 %."""
    c = bs.hertz_contact(b218, np.deg2rad(40.0), True)
    Q = 2000.0
    a, b, p = hertz.semi_axes(c, Q, b218.effective_modulus)
    a_s, b_s, d_s = bs.dimensionless_hertz(c.F_rho)
    srho_mm = float(c.sum_rho) / 1e3
    assert abs(float(a) * 1e3 / (0.0236 * float(a_s) * (Q / srho_mm) ** (1 / 3)) - 1) < 5e-3
    assert abs(float(b) * 1e3 / (0.0236 * float(b_s) * (Q / srho_mm) ** (1 / 3)) - 1) < 5e-3
    delta = (Q / float(c.K)) ** (2 / 3) * 1e3
    assert abs(delta / (2.79e-4 * float(d_s) * Q ** (2 / 3) * srho_mm ** (1 / 3)) - 1) < 5e-3
    # p_max = 3Q / (2 pi a b) and Q = K delta^1.5 consistent with a, b
    assert abs(float(p) - 3 * Q / (2 * np.pi * float(a) * float(b))) < 1e-6 * float(p)


def test_chebyshev_stiffness_curve_reproduces_exact_K(b218):
    curve = hertz.stiffness_curve(b218)
    a = jnp.linspace(-np.pi, np.pi, 721)
    for inner, coeffs in ((True, curve.inner), (False, curve.outer)):
        exact = bs.hertz_contact(b218, a, inner).K
        approx = hertz.chebyshev_eval(coeffs, jnp.cos(a))
        assert float(jnp.max(jnp.abs(approx / exact - 1))) < 1e-13


def test_K_depends_on_contact_angle(b218):
    """K is evaluated at each contact's own angle, not a constant at alpha_0."""
    K20 = float(bs.hertz_contact(b218, np.deg2rad(20.0), True).K)
    K60 = float(bs.hertz_contact(b218, np.deg2rad(60.0), True).K)
    assert K60 / K20 > 1.001
