"""Command line: ``bearingsim info|static|sweep|study|simulate|spectrum|compare|dataset|calibrate|identify|rotor|cache|demo``.

Argument parsing, exit codes and interrupts only: each sub-command is a function of
:mod:`bearingsim.app.commands` (which calls :mod:`bearingsim.app.workflows`; files are written by
:mod:`bearingsim.output.io`, figures drawn by :mod:`bearingsim.output.plots`).  Exit codes
are the ``exit_code`` of the :mod:`bearingsim.errors` classes: 0 success, 2 bad input, 3 a solve
did not converge, 4 an output could not be written, 5 the Dask cluster cannot be reached, 130
interrupted (Ctrl-C / SIGTERM: one line, nothing half-written).
"""
from __future__ import annotations

import _thread
import atexit
import argparse
import os
import shutil
import signal
import sys
import threading
import warnings
from pathlib import Path

from . import commands
from ..datasets import budget
from ..names import LOCATIONS
from ..errors import BearingsimError, OutputError


# ------------------------------------------------------------------------------- parser
_CASE = ("case", "CASE", "case file, or the name of a shipped case (e.g. demo, cwru_6205)")


def _command(sub, name, func, help, positional=_CASE, output=False, plot=None):
    s = sub.add_parser(name, help=help)
    if positional:
        s.add_argument(positional[0], metavar=positional[1], help=positional[2])
    if output:
        s.add_argument("-o", "--output", required=True, metavar="OUT.h5")
    if plot:
        s.add_argument("--plot", metavar=plot[0], help=plot[1])
    s.set_defaults(func=func)
    return s


def _chunk_arg(v):
    if v == "auto":
        return 0
    try:
        n = int(v)
    except ValueError:
        n = -1
    if n < 0:
        raise argparse.ArgumentTypeError(f"--chunk must be a whole number >= 0 or auto, got {v!r}")
    return n


def _cluster_flags(s, what):
    where = s.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N", help=f"run {what} on a local Dask cluster "
                       "of N worker processes (pip install 'bearingsim[distributed]'); same file")
    where.add_argument("--scheduler", metavar="ADDRESS|FILE", help=f"run {what} on an existing Dask "
                       "cluster: scheduler address (tcp://HOST:8786) or scheduler file; same file")


def _cache_parser(sub):
    s = sub.add_parser("cache", help="where the compiled and traced programs (~/.cache/bearingsim/jax, "
                       "BEARINGSIM_CACHE_DIR), the identify banks and cached data sets (~/.cache/bearingsim, BEARINGSIM_CACHE) "
                       "are kept, and --clear")
    s.add_argument("--clear", action="store_true", help="delete the cached programs, identify banks and cached data sets")
    s.set_defaults(func=commands.cmd_cache)
    return s


def _spectrum_parser(sub):
    s = sub.add_parser("spectrum", help="squared-envelope spectrum of a real record (.npz, .npy, .csv, .txt, .wav) "
                       "with the bearing's fault lines (BPFO, BPFI and its shaft sidebands, 2 BSF, FTF), "
                       "or of a `bearingsim simulate` output (.h5)")
    s.add_argument("input", metavar="RECORD", help="a record file (.npz: CWRU layout with fs, rpm, units; "
                   ".npy, .csv/.txt one column, .wav) or a `bearingsim simulate` output (.h5)")
    s.add_argument("-o", "--plot", metavar="PNG", help="write the spectra plot")
    s.add_argument("--case", metavar="CASE", help="the record's bearing: case file or shipped name "
                   "(default cwru_6205)")
    s.add_argument("--rpm", type=float, metavar="N", help="the shaft speed (default: found from the spectrum "
                   "near the file's rpm or the case's speed)")
    s.add_argument("--channel", help="the .npz key (default DE or the only array) or the .wav channel number")
    s.add_argument("--sample-rate-Hz", type=float, metavar="FS", help="sample rate when the file does not say "
                   "(a file's own rate wins: a different one is refused)")
    s.add_argument("--unit", choices=("g", "m/s^2"), help="unit of the samples when the file does not say "
                   "(default m/s^2)")
    s.add_argument("--overlay", metavar="SIM.h5", help="overlay a simulation's envelope spectrum: a "
                   "`bearingsim simulate` output or a `bearingsim dataset` file (item --item)")
    s.add_argument("--item", type=int, default=0, metavar="K", help="the data set item to overlay (default 0)")
    s.set_defaults(func=commands.cmd_spectrum)
    return s


