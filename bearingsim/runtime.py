"""How bearingsim's processes start: float64 JAX and a persistent compilation cache, by default.

Every entry point (``import bearingsim``, the ``bearingsim`` command, Dask workers, notebooks)
runs :func:`configure` once, before JAX is imported where it can, so that

* JAX computes in float64 (``jax_enable_x64``);
* the eager operations outside the package's programs compile with the package's XLA option
  (:data:`EAGER_XLA_FLAG`, added to ``XLA_FLAGS`` unless it names the option);
* compiled programs are kept on disk and reused by the next process: a per-user folder,
  ``$XDG_CACHE_HOME/bearingsim/jax`` (``~/.cache/bearingsim/jax`` when ``XDG_CACHE_HOME`` is not
  set).  JAX writes its cache entries atomically, so concurrent processes (test workers, Dask
  workers, two shells) share one folder safely.

The folder, in order of precedence (:func:`cache_dir`):

1. ``JAX_COMPILATION_CACHE_DIR`` (JAX's own variable; the Makefile sets ``.jax_cache``) if set;
2. ``BEARINGSIM_CACHE_DIR``: a folder, or ``off`` (also ``0``, ``none``, ``false``, empty) to
   compile in memory only;
3. ``$XDG_CACHE_HOME/bearingsim/jax``, else ``~/.cache/bearingsim/jax``.

The traced programs themselves are kept beside them, in ``<folder>/bearingsim-programs``
(:mod:`bearingsim.programs`: a warm process loads a program instead of tracing it).

Programs that compile in less than ``JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS`` (bearingsim's
default 0: every program; JAX's own default is 1 s) are not kept.  Clearing the cache is deleting
the folder (``bearingsim cache --clear``); it is rebuilt by the next run.

:func:`cold` / :func:`mark_warm` tell a command whether its programs were compiled before in this
cache (a marker file per program family), so that it can say "compiling, first run only".

This module imports nothing heavy (no JAX): ``bearingsim --help`` stays fast.
"""
from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

from ._version import __version__

__all__ = ["OFF_VALUES", "PROGRAMS_FOLDER", "cache_dir", "configure", "configured_cache_dir", "cold", "mark_warm", "cache_size",
           "clear_cache"]

#: the subfolder of the cache folder that holds the traced programs (:mod:`bearingsim.programs`)
PROGRAMS_FOLDER = "bearingsim-programs"
#: values of ``BEARINGSIM_CACHE_DIR`` that switch the persistent cache off
OFF_VALUES = ("", "0", "off", "none", "false", "no")
#: minimum compile time of a kept program, unless JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS says
MIN_COMPILE_TIME_S = 0.0

#: the XLA option of the package's programs (:data:`bearingsim.xla.PREFERRED_OPTIONS`) for every
#: other program of the process too: the eager ``jax.numpy`` operations outside a program, each
#: compiled on its own, compile in 15-16 ms instead of 29-31 ms with the CPU backend's older
#: LLVM emitters (a new shape of ``a * 2.0``, 2-core Xeon, LLVM -O0, 2026-12-07).  Set before JAX
#: starts, unless ``XLA_FLAGS`` already names the option.
EAGER_XLA_FLAG = "--xla_cpu_use_fusion_emitters=false"
#: the jaxlib from which :data:`EAGER_XLA_FLAG` is set: an XLA flag a jaxlib does not know aborts
#: the process, and the CPU fusion emitters are an XLA of 2025 (used with jaxlib 0.10.2 on CPUs and
#: 0.11.2 on an H200); an older jaxlib gets no flag (its programs are checked by bearingsim.xla)
EAGER_XLA_FLAG_SINCE = (0, 7)


def _jaxlib_at_least(version) -> bool:
    """Whether the installed jaxlib (read from its metadata: JAX is not imported) is >= ``version``."""
    from importlib.metadata import PackageNotFoundError, version as installed      # local: start-up only

    try:
        parts = installed("jaxlib").split(".")[:2]
        return tuple(int("".join(c for c in p if c.isdigit()) or 0) for p in parts) >= tuple(version)
    except (PackageNotFoundError, ValueError):
        return False

_state: dict = {}


