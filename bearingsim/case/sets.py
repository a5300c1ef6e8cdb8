"""The [set] section: a shaft on several bearings (docs/model.md section 10) -- its cross-checks (one message
per problem, naming the key) and the :class:`bearingsim.physics.shaft.BearingSet` it describes."""
from __future__ import annotations

import math

from ..physics.shaft import ARRANGEMENTS, arrangement_suggestion
from .messages import fmt_num

__all__ = ["set_problems", "set_layout"]

PAIR_SPACING = 3.0      # neighbours closer than this many ball diameters form one (matched) pair


def _numbers(v):
    return isinstance(v, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                       and math.isfinite(x) for x in v)


def set_layout(s: dict, D_mm: float):
    """(facings, positions_mm, preloads or None, preload_class or None, springs (0-based),
    seconds (0-based)) of a validated [set] section (``D_mm``: the spacing default unit)."""
    if "arrangement" in s:
        facings = list(ARRANGEMENTS[str(s["arrangement"]).upper()])
    else:
        facings = [int(round(x)) for x in s["facings"]]
    n = len(facings)
    if "positions_mm" in s:
        z = [float(x) for x in s["positions_mm"]]
    else:
        z = [k * float(s.get("spacing_mm", 0.0)) for k in range(n)]
    return (facings, z, s.get("preloads_N"), s.get("preload_class"),
            [int(k) - 1 for k in s.get("spring_bearings", [])],
            [int(k) - 1 for k in s.get("second_bearings", [])])


def set_problems(data: dict, problems: list) -> None:
    """Cross-checks of [set] (only when the section is there)."""
    s = data.get("set")
    if s is None:
        return
    n0 = len(problems)
    if "arrangement" in s and str(s["arrangement"]).upper() not in ARRANGEMENTS:
        close = arrangement_suggestion(s["arrangement"])
        hint = f"did you mean '{close}'? " if close else ""
        problems.append(f"set.arrangement = {s['arrangement']!r} is not a known arrangement: {hint}"
                        f"(known: {', '.join(ARRANGEMENTS)})")
    for key in ("facings", "positions_mm", "preloads_N", "spring_bearings", "second_bearings"):
        if key in s and not _numbers(s[key]):
            problems.append(f"set.{key} must be an array of finite numbers")
    if "facings" in s and _numbers(s["facings"]) and any(x not in (1, -1) for x in s["facings"]):
        problems.append(f"set.facings = {s['facings']}: each facing must be +1 or -1")
    if len(problems) > n0:
        return
    if "arrangement" in s and "spacing_mm" not in s and "positions_mm" not in s:
        problems.append("set.arrangement needs set.spacing_mm (or set.positions_mm)")
        return
    if "facings" in s and "positions_mm" not in s:
        problems.append("set.facings needs set.positions_mm (one position per bearing)")
        return
    b = data.get("bearing", {})
    D = float(b.get("ball_diameter_mm", 0.0))
    second = data.get("set", {}).get("second_bearing")
    facings, z, pre, cls, springs, seconds = set_layout(s, D)
    n = len(facings)
    if "positions_mm" in s and len(z) != n:
        problems.append(f"set.positions_mm has {len(z)} values for {n} bearings: give one position per bearing")
        return
    for key, idx in (("spring_bearings", springs), ("second_bearings", seconds)):
        bad = [k + 1 for k in idx if not 0 <= k < n]
        if bad:
            problems.append(f"set.{key} = {s[key]}: bearing numbers must be 1..{n}, got {bad}")
            return
    if seconds and second is None:
        problems.append("set.second_bearings names bearings of [set.second_bearing], which is missing")
    if second is not None and not seconds:
        problems.append("[set.second_bearing] is given but set.second_bearings names no bearing that uses it")
    Ds = [float(second.get("ball_diameter_mm", D)) if (second and k in seconds) else D for k in range(n)]
    for k in range(n - 1):
        gap = z[k + 1] - z[k]
        if gap < max(Ds[k], Ds[k + 1]):
            problems.append(f"set.positions_mm: bearings {k + 1} and {k + 2} overlap: positions {fmt_num(z[k])} "
                            f"and {fmt_num(z[k + 1])} mm are {fmt_num(gap)} mm apart, less than one ball "
                            f"diameter ({fmt_num(max(Ds[k], Ds[k + 1]))} mm); positions must increase by at "
                            "least that")
    given = [k for k in ("preload_N", "preload_class", "preloads_N") if k in s]
    if len(given) > 1:
        problems.append(f"set: give at most one of preload_N, preload_class, preloads_N (got {', '.join(given)})")
        return
    if pre is not None:
        if len(pre) != n:
            problems.append(f"set.preloads_N has {len(pre)} values for {n} bearings: give one per bearing")
            return
        if any(p < 0 for p in pre):
            problems.append(f"set.preloads_N = {pre}: preloads must be >= 0 N")
            return
        net = sum(f * p for f, p in zip(facings, pre))
        if abs(net) > 1e-9 * max(sum(pre), 1.0):
            plus = sum(p for f, p in zip(facings, pre) if f > 0)
            problems.append(
                f"set.preloads_N = {pre}: the preloads do not balance (bearings facing +1 carry "
                f"{fmt_num(plus)} N, facing -1 {fmt_num(plus - net)} N): a preload needs an opposed "
                "bearing that carries the same force; make sum(facing x preload) = 0")
    elif ("preload_N" in s and s["preload_N"] > 0) or cls is not None:
        if all(f == facings[0] for f in facings):
            what = f"set.preload_N = {fmt_num(s['preload_N'])}" if "preload_N" in s else f"set.preload_class = {cls!r}"
            problems.append(f"{what}: every bearing of the set faces {facings[0]:+d}; nothing opposes a "
                            "preload (a tandem set cannot carry one): use DB, DF, TBT, ... or no preload")
    if springs:
        if len(set(springs)) == n:
            problems.append("set.spring_bearings: every bearing floats on a spring; nothing holds the shaft "
                            "axially: leave at least one bearing rigid")
        for i in springs:
            for j in springs:
                if j > i and abs(z[j] - z[i]) < PAIR_SPACING * max(Ds[i], Ds[j]):
                    problems.append(f"set.spring_bearings: bearings {i + 1} and {j + 1} form one pair "
                                    f"({fmt_num(abs(z[j] - z[i]))} mm apart, less than {PAIR_SPACING:g} ball "
                                    "diameters): only one bearing of a pair can float on a spring")
        if pre is None:
            problems.append("set.spring_bearings needs set.preloads_N (the spring force of each bearing)")
        else:
            zero = [k + 1 for k in springs if pre[k] <= 0]
            if zero:
                problems.append(f"set.spring_bearings: bearing(s) {zero} have preload 0 N in set.preloads_N: "
                                "a spring preload needs a force > 0")
