"""Regenerate docs/cases.md, the case-file reference, from bearingsim.case.SCHEMA.

    .venv/bin/python docs/generate_cases_md.py           # rewrite docs/cases.md
    .venv/bin/python docs/generate_cases_md.py --check   # exit 1 if docs/cases.md is stale

Everything that can drift is generated: the key tables (``schema_reference_markdown()``), the
unit-suffix table (``UNITS``), the section and exactly-one rules, the error message shown
(produced by the reader itself) and every part of the full example that is not hand-written:
sections without a hand-written block ([dynamics], and any section added later) are generated
from the schema (keys at their defaults; a section with required keys is shown commented out),
and a key added to a hand-written section is appended to it from the schema, with a warning to
write a better example value.  The examples are validated with ``parse_case``.
"""
from __future__ import annotations

import argparse
import difflib
import functools
import re
import sys
from pathlib import Path

from bearingsim.case import (
    OPTIONAL,
    REQUIRED,
    SCHEMA,
    UNITS,
    CaseError,
    parse_case,
    schema_reference_markdown,
    to_toml,
)

OUT = Path(__file__).resolve().parent / "cases.md"

# The hand-written part of the full example.  Sections not written here ([dynamics], and any
# added to the schema later) are generated from the schema and appended.  Alternatives of an
# exactly-one pair, and the optional hybrid-ball section, are shown commented out.
FULL_EXAMPLE_HEAD = '''\
title = "Harris 218 ACBB, 10000 rpm, spall in the load zone"
description = """
Harris & Kotzalas (2006) 218 angular contact ball bearing; thrust plus a radial load whose
load zone is centred on a 3 deg, 0.3 mm deep spall."""

[bearing]
balls = 16
ball_diameter_mm = 22.225
pitch_diameter_mm = 125.26
inner_groove_curvature = 0.5232          # f_i = r_i / D
outer_groove_curvature = 0.5232          # f_o = r_o / D
free_contact_angle_deg = 40.0            # exactly one of these two:
# diametral_clearance_mm = 0.4825        #   cos alpha_0 = 1 - P_d / (2 B D)
design = "auto"                          # "angular_contact" here (alpha_0 > 0) | "deep_groove"
dynamic_load_rating_kN = 143             # catalogue C: ISO/TS 16281 life in `bearingsim static`

# [shoulders]                            # groove-edge angles; default: the design's (land heights)
# inner_high_deg = 74.1                  #   angular contact: 0.38 D high, 0.01 D low
# inner_low_deg = 11.2
# outer_high_deg = 74.1
# outer_low_deg = 11.2

[limits]                                 # reported per contact by `bearingsim static`
contact_pressure_limit_MPa = 4200        # ISO 76 static capacity of ball bearings
friction_coefficient = 0.07              # available at a raceway contact (estimate)

[material]                               # rings (and balls, unless [material.ball] is given)
youngs_modulus_GPa = 207.5
poisson_ratio = 0.3
density_kg_m3 = 7850

# [material.ball]                        # hybrid bearing: silicon nitride balls
# youngs_modulus_GPa = 310
# poisson_ratio = 0.26
# density_kg_m3 = 3200

[operation]
speed_rpm = 10000                        # inner ring; the outer ring is fixed
raceway_control = "outer"                # "outer" | "inner" | "equal"
centrifugal = true
gyroscopic = true
cage_angle_deg = 0.0                     # azimuth of ball 0 (static solve)
hertz = "exact"                          # or "brewe-hamrock"
tilt = "free"                            # or "held": the ring's tilt held at 0 (bearingsim static)

[load]                                   # on the inner ring, docs/model.md frame
axial_N = 10000
radial_x_N = 3000                        # +x: the load zone is centred at azimuth 0
radial_y_N = 0
moment_x_Nm = 0
moment_y_Nm = 0

# [set]                                  # a shaft on several bearings (docs/model.md section 10); omit for one
# arrangement = "DB"                     # exactly one of these two: a named arrangement (DB, DF,
# facings = [1, -1]                      #   DT, TBT, QBC, ...) or each bearing's facing +1 / -1
# spacing_mm = 40                        # arrangement: distance between neighbours
# positions_mm = [0, 40]                 # or each bearing's axial position (with facings)
# preload_N = 2000                       # at most one of these three: the set preload (rigid),
# preload_class = "light"                #   a class (light / medium / heavy),
# preloads_N = [2000, 2000]              #   or each bearing's preload (must balance)
# spring_bearings = [2]                  # 1-based: outer ring on springs (constant preload)
# second_bearings = [2]                  # 1-based: bearings of [set.second_bearing]
# [set.second_bearing]                   # the keys of [bearing], for those bearings
# balls = 8
# ball_diameter_mm = 6.746
# pitch_diameter_mm = 28.5
# inner_groove_curvature = 0.52
# outer_groove_curvature = 0.52
# diametral_clearance_mm = 0.0           # exactly one of these two:
# free_contact_angle_deg = 0.0
# design = "auto"
# dynamic_load_rating_kN = 9.95          # its catalogue C: the set's ISO/TS 16281 life

[defect]                                 # omit the section for a healthy bearing
location = "outer"                       # or "inner" (turns with the inner ring) | "ball"
center_deg = 0.0                         # raceway spall: azimuth of its centre (at t = 0)
extent_deg = 3.0                         # exactly one of these two:
# length_mm = 3.725                      #   arc length along the outer raceway
depth_mm = 0.3
profile = "rectangular"                  # or "ball-path"
# ball_index = 0                         # location = "ball" only: the pitted ball,
# spin_angle_deg = 0.0                   #   and the pit's angle from its outer contact

[sweep]                                  # `bearingsim sweep` and `bearingsim study`
start_deg = -11.25
stop_deg = 11.25                         # default: start_deg + 360 / balls
steps = 181

[study]                                  # `bearingsim study`: one sweep per value
parameter = "operation.speed_rpm"
values = [0, 4000, 8000, 12000, 16000]
'''

