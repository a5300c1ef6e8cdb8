"""TOML writing (``tomllib`` only reads): :func:`to_toml` for changed cases and the examples of
the reference page; ``tomllib.loads(to_toml(d)) == d``."""
from __future__ import annotations

import math
import re

from ..errors import InputTypeError

__all__ = ["to_toml", "toml_value"]


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


def toml_value(v) -> str:
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
        return "[" + ", ".join(toml_value(e) for e in v) + "]"
    raise InputTypeError(f"cannot write {type(v).__name__} {v!r} to TOML",
                         "TOML values here are bool, int, float, str, or lists/tuples of them")


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
            lines.append(f"{_toml_key(k)} = {toml_value(v)}")
        for k, v in tables:
            table(v, path + [k])

    table(data, [])
    return "\n".join(lines) + "\n"
