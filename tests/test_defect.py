"""Outer-raceway spall (MODEL.md section 5): depth profiles and the spalled quasi-static state."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bearingsim as bs
from bearingsim import jones
from bearingsim.defect import depth_profile, wrap_angle
from conftest import ball_equilibrium_error, equilibrium_error

DEG = np.pi / 180
LOADS = bs.Loads(axial=10000.0, radial_x=3000.0)


# ------------------------------------------------------------------------------ profile
def test_rectangular_profile_values(b218):
    D = float(b218.ball_diameter)
    R_o = float(b218.outer_raceway_radius)
    sp = bs.Spall(10 * DEG, 2 * DEG, 1e-3, "rectangular")
    b = R_o * 2 * DEG
    sag = D / 2 - np.sqrt((D / 2) ** 2 - (b / 2) ** 2)       # the ball cannot reach 1 mm
    psi = jnp.array([10 * DEG, 9.01 * DEG, 10.99 * DEG, 8.99 * DEG, 11.01 * DEG, 190 * DEG])
    H = np.asarray(depth_profile(b218, sp, psi))
    np.testing.assert_allclose(H[:3], sag, rtol=1e-12)
    assert np.all(H[3:] == 0.0)
    shallow = bs.Spall(10 * DEG, 2 * DEG, 0.05e-3, "rectangular")
    assert float(depth_profile(b218, shallow, 10 * DEG)) == pytest.approx(0.05e-3, rel=1e-12)


def test_ball_path_profile_is_continuous_and_symmetric(b218):
    sp = bs.Spall(0.0, 8 * DEG, 0.3e-3, "ball-path")
    psi = jnp.linspace(-5 * DEG, 5 * DEG, 20001)
    H = np.asarray(depth_profile(b218, sp, psi))
    assert H[0] == 0.0 and H[-1] == 0.0 and H.max() == pytest.approx(0.3e-3)
    assert np.max(np.abs(np.diff(H))) < 2e-6          # no step (grid 0.0005 deg)
    np.testing.assert_allclose(H, H[::-1], atol=1e-15)


def test_profile_wraps_around_2pi(b218):
    sp = bs.Spall(359 * DEG, 4 * DEG, 0.1e-3, "ball-path")
    assert float(depth_profile(b218, sp, 0.5 * DEG)) > 0
    assert float(depth_profile(b218, sp, -1.0 * DEG)) == pytest.approx(float(depth_profile(b218, sp, 359 * DEG)))
    assert float(wrap_angle(jnp.pi)) == pytest.approx(np.pi) and float(wrap_angle(-jnp.pi)) == pytest.approx(np.pi)


def test_profile_is_differentiable_in_depth_and_extent(b218):
    def H(depth, extent):
        return depth_profile(b218, bs.Spall(0.0, extent, depth, "ball-path"), 1.0 * DEG)
    g = jax.grad(H, argnums=(0, 1))(0.3e-3, 4 * DEG)
    assert all(np.isfinite(float(x)) for x in g)


# ------------------------------------------------------------------------------ solves
def test_depth_zero_is_the_healthy_bearing(b218):
    op = bs.Operation.from_rpm(10000.0)
    healthy = bs.solve(b218, op, LOADS, cage_angle=0.01)
    zero = bs.solve(b218, op, LOADS, cage_angle=0.01, spall=bs.Spall(0.0, 8 * DEG, 0.0, "rectangular"))
    for f in ("Q_inner", "Q_outer", "alpha_inner", "alpha_outer", "displacement"):
        np.testing.assert_allclose(getattr(zero, f), getattr(healthy, f), rtol=1e-12, atol=1e-15)


def test_deep_spall_at_rest_ball_unloaded_neighbours_take_over(b218):
    op = bs.Operation.from_rpm(0.0)
    sp = bs.Spall(0.0, 8 * DEG, 0.3e-3, "rectangular")
    h = bs.solve(b218, op, LOADS)
    s = bs.solve(b218, op, LOADS, spall=sp)
    assert float(s.Q_inner[0]) == 0.0 and float(s.Q_outer[0]) == 0.0        # ball 0 at psi = 0
    assert np.all(np.isfinite(np.asarray(s.alpha_inner))) and np.all(np.isfinite(np.asarray(s.stiffness)))
    assert float(s.Q_inner[1]) > 1.1 * float(h.Q_inner[1]) and float(s.Q_inner[15]) > 1.1 * float(h.Q_inner[15])
    assert equilibrium_error(b218, s, op) <= 1e-9
    assert ball_equilibrium_error(b218, s, op) <= 1e-9


def test_at_speed_ball_in_spall_keeps_outer_contact_and_angles_jump(b218):
    op = bs.Operation.from_rpm(10000.0)
    sp = bs.Spall(0.0, 8 * DEG, 0.3e-3, "rectangular")
    h = bs.solve(b218, op, LOADS)
    s = bs.solve(b218, op, LOADS, spall=sp)
    # the dropped ball all but leaves its inner raceway; F_c keeps it on the spall bottom
    assert float(s.Q_inner[0]) < 0.01 * float(h.Q_inner[0])
    assert 0.8 * float(s.centrifugal[0]) < float(s.Q_outer[0]) < 1.2 * float(s.centrifugal[0]) + float(s.Q_inner[0])
    assert abs(float(s.alpha_outer[0] - h.alpha_outer[0])) > 10 * DEG
    assert equilibrium_error(b218, s, op) <= 1e-9
    assert ball_equilibrium_error(b218, s, op) <= 1e-9


def test_solution_is_differentiable_wrt_spall_depth(b218):
    """d Q_o(ball 1) / d depth by autodiff through the solve equals a central difference."""
    op = bs.Operation.from_rpm(6000.0)
    sol0 = bs.solve(b218, op, LOADS, cage_angle=0.0, spall=bs.Spall(0.0, 3 * DEG, 0.02e-3, "ball-path"))

    def Q1(depth):
        sp = bs.Spall(0.0, 3 * DEG, depth, "ball-path")
        q = sol0.displacement
        # implicit function theorem on the ring equations: dq/dd = -K^-1 dR/dd
        R = lambda qq, d: jones.ring_reactions(b218, op, qq, 0.0, bs.Spall(0.0, 3 * DEG, d, "ball-path"))
        return q, R
    q, R = Q1(0.02e-3)
    dRdd = jax.jit(jax.jacfwd(R, argnums=1))(q, 0.02e-3)
    dqdd = -np.linalg.solve(np.asarray(sol0.stiffness), np.asarray(dRdd))
    h = 1e-7
    sp_ = lambda d: bs.solve(b218, op, LOADS, spall=bs.Spall(0.0, 3 * DEG, d, "ball-path")).displacement
    fd = (np.asarray(sp_(0.02e-3 + h)) - np.asarray(sp_(0.02e-3 - h))) / (2 * h)
    np.testing.assert_allclose(dqdd[:3], fd[:3], rtol=1e-4, atol=1e-6)


# ------------------------------------------------------------------------------ seed findings
def test_seed_findings_speed(b218):
    """Q_o - Q_i grows with speed; alpha_o falls and alpha_i rises (ball in the load zone)."""
    sp = bs.Spall(0.0, 3 * DEG, 0.3e-3, "rectangular")
    out = []
    for rpm in (0.0, 5000.0, 10000.0, 15000.0):
        s = bs.solve(b218, bs.Operation.from_rpm(rpm), LOADS, spall=sp)
        out.append((float(s.Q_outer[1] - s.Q_inner[1]), float(s.alpha_outer[1]), float(s.alpha_inner[1])))
    d, ao, ai = np.array(out).T
    assert np.all(np.diff(d) > 0) and np.all(np.diff(ao) < 0) and np.all(np.diff(ai) > 0)


def test_seed_findings_jump_grows_with_extent(b218):
    """The longer the spall, the deeper the ball drops (until it rests on the spall bottom):
    its outer angle falls further and its neighbours take more load."""
    op = bs.Operation.from_rpm(10000.0)
    h = bs.solve(b218, op, LOADS)
    drop, extra = [], []
    for ext in (1.0, 2.0, 3.0, 4.0):
        s = bs.solve(b218, op, LOADS, spall=bs.Spall(0.0, ext * DEG, 0.3e-3, "rectangular"))
        drop.append(float(h.alpha_outer[0] - s.alpha_outer[0]))
        extra.append(float(s.Q_outer[1] - h.Q_outer[1]))
    assert np.all(np.diff(drop) > 0) and np.all(np.diff(extra) > 0)
