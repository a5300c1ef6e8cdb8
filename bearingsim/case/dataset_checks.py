"""Cross-checks of a case's [dataset] section against its bearing and defect (the ranges a data set
draws from must describe a spall that fits the bearing), and the free contact angle from either
of its keys.  Used by :mod:`bearingsim.case.validation`."""
from __future__ import annotations

import math

from .messages import fmt_num, fmt_value
from .schema import SCHEMA
from .units import from_si, to_si

__all__ = ["dataset_problems", "free_contact_angle_deg"]


def free_contact_angle_deg(b: dict) -> float | None:
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
    return from_si(math.acos(c), "deg")


def dataset_problems(data: dict, problems: list[str], geometry_ok: bool, raw_dataset: dict) -> None:
    """Append to ``problems`` what is wrong between the [dataset] ranges and the rest of the case
    (``raw_dataset``: the file's [dataset] section as written; ``geometry_ok``: the bearing's keys
    are each valid)."""
    ds = data.get("dataset")
    if ds is None:
        return
    b = data.get("bearing", {})
    for key in ("spall_length_mm", "spall_depth_mm"):
        if key not in ds and data.get("defect", {}).get(key[len("spall_"):]) is None:
            if key not in raw_dataset:  # else invalid, reported
                problems.append(f"missing key dataset.{key}: must be {SCHEMA['dataset'].keys[key].requirement_text()} "
                                f"(the case has no [defect] {key[len('spall_'):]} to take it from)")
    if "spall_depth_mm" in ds and "ball_diameter_mm" in b and not ds["spall_depth_mm"][1] < b["ball_diameter_mm"]:
        problems.append(f"dataset.spall_depth_mm = {fmt_value(ds['spall_depth_mm'])}: the largest depth must be "
                        f"less than bearing.ball_diameter_mm = {fmt_num(b['ball_diameter_mm'])}")
    alpha0 = free_contact_angle_deg(b)
    if "spall_length_mm" in ds and geometry_ok and "balls" in b and alpha0 is not None:
        R_o = 0.5 * (b["pitch_diameter_mm"] + b["ball_diameter_mm"] * math.cos(to_si(alpha0, "deg")))
        pitch = 2.0 * math.pi / b["balls"] * R_o
        if not ds["spall_length_mm"][1] < pitch:
            problems.append(f"dataset.spall_length_mm = {fmt_value(ds['spall_length_mm'])}: the longest spall "
                            f"must be shorter than the ball pitch {fmt_num(pitch)} mm along the outer raceway: "
                            "only one ball at a time may be over the spall")
    fr = [ds.get(k) for k in ("healthy_fraction", "outer_fraction", "inner_fraction", "ball_fraction")]
    if all(isinstance(v, (int, float)) for v in fr) and abs(sum(fr) - 1.0) > 1e-9:
        problems.append("dataset.healthy_fraction + outer_fraction + inner_fraction + ball_fraction = "
                        f"{fmt_num(sum(fr))}: the class fractions must add up to 1")
    if "inner_length_mm" in ds and geometry_ok and "balls" in b and alpha0 is not None and ds.get("inner_fraction"):
        R_i = 0.5 * (b["pitch_diameter_mm"] - b["ball_diameter_mm"] * math.cos(to_si(alpha0, "deg")))
        pitch = 2.0 * math.pi / b["balls"] * R_i
        if not ds["inner_length_mm"][1] < pitch:
            problems.append(f"dataset.inner_length_mm = {fmt_value(ds['inner_length_mm'])}: the longest spall "
                            f"must be shorter than the ball pitch {fmt_num(pitch)} mm along the inner raceway")
    if "ball_length_mm" in ds and "ball_diameter_mm" in b and ds.get("ball_fraction"):
        half = 0.5 * math.pi * b["ball_diameter_mm"]
        if not ds["ball_length_mm"][1] < half:
            problems.append(f"dataset.ball_length_mm = {fmt_value(ds['ball_length_mm'])}: the largest pit must "
                            f"be shorter than half the ball's circumference ({fmt_num(half)} mm): it may meet "
                            "one raceway at a time")
    for key in ("inner_depth_mm", "ball_depth_mm"):
        if ds.get(key[:key.index("_")] + "_fraction") and ds.get(key) != ds.get("spall_depth_mm") and \
                key in ds and "ball_diameter_mm" in b and not ds[key][1] < b["ball_diameter_mm"]:
            problems.append(f"dataset.{key} = {fmt_value(ds[key])}: the largest depth must be less than "
                            f"bearing.ball_diameter_mm = {fmt_num(b['ball_diameter_mm'])}")
    if "fault_snr_dB" in ds and ds.get("background", "none") == "none":
        problems.append(f"dataset.fault_snr_dB = {fmt_value(ds['fault_snr_dB'])} needs a background to stand "
                        "over: set dataset.background = \"random\" or \"machine\", or remove fault_snr_dB")
    if "ball_fault_snr_dB" in ds and "fault_snr_dB" not in ds:
        problems.append(f"dataset.ball_fault_snr_dB = {fmt_value(ds['ball_fault_snr_dB'])} is the ball class's "
                        "fault_snr_dB: give dataset.fault_snr_dB (every fault class's) too, or remove it")
    noise = data.get("dynamics", {}).get("noise_rms_m_s2", 0.0)
    if ds.get("background", "none") != "none" and isinstance(noise, (int, float)) and noise > 0.0:
        problems.append(f"dataset.background = \"{ds['background']}\" with dynamics.noise_rms_m_s2 = "
                        f"{fmt_num(noise)}: the background carries the broadband noise (and fault_snr_dB "
                        "scales the bearing's signal against it): set dynamics.noise_rms_m_s2 = 0")
    pos = ds.get("outer_center_positions_deg")
    if pos is not None and not all(isinstance(v, (int, float)) and -360.0 <= v <= 360.0 for v in pos):
        problems.append(f"dataset.outer_center_positions_deg = {fmt_value(pos)}: every position must be a "
                        "number within [-360, 360] deg")
    fr3 = ds.get("split_fractions")
    if fr3 is not None and (len(fr3) != 3 or not all(isinstance(v, (int, float)) and v >= 0 for v in fr3)
                            or sum(fr3) <= 0):
        problems.append(f"dataset.split_fractions = {fmt_value(fr3)}: give three fractions >= 0 (train, "
                        "validation, test) with a positive sum")
    if "radial_N" in ds and "axial_N" in ds and ds["radial_N"][0] <= 0.0 and ds["axial_N"][0] <= 0.0:
        problems.append(f"dataset.radial_N = {fmt_value(ds['radial_N'])} and dataset.axial_N = "
                        f"{fmt_value(ds['axial_N'])} both allow 0: an unloaded bearing has no solution; "
                        "raise the minimum of one of them")
