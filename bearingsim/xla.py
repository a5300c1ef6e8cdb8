"""How bearingsim's programs are compiled: one set of XLA options for every compiled program.

The package's programs are compile-bound on the CPU (a Jones solve compiles in seconds and runs
in milliseconds), so the options favour compile time where run time does not suffer:

* ``xla_cpu_use_fusion_emitters = False``: XLA's CPU backend emits its fused kernels with the
  older LLVM emitters instead of the MLIR fusion emitters.  Measured on 2026-11-23 (jax 0.10.2,
  2-core VM): the demo's quasi-static solve compiles in 5.5-6.1 s of CPU instead of 7.7-9.5 s
  (355 kernels instead of 390) and runs as fast or faster (1.6-1.9 ms vs 2.2-3.8 ms); the
  dynamics' time step runs at the same speed (1.09-1.38 vs 1.23-1.34 s per simulated second of
  the CWRU case at 48 kHz); ``make test`` took 11 min 48 s instead of 15-17 min.

:func:`jit` is :func:`equinox.filter_jit` with these options (arrays are traced, everything else
is static); :func:`compiler_options` gives them for ``jax.jit(f, compiler_options=...)``.  A
jaxlib that does not know an option gets none (checked once, on a one-line program).
"""
from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp

__all__ = ["PREFERRED_OPTIONS", "compiler_options", "jit"]

#: XLA compile options for every bearingsim program (see the module docstring for the measurements)
PREFERRED_OPTIONS = {"xla_cpu_use_fusion_emitters": False}


@functools.cache
def compiler_options() -> dict:
    """:data:`PREFERRED_OPTIONS` if this jaxlib accepts them (checked once), else ``{}``."""
    try:
        jax.jit(lambda x: x + 1.0).lower(jnp.zeros(1)).compile(compiler_options=dict(PREFERRED_OPTIONS))
    except Exception:       # an unknown option in another jaxlib: compile with its defaults
        return {}
    return dict(PREFERRED_OPTIONS)


class _Jit:
    """:func:`equinox.filter_jit` with :func:`compiler_options`, built at the first call (the
    check compiles a program: never at import).  Called inside another jit's trace (where JAX
    accepts compile options only at the top level) it is a plain nested ``filter_jit``: the
    outer program's options apply."""

    def __init__(self, fun, kw):
        self._fun, self._kw, self._top, self._nested = fun, kw, None, None
        functools.update_wrapper(self, fun)

    def _get(self):
        if self._top is None:
            self._top = eqx.filter_jit(self._fun, compiler_options=compiler_options(), **self._kw)
        return self._top

    def __call__(self, *args, **kwargs):
        if not compiler_options():
            return self._get()(*args, **kwargs)
        try:
            return self._get()(*args, **kwargs)
        except ValueError as e:
            if "compiler_options" not in str(e) or "top-level" not in str(e):
                raise
        if self._nested is None:
            self._nested = eqx.filter_jit(self._fun, **self._kw)
        return self._nested(*args, **kwargs)

    def lower(self, *args, **kwargs):
        return self._get().lower(*args, **kwargs)


def jit(fun=None, **kw):
    """:func:`equinox.filter_jit` (``kw`` passed on) compiling with :func:`compiler_options`;
    usable as ``jit(f)`` or as a decorator."""
    if fun is None:
        return lambda f: _Jit(f, kw)
    return _Jit(fun, kw)
