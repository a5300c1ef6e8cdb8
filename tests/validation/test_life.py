"""ISO/TS 16281 rating life (docs/model.md section 11): the published examples of docs/reference-data.md
(the public peer minzhun/ISO16281) through the Jones solve, and closed-form checks of the formulas."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bearingsim as bs
from bearingsim.physics import life

# docs/reference-data.md: deep-groove ball bearing, Z = 7, D = 11.5 mm, d_m = 43.5 mm, f_i = 0.52,
# f_o = 0.53, E = 210 GPa, nu = 0.3 (both bodies), C = 23.4 kN, zero speed.
ISO_MATERIAL = bs.Material(210e9, 0.3, 7850.0)
ISO_C = 23.4e3
STATIC = bs.Operation(0.0, "outer", 0.0, 0.0)


def iso_bearing(clearance):
    """The example bearing; ISO's "radial clearance" is the diametral play P_d of docs/model.md section 2."""
    return bs.Bearing.from_clearance(7, 11.5e-3, 43.5e-3, 0.52, 0.53, clearance, ISO_MATERIAL,
                                     ISO_MATERIAL)


# (clearance m, loads, index of the displacement, published displacement m, published L10r)
ISO_CASES = {
    "1_radial": (0.0, bs.load_vector(radial_x=1000.0), 0, 15.1101e-6, 13163.019),
    "2_axial": (0.0, bs.load_vector(axial=1000.0), 2, 133.5381e-6, 2222.7318),
    "3_radial_clearance": (0.010e-3, bs.load_vector(radial_x=1000.0), 0, 21.223e-6, 10795.7948),
}


@pytest.mark.parametrize("name", sorted(ISO_CASES))
def test_iso16281_examples(name):
    """Displacement and L10r within 0.5 % (issue 21 target; measured: <= 5e-5 in displacement and
    <= 1.2e-4 in life -- the peer uses the ISO/TS Hertz approximations, we the exact ellipticity).
    The nominal contact angle of this deep-groove bearing is 0 (ISO 281) also with clearance."""
    clearance, F, k, disp_ref, L_ref = ISO_CASES[name]
    b = iso_bearing(clearance)
    sol = bs.solve(b, STATIC, F)
    assert float(sol.displacement[k]) == pytest.approx(disp_ref, rel=5e-3)
    L = life.rating_life(b, ISO_C, sol.Q_inner, sol.Q_outer, contact_angle=0.0)
    assert float(L) == pytest.approx(L_ref, rel=5e-3)
    # tighter than the target: what we measured (a regression guard)
    assert abs(float(sol.displacement[k]) / disp_ref - 1) < 2e-4
    assert abs(float(L) / L_ref - 1) < 5e-4


def test_nominal_angle_of_a_deep_groove_bearing_is_zero():
    """With the free contact angle of the clearance (7.6 deg) instead of 0 the life of example 3
    moves by (cos alpha_0)^-2.1 - the ISO life needs the nominal angle, not alpha_0."""
    b = iso_bearing(0.010e-3)
    Q = jnp.full(7, 500.0)
    L0 = life.rating_life(b, ISO_C, Q, Q, contact_angle=0.0)
    La = life.rating_life(b, ISO_C, Q, Q)
    a0 = float(b.free_contact_angle)
    assert np.rad2deg(a0) == pytest.approx(7.56, abs=0.01)
    # Q_c ~ (cos a)^-0.7 (1 + t(gamma)...)^0.3: the life ratio is close to (cos a0)^-2.1
    assert float(La / L0) == pytest.approx(np.cos(a0) ** -2.1, rel=5e-3)


def _iso_ratings_by_hand(Z, D, dm, fi, fo, alpha, C, i=1):
    g = D * np.cos(alpha) / dm
    rho = (fi / fo) * (2 * fo - 1) / (2 * fi - 1)
    t = 1.044 * ((1 - g) / (1 + g)) ** 1.72 * rho ** 0.41
    Qci = C / (0.407 * Z * (i * np.cos(alpha)) ** 0.7) * (1 + t ** (10 / 3)) ** 0.3
    Qco = C / (0.389 * Z * (i * np.cos(alpha)) ** 0.7) * (1 + t ** (-10 / 3)) ** 0.3
    return Qci, Qco


def test_contact_load_ratings_by_hand(b218):
    C = 120e3
    for rows in (1, 2):
        Qci, Qco = life.contact_load_ratings(b218, C, rows)
        ref = _iso_ratings_by_hand(16, 22.225e-3, 125.26e-3, 0.5232, 0.5232, np.deg2rad(40.0), C, rows)
        np.testing.assert_allclose([float(Qci), float(Qco)], ref, rtol=1e-13)
    # equal conformities: the inner contact (convex-convex) is the weaker one
    assert float(Qci) < float(Qco)


