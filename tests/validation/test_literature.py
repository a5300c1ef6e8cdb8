"""Literature benchmarks: every assertion names its source (docs/reference-data.md, docs/model.md).

Harris & Kotzalas (2006) Table 6.1 (Hertz), Table 7.4 (Sjovall integrals), the Harris 218
bearing's published constants and static thrust solution, the closed forms of docs/model.md section 4
(pure thrust, Stribeck 4.37) and the CWRU defect-frequency multipliers.
"""
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bearingsim as bs
from bearingsim.physics import hertz
from bearingsim.xla import compiler_options
from conftest import DEG

HARRIS_6_1 = "Harris & Kotzalas (2006) vol. 1 Table 6.1"
HARRIS_7_4 = "Harris & Kotzalas (2006) vol. 1 Table 7.4"
H218 = "Harris 218 bearing (docs/reference-data.md)"

# F(rho), a*, b*, delta*
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


@pytest.mark.parametrize("row", TABLE_6_1, ids=[f"F={r[0]}" for r in TABLE_6_1])
def test_harris_table_6_1_to_1e3(row):
    """Every row to 1e-3 (the table's rounding; exact elliptic integrals agree to 3.2e-4)."""
    F, a_ref, b_ref, d_ref = row
    a, b, d = (float(v) for v in bs.dimensionless_hertz(F))
    for name, got, ref in (("a*", a, a_ref), ("b*", b, b_ref), ("delta*", d, d_ref)):
        assert abs(got / ref - 1) < 1e-3, f"{HARRIS_6_1}, F(rho) = {F}: {name} {got:.5f} vs {ref}"


def test_harris_218_contact_constants(b218):
    """inner K 1.297e6, outer K 1.349e6 N/mm^1.5, F(rho) 0.9262 / 0.9041, kappa 8.155 / 6.897 at
    alpha = 40 deg (4 significant digits as published: 5e-4)."""
    a = np.deg2rad(40.0)
    ci, co = bs.hertz_contact(b218, a, True), bs.hertz_contact(b218, a, False)
    to_mm = 1e3 ** 1.5
    assert abs(float(ci.K) / to_mm / 1.297e6 - 1) < 5e-4, f"{H218}: inner K {float(ci.K) / to_mm:.4g}"
    assert abs(float(co.K) / to_mm / 1.349e6 - 1) < 5e-4, f"{H218}: outer K {float(co.K) / to_mm:.4g}"
    assert abs(float(ci.F_rho) - 0.9262) < 5e-5 and abs(float(co.F_rho) - 0.9041) < 5e-5, H218
    assert abs(float(ci.kappa) / 8.155 - 1) < 5e-4 and abs(float(co.kappa) / 6.897 - 1) < 5e-4, H218


def test_steel_dimensional_formulas(b218):
    """docs/reference-data.md: a = 0.0236 a* (Q/sum_rho)^(1/3), delta = 2.79e-4 delta* Q^(2/3)
    sum_rho^(1/3) (mm, N, 1/mm); the printed constants have 3 digits, so 0.5 %."""
    c = bs.hertz_contact(b218, np.deg2rad(40.0), True)
    Q = 2000.0
    a, b, p = hertz.semi_axes(c, Q, b218.effective_modulus)
    a_s, b_s, d_s = bs.dimensionless_hertz(c.F_rho)
    srho = float(c.sum_rho) / 1e3
    src = "docs/reference-data.md steel-on-steel formulas"
    assert abs(float(a) * 1e3 / (0.0236 * float(a_s) * (Q / srho) ** (1 / 3)) - 1) < 5e-3, src
    assert abs(float(b) * 1e3 / (0.0236 * float(b_s) * (Q / srho) ** (1 / 3)) - 1) < 5e-3, src
    delta = (Q / float(c.K)) ** (2 / 3) * 1e3
    assert abs(delta / (2.79e-4 * float(d_s) * Q ** (2 / 3) * srho ** (1 / 3)) - 1) < 5e-3, src
    assert abs(float(p) - 3 * Q / (2 * np.pi * float(a) * float(b))) < 1e-6 * float(p), "docs/model.md section 3"


@pytest.mark.parametrize("Fa, alpha_deg, Q, dz_mm", [(22250.0, 41.72, 2089.6, 0.0415),
                                                     (17800.0, 41.495, 1679.1, 0.0359)])
def test_harris_218_published_static_thrust(b218, Fa, alpha_deg, Q, dz_mm):
    """Agreement to the printed digits."""
    sol = bs.solve(b218, bs.Operation.from_rpm(0.0), bs.Loads(axial=Fa))
    a, q, dz = float(sol.alpha_inner[0]) / DEG, float(sol.Q_inner[0]), float(sol.displacement[2]) * 1e3
    assert abs(a - alpha_deg) < 0.0051, f"{H218}, {Fa} N: alpha {a:.4f} deg vs {alpha_deg}"
    assert abs(q - Q) < 0.051, f"{H218}, {Fa} N: Q {q:.2f} N vs {Q}"
    assert abs(dz - dz_mm) < 0.00051, f"{H218}, {Fa} N: axial deflection {dz:.5f} mm vs {dz_mm}"


