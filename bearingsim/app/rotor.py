"""``bearingsim rotor CASE``: a small ROSS rotor on the case's bearing (or set) at both ends, its
Campbell diagram and critical speeds (issue 34; docs/rotordynamics.md).

A steel shaft of ``elements`` elements and one disk at mid-span, the bearings' elements from
:func:`bearingsim.app.rotordynamics.to_ross` (the Jones stiffness over the speeds, the contact
damping of the dynamics with half the rotor's mass); :func:`critical_speeds` finds where the 1X
line crosses a mode; :func:`rotor_command` writes the Campbell diagram
(:func:`bearingsim.output.plots_rotor.plot_campbell`) and the critical speeds (JSON, units in the
key names).  Needs the ``ross`` extra (:func:`~bearingsim.app.rotordynamics.require_ross`).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..case.units import from_si
from ..errors import InputError
from ..output.io import write_json
from ..output.plots_rotor import plot_campbell
from .rotordynamics import (N_PER_UM, RIGID_BODY, BearingStiffness, bearing_stiffness, case_of, checked_speeds,
                            default_speeds_rpm, dropped_terms, require_ross, to_ross)

__all__ = ["RotorModel", "rotor_model", "critical_speeds", "rotor_command"]


@dataclass(frozen=True)
class RotorModel:
    """A small ROSS rotor on the case's bearing (or set) at both ends (:func:`rotor_model`).

    ``rotor`` the ``ross.Rotor``; ``stiffness`` the :class:`BearingStiffness`; ``geometry`` the
    dimensions in SI (``shaft_diameter``, ``span``, ``elements``, ``disk_outer_diameter``,
    ``disk_width``, ``mass`` of the rotor, ``bearing_mass`` the damping's m) and the material."""

    rotor: object
    stiffness: BearingStiffness
    geometry: dict


def _bore(case) -> float:
    """An estimate of the bearing's bore (m): d_m - 1.6 D (the 218: 90 mm; the 6205: 26 mm)."""
    b = case.bearing()
    return float(np.ravel(np.asarray(b.pitch_diameter))[0] - 1.6 * np.ravel(np.asarray(b.ball_diameter))[0])


def rotor_model(case_or_set, speeds_rpm=None, *, stiffness=None, damping=None, shaft_diameter=None, span=None,
                elements=8, disk_diameter_ratio=3.0) -> RotorModel:
    """A steel rotor on two of the case's bearings (or sets), one at each end: a solid shaft of
    ``shaft_diameter`` (m; default the bearing's bore estimate d_m - 1.6 D) and ``span`` (m; default
    8 shaft diameters) in ``elements`` equal elements (6 to 10 keep the first bending modes within
    a fraction of a percent), one steel disk at mid-span (bore the shaft's, outer diameter
    ``disk_diameter_ratio`` shaft diameters, width one shaft diameter).  Each bearing's damping
    mass is half the rotor's mass (:func:`to_ross`, ``damping`` the ratio).  ROSS's steel
    (E = 211 GPa, rho = 7810 kg/m^3)."""
    ross = require_ross()
    case = case_of(case_or_set)
    if stiffness is None:
        stiffness = bearing_stiffness(case, default_speeds_rpm(case) if speeds_rpm is None else speeds_rpm)
    elements = int(elements)
    if not 2 <= elements <= 200 or elements % 2:
        raise InputError(f"elements: an even number of shaft elements from 2 to 200 (the disk sits on the middle "
                         f"node), got {elements}")
    d = _bore(case) if shaft_diameter is None else float(shaft_diameter)
    L = 8.0 * d if span is None else float(span)
    if not (np.isfinite(d) and d > 0 and np.isfinite(L) and L > 0):
        raise InputError(f"shaft_diameter and span must be > 0 m, got {d:g}, {L:g}")
    ratio = float(disk_diameter_ratio)
    if not (np.isfinite(ratio) and ratio > 1.0):
        raise InputError(f"disk_diameter_ratio: the disk's outer diameter in shaft diameters, > 1, got {ratio:g}")
    steel = ross.Material(name="Steel", rho=7810, E=211e9, G_s=81.2e9)
    shaft = [ross.ShaftElement(L=L / elements, idl=0.0, odl=d, material=steel) for _ in range(elements)]
    disk = ross.DiskElement.from_geometry(n=elements // 2, material=steel, width=d, i_d=d, o_d=ratio * d)
    mass = float(sum(e.m for e in shaft) + disk.m)
    z, m_b = damping, 0.5 * mass
    bearings = [to_ross(case, n=k, damping=z, mass_kg=m_b, stiffness=stiffness,
                        tag=f"{'set' if stiffness.is_set else 'bearing'} {i + 1}") for i, k in enumerate((0, elements))]
    rotor = ross.Rotor(shaft, [disk], bearings)
    geometry = dict(shaft_diameter=d, span=L, elements=elements, disk_outer_diameter=ratio * d, disk_width=d,
                    mass=float(rotor.m), bearing_mass=m_b, material="steel: E 211 GPa, rho 7810 kg/m^3")
    return RotorModel(rotor, stiffness, geometry)


def critical_speeds(campbell) -> list[dict]:
    """Where the 1X line crosses a mode of a ROSS Campbell result (``rotor.run_campbell``): each
    tracked mode's damped frequency ``wd`` against the speed, crossings found between neighbouring
    speeds and placed by linear interpolation (no extrapolation beyond the speeds).  One dict per
    crossing, sorted by speed: ``speed_rpm``, ``frequency_Hz`` (= speed / 60), ``mode`` (the column
    of the Campbell arrays), ``whirl`` (ROSS's whirl value at the nearer speed: forward, backward,
    mixed, or axial or torsional), ``damping_ratio``, ``log_dec``."""
    w = np.asarray(campbell.speed_range, float)
    wd = np.asarray(campbell.wd, float)
    zeta = np.asarray(campbell.damping_ratio, float)
    logdec = np.asarray(campbell.log_dec, float)
    whirl = np.asarray(campbell.whirl_values, float)
    names = {0.0: "forward", 1.0: "backward", 0.5: "mixed"}      # ROSS's whirl_values; NaN: not lateral
    out = []
    for j in range(wd.shape[1]):
        f = wd[:, j] - w
        if not np.all(np.isfinite(f)) or np.nanmax(wd[:, j]) < RIGID_BODY:
            continue
        for i in range(len(w) - 1):
            if (f[i] == 0.0 and w[i] > 0.0) or f[i] * f[i + 1] < 0.0:
                t = 0.0 if f[i] == 0.0 else f[i] / (f[i] - f[i + 1])
                speed = w[i] + t * (w[i + 1] - w[i])
                near = i if t < 0.5 else i + 1
                out.append(dict(speed_rpm=float(from_si(speed, "rpm")), frequency_Hz=float(from_si(speed, "rev_s")),
                                mode=j, whirl=names.get(float(whirl[near, j]), "axial or torsional"),
                                damping_ratio=float(zeta[i, j] + t * (zeta[i + 1, j] - zeta[i, j])),
                                log_dec=float(logdec[i, j] + t * (logdec[i + 1, j] - logdec[i, j]))))
    return sorted(out, key=lambda c: c["speed_rpm"])


def rotor_command(case, out_dir, speeds_rpm=None, *, frequencies=8, say=print):
    """``bearingsim rotor CASE [--out DIR] [--speeds-rpm a:b:n]``: the case's bearing (or set)
    stiffness over the speeds, a :func:`rotor_model` on it, its Campbell diagram
    (``DIR/campbell.png``) and critical speeds (``DIR/critical_speeds.json``); returns the paths
    written.  A single bearing or a set alike (the case decides)."""
    case = case_of(case)
    require_ross()
    rpm = default_speeds_rpm(case) if speeds_rpm is None else checked_speeds(speeds_rpm)
    if rpm.size < 2:
        raise InputError("speeds_rpm: a Campbell diagram needs at least 2 speeds")
    st = bearing_stiffness(case, rpm)
    model = rotor_model(case, stiffness=st)
    g = model.geometry
    dropped = dropped_terms(st)
    kind = "set" if st.is_set else "bearing"
    say(f"{case.title or case.source}: the {kind}'s stiffness at {rpm.size} speeds from {rpm[0]:g} to {rpm[-1]:g} rpm")
    K = st.stiffness
    say(f"  kxx {K[0, 0, 0] * N_PER_UM:.4g} -> {K[-1, 0, 0] * N_PER_UM:.4g} N/um, "
        f"kyy {K[0, 1, 1] * N_PER_UM:.4g} -> {K[-1, 1, 1] * N_PER_UM:.4g} N/um, "
        f"kzz {K[0, 2, 2] * N_PER_UM:.4g} -> {K[-1, 2, 2] * N_PER_UM:.4g} N/um")
    say(f"rotor: steel shaft {g['shaft_diameter'] * 1e3:.4g} mm x {g['span'] * 1e3:.4g} mm in {g['elements']} "
        f"elements, disk {g['disk_outer_diameter'] * 1e3:.4g} mm x {g['disk_width'] * 1e3:.4g} mm at mid-span, "
        f"{g['mass']:.4g} kg; the {kind} at both ends")
    say(dropped.text(span=g["span"]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")            # ROSS's own notes (e.g. the plotly renderer)
        camp = model.rotor.run_campbell(st.speed, frequencies=int(frequencies))
    crossings = critical_speeds(camp)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    png, js = out / "campbell.png", out / "critical_speeds.json"
    plot_campbell(camp, crossings, RIGID_BODY, title=f"{case.title or case.source}: rotor on the case's {kind}", path=png)
    data = dict(case=case.source, kind=kind, speeds_rpm=rpm,
                critical_speeds=crossings,
                campbell=dict(speed_rpm=rpm, damped_frequency_Hz=from_si(np.asarray(camp.wd), "rev_s"),
                              damping_ratio=np.asarray(camp.damping_ratio),
                              whirl="ROSS's whirl value per mode column: 0 forward, 1 backward, 0.5 mixed, "
                                    "-1 not lateral (axial or torsional)",
                              whirl_value=np.nan_to_num(np.asarray(camp.whirl_values), nan=-1.0)),
                bearing=dict(kxx_N_per_m=K[:, 0, 0], kyy_N_per_m=K[:, 1, 1], kxy_N_per_m=K[:, 0, 1],
                             kyx_N_per_m=K[:, 1, 0], kzz_N_per_m=K[:, 2, 2],
                             damping="c = 2 zeta sqrt(k m): zeta = dynamics.contact_damping_ratio, "
                                     "m = half the rotor's mass",
                             damping_mass_kg=g["bearing_mass"]),
                dropped=dict(tilt_stiffness_Nm_per_rad=dropped.tilt_stiffness,
                             centre_offset_m=dropped.centre_offset,
                             tilt_stiffness_at_centre_Nm_per_rad=dropped.tilt_stiffness_at_centre,
                             radial_axial_coupling=dropped.radial_axial_coupling,
                             tilt_coupling=dropped.tilt_coupling,
                             rotor_tilt_stiffness_fraction=dropped.tilt_fraction(g["span"])),
                rotor=dict(shaft_diameter_m=g["shaft_diameter"], span_m=g["span"], elements=g["elements"],
                           disk_outer_diameter_m=g["disk_outer_diameter"], disk_width_m=g["disk_width"],
                           mass_kg=g["mass"], material=g["material"]))
    write_json(js, data)
    if crossings:
        say("critical speeds (1X crossings): " + ", ".join(
            f"{c['speed_rpm']:.0f} rpm ({c['whirl']}, zeta {c['damping_ratio']:.3f})" for c in crossings))
    else:
        say(f"no critical speed between {rpm[0]:g} and {rpm[-1]:g} rpm (the 1X line crosses no mode there)")
    return png, js
