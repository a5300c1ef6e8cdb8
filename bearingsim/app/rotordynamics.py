"""bearingsim bearings in a rotor model of ROSS (issue 34; docs/rotordynamics.md).

ROSS (``ross-rotordynamics``, the optional extra ``bearingsim[ross]``) is the open rotordynamics
library: shaft, disk and bearing elements, modal analysis, Campbell diagrams, critical speeds.
Its bearing, ``ross.BearingElement``, holds speed-dependent coefficients at one node: the lateral
stiffness and damping ``kxx, kxy, kyx, kyy`` / ``cxx, ...`` and, from ROSS 2.0 (6 degrees of
freedom per node), the axial ``kzz`` / ``czz``, each an array over ``frequency`` (the rotor
speed, rad/s).  This module fills it from the Jones quasi-static solution of a case:

* :func:`bearing_stiffness`: the bearing's 5x5 stiffness dR/dq at the case's operating point
  (its loads, cage angle, raceway control, Hertz method) at each speed, every speed one item of
  one vmapped batch (``jones.solve_batch``; a set: ``shaft.solve_set_batch``), padded to a power
  of two (at least 8 items) so that few batch shapes are ever compiled.
* :func:`to_ross`: the ``ross.BearingElement`` with ``kxx = K[0, 0]``, ``kxy = K[0, 1]``,
  ``kyx = K[1, 0]``, ``kyy = K[1, 1]``, ``kzz = K[2, 2]`` over the speeds, and the damping of the
  dynamics (:func:`contact_damping`: ``c = 2 zeta sqrt(k m)`` on xx, yy, zz; no cross damping).
* :func:`dropped_terms`: what ROSS has no place for and its size.  A ROSS bearing has no
  rotational (tilt) stiffness and no coupling between its translations and tilts or between its
  radial and axial translations; the 5x5 stiffness has them.  Reported: the tilt stiffness at the
  reference point, the offset of the bearing's stiffness centre (where its radial force acts: an
  angular contact bearing's pressure centre, ~ (d_m / 2) tan(alpha) from its plane), the tilt
  stiffness left at that centre, and the largest dimensionless couplings
  ``|K_ij| / sqrt(K_ii K_jj)``.  Two bearings a span ``L`` apart carry a rotor's tilt with
  ``k L^2 / 2``; each bearing's own tilt stiffness ``K_tt`` adds ``4 K_tt / (k L^2)`` to it.
* A preloaded set (a case with ``[set]``) is **one** element with the set's stiffness (its
  ``SetSolution.stiffness``, the bearings' stiffness through the shared shaft, the floating rings
  condensed out): the set's bearings sit tens of millimetres apart on one sleeve, short against a
  rotor's bending wavelength, so a rotor model puts the set at one node.  The translational terms
  do not depend on the reference point; the set's tilt stiffness (the pair's spread, large for a
  DB pair) is the dropped term that matters and is reported.
* The rotor built on these elements (``bearingsim rotor CASE``) is :mod:`bearingsim.app.rotor`;
  its Campbell diagram is drawn by :mod:`bearingsim.output.plots_rotor`.

Speeds are rpm at the interface (``speeds_rpm``), SI inside (``BearingStiffness.speed`` rad/s,
stiffness N/m, N/rad, N m/m, N m/rad, damping N s/m).  ROSS is imported at first use only
(:func:`require_ross`): ``import bearingsim`` and every other command work without it, and a
command that needs it says ``pip install 'bearingsim[ross]'``.
"""
from __future__ import annotations

import contextlib
import inspect
import os
import sys
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from ..case import Case, as_scenario, load_case
from ..case.units import to_si
from ..errors import failed, InputError, NotConvergedError
from ..physics.jones import raise_for, solve_batch
from ..physics.kinematics import Operation
from ..physics.shaft import raise_for_set, solve_set_batch

