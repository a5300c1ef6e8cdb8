"""Case files: schema validation, defaults, unit conversion, TOML round trip, shipped cases."""
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

import bearingsim
from bearingsim.case import (
    SCHEMA,
    Case,
    CaseError,
    case_from_dict,
    load_case,
    parse_case,
    schema_reference_markdown,
    to_toml,
)

CASES_DIR = Path(__file__).resolve().parents[1] / "cases"

EXAMPLE = """\
title = "Harris 218 angular contact ball bearing"
[bearing]
balls = 16
ball_diameter_mm = 22.225
pitch_diameter_mm = 125.26
inner_groove_curvature = 0.5232     # f_i = r_i / D
outer_groove_curvature = 0.5232     # f_o = r_o / D
free_contact_angle_deg = 40.0
[material]
youngs_modulus_GPa = 207.5
poisson_ratio = 0.3
density_kg_m3 = 7850
[operation]
speed_rpm = 10000
raceway_control = "outer"
centrifugal = true
gyroscopic = true
cage_angle_deg = 0.0
hertz = "exact"
[load]
axial_N = 22250
radial_x_N = 0
radial_y_N = 0
moment_x_Nm = 0
moment_y_Nm = 0
[defect]
center_deg = 0.0
extent_deg = 8.0
depth_mm = 0.3
profile = "ball-path"
[sweep]
start_deg = 0.0
stop_deg = 22.5
steps = 181
[study]
parameter = "operation.speed_rpm"
values = [0, 5000, 10000, 15000]
[dynamics]
duration_s = 1.0
sample_rate_Hz = 48000
"""

MINIMAL = """\
[bearing]
balls = 16
ball_diameter_mm = 22.225
pitch_diameter_mm = 125.26
inner_groove_curvature = 0.5232
outer_groove_curvature = 0.5232
free_contact_angle_deg = 40.0
[operation]
speed_rpm = 10000
"""


def edit(text, old, new):
    """Replace one line fragment of a case text (the fragment must be there)."""
    assert old in text, old
    return text.replace(old, new)


def problems(text, source="cases/x.toml"):
    with pytest.raises(CaseError) as info:
        parse_case(text, source)
    return str(info.value).splitlines()


def one_problem(text, source="cases/x.toml"):
    lines = problems(text, source)
    assert len(lines) == 1, lines
    return lines[0]


# ----------------------------------------------------------------------------------------------
# valid input, defaults
# ----------------------------------------------------------------------------------------------
def test_example_parses():
    c = parse_case(EXAMPLE, "example.toml")
    assert isinstance(c, Case)
    assert c.title == "Harris 218 angular contact ball bearing"
    assert c.source == "example.toml"
    assert c.text == EXAMPLE
    assert c.get("bearing.balls") == 16
    assert c.get("material.density_kg_m3") == 7850.0
    assert isinstance(c.get("material.density_kg_m3"), float)  # int accepted for float, normalised
    assert c.get("defect.profile") == "ball-path"
    assert c.study_settings() == ("operation.speed_rpm", [0, 5000, 10000, 15000])


def test_defaults_filled_in():
    c = parse_case(MINIMAL)
    d = c.data
    assert d["title"] == ""
    assert d["material"] == {"youngs_modulus_GPa": 207.5, "poisson_ratio": 0.3, "density_kg_m3": 7850.0}
    assert "ball" not in d["material"]
    assert d["operation"] == {"speed_rpm": 10000.0, "raceway_control": "outer", "centrifugal": True,
                              "gyroscopic": True, "cage_angle_deg": 0.0, "hertz": "exact", "tilt": "free"}
    assert d["load"] == {"axial_N": 0.0, "radial_x_N": 0.0, "radial_y_N": 0.0,
                         "moment_x_Nm": 0.0, "moment_y_Nm": 0.0}
    assert d["sweep"] == {"start_deg": 0.0, "stop_deg": 22.5, "steps": 181}
    assert {k: d["dynamics"][k] for k in ("duration_s", "sample_rate_Hz")} == {"duration_s": 1.0, "sample_rate_Hz": 48000.0}
    assert d["dynamics"]["resonance_frequency_Hz"] == 3000.0 and d["dynamics"]["unbalance_kg_m"] == 0.0
    assert "defect" not in d and "study" not in d
    assert c.spall() is None
    assert c.study_settings() is None
    assert c.hertz_method == "exact"
    assert c.get("defect.depth_mm") is None            # schema key, section absent
    assert c.get("bearing.diametral_clearance_mm") is None  # the unused one of the pair
    sw = c.sweep_settings()
    assert sw["start"] == 0.0 and sw["steps"] == 181
    assert sw["stop"] == pytest.approx(2 * math.pi / 16, rel=1e-15)
    assert {k: c.dynamics_settings()[k] for k in ("duration", "sample_rate")} == {"duration": 1.0, "sample_rate": 48000.0}


def test_defect_defaults():
    c = parse_case(MINIMAL + "[defect]\nextent_deg = 5\ndepth_mm = 0.1\n")
    assert c.data["defect"] == {"location": "outer", "center_deg": 0.0, "extent_deg": 5.0, "depth_mm": 0.1,
                                "profile": "ball-path"}


def test_sweep_stop_default_follows_start_and_balls():
    c = parse_case(MINIMAL + "[sweep]\nstart_deg = 10\n")
    assert c.get("sweep.stop_deg") == pytest.approx(10 + 22.5)
    c9 = c.with_value("bearing.balls", 9)
    assert c9.get("sweep.stop_deg") == pytest.approx(10 + 40.0)
    assert c9.sweep_settings()["stop"] == pytest.approx(math.radians(50.0))


# ----------------------------------------------------------------------------------------------
# unknown names
# ----------------------------------------------------------------------------------------------
def test_unknown_key_did_you_mean():
    lines = problems(edit(MINIMAL, "ball_diameter_mm", "ball_diamter_mm"), "cases/x.toml")
    line = lines[0]
    assert line.startswith("cases/x.toml: ")
    assert "'ball_diamter_mm'" in line and "[bearing]" in line
    assert "did you mean 'ball_diameter_mm'?" in line
    # the intended key is then missing, and says so
    assert lines[1:] == ["cases/x.toml: missing required key bearing.ball_diameter_mm: must be > 0 mm "
                         "(ball diameter D)"]


