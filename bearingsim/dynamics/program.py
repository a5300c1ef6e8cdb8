"""A chunk of data set items as compiled device programs (issue 25): :func:`chunk_program`.

Every item is a pure function of its ``jax.random`` key and its label arrays.  One call of the
returned :class:`ChunkProgram` runs, vmapped over the chunk's items, without host work per item
and without a host round trip inside the record:

1. ``prepare`` (one program): the items' quasi-static states (a second pass with 8 speed stages
   for the items that failed, inside the program), their defect frequencies and spin ratios,
   and the ball solver's error for every Newton step count of :data:`ITER_CHOICES` per item
   (the check of :func:`bearingsim.dynamics.choose_ball_iterations`, vmapped: 12 cage angles
   over a ball pitch plus a ball over the item's defect, the ring displaced +-5 %).
2. The host reads one integer: the smallest count of :data:`MENU` that meets
   :data:`ITER_TOL` for every item of the chunk (an explicit ``jax.device_get`` of a scalar).
3. ``run`` (one program for every count of the menu: the count is a traced integer, the bound
   of the ball solver's Newton loop): per item the
   motion from its key (:func:`bearingsim.dynamics.draw_motion`), the defect edge and
   pass times as padded arrays, the model's equilibrium at t = 0, the sensor filter of its own
   modes, and the whole record's time loop (one ``lax.scan`` over the samples; the stage and
   jump arrays computed on the device).

The outputs are device arrays (a dict, see :meth:`ChunkProgram.__call__`).  Measurement noise,
background, pass-to-pass variability and the fault-level scaling are not applied here: the
signal stage takes ``housing_acceleration``, ``sensor`` and ``pass_times`` from here.
"""
from __future__ import annotations

import threading

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from . import sensor as sensor_mod
from ..physics.defect import LOCATIONS, Spall
from ..physics.hertz import stiffness_curve
from ..physics.jones import solve_state
from ..keys import item_keys
from ..physics.kinematics import Operation
from ..physics.pit import pit_of_solution
from ..programs import jit
from .ball_force import ITER_CHOICES, ITER_TOL, ball_errors
from .exposure import ball_track
from .integrate import advance_record, check_scheme, edge_fractions, motion_stages
from .frequencies import state_frequencies
from .model import build_model, initial_state
from .motion import (MOTION_STREAM, defect_times, draw_motion, knot_count, motion_at, motion_labels, motion_ok,
                     motion_realism, pass_count)
from .parameters import RESULTS, Realism
from ..errors import failed, succeeded

__all__ = ["MENU", "MOTION_STREAM", "item_keys", "ChunkProgram", "chunk_program", "iterations_needed", "menu_iterations"]

#: the Newton step counts a chunk's time loop may run (data to one compiled program)
MENU = (1, 2, 4, 8, 16)


def _slots(loc, center, extent, depth, profile, slots):
    return tuple(Spall(jnp.where(loc == LOCATIONS.index(L), center, 0.0), jnp.where(loc == LOCATIONS.index(L), extent, 0.0),
                       jnp.where(loc == LOCATIONS.index(L), depth, 0.0), profile, L, 0) for L in slots)


def _check_angles(bearing, loc, theta0, center, extent, k):
    """The 18 (cage angle, shaft angle) pairs of :func:`choose_ball_iterations` for one item:
    12 over a ball pitch, then a ball over the item's defect (its centre and 40 % of its
    half-extent to either side; a ball pit turned into both contacts), padded by repetition."""
    Z = bearing.n_balls
    base = theta0 + jnp.linspace(0.0, 2 * np.pi / Z, 12, endpoint=False)
    u = jnp.stack([0.0 * extent, -0.4 * extent, 0.4 * extent])
    outer_a = jnp.concatenate([center + u, jnp.repeat(center + u[-1:], 3)])
    inner_p = jnp.concatenate([theta0 - center - u, jnp.repeat(theta0 - center - u[-1:], 3)])
    ks = jnp.where(k > 0, k, 1.0)
    ball_p = jnp.stack([(t - center - uu) / ks for uu in (u[0], u[1], u[2]) for t in (0.0, np.pi)])
    six = jnp.ones(6)
    ang = jnp.where(loc == 1, outer_a, jnp.where((loc == 2) | ((loc == 3) & (k > 0)), theta0 * six, base[-1] * six))
    phi = jnp.where(loc == 2, inner_p, jnp.where((loc == 3) & (k > 0), ball_p, 0.0 * six))
    return jnp.concatenate([base, ang]), jnp.concatenate([jnp.zeros(12), phi])