MINIMAL_EXAMPLE = '''\
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
'''

BAD_EXAMPLE = '''\
title = "a case with mistakes"
[bearing]
balls = 16
ball_diamter_mm = 22.225
pitch_diameter_mm = 125.26
inner_groove_curvature = 0.4
outer_groove_curvature = 0.5232
free_contact_angle_deg = 40.0
diametral_clearance_mm = 0.48
[operation]
speed_rpm = 10000
raceway_control = "outr"
[defect]
extent_deg = 30
depth_mm = 0.3
'''


def _default_is_value(spec) -> bool:
    return not (spec.default is REQUIRED or spec.default is OPTIONAL or callable(spec.default))


def _key_line(path: str, key: str) -> str:
    """One example line for a schema key: at its default, or commented with what it needs."""
    sec = SCHEMA[path]
    spec = sec.keys[key]
    if _default_is_value(spec):
        return f"{to_toml({key: spec.default}).strip():<40} # {spec.doc}"
    if spec.default is REQUIRED:
        need = f"required: {spec.requirement_text()}"
    elif spec.default_doc is not None:
        need = f"default: {spec.default_doc}"
    else:
        group = next((g for g in sec.exactly_one if key in g), None)
        need = ("exactly one of " + ", ".join(group)) if group else "optional"
    return f"# {key + ' = ...':<38} # {spec.doc} ({need})"


def _generated_section(path: str) -> str:
    """[path] with one line per key; commented out entirely when it has required keys."""
    sec = SCHEMA[path]
    lines = [f"[{path}]"] + [_key_line(path, k) for k in sec.keys]
    if any(spec.default is REQUIRED for spec in sec.keys.values()):
        lines = ["# " + line if not line.startswith("# ") else "# " + line for line in lines]
        lines.insert(0, f"# [{path}] has required keys: uncomment the section and fill them in")
    return "\n".join(lines) + "\n"


_HEADER = re.compile(r"^(#\s*)?\[([A-Za-z0-9_.-]+)\]")


def _head_sections(text: str) -> dict:
    """{section path: (first line, end line, commented)} of the sections written in ``text``."""
    lines = text.splitlines()
    heads = [(i, m.group(2), bool(m.group(1))) for i, line in enumerate(lines)
             if (m := _HEADER.match(line))]
    out = {}
    for n, (i, path, commented) in enumerate(heads):
        end = heads[n + 1][0] if n + 1 < len(heads) else len(lines)
        out[path] = (i, end, commented)
    return out


