"""Case files: TOML in engineering units -> validated, normalised data -> SI core objects.

A case file describes one bearing, its operating condition, loads, an optional outer-raceway
spall, and the optional sweep / study / dynamics settings, e.g.::

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

Everything the reader accepts is described by :data:`SCHEMA`, a table of sections -> keys ->
:class:`Key` specs (type, default, allowed range, unit, doc).  Validation is driven by that
table, so a new key is one new row; :func:`schema_reference_markdown` renders the table as the
reference page of the documentation.  Units are part of the key names (``_mm``, ``_deg``,
``_rpm``, ``_N``, ``_Nm``, ``_GPa``, ``_kg_m3``, ``_s``, ``_Hz``); :class:`Case` converts to SI.

All problems of a case are collected and raised together as one :class:`CaseError` (an
:class:`~bearingsim.errors.InputError`, hence a ``ValueError``) whose message has one line per problem, each prefixed by the source file name.

This module sits at the edge of the package: it may read files; the core never does.
"""
from __future__ import annotations

import copy
import difflib
import json
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .errors import InputError

__all__ = [
    "CaseError",
    "Case",
    "Key",
    "Section",
    "SCHEMA",
    "UNITS",
    "load_case",
    "parse_case",
    "case_path",
    "shipped_cases",
    "shipped_cases_dir",
    "case_from_dict",
    "unit_of",
    "to_toml",
    "schema_reference_markdown",
]


class CaseError(InputError):
    """Invalid case (an :class:`~bearingsim.errors.InputError`, exit code 2).  ``problems`` lists
    the problems (without the source prefix), ``source`` names the file; the message has one line
    ``<source>: <problem>`` per problem."""

    def __init__(self, source: str, problems: list[str]):
        self.source = source
        self.problems = list(problems)
        super().__init__("\n".join(f"{source}: {p}" for p in self.problems))


# ------------------------------------------------------------------------------------------------
# Units
# ------------------------------------------------------------------------------------------------
#: unit suffix of a key name -> (factor to SI, label shown in docs and messages, SI unit)
UNITS: dict[str, tuple[float, str, str]] = {
    "": (1.0, "", ""),
    "mm": (1e-3, "mm", "m"),
    "deg": (math.pi / 180.0, "deg", "rad"),
    "rpm": (2.0 * math.pi / 60.0, "rpm", "rad/s"),
    "N": (1.0, "N", "N"),
    "Nm": (1.0, "N m", "N m"),
    "GPa": (1e9, "GPa", "Pa"),
    "kg_m3": (1.0, "kg/m^3", "kg/m^3"),
    "s": (1.0, "s", "s"),
    "Hz": (1.0, "Hz", "Hz"),
    "kg": (1.0, "kg", "kg"),
    "kg_m": (1.0, "kg m", "kg m"),
    "N_per_m": (1.0, "N/m", "N/m"),
    "Ns_per_m": (1.0, "N s/m", "N s/m"),
    "m_s2": (1.0, "m/s^2", "m/s^2"),
}


# ------------------------------------------------------------------------------------------------
# Schema
# ------------------------------------------------------------------------------------------------
class _Marker:
    def __init__(self, name):
        self.name = name

    def __repr__(self):
        return self.name


#: default marker: the key must be given
REQUIRED = _Marker("REQUIRED")
#: default marker: the key may be absent and then has no value (e.g. one of an exactly-one pair)
OPTIONAL = _Marker("OPTIONAL")

_TYPE_NAMES = {
    "float": "a number",
    "int": "an integer",
    "bool": "a boolean (true or false)",
    "str": "a string",
    "enum": "a string",
    "numbers": "a non-empty array of numbers",
    "range": "a two-element array [min, max] of numbers",
}


@dataclass(frozen=True)
class Key:
    """Spec of one case key.

    ``type``: "float" (int accepted), "int", "bool", "str", "enum" (a string from ``choices``)
    "numbers" (non-empty array, elements checked elsewhere) or "range" (``[min, max]``: two finite
    numbers, min <= max, each within gt/ge/lt/le; min = max fixes the value).
    ``default``: a value, :data:`REQUIRED`, :data:`OPTIONAL`, or a callable ``f(section_data,
    data)`` evaluated on the normalised data once the other keys are known (``default_doc``
    then describes it).  ``gt/ge/lt/le``: allowed range (exclusive / inclusive bounds).
    ``unit``: a key of :data:`UNITS` (also the key name's suffix).  ``doc``: one line.
    """

    type: str
    doc: str
    unit: str = ""
    default: Any = REQUIRED
    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None
    choices: tuple[str, ...] = ()
    default_doc: str | None = None

    @property
    def numeric(self) -> bool:
        return self.type in ("float", "int")

    @property
    def unit_label(self) -> str:
        return UNITS[self.unit][1]

    def range_text(self) -> str:
        """'>= 3', '> 0.5 and < 1', ... with the unit; '' when unbounded."""
        parts = []
        if self.gt is not None:
            parts.append(f"> {_fmt_num(self.gt)}")
        if self.ge is not None:
            parts.append(f">= {_fmt_num(self.ge)}")
        if self.lt is not None:
            parts.append(f"< {_fmt_num(self.lt)}")
        if self.le is not None:
            parts.append(f"<= {_fmt_num(self.le)}")
        text = " and ".join(parts)
        if text and self.unit_label:
            text += f" {self.unit_label}"
        return text

    def requirement_text(self) -> str:
        """What an acceptable value looks like, e.g. 'an integer >= 3' or '>= 0 rpm'."""
        rng = self.range_text()
        if self.type == "int":
            return f"an integer {rng}" if rng else "an integer"
        if self.type == "float":
            return rng if rng else "a finite number"
        if self.type == "enum":
            return "one of " + ", ".join(json.dumps(c) for c in self.choices)
        if self.type == "range":
            return "[min, max] with min <= max" + (f", each {rng}" if rng else "")
        return _TYPE_NAMES[self.type]


