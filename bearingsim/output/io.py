"""Results files: JSON for single solves, HDF5 for sweeps, studies and simulations.

Everything here is at the edge of the pipeline: the core hands over arrays in SI; this module
converts to the documented output units and writes files atomically (temporary file in the
same directory, then ``os.replace``), refusing to write NaN or infinity.
"""
from __future__ import annotations

import json
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .._version import __version__
from ..case import CaseError, parse_case
from ..case.units import from_si, to_si
from ..errors import BearingsimError, InputError, OutputError, succeeded
from ..physics.kinematics import DefectFrequencies


class NonFiniteOutputError(OutputError):
    """A result about to be written contains NaN or infinity (exit code 4)."""


def _check_finite(name, arr):
    a = np.asarray(arr)
    if a.dtype.kind in "fc" and not np.all(np.isfinite(a)):
        raise NonFiniteOutputError(f"refusing to write {name}: it contains NaN or infinity")
    return a


@contextmanager
def atomic_path(path):
    """Yield a temporary path next to ``path``; move it into place only if the block succeeds.

    A failure of the file system (``OSError``) is raised as :class:`~bearingsim.errors.OutputError`
    naming ``path``; nothing is left behind either way."""
    path = Path(path)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        os.close(fd)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)      # mkstemp makes it owner-only; results are ordinary files
        yield Path(tmp)
        os.replace(tmp, path)
    except BaseException as e:
        if tmp is not None and os.path.exists(tmp):
            os.remove(tmp)
        if isinstance(e, OSError) and not isinstance(e, BearingsimError):
            raise OutputError(f"cannot write {path}: {e.strerror or e}") from e
        raise


#: the ring displacement [x, y, axial, tilt_x, tilt_y] with the unit each is reported in
RING_DOFS = (("x", "um"), ("y", "um"), ("axial", "um"), ("tilt_x", "mrad"), ("tilt_y", "mrad"))

#: per-ball results of the static JSON: (JonesSolution field, unit); the key is "<field>_<unit>"
STATIC_BALL_FIELDS = (("azimuth", "deg"), ("alpha_inner", "deg"), ("alpha_outer", "deg"), ("Q_inner", "N"),
                      ("Q_outer", "N"), ("delta_inner", "um"), ("delta_outer", "um"), ("centrifugal", "N"),
                      ("gyroscopic_moment", "Nm"), ("p_max_inner", "MPa"), ("p_max_outer", "MPa"),
                      ("orbital_speed", "rpm"), ("spall_depth", "um"), ("spall_depth_inner", "um"))


#: the unit convention of every JSON results file and printout (issue 34), stated in each file
#: as its ``units`` entry: engineering units, the unit in every key name, as in the case files
UNITS_NOTE = ("engineering units, the unit in each key name (um, mrad, deg, N, Nm = N m, MPa, rpm, h, Mrev "
              "= 10^6 revolutions, N_per_um, Nm_per_mrad; '-' or none: a ratio or a count); the stiffness "
              "matrix in stiffness.units; SI only inside bearingsim (Python results) and in HDF5 files, "
              "where each dataset has its units attribute")
#: stiffness in the JSON and the printouts: rows the loads (N, N m), columns the displacements in
#: the units of RING_DOFS (um, mrad): N/um, N/mrad, N m/um, N m/mrad
STIFFNESS_JSON_UNITS = ("N/um (force/translation), N/mrad (force/tilt), N m/um (moment/translation), "
                        "N m/mrad (moment/tilt); row = load [Fx, Fy, Fz, Mx, My], column = displacement "
                        "[x, y, axial, tilt_x, tilt_y]")


def stiffness_to_dict(K) -> dict:
    """A 5x5 stiffness dR/dq (SI) as the JSON's ``stiffness`` entry: ``dofs``, ``units``, the matrix
    per um / per mrad of displacement (``matrix_per_um_mrad``) and its diagonal under named keys
    (``radial_x_N_per_um`` ... ``tilt_y_Nm_per_mrad``), the same for a single bearing, each bearing
    of a set and the set."""
    K = np.asarray(K, float)
    col = np.array([to_si(1.0, unit) for _, unit in RING_DOFS])
    E = K * col
    names = ("radial_x_N_per_um", "radial_y_N_per_um", "axial_N_per_um", "tilt_x_Nm_per_mrad", "tilt_y_Nm_per_mrad")
    return {"dofs": [name for name, _ in RING_DOFS], "units": STIFFNESS_JSON_UNITS, "matrix_per_um_mrad": E,
            **{n: float(E[i, i]) for i, n in enumerate(names)}}


