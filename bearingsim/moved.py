"""The module paths before the package was grouped into folders (issue 27, November 2026), kept
working for a deprecation period: ``import bearingsim.jones`` or ``from bearingsim.signal import
bandpass`` give the module at its new path (the same module object, not a copy) with a
``DeprecationWarning`` naming the new path.  Nothing inside the package uses an old path
(``tests/test_architecture.py`` checks it); the finder is installed by ``import bearingsim``.
Imports nothing from the package and no JAX."""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

__all__ = ["MOVED", "new_path", "install"]

#: old path (under ``bearingsim.``) -> new path, in the order of the flow
MOVED = {
    **{m: f"physics.{m}" for m in ("geometry", "hertz", "kinematics", "defect", "balls", "newton", "jones",
                                   "shaft", "sweep", "life", "limits", "pit")},
    **{m: f"signals.{m}" for m in ("sensor", "passes", "background", "signal_stage", "nuisance", "features")},
    "signal": "signals.envelope",
    "dataset": "datasets",
    **{f"dataset.{m}": f"datasets.{m}" for m in ("spec", "program", "writer", "runner")},
    **{m: f"datasets.{m}" for m in ("distributed", "budget", "mldata")},
    **{m: f"realism.{m}" for m in ("calibration", "records", "background_fit", "machine", "transfer",
                                   "fault_size", "identify", "record_spectrum")},
    **{m: f"output.{m}" for m in ("io", "report", "plots", "plots_signal")},
    **{m: f"app.{m}" for m in ("cli", "workflows", "sets")},
}


def new_path(fullname: str) -> str | None:
    """The new dotted path of an old one (``bearingsim.jones`` -> ``bearingsim.physics.jones``),
    or None when ``fullname`` did not move."""
    prefix, _, rest = fullname.partition(".")
    if prefix != "bearingsim" or rest not in MOVED:
        return None
    return f"bearingsim.{MOVED[rest]}"


class _Alias(importlib.abc.Loader):
    def __init__(self, target: str):
        self.target = target

    def create_module(self, spec):
        warnings.warn(f"{spec.name} moved to {self.target}; import it from there "
                      "(the old path goes in a later release)", DeprecationWarning, stacklevel=2)
        module = importlib.import_module(self.target)
        self.own_spec = module.__spec__
        return module

    def exec_module(self, module):
        # the import system gave the module the old path's spec: it keeps its own
        module.__spec__ = self.own_spec


class _MovedFinder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):
        new = new_path(fullname)
        return None if new is None else importlib.util.spec_from_loader(fullname, _Alias(new))


def install() -> None:
    """Put the finder of the old paths first on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, _MovedFinder())
