"""Jones quasi-static model (MODEL.md section 4) against closed forms, published values,
global equilibrium, symmetry and limits."""
import functools
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings, HealthCheck, strategies as st

import bearingsim as bs
from bearingsim import jones
from conftest import harris218

DEG = np.pi / 180


def equilibrium_error(b, sol, op):
    """Ring loads rebuilt in numpy from the reported per-ball values (MODEL.md section 4)."""
    lam_i, lam_o = op.factors
    D = float(b.ball_diameter)
    ai, Qi, Mg, psi = (np.asarray(x) for x in (sol.alpha_inner, sol.Q_inner, sol.gyroscopic_moment, sol.azimuth))
    G = Qi * np.sin(ai) + lam_i * Mg / D * np.cos(ai)
    H = Qi * np.cos(ai) - lam_i * Mg / D * np.sin(ai)
    m = float(b.inner_groove_radius) * G - lam_i * float(b.f_inner) * Mg
    R = np.array([np.sum(H * np.cos(psi)), np.sum(H * np.sin(psi)), np.sum(G),
                  np.sum(m * np.sin(psi)), -np.sum(m * np.cos(psi))])
    F = np.asarray(sol.loads)
    Ri = float(b.inner_groove_radius)
    scale = np.array([1, 1, 1, 1 / Ri, 1 / Ri])
    return np.max(np.abs((R - F) * scale)) / np.max(np.abs(F * scale))


def ball_equilibrium_error(b, sol, op):
    lam_i, lam_o = op.factors
    D = float(b.ball_diameter)
    ai, ao, Qi, Qo, Mg, Fc = (np.asarray(x) for x in (sol.alpha_inner, sol.alpha_outer, sol.Q_inner,
                                                         sol.Q_outer, sol.gyroscopic_moment, sol.centrifugal))
    G = Qi * np.sin(ai) + lam_i * Mg / D * np.cos(ai)
    H = Qi * np.cos(ai) - lam_i * Mg / D * np.sin(ai)
    r1 = G - Qo * np.sin(ao) - lam_o * Mg / D * np.cos(ao)
    r2 = H - Qo * np.cos(ao) + lam_o * Mg / D * np.sin(ao) + Fc
    return max(np.max(np.abs(r1)), np.max(np.abs(r2))) / max(np.max(Qo), 1.0)


# ---------------------------------------------------------------------------- static thrust
def test_static_thrust_closed_form_1e6(b218):
    """Fz / (Z K_n (BD)^1.5) = sin(a) (cos a0 / cos a - 1)^1.5, K_n at the solved angle."""
    op = bs.Operation.from_rpm(0.0)
    loads = np.array([[0, 0, Fa, 0, 0] for Fa in (500.0, 5000.0, 17800.0, 22250.0, 60000.0)])
    sols = bs.solve_batch(b218, op, loads)
    assert np.all(np.asarray(sols.result) == 0)
    a0 = float(b218.free_contact_angle)
    BD = float(b218.A)
    for k, Fa in enumerate(loads[:, 2]):
        a = float(sols.alpha_inner[k, 0])
        Ki = float(bs.hertz_contact(b218, a, True).K)
        Ko = float(bs.hertz_contact(b218, a, False).K)
        Kn = (Ki ** (-2 / 3) + Ko ** (-2 / 3)) ** -1.5
        lhs = Fa / (16 * Kn * BD ** 1.5)
        rhs = np.sin(a) * (np.cos(a0) / np.cos(a) - 1) ** 1.5
        assert abs(lhs / rhs - 1) < 1e-6


@pytest.mark.parametrize("Fa, alpha_deg, Q, dz_mm", [(22250.0, 41.72, 2089.6, 0.0415),
                                                     (17800.0, 41.495, 1679.1, 0.0359)])
def test_harris_218_published_static_thrust(b218, Fa, alpha_deg, Q, dz_mm):
    """reference-data.md: agreement to the printed digits."""
    sol = bs.solve(b218, bs.Operation.from_rpm(0.0), bs.Loads(axial=Fa))
    assert abs(float(sol.alpha_inner[0]) / DEG - alpha_deg) < 0.0051
    assert abs(float(sol.Q_inner[0]) - Q) < 0.051
    assert abs(float(sol.displacement[2]) * 1e3 - dz_mm) < 0.00051