def _states(bearing, curve, speed_rpm, loads, theta0, loc, center, extent, depth, profile, slots, control,
            hertz_method, speed_steps):
    n = speed_rpm.shape[0]
    one = jnp.ones(n)
    op = Operation(2 * np.pi * speed_rpm / 60.0, control, one, one)
    defects = _slots(loc, center, extent, depth, profile, slots)
    sols = jax.vmap(lambda o, F, th, sp: solve_state(bearing, o, F, cage_angle=th, spall=sp, speed_steps=speed_steps,
                                                     curve=curve, hertz_method=hertz_method))(op, loads, theta0, defects)
    return op, defects, sols


_states_jit = jit(_states)


def _merge(sols, retry):
    take = failed(sols.result) & succeeded(retry.result)
    return jax.tree_util.tree_map(lambda a, b: jnp.where(take.reshape(take.shape + (1,) * (a.ndim - 1)), b, a),
                                  sols, retry)


_merge_jit = jit(_merge)


def _prepare(bearing, curve, op, defects, sols, theta0, loc, center, extent, depth):
    n = op.speed.shape[0]
    freqs, a_m, k = jax.vmap(lambda w, s: state_frequencies(bearing, w, s))(op.speed, sols)

    # the ball solver's error per Newton step count (choose_ball_iterations, per item)
    code = jnp.zeros(n, jnp.int32)
    for i, L in enumerate(LOCATIONS):
        code = jnp.where(loc == LOCATIONS.index(L), i + 1, code)
    code = jnp.where(depth > 0, code, 0)                 # 0 healthy, 1 outer, 2 inner, 3 ball

    def errs(o, q, sp, th, c, e, kk, cd):
        ang, phi = _check_angles(bearing, cd, th, c, e, kk)
        return ball_errors(bearing, o, q, sp, curve, ang, jnp.array([0.95, 1.0, 1.05]), phi, kk)

    err = jax.vmap(errs)(op, sols.displacement, defects, theta0, center, extent, k, code)
    needed = iterations_needed(err, succeeded(sols.result))
    return dict(op=op, defects=defects, sols=sols, freqs=freqs, contact_angle=a_m, spin_ratio=k,
                ball_errors=err, needed=needed, chunk_needed=jnp.max(jnp.where(needed == 0, MENU[-1], needed)),
                failed=jnp.any(failed(sols.result)))


_prepare_jit = jit(_prepare)


def _states_prepare(bearing, curve, speed_rpm, loads, theta0, loc, center, extent, depth, profile, slots, control,
                    hertz_method, pit=None, keep_depth=False):
    """The items' states and the ball check.  ``pit`` (pit diameter, machined depth) (N,) each,
    or None: each fault item's pit is then put under its healthy contact, with ball 0 at the pit
    (an outer pit) or at azimuth 0 (an inner or ball pit), solved first in the same program
    (the two solves are one ``lax.scan`` of two passes, so the solve is traced once), which
    gives its effective depth and unbridged fraction (:func:`bearingsim.physics.pit.pit_of_solution`).
    The defective solve then takes the effective depth (``depth`` only marks the fault items:
    > 0), or with ``keep_depth`` the ``depth`` given (depth_rule "machined": the unbridged
    fraction is then only the pass-to-pass variability's scale, and an item whose healthy state
    failed gets 0)."""
    if pit is None:
        op, defects, sols = _states(bearing, curve, speed_rpm, loads, theta0, loc, center, extent, depth, profile,
                                    slots, control, hertz_method, 1)
        out = _prepare(bearing, curve, op, defects, sols, theta0, loc, center, extent, depth)
        out.update(depth=depth, pit_depth=depth, unbridged=jnp.zeros_like(depth), pit_ok=jnp.ones(depth.shape, bool))
        return out
    w, machined = pit
    fault = depth > 0
    th_pit = jnp.where(loc == LOCATIONS.index("outer"), center, 0.0)

    def one_pass(carry, _):
        d, th = carry
        op, defects, sols = _states(bearing, curve, speed_rpm, loads, th, loc, center, extent, d, profile, slots,
                                    control, hertz_method, 1)
        dp, u = jax.vmap(lambda s_, L, ww, mm: pit_of_solution(s_, bearing, 0, L, ww, mm))(sols, loc, w, machined)
        ok = succeeded(sols.result)
        dp = jnp.where(fault & ok, dp, 0.0)
        nxt = jnp.where(fault, depth, 0.0) if keep_depth else dp
        return (nxt, theta0), (op, defects, sols, dp, jnp.where(fault & ok, u, 0.0), ok | ~fault)

    _, (op, defects, sols, dp, u, ok) = lax.scan(one_pass, (jnp.zeros_like(depth), th_pit), None, length=2)
    take = lambda tree, k: jax.tree_util.tree_map(lambda a: a[k], tree)  # noqa: E731
    op, defects, sols = take(op, 1), take(defects, 1), take(sols, 1)
    d_eff = jnp.where(fault, depth, 0.0) if keep_depth else dp[0]
    out = _prepare(bearing, curve, op, defects, sols, theta0, loc, center, extent, d_eff)
    out.update(depth=d_eff, pit_depth=d_eff, unbridged=u[0], pit_ok=jnp.ones_like(ok[0]) if keep_depth else ok[0])
    return out


