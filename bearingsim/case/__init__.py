"""Case files: TOML in engineering units -> validated, normalised data -> SI core objects.

A case file describes one bearing, its operating condition, loads, an optional outer-raceway
spall, and the optional sweep / study / dynamics / dataset settings, e.g.::

    title = "Harris 218 angular contact ball bearing"
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
    axial_N = 22250

``load_case("demo")`` reads a shipped case by name, ``load_case("my.toml")`` a file.  The package
is split by job:

=================== ==================================================================
module              holds
=================== ==================================================================
``units``           the one table of units (:data:`UNITS`, ``to_si``, ``from_si``)
``schema``          :data:`SCHEMA`: sections -> keys -> :class:`Key` (type, default, range, unit, doc)
``validation``      checks driven by the schema, cross-checks, :class:`CaseError`
``files``           shipped cases by name, reading UTF-8 text, TOML errors told by key
``sampling``        the sample-rate rule of simulated signals (:func:`check_sampling`)
``scenario``        :class:`Scenario`: a case built once into its SI objects (``case.build()``)
``toml_writer``     :func:`to_toml`
``reference``       :func:`schema_reference_markdown` (the reference page)
``messages``        how values and names are shown in messages ("did you mean")
=================== ==================================================================

All problems of a case are collected and raised together as one :class:`CaseError` (an
:class:`~bearingsim.errors.InputError`, exit code 2) with one line per problem, each prefixed
by the source file name.  This package is the edge: it reads files; the core never does.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..physics.defect import Spall
from ..physics.geometry import Bearing, Material
from ..physics.jones import load_vector
from ..physics.kinematics import Operation
from ..physics.shaft import BearingSet, preload_class_force
from .files import case_path, parse_toml, read_case_text, shipped_cases, shipped_cases_dir
from .messages import fmt_value, suggest
from .reference import schema_reference_markdown
from .sampling import check_sampling, highest_frequency, nominal_frequencies
from .scenario import Scenario, as_scenario, build
from .schema import OPTIONAL, REQUIRED, SCHEMA, Key, Section, all_keys, lookup, si_name, split_key, unit_of
from .sets import set_layout
from .toml_writer import to_toml
from .units import UNITS, to_si
from .validation import CaseError, section_raw, set_raw, validate

__all__ = [
    "CaseError",
    "Case",
    "Scenario",
    "as_scenario",
    "Key",
    "Section",
    "SCHEMA",
    "UNITS",
    "REQUIRED",
    "OPTIONAL",
    "load_case",
    "parse_case",
    "case_from_dict",
    "case_path",
    "shipped_cases",
    "shipped_cases_dir",
    "unit_of",
    "check_sampling",
    "nominal_frequencies", "highest_frequency",
    "to_toml",
    "schema_reference_markdown",
]


@dataclass(frozen=True)
class Case:
    """A validated case.  Build it with :func:`load_case` / :func:`parse_case`.

    ``text``: the TOML text; ``source``: where it came from (file name); ``data``: normalised
    nested dict in the file's engineering units, defaults filled in (floats for float keys).
    Do not mutate ``data``; use :meth:`with_value`.
    """

    source: str
    text: str
    data: dict
    raw: dict = field(repr=False, compare=False)  # the parsed TOML, without defaults

    # -- access ---------------------------------------------------------------------------------
    @property
    def title(self) -> str:
        return self.data.get("title", "")

    def get(self, dotted_key: str):
        """Value of a dotted key ("bearing.balls", "material.ball.density_kg_m3"), or a copy of a
        section ("bearing").  None for a schema key that this case does not set (e.g. the unused
        one of an exactly-one pair, or a key of an absent optional section)."""
        path, key = split_key(dotted_key)
        if dotted_key in SCHEMA:
            sec = section_raw(self.data, dotted_key)
            return None if sec is None else copy.deepcopy(sec)
        if path not in SCHEMA or key not in SCHEMA[path].keys:
            valid = all_keys() + [p for p in SCHEMA if p]
            raise KeyError(f"'{dotted_key}' is not a case key: {suggest(dotted_key, valid)}")
        sec = section_raw(self.data, path)
        return None if sec is None else copy.deepcopy(sec.get(key))

    def with_value(self, dotted_key: str, value) -> "Case":
        """A new validated case with one key changed (engineering units, as in the file).

        Setting one key of an exactly-one pair (e.g. ``bearing.diametral_clearance_mm``) removes
        the other.  Computed defaults (``sweep.stop_deg``) follow the change unless given
        explicitly.  The new ``text`` is the TOML of the changed file (comments are not kept).
        Raises CaseError if the result is invalid.  The new case's ``source`` names the change
        (``demo.toml with operation.speed_rpm = 12000``), so that an error about the changed case
        says which value was changed.
        """
        if lookup(dotted_key) is None:
            valid = all_keys()
            raise KeyError(f"'{dotted_key}' is not a case key: {suggest(dotted_key, valid)}")
        if hasattr(value, "item") and not isinstance(value, (bool, int, float, str)):
            value = value.item()  # numpy / jax scalars
        raw = set_raw(self.raw, dotted_key, value)
        changed = f"{self.source} with {dotted_key} = {fmt_value(value)}"
        text = to_toml(raw, header=changed)
        return _case_from_raw(raw, text, changed)          # errors name the change, not only the file

    def study_cases(self) -> list["Case"]:
        """One case per study value (each without the [study] section); [] without a study."""
        st = self.study_settings()
        if st is None:
            return []
        param, values = st
        base = copy.deepcopy(self.raw)
        base.pop("study", None)
        base_case = _case_from_raw(base, to_toml(base), self.source)
        return [base_case.with_value(param, v) for v in values]

    # -- SI objects -----------------------------------------------------------------------------
    def si(self, path: str) -> dict:
        """Section ``path`` in SI, keys without their unit suffix (``si("load")["axial"]`` in N,
        ``si("operation")["speed"]`` in rad/s); the section's other keys as they are."""
        sec = section_raw(self.data, path) or {}
        out = {}
        for key, spec in SCHEMA[path].keys.items():
            if key in sec:
                v = sec[key]
                out[si_name(key, spec)] = (to_si(v, spec.unit) if spec.type == "float" else
                                            [to_si(x, spec.unit) for x in v] if spec.type == "range" else v)
        return out

    def _material(self, path: str):
        m = self.si(path)
        return Material(m["youngs_modulus"], m["poisson_ratio"], m["density"])

    def bearing(self):
        """:class:`bearingsim.Bearing` in SI."""
        b = self.si("bearing")
        rings = self._material("material")
        balls = self._material("material.ball") if section_raw(self.data, "material.ball") else rings
        args = (b["balls"], b["ball_diameter"], b["pitch_diameter"], b["inner_groove_curvature"],
                b["outer_groove_curvature"])
        design = b.get("design", "auto")
        if "diametral_clearance" in b:
            bearing = Bearing.from_clearance(*args, b["diametral_clearance"], ball_material=balls,
                                             ring_material=rings,
                                             design="deep_groove" if design == "auto" else design)
        else:
            bearing = Bearing(*args, b["free_contact_angle"], balls, rings, design=design)
        given = self.si("shoulders") if section_raw(self.data, "shoulders") else {}
        if given:
            import jax.numpy as jnp
            names = ("inner_high", "inner_low", "outer_high", "outer_low")
            sh = [given.get(n, d) for n, d in zip(names, np.asarray(bearing.shoulders).tolist())]
            bearing = Bearing(*args, bearing.free_contact_angle, balls, rings, jnp.asarray(sh),
                              bearing.design)
        return bearing

    def limits_settings(self) -> dict:
        """SI settings of the per-contact limits and the life: ``pressure_limit`` (Pa),
        ``friction_coefficient``, ``dynamic_load_rating`` (N, or None)."""
        lim = self.si("limits")
        return {
            "pressure_limit": lim["contact_pressure_limit"],
            "friction_coefficient": lim["friction_coefficient"],
            "dynamic_load_rating": self.si("bearing").get("dynamic_load_rating"),
        }

    @property
    def is_set(self) -> bool:
        """True when the case describes a shaft on several bearings ([set], docs/model.md section 10)."""
        return "set" in self.data

    def _bearing_from(self, path: str):
        b = self.si(path)
        rings = self._material("material")
        balls = self._material("material.ball") if section_raw(self.data, "material.ball") else rings
        args = (b["balls"], b["ball_diameter"], b["pitch_diameter"], b["inner_groove_curvature"],
                b["outer_groove_curvature"])
        design = b.get("design", "auto")
        if "diametral_clearance" in b:
            return Bearing.from_clearance(*args, b["diametral_clearance"], ball_material=balls,
                                          ring_material=rings,
                                          design="deep_groove" if design == "auto" else design)
        return Bearing(*args, b["free_contact_angle"], balls, rings, design=design)

    def bearing_set(self):
        """:class:`bearingsim.physics.shaft.BearingSet` of [set] (SI; preload classes resolved), or None."""
        if not self.is_set:
            return None
        s = self.data["set"]
        first = self.bearing()
        second = self._bearing_from("set.second_bearing") if "second_bearing" in s else None
        facings, z, pre, cls, springs, seconds = set_layout(s, float(self.data["bearing"]["ball_diameter_mm"]))
        n = len(facings)
        bearings = [second if k in seconds else first for k in range(n)]
        if pre is None:
            P = float(s.get("preload_N", 0.0)) if cls is None else preload_class_force(first, cls)
            plus = sum(1 for f in facings if f > 0)
            minus = n - plus
            pre = [0.0] * n if P == 0.0 else [P / (plus if f > 0 else minus) for f in facings]
        return BearingSet(bearings, [x * 1e-3 for x in z], facings, [float(p) for p in pre],
                          [k in springs for k in range(n)])

    def operation(self):
        """:class:`bearingsim.Operation` (speed in rad/s via ``Operation.from_rpm``)."""
        o = self.data["operation"]
        return Operation.from_rpm(o["speed_rpm"], o["raceway_control"], o["centrifugal"], o["gyroscopic"])

    @property
    def hertz_method(self) -> str:
        """"exact" or "brewe-hamrock" (the solvers' ``hertz_method``)."""
        return self.data["operation"]["hertz"]

    @property
    def cage_angle(self) -> float:
        """Cage angle theta_c (rad)."""
        return self.si("operation")["cage_angle"]

    def loads(self):
        """Inner-ring loads [Fx, Fy, Fz, Mx, My] (N, N m) as a float64 jax array."""
        ld = self.si("load")
        return load_vector(axial=ld["axial"], radial_x=ld["radial_x"], radial_y=ld["radial_y"],
                           moment_x=ld["moment_x"], moment_y=ld["moment_y"])

    def spall(self):
        """:class:`bearingsim.Spall` (rad, m), or None for a healthy bearing (no [defect]).  Its
        ``location`` is [defect] location; a ball pit's ``center`` is spin_angle_deg and its
        ``ball`` ball_index."""
        if "defect" not in self.data:
            return None
        d = self.si("defect")
        loc = d.get("location", "outer")
        center = d.get("spin_angle", 0.0) if loc == "ball" else d["center"]
        ball = int(d.get("ball_index", 0)) if loc == "ball" else 0
        if "length" in d:
            return Spall.from_length(self.bearing(), center, d["length"], d["depth"], d["profile"], loc, ball)
        return Spall(center, d["extent"], d["depth"], d["profile"], loc, ball)

    def sweep_settings(self) -> dict:
        """dict(start=rad, stop=rad, steps=int); defaults: 0, one ball pitch 2 pi / Z, 181."""
        return self.si("sweep")

    def study_settings(self):
        """(parameter, values) with values in the key's unit as in the file, or None."""
        st = self.data.get("study")
        if st is None:
            return None
        return st["parameter"], list(st["values"])

    def dataset_settings(self) -> dict | None:
        """The [dataset] keys in SI without unit suffix (ranges as [min, max]), or None."""
        if "dataset" not in self.data:
            return None
        return self.si("dataset")

    def dynamics_settings(self) -> dict:
        """The [dynamics] keys in SI without unit suffix: dict(duration=s, sample_rate=Hz, ...)."""
        return self.si("dynamics")

    def build(self) -> Scenario:
        """This case built once into its SI objects: a frozen :class:`Scenario` (bearing or set,
        operating point, loads, defect, dynamics parameters, realism, background, data set spec),
        the object the workflows, the data set engine, the rig records and identify take."""
        return build(self)


def _case_from_raw(raw: dict, text: str, source: str) -> Case:
    data = validate(raw, source)
    return Case(source=source, text=text, data=data, raw=raw)


def parse_case(text: str, source: str = "<string>") -> Case:
    """Parse and validate TOML case text.  Raises CaseError listing every problem."""
    return _case_from_raw(parse_toml(text, source), text, source)


def load_case(name_or_path) -> Case:
    """Read and validate a case file, or a shipped case by name (see :func:`case_path`).  Error
    lines are prefixed with the path as given (the full path for a shipped case)."""
    p = case_path(name_or_path)
    source = str(name_or_path) if p == Path(name_or_path) else str(p)
    return parse_case(read_case_text(p, source), source=source)


def case_from_dict(data: dict, source: str = "<dict>") -> Case:
    """Validate a nested dict shaped like a case file (engineering units)."""
    raw = copy.deepcopy(data)
    return _case_from_raw(raw, to_toml(raw), source)
