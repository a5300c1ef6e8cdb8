"""Validation of a parsed case file against :data:`~bearingsim.case.schema.SCHEMA`: structure
(unknown sections and keys, with "did you mean"), types and ranges, required keys, exactly-one
pairs, defaults, the cross-checks between keys, and the [study] values.  Every problem is
collected and raised together as one :class:`CaseError`.
"""
from __future__ import annotations

import copy
import difflib
import json
import math

from ..errors import InputError
from .messages import fmt_num, fmt_value, kind_of, suggest
from .dataset_checks import dataset_problems, free_contact_angle_deg
from .sets import set_problems
from .schema import (OPTIONAL, REQUIRED, SCHEMA, TYPE_NAMES, Key, all_keys, join_key, lookup, split_key,
                     subsections)
from .units import from_si, to_si

__all__ = ["CaseError", "validate", "section_raw", "set_raw"]


class CaseError(InputError):
    """Invalid case (an :class:`~bearingsim.errors.InputError`, exit code 2).  ``problems`` lists
    the problems (without the source prefix), ``source`` names the file; the message has one line
    ``<source>: <problem>`` per problem."""

    def __init__(self, source: str, problems: list[str]):
        self.source = source
        self.problems = list(problems)
        super().__init__("\n".join(f"{source}: {p}" for p in self.problems))


def _check_value(name: str, spec: Key, v):
    """Type and range check of one value.  Returns (ok, normalised value, problem or None)."""
    t = spec.type
    shown = f"{name} = {fmt_value(v)}"
    if t in ("float", "int"):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or (t == "int" and isinstance(v, float)):
            return False, None, f"{shown} has the wrong type: expected {TYPE_NAMES[t]}, got {kind_of(v)}"
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
            return False, None, f"{shown} has the wrong type: expected {TYPE_NAMES[t]}, got {kind_of(v)}"
        return True, v, None
    if t in ("str", "enum"):
        if not isinstance(v, str):
            return False, None, f"{shown} has the wrong type: expected {TYPE_NAMES[t]}, got {kind_of(v)}"
        if t == "enum" and v not in spec.choices:
            close = difflib.get_close_matches(v, spec.choices, n=1, cutoff=0.6)
            hint = f" (did you mean {json.dumps(close[0])}?)" if close else ""
            return False, None, f"{shown} is not allowed: must be {spec.requirement_text()}{hint}"
        return True, v, None
    if t == "range":
        if not isinstance(v, list):
            return False, None, f"{shown} has the wrong type: expected {TYPE_NAMES[t]}, got {kind_of(v)}"
        if len(v) != 2:
            return False, None, f"{shown} must have exactly two elements [min, max], got {len(v)}"
        xs = []
        for e in v:
            if isinstance(e, bool) or not isinstance(e, (int, float)) or not math.isfinite(e):
                return False, None, f"{shown} must hold two finite numbers [min, max], got {fmt_value(e)}"
            x = float(e)
            if ((spec.gt is not None and not x > spec.gt) or (spec.ge is not None and not x >= spec.ge)
                    or (spec.lt is not None and not x < spec.lt) or (spec.le is not None and not x <= spec.le)):
                return False, None, f"{shown} is out of range: must be {spec.requirement_text()}"
            xs.append(x)
        if xs[0] > xs[1]:
            return False, None, f"{shown} has min > max: must be {spec.requirement_text()}"
        return True, xs, None
    if t == "names":
        if not isinstance(v, list) or not all(isinstance(e, str) for e in v):
            return False, None, f"{shown} has the wrong type: expected {TYPE_NAMES[t]}, got {kind_of(v)}"
        bad = [e for e in v if e not in spec.choices]
        if bad:
            return False, None, (f"{shown} names {json.dumps(bad[0])}, not allowed: each must be one of "
                                 + ", ".join(json.dumps(c) for c in spec.choices))
        if len(set(v)) != len(v):
            return False, None, f"{shown} names an ingredient twice"
        return True, list(v), None
    if t == "numbers":
        if not isinstance(v, list):
            return False, None, f"{shown} has the wrong type: expected {TYPE_NAMES[t]}, got {kind_of(v)}"
        if not v:
            return False, None, f"{name} is empty: give at least one value"
        return True, list(v), None
    raise AssertionError(f"unknown key type {t!r}")


