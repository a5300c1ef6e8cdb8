"""One vocabulary for what can go wrong: result codes and exceptions.

* Result codes are integer enumerations (:class:`ResultCode` subclasses, one per layer) whose
  members carry a ``message`` and a ``hint``.  They are plain ``int`` values, so they travel
  through ``jit`` / ``vmap`` as int32 arrays and compare with ``==`` against the members.
* Exceptions derive from :class:`BearingsimError`; there is one subclass per kind of failure,
  and each kind has the exit code the command line uses for it:

  ====================== ==== ==================================================
  kind                   exit meaning
  ====================== ==== ==================================================
  :class:`InputError`       2 a case file, key, value or argument is wrong
                              (:class:`InputTypeError`: of the wrong type)
  :class:`NotConvergedError` 3 a solve did not converge
  :class:`InvalidStateError` 3 a solve ended on a state that is not physical
  :class:`OutputError`      4 a result could not be written (or was not finite)
  :class:`ClusterError`     5 the Dask cluster of a distributed run cannot be reached
  (interrupted)           130 Ctrl-C / SIGTERM: one line, nothing half-written
  ====================== ==== ==================================================

Every entry point that can fail has ``throw=True`` by default (raise the exception) and
``throw=False`` (return the result with its code; batches are flagged per item).
"""
from __future__ import annotations

import enum
import sys

__all__ = [
    "ResultCode",
    "SUCCESSFUL",
    "succeeded",
    "failed",
    "BearingsimError",
    "InputError",
    "InputTypeError",
    "NotConvergedError",
    "InvalidStateError",
    "OutputError",
    "ClusterError",
    "SettingWarning",
]


class ResultCode(enum.IntEnum):
    """Base of the result-code enumerations: ``Member(value, message, hint)``."""

    def __new__(cls, value, message, hint=""):
        obj = int.__new__(cls, value)
        obj._value_ = value
        obj.message = message
        obj.hint = hint
        return obj

    @classmethod
    def of(cls, code) -> "ResultCode":
        """The member for an integer code (or a 0-d array)."""
        return cls(int(code))

    def describe(self) -> str:
        """``message`` followed by the hint, for people."""
        return f"{self.message}. Hint: {self.hint}" if self.hint else self.message


#: the value of the ``successful`` member of every :class:`ResultCode` enumeration (the solvers',
#: the set's, the dynamics', a data set's ``DatasetResult``; tests/test_verdicts.py checks each)
SUCCESSFUL = 0


def succeeded(result):
    """Where ``result`` (a code, or a NumPy / JAX array of codes of any :class:`ResultCode`
    enumeration) is its enumeration's ``successful`` member: a bool or a boolean array, traceable
    under ``jit``.  The one place a result code is compared; read a failed code's reason with
    ``RESULTS.of(code).message`` / ``.hint``."""
    return _on_host(result) == SUCCESSFUL


def failed(result):
    """Where ``result`` (as :func:`succeeded`) is any other member: the item failed, with a reason."""
    return _on_host(result) != SUCCESSFUL


def _on_host(result):
    """A concrete JAX array as NumPy (an eager JAX comparison is a program of its own:
    :mod:`bearingsim.hostarrays`); anything else, tracers included, as it is.  No JAX import
    here: where JAX is not loaded, ``result`` is no JAX array."""
    jax = sys.modules.get("jax")
    if jax is not None and isinstance(result, jax.Array) and not isinstance(result, jax.core.Tracer):
        return result.__array__()
    return result


class BearingsimError(Exception):
    """Base of every error bearingsim raises on purpose.  ``exit_code``: the CLI's exit status."""

    exit_code = 1

    def __init__(self, message: str, hint: str = "", code: ResultCode | None = None):
        super().__init__(message + (f"\nHint: {hint}" if hint else ""))
        self.message = message
        self.hint = hint
        self.code = code


class InputError(BearingsimError, ValueError):
    """Bad input: a case file, key, value or argument (exit code 2)."""

    exit_code = 2


class InputTypeError(InputError, TypeError):
    """A wrong type of an input (exit code 2): both a ValueError and a TypeError, so callers
    catching either keep working."""

    exit_code = 2


class NotConvergedError(BearingsimError, RuntimeError):
    """A solve did not converge (exit code 3)."""

    exit_code = 3


class InvalidStateError(NotConvergedError):
    """A solve ended on a state that breaks the model's rules (an inverted contact, equilibrium
    not held, deformations beyond the documented bounds): never reported as converged (exit 3)."""

    exit_code = 3


class OutputError(BearingsimError, OSError):
    """A result could not be written, or holds non-finite values (exit code 4)."""

    exit_code = 4


class ClusterError(BearingsimError, RuntimeError):
    """The Dask cluster of a distributed run could not be reached, or lost the same task's
    worker too often (exit code 5: the input is fine, run again when the cluster is)."""

    exit_code = 5


class SettingWarning(UserWarning):
    """A setting was changed to one the run can use (e.g. a data set's chunk rounded up to whole
    micro-batches); the message says from what to what and why."""
