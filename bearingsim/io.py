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

from ._version import __version__
from .errors import BearingsimError, OutputError

RAD2DEG = 180.0 / np.pi


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


def static_to_dict(sol, bearing=None) -> dict:
    """The fixed JSON interface of ``bearingsim static`` (units in the key names; stiffness SI)."""
    q = np.asarray(sol.displacement)
    d = {
        "converged": bool(int(sol.result) == 0),
        "result": int(sol.result),
        "message": sol.message()[0],
        "iterations": int(sol.iterations),
        "residual_norm": float(sol.residual_norm),
        "residual_norm_units": "N (moments divided by R_i)",
        "ring_displacement": {"x_um": q[0] * 1e6, "y_um": q[1] * 1e6, "axial_um": q[2] * 1e6,
                              "tilt_x_mrad": q[3] * 1e3, "tilt_y_mrad": q[4] * 1e3},
        "cage_speed_rpm": float(sol.cage_speed) * 60.0 / (2.0 * np.pi),
        "loads": dict(zip(["radial_x_N", "radial_y_N", "axial_N", "moment_x_Nm", "moment_y_Nm"],
                          np.asarray(sol.loads).tolist())),
        "balls": {
            "azimuth_deg": np.asarray(sol.azimuth) * RAD2DEG,
            "alpha_inner_deg": np.asarray(sol.alpha_inner) * RAD2DEG,
            "alpha_outer_deg": np.asarray(sol.alpha_outer) * RAD2DEG,
            "Q_inner_N": np.asarray(sol.Q_inner),
            "Q_outer_N": np.asarray(sol.Q_outer),
            "delta_inner_um": np.asarray(sol.delta_inner) * 1e6,
            "delta_outer_um": np.asarray(sol.delta_outer) * 1e6,
            "centrifugal_N": np.asarray(sol.centrifugal),
            "gyroscopic_moment_Nm": np.asarray(sol.gyroscopic_moment),
            "p_max_inner_MPa": np.asarray(sol.p_max_inner) * 1e-6,
            "p_max_outer_MPa": np.asarray(sol.p_max_outer) * 1e-6,
            "orbital_speed_rpm": np.asarray(sol.orbital_speed) * 60.0 / (2.0 * np.pi),
            "spall_depth_um": np.asarray(sol.spall_depth) * 1e6,
        },
        "stiffness": {
            "dofs": ["x", "y", "axial", "tilt_x", "tilt_y"],
            "units": "N/m (force/translation), N/rad (force/tilt), N m/m (moment/translation), "
                     "N m/rad (moment/tilt); row = load, column = displacement",
            "matrix": np.asarray(sol.stiffness),
        },
    }
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
                    ds = g.create_dataset(name, data=a, compression="gzip" if a.size > 4096 else None)
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
    "p_max_inner": ("p_max_inner", "Pa"),
    "p_max_outer": ("p_max_outer", "Pa"),
    "ring_displacement": ("displacement", "x, y, axial in m; tilt_x, tilt_y in rad"),
    "stiffness": ("stiffness", STIFFNESS_UNITS),
    "iterations": ("iterations", "1"),
    "residual_norm": ("residual_norm", "N (moments divided by R_i)"),
    "result": ("result", "1 (0 = converged; see bearingsim.RESULT_MESSAGES)"),
}


def state_datasets(sol):
    """Datasets of a batch of quasi-static states (sweep: leading (N,), study: (M, N)).

    States that did not converge are flagged in ``converged`` and their values set to 0 (never
    NaN in a results file)."""
    ok = np.asarray(sol.result) == 0
    out = {"converged": (ok, "bool (True where the solve converged)")}
    for name, (field, units) in _STATE_FIELDS.items():
        a = np.asarray(getattr(sol, field))
        if a.dtype.kind == "f":
            mask = ok.reshape(ok.shape + (1,) * (a.ndim - ok.ndim))
            a = np.where(mask & np.isfinite(a), a, 0.0) if not np.all(ok) else a
        out[name] = (a, units)
    return out
