"""Finding and reading case files: shipped cases by name, text that is not UTF-8, and TOML errors
told by key (a duplicate key is named, not just placed by line and column).
"""
from __future__ import annotations

import difflib
import re
import tomllib
from pathlib import Path

from .validation import CaseError

__all__ = ["shipped_cases_dir", "shipped_cases", "case_path", "read_case_text", "parse_toml"]


# ------------------------------------------------------------------------------- shipped cases
def shipped_cases_dir() -> Path:
    """Folder of the cases shipped with bearingsim: ``bearingsim/cases`` in an installed wheel,
    the top-level ``cases/`` of a source checkout (editable install)."""
    from importlib.resources import files

    installed = Path(str(files("bearingsim"))) / "cases"
    return installed if installed.is_dir() else Path(__file__).resolve().parents[2] / "cases"


def shipped_cases() -> list[str]:
    """Names of the shipped cases, as :func:`~bearingsim.case.load_case` takes them ("demo",
    "seed/speed", ...)."""
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


# ------------------------------------------------------------------------------- text
def _looks_utf16(data: bytes) -> bool:
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        return True
    n = min(len(data), 400) // 2 * 2
    return n >= 4 and (data[1:n:2].count(0) > 0.8 * n / 2 or data[0:n:2].count(0) > 0.8 * n / 2)


def read_case_text(path, source: str) -> str:
    """The text of a case file, which must be UTF-8 (a leading byte-order mark is allowed)."""
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        raise CaseError(source, [f"cannot read the file: {e.strerror or e}"]) from None
    if _looks_utf16(data):
        raise CaseError(source, ["is UTF-16 text, but TOML case files are UTF-8: save it as UTF-8"])
    if b"\x00" in data:
        raise CaseError(source, ["is a binary file (it contains NUL bytes), not a TOML case file"])
    try:
        return data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as e:
        line = data[:e.start].count(b"\n") + 1
        raise CaseError(source, [f"is not UTF-8 text (byte 0x{data[e.start]:02x} on line {line}): "
                                 "TOML case files are UTF-8; save it as UTF-8"]) from None


# ------------------------------------------------------------------------------- TOML errors
_HEADER = re.compile(r"^\s*\[\s*([^\[\]]+?)\s*\]\s*(#.*)?$")
_ARRAY_HEADER = re.compile(r"^\s*\[\[")
_KEY = re.compile(r"""^\s*((?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*')(?:\s*\.\s*(?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*'))*)\s*=""")
_WHERE = re.compile(r"\(at line (\d+), column \d+\)|\(at end of document\)")


def _dotted(name: str) -> tuple[str, ...]:
    return tuple(part.strip().strip("\"'") for part in re.findall(r"""[A-Za-z0-9_-]+|"[^"]*"|'[^']*'""", name))


def _declarations(text: str):
    """(line number, kind, dotted path) of every table header and key at the start of a line,
    outside multi-line strings and arrays of tables."""
    table, in_string = (), None
    for n, line in enumerate(text.splitlines(), 1):
        if in_string:
            if line.count(in_string) % 2:
                in_string = None
            continue
        if _ARRAY_HEADER.match(line):
            table = None
        elif m := _HEADER.match(line):
            table = _dotted(m.group(1))
            yield n, "table", table
        elif (m := _KEY.match(line)) and table is not None:
            yield n, "key", table + _dotted(m.group(1))
        for quote in ('"""', "'''"):
            if line.count(quote) % 2:
                in_string = quote
                break


def _duplicates(text: str) -> list[str]:
    seen: dict[tuple, tuple[int, str]] = {}
    problems = []
    for n, kind, path in _declarations(text):
        name = ".".join(path)
        if path in seen:
            first, first_kind = seen[path]
            if kind == first_kind == "key":
                problems.append(f"duplicate key {name} (lines {first} and {n}): give each key once")
            elif kind == first_kind:
                problems.append(f"section [{name}] is declared twice (lines {first} and {n}): merge them")
            else:
                problems.append(f"{name} is both a key and a section [{name}] (lines {first} and {n})")
        else:
            seen[path] = (n, kind)
    return problems


def parse_toml(text: str, source: str) -> dict:
    """``tomllib.loads`` with errors told by key: duplicates named, the line and the key of any
    other syntax error shown."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        problems = _duplicates(text)
        if not problems:
            msg = _WHERE.sub("", str(e)).strip()
            m = _WHERE.search(str(e))
            lines = text.splitlines()
            if m and m.group(1) and int(m.group(1)) <= len(lines):
                n = int(m.group(1))
                keys = [p for k, kind, p in _declarations(text) if k == n and kind == "key"]
                what = f"the value of {'.'.join(keys[0])}" if keys else "this line"
                problems = [f"invalid TOML on line {n} ({what}): {msg}: {lines[n - 1].strip()}"]
            else:
                problems = [f"invalid TOML at the end of the file: {msg} (an unclosed string, array "
                            "or table?)"]
        raise CaseError(source, problems) from None
