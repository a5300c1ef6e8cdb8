"""`bearingsim static` with limits and life (issue 21): the ISO/TS 16281 example as a case file
through the workflow, the JSON and the command line; refusals through the command line."""
import json

import numpy as np
import pytest

from bearingsim.app import workflows
from bearingsim.case import parse_case
from bearingsim.app.cli import main

# docs/reference-data.md, ISO/TS 16281 example 1: deep groove, zero clearance, Fr = 1000 N, C = 23.4 kN
ISO_CASE = """\
title = "ISO/TS 16281 example 1"
[bearing]
balls = 7
ball_diameter_mm = 11.5
pitch_diameter_mm = 43.5
inner_groove_curvature = 0.52
outer_groove_curvature = 0.53
diametral_clearance_mm = 0.0
dynamic_load_rating_kN = 23.4
[material]
youngs_modulus_GPa = 210
[operation]
speed_rpm = 0
centrifugal = false
gyroscopic = false
[load]
radial_x_N = 1000
"""

ACBB = """\
title = "218 at 10 krpm"
[bearing]
balls = 16
ball_diameter_mm = 22.225
pitch_diameter_mm = 125.26
inner_groove_curvature = 0.5232
outer_groove_curvature = 0.5232
free_contact_angle_deg = 40.0
[operation]
speed_rpm = 10000
[load]
axial_N = 17800
"""


def test_iso_example_life_through_the_workflow():
    case = parse_case(ISO_CASE)
    sol = workflows.solve_case(case)
    a = workflows.assess_case(case, sol)
    assert a.nominal_angle == 0.0                     # a deep groove: nominal angle 0
    assert a.rating_life == pytest.approx(13163.019, rel=5e-3)
    assert float(sol.displacement[0]) == pytest.approx(15.1101e-6, rel=5e-3)
    assert a.life_hours is None                       # standstill
    Li, Lo = a.ring_lives
    assert (Li ** (-10 / 9) + Lo ** (-10 / 9)) ** (-0.9) == pytest.approx(a.rating_life, rel=1e-12)
    assert not bool(a.limits.any_truncated) and not bool(a.limits.any_overpressure)


def test_static_prints_and_writes_limits_and_life(tmp_path, capsys):
    p = tmp_path / "iso.toml"
    p.write_text(ISO_CASE.replace("speed_rpm = 0", "speed_rpm = 1000"))
    out = tmp_path / "s.json"
    assert main(["static", str(p), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Limits (docs/model.md section 11)" in text and "L10r = " in text and "h at the case's speed" in text
    d = json.loads(out.read_text())
    life, lim = d["life"], d["limits"]
    assert life["dynamic_load_rating_kN"] == 23.4 and life["nominal_contact_angle_deg"] == 0.0
    # 1000 rpm: hours = L10r 1e6 / 60000
    assert life["L10r_h"] == pytest.approx(life["L10r_Mrev"] * 1e6 / 60000.0, rel=1e-12)
    assert life["L10r_Mrev"] == pytest.approx(13163.0, rel=1e-2)     # ~ the rest value at 1000 rpm
    assert lim["over_shoulder"] is False and len(lim["balls"]["friction_ratio"]) == 7
    assert lim["max_pressure_ratio"] == pytest.approx(max(d["balls"]["p_max_inner_MPa"]) / 4200.0, rel=1e-12)


def test_static_refuses_a_contact_over_the_shoulder(tmp_path, capsys):
    """17.8 kN at 10 krpm puts the 218's inner contacts at ~50 deg: with a 45 deg inner shoulder
    the contact centre is over the edge -> result 8, exit 3, named."""
    p = tmp_path / "c.toml"
    p.write_text(ACBB + "[shoulders]\ninner_high_deg = 45\n")
    assert main(["static", str(p)]) == 3
    err = capsys.readouterr().err
    assert "beyond the edge of its groove" in err and "Fz = 17800 N" in err


def test_static_refuses_reverse_axial_load_naming_it(tmp_path, capsys):
    p = tmp_path / "c.toml"
    p.write_text(ACBB.replace("axial_N = 17800", "axial_N = -10000"))
    assert main(["static", str(p)]) == 3
    err = capsys.readouterr().err
    assert "low shoulders" in err and "Fz = -10000 N" in err and "DB back-to-back" in err


def test_static_refuses_no_load_at_speed(tmp_path, capsys):
    p = tmp_path / "c.toml"
    p.write_text(ACBB.replace("axial_N = 17800", "axial_N = 0"))
    assert main(["static", str(p)]) == 3
    assert "no load on the inner ring at speed" in capsys.readouterr().err


def test_static_refuses_the_random_search_state_with_an_85_deg_contact(tmp_path, capsys):
    """One of the converged states with loaded contacts beyond 75 deg (issue 21: 149 of 3696 random
    cases): the 218 at 12 krpm, 3 kN thrust and 152 N m.  The solver reaches it (alpha_i to 85 deg,
    flagged by limits), `static` refuses it as over the shoulder."""
    p = tmp_path / "c.toml"
    p.write_text(ACBB.replace("speed_rpm = 10000", "speed_rpm = 12000")
                 .replace("axial_N = 17800", "axial_N = 3000\nmoment_y_Nm = 152"))
    assert main(["static", str(p)]) == 3
    assert "beyond the edge of its groove" in capsys.readouterr().err


def test_a_ball_over_a_spall_past_a_shoulder_is_returned_flagged_not_silent():
    """Issue 35 / docs/physics.md section 10a: the one stated exemption of the groove-edge rule.
    A Harris 218 with a 3.28 deg, 0.383 mm outer spall at 10 263 rpm (12.5 kN axial, 21 N radial;
    a random-search state): the ball over the spall drops in and its inner contact turns to
    ~79 deg, past the 74 deg high shoulder, carrying ~460 N.  It is returned as converged (result
    0: the spall-entry state the seed paper studies) and flagged per contact by the limits, on
    that ball only; a script reads ``contact_limits(...).over_shoulder``."""
    import bearingsim as bs
    from bearingsim.case import load_case
    from bearingsim.physics.defect import Spall
    from bearingsim.physics.limits import contact_limits

    b = load_case("demo").bearing()
    sp = Spall(0.0, np.radians(3.284824586199771), 0.3832361174491989e-3, "rectangular", "outer", 0)
    sol = bs.solve(b, bs.Operation.from_rpm(10263.0), bs.Loads(axial=12517.0, radial_x=21.0),
                   cage_angle=-0.018036276649185723, spall=sp, throw=False)
    assert int(sol.result) == 0
    over = np.asarray(contact_limits(sol, b, "outer").over_shoulder)
    assert over[0] and not over[1:].any()                        # ball 0 sits over the spall
    assert np.degrees(float(sol.alpha_inner[0])) > np.degrees(float(b.shoulders[0])) > 70.0
    assert float(sol.Q_inner[0]) > 100.0
