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
============================ =========================================== ======================

The workflows of time signals (``simulate_case``, ``compare_case``, ``dataset_case``,
``calibrate_case``, ``spectrum_file``) are :mod:`bearingsim.app.signal_workflows`.

A case with a ``[set]`` section (a shaft on several bearings) goes through the same entries:
:func:`solve_case` and :func:`study_case` dispatch on the case, and the command entries
:func:`info_text`, :func:`static_command` and :func:`study_command` do a command's whole work
(solve, text, files, figures) for a single bearing or a set alike, so the command line has no
set branch.

Errors are the classes of :mod:`bearingsim.errors`: bad input raises ``InputError``; with
``throw=True`` (the default) a failed solve raises ``NotConvergedError`` naming the case file,
with ``throw=False`` the result is returned with its codes (per item for batches).  Nothing here
prints, writes files or draws, except the command entries (which say their lines through ``say`` and write the files
they are given, through :mod:`bearingsim.output.io`, :mod:`bearingsim.output.report`, :mod:`bearingsim.output.plots`
and, for a set, :mod:`bearingsim.output.set_report` and :mod:`bearingsim.output.plots_set`; the set's
computation is :mod:`bearingsim.app.set_workflows`).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..case import as_scenario, unit_of
from ..errors import failed, InputError, succeeded
from ..output import io
from ..output.report import info_text as bearing_info, static_text, study_text
from ..physics import jones
from ..physics import sweep as sweeps
from ..physics.kinematics import Operation
from ..output import plots_set, set_report
from . import set_workflows as sets
from .assessment import Assessment, assess_state

__all__ = ["solve_case", "info_text", "static_command", "study_command", "assess_case", "Assessment", "sweep_case",
           "study_case", "Study", "STUDY_CHUNK", "check_solution", "free_tilt_only"]

#: quasi-static states solved together by :func:`study_case` (the last chunk is padded)
STUDY_CHUNK = 1024

def _progress(total, desc, unit, progress):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, disable=None if progress else True, dynamic_ncols=True)


def check_solution(sol, case, what, throw):
    """With ``throw``, raise NotConvergedError / InvalidStateError for a quasi-static solution
    (single or batch) with a failed item, naming the case file, the reason and the count;
    ``throw="all"``: only when every item failed (a sweep with no valid state at all has the
    verdict of a single solve, e.g. a reverse axial load)."""
    if throw == "all":
        throw = bool(np.all(failed(np.asarray(sol.result))))
    if throw:
        sc = as_scenario(case)
        jones.raise_for(sol, f"{sc.source}: {what}", bearing=sc.bearing)
    return sol


# ------------------------------------------------------------------------------------ solve
def solve_case(case, *, throw=True):
    """The quasi-static state of ``case`` at its cage angle (``bearingsim static``): a
    ``JonesSolution``, or for a case with a ``[set]`` section the set's ``SetSolution``
    (:func:`bearingsim.app.set_workflows.solve_set_case`).  The verdict is the core's
    (:func:`bearingsim.physics.jones.solve`: a loaded contact centred at or beyond a shoulder edge is
    result 8, or 7 at an angular contact bearing's low edge, healthy or with a defect; a set's
    bearings are checked by the same rule); nothing is decided here."""
    sc = as_scenario(case)
    if sc.is_set:
        return sets.solve_set_case(sc, throw=throw)
    sol = jones.solve(sc.bearing, sc.operation, sc.loads, cage_angle=sc.cage_angle,
                      spall=sc.spall, hertz_method=sc.hertz_method, throw=False, tilt=sc.tilt)
    return check_solution(sol, sc, "the quasi-static solve", throw)


def free_tilt_only(case, command):
    """Refuse a held tilt (``operation.tilt = "held"``) where ``command`` solves a free ring only:
    ``bearingsim static`` (:func:`solve_case`) and the Python API solve it, the sweeps, studies,
    simulations and data sets do not (never a free ring's answer to a held case)."""
    sc = as_scenario(case)
    if sc.tilt == "held":
        raise InputError(f'{sc.source}: operation.tilt = "held" is not supported by {command}: it solves a '
                         'free (force-controlled) ring; allowed here: "free"',
                         'solve the held ring with `bearingsim static` (solve_case), or set operation.tilt = '
                         '"free" for this command')


