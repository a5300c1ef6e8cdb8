"""Command line: ``bearingsim info|static|sweep|study|simulate|spectrum|compare|dataset|calibrate|identify|rotor|cache|demo``.

Argument parsing, printing and exit codes only: the work is done by :mod:`bearingsim.app.workflows`,
files are written by :mod:`bearingsim.output.io`, figures drawn by :mod:`bearingsim.output.plots`.  Exit codes
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
import warnings
from pathlib import Path

from .. import runtime
from ..datasets import budget
from ..names import LOCATIONS
from ..errors import BearingsimError, InputError, OutputError


# ------------------------------------------------------------------------------ the start-up seam
# `bearingsim --help` and an argument error load no JAX (tests/test_runtime.py), nor NumPy: each
# module below loads NumPy and most of them JAX, matplotlib or Dask, so each is imported at its
# first use, by the one import statement of its loader (visible to tests/test_architecture.py).
# These loaders are the command line's only function-local imports of bearingsim modules; the
# commands use the module objects.
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


def _envelope():
    from ..signals import envelope as m
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


def _workflows():
    from . import workflows as m
    return m


def _rotor():
    from . import rotor as m
    return m


def _rotordynamics():
    from . import rotordynamics as m
    return m


np, cases, units, jones, envelope = _Lazy(_numpy), _Lazy(_case), _Lazy(_units), _Lazy(_jones), _Lazy(_envelope)
io, report, plots, plots_signal = _Lazy(_io), _Lazy(_report), _Lazy(_plots), _Lazy(_plots_signal)
dataset_spec, distributed = _Lazy(_dataset_spec), _Lazy(_distributed)
record_spectra, ident, workflows = _Lazy(_record_spectra), _Lazy(_identify), _Lazy(_workflows)
rotordynamics, rotor = _Lazy(_rotordynamics), _Lazy(_rotor)


def load_case(*args, **kwargs):
    return cases.load_case(*args, **kwargs)


def from_si(*args, **kwargs):
    return units.from_si(*args, **kwargs)


def _wrote(*paths):
    for p in paths:
        print(f"wrote {p}")


def _warn_failures(result, what):
    codes = np.asarray(result)
    bad = int(np.sum(codes != 0))
    if bad:
        kinds, counts = np.unique(codes[codes != 0], return_counts=True)
        why = "; ".join(f"{n}: {jones.RESULTS.of(c).message} (result {int(c)})" for c, n in zip(kinds, counts))
        print(f"bearingsim: warning: {bad} of {codes.size} {what} failed ({why}); they are "
              "flagged in 'converged' (values set to 0)", file=sys.stderr)


def _plot_dir(path):
    d = Path(path)
    d.mkdir(parents=True, exist_ok=True)
    return d


def _compiling(case, command):
    """Say so before a command compiles with a cold cache ("compiling, first run only: ~N s")."""
    line = budget.compile_notice(case, command)
    if line:
        print(line, flush=True)


def _compiled(case, command):
    budget.mark_compiled(case, command)


# ------------------------------------------------------------------------------- commands
def cmd_info(args):
    print(workflows.info_text(load_case(args.case)))
    return 0


def cmd_static(args):
    budget.check_output(args.plot, "--plot")        # before any work (exit 4)
    case = load_case(args.case)
    _compiling(case, "static")
    workflows.static_command(case, args.json, args.plot, say=print)
    _compiled(case, "static")
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
        p = _plot_dir(plot_dir) / "sweep.png"
        plots.plot_sweep(sol, title=case.title, spall=case.spall(), path=p)
        _wrote(p)


def cmd_sweep(args):
    case = load_case(args.case)
    budget.check_case(case, "sweep", args.output)
    _compiling(case, "sweep")
    _sweep(case, args.output, args.plot)
    _compiled(case, "sweep")
    return 0


def cmd_study(args):
    case = load_case(args.case)
    budget.check_case(case, "study", args.output)
    _compiling(case, "study")
    workflows.study_command(case, args.output, args.plot, workers=args.workers, scheduler=args.scheduler,
                            say=print, warn=_warn_failures)
    _compiled(case, "study")
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
        spectrum = workflows.simulation_spectrum(res, case) if np.size(res.time) > 64 else None
        _wrote(*plots.plot_simulation(res, plot_dir, title=case.title, bearing=case.bearing(), spall=case.spall(),
                                      spectrum=spectrum))


def cmd_simulate(args):
    case = load_case(args.case)
    budget.check_case(case, "simulate", args.output)
    _compiling(case, "simulate")
    _simulate(case, args.output, args.plot)
    _compiled(case, "simulate")
    return 0


def _spectrum(path, plot_path):
    analysis = workflows.spectrum_file(path)
    print(report.spectrum_text(analysis))
    if plot_path:
        import matplotlib.pyplot as plt

        Path(plot_path).parent.mkdir(parents=True, exist_ok=True)
        marks = envelope.defect_markers(analysis.markers, harmonics_of=(analysis.fault,))
        plt.close(plots_signal.plot_envelope_spectrum(analysis.spectrum, marks,
                                                      title=f"{path}: squared-envelope spectrum",
                                                      fmax=5.5 * analysis.fault_hz, path=plot_path))
        _wrote(plot_path)


def _record_spectrum(args):
    """``bearingsim spectrum RECORD``: a real record's spectra with the case's fault lines."""
    case = load_case(args.case or "cwru_6205")
    if args.case is None:
        print("bearing: cwru_6205 (the CWRU drive-end 6205; give --case for another)")
    rs = record_spectra.record_spectrum(args.input, case, rpm=args.rpm, channel=args.channel,
                                        sample_rate=args.sample_rate_Hz, unit=args.unit, overlay=args.overlay,
                                        item=args.item)
    print(report.record_spectrum_text(rs))
    if args.plot:
        import matplotlib.pyplot as plt

        Path(args.plot).parent.mkdir(parents=True, exist_ok=True)
        plt.close(plots_signal.plot_record_spectrum(rs, path=args.plot))
        _wrote(args.plot)


#: flags that apply to a record only (not to a `bearingsim simulate` output)
_RECORD_FLAGS = (("case", "--case"), ("rpm", "--rpm"), ("channel", "--channel"),
                 ("sample_rate_Hz", "--sample-rate-Hz"), ("unit", "--unit"), ("overlay", "--overlay"))


def cmd_spectrum(args):
    budget.check_output(args.plot, "--plot")        # before any work (exit 4)
    if Path(args.input).suffix.lower() in (".h5", ".hdf5"):
        given = [flag for attr, flag in _RECORD_FLAGS if getattr(args, attr, None) is not None]
        if given:
            raise InputError(f"{args.input}: {', '.join(given)} apply to a record file (.npz, .npy, "
                             ".csv, .txt, .wav), not to a simulate output")
        _spectrum(args.input, args.plot)
        return 0
    _record_spectrum(args)
    return 0


def cmd_cache(args):
    """``bearingsim cache [--clear]``: where the compiled and traced programs and the identify
    banks are kept, how much, clearing."""
    bank_dir = ident.cache_dir
    d = runtime.configured_cache_dir()
    banks = sorted(bank_dir().glob("identify_bank_*"))
    asked = runtime.cache_dir()
    if d is None and asked is None:
        print("compilation cache: off (BEARINGSIM_CACHE_DIR=off): every run compiles")
    elif d is None:
        print(f"compilation cache: {asked} cannot be used (not a writable folder); every run compiles in "
              "memory: set BEARINGSIM_CACHE_DIR to a writable folder")
    else:
        n, b = runtime.cache_size(d)
        kept, kb = runtime.cache_size(d / runtime.PROGRAMS_FOLDER)
        print(f"compilation cache: {d} ({n} files, {budget.human_bytes(b)}); move it with "
              "BEARINGSIM_CACHE_DIR=FOLDER, switch it off with BEARINGSIM_CACHE_DIR=off")
        print(f"  of which traced programs: {kept} files, {budget.human_bytes(kb)} in {d / runtime.PROGRAMS_FOLDER} "
              "(loaded instead of traced by the next run; BEARINGSIM_PROGRAM_CACHE=off keeps them in memory)")
    size = sum(p.stat().st_size for p in banks if p.is_file())
    print(f"identify banks: {bank_dir()} ({len(banks)} files, {budget.human_bytes(size)}; simulated records "
          "identify learns from, built once; move them with BEARINGSIM_CACHE=FOLDER)")
    if args.clear:
        if d is not None:
            print(f"cleared: {runtime.clear_cache(d)} files deleted; the next run of each command compiles again")
        gone = 0
        for p in banks:
            try:
                p.unlink()
                gone += 1
            except OSError:
                pass
        print(f"cleared: {gone} identify bank files deleted; the next identify builds its bank again")
    return 0


def _cache_parser(sub):
    s = sub.add_parser("cache", help="where the compiled and traced programs (~/.cache/bearingsim/jax, "
                       "BEARINGSIM_CACHE_DIR) and the identify banks (~/.cache/bearingsim, BEARINGSIM_CACHE) "
                       "are kept, and --clear")
    s.add_argument("--clear", action="store_true", help="delete the cached programs and identify banks")
    s.set_defaults(func=cmd_cache)
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
    s.add_argument("--sample-rate-Hz", type=float, metavar="FS", help="sample rate when the file does not say")
    s.add_argument("--unit", choices=("g", "m/s^2"), help="unit of the samples when the file does not say "
                   "(default m/s^2)")
    s.add_argument("--overlay", metavar="SIM.h5", help="overlay a simulation's envelope spectrum: a "
                   "`bearingsim simulate` output or a `bearingsim dataset` file (item --item)")
    s.add_argument("--item", type=int, default=0, metavar="K", help="the data set item to overlay (default 0)")
    s.set_defaults(func=cmd_spectrum)
    return s


#: the data set flags that override a key of the spec
_DATASET_FLAGS = (("count", "--count", "dataset.count"), ("seed", "--seed", "dataset.seed"),
                  ("duration_s", "--duration-s", "dataset.duration_s"),
                  ("sample_rate_Hz", "--sample-rate-Hz", "dynamics.sample_rate_Hz"))


def _dataset_overrides(case, args):
    """The spec with ``--count``, ``--seed``, ``--duration-s``, ``--sample-rate-Hz`` set
    (validated as the keys are; a refused value names its flag)."""
    if "dataset" not in case.data:
        return case
    for attr, flag, key in _DATASET_FLAGS:
        v = getattr(args, attr, None)
        if v is None:
            continue
        try:
            case = case.with_value(key, v)
        except InputError as e:
            raise InputError(f"{flag} {v:g}: " + str(e).replace("\n", "\n  ")) from None
    return case


def cmd_dataset(args):
    case = _dataset_overrides(load_case(args.spec), args)
    est = budget.check_case(case, "dataset", args.output)
    if est is not None:
        print(est.text(args.workers or 1), flush=True)
    _compiling(case, "dataset")
    kw = dict(throw=False, progress=True, device=args.device, chunk=args.chunk, compression=args.compression)
    if args.workers is None and args.scheduler is None:      # in this process; Dask not imported
        s = workflows.dataset_case(case, args.output, **kw)
    else:
        with distributed.DaskRunner(workers=args.workers, scheduler=args.scheduler) as runner:
            s = workflows.dataset_case(case, args.output, runner=runner, **kw)
    print(f"{case.title}: {s.count} items x {s.samples} samples in {s.seconds:.1f} s "
          f"({s.seconds_per_item:.3f} s per item, compilation included) on {s.device}, {s.chunk} items per chunk")
    if s.failed:
        detail = ", ".join(f"{n} {dataset_spec.DatasetResult(c).message}" for c, n in sorted(s.failures.items()))
        print(f"bearingsim: warning: {s.failed} of {s.count} items failed ({detail}); their "
              "signals are zero and labels/result != 0", file=sys.stderr)
    else:
        print("all items simulated successfully")
    _wrote(args.output)
    _compiled(case, "dataset")
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


def cmd_identify(args):
    case = load_case(args.case or "dataset_cwru_4class")
    if args.case is None:
        print("bearing: dataset_cwru_4class (the CWRU drive-end 6205; give --case for another)")
    budget.check_output(args.plot, "--plot")
    budget.check_output(args.json, "--json")
    r, x, fs = ident.identify_file(args.record, case, channel=args.channel, rpm=args.rpm,
                                   sample_rate=args.sample_rate_Hz)
    print(ident.identification_text(r))
    if args.json:
        io.write_json(args.json, ident.identification_to_dict(r))
        _wrote(args.json)
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        print("simulating the twin at the estimate (compiles once) ...", flush=True)
        twin = ident.twin_record(case, r)
        ident.plot_identification(x, fs, r, twin, path=args.plot, title=f"{Path(args.record).name}: {r.fault_class}")
        _wrote(args.plot)
    return 0


def cmd_compare(args):
    case = load_case(args.case)
    budget.check_case(case, "compare")
    _compiling(case, "compare")
    cmp = workflows.compare_case(case, throw=False)
    print(report.compare_text(case, cmp))
    if args.plot:
        p = _plot_dir(args.plot) / "compare.png"
        plots.plot_compare(cmp, title=case.title, path=p)
        _wrote(p)
    _compiled(case, "compare")
    return 0


def cmd_rotor(args):
    """``bearingsim rotor CASE``: a ROSS rotor on the case's bearing (or set) at both ends, its
    Campbell diagram and critical speeds (bearingsim.app.rotordynamics; needs the ross extra)."""
    speeds = rotordynamics.parse_speeds(args.speeds_rpm) if args.speeds_rpm else None
    rotordynamics.require_ross()                  # before any work: the one message how to install it
    case = load_case(args.case)
    _wrote(*rotor.rotor_command(case, args.out, speeds, say=print))
    return 0


def cmd_demo(args):
    case = load_case(args.case or "demo")
    out = Path(args.out)
    budget.check_case(case, "demo", out / "simulate.h5")
    _compiling(case, "demo")
    t0 = time.time()
    print(f"bearingsim demo: {case.source}\n")
    print(report.info_text(case), "\n")
    print("[1/4] quasi-static solve")
    workflows.static_command(case, out / "static.json", out / "static.png", say=print)
    print("\n[2/4] cage-angle sweep past the spall")
    _sweep(case, out / "sweep.h5", out)
    if "dynamics" in case.raw and case.spall() is not None:
        print("\n[3/4] dynamic simulation past the spall")
        _simulate(case, out / "simulate.h5", out)
        print("\n[4/4] squared-envelope spectrum")
        _spectrum(out / "simulate.h5", out / "envelope_spectrum.png")
    print(f"\ndone in {time.time() - t0:.0f} s; all results and plots are in {out.resolve()}")
    _compiled(case, "demo")
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
    _spectrum_parser(sub)
    s = _command(sub, "dataset", cmd_dataset, "labelled data set of simulated sensor signals ([dataset] "
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
    s = _command(sub, "calibrate", cmd_calibrate, "fit a data set spec to your machine: background, "
                 "resonances and levels from a healthy record (and at most one fault record)",
                 positional=("healthy", "HEALTHY", "healthy record: .npz (channel, fs, rpm, units), .npy, "
                             ".csv or .txt (one column)"))
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
    s = _command(sub, "identify", cmd_identify, "identify a fault from a measured record: class and "
                 "location with a probability, defect length, contact angle and shaft speed with intervals",
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
    _command(sub, "compare", cmd_compare, "quasi-static vs dynamic: the ball loads of the quasi-static "
             "sweep (Jones model, no inertia) against the dynamic simulation's as the balls pass the spall, "
             "and the dynamic amplification",
             plot=("DIR", "write compare.png into DIR"))
    s = _command(sub, "rotor", cmd_rotor, "a small steel rotor (ROSS) on the case's bearing or set at both "
                 "ends: Campbell diagram and critical speeds (pip install 'bearingsim[ross]')")
    s.add_argument("--out", default="results/rotor", metavar="DIR", help="write campbell.png and "
                   "critical_speeds.json into DIR (default results/rotor)")
    s.add_argument("--speeds-rpm", metavar="START:STOP:COUNT", help="rotor speeds in rpm (default "
                   "0:1.5 x the case's speed:16)")
    _cache_parser(sub)
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
        import matplotlib

        matplotlib.use("Agg")          # files only, no display needed
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
    exit (compilations still running in background threads are not waited for)."""
    code = main()
    if code == 130:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    sys.exit(code)


def __getattr__(name):
    if name == "compare_static_dynamic":     # kept for tests/test_dynamics.py (owned by the core)
        return workflows.compare_case        # until it calls workflows.compare_case
    raise AttributeError(f"module 'bearingsim.app.cli' has no attribute {name!r}")


if __name__ == "__main__":
    run()
