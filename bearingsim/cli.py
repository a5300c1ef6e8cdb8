"""Command line: ``bearingsim info|static|sweep|study|simulate|spectrum|compare|dataset|calibrate|demo``.

Argument parsing, printing and exit codes only: the work is done by :mod:`bearingsim.workflows`,
files are written by :mod:`bearingsim.io`, figures drawn by :mod:`bearingsim.plots`.  Exit codes
are the ``exit_code`` of the :mod:`bearingsim.errors` classes: 0 success, 2 bad input, 3 a solve
did not converge, 4 an output could not be written, 5 the Dask cluster cannot be reached, 130
interrupted (Ctrl-C / SIGTERM: one line, nothing half-written).
"""
from __future__ import annotations

import _thread
import argparse
import os
import shutil
import signal
import sys
import threading
import time
from pathlib import Path

import numpy as np

from . import budget, io, report, workflows
from .case import load_case
from .case.units import from_si
from .errors import BearingsimError, OutputError


def _wrote(*paths):
    for p in paths:
        print(f"wrote {p}")


def _warn_failures(result, what):
    from .jones import RESULTS

    codes = np.asarray(result)
    bad = int(np.sum(codes != 0))
    if bad:
        kinds, counts = np.unique(codes[codes != 0], return_counts=True)
        why = "; ".join(f"{n}: {RESULTS.of(c).message} (result {int(c)})" for c, n in zip(kinds, counts))
        print(f"bearingsim: warning: {bad} of {codes.size} {what} failed ({why}); they are "
              "flagged in 'converged' (values set to 0)", file=sys.stderr)


def _plot_dir(path):
    d = Path(path)
    d.mkdir(parents=True, exist_ok=True)
    return d


# ------------------------------------------------------------------------------- commands
def cmd_info(args):
    case = load_case(args.case)
    print(report.info_text(case))
    if case.is_set:
        from . import sets
        print(sets.set_info_text(case))
    return 0


def _static_set(case, json_path, plot_path):
    from . import sets
    sol = sets.solve_set_case(case)
    print(sets.set_text(case, sol))
    if json_path:
        io.write_json(json_path, sets.set_to_dict(case, sol))
        _wrote(json_path)
    if plot_path:
        sets.plot_set_static(sol, title=case.title, path=plot_path)
        _wrote(plot_path)


def _static(case, json_path, plot_path):
    if case.is_set:
        return _static_set(case, json_path, plot_path)
    sol = workflows.solve_case(case)
    assessment = workflows.assess_case(case, sol)
    print(report.static_text(case, sol, assessment))
    if json_path:
        io.write_static(json_path, sol, assessment)
        print()
        _wrote(json_path)
    if plot_path:
        from .plots import plot_static

        Path(plot_path).parent.mkdir(parents=True, exist_ok=True)
        plot_static(sol, title=case.title, spall=case.spall(), path=plot_path)
        _wrote(plot_path)


def cmd_static(args):
    _static(load_case(args.case), args.json, args.plot)
    return 0


def _sweep(case, output, plot_dir):
    sol = workflows.sweep_case(case, throw="all", progress=True)
    _warn_failures(sol.result, "cage angles")
    io.write_sweep(output, case, sol)
    th = from_si(np.asarray(sol.cage_angle), "deg")
    Qo = np.asarray(sol.Q_outer)
    print(f"{case.title}: {len(th)} cage angles from {th[0]:.3f} to {th[-1]:.3f} deg, "
          f"max Q_o {Qo.max():.1f} N, min Q_o {Qo.min():.1f} N")
    _wrote(output)
    if plot_dir:
        from .plots import plot_sweep

        p = _plot_dir(plot_dir) / "sweep.png"
        plot_sweep(sol, title=case.title, spall=case.spall(), path=p)
        _wrote(p)


def cmd_sweep(args):
    case = load_case(args.case)
    budget.check_case(case, "sweep", args.output)
    _sweep(case, args.output, args.plot)
    return 0


def cmd_study(args):
    case = load_case(args.case)
    budget.check_case(case, "study", args.output)
    if case.is_set:
        from . import sets
        study = sets.study_set_case(case, throw=False)
        _warn_failures(study.solution.result, "study states")
        sets.write_set_study(args.output, case, study)
        print(sets.set_study_text(case, study))
        _wrote(args.output)
        if args.plot:
            p = _plot_dir(args.plot) / ("study_set_" + study.parameter.replace(".", "_") + ".png")
            sets.plot_set_study(study, title=case.title, path=p)
            _wrote(p)
            p = _plot_dir(args.plot) / ("limits_set_" + study.parameter.replace(".", "_") + ".png")
            sets.plot_set_limits(case, study, title=case.title, path=p)
            _wrote(p)
        return 0
    if args.workers is None and args.scheduler is None:
        study = workflows.study_case(case, throw=False, progress=True)
    else:
        from .distributed import DaskRunner

        with DaskRunner(workers=args.workers, scheduler=args.scheduler) as runner:
            study = workflows.study_case(case, throw=False, progress=True, runner=runner)
    _warn_failures(study.solution.result, "study states")
    io.write_study(args.output, case, study)
    print(report.study_text(case, study))
    _wrote(args.output)
    if args.plot:
        from .plots import plot_study

        p = _plot_dir(args.plot) / ("study_" + study.parameter.replace(".", "_") + ".png")
        plot_study(study.solution, study.values, study.parameter, study.unit, title=case.title,
                   spall=case.spall(), path=p)
        _wrote(p)
    return 0