def test_static_thrust_closed_form_1e6(b218):
    """docs/model.md section 4: Fz / (Z K_n (BD)^1.5) = sin(a) (cos a0 / cos a - 1)^1.5, K_n at the solved angle."""
    op = bs.Operation.from_rpm(0.0)
    loads = np.array([[0, 0, Fa, 0, 0] for Fa in (500.0, 5000.0, 17800.0, 22250.0, 60000.0)])
    sols = bs.solve_batch(b218, op, loads)
    assert np.all(np.asarray(sols.result) == 0)
    a0, BD = float(b218.free_contact_angle), float(b218.A)
    for k, Fa in enumerate(loads[:, 2]):
        a = float(sols.alpha_inner[k, 0])
        Ki, Ko = float(bs.hertz_contact(b218, a, True).K), float(bs.hertz_contact(b218, a, False).K)
        Kn = (Ki ** (-2 / 3) + Ko ** (-2 / 3)) ** -1.5
        lhs = Fa / (16 * Kn * BD ** 1.5)
        rhs = np.sin(a) * (np.cos(a0) / np.cos(a) - 1) ** 1.5
        assert abs(lhs / rhs - 1) < 1e-6, f"docs/model.md section 4 pure-thrust closed form at {Fa} N"


def test_pure_thrust_stiffness_closed_form(b218):
    """dFz/ddz of identical balls from the closed-form thrust relation (differences of solves)."""
    Fa, h, op = 17800.0, 1e-3, bs.Operation.from_rpm(0.0)
    sol = bs.solve(b218, op, bs.Loads(axial=Fa))
    s1 = bs.solve(b218, op, bs.Loads(axial=Fa * (1 + h)))
    s2 = bs.solve(b218, op, bs.Loads(axial=Fa * (1 - h)))
    kz = 2 * h * Fa / float(s1.displacement[2] - s2.displacement[2])
    assert abs(float(sol.stiffness[2, 2]) / kz - 1) < 1e-5, "pure-thrust stiffness vs closed form"


def test_stribeck_4_37_zero_clearance_large_Z():
    """docs/model.md section 4 (Stribeck): radial load, zero clearance, Z = 60: Q_max Z / F_r = 4.37 within 1 %."""
    b = bs.Bearing(60, 4e-3, 125.26e-3, 0.52, 0.52, 0.0)
    sol = bs.solve(b, bs.Operation.from_rpm(0.0), bs.Loads(radial_x=2000.0))
    ratio = float(sol.Q_inner.max()) * 60 / 2000.0
    assert abs(ratio / 4.37 - 1) < 0.01, f"Stribeck 4.37: got {ratio:.4f}"
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
    curve = hertz.stiffness_curve(b)

    @functools.partial(jax.jit, compiler_options=compiler_options())
    def f(q):
        st_ = bs.balls_at(b, op, q, psi, curve)
        return jnp.max(st_.Q_inner), bs.reactions_from_balls(st_, psi)

    return f


def _sjovall(Z, eps):
    """Translate the ring so that the loaded arc has the given eps (no tilt, tiny deflection so
    alpha stays alpha_0) and read J_r, J_a off the Jones load-displacement map."""
    a0, dr = 40 * DEG, 1e-8
    da = (2 * eps - 1) * dr / np.tan(a0)
    Qmax, R = _sjovall_map(Z)(jnp.array([dr, 0.0, da, 0.0, 0.0]))
    Qmax, Fr, Fa = float(Qmax), float(R[0]), float(R[2])
    return Fr / (Z * Qmax * np.cos(a0)), Fa / (Z * Qmax * np.sin(a0)), Fr * np.tan(a0) / Fa


@pytest.mark.parametrize("row", TABLE_7_4, ids=[f"eps={r[0]}" for r in TABLE_7_4])
def test_harris_table_7_4_approached_as_Z_grows(row):
    """Within Z-discretisation: 3.5 % at Z = 16, 0.5 % at Z = 180, and closer at the larger Z."""
    eps, ratio, Jr, Ja = row
    errs = []
    for Z, tol in ((16, 0.035), (180, 0.005)):
        jr, ja, rt = _sjovall(Z, eps)
        msg = f"{HARRIS_7_4}, eps = {eps}, Z = {Z}: J_r {jr:.4f} ({Jr}), J_a {ja:.4f} ({Ja})"
        assert abs(jr / Jr - 1) < tol and abs(ja / Ja - 1) < tol and abs(rt / ratio - 1) < tol, msg
        errs.append(abs(jr / Jr - 1) + abs(ja / Ja - 1))
    assert errs[1] <= errs[0] + 1e-4, f"{HARRIS_7_4}: not approached as Z grows"


def test_defect_frequencies_cwru_multipliers():
    """CWRU drive end 6205 (docs/reference-data.md): BPFO 3.5848, BPFI 5.4152, FTF 0.39828, 2 BSF 4.7135."""
    b = bs.Bearing(9, 0.3126 * 25.4e-3, 1.537 * 25.4e-3, 0.52, 0.52, 0.0)
    f = bs.defect_frequencies(b, 1.0)
    src = "CWRU published defect frequencies"
    assert abs(float(f.bpfo) - 3.5848) < 5e-4, f"{src}: BPFO {float(f.bpfo):.5f}"
    assert abs(float(f.bpfi) - 5.4152) < 5e-4, f"{src}: BPFI {float(f.bpfi):.5f}"
    assert abs(float(f.ftf) - 0.39828) < 5e-5, f"{src}: FTF {float(f.ftf):.5f}"
    assert abs(float(f.two_bsf) - 4.7135) < 5e-4, f"{src}: 2 BSF {float(f.two_bsf):.5f}"
