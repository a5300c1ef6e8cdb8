"""Case-driven workflows: what the command line, the notebooks, the README and the tests run.

Each function takes a validated :class:`bearingsim.case.Case` (``load_case("demo")`` or a path)
and calls the core with *everything* the case says (cage angle, Hertz method, raceway control,
sweep grid, dynamics settings), so Python and the command line give the same numbers:

============================ =========================================== ======================
function                     result                                      command
============================ =========================================== ======================
:func:`solve_case`           ``JonesSolution`` (a set: ``SetSolution``)  ``bearingsim static``
:func:`assess_case`          :class:`Assessment` (limits, life)          ``bearingsim static``
:func:`sweep_case`           ``JonesSolution`` with a leading (N,) axis  ``bearingsim sweep``
:func:`study_case`           :class:`Study` (solution (M, N); a set:     ``bearingsim study``
                             ``SetStudy``)
:func:`simulate_case`        ``DynamicsResult``                          ``bearingsim simulate``
:func:`compare_case`         :class:`Comparison`                         ``bearingsim compare``
:func:`dataset_case`         ``DatasetSummary`` (file written)           ``bearingsim dataset``
:func:`spectrum_file`        :class:`EnvelopeAnalysis`                   ``bearingsim spectrum``
:func:`calibrate_case`       ``MachineCalibration`` (spec written)       ``bearingsim calibrate``
============================ =========================================== ======================

A case with a ``[set]`` section (a shaft on several bearings) goes through the same entries:
:func:`solve_case` and :func:`study_case` dispatch on the case, and the command entries
:func:`info_text`, :func:`static_command` and :func:`study_command` do a command's whole work
(solve, text, files, figures) for a single bearing or a set alike, so the command line has no
set branch.

Errors are the classes of :mod:`bearingsim.errors`: bad input raises ``InputError``; with
``throw=True`` (the default) a failed solve raises ``NotConvergedError`` naming the case file,
with ``throw=False`` the result is returned with its codes (per item for batches).  Nothing here
prints, writes files or draws, except :func:`dataset_case` and :func:`calibrate_case` (whose result
is the file) and the command entries (which say their lines through ``say`` and write the files
they are given, through :mod:`bearingsim.output.io`, :mod:`bearingsim.output.report`, :mod:`bearingsim.output.plots`
and :mod:`bearingsim.app.sets`).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..case import check_sampling, load_case, unit_of
from ..case.units import from_si
from ..errors import InputError, NotConvergedError
from ..output import io
from ..output.report import info_text as bearing_info, static_text, study_text
from ..physics import jones, life
from ..physics import sweep as sweeps
from ..physics.kinematics import Operation
from ..physics.limits import contact_limits
from ..programs import jit
from ..realism.records import read_record
from ..signals.envelope import envelope_spectrum, fault_lines, harmonic_peaks, peak_frequency, select_band
from . import sets

__all__ = ["solve_case", "info_text", "static_command", "study_command", "assess_case", "Assessment", "sweep_case", "study_case", "simulate_case", "compare_case", "dataset_case",
           "spectrum_file", "calibrate_case", "envelope_band", "simulation_spectrum", "Study", "Comparison",
           "EnvelopeAnalysis", "STUDY_CHUNK"]

#: quasi-static states solved together by :func:`study_case` (the last chunk is padded)
STUDY_CHUNK = 1024

def _progress(total, desc, unit, progress):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, disable=None if progress else True, dynamic_ncols=True)


def _check(sol, case, what, throw):
    """With ``throw``, raise NotConvergedError / InvalidStateError for a quasi-static solution
    (single or batch) with a failed item, naming the case file, the reason and the count;
    ``throw="all"``: only when every item failed (a sweep with no valid state at all has the
    verdict of a single solve, e.g. a reverse axial load)."""
    if throw == "all":
        throw = bool(np.all(np.asarray(sol.result) != 0))
    if throw:
        jones.raise_for(sol, f"{case.source}: {what}", bearing=case.bearing())
    return sol


# ------------------------------------------------------------------------------------ solve
def solve_case(case, *, throw=True):
    """The quasi-static state of ``case`` at its cage angle (``bearingsim static``): a
    ``JonesSolution``, or for a case with a ``[set]`` section the set's ``SetSolution``
    (:func:`bearingsim.app.sets.solve_set_case`).  The verdict is the core's
    (:func:`bearingsim.physics.jones.solve`: a loaded contact centred at or beyond a shoulder edge is
    result 8, or 7 at an angular contact bearing's low edge, healthy or with a defect; a set's
    bearings are checked by the same rule); nothing is decided here."""
    if case.is_set:
        return sets.solve_set_case(case, throw=throw)
    b, op, spall = case.bearing(), case.operation(), case.spall()
    sol = jones.solve(b, op, case.loads(), cage_angle=case.cage_angle,
                      spall=spall, hertz_method=case.hertz_method, throw=False)
    return _check(sol, case, "the quasi-static solve", throw)


@dataclass(frozen=True)
class Assessment:
    """Limits and life of a quasi-static state (:func:`assess_case`; ``bearingsim static``).

    ``limits``: :class:`bearingsim.physics.limits.ContactLimits`; ``settings``: the case's
    ``limits_settings()`` (SI); ``rating_life``: ISO/TS 16281 L10r (10^6 revolutions) or None
    (no dynamic load rating in the case, no load, or a defect: the life is a healthy bearing's); ``ring_lives``: (inner, outer) in 10^6
    revolutions or None; ``life_hours``: at the case's speed, None at standstill or without a
    life; ``nominal_angle``: the contact angle of the life formula (rad; 0 for a deep groove)."""

    limits: object
    settings: dict
    rating_life: float | None
    ring_lives: tuple | None
    life_hours: float | None
    nominal_angle: float


def _contact_limits_jit():
    """:func:`bearingsim.physics.limits.contact_limits` as one compiled program (cached on disk), not
    some thirty small eager ones: a warm ``bearingsim static`` loads one program instead."""
    global _LIMITS_JIT
    if _LIMITS_JIT is None:
        _LIMITS_JIT = jit(contact_limits)
    return _LIMITS_JIT


_LIMITS_JIT = None


def assess_case(case, sol) -> Assessment:
    """Per-contact limits (MODEL.md 11: pressure, the friction raceway control needs, the
    ellipse against the shoulders) and, when the case gives ``bearing.dynamic_load_rating_kN``,
    the ISO/TS 16281 rating life of the state ``sol`` of ``case`` (single state)."""
    b, op = case.bearing(), case.operation()
    st = case.limits_settings()
    lim = _contact_limits_jit()(sol, b, op.control, pressure_limit=st["pressure_limit"],
                                friction_coefficient=st["friction_coefficient"])
    alpha = float(b.free_contact_angle) if bool(b.angular_contact) else 0.0
    L = rings = hours = None
    C = st["dynamic_load_rating"]
    if C is not None and int(sol.result) == 0 and case.spall() is None:
        Lr = float(life.rating_life(b, C, sol.Q_inner, sol.Q_outer, contact_angle=alpha))
        if np.isfinite(Lr):
            L = Lr
            Li, Lo = life.ring_lives(b, C, sol.Q_inner, sol.Q_outer, contact_angle=alpha)
            rings = tuple(float(x) if np.isfinite(float(x)) else None for x in (Li, Lo))
            h = float(life.life_hours(Lr, op.speed))
            hours = h if np.isfinite(h) else None
    return Assessment(lim, st, L, rings, hours, alpha)


def sweep_case(case, *, throw=True, progress=False, resolve_edges=True):
    """Quasi-static states over the case's ``[sweep]`` cage angles (both sides of every
    rectangular-spall edge inserted unless ``resolve_edges=False``).  ``throw``: True raises for
    any failed angle, ``"all"`` (``bearingsim sweep``) only when every angle failed, False never
    (codes per angle)."""
    b, spall = case.bearing(), case.spall()
    st = case.sweep_settings()
    angles = sweeps.sweep_angles(b, spall, st["start"], st["stop"], st["steps"], resolve_edges)
    bar = _progress(len(angles), "sweep", "angle", progress)
    try:
        sol = sweeps.sweep_chunked(b, case.operation(), case.loads(), spall, angles, progress=bar.update,
                                   hertz_method=case.hertz_method)
    finally:
        bar.close()
    return _check(sol, case, "the cage-angle sweep", throw)


# ------------------------------------------------------------------------------------ study
@dataclass(frozen=True)
class Study:
    """Result of :func:`study_case`: one cage-angle sweep per value of ``parameter``.

    ``values`` in the key's unit (``unit``, e.g. "rpm"); ``solution`` a ``JonesSolution`` with
    leading axes (M values, N cage angles); ``batched``: whether all values were solved as one
    batch (keys that leave the bearing and the spall unchanged) or one sweep per value."""

    parameter: str
    values: list
    unit: str
    solution: object
    batched: bool

    @property
    def converged(self):
        return np.asarray(self.solution.result) == 0

    def message(self):
        return self.solution.message()


#: study keys that change the shape of the results: no rectangular (M, N, Z) array
_SHAPE_KEYS = {"bearing.balls": "the number of balls", "sweep.steps": "the number of cage angles"}
#: sections whose keys leave the bearing and the spall as they are: a study of one is one batch
_BATCH_SECTIONS = ("load", "operation", "sweep")


def _grid(c):
    st = c.sweep_settings()
    # one uniform grid per value (no edge insertion), so the study is one rectangular array
    return np.linspace(st["start"], st["stop"], st["steps"])


def _study_batch(cases, grids, bar):
    """Every (value, cage angle) state through ``solve_batch`` in chunks of the next power of two
    (at most :data:`STUDY_CHUNK`), the last one padded, so few batch shapes are ever compiled.
    Only loads, speed, the Fc/Mg switches and the cage angles differ between the values."""
    import jax
    import jax.numpy as jnp

    c0 = cases[0]
    b, spall, control = c0.bearing(), c0.spall(), c0.operation().control
    M, N = len(cases), grids[0].size
    ops, lds = [c.si("operation") for c in cases], [c.si("load") for c in cases]
    per_state = lambda v: np.repeat(np.asarray(v, float), N, axis=0)  # noqa: E731
    speed, cf, gy = (per_state([o[k] for o in ops]) for k in ("speed", "centrifugal", "gyroscopic"))
    loads = per_state(np.asarray(jones.load_vector(**{k: np.array([d[k] for d in lds]) for k in lds[0]})).T)
    angles = np.concatenate(grids)
    total = M * N
    chunk = min(1 << max(0, int(total - 1).bit_length()), STUDY_CHUNK)   # a power of two: few shapes
    parts = []
    for k in range(0, total, chunk):
        idx = np.minimum(np.arange(k, k + chunk), total - 1)      # pad the last chunk: one shape
        sol = jones.solve_batch(b, Operation(speed[idx], control, cf[idx], gy[idx]), loads[idx],
                                cage_angle=angles[idx], spall=spall, hertz_method=c0.hertz_method)
        n = min(chunk, total - k)
        parts.append(jax.tree_util.tree_map(lambda a: a[:n], sol))
        bar.update(n)
    flat = jax.tree_util.tree_map(lambda *a: jnp.concatenate(a), *parts)
    return jax.tree_util.tree_map(lambda a: a.reshape((M, N) + a.shape[1:]), flat)


def _study_sweep(c, grid):
    return sweeps.sweep(c.bearing(), c.operation(), c.loads(), c.spall(), angles=grid, hertz_method=c.hertz_method)


def _study_value(shared, m):
    """The sweep of study value ``m`` (one task of a study on a Dask cluster), as NumPy arrays."""
    import jax

    cases, grids = shared
    return jax.tree_util.tree_map(np.asarray, _study_sweep(cases[m], grids[m]))


def study_case(case, *, throw=True, progress=False, runner=None) -> Study:
    """One cage-angle sweep (the case's ``[sweep]`` grid, no edge insertion) per ``[study]`` value.

    Studies of a ``[load]``, ``[operation]`` or ``[sweep]`` key (loads, speed, the sweep angles)
    are solved as one batch: ``jones.solve_batch`` over every value and angle, in chunks of at
    most STUDY_CHUNK states (a value with a state that fails there is redone by continuation).
    Other keys (geometry, material, spall) run one compiled sweep per value; with ``runner`` (a
    :class:`bearingsim.datasets.distributed.DaskRunner`) those sweeps run on a Dask cluster, one value per
    task, with the same numbers (a batched study stays in this process: it is one vmapped solve
    already, docs/scale.md).  Raises InputError
    without ``[study]`` or for a key that changes the shape of the results (``bearing.balls``,
    ``sweep.steps``).

    A case with a ``[set]`` section: the set's state per value
    (:func:`bearingsim.app.sets.study_set_case` -> ``SetStudy``; one batched solve, in this process:
    ``progress`` and ``runner`` do not apply)."""
    if case.is_set:
        return sets.study_set_case(case, throw=throw)
    import jax

    spec = case.study_settings()
    if spec is None:
        raise InputError(f"{case.source}: no [study] section: add one, e.g.\n[study]\n"
                         'parameter = "operation.speed_rpm"\nvalues = [0, 5000, 10000]')
    param, values = spec
    if param in _SHAPE_KEYS:
        raise InputError(f"{case.source}: study.parameter = '{param}' changes {_SHAPE_KEYS[param]} "
                         "and so the shape of every result; run one sweep per value instead")
    cases = case.study_cases()
    grids = [_grid(c) for c in cases]
    batched = param.split(".")[0] in _BATCH_SECTIONS
    bar = _progress(len(cases) * grids[0].size, f"study {param}", "state", progress)
    try:
        if batched:
            sol = _study_batch(cases, grids, bar)
            for m in np.flatnonzero(np.any(np.asarray(sol.result) != 0, axis=1)):
                sol = _replace_row(sol, int(m), _study_sweep(cases[m], grids[m]))
        elif runner is not None:
            rows = [None] * len(cases)
            for m, row in runner.imap(_study_value, (cases, grids), range(len(cases))):
                rows[m] = row
                bar.update(grids[m].size)
            sol = _stack(rows)
        else:
            rows = []
            for c, grid in zip(cases, grids):
                rows.append(_study_sweep(c, grid))
                bar.update(grid.size)
            sol = _stack(rows)
    finally:
        bar.close()
    if throw:                                     # raise_for describes a flat batch
        _check(jax.tree_util.tree_map(lambda a: a.reshape((-1,) + a.shape[2:]), sol), case,
               f"the study of {param}", throw)
    return Study(param, list(values), unit_of(param), sol, batched)


def _stack(sols):
    import jax
    import jax.numpy as jnp

    return jax.tree_util.tree_map(lambda *a: jnp.stack(a), *sols)


def _replace_row(sol, m, row):
    import jax

    return jax.tree_util.tree_map(lambda a, r: a.at[m].set(r), sol, row)


# ----------------------------------------------------- commands: a single bearing or a set
# One entry per command that reads a case which may describe one bearing or a set: the case
# decides, so the command line (and a notebook that wants the command's outputs) has no set
# branch.  ``say`` receives each line the command prints (the text, then "wrote PATH" per file).
def _plot_dir(path):
    d = Path(path)
    d.mkdir(parents=True, exist_ok=True)
    return d


def info_text(case) -> str:
    """The text of ``bearingsim info``: the case's inputs and derived quantities, and for a set its
    bearings (positions, facings, preloads)."""
    text = bearing_info(case)
    if case.is_set:
        text += "\n" + sets.set_info_text(case)
    return text


def static_command(case, json_path=None, plot_path=None, *, say=print):
    """``bearingsim static``: the state of ``case`` (:func:`solve_case`: a single bearing or a set),
    its text said, its JSON record written to ``json_path`` and its polar plot to ``plot_path``
    (each None: not written).  Raises as :func:`solve_case` with ``throw=True``.  Returns the
    solution."""
    sol = solve_case(case)
    if case.is_set:
        say(sets.set_text(case, sol))
        if json_path:
            io.write_json(json_path, sets.set_to_dict(case, sol))
            say(f"wrote {json_path}")
        if plot_path:
            sets.plot_set_static(sol, title=case.title, path=plot_path)
            say(f"wrote {plot_path}")
        return sol
    assessment = assess_case(case, sol)
    say(static_text(case, sol, assessment))
    if json_path:
        io.write_static(json_path, sol, assessment)
        say("")
        say(f"wrote {json_path}")
    if plot_path:
        from ..output.plots import plot_static  # local: matplotlib (~1 s) only when a figure is asked for

        Path(plot_path).parent.mkdir(parents=True, exist_ok=True)
        plot_static(sol, title=case.title, spall=case.spall(), path=plot_path)
        say(f"wrote {plot_path}")
    return sol


def study_command(case, output, plot_dir=None, *, workers=None, scheduler=None, progress=True, say=print,
                  warn=None):
    """``bearingsim study``: the study of ``case`` (:func:`study_case`, ``throw=False``: a single
    bearing's sweeps, or a set's states) written to ``output`` (HDF5; a set's table also as CSV
    beside it), its text said, its figures drawn into ``plot_dir`` (None: none).  ``workers`` /
    ``scheduler``: the single-bearing sweeps on a Dask cluster (a set's study is one batched solve
    in this process).  ``warn(codes, what)`` receives the result codes (failed states are
    returned flagged, not raised).  Returns the study."""
    if case.is_set:
        study = study_case(case, throw=False)
        if warn:
            warn(study.solution.result, "study states")
        table = sets.set_study_table(case, study)
        sets.write_set_study(output, case, study, table)
        csv = Path(output).with_suffix(".csv")
        sets.write_set_study_csv(csv, case, study, table)
        say(sets.set_study_text(case, study))
        say(f"wrote {output}")
        say(f"wrote {csv}")
        if plot_dir:
            name = study.parameter.replace(".", "_") + ".png"
            p = _plot_dir(plot_dir) / ("study_set_" + name)
            sets.plot_set_study(study, title=case.title, path=p, table=table)
            say(f"wrote {p}")
            p = _plot_dir(plot_dir) / ("limits_set_" + name)
            sets.plot_set_limits(case, study, title=case.title, path=p)
            say(f"wrote {p}")
        return study
    if workers is None and scheduler is None:
        study = study_case(case, throw=False, progress=progress)
    else:
        from ..datasets.distributed import DaskRunner  # local: Dask (optional, ~1 s) only with workers

        with DaskRunner(workers=workers, scheduler=scheduler) as runner:
            study = study_case(case, throw=False, progress=progress, runner=runner)
    if warn:
        warn(study.solution.result, "study states")
    io.write_study(output, case, study)
    say(study_text(case, study))
    say(f"wrote {output}")
    if plot_dir:
        from ..output.plots import plot_study  # local: matplotlib (~1 s) only when a figure is asked for

        p = _plot_dir(plot_dir) / ("study_" + study.parameter.replace(".", "_") + ".png")
        plot_study(study.solution, study.values, study.parameter, study.unit, title=case.title,
                   spall=case.spall(), path=p)
        say(f"wrote {p}")
    return study


# ------------------------------------------------------------------------------- dynamics
def simulate_case(case, *, throw=True, progress=None, **kw):
    """The dynamic simulation of the case's ``[dynamics]`` (``bearingsim.dynamics.simulate_case``).
    Raises CaseError (an InputError) for a sample rate below twice the highest characteristic
    frequency of the case (:func:`bearingsim.case.check_sampling`)."""
    # local: importing the dynamics (and the data set engine, below) costs ~0.5 s of JAX set-up,
    # which only simulate, compare and dataset need: info, static, sweep and study start without it
    from .. import dynamics

    check_sampling(case)
    res = dynamics.simulate_case(case, progress=progress, throw=False, **kw)
    if throw and int(res.result) != 0:
        code = dynamics.RESULTS(int(res.result))
        raise dynamics.DynamicsError(f"{case.source}: the dynamic simulation failed: {code.message} after "
                                     f"{res.num_steps} steps", code.hint, code)
    return res


class Comparison(NamedTuple):
    """Result of :func:`compare_case`.  ``rows``: (quantity, unit, quasi-static, dynamic,
    dynamic / quasi-static or NaN where the quasi-static value is ~0)."""

    dynamic: object          # DynamicsResult
    indices: np.ndarray      # samples of the dynamic run that were compared
    quasi_static: object     # JonesSolution (len(indices),) at those cage angles
    rows: list


#: (quantity, unit, |quasi-static| below which no ratio is given, in that unit)
_COMPARED = (("Q_outer", "N", 1e-6), ("Q_inner", "N", 1e-6), ("alpha_outer", "deg", 1e-3),
             ("alpha_inner", "deg", 1e-3))


def compare_case(case, *, throw=True, max_angles=721) -> Comparison:
    """Quasi-static sweep at the cage angles of the dynamic run (subsampled to ``max_angles``),
    an inner spall or a ball pit turned to where it is at each of those instants, with peak
    values side by side.  Needs a ``[dynamics]`` section in the case file."""
    if "dynamics" not in case.raw:
        raise InputError(f"{case.source}: compare needs a [dynamics] section (duration_s, sample_rate_Hz)")
    res = simulate_case(case)
    th = np.asarray(res.cage_angle)
    idx = np.unique(np.linspace(0, len(th) - 1, min(len(th), max_angles)).astype(int))
    spall = case.spall()
    centers = None          # a turning defect: its centre at each compared instant too
    if spall is not None and spall.location in ("inner", "ball"):
        rate = 1.0 if spall.location == "inner" else float(res.spin_ratio)
        centers = float(spall.center) + rate * np.asarray(res.shaft_angle)[idx]
    qs = sweeps.sweep(case.bearing(), case.operation(), case.loads(), spall, angles=th[idx], centers=centers,
                      hertz_method=case.hertz_method)
    _check(qs, case, "the quasi-static sweep at the dynamic run's cage angles", throw)

    def ratio(d, s, tol):        # amplification only where the static value is not ~0
        return d / s if abs(s) > tol else np.nan

    rows = []
    for name, unit, tol in _COMPARED:
        d = from_si(np.asarray(getattr(res, name))[idx], unit)
        s = from_si(np.asarray(getattr(qs, name)), unit)
        rows.append((f"max {name}", unit, s.max(), d.max(), ratio(d.max(), s.max(), tol)))
        if name.startswith("alpha"):
            rows.append((f"min {name}", unit, s.min(), d.min(), ratio(d.min(), s.min(), tol)))
    qd = from_si(np.asarray(res.ring_displacement)[idx], "um")
    qq = from_si(np.asarray(qs.displacement)[:, :3], "um")
    for j, lab in enumerate(("x", "y", "axial")):
        amp_s, amp_d = np.ptp(qq[:, j]), np.ptp(qd[:, j])
        rows.append((f"peak-to-peak ring {lab}", "um", amp_s, amp_d, ratio(amp_d, amp_s, 1e-6)))
    return Comparison(res, idx, qs, rows)


def dataset_case(case, path, *, throw=True, progress=False, runner=None, device=None, chunk=None,
                 compression=None):
    """Simulate the case's ``[dataset]`` into ``path`` (HDF5; ``dataset.make_dataset``).  Items
    that failed are in the file with a zero signal and a code; ``throw`` raises after writing.
    ``runner``: a :class:`bearingsim.datasets.distributed.DaskRunner` to run the chunks on a Dask cluster
    (same file); None runs them in this process.  ``device`` ("cpu", "gpu", None: JAX's
    default), ``chunk`` (items per chunk; 0: fill the device) and ``compression`` (of /signals)
    as in ``make_dataset``."""
    from ..datasets.runner import make_dataset  # local: the data set engine loads the dynamics (above)

    summary = make_dataset(case, path, progress=progress, runner=runner, device=device, chunk=chunk,
                           compression=compression)
    if throw and summary.failed:
        raise NotConvergedError(f"{case.source}: {summary.failed} of {summary.count} items of the data "
                                f"set failed (written to {path} with labels/result != 0)")
    return summary


# ------------------------------------------------------------------------------- calibrate
def calibrate_case(healthy, output, *, template="dataset_cwru_4class", fault=None, fault_class=None,
                   channel=None, sample_rate=None, rpm=None, fault_rpm=None, unit=None, count=None,
                   duration_s=None, seed=None):
    """Calibrate a data set spec to the machine of a healthy record file (and at most one fault
    record file of a known class) and write it to ``output`` (TOML, atomically): see
    :mod:`bearingsim.realism.machine`.  Record files: .npz (a channel, fs, rpm, units), .npy, .csv / .txt;
    ``sample_rate`` / ``unit`` where the file does not say; ``rpm`` the healthy record's exact
    shaft speed (else searched near the .npz rpm or the template's speed).  Returns the
    ``MachineCalibration``."""
    # local: the machine fits load SciPy (scipy.signal, ~1-2 s), which only `bearingsim calibrate`
    # needs: every other command imports this module without it
    from ..realism.machine import calibrate_machine, write_spec

    tpl = load_case(template)
    x, fs, u, nominal, ch = read_record(healthy, channel, sample_rate, unit)
    kw = {}
    if fault is not None:
        if fault_class is None:
            raise InputError(f"{fault}: a fault record needs its class: --fault-class outer|inner|ball")
        y, ffs, _, _, _ = read_record(fault, ch if str(fault).lower().endswith(".npz") else None,
                                      sample_rate, u)
        kw = dict(fault=y, fault_class=fault_class, fault_sample_rate=ffs, fault_rpm=fault_rpm)
    elif fault_class is not None:
        raise InputError(f"--fault-class {fault_class} without a fault record (--fault RECORD)")
    cal = calibrate_machine(x, fs, tpl, unit=u, shaft_rpm=rpm, nominal_rpm=nominal, count=count,
                            duration_s=duration_s, seed=seed, source=str(healthy),
                            fault_source=str(fault), **kw)
    cal.fault["channel"] = ch
    write_spec(cal, output)
    return cal


# ------------------------------------------------------------------------------- spectra
def envelope_band(sample_rate, resonance_hz):
    """Demodulation band around the structural resonance (kept below 0.45 x the sample rate)."""
    return select_band(np.zeros(16), sample_rate, resonance_hz=min(resonance_hz, 0.45 * sample_rate))


def simulation_spectrum(res, case):
    """Squared-envelope spectrum of a simulation's sensor signal, in the case's resonance band."""
    d = case.dynamics_settings()
    return envelope_spectrum(np.asarray(res.sensor_acceleration), d["sample_rate"],
                             band=envelope_band(d["sample_rate"], d["resonance_frequency"]))


class EnvelopeAnalysis(NamedTuple):
    """Result of :func:`spectrum_file` (frequencies in Hz)."""

    source: str
    samples: int
    sample_rate: float
    duration: float           # s
    band: tuple
    spectrum: object          # signal.EnvelopeSpectrum
    frequencies: dict         # shaft_Hz, ftf_Hz, bpfo_Hz, bpfi_Hz, bsf_Hz of the simulation
    peak: float               # envelope peak near the fault frequency
    harmonics: list           # (k, measured Hz, amplitude) of k x the fault frequency
    fault: str = "BPFO"       # the defect's line: BPFO (outer race, healthy), BPFI (inner), 2BSF (ball)
    fault_hz: float = 0.0     # its frequency (Hz)
    markers: dict = None      # name -> Hz: the line, its sidebands, FTF / shaft (signal.fault_lines)


def spectrum_file(path, *, resonance_hz=3000.0) -> EnvelopeAnalysis:
    """Envelope analysis of a ``bearingsim simulate`` output: the peak near the defect's own line
    (BPFO for an outer-race spall or a healthy bearing, BPFI for an inner-race spall, 2 BSF for a
    ball pit: :func:`bearingsim.signals.envelope.fault_lines`) and its harmonics.  The band is centred on
    the stored case's resonance (else ``resonance_hz``)."""
    sim = io.read_simulation(path)
    t, a, fr = sim["time"], sim["sensor_acceleration"], sim["frequencies"]
    fs = 1.0 / float(t[1] - t[0])
    location = None
    if sim["case"] is not None:
        resonance_hz = sim["case"].dynamics_settings()["resonance_frequency"]
        sp = sim["case"].spall()
        location = None if sp is None else sp.location
    band = envelope_band(fs, resonance_hz)
    es = envelope_spectrum(a, fs, band=band)
    name, f0, markers = fault_lines(fr, location)
    try:
        fp = peak_frequency(es, f0, rel_window=0.05)
    except ValueError as e:
        raise NotConvergedError(f"{path}: no envelope peak near {name} {f0:.3f} Hz: {e}") from None
    return EnvelopeAnalysis(str(path), t.size, fs, float(t[-1] - t[0]) + 1.0 / fs, band, es, fr, fp,
                            harmonic_peaks(es, f0, n=5, rel_window=0.03), name, f0, markers)