def test_equivalent_loads_closed_forms():
    """Uniform loads: both means are the load.  One loaded ball of Z: Q/Z^(1/3), Q/Z^(3/10)."""
    Z, Q = 9, 1234.5
    Qe_i, Qe_o = life.equivalent_loads(jnp.full(Z, Q), jnp.full(Z, 2 * Q))
    assert float(Qe_i) == pytest.approx(Q, rel=1e-14)
    assert float(Qe_o) == pytest.approx(2 * Q, rel=1e-14)
    one = jnp.zeros(Z).at[3].set(Q)
    Qe_i, Qe_o = life.equivalent_loads(one, one)
    assert float(Qe_i) == pytest.approx(Q / Z ** (1 / 3), rel=1e-14)
    assert float(Qe_o) == pytest.approx(Q / Z ** 0.3, rel=1e-14)
    # batched over leading axes
    batch = jnp.stack([jnp.full(Z, Q), one])
    Qe_i, _ = life.equivalent_loads(batch[None], batch[None])
    assert Qe_i.shape == (1, 2)


def test_rating_life_closed_form_uniform_load(b218):
    """Uniform ball load Q (pure thrust at rest): L = ((Q/Q_ci)^(10/3) + (Q/Q_co)^(10/3))^(-9/10),
    and L scales as Q^-3."""
    C = 120e3
    Qci, Qco = life.contact_load_ratings(b218, C)
    Q = 1500.0
    L = life.rating_life(b218, C, jnp.full(16, Q), jnp.full(16, Q))
    ref = ((Q / float(Qci)) ** (10 / 3) + (Q / float(Qco)) ** (10 / 3)) ** -0.9
    assert float(L) == pytest.approx(ref, rel=1e-13)
    L2 = life.rating_life(b218, C, jnp.full(16, 2 * Q), jnp.full(16, 2 * Q))
    assert float(L / L2) == pytest.approx(8.0, rel=1e-13)
    # the rings fail independently: rating_life is the set life of the two ring lives
    Li, Lo = life.ring_lives(b218, C, jnp.full(16, Q), jnp.full(16, Q))
    assert float(life.set_life(jnp.stack([Li, Lo]))) == pytest.approx(float(L), rel=1e-13)


def test_unloaded_bearing_lives_forever(b218):
    z = jnp.zeros(16)
    assert float(life.rating_life(b218, 1e5, z, z)) == np.inf
    Li, Lo = life.ring_lives(b218, 1e5, z, jnp.full(16, 100.0))
    assert float(Li) == np.inf and np.isfinite(float(Lo))
    assert float(life.set_life(jnp.array([np.inf, 50.0]))) == pytest.approx(50.0, rel=1e-14)
    # no NaN in the gradient at zero load
    g = jax.grad(lambda s: life.rating_life(b218, 1e5, s * z, s * z))(1.0)
    assert np.isfinite(float(g))


def test_set_life_identical_bearings():
    """N identical bearings: L / N^(9/10); one bearing: itself."""
    L = 3210.0
    for N in (1, 2, 3, 4):
        assert float(life.set_life(jnp.full(N, L))) == pytest.approx(L / N ** 0.9, rel=1e-13)
    # batched: last axis reduced
    out = life.set_life(jnp.array([[L, L], [L, np.inf]]))
    np.testing.assert_allclose(np.asarray(out), [L / 2 ** 0.9, L], rtol=1e-13)


def test_life_hours():
    """L10r 1e6 / (60 n): 1000 million revolutions at 1000 rpm are 16 666.67 h."""
    assert float(life.life_hours_rpm(1000.0, 1000.0)) == pytest.approx(1e9 / 60e3, rel=1e-14)
    w = 1000.0 * 2 * np.pi / 60
    assert float(life.life_hours(1000.0, w)) == pytest.approx(1e9 / 60e3, rel=1e-14)
    assert float(life.life_hours(1000.0, 0.0)) == np.inf


def test_rating_life_gradient_matches_power_law(b218):
    """dL/dQ for uniform loads: L ~ Q^-3 -> Q dL/dQ = -3 L (autodiff through the formula)."""
    f = lambda q: life.rating_life(b218, 120e3, jnp.full(16, q), jnp.full(16, q))
    q = 1500.0
    assert float(q * jax.grad(f)(q)) == pytest.approx(-3 * float(f(q)), rel=1e-12)
