"""The sampling rule of simulated signals: a sample rate below twice the highest characteristic
frequency of the case (shaft, FTF, BPFO, BPFI, BSF, 2 BSF) cannot show the defect, so it is
refused, naming the keys and the minimum rate."""
from __future__ import annotations

from ..physics.kinematics import DefectFrequencies
from .messages import fmt_num
from .scenario import as_scenario
from .validation import CaseError

__all__ = ["nominal_frequencies", "highest_frequency", "check_sampling"]

_NAMES = {"shaft": "shaft", "ftf": "FTF", "bpfo": "BPFO", "bpfi": "BPFI", "bsf": "BSF", "two_bsf": "2 BSF"}


def nominal_frequencies(case, speed_rpm=None) -> DefectFrequencies:
    """Shaft and defect frequencies (Hz, floats) of a case or scenario at ``speed_rpm`` (default:
    its ``operation.speed_rpm``) and the free contact angle, the ones ``bearingsim info`` shows
    (:meth:`Scenario.frequencies`)."""
    return as_scenario(case).frequencies(speed_rpm)


def highest_frequency(f: DefectFrequencies) -> tuple[str, float]:
    """(name, Hz) of the highest of shaft, FTF, BPFO, BPFI, BSF and 2 BSF."""
    return max(((label, float(getattr(f, k))) for k, label in _NAMES.items()), key=lambda kv: kv[1])


def check_sampling(case, speed_rpm=None, speed_key="operation.speed_rpm"):
    """Raise CaseError when ``dynamics.sample_rate_Hz`` of a case or scenario is below twice the
    highest characteristic frequency at ``speed_rpm`` (default its speed; ``speed_key`` names
    where it comes from)."""
    sc = as_scenario(case)
    n = sc.speed_rpm if speed_rpm is None else float(speed_rpm)
    name, f = highest_frequency(sc.frequencies(n))
    fs = sc.sample_rate
    if fs < 2.0 * f:
        raise CaseError(sc.source, [
            f"dynamics.sample_rate_Hz = {fmt_num(fs)} is below twice the highest characteristic frequency "
            f"of the case ({name} {f:.1f} Hz at {speed_key} {fmt_num(n)} rpm, free contact angle): "
            f"need sample_rate_Hz >= {2.0 * f:.1f} Hz"])