def test_unknown_section_did_you_mean():
    lines = problems(MINIMAL + "[lod]\naxial_N = 3\n")
    assert any("unknown section [lod]" in l and "did you mean 'load'?" in l for l in lines), lines


def test_unknown_top_level_key_did_you_mean():
    line = one_problem('titel = "x"\n' + MINIMAL)
    assert "'titel'" in line and "did you mean 'title'?" in line


def test_unknown_key_without_close_match_lists_valid_names():
    line = one_problem(MINIMAL + "[dynamics]\nzzz = 1\n")
    assert "valid names: duration_s, sample_rate_Hz" in line


def test_unknown_subsection():
    line = one_problem(MINIMAL + "[material.bal]\npoisson_ratio = 0.26\n")
    assert "unknown section [material.bal]" in line and "did you mean 'ball'?" in line


def test_enum_value_did_you_mean():
    line = one_problem(edit(MINIMAL, "speed_rpm = 10000", 'speed_rpm = 10000\nraceway_control = "outr"'))
    assert 'operation.raceway_control = "outr" is not allowed' in line
    assert '"outer", "inner", "equal"' in line and 'did you mean "outer"?' in line


def test_hertz_option():
    c = parse_case(edit(MINIMAL, "speed_rpm = 10000", 'speed_rpm = 10000\nhertz = "brewe-hamrock"'))
    assert c.hertz_method == "brewe-hamrock"
    line = one_problem(edit(MINIMAL, "speed_rpm = 10000", 'speed_rpm = 10000\nhertz = "hamrock"'))
    assert "operation.hertz" in line and '"exact", "brewe-hamrock"' in line


def test_section_given_as_value_and_value_as_table():
    line = one_problem("dynamics = 3\n" + MINIMAL)
    assert "[dynamics] must be a table" in line
    line = one_problem(edit(MINIMAL, "balls = 16", "balls = {n = 16}"))
    assert "bearing.balls must be a value" in line


# ----------------------------------------------------------------------------------------------
# types
# ----------------------------------------------------------------------------------------------
def test_bool_is_not_a_number():
    line = one_problem(edit(MINIMAL, "ball_diameter_mm = 22.225", "ball_diameter_mm = true"))
    assert "bearing.ball_diameter_mm = true has the wrong type: expected a number, got a boolean" in line


def test_string_is_not_a_number():
    line = one_problem(edit(MINIMAL, "speed_rpm = 10000", 'speed_rpm = "10000"'))
    assert 'operation.speed_rpm = "10000" has the wrong type: expected a number, got a string' in line


def test_float_is_not_an_integer():
    line = one_problem(edit(MINIMAL, "balls = 16", "balls = 16.0"))
    assert "bearing.balls = 16.0 has the wrong type: expected an integer, got a float" in line


def test_int_accepted_for_float():
    c = parse_case(edit(MINIMAL, "ball_diameter_mm = 22.225", "ball_diameter_mm = 22"))
    assert c.get("bearing.ball_diameter_mm") == 22.0 and isinstance(c.get("bearing.ball_diameter_mm"), float)


def test_bool_key_rejects_number():
    line = one_problem(edit(MINIMAL, "speed_rpm = 10000", "speed_rpm = 10000\ncentrifugal = 1"))
    assert "operation.centrifugal = 1 has the wrong type: expected a boolean" in line


def test_non_finite_float_rejected():
    line = one_problem(edit(MINIMAL, "speed_rpm = 10000", "speed_rpm = nan"))
    assert "operation.speed_rpm = nan is not a finite number" in line


def test_invalid_toml_is_a_case_error():
    line = one_problem("[bearing\nballs = 3\n", "cases/broken.toml")
    assert line.startswith("cases/broken.toml: invalid TOML")


# ----------------------------------------------------------------------------------------------
# ranges (message names key, value, allowed range with unit)
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("old, new, expected", [
    ("balls = 16", "balls = 2", "bearing.balls = 2 is out of range: must be an integer >= 3"),
    ("ball_diameter_mm = 22.225", "ball_diameter_mm = 0",
     "bearing.ball_diameter_mm = 0 is out of range: must be > 0 mm"),
    ("inner_groove_curvature = 0.5232", "inner_groove_curvature = 0.5",
     "bearing.inner_groove_curvature = 0.5 is out of range: must be > 0.5 and < 1"),
    ("outer_groove_curvature = 0.5232", "outer_groove_curvature = 1.0",
     "bearing.outer_groove_curvature = 1.0 is out of range: must be > 0.5 and < 1"),
    ("free_contact_angle_deg = 40.0", "free_contact_angle_deg = 85",
     "bearing.free_contact_angle_deg = 85 is out of range: must be >= 0 and <= 80 deg"),
    ("free_contact_angle_deg = 40.0", "free_contact_angle_deg = -1",
     "bearing.free_contact_angle_deg = -1 is out of range: must be >= 0 and <= 80 deg"),
    ("free_contact_angle_deg = 40.0", "diametral_clearance_mm = -0.01",
     "bearing.diametral_clearance_mm = -0.01 is out of range: must be >= 0 mm"),
    ("speed_rpm = 10000", "speed_rpm = -1", "operation.speed_rpm = -1 is out of range: must be >= 0 rpm"),
])
def test_out_of_range(old, new, expected):
    line = one_problem(edit(MINIMAL, old, new), "cases/x.toml")
    assert line == f"cases/x.toml: {expected}"


def test_ball_count_message_exact():
    assert one_problem(edit(MINIMAL, "balls = 16", "balls = 2")) == \
        "cases/x.toml: bearing.balls = 2 is out of range: must be an integer >= 3"