def cache_dir(environ=None) -> Path | None:
    """The compilation cache folder this process uses (None: off); see the module docstring."""
    env = os.environ if environ is None else environ
    jax_dir = env.get("JAX_COMPILATION_CACHE_DIR")
    if jax_dir:
        return Path(jax_dir).expanduser()
    if "BEARINGSIM_CACHE_DIR" in env:
        v = env["BEARINGSIM_CACHE_DIR"].strip()
        return None if v.lower() in OFF_VALUES else Path(v).expanduser()
    xdg = env.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path(env.get("HOME") or Path.home()).expanduser() / ".cache"
    return base / "bearingsim" / "jax"


def configure() -> Path | None:
    """Float64 and the persistent cache for this process (idempotent); returns the cache folder
    (None: off).  Before JAX is imported it sets JAX's variables (inherited by subprocesses);
    after, it updates JAX's config, keeping a cache folder the user already configured."""
    if "dir" in _state:
        return _state["dir"]
    d = cache_dir()
    if d is not None:
        try:
            d.mkdir(parents=True, exist_ok=True)
        except OSError as e:             # read-only home: compile in memory, say why once
            print(f"bearingsim: warning: compilation cache {d} cannot be created ({e}); compiling "
                  "in memory (set BEARINGSIM_CACHE_DIR to a writable folder)", file=sys.stderr)
            d = None
    min_s = os.environ.get("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", str(MIN_COMPILE_TIME_S))
    if "jax" not in sys.modules:
        os.environ["JAX_ENABLE_X64"] = "True"
        os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"] = min_s
        flags = os.environ.get("XLA_FLAGS", "")
        if EAGER_XLA_FLAG.split("=")[0] not in flags and _jaxlib_at_least(EAGER_XLA_FLAG_SINCE):
            os.environ["XLA_FLAGS"] = f"{flags} {EAGER_XLA_FLAG}".strip()
        if d is not None:
            os.environ["JAX_COMPILATION_CACHE_DIR"] = str(d)
    else:
        import jax

        jax.config.update("jax_enable_x64", True)
        if d is not None and not jax.config.jax_compilation_cache_dir:
            jax.config.update("jax_compilation_cache_dir", str(d))
            jax.config.update("jax_persistent_cache_min_compile_time_secs", float(min_s))
        elif jax.config.jax_compilation_cache_dir:
            d = Path(jax.config.jax_compilation_cache_dir)
    _state["dir"] = d
    return d


def configured_cache_dir() -> Path | None:
    """The folder :func:`configure` chose (configuring first if needed)."""
    return configure()


def _marker(key: str) -> Path | None:
    d = configured_cache_dir()
    if d is None:
        return None
    h = hashlib.sha1(f"{__version__}|{sys.version_info[:2]}|{key}".encode()).hexdigest()[:16]
    return d / "bearingsim-warm" / h


def cold(key: str) -> bool:
    """True when the programs of ``key`` (a command and what shapes its programs) have not been
    compiled into this cache yet (always True with the cache off: every run compiles)."""
    m = _marker(key)
    return m is None or not m.exists()


def mark_warm(key: str) -> None:
    """Record that the programs of ``key`` are now in the cache (best effort)."""
    m = _marker(key)
    if m is None:
        return
    try:
        m.parent.mkdir(parents=True, exist_ok=True)
        m.touch()
    except OSError:
        pass


def cache_size(d: Path | None = None) -> tuple[int, int]:
    """(files, bytes) in the cache folder."""
    d = configured_cache_dir() if d is None else d
    if d is None or not d.is_dir():
        return 0, 0
    n = b = 0
    for p in d.rglob("*"):
        if p.is_file():
            n += 1
            b += p.stat().st_size
    return n, b


def clear_cache(d: Path | None = None) -> int:
    """Delete the cache's files (the folder stays); returns how many were deleted."""
    d = configured_cache_dir() if d is None else d
    if d is None or not d.is_dir():
        return 0
    n = 0
    for p in sorted(d.rglob("*"), reverse=True):
        try:
            if p.is_file() or p.is_symlink():
                p.unlink()
                n += 1
            elif p.is_dir():
                p.rmdir()
        except OSError:
            pass
    return n
