"""Command line: ``bearingsim info|static|sweep|study|simulate|spectrum|compare|dataset|demo``.

Argument parsing, printing and exit codes only: the work is done by :mod:`bearingsim.workflows`,
files are written by :mod:`bearingsim.io`, figures drawn by :mod:`bearingsim.plots`.  Exit codes
are the ``exit_code`` of the :mod:`bearingsim.errors` classes: 0 success, 2 bad input, 3 a solve
did not converge, 4 an output could not be written.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from . import io, report, workflows
from .case import load_case
from .case.units import from_si
from .errors import BearingsimError, OutputError


def _wrote(*paths):
    for p in paths:
        print(f"wrote {p}")


def _warn_failures(result, what):
    codes = np.asarray(result)
    bad = int(np.sum(codes != 0))
    if bad:
        print(f"bearingsim: warning: {bad} of {codes.size} {what} did not converge; they are "
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
    sol = workflows.sweep_case(case, throw=False, progress=True)
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
    _sweep(load_case(args.case), args.output, args.plot)
    return 0


def cmd_study(args):
    case = load_case(args.case)
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
        return 0
    study = workflows.study_case(case, throw=False, progress=True)
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
    _simulate(load_case(args.case), args.output, args.plot)
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
    s = workflows.dataset_case(case, args.output, throw=False, progress=True)
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


def cmd_compare(args):
    case = load_case(args.case)
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
    _command(sub, "study", cmd_study, "a cage-angle sweep for each value of one case key ([study])",
             output=True, plot=plots_into)
    _command(sub, "simulate", cmd_simulate, "dynamic simulation (shaft, housing, sensor resonator) "
             "with the Jones bearing forces; HDF5 output", output=True, plot=plots_into)
    _command(sub, "spectrum", cmd_spectrum, "envelope spectrum of a simulate output: peak near the defect's line (BPFO, BPFI, 2 BSF), harmonics",
             positional=("input", "OUT.h5", "a `bearingsim simulate` output"),
             plot=("PNG", "write the envelope spectrum plot"))
    _command(sub, "dataset", cmd_dataset, "labelled data set of simulated sensor signals ([dataset] "
             "ranges of speed, loads and spall); HDF5 output",
             positional=("spec", "SPEC.toml", "case file with a [dataset] section, or a shipped case name"),
             output=True)
    _command(sub, "compare", cmd_compare, "quasi-static sweep and dynamic run side by side, with amplification",
             plot=("DIR", "write compare.png into DIR"))
    s = _command(sub, "demo", cmd_demo, "run the default case end to end and write all results and plots",
                 positional=None)
    s.add_argument("--case", default=None, help="case file or shipped case name (default: demo)")
    s.add_argument("--out", default="results/demo", help="output folder (default results/demo)")
    return p


def main(argv=None):
    import matplotlib

    matplotlib.use("Agg")          # files only, no display needed
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except BearingsimError as e:     # the one place where errors become exit codes
        print(f"bearingsim: error: {e}", file=sys.stderr)
        return e.exit_code
    except OSError as e:             # a file the system refused outside bearingsim.io (plots)
        print(f"bearingsim: error: cannot write output: {e}", file=sys.stderr)
        return OutputError.exit_code


#: kept for tests/test_dynamics.py (owned by the core) until it calls workflows.compare_case
compare_static_dynamic = workflows.compare_case


if __name__ == "__main__":
    sys.exit(main())