@pytest.mark.parametrize("extra, expected", [
    ("[material]\npoisson_ratio = 0.5\n", "material.poisson_ratio = 0.5 is out of range: must be >= 0 and < 0.5"),
    ("[material]\nyoungs_modulus_GPa = 0\n", "material.youngs_modulus_GPa = 0 is out of range: must be > 0 GPa"),
    ("[material]\ndensity_kg_m3 = -1\n", "material.density_kg_m3 = -1 is out of range: must be > 0 kg/m^3"),
    ("[defect]\nextent_deg = 5\ndepth_mm = -0.1\n", "defect.depth_mm = -0.1 is out of range: must be >= 0 mm"),
    ("[defect]\nextent_deg = 0\ndepth_mm = 0.1\n", "defect.extent_deg = 0 is out of range: must be > 0 deg"),
    ("[defect]\nlength_mm = 0\ndepth_mm = 0.1\n", "defect.length_mm = 0 is out of range: must be > 0 mm"),
    ("[sweep]\nsteps = 1\n", "sweep.steps = 1 is out of range: must be an integer >= 2"),
    ("[dynamics]\nduration_s = 0\n", "dynamics.duration_s = 0 is out of range: must be > 0 s"),
    ("[dynamics]\nsample_rate_Hz = -48000\n",
     "dynamics.sample_rate_Hz = -48000 is out of range: must be > 0 Hz"),
])
def test_out_of_range_optional_sections(extra, expected):
    assert one_problem(MINIMAL + extra) == f"cases/x.toml: {expected}"


# ----------------------------------------------------------------------------------------------
# required keys and sections
# ----------------------------------------------------------------------------------------------
def test_missing_required_key():
    line = one_problem(edit(MINIMAL, "pitch_diameter_mm = 125.26\n", ""))
    assert "missing required key bearing.pitch_diameter_mm" in line and "> 0 mm" in line


def test_missing_required_section():
    text = MINIMAL.split("[operation]")[0]
    assert one_problem(text) == "cases/x.toml: missing required section [operation]"


def test_defect_depth_required():
    line = one_problem(MINIMAL + "[defect]\nextent_deg = 5\n")
    assert "missing required key defect.depth_mm" in line


def test_hybrid_material_needs_all_three_keys():
    lines = problems(MINIMAL + "[material.ball]\nyoungs_modulus_GPa = 310\n")
    assert len(lines) == 2
    assert "material.ball.poisson_ratio" in lines[0] and "material.ball.density_kg_m3" in lines[1]


# ----------------------------------------------------------------------------------------------
# exactly-one rules, both ways
# ----------------------------------------------------------------------------------------------
def test_contact_angle_and_clearance_both_given():
    line = one_problem(edit(MINIMAL, "free_contact_angle_deg = 40.0",
                            "free_contact_angle_deg = 40.0\ndiametral_clearance_mm = 0.1"))
    assert "exactly one of bearing.free_contact_angle_deg or bearing.diametral_clearance_mm" in line
    assert "not both" in line


def test_contact_angle_and_clearance_neither_given():
    line = one_problem(edit(MINIMAL, "free_contact_angle_deg = 40.0\n", ""))
    assert "missing key: give exactly one of bearing.free_contact_angle_deg or " \
           "bearing.diametral_clearance_mm" in line


def test_extent_and_length_both_given():
    line = one_problem(MINIMAL + "[defect]\nextent_deg = 5\nlength_mm = 2\ndepth_mm = 0.1\n")
    assert "exactly one of defect.extent_deg or defect.length_mm, not both" in line


def test_extent_and_length_neither_given():
    line = one_problem(MINIMAL + "[defect]\ndepth_mm = 0.1\n")
    assert "missing key: give exactly one of defect.extent_deg or defect.length_mm" in line


# ----------------------------------------------------------------------------------------------
# geometric and cross-key consistency
# ----------------------------------------------------------------------------------------------
def test_pitch_diameter_must_exceed_ball_diameter():
    line = one_problem(edit(MINIMAL, "pitch_diameter_mm = 125.26", "pitch_diameter_mm = 20"))
    assert line == ("cases/x.toml: bearing.pitch_diameter_mm = 20 must be greater than "
                    "bearing.ball_diameter_mm = 22.225")


def test_balls_must_fit_around_pitch_circle():
    line = one_problem(edit(MINIMAL, "balls = 16", "balls = 18"))
    # 125.26 sin(pi/18) = 21.75 mm < 22.225 mm: 18 balls overlap, 17 fit
    assert "bearing.balls = 18" in line and "overlap" in line
    assert "sin(180 deg / balls) = 21.75" in line and "at most 17 balls" in line
    parse_case(edit(MINIMAL, "balls = 16", "balls = 17"))


def test_clearance_too_large():
    # B D = 0.0464 * 22.225 mm; alpha0 <= 80 deg means P_d <= 2 B D (1 - cos 80 deg) = 1.70433 mm
    text = edit(MINIMAL, "free_contact_angle_deg = 40.0", "diametral_clearance_mm = 1.8")
    line = one_problem(text)
    assert "bearing.diametral_clearance_mm = 1.8 is too large" in line and "<= 2 B D" in line
    assert "1.70433 mm" in line
    parse_case(edit(MINIMAL, "free_contact_angle_deg = 40.0", "diametral_clearance_mm = 1.7"))


def test_spall_longer_than_ball_pitch_extent():
    line = one_problem(MINIMAL + "[defect]\nextent_deg = 30\ndepth_mm = 0.3\n")
    assert line == ("cases/x.toml: defect.extent_deg = 30 is longer than the ball pitch 22.5 deg: "
                    "only one ball at a time may be over the spall")
    # equal to the pitch is also rejected: two balls would sit on the edges at once
    assert "longer than the ball pitch" in one_problem(MINIMAL + "[defect]\nextent_deg = 22.5\ndepth_mm = 0.3\n")


