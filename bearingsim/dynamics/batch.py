"""Many simulations in lockstep (vmap over items of the fixed-step loop): :func:`simulate_batch`.

Items of different defect classes share one compiled program: the model carries one defect
*slot* per location (outer, inner, ball; a depth-0 slot is inactive), so a four-class data set
compiles once.  The Newton step count of the ball solve and the substeps are fixed for the batch
(:func:`batch_settings`), so chunks of a data set never recompile.
"""
from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..signals import sensor as sensor_mod
from ..physics.defect import LOCATIONS, Spall
from ..errors import InputError
from ..physics.hertz import stiffness_curve
from ..physics.jones import solve, solve_state
from ..physics.kinematics import Operation
from ..physics.newton import converged_only, retry_failed
from ..programs import jit
from .ball_force import ITER_CHOICES, choose_ball_iterations, next_iterations
from .integrate import check_scheme, run_fixed, time_grid
from .model import build_model, choose_substeps, initial_state, linear_modes
from .motion import defect_edge_times, defect_pass_times, draw_motion, motion_at, motion_labels, seed_streams
from .parameters import RESULTS, DynamicsParameters, Realism
from .simulate import characteristic_frequencies, rectangular, slip_reference, spin_ratio, vary_sensor

__all__ = ["DynamicsBatchResult", "defect_slots", "extreme_items", "batch_settings", "quasi_static_batch",
           "simulate_batch"]


class DynamicsBatchResult(NamedTuple):
    """Output of :func:`simulate_batch` (N items, T samples; host arrays)."""

    time: np.ndarray                    # (T,) s
    sensor_acceleration: np.ndarray     # (N, T) m/s^2 (with noise)
    ring_displacement: np.ndarray       # (N, T, 3) m
    result: np.ndarray                  # (N,) RESULTS codes
    num_steps: np.ndarray               # (N,)
    cage_speed: np.ndarray              # (N,) rad/s (quasi-static, nominal)
    bpfo_Hz: np.ndarray                 # (N,)
    realism: list                       # (N,) dicts: labels of the realism draws
    bpfi_Hz: np.ndarray = np.nan        # (N,)
    bsf_Hz: np.ndarray = np.nan         # (N,) ball spin frequency (a pit meets a race at 2 BSF)
    shaft_Hz: np.ndarray = np.nan       # (N,)


def _take(tree, i):
    return jax.tree_util.tree_map(lambda a: a[i], tree)


def defect_slots(location, center, extent, depth, profile="rectangular", slots=None):
    """One :class:`Spall` per slot location (a tuple, batched arrays): item i's defect sits in the
    slot of ``location[i]`` ("outer", "inner", "ball"; a ball pit on ball 0 with ``center`` its
    spin angle), every other slot of item i has depth 0.  ``slots``: the locations the program
    carries (default: those in ``location``, in the order of ``LOCATIONS``)."""
    loc = np.asarray(location)
    bad = sorted(set(loc.ravel().tolist()) - set(LOCATIONS))
    if bad:
        raise InputError(f"defect location must be one of {LOCATIONS}, got {bad}")
    slots = tuple(L for L in LOCATIONS if L in set(loc.ravel().tolist())) if slots is None else tuple(slots)
    out = []
    for L in slots:
        mine = jnp.asarray(loc == L)
        out.append(Spall(jnp.where(mine, center, 0.0), jnp.where(mine, extent, 0.0),
                         jnp.where(mine, depth, 0.0), profile, L, 0))
    return tuple(out)


def extreme_items(groups, speed, load, size):
    """Indices of the items that bound a batch, per group (defect class or location): the
    fastest and the slowest, the most and the least loaded, the largest defect.  The ball Newton
    step count and the substeps checked on them hold for every item between them."""
    groups, speed, load, size = (np.asarray(a) for a in (groups, speed, load, size))
    out = set()
    for g in np.unique(groups):
        ii = np.flatnonzero(groups == g)
        for v in (speed, -speed, load, -load, size):
            out.add(int(ii[np.argmax(v[ii])]))
    return sorted(out)


def _qs_batch(bearing, op, loads, theta0, defects, hertz_method, speed_steps):
    curve = stiffness_curve(bearing, hertz_method)

    def one(o, F, th, sp):
        return solve_state(bearing, o, F, cage_angle=th, spall=sp, speed_steps=speed_steps, curve=curve,
                           hertz_method=hertz_method)

    return jax.vmap(one)(op, loads, theta0, defects)


_qs_batch_jit = jit(_qs_batch)


