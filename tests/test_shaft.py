"""A shaft on N bearings (docs/model.md section 10): every check of the section against an independent
truth (the single-bearing solve, the closed form of section 4 at omega = 0, symmetry, statics).

Compiled programs are shared: one N = 1 set program (both facings in one batch), one program for
every rigid two-bearing set of the 218 (DB, DF, DT, loads, speeds, preloads in batches), one
with a spring-preloaded bearing, one two-support rotor, and one single-bearing batch.
"""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bearingsim as bs
from bearingsim.physics import shaft
from bearingsim.errors import InputError
from bearingsim.physics.jones import solve_batch
from conftest import beyond_high_shoulder

D218 = dict(n_balls=16, ball_diameter=22.225e-3, pitch_diameter=125.26e-3, f_inner=0.5232,
            f_outer=0.5232, free_contact_angle=np.deg2rad(40.0))
P = 2000.0          # preload (N)
SPACING = 0.04      # m between the bearings of a pair
M_FLIP = np.diag([1.0, -1.0, -1.0, 1.0, -1.0])


@pytest.fixture(scope="module")
def b218():
    return bs.Bearing(**D218)


@pytest.fixture(scope="module")
def single(b218):
    """Single-bearing truths: a combined load at 10 krpm; thrusts P and F(2e) at rest."""
    e = float(shaft.preload_offset(b218, P))
    F2e = float(shaft.thrust_at_approach(b218, 2.0 * e))
    loads = jnp.array([[3000.0, 1000.0, 8000.0, 50.0, -30.0], [0, 0, P, 0, 0], [0, 0, F2e, 0, 0]])
    op = bs.Operation.from_rpm(jnp.array([10000.0, 0.0, 0.0]))
    sol = solve_batch(b218, op, loads, cage_angle=0.0, throw=True)
    return dict(sol=sol, e=e, F2e=F2e, loads=loads)


ROTOR = dict(z=(0.0, 0.3), zF=0.1, W=4000.0)


@pytest.fixture(scope="module")
def pairs(b218, single):
    """One program, every pair of the 218 (items: see ``cases``)."""
    F2e = single["F2e"]
    base = shaft.BearingSet([b218, b218], [0.0, SPACING], [1, -1], [P, P])
    tilt = [0, 0, 0, 30.0, 0]
    db, z0, rigid = (1, -1), (0.0, SPACING), (0, 0)
    W, zF = ROTOR["W"], ROTOR["zF"]
    cases = {                                   # (facings, preload, loads, rpm, positions, springs)
        "db0": (db, P, [0, 0, 0, 0, 0], 0.0, z0, rigid),
        "db_fz": (db, P, [0, 0, 1500.0, 0, 0], 0.0, z0, rigid),
        "db_below": (db, P, [0, 0, 0.99 * F2e, 0, 0], 0.0, z0, rigid),
        "db_lift": (db, P, [0, 0, F2e, 0, 0], 0.0, z0, rigid),
        "db_above": (db, P, [0, 0, 1.02 * F2e, 0, 0], 0.0, z0, rigid),
        "db_speed": (db, P, [0, 0, 0, 0, 0], 12000.0, z0, rigid),
        "db_speed_fz": (db, P, [500.0, 0, 1500.0, 0, 0], 12000.0, z0, rigid),
        "db_tilt": (db, P, tilt, 0.0, z0, rigid),
        "df_tilt": ((-1, 1), P, tilt, 0.0, z0, rigid),
        "dt": ((1, 1), 0.0, [0, 0, 5000.0, 0, 0], 6000.0, z0, rigid),
        "spring0": (db, P, [0, 0, 0, 0, 0], 0.0, z0, (0, 1)),
        "spring6": (db, P, [0, 0, 0, 0, 0], 6000.0, z0, (0, 1)),
        "spring12": (db, P, [0, 0, 0, 0, 0], 12000.0, z0, (0, 1)),
        # two supports 0.3 m apart, a radial load W at zF (expressed at O: Fx = W, My = zF W)
        "rotor": (db, 200.0, [W, 0, 0, 0, zF * W], 3000.0, ROTOR["z"], rigid),
    }
    names = list(cases)
    col = lambda i: jnp.array([cases[k][i] for k in names], jnp.float64)
    pre = jnp.array([[cases[k][1]] * 2 for k in names])
    op = bs.Operation.from_rpm(col(3))
    sol = shaft.solve_set_batch(base, op, col(2), facings=col(0), preload=pre, positions=col(4),
                                springs=col(5))
    assert np.all(np.asarray(sol.result) == 0), sol.message()
    return {k: _item(sol, i) for i, k in enumerate(names)}