@dataclass(frozen=True)
class Section:
    """Spec of one case section ([name]; the root section is "").

    ``required``: the section must be present.  ``fill_defaults``: when the section is absent,
    ``Case.data`` still holds it with its defaults (otherwise an absent section stays absent).
    ``exactly_one``: groups of keys of which exactly one must be given.  ``notes``: the
    cross-checks of the section, for the documentation.
    """

    doc: str
    keys: dict[str, Key]
    required: bool = False
    fill_defaults: bool = True
    exactly_one: tuple[tuple[str, ...], ...] = ()
    notes: tuple[str, ...] = ()


def _num(doc, unit="", default=REQUIRED, **rng):
    return Key("float", doc, unit, default, **rng)


def _int(doc, default=REQUIRED, **rng):
    return Key("int", doc, "", default, **rng)


def _bool(doc, default=REQUIRED):
    return Key("bool", doc, "", default)


def _str(doc, default=REQUIRED):
    return Key("str", doc, "", default)


def _enum(doc, choices, default=REQUIRED):
    return Key("enum", doc, "", default, choices=tuple(choices))


def _range(doc, unit="", default=REQUIRED, default_doc=None, **rng):
    return Key("range", doc, unit, default, default_doc=default_doc, **rng)


def _fixed_from(section, key):
    """Default of a [dataset] range: the case's own value, fixed ([v, v]); None if absent."""
    def default(sec, data):
        v = data.get(section, {}).get(key)
        return None if v is None else [float(v), float(v)]
    return default


def _default_sweep_stop(sec, data):
    z = data.get("bearing", {}).get("balls")
    start = sec.get("start_deg")
    if z is None or start is None:
        return None
    return start + 360.0 / z


_MATERIAL_KEYS = {
    "youngs_modulus_GPa": _num("Young's modulus E", "GPa", 207.5, gt=0),
    "poisson_ratio": _num("Poisson's ratio nu", "", 0.3, ge=0, lt=0.5),
    "density_kg_m3": _num("density rho; gives the ball mass for F_c and M_g",
                          "kg_m3", 7850.0, gt=0),
}