def tilt_note(sol) -> str:
    """What the state's ``tilt`` (``JonesSolution.tilt``: "free" or "held") means, for the static
    JSON (``tilt_note``) and text: every output of a state says which model it is."""
    if getattr(sol, "tilt", "free") == "held":
        return ("held: the inner ring's tilt is held at 0 (displacement control, operation.tilt = \"held\"); "
                "the moments in loads are the moments that hold it (the moment sum of the contact forces "
                "about the ring centre); of the 5x5 stiffness the translational 3x3 block (x, y, axial) "
                "is the held ring's")
    return ("free: the inner ring's tilt is force-controlled (operation.tilt = \"free\"): the moments in "
            "loads are applied and the tilts solved (with no moment a radial load tilts the ring)")


def assessment_to_dict(assessment) -> dict:
    """The ``limits`` and ``life`` entries of the ``bearingsim static`` JSON (docs/results.md)."""
    a = assessment
    L = a.limits
    st = a.settings
    arr = lambda x: np.asarray(x)
    deg = lambda x: from_si(np.asarray(x), "deg")
    limits = {
        "contact_pressure_limit_MPa": from_si(float(st["pressure_limit"]), "MPa"),
        "friction_coefficient": float(st["friction_coefficient"]),
        "max_pressure_ratio": float(L.max_pressure_ratio),
        "max_friction_ratio": float(L.max_friction_ratio),
        "min_edge_margin_deg": float(deg(L.min_edge_margin)),
        "overpressure": bool(L.any_overpressure),
        "slip": bool(L.any_slip),
        "truncated": bool(L.any_truncated),
        "over_shoulder": bool(L.any_over_shoulder),
        "flags": list(a.flags),
        "balls": {
            "pressure_ratio_inner": arr(L.pressure_ratio_inner), "pressure_ratio_outer": arr(L.pressure_ratio_outer),
            "friction_needed_inner": arr(L.friction_inner), "friction_needed_outer": arr(L.friction_outer),
            "friction_ratio": arr(L.friction_ratio),
            "edge_margin_high_inner_deg": deg(L.edge_high_inner), "edge_margin_low_inner_deg": deg(L.edge_low_inner),
            "edge_margin_high_outer_deg": deg(L.edge_high_outer), "edge_margin_low_outer_deg": deg(L.edge_low_outer),
            "truncated_inner": arr(L.truncated_inner).tolist(), "truncated_outer": arr(L.truncated_outer).tolist(),
        },
    }
    life = None
    if st["dynamic_load_rating"] is not None:
        life = {
            "dynamic_load_rating_kN": from_si(float(st["dynamic_load_rating"]), "kN"),
            "nominal_contact_angle_deg": from_si(float(a.nominal_angle), "deg"),
            "L10r_Mrev": a.rating_life,
            "L10r_inner_Mrev": None if a.ring_lives is None else a.ring_lives[0],
            "L10r_outer_Mrev": None if a.ring_lives is None else a.ring_lives[1],
            "L10r_h": a.life_hours,
        }
    return {"limits": limits, "life": life}


def static_to_dict(sol, bearing=None, assessment=None) -> dict:
    """The fixed JSON interface of ``bearingsim static`` (:data:`UNITS_NOTE`: units in the key
    names, stiffness per um / mrad: :func:`stiffness_to_dict`); with ``assessment``
    (:func:`bearingsim.app.workflows.assess_case`) also ``limits`` (with ``flags``) and ``life``."""
    q = np.asarray(sol.displacement)
    d = {
        "units": UNITS_NOTE,
        "tilt": getattr(sol, "tilt", "free"),
        "tilt_note": tilt_note(sol),
        "converged": bool(succeeded(int(sol.result))),
        "result": int(sol.result),
        "message": sol.message()[0],
        "iterations": int(sol.iterations),
        "residual_norm": float(sol.residual_norm),
        "residual_norm_units": "N (moments divided by R_i)",
        "ring_displacement": {f"{name}_{unit}": from_si(v, unit) for (name, unit), v in zip(RING_DOFS, q)},
        "cage_speed_rpm": from_si(float(sol.cage_speed), "rpm"),
        "loads": dict(zip(["radial_x_N", "radial_y_N", "axial_N", "moment_x_Nm", "moment_y_Nm"],
                          np.asarray(sol.loads).tolist())),
        "balls": {f"{field}_{unit}": from_si(np.asarray(getattr(sol, field)), unit)
                  for field, unit in STATIC_BALL_FIELDS},
        "stiffness": stiffness_to_dict(sol.stiffness),
    }
    if assessment is not None:
        d.update(assessment_to_dict(assessment))
    return _to_jsonable(d, "static")


