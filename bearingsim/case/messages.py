"""How case values and names are shown in messages: compact numbers, values as written in
TOML, the kind of a value, "did you mean" suggestions."""
from __future__ import annotations

import difflib
import math

from .toml_writer import toml_value

__all__ = ["fmt_num", "fmt_value", "kind_of", "suggest"]


def fmt_num(x) -> str:
    """Compact number for messages: 30.0 -> '30', 0.5232 -> '0.5232', computed values to 6 digits."""
    x = float(x)
    if math.isfinite(x) and x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    s = repr(x)
    return s if len(s) <= 12 else f"{x:.6g}"


def fmt_value(v) -> str:
    """A value as written in TOML (for messages; a table is "a table", anything TOML cannot
    hold its repr)."""
    if isinstance(v, dict):
        return "a table"
    try:
        return toml_value(v)
    except TypeError:
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