@functools.lru_cache(maxsize=None)
def full_example() -> str:
    """FULL_EXAMPLE_HEAD completed from the schema, then the generated sections."""
    lines = FULL_EXAMPLE_HEAD.splitlines()
    found = _head_sections(FULL_EXAMPLE_HEAD)
    # keys the schema has but a hand-written section lacks: append them to that section
    for path in sorted(found, key=lambda p: -found[p][0]):       # bottom-up: indices stay valid
        first, end, commented = found[path]
        if path not in SCHEMA:
            raise SystemExit(f"docs/generate_cases_md.py: the full example has a section [{path}] "
                             "that the schema does not know")
        block = "\n".join(lines[first:end])
        missing = [k for k in SCHEMA[path].keys if not re.search(rf"^[#\s]*{re.escape(k)}\s*=", block, re.M)]
        if not missing:
            continue
        print(f"docs/generate_cases_md.py: warning: the hand-written example of [{path}] lacks "
              f"{', '.join(missing)}; generated from the schema (edit FULL_EXAMPLE_HEAD for a better "
              "example)", file=sys.stderr)
        new = [_key_line(path, k) for k in missing]
        if commented:
            new = ["# " + line for line in new]
        at = end
        while at > first + 1 and not lines[at - 1].strip():
            at -= 1
        lines[at:at] = new
    top = [k for k in SCHEMA[""].keys if not re.search(rf"^{re.escape(k)}\s*=", FULL_EXAMPLE_HEAD, re.M)]
    if top:
        raise SystemExit("docs/generate_cases_md.py: add the top-level key(s) " + ", ".join(top)
                         + " to FULL_EXAMPLE_HEAD")
    text = "\n".join(lines) + "\n"
    for path in SCHEMA:
        if path and path not in found:
            text += "\n" + _generated_section(path)
    return text


def _check_examples() -> None:
    for name, text in (("full example", full_example()), ("minimal example", MINIMAL_EXAMPLE)):
        try:
            parse_case(text, name)
        except CaseError as e:
            raise SystemExit(f"docs/generate_cases_md.py: the {name} does not validate:\n{e}")


def _section_lists() -> str:
    req = [p for p, sec in SCHEMA.items() if p and sec.required]
    dflt = [p for p, sec in SCHEMA.items() if p and not sec.required and sec.fill_defaults]
    opt = [p for p, sec in SCHEMA.items() if p and not sec.required and not sec.fill_defaults]
    fmt = lambda ps: ", ".join(f"`[{p}]`" for p in ps)  # noqa: E731
    return (f"- **Sections.** Required: {fmt(req)}. May be omitted, their defaults then apply: "
            f"{fmt(dflt)}. Truly optional (absent means not used, e.g. a healthy bearing without "
            f"`[defect]`; when present, their required keys must be given): {fmt(opt)}.")


def _bad_example_message() -> str:
    try:
        parse_case(BAD_EXAMPLE, "cases/bad.toml")
    except CaseError as e:
        return str(e)
    raise SystemExit("docs/generate_cases_md.py: BAD_EXAMPLE unexpectedly passed validation")


def _units_table() -> str:
    used = {spec.unit for sec in SCHEMA.values() for spec in sec.keys.values()}
    rows = ["| suffix | unit in the file | SI unit inside | factor to SI |", "|---|---|---|---|"]
    for suffix, (factor, label, si) in UNITS.items():
        if not suffix or suffix not in used:
            continue
        rows.append(f"| `_{suffix}` | {label} | {si} | {factor:.12g} |")
    return "\n".join(rows)


def _exactly_one_list() -> str:
    out = []
    for path, sec in SCHEMA.items():
        for group in sec.exactly_one:
            keys = " or ".join(f"`{path}.{k}`" for k in group)
            out.append(f"  - [{path}]: exactly one of {keys} (when the section is present)")
    return "\n".join(out)


def _schema_tables() -> str:
    """The per-section tables of schema_reference_markdown(), without its title paragraph."""
    md = schema_reference_markdown()
    start = md.find("\n## ")
    if start < 0:
        raise SystemExit("docs/generate_cases_md.py: schema_reference_markdown() has no '## ' sections")
    return md[start + 1:].rstrip() + "\n"


def _schema_intro() -> str:
    """The one-paragraph intro of schema_reference_markdown() (after its title)."""
    md = schema_reference_markdown()
    body = md.split("\n## ", 1)[0].splitlines()
    return " ".join(line for line in body[1:] if line.strip())