def build_parser():
    p = argparse.ArgumentParser(prog="bearingsim", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    plots_into = ("DIR", "write plots into DIR")
    _command(sub, "info", commands.cmd_info, "geometry, Hertz constants, kinematics and defect frequencies of a case")
    s = _command(sub, "static", commands.cmd_static, "quasi-static Jones solution: per-ball table, displacement, stiffness",
                 plot=("OUT.png", "polar load distribution and contact angles"))
    s.add_argument("--json", metavar="OUT.json", help="write the solution as JSON")
    _command(sub, "sweep", commands.cmd_sweep, "quasi-static states over cage angles as the balls pass the spall",
             output=True, plot=plots_into)
    s = _command(sub, "study", commands.cmd_study, "a cage-angle sweep for each value of one case key ([study])",
                 output=True, plot=plots_into)
    _cluster_flags(s, "the sweeps of a geometry, material or defect study")
    _command(sub, "simulate", commands.cmd_simulate, "dynamic simulation (shaft, housing, sensor resonator) "
             "with the Jones bearing forces; HDF5 output", output=True, plot=plots_into)
    _spectrum_parser(sub)
    s = _command(sub, "dataset", commands.cmd_dataset, "labelled data set of simulated sensor signals ([dataset] "
             "ranges of speed, loads and spall); HDF5 output",
             positional=("spec", "SPEC.toml", "case file with a [dataset] section, or a shipped case name"),
             output=True)
    _cluster_flags(s, "the chunks")
    s.add_argument("--count", type=int, metavar="N", help="items (overrides dataset.count)")
    s.add_argument("--seed", type=int, metavar="S", help="random seed (overrides dataset.seed)")
    s.add_argument("--duration-s", type=float, metavar="D", help="seconds per item (overrides dataset.duration_s)")
    s.add_argument("--sample-rate-Hz", type=float, metavar="FS", dest="sample_rate_Hz",
                   help="sample rate of the items in Hz, e.g. 12000 for the CWRU 12 kHz records (overrides "
                        "dynamics.sample_rate_Hz)")
    s.add_argument("--device", choices=("cpu", "gpu"), help="run the chunks on this JAX device (default: "
                   "JAX's choice, the GPU where JAX sees one; the run says which)")
    s.add_argument("--chunk", type=_chunk_arg, metavar="N|auto", help="items per chunk (default: the "
                   "spec's [dataset] chunk; auto or 0: what fills the device: 16 per CPU core, or as many "
                   "as fit in a quarter of the GPU's memory); the file does not depend on it")
    s.add_argument("--compression", choices=("none", "lzf", "gzip", "gzip1", "zstd"), default=None,
                   help="codec of /signals: none (default: fastest; float32 noise hardly compresses), "
                   "gzip (archive any reader opens: 7%% smaller, 20x slower to write), zstd (archive: "
                   "14%% smaller; needs pip install 'bearingsim[compress]'), lzf, gzip1")
    s = _command(sub, "calibrate", commands.cmd_calibrate, "fit a data set spec to your machine: background, "
                 "resonances and levels from a healthy record (and at most one fault record)",
                 positional=("healthy", "HEALTHY", "healthy record: .npz (channel, fs, rpm, units), .npy, "
                             ".csv or .txt (one column); of a long record the first 2^22 samples are analysed "
                             "(349.5 s at 12 kHz: bounded memory), as the output says"))
    s.add_argument("-o", "--output", required=True, metavar="SPEC.toml")
    s.add_argument("--template", default="dataset_cwru_4class", metavar="CASE",
                   help="data set spec with the bearing geometry and [dataset] (default dataset_cwru_4class)")
    s.add_argument("--fault", metavar="RECORD", help="one record of a known fault (same sample rate)")
    s.add_argument("--fault-class", choices=LOCATIONS, help="the fault record's class")
    s.add_argument("--channel", help="the .npz key of the signal (default DE, or the file's only array)")
    s.add_argument("--sample-rate-Hz", type=float, metavar="FS", help="sample rate when the file does not say")
    s.add_argument("--rpm", type=float, metavar="N", help="the healthy record's shaft speed (default: "
                   "from the spectrum, near the .npz rpm or the template's speed)")
    s.add_argument("--unit", choices=("g", "m/s^2"), help="unit of the samples when the file does not say")
    s.add_argument("--count", type=int, metavar="N", help="items of the data set (default: the template's)")
    s.add_argument("--duration-s", type=float, metavar="S", help="seconds per item (default: the template's)")
    s = _command(sub, "identify", commands.cmd_identify, "identify a fault from a measured record: class and "
                 "location with a calibrated probability (or 'uncertain' below 0.8), defect length (or 'size "
                 "not resolved'), contact angle and shaft speed with intervals; the classes weak on real "
                 "records named",
                 positional=("record", "RECORD", "record: .npz (channel, fs, rpm), .npy, .csv or .txt (one column)"),
                 plot=("OUT.png", "the record against a simulated twin at the estimate"))
    s.add_argument("--case", default=None, metavar="CASE", help="the bearing's case (its geometry; the "
                   "operating point is estimated; default dataset_cwru_4class, the CWRU drive-end 6205, as "
                   "spectrum's default)")
    s.add_argument("--rpm", type=float, metavar="N", help="nominal shaft speed (searched +-10 %%; default "
                   "the .npz rpm or the case's speed)")
    s.add_argument("--channel", help="the .npz key of the signal (default DE, or the file's only array)")
    s.add_argument("--sample-rate-Hz", type=float, metavar="FS", help="sample rate when the file does not say")
    s.add_argument("--json", metavar="OUT.json", help="write the identification as JSON")
    _command(sub, "compare", commands.cmd_compare, "quasi-static vs dynamic: the ball loads of the quasi-static "
             "sweep (Jones model, no inertia) against the dynamic simulation's as the balls pass the spall, "
             "and the dynamic amplification",
             plot=("DIR", "write compare.png into DIR"))
    s = _command(sub, "rotor", commands.cmd_rotor, "a small steel rotor (ROSS) on the case's bearing or set at both "
                 "ends: Campbell diagram and critical speeds (pip install 'bearingsim[ross]')")
    s.add_argument("--out", default="results/rotor", metavar="DIR", help="write campbell.png and "
                   "critical_speeds.json into DIR (default results/rotor)")
    s.add_argument("--speeds-rpm", metavar="START:STOP:COUNT", help="rotor speeds in rpm (default "
                   "0:1.5 x the case's speed:16)")
    _cache_parser(sub)
    s = _command(sub, "demo", commands.cmd_demo, "run the default case end to end and write all results and plots",
                 positional=None)
    s.add_argument("--case", default=None, help="case file or shipped case name (default: demo)")
    s.add_argument("--out", default="results/demo", help="output folder (default results/demo)")
    return p


#: the signal that stopped the run (set by the handler, so that an interrupt that a library
#: wrapped in its own exception while it ran, e.g. JAX while tracing, is still told as one line)
_stopped_by = []


#: seconds the run has, after a Ctrl-C / SIGTERM, to unwind (and clean up) on its own
HARD_STOP_S = 10.0
_watchdog = []
#: outputs of the running command (their temporary files are removed by a hard stop)
_outputs = []


def _hard_stop():
    """The interrupt was swallowed (raised inside a callback that ignores exceptions, e.g. a
    garbage-collector hook) or the run is stuck in a library: remove this command's temporary
    files, say so in one line, exit 130 now."""
    for out in _outputs:
        p = Path(out)
        for tmp in p.parent.glob(f".{p.name}.*.tmp"):
            tmp.unlink(missing_ok=True)
        part = p.with_name(p.name + ".partial")
        if part.is_dir():
            for tmp in part.glob(".*.tmp"):
                tmp.unlink(missing_ok=True)
            if not any(part.glob("chunk_*.npz")):
                shutil.rmtree(part, ignore_errors=True)
    os.write(2, f"bearingsim: {_stopped_by[0]}: interrupted; no output is half-written\n".encode())
    os._exit(130)


def _importing(frame):
    """Whether the interrupted code is inside an import: a KeyboardInterrupt raised there can
    escape a native extension's initialisation (jaxlib's: ``std::terminate``, exit -6 / -11)."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def _stop(signum, frame):
    _stopped_by.append(signal.Signals(signum).name)
    if _importing(frame):       # while a library loads: clean up and exit now, raise nothing
        _hard_stop()
    if not _watchdog:
        t = threading.Timer(HARD_STOP_S, _hard_stop)
        t.daemon = True
        t.start()
        _watchdog.append(t)
    raise KeyboardInterrupt(_stopped_by[0])


def _unraisable(u, default=sys.unraisablehook):
    """An interrupt raised inside a callback that ignores exceptions (e.g. JAX's garbage-collector
    hook) is raised again in the main thread at the next bytecode, not printed as ignored."""
    if _stopped_by and isinstance(u.exc_value, KeyboardInterrupt):
        t = threading.Timer(0.05, _thread.interrupt_main, (signal.SIGINT,))   # not from inside the hook
        t.daemon = True
        t.start()
        return
    default(u)


def _stop_handlers():
    """SIGINT and SIGTERM raise KeyboardInterrupt (finally blocks remove temporary files);
    returns the handlers to restore (none outside the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    return {sg: signal.signal(sg, _stop) for sg in (signal.SIGINT, signal.SIGTERM)}


def _format_warning(message, category, filename, lineno, line=None):
    """A warning as one line a person reads (no package path, no source line): bearingsim's own
    (:class:`bearingsim.OverloadWarning`, ...) as ``bearingsim: warning: MESSAGE``, another
    package's with its category.  (``warnings.formatwarning``: a caller recording warnings,
    e.g. ``pytest.warns``, still records them.)"""
    own = category.__module__.split(".")[0] == "bearingsim"
    text = " ".join(str(message).split())
    return (f"bearingsim: warning: {text}" if own else f"bearingsim: warning ({category.__name__}): {text}") + "\n"


def main(argv=None):
    """Run ``bearingsim ARGS``; returns the exit code (Ctrl-C / SIGTERM at any moment: one
    line, 130, nothing half-written: every file is written atomically).  Warnings are one line
    each (:func:`_format_warning`)."""
    _stopped_by.clear()
    _outputs.clear()
    old = _stop_handlers()
    old_hook, sys.unraisablehook = sys.unraisablehook, _unraisable
    old_format, warnings.formatwarning = warnings.formatwarning, _format_warning
    try:
        args = build_parser().parse_args(argv)
        if "matplotlib" in sys.modules:     # files only, no display needed
            sys.modules["matplotlib"].use("Agg")
        else:                               # not imported before a command plots (0.27 s saved)
            os.environ["MPLBACKEND"] = "Agg"
        for flag in ("output", "json"):
            budget.check_output(getattr(args, flag, None), "-o" if flag == "output" else "--json")
            if getattr(args, flag, None):
                _outputs.append(getattr(args, flag))
        return args.func(args)
    except BaseException as e:       # the one place where errors become exit codes
        if isinstance(e, SystemExit):
            raise
        if _stopped_by or isinstance(e, KeyboardInterrupt) or getattr(e, "exit_code", None) == 130:
            if isinstance(e, BearingsimError) and e.exit_code == 130:    # says what was kept
                print(f"bearingsim: {e}", file=sys.stderr)
            else:
                how = _stopped_by[0] if _stopped_by else "SIGINT"
                print(f"bearingsim: {how}: interrupted; no output is half-written", file=sys.stderr)
            return 130
        if isinstance(e, BearingsimError):
            print(f"bearingsim: error: {e}", file=sys.stderr)
            return e.exit_code
        if isinstance(e, OSError):   # a file the system refused outside bearingsim.io (plots)
            print(f"bearingsim: error: cannot write output: {e}", file=sys.stderr)
            return OutputError.exit_code
        raise
    finally:
        for sg, h in old.items():
            signal.signal(sg, h)
        sys.unraisablehook = old_hook
        warnings.formatwarning = old_format
        while _watchdog:
            _watchdog.pop().cancel()


def run():
    """The ``bearingsim`` console command: :func:`main`, and after an interrupt an immediate
    exit (compilations still running in background threads are not waited for).  A finished
    command whose other threads are all daemons (nothing left to wait for) runs the exit
    handlers, flushes and leaves without the interpreter's teardown of JAX's modules and
    compiled programs (~0.3 s of every command on a 2-core CPU, 2026-12-08: ``bearingsim static
    demo``, warm, 1.6-1.9 s -> 1.3-1.5 s); every file is closed by then (written atomically)."""
    leave(main())


def leave(code):
    """Exit the ``bearingsim`` process with ``code`` (:func:`main`'s) as :func:`run` does."""
    if code == 130:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    code = 0 if code is None else code
    if isinstance(code, int) and all(t.daemon for t in threading.enumerate() if t is not threading.main_thread()):
        atexit._run_exitfuncs()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    run()
