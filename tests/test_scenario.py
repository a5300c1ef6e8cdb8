"""The built scenario (issue 35 item 1): ``case.build()`` turns a validated case into one frozen
object of SI objects, built once; the workflows and the data set engine take it.  Independent
truth: the case's own accessors (``Case.bearing()``, ``loads()``, ``dynamics_settings()``, ...),
which the scenario must reproduce exactly (the same constructors: equality, no tolerance)."""
from __future__ import annotations

import dataclasses

import jax
import numpy as np
import pytest

from bearingsim.case import Scenario, as_scenario, case_from_dict, load_case
from bearingsim.datasets import draw_labels
from bearingsim.dynamics import DynamicsParameters, Realism


def _same_tree(a, b):
    la, lb = jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b)
    return jax.tree_util.tree_structure(a) == jax.tree_util.tree_structure(b) and all(
        np.array_equal(np.asarray(x), np.asarray(y)) for x, y in zip(la, lb))


@pytest.mark.parametrize("name", ["demo", "cwru_6205", "dataset_cwru_4class", "harris218_db_light", "cwru_rotor"])
def test_build_reproduces_the_case_accessors(name):
    case = load_case(name)
    sc = case.build()
    assert isinstance(sc, Scenario) and as_scenario(sc) is sc
    assert sc.source == case.source and sc.text == case.text and sc.title == case.title
    assert _same_tree(sc.bearing, case.bearing())
    assert _same_tree(sc.bearing_set, case.bearing_set())
    assert _same_tree(sc.operation, case.operation())
    assert np.array_equal(np.asarray(sc.loads), np.asarray(case.loads()))
    assert _same_tree(sc.spall, case.spall())
    assert sc.cage_angle == case.cage_angle and sc.hertz_method == case.hertz_method
    assert sc.speed_rpm == case.get("operation.speed_rpm")
    assert sc.limits == case.limits_settings() and sc.sweep == case.sweep_settings()
    assert sc.dynamics == case.dynamics_settings()
    assert _same_tree(sc.params, DynamicsParameters.from_settings(case.dynamics_settings()))
    assert sc.realism == Realism.from_settings(case.dynamics_settings())
    assert sc.dataset == case.get("dataset")
    assert sc.is_set == case.is_set
    assert sc.has_dynamics == ("dynamics" in case.raw)
    assert sc.sample_rate == case.get("dynamics.sample_rate_Hz")
    assert sc.duration == case.get("dynamics.duration_s")


def test_scenario_is_frozen_and_a_changed_case_builds_a_new_one():
    case = load_case("demo")
    sc = case.build()
    with pytest.raises(dataclasses.FrozenInstanceError):
        sc.speed_rpm = 1.0
    faster = case.with_value("operation.speed_rpm", 12000).build()
    assert faster.speed_rpm == 12000.0 and sc.speed_rpm == 10000.0
    assert float(faster.operation.speed) == pytest.approx(12000 * 2 * np.pi / 60, rel=1e-15)


def test_background_section_and_set_ratings():
    """[background] -> the machine's Background field by field (SI); a set's per-bearing ratings
    from [bearing] / [set.second_bearing] dynamic_load_rating_kN (kN -> N)."""
    raw = load_case("dataset_cwru_4class").raw
    raw = dict(raw, background={"noise_rms_m_s2": 0.7, "line_frequency_Hz": 50.0, "knock_rate_Hz": 2.0,
                                "shaft_amplitudes_m_s2": [0.1, 0.05]})
    sc = case_from_dict(raw).build()
    bg = sc.background
    assert bg.noise_rms == 0.7 and bg.line_frequency == 50.0 and bg.knock_rate == 2.0
    assert bg.shaft_amplitudes == (0.1, 0.05)
    assert load_case("demo").build().background is None
    s = load_case("harris218_db_light")
    C = s.get("bearing.dynamic_load_rating_kN")
    ratings = s.build().set_ratings
    assert len(ratings) == len(s.build().bearing_set.bearings)
    assert all(r == (None if C is None else 1e3 * C) for r in ratings)
    assert load_case("demo").build().set_ratings is None


def test_labels_of_a_case_and_of_its_scenario_are_the_same_bytes():
    case = load_case("dataset_cwru_4class").with_value("dataset.count", 8)
    assert draw_labels(case).tobytes() == draw_labels(case.build()).tobytes()