def _check_structure(raw: dict, path: str, problems: list[str]) -> None:
    """Unknown sections / keys, and tables where values belong (and vice versa)."""
    sec = SCHEMA[path]
    subs = subsections(path)
    valid = list(sec.keys) + subs
    for name, v in raw.items():
        full = join_key(path, name)
        if name in sec.keys:
            if isinstance(v, dict):
                problems.append(f"{full} must be a value ({TYPE_NAMES[sec.keys[name].type]}), not a table")
        elif name in subs:
            if not isinstance(v, dict):
                problems.append(f"[{full}] must be a table (section), got {kind_of(v)} {fmt_value(v)}")
            else:
                _check_structure(v, full, problems)
        elif isinstance(v, dict):
            where = "" if path == "" else f" in [{path}]"
            problems.append(f"unknown section [{full}]{where}: {suggest(name, subs if path == '' else valid)}")
        else:
            where = "top-level key" if path == "" else "key"
            inside = "" if path == "" else f" in [{path}]"
            problems.append(f"unknown {where} '{name}'{inside}: {suggest(name, valid)}")


def section_raw(raw: dict, path: str):
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
        tab = section_raw(raw, path)
        if tab is None:
            if sec.required:
                problems.append(f"missing required section [{path}]")
            if not sec.fill_defaults or sec.required:
                continue
            tab = {}
        out: dict = {}
        for key, spec in sec.keys.items():
            full = join_key(path, key)
            if key in tab:
                if isinstance(tab[key], dict):
                    continue  # reported by _check_structure
                ok, x, msg = _check_value(full, spec, tab[key])
                if ok:
                    out[key] = x
                else:
                    problems.append(msg)
            elif spec.default is REQUIRED:
                if section_raw(raw, path) is not None:
                    problems.append(f"missing required key {full}: must be {spec.requirement_text()} "
                                    f"({spec.doc})")
            elif spec.default is OPTIONAL or callable(spec.default):
                pass
            else:
                out[key] = spec.default
        if section_raw(raw, path) is not None:
            for group in sec.exactly_one:
                given = [k for k in group if k in tab]
                names = " or ".join(join_key(path, k) for k in group)
                if len(given) > 1:
                    problems.append(f"give exactly one of {names}, not both")
                elif not given:
                    problems.append(f"missing key: give exactly one of {names}")
        _set_section(data, path, out)
    # computed defaults, once every section is known
    for path, sec in SCHEMA.items():
        out = section_raw(data, path)
        if out is None:
            continue
        tab = section_raw(raw, path) or {}
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


