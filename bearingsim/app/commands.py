"""The commands of ``bearingsim``: one function per sub-command (``cmd_static``, ``cmd_dataset``,
...), each taking the parsed arguments, calling the workflows (:mod:`bearingsim.app.workflows`
and the modules beside it), printing and writing; :mod:`bearingsim.app.cli` parses the command
line, maps errors to exit codes and handles interrupts.
"""
from __future__ import annotations

import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from .. import runtime
from ..datasets import budget
from ..errors import InputError, failed


from .lazy_modules import (cases, dataset_spec, distributed, ident, ident_bank, ident_report, io, jones, lines, np,
                           plots, plots_signal, record_spectra, report, rotor, rotordynamics, signal_workflows, units,
                           workflows)


def load_case(*args, **kwargs):
    return cases.load_case(*args, **kwargs)


def from_si(*args, **kwargs):
    return units.from_si(*args, **kwargs)


def _wrote(*paths):
    for p in paths:
        print(f"wrote {p}")


def _warn_failures(result, what):
    codes = np.asarray(result)
    bad = int(np.sum(failed(codes)))
    if bad:
        kinds, counts = np.unique(codes[failed(codes)], return_counts=True)
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


def _sweep(case, output, plot_dir, sol=None):
    """The sweep's files, text and figure (``sol``: the sweep already solved, else solved here)."""
    sol = workflows.sweep_case(case, throw="all", progress=True) if sol is None else sol
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


def _simulate(case, output, plot_dir, res=None):
    """The simulation's files, text and figures (``res``: already simulated, else simulated here)."""
    res = signal_workflows.simulate_case(case) if res is None else res
    io.write_simulation(output, case, res)
    a = np.asarray(res.sensor_acceleration)
    print(f"{case.title}: {float(res.time[-1]):.4f} s simulated in {res.num_steps} steps "
          f"({res.ball_iterations or 'exact'} ball Newton steps), sensor rms {a.std():.4g} m/s^2, "
          f"{len(res.pass_times)} defect passes")
    print("  ".join(f"{k[:-3]} {v:.4f} Hz" for k, v in res.frequencies.hz().items()))
    _wrote(output)
    if plot_dir:
        spectrum = signal_workflows.simulation_spectrum(res, case) if np.size(res.time) > 64 else None
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
    analysis = signal_workflows.spectrum_file(path)
    print(report.spectrum_text(analysis))
    if plot_path:
        import matplotlib.pyplot as plt

        Path(plot_path).parent.mkdir(parents=True, exist_ok=True)
        marks = lines.defect_markers(analysis.markers, harmonics_of=(analysis.fault,))
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
    """``bearingsim cache [--clear]``: where the compiled and traced programs, the identify
    banks and the cached data sets are kept, how much, clearing."""
    bank_dir = ident_bank.cache_dir
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
    sets = [p for p in sorted(bank_dir().glob("*.h5")) if p not in banks]
    if sets:
        size = sum(p.stat().st_size for p in sets if p.is_file())
        print(f"cached data sets: {len(sets)} files, {budget.human_bytes(size)} beside them (training sets "
              "simulated once per spec: bearingsim.datasets.cached_dataset)")
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
        gone = 0
        for p in sets:
            try:
                p.unlink()
                p.with_name(p.name + ".lock").unlink(missing_ok=True)
                gone += 1
            except OSError:
                pass
        if sets:
            print(f"cleared: {gone} cached data sets deleted")
    return 0


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
        s = signal_workflows.dataset_case(case, args.output, **kw)
    else:
        with distributed.DaskRunner(workers=args.workers, scheduler=args.scheduler) as runner:
            s = signal_workflows.dataset_case(case, args.output, runner=runner, **kw)
    print(f"{case.title}: {s.count} items x {s.samples} samples in {s.seconds:.1f} s "
          f"({s.seconds_per_item:.3f} s per item, compilation included) on {s.device}, {s.chunk} items per chunk")
    out = int(dataset_spec.DatasetResult.fault_not_excited)
    if s.failed:
        detail = ", ".join(f"{n} {dataset_spec.DatasetResult(c).message}" for c, n in sorted(s.failures.items())
                           if c != out)
        print(f"bearingsim: warning: {s.failed} of {s.count} items failed ({detail}); their "
              "signals are zero and labels/result != 0", file=sys.stderr)
    if s.excluded:
        m = dataset_spec.DatasetResult.fault_not_excited
        print(f"{s.excluded} of {s.count} fault items excluded: {m.message} (labels/result {int(m)}, signal "
              f"zero; load_dataset drops them).  To keep them: {m.hint}")
    if not s.failed:
        print(f"all {'other ' if s.excluded else ''}items simulated successfully")
    _wrote(args.output)
    _compiled(case, "dataset")
    return 0


def cmd_calibrate(args):
    cal = signal_workflows.calibrate_case(args.healthy, args.output, template=args.template, fault=args.fault,
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
    print(ident_report.identification_text(r))
    if args.json:
        io.write_json(args.json, ident_report.identification_to_dict(r))
        _wrote(args.json)
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        twin = None
        if r.fault_class == "uncertain":
            print("no simulated twin: the class is uncertain (the plot shows the record alone)")
        else:
            print("simulating the twin at the estimate (the first twin of a class compiles, later ones "
                  "load the kept programs) ...", flush=True)
            twin = ident_bank.twin_record(r)
        ident_report.plot_identification(x, fs, r, twin, path=args.plot,
                                         title=f"{Path(args.record).name}: {r.fault_class}")
        _wrote(args.plot)
    return 0


def cmd_compare(args):
    case = load_case(args.case)
    budget.check_case(case, "compare")
    _compiling(case, "compare")
    cmp = signal_workflows.compare_case(case, throw=False)
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
    dynamic = "dynamics" in case.raw and case.spall() is not None
    # the sweep and the simulation are solved beside the static solve (their programs compile on
    # the other core; on a first run compiling is most of the demo); files, text and figures
    # follow in order in this thread
    with ThreadPoolExecutor(2) as pool:
        sweep = pool.submit(workflows.sweep_case, case, throw="all", progress=False)
        sim = pool.submit(signal_workflows.simulate_case, case) if dynamic else None
        print(f"bearingsim demo: {case.source}\n")
        print(report.info_text(case), "\n")
        print("[1/4] quasi-static solve")
        workflows.static_command(case, out / "static.json", out / "static.png", say=print)
        print("\n[2/4] cage-angle sweep past the spall")
        _sweep(case, out / "sweep.h5", out, sweep.result())
        if dynamic:
            print("\n[3/4] dynamic simulation past the spall")
            _simulate(case, out / "simulate.h5", out, sim.result())
            print("\n[4/4] squared-envelope spectrum")
            _spectrum(out / "simulate.h5", out / "envelope_spectrum.png")
    print(f"\ndone in {time.time() - t0:.0f} s; all results and plots are in {out.resolve()}")
    _compiled(case, "demo")
    return 0