def _to_jsonable(obj, name):
    if isinstance(obj, dict):
        return {k: _to_jsonable(v, f"{name}.{k}") for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_to_jsonable(v, name) for v in obj]
    if isinstance(obj, (np.ndarray, np.generic)) or hasattr(obj, "__array__"):
        a = _check_finite(name, obj)
        return a.tolist()
    if isinstance(obj, float) and not np.isfinite(obj):
        raise NonFiniteOutputError(f"refusing to write {name}: it is {obj}")
    return obj


def write_json(path, data: dict):
    """Write ``data`` (dicts, lists, numbers, arrays) as JSON atomically; refuses NaN and infinity."""
    data = _to_jsonable(data, Path(path).name)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(data, indent=2) + "\n")


def write_h5(path, groups: dict, attrs: dict | None = None):
    """Write ``{group: {name: (array, units, extra_attrs_or_None)}}`` to HDF5 atomically.

    Root attributes ``bearingsim_version`` and whatever ``attrs`` holds (e.g. ``case_toml``);
    group attributes under the key ``"@attrs"``.  Every dataset gets a ``units`` attribute.
    """
    import h5py

    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["bearingsim_version"] = __version__
            for k, v in (attrs or {}).items():
                f.attrs[k] = v
            for gname, items in groups.items():
                g = f.require_group(gname)
                for name, spec in items.items():
                    if name == "@attrs":
                        for ak, av in spec.items():
                            g.attrs[ak] = av
                        continue
                    arr, units = spec[0], spec[1]
                    a = _check_finite(f"/{gname}/{name}", arr)
                    # uncompressed: gzip saved 10 % of a `bearingsim simulate` file (17.7 -> 16.0 MB:
                    # physical float64 series hardly compress) and cost 0.3 s of the 3.4 s command
                    ds = g.create_dataset(name, data=a)
                    ds.attrs["units"] = units
                    if len(spec) > 2 and spec[2]:
                        for ak, av in spec[2].items():
                            ds.attrs[ak] = av


STIFFNESS_UNITS = ("N/m, N/rad, N m/m, N m/rad: row = load [Fx, Fy, Fz, Mx, My], "
                   "column = displacement [x, y, axial, tilt_x, tilt_y]")

# name in the results file -> (JonesSolution field, units)
_STATE_FIELDS = {
    "cage_angle": ("cage_angle", "rad"),
    "azimuth": ("azimuth", "rad"),
    "alpha_inner": ("alpha_inner", "rad"),
    "alpha_outer": ("alpha_outer", "rad"),
    "Q_inner": ("Q_inner", "N"),
    "Q_outer": ("Q_outer", "N"),
    "delta_inner": ("delta_inner", "m"),
    "delta_outer": ("delta_outer", "m"),
    "centrifugal": ("centrifugal", "N"),
    "gyroscopic_moment": ("gyroscopic_moment", "N m"),
    "orbital_speed": ("orbital_speed", "rad/s"),
    "spall_depth": ("spall_depth", "m"),
    "spall_depth_inner": ("spall_depth_inner", "m"),
    "p_max_inner": ("p_max_inner", "Pa"),
    "p_max_outer": ("p_max_outer", "Pa"),
    "ring_displacement": ("displacement", "x, y, axial in m; tilt_x, tilt_y in rad"),
    "stiffness": ("stiffness", STIFFNESS_UNITS),
    "iterations": ("iterations", "1"),
    "residual_norm": ("residual_norm", "N (moments divided by R_i)"),
    "result": ("result", "1 (0 = converged; see bearingsim.RESULTS)"),
}


def state_datasets(sol):
    """Datasets of a batch of quasi-static states (sweep: leading (N,), study: (M, N)).

    States that did not converge are flagged in ``converged`` and their values set to 0 (never
    NaN in a results file)."""
    ok = succeeded(np.asarray(sol.result))
    out = {"converged": (ok, "bool (True where the solve converged)")}
    for name, (field, units) in _STATE_FIELDS.items():
        a = np.asarray(getattr(sol, field))
        if a.dtype.kind == "f":
            mask = ok.reshape(ok.shape + (1,) * (a.ndim - ok.ndim))
            a = np.where(mask & np.isfinite(a), a, 0.0) if not np.all(ok) else a
        out[name] = (a, units)
    return out