def _simulate(case, output, plot_dir):
    res = workflows.simulate_case(case)
    io.write_simulation(output, case, res)
    a = np.asarray(res.sensor_acceleration)
    print(f"{case.title}: {float(res.time[-1]):.4f} s simulated in {res.num_steps} steps "
          f"({res.ball_iterations or 'exact'} ball Newton steps), sensor rms {a.std():.4g} m/s^2, "
          f"{len(res.pass_times)} defect passes")
    print("  ".join(f"{k[:-3]} {v:.4f} Hz" for k, v in res.frequencies.items()))
    _wrote(output)
    if plot_dir:
        from .plots import plot_simulation

        spectrum = workflows.simulation_spectrum(res, case) if np.size(res.time) > 64 else None
        _wrote(*plot_simulation(res, plot_dir, title=case.title, bearing=case.bearing(), spall=case.spall(),
                                spectrum=spectrum))


def cmd_simulate(args):
    case = load_case(args.case)
    budget.check_case(case, "simulate", args.output)
    _simulate(case, args.output, args.plot)
    return 0


def _spectrum(path, plot_path):
    analysis = workflows.spectrum_file(path)
    print(report.spectrum_text(analysis))
    if plot_path:
        import matplotlib.pyplot as plt

        from .plots_signal import plot_envelope_spectrum
        from .signal import defect_markers

        Path(plot_path).parent.mkdir(parents=True, exist_ok=True)
        marks = defect_markers(analysis.markers, harmonics_of=(analysis.fault,))
        plt.close(plot_envelope_spectrum(analysis.spectrum, marks, title=f"{path}: squared-envelope spectrum",
                                         fmax=5.5 * analysis.fault_hz, path=plot_path))
        _wrote(plot_path)


def cmd_spectrum(args):
    _spectrum(args.input, args.plot)
    return 0


def cmd_dataset(args):
    from .dataset import DatasetResult

    case = load_case(args.spec)
    est = budget.check_case(case, "dataset", args.output)
    if est is not None:
        print(est.text(args.workers or 1), flush=True)
    if args.workers is None and args.scheduler is None:      # in this process; Dask not imported
        s = workflows.dataset_case(case, args.output, throw=False, progress=True)
    else:
        from .distributed import DaskRunner

        with DaskRunner(workers=args.workers, scheduler=args.scheduler) as runner:
            s = workflows.dataset_case(case, args.output, throw=False, progress=True, runner=runner)
    print(f"{case.title}: {s.count} items x {s.samples} samples in {s.seconds:.1f} s "
          f"({s.seconds_per_item:.3f} s per item, compilation included)")
    if s.failed:
        detail = ", ".join(f"{n} {DatasetResult(c).message}" for c, n in sorted(s.failures.items()))
        print(f"bearingsim: warning: {s.failed} of {s.count} items failed ({detail}); their "
              "signals are zero and labels/result != 0", file=sys.stderr)
    else:
        print("all items simulated successfully")
    _wrote(args.output)
    return 0


def cmd_calibrate(args):
    cal = workflows.calibrate_case(args.healthy, args.output, template=args.template, fault=args.fault,
                                   fault_class=args.fault_class, channel=args.channel,
                                   sample_rate=args.sample_rate_Hz, rpm=args.rpm, unit=args.unit,
                                   count=args.count, duration_s=args.duration_s)
    print(report.calibration_text(cal))
    _wrote(args.output)
    print(f"run it: bearingsim dataset {args.output} -o data.h5")
    return 0


def cmd_compare(args):
    case = load_case(args.case)
    budget.check_case(case, "compare")
    cmp = workflows.compare_case(case, throw=False)
    print(report.compare_text(case, cmp))
    if args.plot:
        from .plots import plot_compare

        p = _plot_dir(args.plot) / "compare.png"
        plot_compare(cmp, title=case.title, path=p)
        _wrote(p)
    return 0


def cmd_demo(args):
    case = load_case(args.case or "demo")
    out = Path(args.out)
    budget.check_case(case, "demo", out / "simulate.h5")
    t0 = time.time()
    print(f"bearingsim demo: {case.source}\n")
    print(report.info_text(case), "\n")
    print("[1/4] quasi-static solve (compiles once, ~10 s)")
    _static(case, out / "static.json", out / "static.png")
    print("\n[2/4] cage-angle sweep past the spall")
    _sweep(case, out / "sweep.h5", out)
    if "dynamics" in case.raw and case.spall() is not None:
        print("\n[3/4] dynamic simulation past the spall")
        _simulate(case, out / "simulate.h5", out)
        print("\n[4/4] squared-envelope spectrum")
        _spectrum(out / "simulate.h5", out / "envelope_spectrum.png")
    print(f"\ndone in {time.time() - t0:.0f} s; all results and plots are in {out.resolve()}")
    return 0


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