@pytest.mark.parametrize("rpm", [0.0, 10000.0])
def test_identical_balls_under_pure_thrust(b218, rpm):
    sol = bs.solve(b218, bs.Operation.from_rpm(rpm), bs.Loads(axial=17800.0), cage_angle=0.3)
    for arr in (sol.Q_inner, sol.Q_outer, sol.alpha_inner, sol.alpha_outer):
        a = np.asarray(arr)
        assert np.ptp(a) <= 1e-10 * np.max(np.abs(a))
    assert np.max(np.abs(np.asarray(sol.displacement)[[0, 1, 3, 4]])) < 1e-15


def test_static_contacts_are_collinear(b218):
    sol = bs.solve(b218, bs.Operation.from_rpm(0.0), bs.Loads(axial=8000.0, radial_x=3000.0, moment_y=100.0))
    loaded = np.asarray(sol.Q_inner) > 0
    np.testing.assert_allclose(sol.alpha_inner[loaded], sol.alpha_outer[loaded], atol=1e-12)
    np.testing.assert_allclose(sol.Q_inner, sol.Q_outer, rtol=1e-10, atol=1e-9)


# ---------------------------------------------------------------------------- Stribeck / Sjovall
def test_stribeck_4_37_zero_clearance_large_Z():
    """Radial load, zero clearance (alpha_0 = 0), Z = 60: Q_max Z / F_r = 1/J_r(0.5) = 4.37 within 1 %."""
    b = bs.Bearing(60, 4e-3, 125.26e-3, 0.52, 0.52, 0.0)
    sol = bs.solve(b, bs.Operation.from_rpm(0.0), bs.Loads(radial_x=2000.0))
    ratio = float(sol.Q_inner.max()) * 60 / 2000.0
    assert abs(ratio / 4.37 - 1) < 0.01
    assert abs(float(sol.displacement[2])) < 1e-12       # symmetric: no axial shift


TABLE_7_4 = [  # eps, Fr tan a / Fa, J_r, J_a
    (0.2, 0.9318, 0.1590, 0.1707), (0.5, 0.8225, 0.2288, 0.2782), (0.8, 0.6995, 0.2559, 0.3658),
    (1.0, 0.6000, 0.2546, 0.4244), (1.25, 0.4538, 0.2289, 0.5044), (1.67, 0.3088, 0.1871, 0.6060),
]


@functools.lru_cache(maxsize=None)
def _sjovall_map(Z):
    b = bs.Bearing(Z, 2e-3, 125.26e-3, 0.5232, 0.5232, 40 * DEG)
    op = bs.Operation.from_rpm(0.0)
    psi = b.ball_azimuths(0.0)
    curve = bs.hertz.stiffness_curve(b)

    @jax.jit
    def f(q):
        st_ = jones.balls_at(b, op, q, psi, None, curve)[0]
        return jnp.max(st_.Q_i), jones._reactions_from_balls(st_, psi)

    return f


def _sjovall(Z, eps):
    """Translate the ring so that the loaded arc has the given eps (no tilt, tiny deflection so
    alpha stays alpha_0) and read J_r, J_a off the Jones load-displacement map."""
    a0 = 40 * DEG
    dr = 1e-8
    da = (2 * eps - 1) * dr / np.tan(a0)
    Qmax, R = _sjovall_map(Z)(jnp.array([dr, 0.0, da, 0.0, 0.0]))
    Qmax, Fr, Fa = float(Qmax), float(R[0]), float(R[2])
    return Fr / (Z * Qmax * np.cos(a0)), Fa / (Z * Qmax * np.sin(a0)), Fr * np.tan(a0) / Fa


@pytest.mark.parametrize("row", TABLE_7_4)
def test_harris_table_7_4_approached_as_Z_grows(row):
    eps, ratio, Jr, Ja = row
    errs = []
    for Z, tol in ((16, 0.035), (180, 0.005)):
        jr, ja, rt = _sjovall(Z, eps)
        assert abs(jr / Jr - 1) < tol and abs(ja / Ja - 1) < tol and abs(rt / ratio - 1) < tol
        errs.append(abs(jr / Jr - 1) + abs(ja / Ja - 1))
    assert errs[1] <= errs[0] + 1e-4


# ---------------------------------------------------------------------------- equilibrium
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(Fa=st.floats(3000.0, 40000.0), Fx=st.floats(-6000.0, 6000.0), Fy=st.floats(-6000.0, 6000.0),
       Mx=st.floats(-200.0, 200.0), My=st.floats(-200.0, 200.0), rpm=st.sampled_from([0.0, 6000.0, 12000.0]),
       cage=st.floats(0.0, 2 * np.pi))