# ----------------------------------------------------------------------------- results files
def case_attrs(case) -> dict:
    """Root attributes of every results file written for a case: its TOML and title."""
    return {"case_toml": case.text, "title": case.title}


def write_static(path, sol, assessment=None):
    """The JSON of ``bearingsim static`` (:func:`static_to_dict`)."""
    write_json(path, static_to_dict(sol, assessment=assessment))


def write_sweep(path, case, sol):
    """The HDF5 of ``bearingsim sweep``: group ``/sweep`` (:func:`state_datasets`)."""
    write_h5(path, {"sweep": state_datasets(sol)}, attrs=case_attrs(case))


def write_study(path, case, study):
    """The HDF5 of ``bearingsim study``: group ``/study`` with (M, N) states, ``values`` (in the
    key's unit) and the attribute ``parameter``."""
    ds = state_datasets(study.solution)
    ds["values"] = (np.asarray(study.values, dtype=float), study.unit or "1")
    ds["@attrs"] = {"parameter": study.parameter}
    write_h5(path, {"study": ds}, attrs=case_attrs(case))


def simulation_datasets(res, balls):
    """The fixed ``/dynamics`` layout of ``bearingsim simulate`` (SI)."""
    attrs = {k: float(v) for k, v in res.frequencies.hz().items()}
    attrs.update(
        contact_angle_rad=float(res.contact_angle),
        frequency_note=("ftf = quasi-static cage speed / 2 pi, bpfo = Z ftf; bpfi and bsf (once per "
                        "ball revolution) from docs/model.md section 8 at the mean loaded contact angle "
                        "contact_angle_rad"),
        result=int(res.result), num_steps=int(res.num_steps), balls=int(balls),
        ball_iterations=int(res.ball_iterations),
        contact_damping_Ns_per_m=np.asarray(res.contact_damping))
    return {
        "time": (np.asarray(res.time), "s"),
        "cage_angle": (np.asarray(res.cage_angle), "rad"),
        "ring_displacement": (np.asarray(res.ring_displacement), "m (shaft relative to housing: x, y, axial)"),
        "housing_displacement": (np.asarray(res.housing_displacement), "m (x, y)"),
        "housing_acceleration": (np.asarray(res.housing_acceleration), "m/s^2 (x, y)"),
        "sensor_acceleration": (np.asarray(res.sensor_acceleration), "m/s^2"),
        "Q_inner": (np.asarray(res.Q_inner), "N"),
        "Q_outer": (np.asarray(res.Q_outer), "N"),
        "alpha_inner": (np.asarray(res.alpha_inner), "rad"),
        "alpha_outer": (np.asarray(res.alpha_outer), "rad"),
        "spall_edge_times": (np.asarray(res.jump_times, float), "s"),
        "spall_pass_times": (np.asarray(res.pass_times, float), "s"),
        "@attrs": attrs,
    }


def write_simulation(path, case, res):
    """The HDF5 of ``bearingsim simulate``: group ``/dynamics`` (:func:`simulation_datasets`)."""
    write_h5(path, {"dynamics": simulation_datasets(res, case.bearing().n_balls)}, attrs=case_attrs(case))


_FREQUENCIES = ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz")


def read_simulation(path) -> dict:
    """Read back a ``bearingsim simulate`` file: dict(time, sensor_acceleration, frequencies (a
    :class:`~bearingsim.physics.kinematics.DefectFrequencies` from the file's shaft_Hz, ftf_Hz,
    bpfo_Hz, bpfi_Hz, bsf_Hz), case: the stored Case or None).  Raises
    :class:`~bearingsim.errors.InputError` for anything else."""
    import h5py

    if Path(path).is_dir():
        raise InputError(f"{path}: is a directory, not a bearingsim simulate output")
    try:
        with h5py.File(path, "r") as f:
            g = f["dynamics"]
            out = {"time": g["time"][()], "sensor_acceleration": g["sensor_acceleration"][()],
                   "frequencies": DefectFrequencies.from_hz({k: float(g.attrs[k]) for k in _FREQUENCIES})}
            toml = f.attrs.get("case_toml", "")
    except (OSError, KeyError) as e:
        raise InputError(f"{path}: not a bearingsim simulate output ({e})") from None
    if out["time"].size < 2:
        raise InputError(f"{path}: /dynamics/time has {out['time'].size} samples; need at least 2")
    try:
        out["case"] = parse_case(toml, source=f"{path}:case_toml") if toml else None
    except CaseError:
        out["case"] = None
    return out
