"""Per-contact limits (docs/model.md section 11): pressure, the friction raceway control needs, the contact
ellipse against the shoulders -- against hand computations and a real solve."""
from types import SimpleNamespace

import jax.numpy as jnp
import numpy as np
import pytest

import bearingsim as bs
from bearingsim.physics import limits

DEG = np.pi / 180


def _state(**kw):
    """A hand-made per-ball state (2 balls) with the JonesSolution fields limits reads."""
    base = dict(alpha_inner=[40 * DEG, 70 * DEG], alpha_outer=[35 * DEG, -12 * DEG],
                Q_inner=[1000.0, 500.0], Q_outer=[1200.0, 0.0], a_inner=[2e-3, 1e-3],
                a_outer=[2.5e-3, 0.0], p_max_inner=[2.1e9, 4.41e9], p_max_outer=[1.0e9, 0.0],
                gyroscopic_moment=[0.5, -0.4])
    base.update(kw)
    return SimpleNamespace(**{k: jnp.asarray(v, jnp.float64) for k, v in base.items()})


def test_limits_by_hand(b218):
    """The 218: D = 22.225 mm, f = 0.5232, shoulders 74.12 / 11.22 deg (land 0.38 D / 0.01 D)."""
    st = _state()
    L = limits.contact_limits(st, b218, "outer", friction_coefficient=0.05)
    D, f = 22.225e-3, 0.5232
    th_hi, th_lo = np.arccos(1 - 0.38 / f), np.arccos(1 - 0.01 / f)
    np.testing.assert_allclose(np.asarray(L.pressure_ratio_inner), [0.5, 1.05], rtol=1e-14)
    assert list(np.asarray(L.overpressure)) == [False, True]
    # outer control: the outer contact supplies 2 M_g / D; the second ball has no outer load
    np.testing.assert_allclose(np.asarray(L.friction_outer), [2 * 0.5 / (D * 1200.0), 0.0], rtol=1e-14)
    np.testing.assert_allclose(np.asarray(L.friction_inner), [0.0, 0.0])
    assert float(L.max_friction_ratio) == pytest.approx(2 * 0.5 / (D * 1200.0) / 0.05, rel=1e-14)
    # edges: ball 0 inner 40 deg + 2 mm / (f D) = 40 + 9.85 deg, inside 74.1
    hi0 = th_hi - (40 * DEG + 2e-3 / (f * D))
    assert float(L.edge_high_inner[0]) == pytest.approx(hi0, rel=1e-13)
    # ball 1 inner at 70 deg + 4.93 deg runs over 74.1: truncated, centre still on the groove
    assert bool(L.truncated_inner[1]) and not bool(L.over_shoulder_inner[1])
    assert float(L.edge_high_inner[1]) == pytest.approx(th_hi - (70 * DEG + 1e-3 / (f * D)), rel=1e-13)
    # ball 1 outer at -12 deg (beyond the 11.2 deg low edge) carries no load: not flagged
    assert not bool(L.over_shoulder_outer[1]) and float(L.edge_low_outer[1]) == pytest.approx(np.pi)
    assert float(L.edge_low_outer[0]) == pytest.approx(th_lo + 35 * DEG - 2.5e-3 / (f * D), rel=1e-13)
    assert bool(L.any_truncated) and not bool(L.any_over_shoulder)
    # a loaded contact centred beyond the low edge is over the shoulder
    L2 = limits.contact_limits(_state(Q_outer=[1200.0, 10.0], a_outer=[2.5e-3, 1e-4]), b218)
    assert bool(L2.over_shoulder_outer[1]) and bool(L2.any_over_shoulder)


def test_control_hypotheses_put_the_friction_where_the_moment_is_supplied(b218):
    st = _state()
    D = 22.225e-3
    Li = limits.contact_limits(st, b218, "inner")
    np.testing.assert_allclose(np.asarray(Li.friction_inner), 2 * np.array([0.5, 0.4]) / (D * np.array([1000, 500])),
                               rtol=1e-14)
    Le = limits.contact_limits(st, b218, "equal")
    np.testing.assert_allclose(np.asarray(Le.friction_inner), np.array([0.5, 0.4]) / (D * np.array([1000, 500])),
                               rtol=1e-14)
    np.testing.assert_allclose(np.asarray(Le.friction_outer), [0.5 / (D * 1200), 0.0], rtol=1e-14)


def test_limits_of_a_solve_batched(b218):
    """A real state at 10 krpm (pure thrust: identical balls) and a batch of two: shapes follow the
    batch, the friction needed is 2 M_g / (D Q_o) from the solution's own fields."""
    op = bs.Operation.from_rpm(10000.0)
    sol = bs.solve_batch(b218, op, np.array([[0, 0, 17800.0, 0, 0], [0, 0, 8000.0, 0, 0]]))
    assert np.all(np.asarray(sol.result) == 0)
    L = limits.contact_limits(sol, b218, op.control, friction_coefficient=jnp.array([0.1, 0.01]))
    assert L.friction_ratio.shape == (2, 16) and L.any_slip.shape == (2,)
    mu = 2 * np.abs(np.asarray(sol.gyroscopic_moment)) / (22.225e-3 * np.asarray(sol.Q_outer))
    np.testing.assert_allclose(np.asarray(L.friction_outer), mu, rtol=1e-13)
    assert 0.005 < mu.max() < 0.1            # a few hundredths: the hypothesis holds at mu = 0.1
    assert list(np.asarray(L.any_slip)) == [False, True]
    assert not np.any(np.asarray(L.any_over_shoulder))
    # a shoulder set low enough cuts the 17.8 kN contact (alpha_i ~ 50 deg at 10 krpm)
    low = bs.Bearing(16, 22.225e-3, 125.26e-3, 0.5232, 0.5232, 40 * DEG,
                     shoulder_angles=jnp.array([45, 11, 45, 11]) * DEG)
    Llow = limits.contact_limits(sol, low, op.control)
    assert bool(Llow.any_over_shoulder[0])