def _item(sol, i):
    import jax
    return jax.tree_util.tree_map(lambda a: a[i], sol)


def test_n1_is_the_single_bearing_and_a_mirrored_bearing_mirrors(b218, single):
    """N = 1, z = 0, s = +1, e = 0 is the single bearing; s = -1 under the mirrored loads (-Fz)
    gives the mirrored state: q_s = M q, ball j at shaft azimuth psi_j is the single bearing's
    ball at -psi_j, stiffness M K M."""
    ref = _item(single["sol"], 0)
    F = single["loads"][0]
    one = shaft.BearingSet([b218], [0.0], [1])
    op = bs.Operation.from_rpm(10000.0)
    sol = shaft.solve_set_batch(one, op, jnp.stack([F, M_FLIP @ F]), facings=jnp.array([[1.0], [-1.0]]))
    assert np.all(np.asarray(sol.result) == 0)
    plus, minus = _item(sol, 0), _item(sol, 1)
    scale = np.max(np.abs(ref.displacement))
    np.testing.assert_allclose(plus.displacement, ref.displacement, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(plus.bearings[0].Q_inner, ref.Q_inner, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(plus.bearings[0].alpha_outer, ref.alpha_outer, rtol=0, atol=1e-10)
    np.testing.assert_allclose(plus.stiffness, ref.stiffness, rtol=1e-8, atol=1e-8 * np.abs(ref.stiffness).max())
    # mirrored: own-frame azimuths -psi_j; ball j <-> single ball (Z - j) % Z at cage angle 0
    Z = b218.n_balls
    back = (-np.arange(Z)) % Z
    np.testing.assert_allclose(minus.displacement, M_FLIP @ np.asarray(ref.displacement), rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(minus.bearings[0].Q_inner, np.asarray(ref.Q_inner)[back], rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(minus.bearings[0].alpha_inner, np.asarray(ref.alpha_inner)[back], rtol=0, atol=1e-10)
    np.testing.assert_allclose(minus.shaft_azimuth(0), np.arange(Z) * 2 * np.pi / Z, atol=1e-15)
    K = M_FLIP @ np.asarray(ref.stiffness) @ M_FLIP
    np.testing.assert_allclose(minus.stiffness, K, rtol=1e-8, atol=1e-8 * np.abs(K).max())
    # the shaft's equilibrium from the bearing's own loads
    np.testing.assert_allclose(minus.shaft_reactions()[0], M_FLIP @ F, rtol=1e-9, atol=1e-6)


def test_preload_offset_is_the_single_bearing_approach(single):
    """e from the closed form equals the single-bearing solve's axial approach under P; F(2e)
    is carried by the single bearing at approach 2e (the solve, not the closed form)."""
    sol = single["sol"]
    np.testing.assert_allclose(sol.displacement[1, 2], single["e"], rtol=1e-9)
    np.testing.assert_allclose(sol.displacement[2, 2], 2.0 * single["e"], rtol=1e-9)
    # catalogues: lift-off at about 3 P; 2^1.5 P for a constant contact angle
    assert 2.0 ** 1.5 < single["F2e"] / P < 3.0


def test_db_pair_at_zero_load(pairs, single):
    """+P and -P with q_s = 0; axial stiffness 2 K_zz of one bearing at P."""
    s = pairs["db0"]
    np.testing.assert_allclose(s.axial_load, [P, P], rtol=1e-10)
    np.testing.assert_allclose(s.shaft_reactions()[:, 2], [P, -P], rtol=1e-10)
    assert np.max(np.abs(s.displacement[:3])) < 1e-15
    np.testing.assert_allclose(s.offset, single["e"], rtol=1e-12)
    Kzz = float(single["sol"].stiffness[1, 2, 2])
    np.testing.assert_allclose(s.stiffness[2, 2], 2.0 * Kzz, rtol=1e-9)
    np.testing.assert_allclose(s.lift_off_margin, [1.0, 1.0], rtol=1e-10)


def test_db_pair_under_axial_load_and_lift_off(pairs, single):
    """R1z - R2z = Fz, the axial approaches sum to 2e, and bearing 2 unloads at F(2e)."""
    e = single["e"]
    for k in ("db_fz", "db_below", "db_lift", "db_above"):
        s = pairs[k]
        Fz = float(s.loads[2])
        R = s.axial_load
        np.testing.assert_allclose(R[0] - R[1], Fz, rtol=1e-10)
        q1, q2 = s.bearings[0].displacement[2], s.bearings[1].displacement[2]
        np.testing.assert_allclose(q1 + q2, 2.0 * e, rtol=1e-12)
    assert float(pairs["db_below"].axial_load[1]) > 1e-3 * P
    assert abs(float(pairs["db_lift"].axial_load[1])) < 1e-6 * P
    assert float(pairs["db_above"].axial_load[1]) == 0.0
    # beyond lift-off bearing 1 alone carries the load: its approach exceeds 2e
    assert float(pairs["db_above"].bearings[0].displacement[2]) > 2.0 * e


def test_rigid_preload_changes_with_speed_symmetrically(pairs):
    """A rigid offset held at 12 krpm: both bearings carry the same (changed) axial load, the
    shaft stays at q_s = 0; under external load equilibrium still holds."""
    s = pairs["db_speed"]
    R = np.asarray(s.axial_load)
    np.testing.assert_allclose(R[0], R[1], rtol=1e-10)
    assert abs(R[0] - P) > 0.1 * P
    assert np.max(np.abs(s.displacement[:3])) < 1e-14
    s = pairs["db_speed_fz"]
    np.testing.assert_allclose(np.sum(np.asarray(s.shaft_reactions()), axis=0), s.loads,
                               rtol=0, atol=1e-7 * float(np.max(np.abs(s.bearings[0].Q_inner))))


def test_db_tilt_stiffer_than_df_and_tandem_shares(pairs):
    """DB tilt stiffness > DF (pressure centres outside / inside the pair); DT shares Fz."""
    kdb = np.asarray(pairs["db_tilt"].stiffness)
    kdf = np.asarray(pairs["df_tilt"].stiffness)
    assert kdb[3, 3] > 1.5 * kdf[3, 3] and kdb[4, 4] > 1.5 * kdf[4, 4]
    # same preload, same axial stiffness (the tilt differs through the pressure centres)
    np.testing.assert_allclose(pairs["db_tilt"].stiffness[2, 2], pairs["df_tilt"].stiffness[2, 2], rtol=1e-2)
    dt = pairs["dt"]
    np.testing.assert_allclose(dt.axial_load, [2500.0, 2500.0], rtol=1e-10)


def test_spring_preload_constant_at_every_speed(pairs, single):
    """A spring-preloaded bearing carries P at every speed; the set's axial stiffness is then the
    rigid bearing's alone (the floating ring adds none): K_zz of one bearing at P at rest."""
    for k in ("spring0", "spring6", "spring12"):
        np.testing.assert_allclose(pairs[k].axial_load, [P, P], rtol=1e-10)
    np.testing.assert_allclose(pairs["spring0"].stiffness[2, 2], single["sol"].stiffness[1, 2, 2], rtol=1e-9)
    u = [float(pairs[k].spring_shift[1]) for k in ("spring0", "spring6", "spring12")]
    # u is measured from the touching position (e_k = 0 for a spring bearing): -e at rest
    np.testing.assert_allclose(u[0], -single["e"], rtol=1e-9)
    assert u[2] > u[1] > 1e-5             # the ring floats out as speed rises
    assert float(pairs["spring0"].spring_shift[0]) == 0.0


def test_two_supports_lever_rule(pairs):
    """Two supports 0.3 m apart, a radial load between them: the radial reactions obey statics
    including the bearings' own (small) moments; neglecting those (bearings that carry no moment)
    gives the lever rule, to within the moments they do carry."""
    s = pairs["rotor"]
    (z1, z2), zF, W = ROTOR["z"], ROTOR["zF"], ROTOR["W"]
    R = np.asarray(s.shaft_reactions())
    own_My = np.array([float(s.bearings[0].loads[4]), -float(s.bearings[1].loads[4])])  # shaft frame
    np.testing.assert_allclose(R[:, 0].sum(), W, rtol=1e-10)
    np.testing.assert_allclose(R[1, 0] * (z2 - z1) + own_My.sum(), W * (zF - z1), rtol=1e-9)
    # the lever rule, corrected by exactly the moments the (angular contact) supports carry
    lever = np.array([W * (z2 - zF), W * (zF - z1)]) / (z2 - z1)
    m = own_My.sum() / (z2 - z1)
    np.testing.assert_allclose(R[:, 0], lever + np.array([m, -m]), rtol=1e-9)


def test_set_input_checks(b218):
    with pytest.raises(InputError, match="did you mean"):
        shaft.arrangement_facings("BD")
    with pytest.raises(InputError, match="cannot carry a preload"):
        shaft.BearingSet.arrangement("DT", b218, SPACING, P)
    with pytest.raises(InputError, match="do not balance"):
        shaft.BearingSet([b218, b218], [0.0, SPACING], [1, -1], [P, 2 * P]).check_balance()
    with pytest.raises(InputError, match="spring preload"):
        shaft.BearingSet([b218, b218], [0.0, SPACING], [1, -1], [P, P], springs=[True, True])
    s = shaft.BearingSet.arrangement("TBT", b218, SPACING, 3000.0)
    np.testing.assert_allclose(s.preload, [1500.0, 1500.0, 3000.0])
    s.check_balance()


def test_defect_in_one_bearing_swept_over_the_cage_angle(b218):
    """An outer-raceway spall in bearing 1 of a DB pair under a radial load, swept over one ball
    pitch of bearing 1's cage: when a loaded ball of bearing 1 drops into the spall, bearing 1
    carries less of the radial load and bearing 2 (healthy) takes it up; the shaft's equilibrium
    holds at every angle, and the healthy set is recovered away from the spall.  The spall's
    centre is given in the shaft frame (psi = 0, the most loaded azimuth of both bearings)."""
    from bearingsim.physics.defect import Spall
    bset = shaft.BearingSet([b218, b218], [0.0, SPACING], [1, -1], [P, P])
    spall = Spall(0.0, np.deg2rad(12.0), 0.3e-3, "ball-path")
    Z = b218.n_balls
    th = np.linspace(-np.pi / Z, np.pi / Z, 9)
    n = th.size
    F = jnp.array([6000.0, 0.0, 0.0, 0.0, 0.0])
    sol = shaft.solve_set_batch(bset, bs.Operation.from_rpm(3000.0), jnp.tile(F, (n, 1)),
                                cage_angle=jnp.stack([th, np.zeros(n)], axis=1), spalls=(spall, None))
    # with ball 0 over the 0.3 mm spall its inner contact (a few N) lies beyond bearing 1's 74 deg
    # inner shoulder at some angles: refused (result 8, issue 27), confirmed from the per-ball
    # angles; the states are still the solver's own and the shaft's equilibrium is checked on all
    codes = np.asarray(sol.result)
    assert set(np.unique(codes)) <= {0, 8} and codes[0] == 0 and codes[-1] == 0, sol.message()
    for k in np.flatnonzero(codes == 8):
        assert int(np.asarray(sol.bearing_result)[k, 1]) == 0
        assert beyond_high_shoulder(b218, jax.tree_util.tree_map(lambda a: a[k], sol.bearings[0]))
    R = np.asarray(sol.shaft_reactions())                     # (n, 2, 5)
    np.testing.assert_allclose(R.sum(axis=1)[:, 0], 6000.0, rtol=1e-9)
    share1 = R[:, 0, 0]
    mid = n // 2                                              # ball 0 of bearing 1 over the spall centre
    assert share1[mid] < share1[0] - 5.0 and share1[mid] < share1[-1] - 5.0    # ~20 N of ~3.8 kN
    assert R[mid, 1, 0] > R[0, 1, 0] + 5.0                     # the partner takes it up
    assert float(sol.bearings[0].Q_outer[mid, 0]) < 0.5 * float(sol.bearings[1].Q_outer[mid, 0])