__all__ = ["BearingStiffness", "bearing_stiffness", "contact_damping", "DroppedTerms", "dropped_terms",
           "to_ross", "require_ross", "default_speeds_rpm", "parse_speeds", "case_of", "checked_speeds",
           "INSTALL", "MAX_SPEEDS", "MIN_BATCH", "RIGID_BODY", "N_PER_UM"]

#: how to get ROSS
INSTALL = "pip install 'bearingsim[ross]'"
#: at most this many speeds in one call (one batch)
MAX_SPEEDS = 1024
#: the smallest batch solved: a few speeds share one compiled program (padded with the last speed)
MIN_BATCH = 8
#: stiffness in reports: N/m -> N/um
N_PER_UM = 1e-6
#: the dropped off-diagonal pairs of the 5x5 stiffness [x, y, z, tilt_x, tilt_y]
_RADIAL_AXIAL = ((0, 2), (1, 2))
_TILT = ((0, 3), (0, 4), (1, 3), (1, 4), (2, 3), (2, 4), (3, 4))
#: modes below this frequency (rad/s) are rigid-body modes (the free torsion of the rotor)
RIGID_BODY = 1e-3


# ------------------------------------------------------------------------------------ ROSS
@contextlib.contextmanager
def _quiet_import():
    """Importing ROSS imports ccp and CoolProp, whose C++ library prints a REFPROP notice on the
    process's stdout and warns that REFPROP is not configured (neither is used here): both go to
    a temporary file while ROSS is imported; a real import error is still raised."""
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = [os.dup(1), os.dup(2)]
    except (OSError, ValueError):        # no file descriptors to redirect (an embedded interpreter)
        saved = None
    with warnings.catch_warnings(), tempfile.TemporaryFile() as sink:
        warnings.simplefilter("ignore")
        if saved is None:
            yield
            return
        try:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
            yield
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)


#: the ROSS functions whose Numba cache this process has switched on
_CACHED = set()


def require_ross():
    """The ``ross`` module, imported at first use; :class:`InputError` saying how to install it
    when it is missing, too old (the axial ``kzz`` of ROSS >= 2.0 is used) or broken.

    ROSS compiles one Numba function (the orbits of every mode shape) at the first modal analysis
    of each process, ~13 s; its cache is switched on here so that later processes load it."""
    try:
        with _quiet_import():
            import ross
    except ImportError as e:
        raise InputError(f"the rotordynamics functions need ROSS (ross-rotordynamics), which is not "
                         f"installed ({e}): {INSTALL}") from None
    except Exception as e:       # noqa: BLE001 - e.g. ROSS 2.3 with plotly 7 (a removed plotly trace type)
        first = str(e).strip().splitlines()[0] if str(e).strip() else ""
        raise InputError(f"ROSS (ross-rotordynamics) is installed but does not import: {type(e).__name__}: "
                         f"{first}; {INSTALL} installs versions that work together (plotly < 7)") from None
    if "kzz" not in inspect.signature(ross.BearingElement).parameters:
        raise InputError(f"ROSS {getattr(ross, '__version__', '?')} is too old: its BearingElement has no axial "
                         f"stiffness kzz (ROSS >= 2.0, 6 degrees of freedom per node): {INSTALL}")
    orbit = getattr(getattr(ross, "results", None), "_init_orbit", None)
    if hasattr(orbit, "enable_caching") and id(orbit) not in _CACHED:
        try:
            orbit.enable_caching()       # Numba's own cache: next to ROSS's source, else the user's cache
        except Exception:        # noqa: BLE001 - a cache that cannot be used: ROSS compiles in every process
            pass
        _CACHED.add(id(orbit))
    return ross


# ------------------------------------------------------------------------------ the inputs
def case_of(case_or_set) -> Case:
    if isinstance(case_or_set, Case):
        return case_or_set
    if isinstance(case_or_set, (str, Path)):
        return load_case(case_or_set)
    raise InputError(f"case_or_set: a Case (load_case(...), a single bearing or a set) or a case file / shipped "
                     f"case name, got {type(case_or_set).__name__}")