def quasi_static_batch(bearing, op, loads, theta0, defects, hertz_method="exact"):
    """The items' quasi-static states (a batched :class:`bearingsim.JonesSolution`, ``result``
    per item): ``op`` with (N,) speeds, ``loads`` (N, 5), ``theta0`` (N,) cage angles,
    ``defects`` the slots of :func:`defect_slots` (batched arrays).  Items that fail are retried
    once with 8 speed stages (only them).  The program is the one :func:`simulate_batch` uses
    (same shapes, same program: a healthy solve of a data set's items with depth-0 slots costs no
    compilation)."""
    sols = _qs_batch_jit(bearing, op, loads, theta0, defects, hertz_method, 1)
    # retry the failed items with 8 speed stages (only them; padded: one compiled retry shape)
    return retry_failed(sols, lambda idx: _qs_batch_jit(bearing, _take(op, idx), loads[idx], theta0[idx],
                                                       _take(defects, idx), hertz_method, 8), converged_only)


_init_batch_jit = jit(jax.vmap(initial_state))


def batch_settings(bearing, op, loads, spall, theta0, sample_rate, params=None, hertz_method="exact"):
    """(ball_iterations, substeps) for items like this one (a single item's quasi-static state
    checked with :func:`choose_ball_iterations` and :func:`choose_substeps`); fix them once for
    a data set so that no chunk recompiles.  ``spall``: None, a Spall or a tuple (slots)."""
    params = DynamicsParameters() if params is None else params
    curve = stiffness_curve(bearing, hertz_method)
    sol = solve(bearing, op, loads, cage_angle=theta0, spall=spall, hertz_method=hertz_method, throw=False)
    if int(sol.result) != 0:
        return None, None
    _, a_m = characteristic_frequencies(bearing, op, sol)
    k = spin_ratio(bearing, a_m)
    it, _ = choose_ball_iterations(bearing, op, sol.displacement, spall, curve, theta0, spin_ratio=k)
    it = it or ITER_CHOICES[-1]
    model = build_model(bearing, op, loads, (), sol, params, curve, it)
    lam = np.abs(linear_modes(model))
    return it, choose_substeps(np.max(lam[np.isfinite(lam)], initial=0.0), sample_rate)