#: section path -> Section.  Order is the order of the docs and of emitted TOML.
SCHEMA: dict[str, Section] = {
    "": Section(
        "Top-level keys.",
        {
            "title": _str("one-line title of the case (plots and reports)", ""),
            "description": _str("free-form notes: sources, assumptions", ""),
        },
        required=True,
    ),
    "bearing": Section(
        "Geometry of the bearing (MODEL.md section 2).",
        {
            "balls": _int("number of balls Z", ge=3),
            "ball_diameter_mm": _num("ball diameter D", "mm", gt=0),
            "pitch_diameter_mm": _num("pitch diameter d_m", "mm", gt=0),
            "inner_groove_curvature": _num("inner groove curvature ratio f_i = r_i / D", "", gt=0.5, lt=1.0),
            "outer_groove_curvature": _num("outer groove curvature ratio f_o = r_o / D", "", gt=0.5, lt=1.0),
            "free_contact_angle_deg": _num("free (unloaded) contact angle alpha_0", "deg", OPTIONAL,
                                           ge=0, le=80),
            "diametral_clearance_mm": _num("diametral clearance P_d; then cos alpha_0 = 1 - P_d / (2 B D), "
                                           "B = f_i + f_o - 1", "mm", OPTIONAL, ge=0),
        },
        required=True,
        exactly_one=(("free_contact_angle_deg", "diametral_clearance_mm"),),
        notes=(
            "pitch_diameter_mm > ball_diameter_mm",
            "the balls fit around the pitch circle: ball_diameter_mm < pitch_diameter_mm * sin(180 deg / balls)",
            "diametral_clearance_mm gives a free contact angle within [0, 80] deg: "
            "P_d <= 2 B D (1 - cos 80 deg)",
        ),
    ),
    "material": Section(
        "Material of the rings, and of the balls unless [material.ball] is given. "
        "Default: bearing steel.",
        dict(_MATERIAL_KEYS),
    ),
    "material.ball": Section(
        "Optional ball material for hybrid bearings (e.g. silicon nitride: 310 GPa, 0.26, 3200 kg/m^3); "
        "[material] is then the rings only.  All three keys are required when the section is given.",
        {k: Key(v.type, v.doc, v.unit, REQUIRED, v.gt, v.ge, v.lt, v.le) for k, v in _MATERIAL_KEYS.items()},
        fill_defaults=False,
    ),
    "operation": Section(
        "Operating condition: inner ring turning, outer ring fixed (MODEL.md sections 1 and 4).",
        {
            "speed_rpm": _num("inner-ring speed n", "rpm", ge=0),
            "raceway_control": _enum("raceway control hypothesis for the ball kinematics",
                                     ("outer", "inner", "equal"), "outer"),
            "centrifugal": _bool("include the ball centrifugal force F_c", True),
            "gyroscopic": _bool("include the ball gyroscopic moment M_g", True),
            "cage_angle_deg": _num("cage angle theta_c: azimuth of ball 0, from +x towards +y", "deg", 0.0),
            "hertz": _enum("Hertz ellipticity and elliptic integrals: exact, or the Brewe-Hamrock "
                           "approximation", ("exact", "brewe-hamrock"), "exact"),
        },
        required=True,
    ),
    "load": Section(
        "Loads applied to the inner ring in the MODEL.md section 1 frame (z axial, +Fz loads the "
        "bearing in its contact direction; +Fx makes the ball at azimuth 0 the most loaded).",
        {
            "axial_N": _num("axial force Fz", "N", 0.0),
            "radial_x_N": _num("radial force Fx", "N", 0.0),
            "radial_y_N": _num("radial force Fy", "N", 0.0),
            "moment_x_Nm": _num("moment Mx about +x", "Nm", 0.0),
            "moment_y_Nm": _num("moment My about +y", "Nm", 0.0),
        },
    ),
    "defect": Section(
        "Optional spall on the outer raceway (MODEL.md section 5).  Absent: healthy bearing.",
        {
            "center_deg": _num("azimuth psi_d of the spall centre", "deg", 0.0),
            "extent_deg": _num("circumferential extent of the spall", "deg", OPTIONAL, gt=0),
            "length_mm": _num("arc length b of the spall along the outer raceway, "
                              "radius R_o = (d_m + D cos alpha_0) / 2", "mm", OPTIONAL, gt=0),
            "depth_mm": _num("depth d of the spall (0: healthy)", "mm", ge=0),
            "profile": _enum("depth profile under a ball: rectangular (step) or ball-path (the ball "
                             "centre follows the edges; continuous)", ("rectangular", "ball-path"),
                             "ball-path"),
        },
        fill_defaults=False,
        exactly_one=(("extent_deg", "length_mm"),),
        notes=(
            "the spall is shorter than the ball pitch 360 deg / balls: only one ball at a time "
            "may be over the spall",
            "depth_mm < bearing.ball_diameter_mm",
        ),
    ),
    "sweep": Section(
        "Cage-angle sweep (MODEL.md section 6).",
        {
            "start_deg": _num("first cage angle", "deg", 0.0),
            "stop_deg": Key("float", "last cage angle", "deg", _default_sweep_stop,
                            default_doc="start_deg + 360 / balls (one ball pitch)"),
            "steps": _int("number of cage angles, start and stop included", 181, ge=2),
        },
        notes=("stop_deg != start_deg",),
    ),
    "study": Section(
        "Optional parameter study: the case is run once per value of one key.",
        {
            "parameter": _str("dotted name of a numeric key of this schema, e.g. \"operation.speed_rpm\""),
            "values": Key("numbers", "values of the parameter, in the key's unit; each must pass "
                          "that key's validation (and the whole case must stay valid)"),
        },
        fill_defaults=False,
        notes=("parameter names a numeric key outside [study], of a section the case has "
               "(or one that has defaults)",),
    ),
    "dynamics": Section(
        "Settings of the dynamic simulation (MODEL.md section 7).",
        {
            "duration_s": _num("simulated time", "s", 1.0, gt=0),
            "sample_rate_Hz": _num("output sample rate of the signals", "Hz", 48000.0, gt=0),
            "shaft_mass_kg": _num("mass m_s of the inner ring and the shaft/rotor it carries "
                                  "(translations x, y, axial)", "kg", 2.0, gt=0),
            "housing_mass_kg": _num("mass m_h of the outer ring and housing (x, y)", "kg", 5.0, gt=0),
            "housing_stiffness_N_per_m": _num("support stiffness k_h of the housing (x and y)",
                                              "N_per_m", 5e7, gt=0),
            "housing_damping_Ns_per_m": _num("support damping c_h of the housing (x and y)",
                                             "Ns_per_m", 2000.0, ge=0),
            "resonance_frequency_Hz": _num("natural frequency f_n of the structural resonator on the "
                                           "housing (x); the sensor measures its acceleration",
                                           "Hz", 3000.0, gt=0),
            "resonance_damping_ratio": _num("damping ratio zeta of the resonator", "", 0.05, gt=0, lt=1),
            "resonator_mass_kg": _num("mass m_r of the resonator (its reaction acts on the housing)",
                                      "kg", 0.05, gt=0),
            "contact_damping_ratio": _num("bearing contact damping: c_b = 2 zeta_b sqrt(k m_s) per "
                                          "direction with k the quasi-static stiffness diagonal (x, y, axial)",
                                          "", 0.05, ge=0, lt=2),
            "unbalance_kg_m": _num("rotating unbalance m_u e of the shaft (force m_u e omega^2 at shaft "
                                   "speed, along +x at t = 0)", "kg_m", 0.0, ge=0),
            "noise_rms_m_s2": _num("white Gaussian noise added to the sensor acceleration (rms)",
                                   "m_s2", 0.0, ge=0),
            "seed": _int("seed of the noise generator", 0, ge=0),
            "rtol": _num("relative tolerance of the adaptive time integration", "", 1e-5, gt=0, lt=1),
            "atol": _num("absolute tolerance of the time integration, on displacements in um and "
                         "velocities in mm/s", "", 1e-5, gt=0),
        },
    ),
    "dataset": Section(
        "Labelled data set of simulated sensor signals (``bearingsim dataset``): ``count`` items, "
        "each a [dynamics] simulation of ``duration_s`` with its speed, loads and spall drawn "
        "uniformly from the [min, max] ranges below (min = max fixes a value); the first "
        "round(healthy_fraction x count) items are healthy (no spall).  The other [dynamics] "
        "keys (sample rate, structure, tolerances, noise) apply to every item.",
        {
            "count": _int("number of items N", ge=1),
            "seed": _int("seed of the label draw (numpy default_rng) and of the noise", 0, ge=0),
            "duration_s": _num("simulated time per item", "s", 0.1, gt=0),
            "chunk": _int("items simulated together (vmap); memory and speed trade-off", 16, ge=1),
            "healthy_fraction": _num("fraction of healthy items (spall depth and length 0)", "",
                                     0.2, ge=0, le=1),
            "speed_rpm": _range("inner-ring speed range", "rpm", _fixed_from("operation", "speed_rpm"),
                                "[operation.speed_rpm, operation.speed_rpm]", gt=0),
            "radial_N": _range("radial load range, along +x (the load zone is centred at azimuth 0)",
                               "N", _fixed_from("load", "radial_x_N"),
                               "[load.radial_x_N, load.radial_x_N]", ge=0),
            "axial_N": _range("axial load range", "N", _fixed_from("load", "axial_N"),
                              "[load.axial_N, load.axial_N]", ge=0),
            "spall_length_mm": _range("spall arc length range along the outer raceway", "mm",
                                      _fixed_from("defect", "length_mm"),
                                      "[defect.length_mm, defect.length_mm]", gt=0),
            "spall_depth_mm": _range("spall depth range", "mm", _fixed_from("defect", "depth_mm"),
                                     "[defect.depth_mm, defect.depth_mm]", ge=0),
            "spall_center_deg": _range("spall centre azimuth range (0: centre of the load zone)",
                                       "deg", _fixed_from("defect", "center_deg"),
                                       "[defect.center_deg, defect.center_deg]", ge=-360, le=360),
        },
        fill_defaults=False,
        notes=(
            "spall_length_mm and spall_depth_mm must be given when the case has no [defect] "
            "(with length_mm) to take them from",
            "spall_depth_mm max < bearing.ball_diameter_mm; spall_length_mm max shorter than the "
            "ball pitch along the outer raceway",
            "radial_N and axial_N may not both allow 0 (an unloaded bearing has no solution)",
        ),
    ),
}