def checked_speeds(speeds_rpm, what="speeds_rpm") -> np.ndarray:
    """The speeds (rpm) as a 1-d float array, checked: 1 to MAX_SPEEDS finite values >= 0."""
    try:
        s = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    except (TypeError, ValueError):
        raise InputError(f"{what}: numbers in rpm expected, got {speeds_rpm!r}") from None
    if s.ndim != 1 or not 1 <= s.size <= MAX_SPEEDS:
        raise InputError(f"{what}: 1 to {MAX_SPEEDS} speeds in rpm (a 1-d list), got shape {s.shape}")
    if not np.all(np.isfinite(s)) or np.any(s < 0.0):
        bad = s[~np.isfinite(s) | (s < 0.0)][0]
        raise InputError(f"{what}: every speed must be a finite number >= 0 rpm, got {bad:g}")
    return s


def default_speeds_rpm(case) -> np.ndarray:
    """16 speeds from 0 to 1.5 times the case's speed (10 000 rpm for a case at standstill)."""
    top = float(case_of(case).get("operation.speed_rpm")) * 1.5 or 10000.0
    return np.linspace(0.0, top, 16)


def parse_speeds(text: str, flag: str = "--speeds-rpm") -> np.ndarray:
    """``"START:STOP:COUNT"`` (rpm) -> ``np.linspace(START, STOP, COUNT)``: 0 <= START < STOP,
    COUNT from 2 to :data:`MAX_SPEEDS` (the command line's ``--speeds-rpm``)."""
    parts = str(text).split(":")
    usage = (f"{flag} {text!r}: START:STOP:COUNT in rpm expected, e.g. 0:15000:16 (0 <= START < STOP, "
             f"COUNT from 2 to {MAX_SPEEDS})")
    if len(parts) != 3:
        raise InputError(usage)
    try:
        a, b, n = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise InputError(usage) from None
    if not (np.isfinite(a) and np.isfinite(b) and 0.0 <= a < b and 2 <= n <= MAX_SPEEDS):
        raise InputError(usage)
    return np.linspace(a, b, n)


# ---------------------------------------------------------------------------- the stiffness
@dataclass(frozen=True)
class BearingStiffness:
    """The stiffness of a case's bearing (or set) over speeds (:func:`bearing_stiffness`).

    ``speeds_rpm`` (M,) rpm; ``stiffness`` (M, 5, 5) dR/dq (rows the loads [Fx, Fy, Fz, Mx, My],
    columns the displacements [x, y, axial, tilt_x, tilt_y]: N/m, N/rad, N m/m, N m/rad; a set's at
    its reference point, shaft frame); ``is_set``; ``source`` (the case); ``solution`` the
    quasi-static states, one per speed (``JonesSolution`` or ``SetSolution`` with a leading (M,)
    axis)."""

    speeds_rpm: np.ndarray
    stiffness: np.ndarray
    is_set: bool
    source: str
    solution: object

    @property
    def speed(self) -> np.ndarray:
        """The speeds in rad/s (ROSS's ``frequency``)."""
        return to_si(self.speeds_rpm, "rpm")

    @property
    def radial(self) -> np.ndarray:
        """(M, 2, 2) the radial translational block [[kxx, kxy], [kyx, kyy]] (N/m)."""
        return self.stiffness[:, :2, :2]


def _padded(n: int) -> int:
    return max(MIN_BATCH, 1 << max(0, int(n - 1).bit_length()))


