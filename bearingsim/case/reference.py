"""The reference page of the case format, generated from the schema (``docs/cases.md`` is built
from it by ``docs/generate_cases_md.py``)."""
from __future__ import annotations

from .schema import OPTIONAL, REQUIRED, SCHEMA
from .toml_writer import toml_value

__all__ = ["schema_reference_markdown"]


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
                   "enum": "string", "numbers": "array of numbers", "names": "array of strings",
                   "range": "[min, max]"}[spec.type]
            if spec.default_doc is not None:
                default = spec.default_doc
            elif spec.default is REQUIRED:
                default = "required"
            elif spec.default is OPTIONAL:
                group = next((g for g in sec.exactly_one if key in g), None)
                default = ("exactly one of " + ", ".join(f"`{k}`" for k in group)) if group else "none"
            else:
                default = f"`{toml_value(spec.default)}`"
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
            elif spec.type == "names":
                allowed = "each one of " + ", ".join(f'`"{c}"`' for c in spec.choices)
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