_states_prepare_jit = jit(_states_prepare)


def iterations_needed(errors, valid, tol=ITER_TOL):
    """Per item the smallest count of :data:`ITER_CHOICES` whose error (``errors`` (N, 6)) is
    within ``tol`` (0 where none is; invalid items 1): device arrays."""
    ok = errors <= tol
    first = jnp.argmax(ok, axis=-1)
    its = jnp.where(jnp.any(ok, axis=-1), jnp.asarray(ITER_CHOICES)[first], 0)
    return jnp.where(valid, its, 1)


def menu_iterations(needed):
    """The chunk's count: the smallest of :data:`MENU` at least every item's (``needed``, host
    ints; 0 -- no count suffices -- takes the largest)."""
    m = int(np.max(np.where(np.asarray(needed) == 0, MENU[-1], needed), initial=1))
    return next(c for c in MENU if c >= m)


def _run(bearing, curve, prep, keys, loads, theta0, modes, params, iterations, substeps, T, fs, scheme, realism,
         n_knots, P, profile):
    sols, defects, op = prep["sols"], prep["defects"], prep["op"]
    Z = bearing.n_balls
    h = 1.0 / (substeps * fs)
    f_m, z_m, g_m = modes
    params = eqx.tree_at(lambda q: (q.resonance_frequency, q.resonance_damping_ratio, q.resonance_gain), params,
                         (f_m, z_m, g_m))

    def one(key, o, F, sp, sol, p, k, th, fm, zm, gm, needed, pit_ok):
        model = build_model(bearing, o, F, sp, sol, p, curve, iterations, k)
        wc = jnp.where(jnp.isfinite(sol.cage_speed) & (sol.cage_speed > 0), sol.cage_speed, 0.0)
        centre = next((s.center for s in sp if s.location == "outer"), 0.0)
        m = draw_motion(jax.random.fold_in(key, MOTION_STREAM), Z, th, wc, o.speed, (T - 1) / fs, centre, realism,
                               n_knots)
        st0 = jnp.stack(motion_at(m, Z, jnp.zeros(())), -1)
        y0, ok, dy0, _ = initial_state(model, sol.displacement[:3], st0)
        if profile == "rectangular":
            edges, e_ok = defect_times(m, Z, sp, k, T / fs, P, ("lo", "hi"))
            edges = edges[:2 * P]
        else:
            edges, e_ok = jnp.full((1,), jnp.inf), jnp.bool_(True)
        passes, p_ok = defect_times(m, Z, sp, k, (T - 1) / fs, P, ("mid",))
        passes = passes[:P]
        flt = sensor_mod.sensor_filter(fm, zm, gm, h)
        stages = motion_stages(m, Z, 0, T, fs, scheme, substeps)
        jumps = edge_fractions(edges, 0, T, substeps, h)
        carry = (y0, dy0, jnp.zeros(fm.shape + (2,)))
        _, (ah, sens) = advance_record(model, carry, stages, jumps, h, flt, scheme, lean=True)
        code = jnp.where(failed(sol.result) | ~pit_ok, RESULTS.initial_state.value,
                         jnp.where(~ok, RESULTS.initial_equilibrium.value, 0))
        fits = motion_ok(m, Z, T / fs) & e_ok & p_ok
        code = jnp.where(succeeded(code) & ~fits, RESULTS.fixed_size.value, code)
        code = jnp.where(succeeded(code) & (needed == 0), RESULTS.ball_solver.value, code)
        finite = jnp.all(jnp.isfinite(ah)) & jnp.all(jnp.isfinite(sens))
        code = jnp.where(succeeded(code) & ~finite, RESULTS.nonfinite.value, code)
        good = succeeded(code)
        lab = motion_labels(m)
        return dict(sensor=jnp.where(good, sens, 0.0), housing_acceleration=jnp.where(good, ah, 0.0),
                    result=code.astype(jnp.int32), pass_times=jnp.where(good, passes, jnp.inf),
                    pass_jitter_percent=lab["pass_jitter_percent"],
                    speed_fluctuation_frequencies_Hz=m.fluct_freqs, cage_speed=jnp.where(good, wc, jnp.nan))

    out = jax.vmap(one)(keys, op, loads, defects, sols, params, prep["spin_ratio"], theta0, f_m, z_m, g_m,
                        prep["needed"], prep["pit_ok"])
    out.update(prep["freqs"].hz())
    out["contact_angle"] = prep["contact_angle"]
    for k_ in ("pit_depth", "unbridged", "pit_ok"):
        out[k_] = prep[k_]
    out["spin_ratio"] = prep["spin_ratio"]
    column = jnp.argmax(jnp.asarray(ITER_CHOICES) == iterations)      # iterations: a count of MENU
    out["ball_error"] = jnp.take_along_axis(prep["ball_errors"], jnp.full((keys.shape[0], 1), column), axis=1)[:, 0]
    return out