def bearing_stiffness(case_or_set, speeds_rpm, *, throw=True) -> BearingStiffness:
    """The 5x5 stiffness of the case's bearing at its operating point at each speed (rpm).

    The case's loads, cage angle, raceway control, centrifugal and gyroscopic switches, Hertz
    method (and defect) with the speed replaced by each value; every speed is one item of one
    vmapped batch (``jones.solve_batch``, a set: ``shaft.solve_set_batch`` with the rigid preload
    offsets fixed at standstill, as ``bearingsim study`` of the speed), padded to a power of two
    (>= :data:`MIN_BATCH`).  ``case_or_set``: a :class:`~bearingsim.case.Case` (a single bearing or
    a ``[set]``) or a case file / shipped name.  ``throw``: raise ``NotConvergedError`` /
    ``InvalidStateError`` naming the case and the first speed that failed; else check
    ``.solution.result``."""
    case = case_of(case_or_set)
    sc = as_scenario(case)
    rpm = checked_speeds(speeds_rpm)
    M, n = rpm.size, _padded(rpm.size)
    idx = np.minimum(np.arange(n), M - 1)
    base = sc.operation
    op = Operation(jnp.asarray(to_si(rpm[idx], "rpm")), base.control, base.centrifugal, base.gyroscopic)
    loads = jnp.broadcast_to(sc.loads, (n, 5))
    if sc.is_set:
        sol = solve_set_batch(sc.bearing_set, op, loads, cage_angle=sc.cage_angle,
                              hertz_method=sc.hertz_method)
    else:
        sol = solve_batch(sc.bearing, op, loads, cage_angle=sc.cage_angle, spall=sc.spall,
                          hertz_method=sc.hertz_method, tilt=sc.tilt)
    sol = jax.tree_util.tree_map(lambda a: a[:M], sol)
    bad = np.flatnonzero(failed(np.asarray(sol.result)))
    if throw and bad.size:
        k = int(bad[0])
        one = jax.tree_util.tree_map(lambda a: a[k], sol)
        more = f"; {bad.size} of {M} speeds failed" if bad.size > 1 else ""
        what = f"{sc.source}: the quasi-static solve at {rpm[k]:g} rpm (stiffness for ROSS{more})"
        try:
            if sc.is_set:
                raise_for_set(one, what)
            raise_for(one, what, bearing=sc.bearing)
        except NotConvergedError as e:          # InvalidStateError too: the same class, the speeds named
            below = rpm[rpm < rpm[k]]
            keep = f"or keep the speeds (speeds_rpm) below {rpm[k]:g} rpm" if below.size else \
                "or change the speeds (speeds_rpm)"
            if below.size >= 2 and below.max() > below.min():
                keep += f" (bearingsim rotor --speeds-rpm {below.min():g}:{below.max():g}:{below.size})"
            raise type(e)(e.message, f"{e.hint}; {keep}" if e.hint else keep, e.code) from None
    return BearingStiffness(rpm, np.asarray(sol.stiffness), bool(case.is_set), case.source, sol)


def contact_damping(stiffness, ratio, mass) -> np.ndarray:
    """The contact damping of the dynamics (``bearingsim.dynamics.model.contact_damping``, the
    ``[dynamics]`` keys ``contact_damping_ratio`` and ``shaft_mass_kg``): ``c = 2 zeta sqrt(k m)``
    (N s/m) on the diagonal k of x, y, axial of ``stiffness`` (..., 5, 5) or (..., 3, 3); (..., 3).
    A bearing-on-mass mode of mass ``m`` then has the damping ratio ``zeta``."""
    K = np.asarray(stiffness, float)
    k = np.diagonal(K[..., :3, :3], axis1=-2, axis2=-1)
    return 2.0 * float(ratio) * np.sqrt(np.maximum(k, 0.0) * float(mass))


