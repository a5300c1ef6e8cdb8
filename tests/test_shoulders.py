"""What one bearing cannot carry (issue 21 item 6): shoulders, a reverse axial load on an angular
contact bearing, no load at speed, the ring-travel bound of a deep groove."""
import numpy as np
import pytest

import bearingsim as bs
from bearingsim.physics import geometry, jones

DEG = np.pi / 180
REST = bs.Operation.from_rpm(0.0)


def test_default_shoulder_angles_from_land_heights(b218):
    """theta = arccos(1 - h / f): the 218 (f = 0.5232) has its high shoulders at 0.38 D -> 74.1
    deg and its low shoulders at 0.01 D -> 11.2 deg; a deep groove (0.2 D) at f = 0.52 -> 52.0."""
    sh = np.degrees(np.asarray(b218.shoulders))
    np.testing.assert_allclose(sh, [74.12, 11.22, 74.12, 11.22], atol=0.01)
    assert bool(b218.angular_contact)
    dg = bs.Bearing.from_clearance(9, 7.94e-3, 39.04e-3, 0.52, 0.52, 12e-6)
    assert not bool(dg.angular_contact) and dg.design == "deep_groove"
    np.testing.assert_allclose(np.degrees(np.asarray(dg.shoulders)), 52.02, atol=0.01)
    # alpha_0 = 0 given directly: "auto" is a deep groove
    assert not bool(bs.Bearing(9, 7.94e-3, 39.04e-3, 0.52, 0.52, 0.0).angular_contact)
    # land height and angle are inverse
    h = geometry.land_height(geometry.shoulder_angle(0.3, 0.53), 0.53)
    assert float(h) == pytest.approx(0.3, rel=1e-14)
    given = bs.Bearing(16, 22.225e-3, 125.26e-3, 0.5232, 0.5232, 40 * DEG,
                       shoulder_angles=np.array([80, 0, 70, 5]) * DEG)
    np.testing.assert_allclose(np.degrees(np.asarray(given.shoulders)), [80, 0, 70, 5], atol=1e-12)
    with pytest.raises(ValueError, match="design"):
        bs.Bearing(16, 22.225e-3, 125.26e-3, 0.5232, 0.5232, 40 * DEG, design="roller")


@pytest.mark.parametrize("rpm, Fz", [(0.0, -71.0), (0.0, -10000.0), (10000.0, -10000.0)])
def test_reverse_axial_load_on_an_angular_contact_bearing_is_refused(b218, rpm, Fz):
    """Before: -10 kN converged with mirrored contact angles (-34..-71 deg at 10 krpm) and exit 0.
    Now: result 7, and the exception names the load and suggests a preloaded pair."""
    op = bs.Operation.from_rpm(rpm)
    sol = bs.solve(b218, op, bs.Loads(axial=Fz), throw=False)
    assert int(sol.result) == bs.RESULTS.low_shoulder
    with pytest.raises(bs.InvalidStateError, match=rf"(?s)low shoulders.*Fz = {Fz:g} N.*DB back-to-back"):
        bs.solve(b218, op, bs.Loads(axial=Fz))


def test_light_reverse_load_with_radial_load_is_refused_for_its_cause(b218):
    """The rest state under 3 kN radial and -71 N axial (the ring slid to the far side: its balls
    sit at -0.2..-2 deg) is refused as a low-shoulder load, and the cause is real: loaded balls
    pushed to -z."""
    op = REST
    sol = bs.solve(b218, op, bs.Loads(axial=-71.0, radial_x=3000.0), throw=False)
    assert int(sol.result) == bs.RESULTS.low_shoulder
    Qi, ai = np.asarray(sol.Q_inner), np.asarray(sol.alpha_inner)
    assert np.any((Qi > 0) & (ai < 0))          # the cause is real: a ball pushed to -z


def test_deep_groove_carries_reverse_axial_load_as_the_mirror_image():
    """A deep groove has full shoulders on both sides: -Fz is the mirror image of +Fz (same ball
    loads, opposite contact angles and axial displacement).  Before, the ring travel bound (A)
    refused the far-side contact (2 A sin alpha_0 of travel) as 'loads exceed the capacity'."""
    b = bs.Bearing.from_clearance(9, 7.94004e-3, 39.0398e-3, 0.52, 0.52, 40e-6)
    plus = bs.solve(b, REST, bs.Loads(axial=71.0))
    minus = bs.solve(b, REST, bs.Loads(axial=-71.0))
    np.testing.assert_allclose(np.asarray(minus.Q_inner), np.asarray(plus.Q_inner), rtol=1e-8)
    np.testing.assert_allclose(np.asarray(minus.alpha_inner), -np.asarray(plus.alpha_inner), rtol=1e-8)
    # the rings travel across the clearance: more than A sin alpha_0 + A
    dz = float(minus.displacement[2])
    assert dz == pytest.approx(-float(plus.displacement[2]) - 2 * float(b.A * np.sin(b.free_contact_angle)),
                               rel=1e-8)


def test_no_load_at_speed_is_refused_at_rest_it_is_the_unloaded_bearing(b218):
    """At speed nothing determines the ring (any position in the clearance is an equilibrium,
    nothing drives the balls): result 9 naming the load.  At rest: q = 0, no ball load."""
    op = bs.Operation.from_rpm(10000.0)
    sol = bs.solve(b218, op, bs.Loads(), throw=False)
    assert int(sol.result) == bs.RESULTS.no_load
    with pytest.raises(bs.InvalidStateError, match=r"(?s)no load.*Fz = 0 N"):
        bs.solve(b218, op, bs.Loads())
    rest = bs.solve(b218, REST, bs.Loads())
    assert int(rest.result) == 0 and float(np.max(np.abs(np.asarray(rest.displacement)))) == 0.0


def test_every_result_code_has_a_cause_and_a_hint():
    for r in jones.RESULTS:
        assert r.message and (r == 0 or r.hint), r