def test_spall_longer_than_ball_pitch_length():
    # R_o = (125.26 + 22.225 cos 40 deg) / 2 = 71.1427 mm; pitch arc = 22.5 deg -> 27.94 mm
    line = one_problem(MINIMAL + "[defect]\nlength_mm = 28\ndepth_mm = 0.3\n")
    assert "defect.length_mm = 28 is longer than the ball pitch 22.5 deg = 27.9377 mm" in line
    assert "only one ball at a time may be over the spall" in line
    parse_case(MINIMAL + "[defect]\nlength_mm = 27.9\ndepth_mm = 0.3\n")


def test_spall_depth_less_than_ball_diameter():
    line = one_problem(MINIMAL + "[defect]\nextent_deg = 5\ndepth_mm = 22.225\n")
    assert line == ("cases/x.toml: defect.depth_mm = 22.225 must be less than the ball diameter "
                    "bearing.ball_diameter_mm = 22.225")


def test_sweep_stop_must_differ_from_start():
    line = one_problem(MINIMAL + "[sweep]\nstart_deg = 5\nstop_deg = 5.0\n")
    assert line == "cases/x.toml: sweep.stop_deg = 5.0 must differ from sweep.start_deg = 5"
    c = parse_case(MINIMAL + "[sweep]\nstart_deg = 5\nstop_deg = -5\n")  # backwards is fine
    assert c.sweep_settings()["stop"] == pytest.approx(math.radians(-5))


# ----------------------------------------------------------------------------------------------
# study
# ----------------------------------------------------------------------------------------------
def test_study_unknown_parameter_did_you_mean():
    line = one_problem(MINIMAL + '[study]\nparameter = "operation.sped_rpm"\nvalues = [1]\n')
    assert 'study.parameter = "operation.sped_rpm" is not a key' in line
    assert "did you mean 'operation.speed_rpm'?" in line


def test_study_parameter_must_be_numeric():
    line = one_problem(MINIMAL + '[study]\nparameter = "operation.raceway_control"\nvalues = [1]\n')
    assert "must name a numeric key" in line


def test_study_parameter_in_absent_section():
    line = one_problem(MINIMAL + '[study]\nparameter = "defect.depth_mm"\nvalues = [0.1]\n')
    assert "[defect], which this case does not have" in line


def test_study_values_non_empty():
    line = one_problem(MINIMAL + '[study]\nparameter = "operation.speed_rpm"\nvalues = []\n')
    assert "study.values is empty" in line


def test_study_values_validated_with_the_keys_rules():
    lines = problems(MINIMAL + '[study]\nparameter = "operation.speed_rpm"\nvalues = [0, -5, true]\n')
    assert lines == [
        "cases/x.toml: study.values[1]: operation.speed_rpm = -5 is out of range: must be >= 0 rpm",
        "cases/x.toml: study.values[2]: operation.speed_rpm = true has the wrong type: "
        "expected a number, got a boolean",
    ]


def test_study_values_keep_the_case_consistent():
    # 18 balls of 22.225 mm do not fit on 125.26 mm: caught although 18 >= 3
    line = one_problem(MINIMAL + '[study]\nparameter = "bearing.balls"\nvalues = [12, 18]\n')
    assert line.startswith("cases/x.toml: study.values[1] (bearing.balls = 18): bearing.balls = 18")
    assert "overlap" in line


def test_study_cases():
    c = parse_case(EXAMPLE)
    runs = c.study_cases()
    assert [r.get("operation.speed_rpm") for r in runs] == [0.0, 5000.0, 10000.0, 15000.0]
    assert all(r.study_settings() is None for r in runs)
    assert float(runs[1].operation().speed) == pytest.approx(5000 * 2 * math.pi / 60)


def test_study_over_the_other_member_of_a_pair():
    c = parse_case(MINIMAL + '[study]\nparameter = "bearing.diametral_clearance_mm"\nvalues = [0, 0.05]\n')
    runs = c.study_cases()
    assert runs[1].get("bearing.free_contact_angle_deg") is None
    assert runs[1].get("bearing.diametral_clearance_mm") == 0.05


# ----------------------------------------------------------------------------------------------
# several problems at once
# ----------------------------------------------------------------------------------------------
def test_all_problems_reported_together():
    text = """\
titel = "x"
[bearing]
balls = 2
ball_diameter_mm = true
pitch_diameter_mm = 125.26
inner_groove_curvature = 0.5
outer_groove_curvature = 0.5232
free_contact_angle_deg = 40.0
diametral_clearance_mm = 0.1
[operation]
speed_rpm = -5
[lod]
axial_N = 1
[dynamics]
duration_s = 0
"""
    with pytest.raises(CaseError) as info:
        parse_case(text, "cases/many.toml")
    err = info.value
    assert isinstance(err, ValueError)
    lines = str(err).splitlines()
    assert len(lines) == len(err.problems) == 8
    assert all(l.startswith("cases/many.toml: ") for l in lines)
    joined = "\n".join(lines)
    for fragment in ["'titel'", "[lod]", "bearing.balls = 2", "bearing.ball_diameter_mm = true",
                     "bearing.inner_groove_curvature = 0.5", "not both", "operation.speed_rpm = -5",
                     "dynamics.duration_s = 0"]:
        assert fragment in joined, fragment
    assert err.source == "cases/many.toml"


