"""bearingsim: angular contact ball bearings with localized defects.

The folders show the flow (docs/architecture.md): ``physics`` (geometry -> hertz -> jones
(+defect; shaft for sets) -> sweep, life, limits) -> ``dynamics`` -> ``signals`` (the sensor, the
signal stage, envelope analysis) form the core, pure JAX in float64, knowing nothing of files or
printing; ``case`` (case files), ``output`` (results files, reports, figures), ``datasets`` (data
sets, their reader, scale-out), ``realism`` (real records: calibration, transfer, identification)
and ``app`` (workflows, sets, the command line) are the edge.  The flat paths before the folders
(``bearingsim.jones``) are gone (issue 35; they warned since the folders came): import from the folders.

The nouns a user types are here, imported at first use: ``bearingsim.solve``, ``solve_set``,
``sweep``, ``simulate``, ``load_case``, ``solve_case``, ``make_dataset``, ``load_dataset``,
``identify``, ... (``dir(bearingsim)`` lists them).
"""
import os as _os
import sys as _sys

if _os.path.basename(_sys.argv[0] if _sys.argv else "") == "bearingsim" and "__mp_main__" not in _sys.modules:
    # the `bearingsim` command (not its Dask worker processes): Ctrl-C / SIGTERM while the
    # libraries load (nothing is written yet) is one line and exit 130; bearingsim.app.cli.main
    # installs its own handlers once they are loaded
    import signal as _signal

    def _stopped_while_loading(signum, frame):
        _os.write(2, f"bearingsim: {_signal.Signals(signum).name}: interrupted while starting; "
                     "nothing written\n".encode())
        _os._exit(130)

    for _sg in (_signal.SIGINT, _signal.SIGTERM):
        _signal.signal(_sg, _stopped_while_loading)

from . import runtime as _runtime  # noqa: E402

_runtime.configure()        # float64 and the persistent compilation cache, before JAX loads

from ._version import __version__  # noqa: E402
from .names import lazy_exports as _lazy_exports  # noqa: E402

#: the names a user types, and the module each comes from: imported at first use (PEP 562), so
#: that ``import bearingsim`` and ``bearingsim --help`` do not load JAX.  The edge's nouns
#: (``load_case``, ``make_dataset``, ``load_dataset``, ``identify``) are named here too: a string
#: is no import, so ``import bearingsim`` still loads no edge module.
_EXPORTS = {
    "physics.geometry": ("Bearing", "Material", "STEEL", "SILICON_NITRIDE"),
    "physics.hertz": ("ellipk_ellipe", "ellipticity", "contact_constant", "hertz_contact", "HertzContact",
              "dimensionless_hertz"),
    "physics.kinematics": ("Operation", "ball_kinematics", "defect_frequencies", "DefectFrequencies"),
    "physics.defect": ("Spall", "NO_SPALL", "depth_profile", "contact_depths"),
    "errors": ("BearingsimError", "InputError", "InputTypeError", "NotConvergedError", "InvalidStateError", "OutputError"),
    "physics.balls": ("BallState", "balls_at", "reactions_from_balls"),
    "physics.jones": ("JonesSolution", "RESULTS", "OverloadWarning", "solve", "solve_state", "solve_batch",
              "ring_reactions", "load_vector", "Loads"),
    "physics.shaft": ("BearingSet", "SetSolution", "solve_set", "solve_set_batch"),
    "physics.sweep": ("sweep", "sweep_chunked"),
    "physics.life": ("rating_life",),
    "physics.limits": ("contact_limits",),
    "dynamics": ("simulate", "DynamicsParameters", "DynamicsResult"),
    "case": ("load_case", "Case"),
    "app.workflows": ("solve_case", "sweep_case", "study_case"),
    "app.signal_workflows": ("simulate_case",),
    "datasets.runner": ("make_dataset",),
    "datasets.mldata": ("load_dataset", "WindowDataset"),
    "realism.identify": ("identify",),
}


__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)


__all__ = [
    "__version__",
    "Bearing",
    "Material",
    "STEEL",
    "SILICON_NITRIDE",
    "ellipk_ellipe",
    "ellipticity",
    "contact_constant",
    "hertz_contact",
    "HertzContact",
    "dimensionless_hertz",
    "Operation",
    "ball_kinematics",
    "defect_frequencies",
    "DefectFrequencies",
    "Spall",
    "NO_SPALL",
    "depth_profile",
    "contact_depths",
    "BearingsimError",
    "InputError",
    "InputTypeError",
    "NotConvergedError",
    "InvalidStateError",
    "OutputError",
    "BallState",
    "balls_at",
    "reactions_from_balls",
    "JonesSolution",
    "RESULTS",
    "OverloadWarning",
    "solve_state",
    "load_vector",
    "solve",
    "solve_batch",
    "ring_reactions",
    "Loads",
    "BearingSet",
    "SetSolution",
    "solve_set",
    "solve_set_batch",
    "sweep",
    "sweep_chunked",
    "rating_life",
    "contact_limits",
    "simulate",
    "DynamicsParameters",
    "DynamicsResult",
    "load_case",
    "Case",
    "solve_case",
    "sweep_case",
    "study_case",
    "simulate_case",
    "make_dataset",
    "load_dataset",
    "WindowDataset",
    "identify",
]
