"""The case-file schema: one table (:data:`SCHEMA`) of sections -> keys -> :class:`Key` specs
(type, default, allowed range, unit, doc), from which validation, defaults, error messages, the
SI conversion and the reference page all follow.  A new key is one new row.

Units are part of the key names; the suffix is a unit of :mod:`bearingsim.case.units`.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

from ..physics.defect import LOCATIONS
from .messages import fmt_num, suggest
from .units import label

__all__ = ["REQUIRED", "OPTIONAL", "TYPE_NAMES", "Key", "Section", "SCHEMA", "parent", "subsections",
           "join_key", "split_key", "si_name", "lookup", "unit_of", "all_keys"]


class _Marker:
    def __init__(self, name):
        self.name = name

    def __repr__(self):
        return self.name


#: default marker: the key must be given
REQUIRED = _Marker("REQUIRED")
#: default marker: the key may be absent and then has no value (e.g. one of an exactly-one pair)
OPTIONAL = _Marker("OPTIONAL")

TYPE_NAMES = {
    "float": "a number",
    "int": "an integer",
    "bool": "a boolean (true or false)",
    "str": "a string",
    "enum": "a string",
    "numbers": "a non-empty array of numbers",
    "names": "an array of strings",
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
        return label(self.unit)

    def range_text(self) -> str:
        """'>= 3', '> 0.5 and < 1', ... with the unit; '' when unbounded."""
        parts = []
        if self.gt is not None:
            parts.append(f"> {fmt_num(self.gt)}")
        if self.ge is not None:
            parts.append(f">= {fmt_num(self.ge)}")
        if self.lt is not None:
            parts.append(f"< {fmt_num(self.lt)}")
        if self.le is not None:
            parts.append(f"<= {fmt_num(self.le)}")
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
        return TYPE_NAMES[self.type]


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


def _names(doc, choices, default=REQUIRED):
    return Key("names", doc, "", default, choices=tuple(choices))


def _range(doc, unit="", default=REQUIRED, default_doc=None, **rng):
    return Key("range", doc, unit, default, default_doc=default_doc, **rng)


def _fixed_from(section, key):
    """Default of a [dataset] range: the case's own value, fixed ([v, v]); None if absent."""
    def default(sec, data):
        v = data.get(section, {}).get(key)
        return None if v is None else [float(v), float(v)]
    return default


def _same_as(key):
    """Default of a [dataset] range: the same section's ``key`` (already filled)."""
    def default(sec, data):
        v = sec.get(key)
        return None if v is None else list(v)
    return default


def _rest_fraction(sec, data):
    return max(0.0, 1.0 - sum(float(sec.get(k, d)) for k, d in (("healthy_fraction", 0.2),
                                                                  ("inner_fraction", 0.0),
                                                                  ("ball_fraction", 0.0))))


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