def _parent(path: str) -> str | None:
    if path == "":
        return None
    return path.rpartition(".")[0]


def _subsections(path: str) -> list[str]:
    """Names (last component) of the sections directly under ``path``."""
    return [p.rpartition(".")[2] for p in SCHEMA if p != "" and _parent(p) == path]


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _split_key(dotted: str) -> tuple[str, str]:
    path, _, key = dotted.rpartition(".")
    return path, key


def _si_name(key: str, spec: Key) -> str:
    if spec.unit and key.endswith("_" + spec.unit):
        return key[: -len(spec.unit) - 1]
    return key


def _lookup(dotted: str) -> Key | None:
    path, key = _split_key(dotted)
    sec = SCHEMA.get(path)
    return None if sec is None else sec.keys.get(key)


def unit_of(dotted_key: str) -> str:
    """Unit of a case key as shown in files and messages ("mm", "rpm", "N m"; "" if none)."""
    spec = _lookup(dotted_key)
    if spec is None:
        raise KeyError(f"'{dotted_key}' is not a case key: {_suggest(dotted_key, _all_keys())}")
    return spec.unit_label


def _all_keys() -> list[str]:
    return [_join(p, k) for p, s in SCHEMA.items() for k in s.keys]


# ------------------------------------------------------------------------------------------------
# Formatting helpers
# ------------------------------------------------------------------------------------------------
def _fmt_num(x) -> str:
    """Compact number for messages: 30.0 -> '30', 0.5232 -> '0.5232', computed values to 6 digits."""
    x = float(x)
    if math.isfinite(x) and x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    s = repr(x)
    return s if len(s) <= 12 else f"{x:.6g}"