def assess_case(case, sol) -> Assessment:
    """Per-contact limits (docs/model.md section 11: pressure, the friction raceway control needs, the
    ellipse against the shoulders) and, when the case gives ``bearing.dynamic_load_rating_kN``,
    the ISO/TS 16281 rating life of the state ``sol`` of ``case`` (single state;
    :func:`bearingsim.app.assessment.assess_state`, the rule each bearing of a set is assessed by)."""
    sc = as_scenario(case)
    return assess_state(sc.bearing, sc.operation, sol, sc.limits, healthy=sc.spall is None)


def sweep_case(case, *, throw=True, progress=False, resolve_edges=True):
    """Quasi-static states over the case's ``[sweep]`` cage angles (both sides of every
    rectangular-spall edge inserted unless ``resolve_edges=False``).  ``throw``: True raises for
    any failed angle, ``"all"`` (``bearingsim sweep``) only when every angle failed, False never
    (codes per angle)."""
    sc = as_scenario(case)
    free_tilt_only(sc, "the cage-angle sweep")
    b, spall, st = sc.bearing, sc.spall, sc.sweep
    angles = sweeps.sweep_angles(b, spall, st["start"], st["stop"], st["steps"], resolve_edges)
    bar = _progress(len(angles), "sweep", "angle", progress)
    try:
        sol = sweeps.sweep_chunked(b, sc.operation, sc.loads, spall, angles, progress=bar.update,
                                   hertz_method=sc.hertz_method)
    finally:
        bar.close()
    return check_solution(sol, sc, "the cage-angle sweep", throw)


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
        return succeeded(np.asarray(self.solution.result))

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
    (:func:`bearingsim.app.set_workflows.study_set_case` -> ``SetStudy``; one batched solve, in this process:
    ``progress`` and ``runner`` do not apply)."""
    if case.is_set:
        return sets.study_set_case(case, throw=throw)
    free_tilt_only(case, "a study")
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
            for m in np.flatnonzero(np.any(failed(np.asarray(sol.result)), axis=1)):
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
        check_solution(jax.tree_util.tree_map(lambda a: a.reshape((-1,) + a.shape[2:]), sol), case,
               f"the study of {param}", throw)
    return Study(param, list(values), unit_of(param), sol, batched)


def _stack(sols):
    import jax

    # NumPy: one eager JAX program per field otherwise (bearingsim.hostarrays)
    return jax.tree_util.tree_map(lambda *a: np.stack([np.asarray(v) for v in a]), *sols)


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
        text += "\n" + set_report.set_info_text(case)
    return text


def static_command(case, json_path=None, plot_path=None, *, say=print):
    """``bearingsim static``: the state of ``case`` (:func:`solve_case`: a single bearing or a set),
    its text said, its JSON record written to ``json_path`` and its polar plot to ``plot_path``
    (each None: not written).  Raises as :func:`solve_case` with ``throw=True``.  Returns the
    solution."""
    sol = solve_case(case)
    if case.is_set:
        assessment = sets.assess_set_case(case, sol)
        say(set_report.set_text(case, sol, assessment))
        if json_path:
            io.write_json(json_path, set_report.set_to_dict(case, sol, assessment))
            say(f"wrote {json_path}")
        if plot_path:
            plots_set.plot_set_static(sol, title=case.title, path=plot_path)
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
        set_report.write_set_study(output, case, study, table)
        csv = Path(output).with_suffix(".csv")
        set_report.write_set_study_csv(csv, study, table)
        say(set_report.set_study_text(case, study))
        say(f"wrote {output}")
        say(f"wrote {csv}")
        if plot_dir:
            name = study.parameter.replace(".", "_") + ".png"
            p = _plot_dir(plot_dir) / ("study_set_" + name)
            plots_set.plot_set_study(study, title=case.title, path=p, table=table)
            say(f"wrote {p}")
            p = _plot_dir(plot_dir) / ("limits_set_" + name)
            plots_set.plot_set_limits(study, sets.study_limits(case, study), title=case.title, path=p)
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
