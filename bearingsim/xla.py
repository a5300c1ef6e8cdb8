"""How bearingsim's programs are compiled: one set of XLA options for every compiled program.

The package's programs are compile-bound on the CPU (a Jones solve compiles in seconds and runs
in milliseconds), so the options favour compile time where run time does not suffer:

* ``xla_cpu_use_fusion_emitters = False``: XLA's CPU backend emits its fused kernels with the
  older LLVM emitters instead of the MLIR fusion emitters.  Measured on 2026-11-23 (jax 0.10.2,
  2-core VM): the demo's quasi-static solve compiles in 5.5-6.1 s of CPU instead of 7.7-9.5 s
  (355 kernels instead of 390) and runs as fast or faster (1.6-1.9 ms vs 2.2-3.8 ms); the
  dynamics' time step runs at the same speed (1.09-1.38 vs 1.23-1.34 s per simulated second of
  the CWRU case at 48 kHz); ``make test`` took 11 min 48 s instead of 15-17 min.
* ``xla_cpu_parallel_codegen_split_count = 1`` for a program compiled with LLVM at -O0
  (:data:`QUICK_CODEGEN`): the CPU backend emits its LLVM module as one object file instead of
  32 parts compiled on a thread pool.  At -O0 the parts' overhead outweighs the codegen they
  share out: measured on 2026-12-08 (jax 0.10.2, 2-core VM, empty caches, the CWRU solve and a
  0.01 s simulation, every program at -O0): compile events 11.2-12.4 s -> 9.2-10.2 s, the
  process 20.7-21.2 -> 16.6-19.1 s of CPU; the first ``bearingsim static`` call 6.9 -> 5.1 s and
  ``simulate cwru_6205`` 16.1 -> 13.2 s with an empty cache.  At XLA's default level the parallel
  parts pay on two cores (a 16-item data set with an empty cache took 64.8 s with one object
  file, 45.0 s with 32), so the optimised programs keep them; and ``make test`` (every program at
  -O0 through ``XLA_FLAGS``) took 766 s with one file for every program against 729 s without,
  back to back on a fresh clone, though three-file subsets had run 6-31 % faster: the suite
  keeps the parts for all but these programs.  The machine code differs: a CWRU record's samples moved by ~1e-11
  relative with every program at -O0 (a result stays a function of the package version, the
  spec, the options and the device type).

:func:`compiler_options` gives them for ``jax.jit(f, compiler_options=...)``; every program of the
package is compiled with them (:func:`bearingsim.programs.jit`, which also keeps the traced
programs across processes).  A jaxlib that does not know an option gets none (checked once, on a
one-line program).
"""
from __future__ import annotations

import functools

import jax
import jaxlib
import numpy as np

from .runtime import cold, mark_warm

__all__ = ["PREFERRED_OPTIONS", "QUICK_CODEGEN", "QUICK_COMPILE", "compiler_options", "lowering_platform"]

#: XLA compile options for every bearingsim program (see the module docstring for the measurements)
PREFERRED_OPTIONS = {"xla_cpu_use_fusion_emitters": False}
#: the option of a program compiled with LLVM at -O0 (:data:`QUICK_COMPILE`): one object file
#: (see the module docstring)
QUICK_CODEGEN = ("xla_cpu_parallel_codegen_split_count", 1)

#: extra options of a program that runs for milliseconds per call and is compiled on a user's first
#: command (the single Jones state of ``bearingsim static``): LLVM at -O0.  Measured 2026-11-28
#: (2-core CPU, empty caches, ``bearingsim static demo``): the whole first command 4.2-4.95 s at
#: XLA's default level, 3.7-3.8 s with -O0 (the Jones program compiles in ~1.2 s instead of ~2.2
#: s); its solve runs in milliseconds either way.  Batch, sweep and time-loop programs keep the
#: default level (they run long enough for the optimiser to pay).
QUICK_COMPILE = (("xla_backend_optimization_level", 0),)


@functools.cache
def compiler_options(extra: tuple = ()) -> dict:
    """:data:`PREFERRED_OPTIONS` and the ``extra`` (key, value) pairs, with :data:`QUICK_CODEGEN`
    where ``extra`` asks for -O0, if this jaxlib accepts them (checked once per ``extra``), else
    the options it accepts without ``extra``, else ``{}``."""
    opts = dict(PREFERRED_OPTIONS, **dict(extra))
    if opts.get("xla_backend_optimization_level") == 0:
        opts.update([QUICK_CODEGEN])
    # the verdict is kept per jaxlib and cache folder (a marker file): the check is a compiled
    # program, ~50 ms of every process's first command on a 2-core CPU even as a cache hit
    key = f"xla-options|{jaxlib.__version__}|{sorted(opts.items())}"
    if not cold(key):
        return opts
    try:
        jax.jit(lambda x: x + 1.0).lower(np.zeros(1)).compile(compiler_options=opts)
    except Exception:       # an unknown option in another jaxlib: compile with its defaults
        return compiler_options() if extra else {}
    mark_warm(key)
    return opts


def lowering_platform(dev) -> str:
    """The platform name :func:`jax.export.export` lowers for on device ``dev``: a JAX device says
    ``gpu`` where the export needs ``cuda`` or ``rocm`` (seen on an H200, jax 0.11.2)."""
    if dev.platform != "gpu":
        return dev.platform
    return "rocm" if "rocm" in str(getattr(dev.client, "platform_version", "")).lower() else "cuda"