# ------------------------------------------------------------------------- the dropped terms
@dataclass(frozen=True)
class DroppedTerms:
    """What a ROSS bearing element has no place for, per speed (:func:`dropped_terms`).

    ``tilt_stiffness`` (M, 2): K[3, 3], K[4, 4] at the reference point (N m/rad);
    ``centre_offset`` (M, 2): where the radial force acts along the shaft axis from the reference
    point, from the x and the y plane (K[4, 0] / K[0, 0], -K[3, 1] / K[1, 1]; m; an angular contact
    bearing's pressure centre); ``tilt_stiffness_at_centre`` (M, 2): the tilt stiffness left once
    the bearing sits at that centre (N m/rad; what a node there still misses);
    ``radial_axial_coupling`` (M,) and ``tilt_coupling`` (M,): the largest ``|K_ij| /
    sqrt(K_ii K_jj)`` of the radial-axial terms (independent of the reference point) and of the
    translation-tilt and tilt-tilt terms (at the reference point)."""

    speeds_rpm: np.ndarray
    tilt_stiffness: np.ndarray
    centre_offset: np.ndarray
    tilt_stiffness_at_centre: np.ndarray
    radial_axial_coupling: np.ndarray
    tilt_coupling: np.ndarray
    radial_stiffness: np.ndarray     # (M, 2) kxx, kyy (N/m), for the ratios

    def tilt_fraction(self, span) -> np.ndarray:
        """(M,) the rotor tilt stiffness the two bearings' own tilt stiffness would add to what
        their radial stiffness gives, for two such bearings ``span`` (m) apart:
        ``4 K_tt / (k span^2)`` (K_tt at the stiffness centre, the larger plane)."""
        k = self.radial_stiffness
        return np.max(4.0 * self.tilt_stiffness_at_centre / (np.maximum(k, 1e-300) * float(span) ** 2), axis=-1)

    def text(self, span=None) -> str:
        """The sizes in a few lines (the ranges over the speeds)."""
        def rng(a, f=1.0, fmt=".3g"):
            a = np.asarray(a) * f
            lo, hi = float(np.min(a)), float(np.max(a))
            return f"{lo:{fmt}}" if np.isclose(lo, hi, rtol=1e-3, atol=0) else f"{lo:{fmt}} to {hi:{fmt}}"

        lines = ["not in the ROSS element (no place for them):",
                 f"  tilt stiffness at the reference point {rng(self.tilt_stiffness, 1e-3)} N m/mrad",
                 f"  stiffness centre (radial force line) {rng(self.centre_offset, 1e3)} mm along the shaft "
                 "axis from the reference point",
                 f"  tilt stiffness at that centre {rng(self.tilt_stiffness_at_centre, 1e-3)} N m/mrad",
                 f"  largest radial-axial coupling |K_ij|/sqrt(K_ii K_jj) {rng(self.radial_axial_coupling)}; "
                 f"translation-tilt {rng(self.tilt_coupling)}"]
        if span is not None:
            lines.append(f"  for bearings {float(span) * 1e3:.4g} mm apart their own tilt stiffness would add "
                         f"{rng(self.tilt_fraction(span), 100.0, '.2g')} % to the rotor's tilt stiffness")
        return "\n".join(lines)


def _coupling(K, pairs):
    d = np.abs(np.diagonal(K, axis1=-2, axis2=-1))
    out = np.zeros(K.shape[:-2])
    for i, j in pairs:
        c = np.maximum(np.abs(K[..., i, j]), np.abs(K[..., j, i])) / np.sqrt(np.maximum(d[..., i] * d[..., j], 1e-300))
        out = np.maximum(out, c)
    return out


def dropped_terms(stiffness: BearingStiffness) -> DroppedTerms:
    """The size of the 5x5 stiffness terms a ROSS bearing element drops (see :class:`DroppedTerms`)."""
    K = np.asarray(stiffness.stiffness, float)
    kx, ky = K[:, 0, 0], K[:, 1, 1]
    ex = K[:, 4, 0] / kx
    ey = -K[:, 3, 1] / ky
    tx = K[:, 3, 3] - K[:, 3, 1] * K[:, 1, 3] / ky
    ty = K[:, 4, 4] - K[:, 4, 0] * K[:, 0, 4] / kx
    return DroppedTerms(stiffness.speeds_rpm, np.stack([K[:, 3, 3], K[:, 4, 4]], -1), np.stack([ex, ey], -1),
                        np.stack([tx, ty], -1), _coupling(K, _RADIAL_AXIAL), _coupling(K, _TILT),
                        np.stack([kx, ky], -1))