def test_global_equilibrium_random_combined_loads(b218, Fa, Fx, Fy, Mx, My, rpm, cage):
    op = bs.Operation.from_rpm(rpm)
    sol = bs.solve(b218, op, bs.Loads(axial=Fa, radial_x=Fx, radial_y=Fy, moment_x=Mx, moment_y=My),
                   cage_angle=cage)
    assert equilibrium_error(b218, sol, op) <= 1e-9
    assert ball_equilibrium_error(b218, sol, op) <= 1e-9
    for arr in (sol.Q_inner, sol.Q_outer, sol.alpha_inner, sol.alpha_outer, sol.stiffness):
        assert np.all(np.isfinite(np.asarray(arr)))


@pytest.mark.parametrize("control", ["outer", "inner", "equal"])
def test_equilibrium_each_raceway_control(b218, control):
    op = bs.Operation.from_rpm(12000.0, control)
    sol = bs.solve(b218, op, bs.Loads(axial=12000.0, radial_x=3000.0, moment_y=-80.0))
    assert equilibrium_error(b218, sol, op) <= 1e-9
    assert ball_equilibrium_error(b218, sol, op) <= 1e-9


# ---------------------------------------------------------------------------- speed effects
def test_high_speed_outer_angle_below_inner_and_outer_load_above(b218):
    sol = bs.solve(b218, bs.Operation.from_rpm(10000.0), bs.Loads(axial=22250.0))
    assert np.all(np.asarray(sol.alpha_outer) < np.asarray(sol.alpha_inner))
    assert np.all(np.asarray(sol.Q_outer) > np.asarray(sol.Q_inner))
    # the outer-control spin/gyroscopic identity M_g = J w_m^2 sin(a_o) / g
    Mg = float(b218.ball_inertia) * float(sol.orbital_speed[0]) ** 2 * np.sin(float(sol.alpha_outer[0])) / float(b218.g)
    assert abs(float(sol.gyroscopic_moment[0]) / Mg - 1) < 1e-12
    Fc = 0.5 * float(b218.ball_mass) * float(b218.pitch_diameter) * float(sol.orbital_speed[0]) ** 2
    assert abs(float(sol.centrifugal[0]) / Fc - 1) < 1e-12


def test_continuity_as_speed_goes_to_zero(b218):
    loads = bs.Loads(axial=9000.0, radial_x=2500.0, moment_y=60.0)
    s0 = bs.solve(b218, bs.Operation.from_rpm(0.0), loads)
    prev = None
    for rpm in (100.0, 10.0, 1.0):
        s = bs.solve(b218, bs.Operation.from_rpm(rpm), loads)
        d = max(float(jnp.max(jnp.abs(s.Q_inner - s0.Q_inner))) / float(s0.Q_inner.max()),
                float(jnp.max(jnp.abs(s.displacement[:3] - s0.displacement[:3]))) / 1e-6 * 1e-3)
        if prev is not None:
            assert d < prev / 10 + 1e-12      # F_c, M_g ~ w^2: 10x slower -> >= 10x closer
        prev = d
    assert prev < 1e-6


def test_switches_off_recover_static_model(b218):
    loads = bs.Loads(axial=9000.0, radial_x=2500.0)
    s0 = bs.solve(b218, bs.Operation.from_rpm(0.0), loads)
    s = bs.solve(b218, bs.Operation.from_rpm(15000.0, centrifugal=False, gyroscopic=False), loads)
    np.testing.assert_allclose(s.Q_inner, s0.Q_inner, rtol=1e-9, atol=1e-7)
    np.testing.assert_allclose(s.displacement, s0.displacement, rtol=1e-9, atol=1e-14)
    assert float(s.cage_speed) > 0


def test_gyroscopic_switch_matters_at_speed(b218):
    loads = bs.Loads(axial=9000.0)
    on = bs.solve(b218, bs.Operation.from_rpm(15000.0), loads)
    off = bs.solve(b218, bs.Operation.from_rpm(15000.0, gyroscopic=False), loads)
    assert float(jnp.max(off.gyroscopic_moment)) == 0.0
    assert abs(float(on.alpha_outer[0] - off.alpha_outer[0])) > 0.1 * DEG