def render() -> str:
    _check_examples()
    parts = [
        "# Case file reference",
        "",
        "<!-- Generated by docs/generate_cases_md.py from bearingsim.case.SCHEMA: do not edit by "
        "hand; run `.venv/bin/python docs/generate_cases_md.py` after changing the schema. -->",
        "",
        "A case file describes one bearing, its operating condition and loads, an optional "
        "spall on the outer raceway, and the optional sweep, study and dynamics settings. "
        "The commands read one (`bearingsim static CASE.toml`, ...; see `bearingsim --help`); from Python, "
        "`bearingsim.case.load_case(path)` returns a validated `Case` (`load_case(\"demo\")` loads a case shipped "
        "with the package by name: `bearingsim.case.shipped_cases()` lists them). " + _schema_intro(),
        "",
        "## Units are part of the key names",
        "",
        "Files are written in engineering units, and the unit of every dimensional key is the "
        "suffix of its name (`ball_diameter_mm`, `speed_rpm`, `axial_N`, ...): a value can never "
        "be read in the wrong unit. Keys without a suffix are dimensionless (`poisson_ratio`, "
        "`inner_groove_curvature`, `steps`). The reader converts to SI (m, rad, rad/s, N, Pa) "
        "when it builds the core objects; `Case.data` and `Case.get()` keep the file's units.",
        "",
        _units_table(),
        "",
        "## Rules",
        "",
        _section_lists(),
        "- **Exactly one of a pair.** Some quantities can be given in two ways; give exactly one:",
        "",
        _exactly_one_list(),
        "",
        "- **Computed default.** `sweep.stop_deg` defaults to `start_deg + 360 / balls` (one ball "
        "pitch, which covers every configuration of the ball set relative to one spall); it "
        "follows `start_deg` and `balls` unless given.",
        "- **Cross-checks** between keys (listed under each table below) run once the keys they "
        "need are individually valid.",
        "- **Studies.** `[study] parameter` names any numeric key outside `[study]` by its dotted "
        "name (`operation.speed_rpm`, `defect.extent_deg`, `load.moment_y_Nm`, ...), `values` are "
        "in that key's unit; every value is validated as if written into the file, together with "
        "the rest of the case. `bearingsim study` runs one cage-angle sweep per value "
        "(`bearing.balls` is refused there: it changes the shape of the results).",
        "- **Changing a value from Python.** `case.with_value(\"load.axial_N\", 15000)` returns a "
        "new validated case (engineering units, as in the file); setting one key of an "
        "exactly-one pair removes the other. `case.get(\"bearing.balls\")` reads a value. "
        "`case.bearing()`, `case.operation()`, `case.loads()`, `case.spall()`, "
        "`case.sweep_settings()` and `case.dynamics_settings()` give the SI objects.",
        "",
        "## Errors",
        "",
        "Unknown sections and keys, wrong types, values out of range, a missing required key, both "
        "or neither of an exactly-one pair, and failed cross-checks are all errors. The reader "
        "collects *every* problem of the file and raises one `CaseError` (a `bearingsim.errors.InputError`, "
        "hence a `ValueError`) with one "
        "line per problem, each prefixed by the file name; a misspelt key, section or choice gets "
        "a \"did you mean\" suggestion (or the list of valid names). The command line prints the "
        "message and exits with status 2. A file that is not UTF-8 text, a duplicate key (named, with "
        "both lines) and a TOML syntax error (with the line and its key) are reported the same way. "
        "For example, this file",
        "",
        "```toml",
        BAD_EXAMPLE.rstrip(),
        "```",
        "",
        "is rejected with",
        "",
        "```text",
        _bad_example_message(),
        "```",
        "",
        "A cross-check runs only when the keys it needs are valid on their own: here "
        "`bearing.balls` is valid, so the spall extent is compared with the ball pitch; the "
        "clearance is not checked against the contact-angle range, because that check needs "
        "`ball_diameter_mm` and `inner_groove_curvature`, which are not valid.",
        "",
        "## Minimal example",
        "",
        "```toml",
        MINIMAL_EXAMPLE.rstrip(),
        "```",
        "",
        "## Full example",
        "",
        "Every section and key (alternatives commented out). The sections after `[study]` are "
        "generated from the schema: keys at their defaults, and a section with required keys "
        "commented out.",
        "",
        "```toml",
        full_example().rstrip(),
        "```",
        "",
        "More cases: `cases/*.toml` (Harris 218 static, at speed, combined load; the CWRU 6205; "
        "the demo) and `cases/seed/*.toml` (the four studies of the seed paper).",
        "",
        "## Key reference",
        "",
        "Generated from `bearingsim.case.SCHEMA` by `schema_reference_markdown()`.",
        "",
        _schema_tables().replace("\n## ", "\n### ").replace("## Top level", "### Top level", 1),
        "## Regenerating this page",
        "",
        "`.venv/bin/python docs/generate_cases_md.py` rewrites this file from the schema; "
        "`--check` exits with status 1 when the file is out of date.",
        "",
    ]
    return "\n".join(parts)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="do not write; exit 1 if docs/cases.md is stale")
    ap.add_argument("--output", type=Path, default=OUT, help="output file (default docs/cases.md)")
    args = ap.parse_args(argv)
    text = render()
    if args.check:
        old = args.output.read_text(encoding="utf-8") if args.output.exists() else ""
        if old != text:
            diff = difflib.unified_diff(old.splitlines(), text.splitlines(), str(args.output), "generated",
                                        lineterm="", n=1)
            print("\n".join(list(diff)[:60]))
            print(f"{args.output} is out of date: run .venv/bin/python docs/generate_cases_md.py",
                  file=sys.stderr)
            return 1
        print(f"{args.output} is up to date")
        return 0
    args.output.write_text(text, encoding="utf-8")
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