# ---------------------------------------------------------------------------- the element
def _damping_settings(case, damping, mass_kg):
    dyn = as_scenario(case).dynamics
    ratio = dyn["contact_damping_ratio"] if damping is None else damping
    mass = dyn["shaft_mass"] if mass_kg is None else mass_kg
    try:
        ratio, mass = float(ratio), float(mass)
    except (TypeError, ValueError):
        raise InputError(f"damping (a damping ratio) and mass_kg must be numbers, got {damping!r}, {mass_kg!r}") from None
    if not (np.isfinite(ratio) and 0.0 <= ratio < 2.0):
        raise InputError(f"damping: the contact damping ratio zeta_b must be in [0, 2) (as "
                         f"dynamics.contact_damping_ratio), got {ratio:g}")
    if not (np.isfinite(mass) and mass > 0.0):
        raise InputError(f"mass_kg: the mass of c = 2 zeta sqrt(k m) must be > 0 kg, got {mass:g}")
    return ratio, mass


def to_ross(case_or_set, n=0, speeds_rpm=None, damping=None, *, mass_kg=None, tag=None, stiffness=None,
            n_link=None, scale_factor=1.0):
    """A ``ross.BearingElement`` at node ``n`` from the case's bearing (or set) over ``speeds_rpm``.

    Stiffness (N/m): ``kxx, kxy, kyx, kyy`` = the radial translational block of
    :func:`bearing_stiffness` (dR/dq at the case's loads, each speed its own Jones solution) and
    the axial ``kzz`` = K[2, 2]; ``frequency`` = the speeds in rad/s (ROSS interpolates between
    them).  Damping (N s/m): the contact damping the dynamics use, ``c = 2 zeta sqrt(k m)`` on
    ``cxx, cyy, czz`` with ``k`` the direct stiffness at each speed (:func:`contact_damping`), no
    cross damping; ``damping`` is the ratio ``zeta`` (default: the case's
    ``dynamics.contact_damping_ratio``, 0.05 unless set) and ``mass_kg`` the mass ``m`` (default the
    case's ``dynamics.shaft_mass_kg``; in a rotor the mass share each bearing carries, so that a
    bearing-on-mass mode has the damping ratio ``zeta``).  ``damping=0``: undamped.

    Dropped (ROSS has no place for them): the tilt stiffness and the translation-tilt and
    radial-axial couplings; their size: :func:`dropped_terms` (``bearingsim rotor`` prints it).
    A set gives one element with the set's stiffness (its bearings sit close together on one
    node).  ``stiffness``: a :class:`BearingStiffness` already computed (then ``speeds_rpm`` is its
    own); ``speeds_rpm`` default :func:`default_speeds_rpm`.  Needs ROSS (:func:`require_ross`)."""
    ross = require_ross()
    case = case_of(case_or_set)
    ratio, mass = _damping_settings(case, damping, mass_kg)
    if stiffness is None:
        stiffness = bearing_stiffness(case, default_speeds_rpm(case) if speeds_rpm is None else speeds_rpm)
    elif speeds_rpm is not None and not np.array_equal(np.asarray(speeds_rpm, float), stiffness.speeds_rpm):
        raise InputError("speeds_rpm: give the speeds or a stiffness computed at them, not both differing")
    K = stiffness.stiffness
    c = contact_damping(K, ratio, mass)
    if tag is None:
        tag = f"{'set' if stiffness.is_set else 'bearing'} {Path(str(stiffness.source).split(' with ')[0]).stem} " \
              f"node {n}"
    return ross.BearingElement(n=int(n), kxx=K[:, 0, 0], kxy=K[:, 0, 1], kyx=K[:, 1, 0], kyy=K[:, 1, 1],
                               kzz=K[:, 2, 2], cxx=c[:, 0], cyy=c[:, 1], cxy=np.zeros(len(K)),
                               cyx=np.zeros(len(K)), czz=c[:, 2], frequency=stiffness.speed, tag=tag,
                               n_link=n_link, scale_factor=scale_factor)