def _fmt_value(v) -> str:
    """A value as written in TOML (for messages)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_fmt_value(e) for e in v) + "]"
    if isinstance(v, dict):
        return "a table"
    return repr(v)


def _kind(v) -> str:
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, int):
        return "an integer"
    if isinstance(v, float):
        return "a float"
    if isinstance(v, str):
        return "a string"
    if isinstance(v, list):
        return "an array"
    if isinstance(v, dict):
        return "a table"
    return f"a {type(v).__name__}"  # dates and times


def _suggest(name: str, valid) -> str:
    valid = list(valid)
    close = difflib.get_close_matches(name, valid, n=1, cutoff=0.6)
    if close:
        return f"did you mean '{close[0]}'?"
    return "valid names: " + ", ".join(valid) if valid else "nothing is allowed here"


# ------------------------------------------------------------------------------------------------
# Validation
# ------------------------------------------------------------------------------------------------
def _check_value(name: str, spec: Key, v):
    """Type and range check of one value.  Returns (ok, normalised value, problem or None)."""
    t = spec.type
    shown = f"{name} = {_fmt_value(v)}"
    if t in ("float", "int"):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or (t == "int" and isinstance(v, float)):
            return False, None, f"{shown} has the wrong type: expected {_TYPE_NAMES[t]}, got {_kind(v)}"
        if isinstance(v, float) and not math.isfinite(v):
            return False, None, f"{shown} is not a finite number"
        x = float(v) if t == "float" else int(v)
        bad = ((spec.gt is not None and not x > spec.gt) or (spec.ge is not None and not x >= spec.ge)
               or (spec.lt is not None and not x < spec.lt) or (spec.le is not None and not x <= spec.le))
        if bad:
            return False, None, f"{shown} is out of range: must be {spec.requirement_text()}"
        return True, x, None
    if t == "bool":
        if not isinstance(v, bool):
            return False, None, f"{shown} has the wrong type: expected {_TYPE_NAMES[t]}, got {_kind(v)}"
        return True, v, None
    if t in ("str", "enum"):
        if not isinstance(v, str):
            return False, None, f"{shown} has the wrong type: expected {_TYPE_NAMES[t]}, got {_kind(v)}"
        if t == "enum" and v not in spec.choices:
            close = difflib.get_close_matches(v, spec.choices, n=1, cutoff=0.6)
            hint = f" (did you mean {json.dumps(close[0])}?)" if close else ""
            return False, None, f"{shown} is not allowed: must be {spec.requirement_text()}{hint}"
        return True, v, None
    if t == "range":
        if not isinstance(v, list):
            return False, None, f"{shown} has the wrong type: expected {_TYPE_NAMES[t]}, got {_kind(v)}"
        if len(v) != 2:
            return False, None, f"{shown} must have exactly two elements [min, max], got {len(v)}"
        xs = []
        for e in v:
            if isinstance(e, bool) or not isinstance(e, (int, float)) or not math.isfinite(e):
                return False, None, f"{shown} must hold two finite numbers [min, max], got {_fmt_value(e)}"
            x = float(e)
            if ((spec.gt is not None and not x > spec.gt) or (spec.ge is not None and not x >= spec.ge)
                    or (spec.lt is not None and not x < spec.lt) or (spec.le is not None and not x <= spec.le)):
                return False, None, f"{shown} is out of range: must be {spec.requirement_text()}"
            xs.append(x)
        if xs[0] > xs[1]:
            return False, None, f"{shown} has min > max: must be {spec.requirement_text()}"
        return True, xs, None
    if t == "numbers":
        if not isinstance(v, list):
            return False, None, f"{shown} has the wrong type: expected {_TYPE_NAMES[t]}, got {_kind(v)}"
        if not v:
            return False, None, f"{name} is empty: give at least one value"
        return True, list(v), None
    raise AssertionError(f"unknown key type {t!r}")


def _check_structure(raw: dict, path: str, problems: list[str]) -> None:
    """Unknown sections / keys, and tables where values belong (and vice versa)."""
    sec = SCHEMA[path]
    subs = _subsections(path)
    valid = list(sec.keys) + subs
    for name, v in raw.items():
        full = _join(path, name)
        if name in sec.keys:
            if isinstance(v, dict):
                problems.append(f"{full} must be a value ({_TYPE_NAMES[sec.keys[name].type]}), not a table")
        elif name in subs:
            if not isinstance(v, dict):
                problems.append(f"[{full}] must be a table (section), got {_kind(v)} {_fmt_value(v)}")
            else:
                _check_structure(v, full, problems)
        elif isinstance(v, dict):
            where = "" if path == "" else f" in [{path}]"
            problems.append(f"unknown section [{full}]{where}: {_suggest(name, subs if path == '' else valid)}")
        else:
            where = "top-level key" if path == "" else "key"
            inside = "" if path == "" else f" in [{path}]"
            problems.append(f"unknown {where} '{name}'{inside}: {_suggest(name, valid)}")


def _section_raw(raw: dict, path: str):
    """The raw table of ``path`` (None if absent or not a table)."""
    node = raw
    if path == "":
        return node
    for part in path.split("."):
        if not isinstance(node, dict):
            return None
        node = node.get(part)
    return node if isinstance(node, dict) else None


def _validate_sections(raw: dict, problems: list[str]) -> dict:
    """Per-key checks and defaults; returns the normalised data (valid values only)."""
    data: dict = {}
    for path, sec in SCHEMA.items():
        tab = _section_raw(raw, path)
        if tab is None:
            if sec.required:
                problems.append(f"missing required section [{path}]")
            if not sec.fill_defaults or sec.required:
                continue
            tab = {}
        out: dict = {}
        for key, spec in sec.keys.items():
            full = _join(path, key)
            if key in tab:
                if isinstance(tab[key], dict):
                    continue  # reported by _check_structure
                ok, x, msg = _check_value(full, spec, tab[key])
                if ok:
                    out[key] = x
                else:
                    problems.append(msg)
            elif spec.default is REQUIRED:
                if _section_raw(raw, path) is not None:
                    problems.append(f"missing required key {full}: must be {spec.requirement_text()} "
                                    f"({spec.doc})")
            elif spec.default is OPTIONAL or callable(spec.default):
                pass
            else:
                out[key] = spec.default
        if _section_raw(raw, path) is not None:
            for group in sec.exactly_one:
                given = [k for k in group if k in tab]
                names = " or ".join(_join(path, k) for k in group)
                if len(given) > 1:
                    problems.append(f"give exactly one of {names}, not both")
                elif not given:
                    problems.append(f"missing key: give exactly one of {names}")
        _set_section(data, path, out)
    # computed defaults, once every section is known
    for path, sec in SCHEMA.items():
        out = _section_raw(data, path)
        if out is None:
            continue
        tab = _section_raw(raw, path) or {}
        for key, spec in sec.keys.items():
            if callable(spec.default) and key not in tab:
                val = spec.default(out, data)
                if val is not None:
                    out[key] = val
    return data


def _set_section(data: dict, path: str, out: dict) -> None:
    if path == "":
        data.update(out)
        return
    node = data
    parts = path.split(".")
    for part in parts[:-1]:
        node = node.setdefault(part, {})
    existing = node.get(parts[-1], {})
    out.update({k: v for k, v in existing.items() if isinstance(v, dict)})
    node[parts[-1]] = out


def _free_contact_angle_deg(b: dict) -> float | None:
    """alpha_0 in deg from either key (None if not computable)."""
    if "free_contact_angle_deg" in b:
        return b["free_contact_angle_deg"]
    need = ("diametral_clearance_mm", "ball_diameter_mm", "inner_groove_curvature", "outer_groove_curvature")
    if not all(k in b for k in need):
        return None
    B = b["inner_groove_curvature"] + b["outer_groove_curvature"] - 1.0
    c = 1.0 - b["diametral_clearance_mm"] / (2.0 * B * b["ball_diameter_mm"])
    if not -1.0 <= c <= 1.0:
        return None
    return math.degrees(math.acos(c))


def _cross_checks(data: dict, problems: list[str], raw: dict | None = None) -> None:
    """Checks between keys; each runs only when the keys it needs are individually valid.
    Values are shown as written in ``raw`` (the file) when given there."""
    b = data.get("bearing", {})
    has = lambda d, *ks: all(k in d for k in ks)  # noqa: E731

    def shown(path, key):
        tab = _section_raw(raw or {}, path)
        v = tab[key] if tab is not None and key in tab else _section_raw(data, path)[key]
        return _fmt_value(v)

    geometry_ok = True
    if has(b, "ball_diameter_mm", "pitch_diameter_mm"):
        D, dm = b["ball_diameter_mm"], b["pitch_diameter_mm"]
        if not dm > D:
            geometry_ok = False
            problems.append(f"bearing.pitch_diameter_mm = {shown('bearing', 'pitch_diameter_mm')} must be "
                            f"greater than bearing.ball_diameter_mm = {shown('bearing', 'ball_diameter_mm')}")
        elif "balls" in b:
            Z = b["balls"]
            limit = dm * math.sin(math.pi / Z)
            if not D < limit:
                geometry_ok = False
                problems.append(
                    f"bearing.balls = {Z}: {Z} balls of diameter {shown('bearing', 'ball_diameter_mm')} mm overlap on the pitch "
                    f"circle of {shown('bearing', 'pitch_diameter_mm')} mm: need ball_diameter_mm < pitch_diameter_mm * "
                    f"sin(180 deg / balls) = {_fmt_num(limit)} mm (at most "
                    f"{int(math.floor(math.pi / math.asin(min(1.0, D / dm)) - 1e-12))} balls)")
    else:
        geometry_ok = False

    if has(b, "diametral_clearance_mm", "ball_diameter_mm", "inner_groove_curvature", "outer_groove_curvature"):
        D, Pd = b["ball_diameter_mm"], b["diametral_clearance_mm"]
        B = b["inner_groove_curvature"] + b["outer_groove_curvature"] - 1.0
        amax = SCHEMA["bearing"].keys["free_contact_angle_deg"].le
        limit = 2.0 * B * D * (1.0 - math.cos(math.radians(amax)))
        if Pd > limit:
            geometry_ok = False
            problems.append(
                f"bearing.diametral_clearance_mm = {shown('bearing', 'diametral_clearance_mm')} is too large: with these groove "
                f"curvatures (B = f_i + f_o - 1 = {_fmt_num(B)}) it gives a free contact angle above "
                f"{_fmt_num(amax)} deg; must be <= 2 B D (1 - cos {_fmt_num(amax)} deg) = {_fmt_num(limit)} mm")

    d = data.get("defect")
    if d is not None:
        if "depth_mm" in d and "ball_diameter_mm" in b and not d["depth_mm"] < b["ball_diameter_mm"]:
            problems.append(f"defect.depth_mm = {shown('defect', 'depth_mm')} must be less than the ball "
                            f"diameter bearing.ball_diameter_mm = {shown('bearing', 'ball_diameter_mm')}")
        if "balls" in b:
            pitch = 360.0 / b["balls"]
            if "extent_deg" in d and not d["extent_deg"] < pitch:
                problems.append(f"defect.extent_deg = {shown('defect', 'extent_deg')} is longer than the ball "
                                f"pitch {_fmt_num(pitch)} deg: only one ball at a time may be over the spall")
            alpha0 = _free_contact_angle_deg(b)
            if "length_mm" in d and geometry_ok and alpha0 is not None:
                R_o = 0.5 * (b["pitch_diameter_mm"] + b["ball_diameter_mm"] * math.cos(math.radians(alpha0)))
                extent = math.degrees(d["length_mm"] / R_o)
                if not extent < pitch:
                    problems.append(
                        f"defect.length_mm = {shown('defect', 'length_mm')} is longer than the ball pitch "
                        f"{_fmt_num(pitch)} deg = {_fmt_num(math.radians(pitch) * R_o)} mm along the outer "
                        f"raceway (R_o = {_fmt_num(R_o)} mm; the spall spans {_fmt_num(extent)} deg): "
                        f"only one ball at a time may be over the spall")

    _dataset_checks(data, problems, geometry_ok, raw)

    s = data.get("sweep")
    if s is not None and has(s, "start_deg", "stop_deg") and s["start_deg"] == s["stop_deg"]:
        problems.append(f"sweep.stop_deg = {shown('sweep', 'stop_deg')} must differ from "
                        f"sweep.start_deg = {shown('sweep', 'start_deg')}")


def _dataset_checks(data: dict, problems: list[str], geometry_ok: bool, raw: dict | None) -> None:
    ds = data.get("dataset")
    if ds is None:
        return
    b = data.get("bearing", {})
    for key in ("spall_length_mm", "spall_depth_mm"):
        if key not in ds and data.get("defect", {}).get(key[len("spall_"):]) is None:
            if key not in (_section_raw(raw or {}, "dataset") or {}):  # else invalid, reported
                problems.append(f"missing key dataset.{key}: must be {SCHEMA['dataset'].keys[key].requirement_text()} "
                                f"(the case has no [defect] {key[len('spall_'):]} to take it from)")
    if "spall_depth_mm" in ds and "ball_diameter_mm" in b and not ds["spall_depth_mm"][1] < b["ball_diameter_mm"]:
        problems.append(f"dataset.spall_depth_mm = {_fmt_value(ds['spall_depth_mm'])}: the largest depth must be "
                        f"less than bearing.ball_diameter_mm = {_fmt_num(b['ball_diameter_mm'])}")
    alpha0 = _free_contact_angle_deg(b)
    if "spall_length_mm" in ds and geometry_ok and "balls" in b and alpha0 is not None:
        R_o = 0.5 * (b["pitch_diameter_mm"] + b["ball_diameter_mm"] * math.cos(math.radians(alpha0)))
        pitch = 2.0 * math.pi / b["balls"] * R_o
        if not ds["spall_length_mm"][1] < pitch:
            problems.append(f"dataset.spall_length_mm = {_fmt_value(ds['spall_length_mm'])}: the longest spall "
                            f"must be shorter than the ball pitch {_fmt_num(pitch)} mm along the outer raceway: "
                            "only one ball at a time may be over the spall")
    if "radial_N" in ds and "axial_N" in ds and ds["radial_N"][0] <= 0.0 and ds["axial_N"][0] <= 0.0:
        problems.append(f"dataset.radial_N = {_fmt_value(ds['radial_N'])} and dataset.axial_N = "
                        f"{_fmt_value(ds['axial_N'])} both allow 0: an unloaded bearing has no solution; "
                        "raise the minimum of one of them")


def _study_problems(raw: dict, data: dict, base_ok: bool) -> list[str]:
    st = data.get("study")
    if st is None or "parameter" not in st:
        return []
    problems = []
    param = st["parameter"]
    shown = f"study.parameter = {_fmt_value(param)}"
    spec = _lookup(param)
    path, _ = _split_key(param)
    if spec is None:
        numeric = [k for k in _all_keys() if _lookup(k).numeric and not k.startswith("study.")]
        return [f"{shown} is not a key of the case schema: {_suggest(param, numeric)}"]
    if path == "study" or not spec.numeric:
        return [f"{shown} must name a numeric key (float or integer) outside [study]; "
                f"{param} is {_TYPE_NAMES[spec.type]}"]
    if _section_raw(raw, path) is None and not SCHEMA[path].fill_defaults:
        return [f"{shown} names a key of [{path}], which this case does not have"]
    for i, v in enumerate(st.get("values", [])):
        ok, x, msg = _check_value(param, spec, v)
        if not ok:
            problems.append(f"study.values[{i}]: {msg}")
        elif base_ok:
            trial = _set_raw(raw, param, x)
            trial.pop("study", None)
            sub: list[str] = []
            _cross_checks(_validate_sections(trial, sub), sub, trial)
            problems.extend(f"study.values[{i}] ({param} = {_fmt_value(v)}): {p}" for p in sub)
    return problems


def _validate(raw: dict, source: str) -> dict:
    problems: list[str] = []
    _check_structure(raw, "", problems)
    data = _validate_sections(raw, problems)
    _cross_checks(data, problems, raw)
    problems.extend(_study_problems(raw, data, base_ok=not problems))
    if problems:
        raise CaseError(source, problems)
    return data


def _set_raw(raw: dict, dotted: str, value) -> dict:
    """Deep copy of ``raw`` with ``dotted`` set; the other member of an exactly-one group goes."""
    new = copy.deepcopy(raw)
    path, key = _split_key(dotted)
    node = new
    if path:
        for part in path.split("."):
            nxt = node.get(part)
            if not isinstance(nxt, dict):
                nxt = node[part] = {}
            node = nxt
    sec = SCHEMA.get(path)
    if sec is not None:
        for group in sec.exactly_one:
            if key in group:
                for other in group:
                    if other != key:
                        node.pop(other, None)
    node[key] = value
    return new


# ------------------------------------------------------------------------------------------------
# TOML emitter (tomllib only reads)
# ------------------------------------------------------------------------------------------------
_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def _toml_key(k: str) -> str:
    return k if _BARE_KEY.match(k) else _toml_str(k)


def _toml_str(s: str) -> str:
    out = ['"']
    for ch in s:
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)  # always has '.', 'e' or is inf/nan: a TOML float
    if isinstance(v, str):
        return _toml_str(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(e) for e in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} {v!r} to TOML")


def to_toml(data: dict, header: str | None = None) -> str:
    """TOML text for a nested dict of str / bool / int / float / lists of those / tables.

    ``tomllib.loads(to_toml(d)) == d`` for such dicts.  ``header`` is written as comment lines.
    """
    lines: list[str] = []
    if header:
        lines += ["# " + h if h else "#" for h in header.splitlines()]

    def table(d: dict, path: list[str]):
        scalars = [(k, v) for k, v in d.items() if not isinstance(v, dict)]
        tables = [(k, v) for k, v in d.items() if isinstance(v, dict)]
        if path:
            if lines:
                lines.append("")
            lines.append("[" + ".".join(_toml_key(p) for p in path) + "]")
        for k, v in scalars:
            lines.append(f"{_toml_key(k)} = {_toml_value(v)}")
        for k, v in tables:
            table(v, path + [k])

    table(data, [])
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------------------------------------
# Case
# ------------------------------------------------------------------------------------------------
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
        path, key = _split_key(dotted_key)
        if dotted_key in SCHEMA:
            sec = _section_raw(self.data, dotted_key)
            return None if sec is None else copy.deepcopy(sec)
        if path not in SCHEMA or key not in SCHEMA[path].keys:
            valid = _all_keys() + [p for p in SCHEMA if p]
            raise KeyError(f"'{dotted_key}' is not a case key: {_suggest(dotted_key, valid)}")
        sec = _section_raw(self.data, path)
        return None if sec is None else copy.deepcopy(sec.get(key))

    def with_value(self, dotted_key: str, value) -> "Case":
        """A new validated case with one key changed (engineering units, as in the file).

        Setting one key of an exactly-one pair (e.g. ``bearing.diametral_clearance_mm``) removes
        the other.  Computed defaults (``sweep.stop_deg``) follow the change unless given
        explicitly.  The new ``text`` is the TOML of the changed file (comments are not kept).
        Raises CaseError if the result is invalid.
        """
        if _lookup(dotted_key) is None:
            valid = _all_keys()
            raise KeyError(f"'{dotted_key}' is not a case key: {_suggest(dotted_key, valid)}")
        if hasattr(value, "item") and not isinstance(value, (bool, int, float, str)):
            value = value.item()  # numpy / jax scalars
        raw = _set_raw(self.raw, dotted_key, value)
        text = to_toml(raw, header=f"{self.source} with {dotted_key} = {_fmt_value(value)}")
        return _case_from_raw(raw, text, self.source)

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
    def _si(self, path: str) -> dict:
        """Section ``path`` in SI, keys without their unit suffix."""
        sec = _section_raw(self.data, path) or {}
        out = {}
        for key, spec in SCHEMA[path].keys.items():
            if key in sec:
                v = sec[key]
                f = UNITS[spec.unit][0]
                out[_si_name(key, spec)] = (v * f if spec.type == "float" else
                                            [x * f for x in v] if spec.type == "range" else v)
        return out

    def _material(self, path: str):
        from .geometry import Material
        m = self._si(path)
        return Material(m["youngs_modulus"], m["poisson_ratio"], m["density"])

    def bearing(self):
        """:class:`bearingsim.Bearing` in SI."""
        from .geometry import Bearing
        b = self._si("bearing")
        rings = self._material("material")
        balls = self._material("material.ball") if _section_raw(self.data, "material.ball") else rings
        args = (b["balls"], b["ball_diameter"], b["pitch_diameter"], b["inner_groove_curvature"],
                b["outer_groove_curvature"])
        if "diametral_clearance" in b:
            return Bearing.from_clearance(*args, b["diametral_clearance"], ball_material=balls,
                                          ring_material=rings)
        return Bearing(*args, b["free_contact_angle"], balls, rings)

    def operation(self):
        """:class:`bearingsim.Operation` (speed in rad/s via ``Operation.from_rpm``)."""
        from .kinematics import Operation
        o = self.data["operation"]
        return Operation.from_rpm(o["speed_rpm"], o["raceway_control"], o["centrifugal"], o["gyroscopic"])

    @property
    def hertz_method(self) -> str:
        """"exact" or "brewe-hamrock" (the solvers' ``hertz_method``)."""
        return self.data["operation"]["hertz"]

    @property
    def cage_angle(self) -> float:
        """Cage angle theta_c (rad)."""
        return self._si("operation")["cage_angle"]

    def loads(self):
        """Inner-ring loads [Fx, Fy, Fz, Mx, My] (N, N m) as a float64 jax array."""
        from .jones import load_vector
        ld = self._si("load")
        return load_vector(axial=ld["axial"], radial_x=ld["radial_x"], radial_y=ld["radial_y"],
                           moment_x=ld["moment_x"], moment_y=ld["moment_y"])

    def spall(self):
        """:class:`bearingsim.Spall` (rad, m), or None for a healthy bearing (no [defect])."""
        from .defect import Spall
        if "defect" not in self.data:
            return None
        d = self._si("defect")
        if "length" in d:
            return Spall.from_length(self.bearing(), d["center"], d["length"], d["depth"], d["profile"])
        return Spall(d["center"], d["extent"], d["depth"], d["profile"])

    def sweep_settings(self) -> dict:
        """dict(start=rad, stop=rad, steps=int); defaults: 0, one ball pitch 2 pi / Z, 181."""
        return self._si("sweep")

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
        return self._si("dataset")

    def dynamics_settings(self) -> dict:
        """The [dynamics] keys in SI without unit suffix: dict(duration=s, sample_rate=Hz, ...)."""
        return self._si("dynamics")


def _case_from_raw(raw: dict, text: str, source: str) -> Case:
    data = _validate(raw, source)
    return Case(source=source, text=text, data=data, raw=raw)


def parse_case(text: str, source: str = "<string>") -> Case:
    """Parse and validate TOML case text.  Raises CaseError listing every problem."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise CaseError(source, [f"invalid TOML: {e}"]) from None
    return _case_from_raw(raw, text, source)


def shipped_cases_dir() -> Path:
    """Folder of the cases shipped with bearingsim: ``bearingsim/cases`` in an installed wheel,
    the top-level ``cases/`` of a source checkout (editable install)."""
    from importlib.resources import files

    installed = Path(str(files("bearingsim"))) / "cases"
    return installed if installed.is_dir() else Path(__file__).resolve().parent.parent / "cases"


def shipped_cases() -> list[str]:
    """Names of the shipped cases, as :func:`load_case` takes them ("demo", "seed/speed", ...)."""
    root = shipped_cases_dir()
    return sorted(p.relative_to(root).with_suffix("").as_posix() for p in root.rglob("*.toml"))


def case_path(name_or_path) -> Path:
    """The file a case argument names: an existing file as given, else a shipped case by name
    (``"cwru_6205"``, ``"seed/speed"``, with or without ``.toml``).  Raises CaseError."""
    p = Path(name_or_path)
    if p.is_dir():
        raise CaseError(str(name_or_path), ["is a directory, not a case file: give a .toml file"])
    if p.is_file():
        return p
    names = shipped_cases()
    name = p.as_posix().removesuffix(".toml")
    if name in names:
        return shipped_cases_dir() / f"{name}.toml"
    close = difflib.get_close_matches(name, names, n=1, cutoff=0.6)
    hint = f"did you mean '{close[0]}'?" if close else "shipped cases: " + ", ".join(names)
    raise CaseError(str(name_or_path), [f"no such case file, and no shipped case of that name: {hint}"])


def load_case(name_or_path) -> Case:
    """Read and validate a case file, or a shipped case by name (see :func:`case_path`).  Error
    lines are prefixed with the path as given."""
    p = case_path(name_or_path)
    source = str(name_or_path) if p == Path(name_or_path) else str(p)
    return parse_case(p.read_text(encoding="utf-8"), source=source)


def case_from_dict(data: dict, source: str = "<dict>") -> Case:
    """Validate a nested dict shaped like a case file (engineering units)."""
    raw = copy.deepcopy(data)
    return _case_from_raw(raw, to_toml(raw), source)


# ------------------------------------------------------------------------------------------------
# Documentation
# ------------------------------------------------------------------------------------------------
def _md(s: str) -> str:
    return s.replace("|", "\\|")


def schema_reference_markdown() -> str:
    """Markdown reference of the case format: one table per section, generated from SCHEMA."""
    out = ["# Case file reference", "",
           "Case files are TOML.  Units are part of the key names; the reader converts to SI. "
           "Unknown sections or keys are errors; all problems of a file are reported together.", ""]
    for path, sec in SCHEMA.items():
        out.append("## Top level" if path == "" else f"## [{path}]")
        out.append("")
        status = "required" if sec.required else (
            "optional; defaults apply when absent" if sec.fill_defaults else "optional")
        out.append(sec.doc if path == "" else f"{sec.doc} ({status})")
        out.append("")
        out.append("| key | type | unit | default | allowed range | meaning |")
        out.append("|---|---|---|---|---|---|")
        for key, spec in sec.keys.items():
            typ = {"float": "float", "int": "integer", "bool": "boolean", "str": "string",
                   "enum": "string", "numbers": "array of numbers",
                   "range": "[min, max]"}[spec.type]
            if spec.default_doc is not None:
                default = spec.default_doc
            elif spec.default is REQUIRED:
                default = "required"
            elif spec.default is OPTIONAL:
                group = next((g for g in sec.exactly_one if key in g), None)
                default = ("exactly one of " + ", ".join(f"`{k}`" for k in group)) if group else "none"
            else:
                default = f"`{_toml_value(spec.default)}`"
            if spec.type == "enum":
                allowed = ", ".join(f'`"{c}"`' for c in spec.choices)
            elif spec.numeric:
                allowed = spec.range_text() or "any finite number"
                if spec.type == "int":
                    allowed = "integer " + allowed if spec.range_text() else "any integer"
            elif spec.type == "bool":
                allowed = "`true`, `false`"
            elif spec.type == "numbers":
                allowed = "non-empty"
            elif spec.type == "range":
                allowed = "min <= max" + (f"; each {spec.range_text()}" if spec.range_text() else "")
            else:
                allowed = "any"
            out.append(f"| `{key}` | {typ} | {spec.unit_label or '-'} | {_md(default)} | {_md(allowed)} "
                       f"| {_md(spec.doc)} |")
        if sec.notes or sec.exactly_one:
            out.append("")
            for g in sec.exactly_one:
                out.append("- give exactly one of " + ", ".join(f"`{k}`" for k in g))
            for n in sec.notes:
                out.append(f"- {_md(n)}")
        out.append("")
    return "\n".join(out)