def _cross_checks(data: dict, problems: list[str], raw: dict | None = None) -> None:
    """Checks between keys; each runs only when the keys it needs are individually valid.
    Values are shown as written in ``raw`` (the file) when given there."""
    set_problems(data, problems)
    b = data.get("bearing", {})
    has = lambda d, *ks: all(k in d for k in ks)  # noqa: E731

    def shown(path, key):
        tab = section_raw(raw or {}, path)
        v = tab[key] if tab is not None and key in tab else section_raw(data, path)[key]
        return fmt_value(v)

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
                    f"sin(180 deg / balls) = {fmt_num(limit)} mm (at most "
                    f"{int(math.floor(math.pi / math.asin(min(1.0, D / dm)) - 1e-12))} balls)")
    else:
        geometry_ok = False

    if has(b, "diametral_clearance_mm", "ball_diameter_mm", "inner_groove_curvature", "outer_groove_curvature"):
        D, Pd = b["ball_diameter_mm"], b["diametral_clearance_mm"]
        B = b["inner_groove_curvature"] + b["outer_groove_curvature"] - 1.0
        amax = SCHEMA["bearing"].keys["free_contact_angle_deg"].le
        limit = 2.0 * B * D * (1.0 - math.cos(to_si(amax, "deg")))
        if Pd > limit:
            geometry_ok = False
            problems.append(
                f"bearing.diametral_clearance_mm = {shown('bearing', 'diametral_clearance_mm')} is too large: with these groove "
                f"curvatures (B = f_i + f_o - 1 = {fmt_num(B)}) it gives a free contact angle above "
                f"{fmt_num(amax)} deg; must be <= 2 B D (1 - cos {fmt_num(amax)} deg) = {fmt_num(limit)} mm")

    d = data.get("defect")
    if d is not None:
        if "depth_mm" in d and "ball_diameter_mm" in b and not d["depth_mm"] < b["ball_diameter_mm"]:
            problems.append(f"defect.depth_mm = {shown('defect', 'depth_mm')} must be less than the ball "
                            f"diameter bearing.ball_diameter_mm = {shown('bearing', 'ball_diameter_mm')}")
        loc = d.get("location", "outer")
        given = section_raw(raw or {}, "defect") or {}
        if loc == "ball":
            if "center_deg" in given:
                problems.append(f"defect.center_deg = {shown('defect', 'center_deg')} is not used for a ball "
                                "pit (location = \"ball\"): give its position as defect.spin_angle_deg")
            if "balls" in b and "ball_index" in d and not d["ball_index"] < b["balls"]:
                problems.append(f"defect.ball_index = {shown('defect', 'ball_index')} is out of range: the "
                                f"bearing has {b['balls']} balls (0 to {b['balls'] - 1})")
            if "extent_deg" in d and not d["extent_deg"] < 180.0:
                problems.append(f"defect.extent_deg = {shown('defect', 'extent_deg')} spans half the ball or "
                                "more: a pit must be smaller than 180 deg (it cannot touch both contacts)")
            if "length_mm" in d and "ball_diameter_mm" in b:
                extent = from_si(2.0 * d["length_mm"] / b["ball_diameter_mm"], "deg")
                if not extent < 180.0:
                    problems.append(
                        f"defect.length_mm = {shown('defect', 'length_mm')} spans {fmt_num(extent)} deg of the "
                        f"ball (radius {fmt_num(0.5 * b['ball_diameter_mm'])} mm): a pit must be smaller than "
                        "180 deg (it cannot touch both contacts)")
        else:
            for key in ("ball_index", "spin_angle_deg"):
                if key in d:
                    problems.append(f"defect.{key} = {shown('defect', key)} applies only to a ball pit: set "
                                    f"defect.location = \"ball\" (it is \"{loc}\"), or remove the key")
        if "balls" in b and loc != "ball":
            pitch = 360.0 / b["balls"]
            if "extent_deg" in d and not d["extent_deg"] < pitch:
                problems.append(f"defect.extent_deg = {shown('defect', 'extent_deg')} is longer than the ball "
                                f"pitch {fmt_num(pitch)} deg: only one ball at a time may be over the spall")
            alpha0 = free_contact_angle_deg(b)
            if "length_mm" in d and geometry_ok and alpha0 is not None:
                sign, name, sym = (1.0, "outer", "R_o") if loc == "outer" else (-1.0, "inner", "R_ir")
                R_o = 0.5 * (b["pitch_diameter_mm"] + sign * b["ball_diameter_mm"] * math.cos(to_si(alpha0, "deg")))
                extent = from_si(d["length_mm"] / R_o, "deg")
                if not extent < pitch:
                    problems.append(
                        f"defect.length_mm = {shown('defect', 'length_mm')} is longer than the ball pitch "
                        f"{fmt_num(pitch)} deg = {fmt_num(to_si(pitch, 'deg') * R_o)} mm along the {name} "
                        f"raceway ({sym} = {fmt_num(R_o)} mm; the spall spans {fmt_num(extent)} deg): "
                        f"only one ball at a time may be over the spall")

    dataset_problems(data, problems, geometry_ok, section_raw(raw or {}, "dataset") or {})

    s = data.get("sweep")
    if s is not None and has(s, "start_deg", "stop_deg") and s["start_deg"] == s["stop_deg"]:
        problems.append(f"sweep.stop_deg = {shown('sweep', 'stop_deg')} must differ from "
                        f"sweep.start_deg = {shown('sweep', 'start_deg')}")

    if data.get("operation", {}).get("tilt") == "held":
        ld = data.get("load", {})
        for key in ("moment_x_Nm", "moment_y_Nm"):
            if ld.get(key, 0.0) != 0.0:
                problems.append(f"load.{key} = {shown('load', key)} with operation.tilt = \"held\": a held tilt "
                                "takes no applied moment (the moments that hold it are the result); set it to 0, "
                                "or operation.tilt = \"free\" to apply it")
        if "set" in data:
            problems.append("operation.tilt = \"held\" applies to a single bearing: a [set]'s shaft tilt is "
                            "solved from its bearings; remove the key or set it to \"free\"")

    dyn = data.get("dynamics", {})
    for path in ("dynamics", "dataset"):
        sec = data.get(path)
        if sec is not None and "duration_s" in sec and "sample_rate_Hz" in dyn:
            n = round(sec["duration_s"] * dyn["sample_rate_Hz"])
            if n < 2:
                problems.append(f"{path}.duration_s = {shown(path, 'duration_s')} x dynamics.sample_rate_Hz = "
                                f"{shown('dynamics', 'sample_rate_Hz')} gives {n} samples: need at least 2 "
                                "(raise one of them)")