def test_load_case_prefixes_file_name(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text(edit(MINIMAL, "balls = 16", "balls = 2"))
    with pytest.raises(CaseError) as info:
        load_case(p)
    assert str(info.value).startswith(f"{p}: bearing.balls = 2 is out of range")


# ----------------------------------------------------------------------------------------------
# SI conversion
# ----------------------------------------------------------------------------------------------
def test_bearing_si():
    b = parse_case(EXAMPLE).bearing()
    assert isinstance(b, bearingsim.Bearing)
    assert b.n_balls == 16
    np.testing.assert_allclose(float(b.ball_diameter), 22.225e-3, rtol=1e-15)
    np.testing.assert_allclose(float(b.pitch_diameter), 125.26e-3, rtol=1e-15)
    assert float(b.f_inner) == 0.5232 and float(b.f_outer) == 0.5232
    np.testing.assert_allclose(float(b.free_contact_angle), 40 * math.pi / 180, rtol=1e-15)
    for m in (b.ring_material, b.ball_material):
        assert float(m.youngs_modulus) == 207.5e9
        assert float(m.poisson_ratio) == 0.3
        assert float(m.density) == 7850.0


def test_bearing_from_clearance():
    c = parse_case(edit(MINIMAL, "free_contact_angle_deg = 40.0", "diametral_clearance_mm = 0.5"))
    b = c.bearing()
    B, D = 0.0464, 22.225e-3
    np.testing.assert_allclose(float(b.free_contact_angle), math.acos(1 - 0.5e-3 / (2 * B * D)), rtol=1e-12)
    np.testing.assert_allclose(float(b.diametral_clearance), 0.5e-3, rtol=1e-12)


def test_hybrid_materials():
    c = parse_case(MINIMAL + "[material.ball]\nyoungs_modulus_GPa = 310\npoisson_ratio = 0.26\n"
                             "density_kg_m3 = 3200\n")
    b = c.bearing()
    assert float(b.ball_material.youngs_modulus) == 310e9
    assert float(b.ball_material.poisson_ratio) == 0.26
    assert float(b.ball_material.density) == 3200.0
    assert float(b.ring_material.youngs_modulus) == 207.5e9
    assert float(b.ring_material.density) == 7850.0
    assert c.get("material.ball.density_kg_m3") == 3200.0


def test_operation_si():
    text = edit(MINIMAL, "speed_rpm = 10000", 'speed_rpm = 6000\nraceway_control = "inner"\n'
                                               "centrifugal = false\ngyroscopic = true\ncage_angle_deg = 90")
    c = parse_case(text)
    op = c.operation()
    assert isinstance(op, bearingsim.Operation)
    np.testing.assert_allclose(float(op.speed), 6000 * 2 * math.pi / 60, rtol=1e-15)
    assert op.control == "inner"
    assert float(op.centrifugal) == 0.0 and float(op.gyroscopic) == 1.0
    assert c.cage_angle == pytest.approx(math.pi / 2, rel=1e-15)


def test_loads_vector_order():
    text = MINIMAL + "[load]\naxial_N = 3\nradial_x_N = 1\nradial_y_N = 2\nmoment_x_Nm = 4\nmoment_y_Nm = 5\n"
    v = parse_case(text).loads()
    assert v.dtype == np.float64
    np.testing.assert_array_equal(np.asarray(v), [1.0, 2.0, 3.0, 4.0, 5.0])  # [Fx, Fy, Fz, Mx, My]
    np.testing.assert_array_equal(np.asarray(parse_case(MINIMAL).loads()), np.zeros(5))


def test_spall_from_extent():
    s = parse_case(EXAMPLE).spall()
    assert isinstance(s, bearingsim.Spall)
    np.testing.assert_allclose(float(s.center), 0.0)
    np.testing.assert_allclose(float(s.extent), math.radians(8.0), rtol=1e-15)
    np.testing.assert_allclose(float(s.depth), 0.3e-3, rtol=1e-15)
    assert s.profile == "ball-path"


def test_spall_from_length():
    c = parse_case(MINIMAL + '[defect]\ncenter_deg = 180\nlength_mm = 2.0\ndepth_mm = 0.2\n'
                             'profile = "rectangular"\n')
    b, s = c.bearing(), c.spall()
    R_o = 0.5 * (125.26e-3 + 22.225e-3 * math.cos(math.radians(40)))
    np.testing.assert_allclose(float(s.extent), 2.0e-3 / R_o, rtol=1e-12)
    np.testing.assert_allclose(float(s.length(b)), 2.0e-3, rtol=1e-12)
    np.testing.assert_allclose(float(s.center), math.pi, rtol=1e-15)
    assert s.profile == "rectangular"


def test_sweep_and_dynamics_si():
    c = parse_case(EXAMPLE)
    assert c.sweep_settings() == {"start": 0.0, "stop": pytest.approx(math.radians(22.5)), "steps": 181}
    assert {k: c.dynamics_settings()[k] for k in ("duration", "sample_rate")} == {"duration": 1.0, "sample_rate": 48000.0}


# ----------------------------------------------------------------------------------------------
# with_value, TOML emitter
# ----------------------------------------------------------------------------------------------
def test_with_value_round_trips_through_toml():
    c = parse_case(EXAMPLE, "example.toml")
    c2 = c.with_value("operation.speed_rpm", 5000)
    assert c.get("operation.speed_rpm") == 10000.0  # the original is unchanged
    assert c2.get("operation.speed_rpm") == 5000.0
    assert c2.source == "example.toml with operation.speed_rpm = 5000"     # errors name the change (issue 34)
    again = parse_case(c2.text)
    assert again.data == c2.data
    expected = dict(c.data, operation=dict(c.data["operation"], speed_rpm=5000.0))
    assert c2.data == expected


def test_with_value_nested_section():
    hybrid = MINIMAL + "[material.ball]\nyoungs_modulus_GPa = 310\npoisson_ratio = 0.26\ndensity_kg_m3 = 3200\n"
    c = parse_case(hybrid).with_value("material.ball.density_kg_m3", 3300)
    assert float(c.bearing().ball_material.density) == 3300.0
    assert parse_case(c.text).data == c.data
    # a new, incomplete [material.ball] section is rejected
    with pytest.raises(CaseError, match="missing required key material.ball.poisson_ratio"):
        parse_case(MINIMAL).with_value("material.ball.youngs_modulus_GPa", 310)


def test_with_value_validates():
    c = parse_case(MINIMAL)
    with pytest.raises(CaseError, match=r"bearing.balls = 2 is out of range"):
        c.with_value("bearing.balls", 2)
    with pytest.raises(CaseError, match=r"missing required key defect.depth_mm"):
        c.with_value("defect.extent_deg", 5.0)
    with pytest.raises(KeyError, match="did you mean 'operation.speed_rpm'"):
        c.with_value("operation.sped_rpm", 1)


def test_with_value_adds_section_and_replaces_pair_member():
    c = parse_case(MINIMAL)
    c2 = c.with_value("bearing.diametral_clearance_mm", 0.05)
    assert c2.get("bearing.free_contact_angle_deg") is None
    assert c2.get("bearing.diametral_clearance_mm") == 0.05
    assert parse_case(c2.text).data == c2.data
    c3 = c.with_value("dynamics.duration_s", 0.25).with_value("title", 'say "hi"\nbye')
    assert c3.dynamics_settings()["duration"] == 0.25
    assert parse_case(c3.text).data == c3.data
    assert c3.title == 'say "hi"\nbye'


def test_with_value_accepts_numpy_scalars():
    c = parse_case(MINIMAL).with_value("operation.speed_rpm", np.float64(1234.5))
    assert c.get("operation.speed_rpm") == 1234.5
    assert parse_case(MINIMAL).with_value("bearing.balls", np.int64(12)).get("bearing.balls") == 12


@pytest.mark.parametrize("value", [
    {"a": 1, "b": -2.5, "c": True, "d": "x\"y\\z\n\t\u0001", "e": [1, 2.0, 3e-9], "f": 1e300,
     "g": {"h": 0.1 + 0.2, "i": {"j": "k"}}, "weird key": 1.0, "empty": {}},
])
def test_to_toml_round_trip(value):
    assert tomllib.loads(to_toml(value)) == value


def test_to_toml_non_finite():
    out = tomllib.loads(to_toml({"a": float("inf"), "b": float("-inf"), "c": float("nan")}))
    assert out["a"] == math.inf and out["b"] == -math.inf and math.isnan(out["c"])


# ----------------------------------------------------------------------------------------------
# get, schema docs
# ----------------------------------------------------------------------------------------------
def test_get():
    c = parse_case(EXAMPLE)
    assert c.get("title") == "Harris 218 angular contact ball bearing"
    assert c.get("bearing")["balls"] == 16
    sec = c.get("bearing")
    sec["balls"] = 3
    assert c.get("bearing.balls") == 16  # copies, not views
    with pytest.raises(KeyError, match="did you mean 'bearing.balls'"):
        c.get("bearing.ballz")


def test_case_from_dict():
    c = parse_case(EXAMPLE)
    c2 = case_from_dict(c.raw)
    assert c2.data == c.data
    with pytest.raises(CaseError, match="<dict>: bearing.balls = 1"):
        case_from_dict({**c.raw, "bearing": {**c.raw["bearing"], "balls": 1}})


def test_every_key_documented():
    md = schema_reference_markdown()
    for path, sec in SCHEMA.items():
        assert sec.doc
        if path:
            assert f"## [{path}]" in md
        for key, spec in sec.keys.items():
            assert spec.doc.strip(), f"{path}.{key}"
            assert f"| `{key}` |" in md
            if spec.unit:
                assert key.endswith("_" + spec.unit), key  # units are in the key names
    assert "| `balls` | integer | - | required | integer >= 3 |" in md
    assert "| `speed_rpm` | float | rpm | required | >= 0 rpm |" in md
    assert "start_deg + 360 / balls" in md


# ----------------------------------------------------------------------------------------------
# shipped case files
# ----------------------------------------------------------------------------------------------
CASE_FILES = sorted(CASES_DIR.rglob("*.toml"))


def test_cases_directory_not_empty():
    names = {p.name for p in CASE_FILES}
    assert {"harris218_thrust.toml", "harris218_10krpm.toml", "harris218_combined.toml",
            "cwru_6205.toml"} <= names


@pytest.mark.parametrize("path", CASE_FILES, ids=lambda p: str(p.relative_to(CASES_DIR)))
def test_shipped_case_loads(path):
    c = load_case(path)
    assert c.title
    c.bearing(), c.operation(), c.loads(), c.spall(), c.sweep_settings(), c.dynamics_settings()
    assert parse_case(to_toml(c.raw)).data == c.data


def test_harris_cases():
    thrust = load_case(CASES_DIR / "harris218_thrust.toml")
    assert thrust.get("operation.speed_rpm") == 0.0 and thrust.get("load.axial_N") == 22250.0
    assert "static" in thrust.title
    fast = load_case(CASES_DIR / "harris218_10krpm.toml")
    assert fast.get("operation.speed_rpm") == 10000.0 and fast.get("load.axial_N") == 22250.0
    comb = load_case(CASES_DIR / "harris218_combined.toml")
    np.testing.assert_array_equal(np.asarray(comb.loads()), [8000.0, 0.0, 17800.0, 0.0, 200.0])


def test_cwru_case():
    c = load_case(CASES_DIR / "cwru_6205.toml")
    b = c.bearing()
    assert b.n_balls == 9
    np.testing.assert_allclose(float(b.ball_diameter), 0.3126 * 25.4e-3, rtol=1e-12)
    np.testing.assert_allclose(float(b.pitch_diameter), 1.537 * 25.4e-3, rtol=1e-12)
    s = c.spall()
    assert s.profile == "rectangular"
    np.testing.assert_allclose(float(s.length(b)), 0.021 * 25.4e-3, rtol=1e-12)
    # calibrated (docs/calibrate_cwru.py, docs/realism.md): the depth is the effective depth of
    # the 0.011 in deep EDM pit under the contact, written to 4 significant digits
    from bearingsim.realism.rig_record import pit_effective_depth
    pit = pit_effective_depth(b, c.operation(), c.loads(), 0.021 * 25.4e-3, 0.011 * 25.4e-3)
    np.testing.assert_allclose(float(s.depth), pit.depth, rtol=1e-3)
    assert c.get("operation.speed_rpm") == 1797.0
    F = np.asarray(c.loads())
    assert F[0] == 100.0 and F[1] == 0.0 and F[2] > 0.0
    assert {k: c.dynamics_settings()[k] for k in ("duration", "sample_rate")} == {"duration": 1.0, "sample_rate": 48000.0}


# ---------------------------------------------------------------------------------------------
# shipped cases by name, units
# ---------------------------------------------------------------------------------------------
def test_shipped_cases_load_by_name_as_by_path():
    from bearingsim.case import shipped_cases

    names = shipped_cases()
    assert names == sorted(p.relative_to(CASES_DIR).with_suffix("").as_posix() for p in CASE_FILES)
    for name in ("cwru_6205", "seed/speed", "demo.toml"):
        by_name = load_case(name)
        by_path = load_case(CASES_DIR / (name.removesuffix(".toml") + ".toml"))
        assert by_name.data == by_path.data and Path(by_name.source).is_file()


def test_unknown_case_name_suggests_a_shipped_one(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(CaseError, match="did you mean 'cwru_6205'"):
        load_case("cwru6205")
    with pytest.raises(CaseError, match="shipped cases: cwru_6205, .*demo"):
        load_case("zzz")
    (tmp_path / "demo.toml").write_text(EXAMPLE)          # a file of that name wins over the shipped case
    assert load_case("demo.toml").title == load_case(str(tmp_path / "demo.toml")).title != load_case("demo").title


def test_unit_table_round_trips_and_covers_every_key():
    from bearingsim.case.units import UNITS, from_si, label, to_si

    for unit in UNITS:
        assert from_si(to_si(2.5, unit), unit) == pytest.approx(2.5)
    used = {spec.unit for section in SCHEMA.values() for spec in section.keys.values()}
    assert used <= set(UNITS)
    assert to_si(10000, "rpm") == pytest.approx(10000 * 2 * math.pi / 60)
    assert from_si(math.pi, "deg") == pytest.approx(180.0) and label("Nm") == "N m"
    assert from_si(1.0, "N_per_mm1_5") == pytest.approx(1e3 ** -1.5)


# ----------------------------------------------------------------------------------------------
# inner-raceway spall and ball pit (docs/model.md section 9)
# ----------------------------------------------------------------------------------------------
def test_inner_spall_from_length():
    c = parse_case(MINIMAL + '[defect]\nlocation = "inner"\ncenter_deg = 90\nlength_mm = 2.0\n'
                             'depth_mm = 0.2\nprofile = "rectangular"\n')
    b, s = c.bearing(), c.spall()
    R_ir = 0.5 * (125.26e-3 - 22.225e-3 * math.cos(math.radians(40)))
    assert s.location == "inner" and s.profile == "rectangular"
    np.testing.assert_allclose(float(s.extent), 2.0e-3 / R_ir, rtol=1e-12)
    np.testing.assert_allclose(float(s.length(b)), 2.0e-3, rtol=1e-12)
    np.testing.assert_allclose(float(s.center), math.pi / 2, rtol=1e-15)


def test_ball_pit_keys():
    c = parse_case(MINIMAL + '[defect]\nlocation = "ball"\nball_index = 5\nspin_angle_deg = 180\n'
                             'length_mm = 0.5\ndepth_mm = 0.2\n')
    s = c.spall()
    assert s.location == "ball" and s.ball == 5
    np.testing.assert_allclose(float(s.center), math.pi, rtol=1e-15)
    np.testing.assert_allclose(float(s.extent), 2 * 0.5 / 22.225, rtol=1e-12)   # on the ball, radius D/2
    d = parse_case(MINIMAL + '[defect]\nlocation = "ball"\nextent_deg = 3\ndepth_mm = 0.2\n').spall()
    assert d.ball == 0 and float(d.center) == 0.0                               # defaults


def test_outer_keys_stay_valid_and_location_defaults_to_outer():
    s = parse_case(EXAMPLE).spall()
    assert s.location == "outer" and s.ball == 0


@pytest.mark.parametrize("defect, expected", [
    ('location = "inr"\nextent_deg = 3\ndepth_mm = 0.1\n', 'defect.location = "inr" is not allowed: must be one '
     'of "outer", "inner", "ball" (did you mean "inner"?)'),
    ('spin_angel_deg = 3\nextent_deg = 3\ndepth_mm = 0.1\n', "did you mean 'spin_angle_deg'?"),
    ('location = "inner"\nball_index = 2\nextent_deg = 3\ndepth_mm = 0.1\n',
     'defect.ball_index = 2 applies only to a ball pit: set defect.location = "ball" (it is "inner")'),
    ('spin_angle_deg = 10\nextent_deg = 3\ndepth_mm = 0.1\n', "defect.spin_angle_deg = 10 applies only to a ball pit"),
    ('location = "ball"\nball_index = 16\nextent_deg = 3\ndepth_mm = 0.1\n',
     "defect.ball_index = 16 is out of range: the bearing has 16 balls (0 to 15)"),
    ('location = "ball"\nball_index = -1\nextent_deg = 3\ndepth_mm = 0.1\n', "defect.ball_index = -1 is out of range"),
    ('location = "ball"\ncenter_deg = 5\nextent_deg = 3\ndepth_mm = 0.1\n',
     "defect.center_deg = 5 is not used for a ball pit"),
    ('location = "ball"\nextent_deg = 180\ndepth_mm = 0.1\n', "a pit must be smaller than 180 deg"),
    ('location = "ball"\nlength_mm = 35\ndepth_mm = 0.1\n', "defect.length_mm = 35 spans 180.459 deg of the ball"),
    # R_ir = 54.1173 mm: the 22.5 deg pitch is 21.2518 mm along the inner raceway
    ('location = "inner"\nlength_mm = 21.5\ndepth_mm = 0.1\n', "along the inner raceway (R_ir = 54.1173 mm"),
])
def test_inner_and_ball_defect_errors(defect, expected):
    assert expected in one_problem(MINIMAL + "[defect]\n" + defect)


def test_inner_and_ball_cases_round_trip_through_toml():
    for name in ("cwru_6205_inner", "cwru_6205_ball"):
        c = load_case(name)
        again = parse_case(to_toml(c.raw))
        assert again.data["defect"] == c.data["defect"]
        a, b = c.spall(), again.spall()
        assert (a.location, a.ball, a.profile) == (b.location, b.ball, b.profile)
        for f in ("center", "extent", "depth"):
            assert float(getattr(a, f)) == float(getattr(b, f))


def test_cwru_inner_and_ball_cases():
    outer = load_case("cwru_6205")
    for name, loc in (("cwru_6205_inner", "inner"), ("cwru_6205_ball", "ball")):
        c = load_case(name)
        # the same bearing and operating point as the outer-race case ([load] and [dynamics] are
        # copies of its blocks at the time of writing; its calibration may move on)
        for sec in ("bearing", "operation"):
            assert c.data[sec] == outer.data[sec], (name, sec)
        assert c.data["dynamics"]["sample_rate_Hz"] == outer.data["dynamics"]["sample_rate_Hz"]
        s = c.spall()
        assert s.location == loc and c.data["defect"]["length_mm"] == 0.1778 and c.data["defect"]["depth_mm"] == 0.2794
        np.testing.assert_allclose(float(s.length(c.bearing())), 0.1778e-3, rtol=1e-12)


# ---------------------------------------------------------------------------------------------
# [set]: a shaft on several bearings (docs/model.md section 10)
# ---------------------------------------------------------------------------------------------
def _set_case(set_text, extra=""):
    base = (CASES_DIR / "harris218_db_light.toml").read_text()
    head = base.split("[set]")[0]
    return head + "[set]\n" + set_text + "\n" + extra


@pytest.mark.parametrize("set_text, message", [
    ('arrangement = "BD"\nspacing_mm = 40', "set.arrangement = 'BD' is not a known arrangement: did you mean 'DB'?"),
    ('arrangement = "DB"', "set.arrangement needs set.spacing_mm"),
    ('facings = [1, -1]\npositions_mm = [0, 10]', "set.positions_mm: bearings 1 and 2 overlap"),
    ('facings = [1, 2]\npositions_mm = [0, 40]', "set.facings = [1, 2]: each facing must be +1 or -1"),
    ('arrangement = "DT"\nspacing_mm = 40\npreload_N = 1000', "set.preload_N = 1000: every bearing of the set faces +1"),
    ('facings = [1, -1]\npositions_mm = [0, 40]\npreloads_N = [1000, 2000]', "set.preloads_N = [1000, 2000]: the preloads do not balance"),
    ('facings = [1, -1, -1]\npositions_mm = [0, 40, 300]\npreloads_N = [2000, 1000, 1000]\nspring_bearings = [1, 2]',
     "set.spring_bearings: bearings 1 and 2 form one pair"),
    ('arrangement = "DB"\nspacing_mm = 40\npreload_N = 100\npreload_class = "light"', "give at most one of preload_N, preload_class, preloads_N"),
    ('arrangement = "DB"\nspacing_mm = 40\npreload_class = "hevy"', "set.preload_class"),
])
def test_bad_set_inputs_name_the_key(set_text, message):
    with pytest.raises(CaseError) as e:
        parse_case(_set_case(set_text))
    assert message in str(e.value)


def test_set_cases_build_their_sets():
    from bearingsim.physics import shaft
    c = load_case(CASES_DIR / "harris218_db_heavy.toml")
    s = c.bearing_set()
    np.testing.assert_array_equal(np.asarray(s.facings), [1.0, -1.0])
    np.testing.assert_allclose(np.asarray(s.positions), [0.0, 0.04])
    np.testing.assert_allclose(np.asarray(s.preload), 0.012 * float(shaft.static_axial_capacity(s.bearings[0])))
    sp = load_case(CASES_DIR / "spindle_tbt_spring.toml").bearing_set()
    np.testing.assert_array_equal(np.asarray(sp.springs), [0, 0, 0, 1])
    sp.check_balance()
    rotor = load_case(CASES_DIR / "cwru_rotor.toml").bearing_set()
    assert [b.n_balls for b in rotor.bearings] == [9, 8]
    np.testing.assert_allclose(float(rotor.bearings[1].ball_diameter), 0.2656 * 25.4e-3, rtol=1e-5)

# ----------------------------------------------------------------------------------------------
# shoulders, design, limits, dynamic load rating (issue 21)
# ----------------------------------------------------------------------------------------------
def test_shoulder_design_and_limits_keys():
    c = parse_case(MINIMAL)
    assert c.get("bearing.design") == "auto" and c.get("bearing.dynamic_load_rating_kN") is None
    assert c.limits_settings() == {"pressure_limit": 4.2e9, "friction_coefficient": 0.07,
                                   "dynamic_load_rating": None}
    b = c.bearing()                      # alpha_0 = 40 deg given: an angular contact bearing
    assert bool(b.angular_contact)
    sh = np.degrees(np.asarray(b.shoulders))
    c2 = parse_case(MINIMAL + "[shoulders]\nouter_low_deg = 5\n[limits]\nfriction_coefficient = 0.1\n"
                    "contact_pressure_limit_MPa = 3000\n")
    sh2 = np.degrees(np.asarray(c2.bearing().shoulders))
    np.testing.assert_allclose(sh2, [sh[0], sh[1], sh[2], 5.0], rtol=1e-12)
    assert c2.limits_settings()["pressure_limit"] == pytest.approx(3e9)
    assert c2.limits_settings()["friction_coefficient"] == 0.1
    c3 = c.with_value("bearing.dynamic_load_rating_kN", 143.0).with_value("bearing.design", "deep_groove")
    assert c3.limits_settings()["dynamic_load_rating"] == pytest.approx(143e3)
    assert not bool(c3.bearing().angular_contact)


def test_clearance_gives_a_deep_groove_unless_told():
    text = MINIMAL.replace("free_contact_angle_deg = 40.0", "diametral_clearance_mm = 0.05")
    assert "diametral_clearance_mm" in text
    assert parse_case(text).bearing().design == "deep_groove"
    c = parse_case(text.replace("[bearing]", '[bearing]\ndesign = "angular_contact"'))
    assert c.bearing().design == "angular_contact"


def test_shoulder_angle_out_of_range():
    assert one_problem(MINIMAL + "[shoulders]\ninner_high_deg = 0\n") == (
        "cases/x.toml: shoulders.inner_high_deg = 0 is out of range: must be > 0 and < 90 deg")
