"""The one table of units: every conversion between SI (inside) and engineering units (case
files, reports, results files, plot labels) goes through :data:`UNITS`.

A case key's unit is the suffix of its name (``ball_diameter_mm``, ``speed_rpm``, ``axial_N``);
the table also holds the output units the reports and plots use (um, mrad, MPa, ...)::

    to_si(22.225, "mm")         # 0.022225 (m)
    from_si(1047.2, "rpm")      # 10000.0 (from rad/s)
    label("Nm")                 # "N m"
"""
from __future__ import annotations

import math

__all__ = ["UNITS", "to_si", "from_si", "label", "si_unit"]

#: unit name (the suffix of a key name) -> (factor to SI, label in files, docs and messages, SI unit)
UNITS: dict[str, tuple[float, str, str]] = {
    "": (1.0, "", ""),
    "mm": (1e-3, "mm", "m"),
    "deg": (math.pi / 180.0, "deg", "rad"),
    "rpm": (2.0 * math.pi / 60.0, "rpm", "rad/s"),
    "N": (1.0, "N", "N"),
    "kN": (1e3, "kN", "N"),
    "Nm": (1.0, "N m", "N m"),
    "GPa": (1e9, "GPa", "Pa"),
    "kg_m3": (1.0, "kg/m^3", "kg/m^3"),
    "s": (1.0, "s", "s"),
    "Hz": (1.0, "Hz", "Hz"),
    "kg": (1.0, "kg", "kg"),
    "kg_m": (1.0, "kg m", "kg m"),
    "N_per_m": (1.0, "N/m", "N/m"),
    "Ns_per_m": (1.0, "N s/m", "N s/m"),
    "m_s2": (1.0, "m/s^2", "m/s^2"),
    "dB": (1.0, "dB", "dB"),                     # a level ratio, kept in dB
    # output units of reports, results files and plots
    "um": (1e-6, "um", "m"),
    "mrad": (1e-3, "mrad", "rad"),
    "MPa": (1e6, "MPa", "Pa"),
    "g": (1e-3, "g", "kg"),
    "ms": (1e-3, "ms", "s"),
    "per_mm": (1e3, "1/mm", "1/m"),
    "N_per_mm1_5": (1e3 ** 1.5, "N/mm^1.5", "N/m^1.5"),
    "rev_s": (2.0 * math.pi, "Hz", "rad/s"),       # a rotation frequency (shaft, cage) in Hz
    "h": (3600.0, "h", "s"),
    "Mrev": (1e6, "10^6 rev", "rev"),
    "N_per_um": (1e6, "N/um", "N/m"),              # stiffness in the JSON and the printouts
    "Nm_per_mrad": (1e3, "N m/mrad", "N m/rad"),
}


def to_si(value, unit: str):
    """``value`` in ``unit`` -> SI (numbers, NumPy or JAX arrays)."""
    return value * UNITS[unit][0]


def from_si(value, unit: str):
    """SI ``value`` -> ``unit`` (numbers, NumPy or JAX arrays)."""
    return value / UNITS[unit][0]


def label(unit: str) -> str:
    """How ``unit`` is written in files, reports and messages ("N m" for "Nm")."""
    return UNITS[unit][1]


def si_unit(unit: str) -> str:
    """The SI unit values in ``unit`` are converted to ("m" for "mm")."""
    return UNITS[unit][2]
