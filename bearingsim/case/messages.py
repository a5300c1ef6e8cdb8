"""How case values and names are shown in messages: compact numbers, values as written in
TOML, the kind of a value, "did you mean" suggestions."""
from __future__ import annotations

import difflib
import json
import math

__all__ = ["fmt_num", "fmt_value", "kind_of", "suggest"]


def fmt_num(x) -> str:
    """Compact number for messages: 30.0 -> '30', 0.5232 -> '0.5232', computed values to 6 digits."""
    x = float(x)
    if math.isfinite(x) and x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    s = repr(x)
    return s if len(s) <= 12 else f"{x:.6g}"


def fmt_value(v) -> str:
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
        return "[" + ", ".join(fmt_value(e) for e in v) + "]"
    if isinstance(v, dict):
        return "a table"
    return repr(v)


_KINDS = ((bool, "a boolean"), (int, "an integer"), (float, "a float"), (str, "a string"), (list, "an array"),
          (dict, "a table"))


def kind_of(v) -> str:
    """What a TOML value is, for messages ("an integer", "a table", "a datetime")."""
    return next((name for t, name in _KINDS if isinstance(v, t)), f"a {type(v).__name__}")


def suggest(name: str, valid) -> str:
    valid = list(valid)
    close = difflib.get_close_matches(name, valid, n=1, cutoff=0.6)
    if close:
        return f"did you mean '{close[0]}'?"
    return "valid names: " + ", ".join(valid) if valid else "nothing is allowed here"