# ---------------------------------------------------------------------------- stiffness
@pytest.mark.parametrize("rpm", [0.0, 12000.0])
def test_stiffness_equals_central_difference(b218, rpm):
    op = bs.Operation.from_rpm(rpm)
    sol = bs.solve(b218, op, bs.Loads(axial=10000.0, radial_x=3000.0, moment_y=50.0), cage_angle=0.1)
    q = sol.displacement
    R = jax.jit(lambda q: jones.ring_reactions(b218, op, q, 0.1))
    K = np.asarray(sol.stiffness)
    h = np.array([1e-8, 1e-8, 1e-8, 1e-7, 1e-7])
    for j in range(5):
        e = jnp.zeros(5).at[j].set(h[j])
        fd = (np.asarray(R(q + e)) - np.asarray(R(q - e))) / (2 * h[j])
        np.testing.assert_allclose(K[:, j], fd, rtol=2e-5, atol=2e-5 * np.max(np.abs(K[:, j])))
    if rpm == 0.0:
        # nearly symmetric at rest; not exactly, because K is evaluated at the contact angle
        # (Q = K(alpha) delta^1.5 has no potential), which moves K by ~1e-4 here
        Ks = K / np.sqrt(np.outer(np.abs(np.diag(K)), np.abs(np.diag(K))))
        np.testing.assert_allclose(Ks, Ks.T, atol=1e-3)


def test_pure_thrust_stiffness_closed_form(b218):
    """Axial stiffness of identical balls: dFz/ddz from the closed-form thrust relation."""
    Fa = 17800.0
    sol = bs.solve(b218, bs.Operation.from_rpm(0.0), bs.Loads(axial=Fa))
    h = 1e-3
    s1 = bs.solve(b218, bs.Operation.from_rpm(0.0), bs.Loads(axial=Fa * (1 + h)))
    s2 = bs.solve(b218, bs.Operation.from_rpm(0.0), bs.Loads(axial=Fa * (1 - h)))
    kz = 2 * h * Fa / float(s1.displacement[2] - s2.displacement[2])
    assert abs(float(sol.stiffness[2, 2]) / kz - 1) < 1e-5


# ---------------------------------------------------------------------------- batch / robustness
def test_batch_equals_single_solves(b218):
    op = bs.Operation.from_rpm(8000.0)
    loads = np.array([[1000.0, 0, 12000.0, 0, 40.0], [0, -2000.0, 6000.0, -30.0, 0], [0, 0, 22250.0, 0, 0]])
    batch = bs.solve_batch(b218, op, loads)
    for k in range(3):
        s = bs.solve(b218, op, loads[k])
        np.testing.assert_allclose(batch.Q_inner[k], s.Q_inner, rtol=1e-10, atol=1e-8)
        np.testing.assert_allclose(batch.displacement[k], s.displacement, rtol=1e-10, atol=1e-16)


def test_zero_load_at_rest_is_the_unloaded_bearing(b218):
    sol = bs.solve(b218, bs.Operation.from_rpm(0.0), bs.Loads())
    assert int(sol.result) == 0
    assert float(jnp.max(jnp.abs(sol.displacement))) == 0.0
    assert float(jnp.max(sol.Q_inner)) == 0.0
    assert np.all(np.isfinite(np.asarray(sol.alpha_inner)))


def test_non_convergence_raises_with_residual_and_hint(b218):
    op = bs.Operation.from_rpm(10000.0)
    with pytest.raises(jones.NotConvergedError, match=r"residual .* N.*Hint"):
        bs.solve(b218, op, bs.Loads(axial=17800.0), maxit=1)
    sol = bs.solve(b218, op, bs.Loads(axial=17800.0), maxit=1, throw=False)
    assert int(sol.result) == 1 and sol.message() == [bs.RESULT_MESSAGES[1]]


def test_deep_groove_radial_load_centres_axially():
    """Clearance bearing (alpha_0 from P_d) under pure radial load: contacts at alpha ~ 0."""
    b = bs.Bearing.from_clearance(9, 7.94004e-3, 39.0398e-3, 0.52, 0.52, 12e-6)
    sol = bs.solve(b, bs.Operation.from_rpm(1797.0), bs.Loads(radial_x=1000.0))
    assert int(sol.result) == 0
    loaded = np.asarray(sol.Q_inner) > 0
    assert np.max(np.abs(np.asarray(sol.alpha_inner)[loaded])) < 1e-6
    assert equilibrium_error(b, sol, bs.Operation.from_rpm(1797.0)) < 1e-9


def test_defect_frequencies_cwru_multipliers():
    """CWRU drive end 6205 (reference-data.md): BPFO 3.5848, BPFI 5.4152, FTF 0.39828, 2 BSF 4.7135."""
    b = bs.Bearing(9, 0.3126 * 25.4e-3, 1.537 * 25.4e-3, 0.52, 0.52, 0.0)
    f = bs.defect_frequencies(b, 1.0)
    assert abs(float(f.bpfo) - 3.5848) < 5e-4
    assert abs(float(f.bpfi) - 5.4152) < 5e-4
    assert abs(float(f.ftf) - 0.39828) < 5e-5
    assert abs(float(f.two_bsf) - 4.7135) < 5e-4
