"""A built scenario: a validated case turned once into the frozen SI objects every workflow takes.

``load_case(...)`` gives a :class:`~bearingsim.case.Case`: the file's keys, validated, in the
file's engineering units.  ``case.build()`` (:func:`build`) turns it into one
:class:`Scenario`: the bearing (or set), the operating point, the loads, the defect, the
dynamics parameters and realism ingredients, the machine's background and the data set spec,
each built once.  The workflows (``simulate_case``, ``make_dataset``, the rig records,
``identify``) take a scenario (or a case, which they build once at their entry) and read its
fields; below them nothing reads the case API (``tests/test_architecture.py`` checks the data
set engine).  A scenario is immutable: a changed case (``case.with_value``) builds a new one.

    sc = load_case("cwru_6205").build()
    sc.bearing, sc.operation, sc.loads, sc.spall, sc.params, sc.sample_rate, sc.duration
"""
from __future__ import annotations

from dataclasses import dataclass

from ..dynamics.parameters import DynamicsParameters, Realism
from ..physics.kinematics import DefectFrequencies, defect_frequencies
from ..signals.background import Background
from .sets import set_layout
from .units import from_si, to_si

__all__ = ["Scenario", "build", "as_scenario"]


@dataclass(frozen=True, eq=False)
class Scenario:
    """Everything a case says, built once (SI, radians; see the module docstring).

    ``text`` is the case's TOML (results files and data sets carry it); ``dataset`` the validated
    ``[dataset]`` spec in its keys' units (the label table is written in those units; ``None``
    without the section); ``background`` the machine's :class:`Background` of ``[background]``
    (``None`` without the section); ``has_dynamics``: the file has a ``[dynamics]`` section (its
    defaults serve otherwise)."""

    source: str
    title: str
    text: str
    bearing: object                 # physics.geometry.Bearing (the first bearing of a set)
    bearing_set: object             # physics.shaft.BearingSet, or None for one bearing
    operation: object               # physics.kinematics.Operation
    speed_rpm: float
    loads: object                   # (5,) [Fx, Fy, Fz, Mx, My] N, N m
    spall: object                   # physics.defect.Spall, or None (healthy)
    cage_angle: float               # rad
    hertz_method: str
    control: str                    # raceway control: "outer" | "inner" | "hybrid"
    centrifugal: bool
    gyroscopic: bool
    tilt: str                       # "free" | "held"
    profile: str                    # the defect's depth profile
    limits: dict                    # pressure_limit Pa, friction_coefficient, dynamic_load_rating N or None
    sweep: dict                     # start, stop rad, steps
    dynamics: dict                  # the [dynamics] keys in SI (duration s, sample_rate Hz, ...)
    params: DynamicsParameters
    realism: Realism
    has_dynamics: bool
    dataset: dict | None
    background: Background | None
    set_ratings: tuple | None = None  # a set's dynamic load rating C (N) per bearing, None where not given

    @property
    def is_set(self) -> bool:
        """True for a shaft on several bearings (docs/model.md section 10)."""
        return self.bearing_set is not None

    @property
    def sample_rate(self) -> float:
        """Sample rate of a simulated record (Hz)."""
        return float(self.dynamics["sample_rate"])

    @property
    def duration(self) -> float:
        """Duration of a single simulation (s)."""
        return float(self.dynamics["duration"])

    @property
    def seed(self) -> int:
        """The single simulation's seed."""
        return int(self.dynamics.get("seed", 0))

    def frequencies(self, speed_rpm=None) -> DefectFrequencies:
        """Shaft and defect frequencies (Hz, floats) at ``speed_rpm`` (default the scenario's) and
        the free contact angle (``bearingsim info``'s)."""
        n = self.speed_rpm if speed_rpm is None else float(speed_rpm)
        shaft = from_si(to_si(n, "rpm"), "rev_s")
        return DefectFrequencies(*(float(v) for v in defect_frequencies(self.bearing, shaft)))


def machine_background(sec: dict) -> Background:
    """The :class:`Background` of a ``[background]`` section in SI (``Case.si("background")``)."""
    return Background(tuple(sec.get("shaft_amplitudes") or ()), float(sec.get("line_frequency", 60.0)),
                      tuple(sec.get("line_amplitudes") or ()), float(sec.get("noise_rms", 0.0)),
                      tuple(sec.get("psd_frequencies") or ()), tuple(sec.get("psd_levels") or ()),
                      tuple(sec.get("modulation_depths") or ()), float(sec.get("knock_rate", 0.0)),
                      float(sec.get("knock_amplitude", 0.0)), float(sec.get("knock_frequency", 3000.0)),
                      float(sec.get("knock_damping_ratio", 0.05)))


def set_ratings(data: dict) -> tuple | None:
    """C (N) of every bearing of a set ([bearing] / [set.second_bearing] dynamic_load_rating_kN),
    None for a bearing without a rating; None for a single bearing (its rating: ``limits``)."""
    s = data.get("set")
    if s is None:
        return None
    facings, _, _, _, _, seconds = set_layout(s, 0.0)
    C1 = data["bearing"].get("dynamic_load_rating_kN")
    C2 = s.get("second_bearing", {}).get("dynamic_load_rating_kN")
    return tuple(None if c is None else 1e3 * c for c in (C2 if k in seconds else C1 for k in range(len(facings))))


def build(case) -> Scenario:
    """The :class:`Scenario` of a validated :class:`~bearingsim.case.Case` (``case.build()``)."""
    d = case.dynamics_settings()
    o = case.data["operation"]
    return Scenario(
        source=case.source, title=case.title, text=case.text,
        bearing=case.bearing(), bearing_set=case.bearing_set(), operation=case.operation(),
        speed_rpm=float(o["speed_rpm"]), loads=case.loads(), spall=case.spall(),
        cage_angle=float(case.cage_angle), hertz_method=case.hertz_method, control=o["raceway_control"],
        centrifugal=bool(o["centrifugal"]), gyroscopic=bool(o["gyroscopic"]), tilt=o.get("tilt") or "free",
        profile=case.data.get("defect", {}).get("profile", "rectangular"),
        limits=case.limits_settings(), sweep=case.sweep_settings(), dynamics=d,
        params=DynamicsParameters.from_settings(d), realism=Realism.from_settings(d),
        has_dynamics="dynamics" in case.raw,
        dataset=case.get("dataset"),
        background=machine_background(case.si("background")) if "background" in case.data else None,
        set_ratings=set_ratings(case.data))


def as_scenario(case_or_scenario) -> Scenario:
    """A :class:`Scenario` as it is, a case built (:func:`build`): what a workflow's entry does."""
    return case_or_scenario if isinstance(case_or_scenario, Scenario) else build(case_or_scenario)