def _study_problems(raw: dict, data: dict, base_ok: bool) -> list[str]:
    st = data.get("study")
    if st is None or "parameter" not in st:
        return []
    problems = []
    param = st["parameter"]
    shown = f"study.parameter = {fmt_value(param)}"
    spec = lookup(param)
    path, _ = split_key(param)
    if spec is None:
        numeric = [k for k in all_keys() if lookup(k).numeric and not k.startswith("study.")]
        return [f"{shown} is not a key of the case schema: {suggest(param, numeric)}"]
    if path == "study" or not spec.numeric:
        return [f"{shown} must name a numeric key (float or integer) outside [study]; "
                f"{param} is {TYPE_NAMES[spec.type]}"]
    if section_raw(raw, path) is None and not SCHEMA[path].fill_defaults:
        return [f"{shown} names a key of [{path}], which this case does not have"]
    for i, v in enumerate(st.get("values", [])):
        ok, x, msg = _check_value(param, spec, v)
        if not ok:
            problems.append(f"study.values[{i}]: {msg}")
        elif base_ok:
            trial = set_raw(raw, param, x)
            trial.pop("study", None)
            sub: list[str] = []
            _cross_checks(_validate_sections(trial, sub), sub, trial)
            problems.extend(f"study.values[{i}] ({param} = {fmt_value(v)}): {p}" for p in sub)
    return problems


def validate(raw: dict, source: str) -> dict:
    problems: list[str] = []
    _check_structure(raw, "", problems)
    data = _validate_sections(raw, problems)
    _cross_checks(data, problems, raw)
    problems.extend(_study_problems(raw, data, base_ok=not problems))
    if problems:
        raise CaseError(source, problems)
    return data


def set_raw(raw: dict, dotted: str, value) -> dict:
    """Deep copy of ``raw`` with ``dotted`` set; the other member of an exactly-one group goes."""
    new = copy.deepcopy(raw)
    path, key = split_key(dotted)
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
