"""The command line's start-up seam: the modules its commands use, each imported at its first use.

`bearingsim --help` and an argument error load no JAX (tests/test_runtime.py), nor NumPy: each
module below loads NumPy and most of them JAX, matplotlib or Dask, so each is imported by the one
import statement of its loader (visible to tests/test_architecture.py) when a command first uses
it.  These loaders are the command line's only function-local imports of bearingsim modules;
the commands (:mod:`bearingsim.app.commands`) use the module objects.
"""
from __future__ import annotations

__all__ = ["np", "cases", "units", "jones", "lines", "io", "report", "plots", "plots_signal", "dataset_spec", "distributed", "record_spectra", "ident", "workflows", "ident_bank", "ident_report", "rotordynamics", "rotor", "signal_workflows"]


class _Lazy:
    """A module imported at its first use."""

    def __init__(self, load):
        self._load = load

    def __getattr__(self, attr):
        return getattr(self._load(), attr)


def _numpy():
    import numpy as m
    return m


def _case():
    from .. import case as m
    return m


def _units():
    from ..case import units as m
    return m


def _jones():
    from ..physics import jones as m
    return m


def _lines():
    from ..signals import lines as m
    return m


def _io():
    from ..output import io as m
    return m


def _report():
    from ..output import report as m
    return m


def _plots():
    from ..output import plots as m
    return m


def _plots_signal():
    from ..output import plots_signal as m
    return m


def _dataset_spec():
    from ..datasets import spec as m
    return m


def _distributed():
    from ..datasets import distributed as m
    return m


def _record_spectra():
    from ..realism import record_spectrum as m
    return m


def _identify():
    from ..realism import identify as m
    return m


def _identify_bank():
    from ..realism import identify_bank as m
    return m


def _identify_report():
    from ..output import identify_report as m
    return m


def _workflows():
    from . import workflows as m
    return m


def _signal_workflows():
    from . import signal_workflows as m
    return m


def _rotor():
    from . import rotor as m
    return m


def _rotordynamics():
    from . import rotordynamics as m
    return m


np, cases, units, jones, lines = _Lazy(_numpy), _Lazy(_case), _Lazy(_units), _Lazy(_jones), _Lazy(_lines)
io, report, plots, plots_signal = _Lazy(_io), _Lazy(_report), _Lazy(_plots), _Lazy(_plots_signal)
dataset_spec, distributed = _Lazy(_dataset_spec), _Lazy(_distributed)
record_spectra, ident, workflows = _Lazy(_record_spectra), _Lazy(_identify), _Lazy(_workflows)
ident_bank, ident_report = _Lazy(_identify_bank), _Lazy(_identify_report)
rotordynamics, rotor = _Lazy(_rotordynamics), _Lazy(_rotor)
signal_workflows = _Lazy(_signal_workflows)