_BEARING_KEYS = {
            "balls": _int("number of balls Z", ge=3),
            "ball_diameter_mm": _num("ball diameter D", "mm", gt=0),
            "pitch_diameter_mm": _num("pitch diameter d_m", "mm", gt=0),
            "inner_groove_curvature": _num("inner groove curvature ratio f_i = r_i / D", "", gt=0.5, lt=1.0),
            "outer_groove_curvature": _num("outer groove curvature ratio f_o = r_o / D", "", gt=0.5, lt=1.0),
            "free_contact_angle_deg": _num("free (unloaded) contact angle alpha_0", "deg", OPTIONAL,
                                           ge=0, le=80),
            "diametral_clearance_mm": _num("diametral clearance P_d; then cos alpha_0 = 1 - P_d / (2 B D), "
                                           "B = f_i + f_o - 1", "mm", OPTIONAL, ge=0),
    "design": _enum("bearing design, for its shoulders and its life: \"deep_groove\" (full shoulders on "
                    "both sides of both rings, nominal contact angle 0), \"angular_contact\" (one high and "
                    "one low shoulder per ring: axial load in +z only), \"auto\" (deep groove when given "
                    "by diametral_clearance_mm or alpha_0 = 0, else angular contact)",
                    ("auto", "deep_groove", "angular_contact"), "auto"),
    "dynamic_load_rating_kN": _num("basic dynamic load rating C (catalogue); gives the ISO/TS 16281 "
                                   "rating life L10r in `bearingsim static` (of each bearing and of the "
                                   "set for a [set] case)", "kN", OPTIONAL, gt=0),
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
        "Geometry of the bearing (docs/model.md section 2).",
        dict(_BEARING_KEYS),
        required=True,
        exactly_one=(("free_contact_angle_deg", "diametral_clearance_mm"),),
        notes=(
            "pitch_diameter_mm > ball_diameter_mm",
            "the balls fit around the pitch circle: ball_diameter_mm < pitch_diameter_mm * sin(180 deg / balls)",
            "diametral_clearance_mm gives a free contact angle within [0, 80] deg: "
            "P_d <= 2 B D (1 - cos 80 deg)",
        ),
    ),
    "shoulders": Section(
        "Groove-edge (shoulder) angles of the rings, measured at the groove's curvature centre from the "
        "groove bottom, positive on the side of the contact direction (docs/physics.md \"Shoulders\"); a "
        "land height h (in ball diameters) above the groove bottom is the angle arccos(1 - h / f).  Each key "
        "defaults to the design's value: deep groove h = 0.2 D on both sides (~52 deg), angular contact "
        "h = 0.38 D high (~74 deg) and 0.01 D low (~11 deg).",
        {
            "inner_high_deg": _num("inner ring, high-shoulder side", "deg", OPTIONAL, gt=0, lt=90),
            "inner_low_deg": _num("inner ring, low-shoulder side", "deg", OPTIONAL, ge=0, lt=90),
            "outer_high_deg": _num("outer ring, high-shoulder side", "deg", OPTIONAL, gt=0, lt=90),
            "outer_low_deg": _num("outer ring, low-shoulder side", "deg", OPTIONAL, ge=0, lt=90),
        },
        fill_defaults=False,
    ),
    "limits": Section(
        "Limits reported per contact by `bearingsim static` (docs/model.md section 11).",
        {
            "contact_pressure_limit_MPa": _num("peak Hertz pressure limit (ISO 76 static capacity of ball "
                                               "bearings: 4200 MPa)", "MPa", 4200.0, gt=0),
            "friction_coefficient": _num("friction (traction) coefficient available at a raceway contact, "
                                         "against which the coefficient raceway control needs, "
                                         "lambda M_g / (D Q), is checked (an estimate: 0.03-0.1 lubricated)",
                                         "", 0.07, gt=0),
        },
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
        "Operating condition: inner ring turning, outer ring fixed (docs/model.md sections 1 and 4).",
        {
            "speed_rpm": _num("inner-ring speed n", "rpm", ge=0),
            "raceway_control": _enum("raceway control hypothesis for the ball kinematics",
                                     ("outer", "inner", "equal"), "outer"),
            "centrifugal": _bool("include the ball centrifugal force F_c", True),
            "gyroscopic": _bool("include the ball gyroscopic moment M_g", True),
            "cage_angle_deg": _num("cage angle theta_c: azimuth of ball 0, from +x towards +y", "deg", 0.0),
            "hertz": _enum("Hertz ellipticity and elliptic integrals: exact, or the Brewe-Hamrock "
                           "approximation", ("exact", "brewe-hamrock"), "exact"),
            "tilt": _enum("the inner ring's tilt: \"free\" (force-controlled: the moments of [load] act, "
                          "the tilts are solved; with no moment a radial load tilts the ring) or \"held\" "
                          "(a displacement-controlled tilt of zero, the usual spindle assumption: the "
                          "translations are solved under the forces and the moments that hold the ring "
                          "square are reported)", ("free", "held"), "free"),
        },
        required=True,
        notes=(
            "tilt = \"held\": the moments of [load] must be 0 (they are the result) and the case has no "
            "[set] (a set's shaft tilt is solved from its bearings); `bearingsim static`, `bearingsim rotor` "
            "and the Python API solve it, `sweep`, `study`, `simulate`, `compare` and `dataset` refuse it",
        ),
    ),
    "load": Section(
        "Loads applied to the inner ring in the docs/model.md section 1 frame (z axial, +Fz loads the "
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
        "Optional localized defect (docs/model.md sections 5 and 9): a spall on the outer raceway "
        "(default), a spall on the inner raceway, or a pit on one ball.  Absent: healthy bearing.",
        {
            "location": _enum("where the defect is: outer raceway, inner raceway (turns with the inner "
                              "ring), or a pit on one ball", LOCATIONS, "outer"),
            "center_deg": _num("azimuth of the spall centre (outer or inner raceway; for the inner "
                               "raceway at the instant t = 0 of the solve, psi_di = center + omega t); "
                               "not used for a ball pit", "deg", 0.0),
            "extent_deg": _num("angular extent: about the bearing axis for a raceway spall, about the "
                               "ball centre for a ball pit", "deg", OPTIONAL, gt=0),
            "length_mm": _num("arc length b of the defect on its surface: along the outer raceway "
                              "(R_o = (d_m + D cos alpha_0) / 2), the inner raceway "
                              "(R_ir = (d_m - D cos alpha_0) / 2), or the pit diameter on the ball "
                              "surface (radius D / 2)", "mm", OPTIONAL, gt=0),
            "depth_mm": _num("depth d of the defect (0: healthy)", "mm", ge=0),
            "profile": _enum("depth profile under a contact: rectangular (step) or ball-path (the "
                             "contact follows the edges; continuous)", ("rectangular", "ball-path"),
                             "ball-path"),
            "ball_index": _int("ball pit only (default 0): index j of the pitted ball (the ball at "
                               "azimuth cage_angle + 360 j / balls)", OPTIONAL, ge=0),
            "spin_angle_deg": _num("ball pit only (default 0): the pit's angle on the ball's rolling "
                                   "great circle from its outer contact (0: in the outer contact, 180: "
                                   "in the inner contact)", "deg", OPTIONAL),
        },
        fill_defaults=False,
        exactly_one=(("extent_deg", "length_mm"),),
        notes=(
            "a raceway spall is shorter than the ball pitch 360 deg / balls along its raceway: only "
            "one ball at a time may be over the spall",
            "a ball pit spans less than 180 deg of the ball (it cannot touch both contacts at once)",
            "ball_index < bearing.balls; ball_index and spin_angle_deg only with location = \"ball\", "
            "center_deg not with it",
            "depth_mm < bearing.ball_diameter_mm",
        ),
    ),
    "set": Section(
        "Optional: a rigid shaft on several bearings (docs/model.md section 10).  [bearing] is every "
        "bearing of the set (unless [set.second_bearing]); [load] acts on the shaft at z = 0 in the "
        "shaft frame; bearing k (k = 1..N by increasing position) faces +1 (carries +Fz, the bearing "
        "of docs/model.md section 1) or -1 (mirrored).  Either an arrangement name with a spacing, or explicit "
        "facings and positions.",
        {
            "arrangement": _str("named arrangement, bearings by increasing z: DB (back to back, "
                                "facings +1 -1), DF (face to face, -1 +1), DT (tandem, +1 +1), TBT, "
                                "TFT, TT, QBC, QFC, QBT, QFT, QT", OPTIONAL),
            "facings": Key("numbers", "explicit facing of each bearing, +1 or -1", "", OPTIONAL),
            "spacing_mm": _num("distance between neighbouring bearings of an arrangement", "mm",
                               OPTIONAL, gt=0),
            "positions_mm": Key("numbers", "axial position z_k of each bearing's inner groove-centre "
                                "plane (default for an arrangement: 0, spacing, 2 spacing, ...)", "mm",
                                OPTIONAL),
            "preload_N": _num("preload of the set (rigid): each bearing of a facing group carries "
                              "preload / (bearings facing that way) at standstill", "N", OPTIONAL, ge=0),
            "preload_class": _enum("preload class instead of preload_N: light / medium / heavy = "
                                   "0.3 / 0.6 / 1.2 % of the bearing's static axial capacity C_0a "
                                   "(p_max = 4.2 GPa at standstill): bearingsim's own convention, not a "
                                   "catalogue's classes", ("light", "medium", "heavy"),
                                   OPTIONAL),
            "preloads_N": Key("numbers", "preload of each bearing (N): its thrust at standstill "
                              "(rigid), or its constant spring force (spring_bearings)", "N", OPTIONAL),
            "spring_bearings": Key("numbers", "bearings (1-based, by position) whose outer ring floats "
                                   "on a spring: constant preload", "", OPTIONAL),
            "second_bearings": Key("numbers", "bearings (1-based) that are [set.second_bearing] "
                                   "instead of [bearing]", "", OPTIONAL),
        },
        fill_defaults=False,
        exactly_one=(("arrangement", "facings"),),
        notes=(
            "an arrangement name must be known (a near miss is suggested); facings are +1 or -1",
            "an arrangement needs spacing_mm or positions_mm; facings need positions_mm; one position "
            "per bearing, increasing, neighbours at least one ball diameter apart (else the bearings "
            "overlap)",
            "at most one of preload_N, preload_class, preloads_N; a set preload needs bearings facing "
            "both ways; per-bearing preloads must balance: sum of facing x preload = 0",
            "spring_bearings: valid indices, not every bearing, never both bearings of one pair "
            "(neighbours closer than 3 ball diameters), each with a preload > 0",
        ),
    ),
    "set.second_bearing": Section(
        "Geometry of the bearings listed in [set] second_bearings (e.g. the fan-end bearing of a "
        "two-support rotor); the keys of [bearing].",
        dict(_BEARING_KEYS),
        fill_defaults=False,
        exactly_one=(("free_contact_angle_deg", "diametral_clearance_mm"),),
    ),
    "sweep": Section(
        "Cage-angle sweep (docs/model.md section 6).",
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
        "Settings of the dynamic simulation (docs/model.md section 7).",
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
            "resonance_frequencies_Hz": Key("numbers", "natural frequencies of several structural modes "
                                            "in the sensor path (overrides resonance_frequency_Hz)",
                                            "Hz", OPTIONAL),
            "resonance_damping_ratios": Key("numbers", "damping ratio of each mode of "
                                            "resonance_frequencies_Hz (one value: all)", "", OPTIONAL),
            "resonance_gains": Key("numbers", "gain g_k of each mode: sensor = a_h + sum g_k z_k'' "
                                   "(one value: all; default 1)", "", OPTIONAL),
            "slip_percent": _num("random slip: each ball-pitch advance of the cage takes (1 + eps) times "
                                 "its nominal time, eps ~ N(0, (slip_percent/100)^2) (the jitter of the "
                                 "ball-pass interval)", "", 0.0, ge=0, lt=20),
            "pass_amplitude_cv_max_percent": _num(
                "pass-to-pass variability of a pit's impacts: coefficient of variation of a per-pass "
                "factor on the housing acceleration (log-normal, mean square 1) where the contact cannot "
                "bridge the pit at all; scaled by the pit's unbridged fraction max(0, 1 - 2b/w) (b the "
                "contact's semi-axis along the track, w the pit length; bearingsim.realism.rig_record)",
                "", 0.0, ge=0, lt=100),
            "pass_delay_sd_max_percent": _num(
                "pass-to-pass variability of a pit's impacts: standard deviation of a per-pass delay "
                "of the housing acceleration, % of the pass interval, where the contact cannot bridge "
                "the pit at all; scaled like pass_amplitude_cv_max_percent", "", 0.0, ge=0, lt=50),
            "speed_fluctuation_percent": _num("RMS fluctuation of the shaft speed", "", 0.0, ge=0, lt=50),
            "speed_fluctuation_bandwidth_Hz": _num("bandwidth B of the speed fluctuation (8 random-phase "
                                                   "sinusoids, frequencies uniform in (0, B])", "Hz", 5.0, gt=0),
            "noise_rms_m_s2": _num("Gaussian measurement noise added to the sensor acceleration (rms; the "
                                   "CWRU normal drive-end baseline is 0.07 g = 0.686 m/s^2)", "m_s2", 0.0, ge=0),
            "noise_band_Hz": Key("range", "band [lo, hi] of the measurement noise (white when absent)", "Hz",
                                 OPTIONAL, ge=0),
            "seed": _int("seed of the realism draws (slip, speed fluctuation, noise, pass-to-pass variability)", 0, ge=0),
            "rtol": _num("relative tolerance of the adaptive reference integration (the default "
                         "fixed-step integration does not use it)", "", 1e-5, gt=0, lt=1),
            "atol": _num("absolute tolerance of the time integration, on displacements in um and "
                         "velocities in mm/s", "", 1e-5, gt=0),
        },
        notes=("duration_s x sample_rate_Hz gives at least 2 samples",
               "a simulation (``bearingsim simulate``, ``compare``, ``dataset``) refuses a "
               "sample_rate_Hz below twice the highest characteristic frequency of the case "
               "(shaft, FTF, BPFO, BPFI, BSF, 2 BSF at the free contact angle and the highest speed)"),
    ),
    "dataset": Section(
        "Labelled data set of simulated sensor signals (``bearingsim dataset``): ``count`` items, "
        "each a [dynamics] simulation of ``duration_s`` with its speed, loads and spall drawn "
        "uniformly from the [min, max] ranges below (min = max fixes a value).  Four classes: "
        "healthy, outer, inner, ball, in blocks of round(fraction x count) items in that order "
        "(healthy first; by default all others outer); each class has its own size and position "
        "ranges (inner_* and ball_* default to the spall_* ranges).  The other [dynamics] "
        "keys (sample rate, structure, tolerances, noise) apply to every item.",
        {
            "count": _int("number of items N", ge=1),
            "seed": _int("seed of the items' keys (jax.random.fold_in(PRNGKey(seed), index)): every draw of an item", 0, ge=0),
            "duration_s": _num("simulated time per item", "s", 0.1, gt=0),
            "chunk": _int("items simulated together (vmap); memory and speed trade-off; 0: what fills "
                          "the device (16 per CPU core; on a GPU as many as fit in a quarter of its "
                          "memory); the file does not depend on it", 16, ge=0),
            "healthy_fraction": _num("fraction of healthy items (spall depth and length 0)", "",
                                     0.2, ge=0, le=1),
            "depth_rule": _enum("how an item's drawn depth enters the contact: machined (the depth "
                                "itself, with the [defect] profile: a groove across the track, the "
                                "ball drops by its sag over the chord) or pit (a round EDM pit of "
                                "diameter spall_length_mm narrower than the contact: the depth that "
                                "loses the Hertz load over the pit's area at the item's own speed and "
                                "loads, bearingsim.realism.rig_record; label effective_depth_mm)",
                                ("machined", "pit"), "machined"),
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
            "inner_fraction": _num("fraction of items with an inner-raceway spall", "", 0.0, ge=0, le=1),
            "ball_fraction": _num("fraction of items with a pit on a ball", "", 0.0, ge=0, le=1),
            "outer_fraction": _num("fraction of items with an outer-raceway spall", "", _rest_fraction,
                                   ge=0, le=1, default_doc="1 - healthy_fraction - inner_fraction - "
                                   "ball_fraction"),
            "inner_length_mm": _range("inner-raceway spall arc length range", "mm",
                                      _same_as("spall_length_mm"), "dataset.spall_length_mm", gt=0),
            "inner_depth_mm": _range("inner-raceway spall depth range", "mm", _same_as("spall_depth_mm"),
                                     "dataset.spall_depth_mm", ge=0),
            "inner_center_deg": _range("inner spall centre azimuth range at t = 0 (it then turns with "
                                       "the shaft)", "deg", _same_as("spall_center_deg"),
                                       "dataset.spall_center_deg", ge=-360, le=360),
            "ball_length_mm": _range("ball pit diameter range (arc on the ball surface)", "mm",
                                     _same_as("spall_length_mm"), "dataset.spall_length_mm", gt=0),
            "ball_depth_mm": _range("ball pit depth range", "mm", _same_as("spall_depth_mm"),
                                    "dataset.spall_depth_mm", ge=0),
            "ball_spin_angle_deg": _range("pit spin angle range at t = 0 (0: in the outer contact, 180: "
                                          "in the inner contact); the pitted ball is ball 0",
                                          "deg", [0.0, 360.0], ge=-360, le=360),
            "resonance_frequency_Hz": _range("domain randomisation of the transfer path: every sensor "
                                             "mode's frequency of every item drawn log-uniform in this "
                                             "range (absent: the [dynamics] modes for all items)", "Hz",
                                             OPTIONAL, gt=0),
            "resonance_damping_ratio": _range("every sensor mode's damping ratio, drawn uniform (absent: "
                                              "the [dynamics] values)", "", OPTIONAL, gt=0, lt=1),
            "resonance_gain": _range("every sensor mode's gain, drawn log-uniform (absent: the "
                                     "[dynamics] values)", "", OPTIONAL, gt=0),
            "signal_gain": _range("factor on each item's bearing signal (the level of the transfer "
                                  "path, unknown on a new machine), drawn log-uniform", "", [1.0, 1.0], gt=0),
            "fault_snr_dB": _range("signal-to-background ratio of every fault item: its bearing signal is "
                                   "scaled so that its RMS stands this far over its background's RMS (drawn "
                                   "uniform in dB; replaces signal_gain for fault items; needs a background)",
                                   "dB", OPTIONAL, ge=-60, le=80),
            "ball_fault_snr_dB": _range("fault_snr_dB of the ball items only (absent: fault_snr_dB): a ball "
                                        "pit's periodic signature stands weaker over a machine's background "
                                        "than a race pit's of the same size (docs/realism.md, the CWRU ball "
                                        "records whitened)", "dB", OPTIONAL, ge=-60, le=80),
            "ball_strike_probability": _range("probability that a ball pit strikes the raceways on a "
                                              "pass (its spin axis wanders), drawn uniform per item; "
                                              "1: every pass", "", [1.0, 1.0], ge=0, le=1),
            "ball_exposure": _enum("how a ball pit meets the raceways (issue 33; docs/physics.md §8.3): gate "
                                   "(the drawn strikes of ball_strike_probability and the ball fault model's "
                                   "drawn gate, issue 26) or kinematic (the pit's overlap with the rolling "
                                   "track pass by pass, from the spin axis of raceway control, its wander and "
                                   "the Hertz contact width: bearingsim.dynamics.exposure; replaces the strikes "
                                   "and the gate)", ("gate", "kinematic"), "gate"),
            "ball_pit_latitude_deg": _range("ball_exposure = \"kinematic\": the pit's latitude above the "
                                            "ball's spin equator, drawn uniform per item", "deg", [-10.0, 10.0],
                                            ge=-90, le=90),
            "ball_axis_wander_deg": _range("ball_exposure = \"kinematic\": s.d. of the spin axis's pitch and "
                                           "yaw wander, drawn uniform per item", "deg", [1.0, 6.0], ge=0, le=45),
            "ball_axis_correlation_cage_rev": _range("ball_exposure = \"kinematic\": correlation of the axis "
                                                     "wander in cage revolutions (Ornstein-Uhlenbeck), drawn "
                                                     "uniform per item", "", [0.5, 2.0], gt=0),
            "outer_center_positions_deg": Key("numbers", "outer-race pits at these load-zone positions "
                                              "only (0: load-zone centre, the CWRU 6:00; 90 / -90: 3:00 / "
                                              "9:00; 180: 12:00), each item one of them at random; absent: "
                                              "spall_center_deg's range", "deg", OPTIONAL),
            "background": _enum("the machine's own vibration added to every item (bearingsim.signals.background): "
                                "none; random (drawn per item from the ranges of "
                                "bearingsim.signals.background.BACKGROUND_DEFAULTS and background_rms_m_s2: shaft and "
                                "supply-frequency lines, shaped broadband noise modulated at the shaft "
                                "rate, random knocks); machine (the [background] section, e.g. from "
                                "bearingsim calibrate)", ("none", "random", "machine"), "none"),
            "background_rms_m_s2": _range("broadband background RMS range of background = \"random\" "
                                          "(log-uniform)", "m_s2", [0.2, 2.0], gt=0),
            "realism_ingredients": _names("issue 26's ingredients added inside the device program "
                                          "(bearingsim.signals.nuisance): ball_fault_model (a ball pit's signal "
                                          "as real damaged balls show it: spin-axis gate, contact noise over "
                                          "the pit's edge, load-zone and ring-waviness modulation), nuisance "
                                          "(shaft and looseness lines, rub, lines near bearing orders, knocks "
                                          "in every class, at the background RMS), shaft_modulation (the "
                                          "whole record modulated at shaft orders and half orders), race_waviness (a "
                                          "healthy bearing's own orders: the background modulated at BPFO, "
                                          "BPFI and 2 BSF, every class); each "
                                          "drawn from the item's key (ranges: bearingsim.signals.nuisance."
                                          "NUISANCE_DEFAULTS, docs/realism.md); [] none",
                                          ("ball_fault_model", "nuisance", "shaft_modulation", "race_waviness"), []),
            "split_fractions": Key("numbers", "train, validation and test fractions of the label field "
                                   "split (0, 1, 2), assigned per item and class: windows of one item "
                                   "never straddle two parts", "", [0.7, 0.15, 0.15]),
        },
        fill_defaults=False,
        notes=(
            "spall_length_mm and spall_depth_mm must be given when the case has no [defect] "
            "(with length_mm) to take them from",
            "spall_depth_mm max < bearing.ball_diameter_mm; spall_length_mm max shorter than the "
            "ball pitch along the outer raceway",
            "radial_N and axial_N may not both allow 0 (an unloaded bearing has no solution)",
            "healthy_fraction + outer_fraction + inner_fraction + ball_fraction = 1",
            "duration_s x dynamics.sample_rate_Hz gives at least 2 samples",
        ),
    ),
    "background": Section(
        "The machine's own vibration (bearingsim.signals.background), added to every data set item with "
        "dataset.background = \"machine\"; written by ``bearingsim calibrate`` from a healthy record "
        "(shaft and supply-frequency lines, the broadband part's RMS, spectral shape and shaft-rate "
        "modulation, random knocks).",
        {
            "noise_rms_m_s2": _num("RMS of the broadband part", "m_s2", 0.0, ge=0),
            "psd_frequencies_Hz": Key("numbers", "frequencies of the broadband part's spectral shape",
                                      "Hz", OPTIONAL),
            "psd_levels_dB": Key("numbers", "its power spectral density at psd_frequencies_Hz (dB, any "
                                 "reference: the shape counts, noise_rms_m_s2 sets the level)", "dB", OPTIONAL),
            "shaft_amplitudes_m_s2": Key("numbers", "amplitudes of the lines at 1, 2, ... x the shaft "
                                         "frequency", "m_s2", OPTIONAL),
            "line_frequency_Hz": _num("supply frequency", "Hz", 60.0, gt=0),
            "line_amplitudes_m_s2": Key("numbers", "amplitudes of the lines at 1, 2, ... x the supply "
                                        "frequency", "m_s2", OPTIONAL),
            "modulation_depths": Key("numbers", "amplitude modulation of the broadband part at 1, 2, ... "
                                     "x the shaft frequency (0-1)", "", OPTIONAL),
            "knock_rate_Hz": _num("mean rate of random knocks", "Hz", 0.0, ge=0),
            "knock_amplitude_m_s2": _num("peak of a knock", "m_s2", 0.0, ge=0),
            "knock_frequency_Hz": _num("the resonance a knock rings", "Hz", 3000.0, gt=0),
            "knock_damping_ratio": _num("its damping ratio", "", 0.05, gt=0, lt=1),
        },
        fill_defaults=False,
    ),
}


def parent(path: str) -> str | None:
    if path == "":
        return None
    return path.rpartition(".")[0]


def subsections(path: str) -> list[str]:
    """Names (last component) of the sections directly under ``path``."""
    return [p.rpartition(".")[2] for p in SCHEMA if p != "" and parent(p) == path]


def join_key(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def split_key(dotted: str) -> tuple[str, str]:
    path, _, key = dotted.rpartition(".")
    return path, key


def si_name(key: str, spec: Key) -> str:
    if spec.unit and key.endswith("_" + spec.unit):
        return key[: -len(spec.unit) - 1]
    return key


def lookup(dotted: str) -> Key | None:
    path, key = split_key(dotted)
    sec = SCHEMA.get(path)
    return None if sec is None else sec.keys.get(key)


def unit_of(dotted_key: str) -> str:
    """Unit of a case key as shown in files and messages ("mm", "rpm", "N m"; "" if none)."""
    spec = lookup(dotted_key)
    if spec is None:
        raise KeyError(f"'{dotted_key}' is not a case key: {suggest(dotted_key, all_keys())}")
    return spec.unit_label


def all_keys() -> list[str]:
    return [join_key(p, k) for p, s in SCHEMA.items() for k in s.keys]