_run_jit = jit(_run)


def _ball_tracks(bearing, sols, defects):
    """(N, 7) every item's :func:`bearingsim.dynamics.exposure.ball_track` (issue 33): a program of
    its own, run only when asked, so that the other programs stay as they were."""
    pit_extent = next((sp.extent for sp in defects if sp.location == "ball"), jnp.zeros(sols.beta.shape[0]))
    return jax.vmap(lambda s_, e: ball_track(bearing, s_, e))(sols, pit_extent)


_ball_tracks_jit = jit(_ball_tracks)


class ChunkProgram:
    """The compiled programs of one data set configuration (:func:`chunk_program`)."""

    def __init__(self, bearing, *, slots, profile, control, hertz_method, sample_rate, samples, substeps, scheme,
                 realism, max_speed_rpm):
        check_scheme(scheme)
        self.bearing, self.slots, self.profile = bearing, tuple(slots), profile
        self.control, self.hertz_method = control, hertz_method
        self.fs, self.T, self.substeps, self.scheme = float(sample_rate), int(samples), int(substeps), scheme
        self.realism = Realism() if realism is None else realism
        # the bearing (NumPy outside a program: bearingsim.hostarrays) and its curve go to the
        # default device once, not with every call of the programs
        self.bearing, self.curve = jax.device_put((bearing, stiffness_curve(bearing, hertz_method)))
        a = float(self.realism.speed_fluctuation_percent) / 100.0
        sigma = float(self.realism.slip_percent) / 100.0
        dur = self.T / self.fs
        shaft = float(max_speed_rpm) / 60.0
        self.n_knots = knot_count(bearing.n_balls, 0.5 * shaft, dur, a)
        self.P = pass_count(shaft, dur, bearing, a, sigma)
        self.calls = 0          # device programs launched (a test counts them)
        self._count = threading.Lock()      # micro-batches may run in threads

    def prepare(self, speed_rpm, loads, theta0, location, center, extent, depth, pit=None, keep_depth=False):
        """The items' quasi-static states and the ball solver's check (device arrays).  Items
        whose state failed are solved again with 8 speed stages, all of them in a second
        program that runs (and compiles) only when a chunk has one: the host reads one bool."""
        args = (self.bearing, self.curve, speed_rpm, loads, theta0, location, center, extent, depth, self.profile,
                self.slots, self.control, self.hertz_method)
        prep = _states_prepare_jit(*args, pit, bool(keep_depth))
        args = args[:8] + (prep["depth"],) + args[9:]
        self._add(1)
        if bool(jax.device_get(prep["failed"])):      # rare: the second pass
            sols = _merge_jit(prep["sols"], _states_jit(*args, 8)[2])
            keep = {k: prep[k] for k in ("depth", "pit_depth", "unbridged", "pit_ok")}
            prep = _prepare_jit(self.bearing, self.curve, prep["op"], prep["defects"], sols, theta0, location, center,
                                extent, keep["depth"])
            prep.update(keep)
            self._add(3)
        return prep

    def _add(self, n):
        with self._count:
            self.calls += n

    def run(self, prep, keys, loads, theta0, modes, params, iterations):
        self._add(1)
        # the count is data (a traced int32): one compiled time loop serves every count of MENU
        return _run_jit(self.bearing, self.curve, prep, keys, loads, theta0, modes, params,
                        jax.device_put(np.int32(int(iterations))),
                        self.substeps, self.T, self.fs, self.scheme, motion_realism(self.realism), self.n_knots, self.P,
                        self.profile)

    def __call__(self, keys, speed_rpm, loads, theta0, location, center, extent, depth, modes, params,
                 iterations=None, pit=None, keep_depth=False, track=False):
        """Simulate one chunk: ``keys`` (N, 2) uint32 (``jax.random`` keys, one per item),
        ``speed_rpm`` (N,), ``loads`` (N, 5) N / N m, ``theta0`` (N,) cage angle at t = 0 (rad),
        ``location`` (N,) int (index in :data:`bearingsim.physics.defect.LOCATIONS`), ``center``,
        ``extent`` (rad) and ``depth`` (m) (N,) of the item's defect (depth 0: healthy),
        ``modes`` ((N, M) frequencies Hz, damping ratios, gains), ``params`` a
        :class:`DynamicsParameters` whose fields are (N,) arrays (its modes are not used:
        ``modes``); ``iterations``: a fixed Newton step count, or None (the chunk's own from
        :data:`MENU`).  Returns a dict of device arrays: ``sensor`` (N, T) m/s^2 through the
        item's sensor modes (no noise, no background, no pass variability),
        ``housing_acceleration`` (N, T) x, ``result`` (N,) :class:`RESULTS` codes (failed
        items: zero signals), ``pass_times`` (N, P) s ascending, +inf padded,
        ``pass_jitter_percent``, ``speed_fluctuation_frequencies_Hz`` (N, K), ``cage_speed``,
        ``shaft_Hz``, ``ftf_Hz``, ``bpfo_Hz``, ``bpfi_Hz``, ``bsf_Hz``, ``contact_angle``,
        ``spin_ratio``, ``ball_error`` (N,), with ``track`` ``ball_track`` (N, 7:
        :func:`bearingsim.dynamics.exposure.ball_track`, the kinematic exposure's geometry, one more
        program), ``pit_depth`` (m; the depth simulated),
        ``unbridged`` and ``pit_ok`` (N,) and ``ball_iterations`` (the host int used).
        ``pit``: None, or (pit diameter, machined depth) (N,) m each for ``depth_rule = "pit"``:
        every fault item's depth is then its pit's effective depth at its own healthy contact,
        computed in the same program (``depth`` only marks the fault items: > 0); an item whose
        healthy state failed has ``pit_ok`` False and result ``initial_state``.  ``keep_depth``
        (with ``pit``): simulate ``depth`` as given and take only the pits' unbridged fractions
        from their healthy contacts (depth_rule "machined" with the pass-to-pass variability)."""
        prep = self.prepare(speed_rpm, loads, theta0, location, center, extent, depth, pit, keep_depth)
        if iterations is None:
            iterations = menu_iterations([int(jax.device_get(prep["chunk_needed"]))])
        out = self.run(prep, keys, loads, theta0, modes, params, iterations)
        out["ball_iterations"] = int(iterations)
        if track:
            self._add(1)
            out["ball_track"] = _ball_tracks_jit(self.bearing, prep["sols"], prep["defects"])
        return out


def chunk_program(bearing, *, slots=LOCATIONS, profile="rectangular", control="outer", hertz_method="exact",
                  sample_rate=48000.0, samples=4800, substeps=1, scheme="newmark", realism: Realism | None = None,
                  max_speed_rpm=1800.0) -> ChunkProgram:
    """The device programs of one data set configuration (static: the bearing, the defect
    ``slots`` the items may use, the profile, raceway control, Hertz method, sample rate, the
    number of ``samples`` per item, ``substeps`` per sample, the scheme, and the fastest shaft
    speed with the realism's slip and speed fluctuation, which size the slip walk and the pass
    lists; the slip and fluctuation values themselves are data of the time loop,
    :func:`bearingsim.dynamics.motion_realism`).  Call the result per chunk
    (:meth:`ChunkProgram.__call__`); equal shapes reuse the compiled programs."""
    return ChunkProgram(bearing, slots=slots, profile=profile, control=control, hertz_method=hertz_method,
                        sample_rate=sample_rate, samples=samples, substeps=substeps, scheme=scheme, realism=realism,
                        max_speed_rpm=max_speed_rpm)