def simulate_batch(bearing, speed_rpm, loads, spall_center, spall_extent, spall_depth,
                   profile="rectangular", params: DynamicsParameters | None = None, duration=0.1,
                   sample_rate=48000.0, theta0=0.0, *, location="outer", slots=None,
                   realism: Realism | None = None, seeds=None, control="outer", hertz_method="exact",
                   scheme="newmark", substeps=None, ball_iterations=None, unbridged=None,
                   strike=None) -> DynamicsBatchResult:
    """N simulations in lockstep (vmap over items of the fixed-step loop): same bearing (Z),
    defect profile, duration and sample rate.

    ``speed_rpm`` (N,), ``loads`` (N, 5), ``spall_center``/``spall_extent`` (rad),
    ``spall_depth`` (m) (N,) each; ``location`` "outer" | "inner" | "ball" or (N,) of them (a
    ball pit's ``spall_center`` is its spin angle, on ball 0); ``slots`` the locations the
    compiled program carries (:func:`defect_slots`; pass all a data set uses so that every
    chunk shares one program); ``params`` fields may be scalars or (N,) ((N, M) for the modes);
    ``seeds`` (N,) the items' realism seeds (default 0..N-1).  ``unbridged`` (N,): each item's
    pit's unbridged fraction (:func:`bearingsim.physics.pit.pit_unbridged_fraction`, needed when
    ``realism`` has the pass-to-pass variability on; :func:`bearingsim.dynamics.vary_sensor`).
    ``strike`` (N,) or None: each item's probability that its pit strikes on a pass (ball pits
    whose spin axis wanders; :func:`bearingsim.signals.passes.strike_mask`).  Never raises for an item:
    ``result`` is per item.  ``ball_iterations``/``substeps`` None: :func:`batch_settings` on
    the extreme items of each location (:func:`extreme_items`), the largest count."""
    check_scheme(scheme)
    realism = Realism() if realism is None else realism
    loads = jnp.asarray(loads, jnp.float64)
    n = loads.shape[0]
    if realism.pass_variation and unbridged is None:
        raise InputError("simulate_batch: the pass-to-pass variability is on (Realism."
                         "pass_amplitude_cv_max_percent / pass_delay_sd_max_percent) but no unbridged "
                         "fraction was given; pass unbridged=(N,) (bearingsim.physics.pit.pit_unbridged_fraction)")
    bc = lambda v: jnp.broadcast_to(jnp.asarray(v, jnp.float64), (n,))
    params = DynamicsParameters() if params is None else params
    f, z, g = params.modes()
    M = f.shape[-1]
    params = eqx.tree_at(lambda p: (p.resonance_frequency, p.resonance_damping_ratio, p.resonance_gain),
                         params, tuple(jnp.broadcast_to(v, (n, M)) for v in (f, z, g)))
    params = jax.tree_util.tree_map(lambda a: a if a.ndim == 2 else bc(a), params)
    speed = np.broadcast_to(np.asarray(speed_rpm, float), (n,))
    op = Operation(bc(2 * np.pi * speed / 60.0), control, bc(1.0), bc(1.0))
    loc = np.broadcast_to(np.asarray(location), (n,))
    defects = defect_slots(loc, bc(spall_center), bc(spall_extent), bc(spall_depth), profile, slots)
    th = bc(theta0)
    fs = float(sample_rate)
    ts = time_grid(duration, fs)
    T = ts.size
    seeds = np.arange(n) if seeds is None else np.asarray(seeds)
    if ball_iterations is None or substeps is None:
        its, subs = [], []
        absF = np.abs(np.asarray(loads)).sum(1)
        for i in extreme_items(loc, speed, absF, np.asarray(spall_extent) * np.asarray(spall_depth) + np.zeros(n)):
            it_i, s_i = batch_settings(bearing, _take(op, i), loads[i], _take(defects, i), float(th[i]), fs,
                                       _take(params, i), hertz_method)
            if it_i is not None:
                its.append(it_i)
                subs.append(s_i)
        ball_iterations = ball_iterations or next_iterations(its)
        substeps = substeps or max(subs, default=1)
    sols = quasi_static_batch(bearing, op, loads, th, defects, hertz_method)
    freqs, a_m = characteristic_frequencies(bearing, op, sols)
    k_spin = spin_ratio(bearing, a_m)
    curve = stiffness_curve(bearing, hertz_method)
    bearing_b = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (n,) + jnp.shape(a)), bearing)
    curve_b = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (n,) + jnp.shape(a)), curve)
    model = build_model(bearing_b, op, loads, defects, sols, params, curve_b, int(ball_iterations),
                        jnp.asarray(k_spin))
    omega_c = np.asarray(sols.cage_speed)
    okc = np.isfinite(omega_c) & (omega_c > 0)
    host = jax.tree_util.tree_map(np.asarray, defects)      # per-item defects, host copies
    items = [_take(host, i) for i in range(n)]
    motions = [draw_motion(int(seeds[i]), bearing.n_balls, float(th[i]), float(omega_c[i]) if okc[i] else 0.0,
                           float(op.speed[i]), ts[-1], slip_reference(items[i]), realism) for i in range(n)]
    st0 = jnp.asarray(np.stack([np.stack(motion_at(m, np.zeros(1)), -1)[0] for m in motions]))
    y0, ok, dy0, _ = _init_batch_jit(model, sols.displacement[:, :3], st0)
    edges = [defect_edge_times(mm, rectangular(items[i]), ts[-1] + 1.0 / fs, k_spin[i])
             for i, mm in enumerate(motions)]
    y, ah, sens, nsteps, _, _ = run_fixed(model, y0, dy0, motions, edges, fs, T, scheme, int(substeps), True, False)
    code = np.where(np.asarray(sols.result) != 0, int(RESULTS.initial_state),
                    np.where(~np.asarray(ok), int(RESULTS.initial_equilibrium), int(RESULTS.successful)))
    finite = np.all(np.isfinite(y), axis=(1, 2)) & np.all(np.isfinite(sens), axis=1)
    code = np.where((code == 0) & ~finite, int(RESULTS.nonfinite), code)
    sens = np.where(code[:, None] == 0, sens, 0.0)        # a failed item is flagged, never used
    labels = [motion_labels(m, realism) for m in motions]
    intermittent = strike is not None and bool(np.any(np.asarray(strike) < 1.0))
    if realism.pass_variation or intermittent:
        active = [tuple(sp for sp in items[i] if sp.location == loc[i]) for i in range(n)]
        passes = [defect_pass_times(m, active[i], ts[-1], k_spin[i]) for i, m in enumerate(motions)]
        u = np.where(code == 0, np.broadcast_to(np.asarray(0.0 if unbridged is None else unbridged, float), (n,)), 0.0)
        p = None if strike is None else np.where(code == 0, np.broadcast_to(np.asarray(strike, float), (n,)), 1.0)
        sens = vary_sensor(ah[..., 0], sens, fs, passes, realism, u, seeds, params.modes(), labels, p)
    for i, m in enumerate(motions):
        if realism.noise_rms > 0.0:
            sens[i] += sensor_mod.measurement_noise(seed_streams(int(seeds[i]))[3], T, realism.noise_rms, fs,
                                                    realism.noise_band)
    rel = np.stack([y[..., 0] - y[..., 3], y[..., 1] - y[..., 4], y[..., 2]], axis=-1)
    wc = np.where(okc, omega_c, np.nan)
    return DynamicsBatchResult(ts, sens, rel, code.astype(np.int32), np.full(n, nsteps), wc,
                               bearing.n_balls * wc / (2 * np.pi), labels, freqs["bpfi_Hz"], freqs["bsf_Hz"],
                               freqs["shaft_Hz"])