def _cluster_flags(s, what):
    where = s.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N", help=f"run {what} on a local Dask cluster "
                       "of N worker processes (pip install 'bearingsim[distributed]'); same file")
    where.add_argument("--scheduler", metavar="ADDRESS|FILE", help=f"run {what} on an existing Dask "
                       "cluster: scheduler address (tcp://HOST:8786) or scheduler file; same file")


def build_parser():
    p = argparse.ArgumentParser(prog="bearingsim", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    plots_into = ("DIR", "write plots into DIR")
    _command(sub, "info", cmd_info, "geometry, Hertz constants, kinematics and defect frequencies of a case")
    s = _command(sub, "static", cmd_static, "quasi-static Jones solution: per-ball table, displacement, stiffness",
                 plot=("OUT.png", "polar load distribution and contact angles"))
    s.add_argument("--json", metavar="OUT.json", help="write the solution as JSON")
    _command(sub, "sweep", cmd_sweep, "quasi-static states over cage angles as the balls pass the spall",
             output=True, plot=plots_into)
    s = _command(sub, "study", cmd_study, "a cage-angle sweep for each value of one case key ([study])",
                 output=True, plot=plots_into)
    _cluster_flags(s, "the sweeps of a geometry, material or defect study")
    _command(sub, "simulate", cmd_simulate, "dynamic simulation (shaft, housing, sensor resonator) "
             "with the Jones bearing forces; HDF5 output", output=True, plot=plots_into)
    _command(sub, "spectrum", cmd_spectrum, "envelope spectrum of a simulate output: peak near the defect's line (BPFO, BPFI, 2 BSF), harmonics",
             positional=("input", "OUT.h5", "a `bearingsim simulate` output"),
             plot=("PNG", "write the envelope spectrum plot"))
    s = _command(sub, "dataset", cmd_dataset, "labelled data set of simulated sensor signals ([dataset] "
             "ranges of speed, loads and spall); HDF5 output",
             positional=("spec", "SPEC.toml", "case file with a [dataset] section, or a shipped case name"),
             output=True)
    _cluster_flags(s, "the chunks")
    s = _command(sub, "calibrate", cmd_calibrate, "fit a data set spec to your machine: background, "
                 "resonances and levels from a healthy record (and at most one fault record)",
                 positional=("healthy", "HEALTHY", "healthy record: .npz (channel, fs, rpm, units), .npy, "
                             ".csv or .txt (one column)"))
    s.add_argument("-o", "--output", required=True, metavar="SPEC.toml")
    s.add_argument("--template", default="dataset_cwru_4class", metavar="CASE",
                   help="data set spec with the bearing geometry and [dataset] (default dataset_cwru_4class)")
    s.add_argument("--fault", metavar="RECORD", help="one record of a known fault (same sample rate)")
    s.add_argument("--fault-class", choices=("outer", "inner", "ball"), help="the fault record's class")
    s.add_argument("--channel", help="the .npz key of the signal (default DE, or the file's only array)")
    s.add_argument("--sample-rate-Hz", type=float, metavar="FS", help="sample rate when the file does not say")
    s.add_argument("--rpm", type=float, metavar="N", help="the healthy record's shaft speed (default: "
                   "from the spectrum, near the .npz rpm or the template's speed)")
    s.add_argument("--unit", choices=("g", "m/s^2"), help="unit of the samples when the file does not say")
    s.add_argument("--count", type=int, metavar="N", help="items of the data set (default: the template's)")
    s.add_argument("--duration-s", type=float, metavar="S", help="seconds per item (default: the template's)")
    _command(sub, "compare", cmd_compare, "quasi-static sweep and dynamic run side by side, with amplification",
             plot=("DIR", "write compare.png into DIR"))
    s = _command(sub, "demo", cmd_demo, "run the default case end to end and write all results and plots",
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


def _stop(signum, frame):
    _stopped_by.append(signal.Signals(signum).name)
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


def main(argv=None):
    """Run ``bearingsim ARGS``; returns the exit code (Ctrl-C / SIGTERM at any moment: one
    line, 130, nothing half-written: every file is written atomically)."""
    _stopped_by.clear()
    _outputs.clear()
    old = _stop_handlers()
    old_hook, sys.unraisablehook = sys.unraisablehook, _unraisable
    try:
        import matplotlib

        matplotlib.use("Agg")          # files only, no display needed
        args = build_parser().parse_args(argv)
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
        while _watchdog:
            _watchdog.pop().cancel()


def run():
    """The ``bearingsim`` console command: :func:`main`, and after an interrupt an immediate
    exit (compilations still running in background threads are not waited for)."""
    code = main()
    if code == 130:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    sys.exit(code)


#: kept for tests/test_dynamics.py (owned by the core) until it calls workflows.compare_case
compare_static_dynamic = workflows.compare_case


if __name__ == "__main__":
    run()
