"""Time integration of the shaft/housing model: fixed steps in compiled chunks (the default),
or the adaptive diffrax reference.

Fixed steps ``h = 1 / (substeps * sample_rate)`` in a ``lax.scan`` over chunks of :data:`CHUNK`
samples; the stage angles are computed on the device from the drawn motion and h is an array,
so no duration, sample rate or chunk recompiles.  The default scheme ``"newmark"``: central difference
in x, trapezoidal in v for the (linear) damping -- one bearing-force evaluation per step, second
order.  A ball crossing a rectangular defect edge inside a step (times known in advance from the
motion, :func:`bearingsim.dynamics.defect_edge_times`) is integrated exactly: the force step
weights the velocity update by where it falls (theta, 1 - theta instead of 1/2, 1/2) and the
sensor modes see a step at that instant (:func:`bearingsim.dynamics.sensor.filter_update`), so an edge
costs nothing extra (no step rejection, no lax.cond: batches stay in lockstep).  ``"heun"`` /
``"rk4"`` are explicit Runge-Kutta alternatives without edge handling (first order at
rectangular edges).  The state at each step's start gives the outputs and the sensor filter's
input at no extra cost.

The sensor path (one or more structural modes, :mod:`bearingsim.dynamics.sensor`) is linear and one-way
coupled: it is applied exactly to the housing acceleration ``a_h,x`` on the step grid
(first-order-hold discretisation), not integrated, so it never limits the step.

``run_adaptive``: the reference -- diffrax Tsit5 with a PID controller, the defect edges as
``jump_ts``, and the sensor modes integrated in the ODE (optionally with their reaction on the
housing, ``coupling=True``, resonator mass ``m_r g_k`` per mode).
"""
from __future__ import annotations

import threading

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from . import sensor as sensor_mod
from ..errors import InputError
from ..programs import jit
from ..xla import compiler_options
from .ball_force import initial_ball_carry
from .model import DynamicModel
from .motion import Motion, motion_at, pad_knots

__all__ = ["SCHEMES", "CHUNK", "check_scheme", "time_grid", "run_fixed", "precompile_fixed", "run_adaptive",
           "stage_grid", "motion_stages", "edge_fractions", "advance_record"]

#: explicit Runge-Kutta schemes: (c, a, b)
SCHEMES = {
    "heun": ((0.0, 1.0), ((), (1.0,)), (0.5, 0.5)),
    "rk4": ((0.0, 0.5, 0.5, 1.0), ((), (0.5,), (0.0, 0.5), (0.0, 0.0, 1.0)),
            (1 / 6, 1 / 3, 1 / 3, 1 / 6)),
    # Newmark average acceleration in v / central difference in x (velocity Verlet with the
    # linear damping trapezoidal): second order, one bearing-force evaluation per step
    "newmark": ((0.0, 1.0), None, None),
}
#: samples per compiled chunk of the time loop
CHUNK = 1024


def check_scheme(scheme):
    """Refuse an unknown integration scheme (InputError)."""
    if scheme not in SCHEMES:
        raise InputError(f"scheme must be one of {sorted(SCHEMES)}, got {scheme!r}")


def _advance(model: DynamicModel, carry, stages, jumps, h, flt, scheme: str, record: bool = False,
             chord: bool = False, lean: bool = False):
    """Advance over a chunk: ``stages`` (N, S, n_c, 3) motion at the non-zero stage points of
    every step, ``jumps`` (N, S) the fraction of the step at which a ball crosses a rectangular
    spall edge (-1: none).  carry = (y, dy, s, rec): state, its derivative, sensor-mode states,
    the balls' record (RECORD_ROWS, Z) at y (:meth:`DynamicModel.ring_load`; only with
    ``record``: Newmark takes it from the step's own force evaluation, the Runge-Kutta schemes
    evaluate it once more).  Returns the new carry and per sample (y, a_h (2), sensor[, rec])
    at the sample instant (``lean``: (a_h x, sensor) only)."""
    c, a, b = SCHEMES[scheme]
    cs = sorted(set(c) - {0.0})
    idx = [None if ci == 0.0 else cs.index(ci) for ci in c]
    last = cs.index(1.0)
    if scheme == "newmark":
        mass = model.masses()
        MC = model.damping_matrix() / mass[:, None]
        P = jnp.linalg.inv(jnp.eye(5) + 0.5 * h * MC)

    def step(carry, st, th):
        y, k1, s = carry[:3]
        rec = carry[3] if record else None
        bc = carry[-1] if chord else None
        if scheme == "newmark":
            # x: central difference; v: the damping trapezoidal (implicit, linear), the forces
            # weighted by where they jump (a step at theta h: weights theta, 1 - theta; none:
            # 1/2, 1/2) -- one bearing-force evaluation per step
            x, v, acc = y[:5], y[5:], k1[5:]
            F0 = acc + MC @ v
            wgt = jnp.where(th >= 0.0, th, 0.5)
            x1 = x + h * v + 0.5 * h * h * acc
            if chord:       # the balls from the carried positions; a defect edge: in full
                F1, rec_c, bc = model.forces(x1, st[last], chord=(bc, th >= 0.0))
                rec = rec_c if record else None
            else:
                F1 = model.forces(x1, st[last], full_state=record)
                F1, rec = F1 if record else (F1, None)
            F1 = F1 / mass
            v1 = P @ (v - 0.5 * h * (MC @ v) + h * (wgt * F0 + (1.0 - wgt) * F1))
            acc1 = F1 - MC @ v1
            y1, k1n = jnp.concatenate([x1, v1]), jnp.concatenate([v1, acc1])
            s = sensor_mod.filter_update(flt, s, k1[8], k1n[8], th, h)
        else:
            ks = [k1]
            for i in range(1, len(c)):
                yi = y + h * sum(a[i][j] * ks[j] for j in range(i) if a[i][j] != 0.0)
                ks.append(model.rhs(yi, st[idx[i]]))
            y1 = y + h * sum(bi * ki for bi, ki in zip(b, ks))
            k1n = model.rhs(y1, st[last])
            s = sensor_mod.filter_update(flt, s, k1[8], k1n[8])
            if record:
                rec = model.forces(y1[:5], st[last], full_state=True)[1]
        return (y1, k1n, s) + ((rec,) if record else ()) + ((bc,) if chord else ()), None

    def sample(carry, xs):
        st_sample, th_sample = xs
        y, k1, s = carry[:3]
        if lean:
            out = (k1[8], sensor_mod.filter_output(flt, s, k1[8]))
        else:
            out = (y, k1[8:10], sensor_mod.filter_output(flt, s, k1[8])) + ((carry[3],) if record else ())
        for j in range(st_sample.shape[0]):         # substeps: a static, small count
            carry, _ = step(carry, st_sample[j], th_sample[j])
        return carry, out

    return lax.scan(sample, carry, (stages, jumps))


_advance_jit = jit(_advance)


def _advance_device(model, carry, m, edges, k0, h, flt, scheme, substeps, fs, record, chord):
    """:func:`_advance` over samples k0..k0+CHUNK-1 with the stage and jump arrays built in the
    program from the :class:`Motion` ``m`` and the padded edge times (no host arrays per
    chunk)."""
    Z = model.bearing.n_balls
    stages = motion_stages(m, Z, k0, CHUNK, fs, scheme, substeps)
    jumps = edge_fractions(edges, k0, CHUNK, substeps, h)
    return _advance(model, carry, stages, jumps, h, flt, scheme, record, chord)


_advance_device_jit = jit(_advance_device)


def _pad_to(n, block=256):
    return block * (n // block + 1)


def _stage_grid(scheme, substeps):
    c = SCHEMES[scheme][0]
    cs = np.array(sorted(set(c) - {0.0}))
    j = np.arange(substeps)
    return (j[:, None] + cs[None, :]) / substeps          # (S, n_c) in samples


def stage_grid(scheme, substeps):
    """(S, n_c) stage points of every sample's steps, in samples (the non-zero stage points of
    the scheme; Newmark: the end of each step)."""
    return _stage_grid(scheme, substeps)


def motion_stages(m, Z, k0, n, fs, scheme, substeps):
    """The motion of the :class:`Motion` ``m`` (cage angle, shaft angle, shaft speed) at
    the stage points of samples k0..k0+n-1 (jit/vmap; ``n``, ``scheme``, ``substeps`` static;
    ``k0`` may be traced): (n, S, n_c, 3)."""
    grid = jnp.asarray(_stage_grid(scheme, substeps))
    t = (k0 + jnp.arange(n, dtype=jnp.float64)[:, None, None] + grid[None]) / fs
    return jnp.stack(motion_at(m, Z, t), axis=-1)


def edge_fractions(edges, k0, n, substeps, h):
    """(n, S) fraction of each step of samples k0..k0+n-1 at which a defect edge is crossed
    (-1: none; jit/vmap); ``edges`` ascending, padded with +inf."""
    steps = ((k0 + jnp.arange(n, dtype=jnp.float64))[:, None] * substeps
             + jnp.arange(substeps, dtype=jnp.float64)[None, :])
    t0 = steps * h
    i = jnp.searchsorted(edges, t0.ravel(), side="left").reshape(t0.shape)
    te = jnp.where(i < edges.shape[0], edges[jnp.minimum(i, edges.shape[0] - 1)], jnp.inf)
    frac = (te - t0) / h
    return jnp.where(frac < 1.0, frac, -1.0)


def advance_record(model, carry, stages, jumps, h, flt, scheme, record=False, chord=False, lean=False):
    """The time loop over the samples of ``stages`` (n, S, n_c, 3) / ``jumps`` (n, S) as a pure
    function (one ``lax.scan``; for use inside a compiled program): (carry, outputs) as
    :func:`_advance`."""
    return _advance(model, carry, stages, jumps, h, flt, scheme, record, chord, lean)


def time_grid(duration, sample_rate):
    n = int(round(float(duration) * float(sample_rate)))
    if n < 2:
        raise InputError(f"duration {duration} s at {sample_rate} Hz gives {n} samples; need at least 2")
    return np.arange(n) / float(sample_rate)


def run_fixed(model, y0, dy0, motion, edges, fs, T, scheme, substeps, progress, rec0=None, ball_solver="full"):
    """Chunked fixed-step integration of one model: its drawn :class:`Motion` ``motion`` and
    the rectangular defects' edge times ``edges``; the stages and jumps of each chunk are built
    on the device from the motion (the data set's chunk program builds them the same way, for
    the whole record).  Returns host arrays y (T, 10), a_h (T, 2), sensor (T,), the number of
    steps, with the balls' record at t = 0 ``rec0`` (RECORD_ROWS, Z) the per-sample records
    (T, RECORD_ROWS, Z) (else None), and the ball solver's counters (a dict: ``full_steps``,
    ``rejected_steps``, ``worst_residual``; None without the chord method).

    ``ball_solver``: "full" (every step from the closed form, :func:`bearing_force`) or "chord"
    (one model with the Newmark scheme only: the balls' positions carried from step to step,
    :func:`bearingsim.dynamics.bearing_force_chord`, a full solve at defect edges and wherever
    a chord step misses its tolerance)."""
    h = 1.0 / (substeps * fs)
    f, z, g = model.params.modes()
    flt = sensor_mod.host_sensor_filter(f, z, g, h)
    record = rec0 is not None
    chord = ball_solver == "chord" and scheme == "newmark"
    carry = (y0, dy0, np.zeros(np.shape(f) + (2,))) + ((np.asarray(rec0, np.float64),) if record else ()) + (
        (initial_ball_carry(model.bearing.n_balls),) if chord else ())
    outs = []
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=T, desc="simulate", unit="sample", unit_scale=True, dynamic_ncols=True)
    md = pad_knots(motion, 256)
    e = np.asarray(edges, float)
    edges_dev = jax.device_put(np.concatenate([e, np.full(_pad_to(e.size) - e.size, np.inf)]))
    for k0 in range(0, T, CHUNK):
        n = min(CHUNK, T - k0)
        carry, out = _advance_device_jit(model, carry, md, edges_dev, np.float64(k0), np.float64(h), flt,
                                         scheme, int(substeps), float(fs), record, chord)
        outs.append(out)            # stays on the device until the end (no round trip per chunk)
        if bar is not None:
            jax.block_until_ready(carry[0])
            bar.update(n)
    # fetched once, joined on the host (no device ops to compile)
    outs = [jax.tree_util.tree_map(lambda *a: np.concatenate([np.asarray(x) for x in a], axis=0)[:T], *outs)]
    if bar is not None:
        bar.close()
    y = np.concatenate([o[0] for o in outs], axis=-2)
    ah = np.concatenate([o[1] for o in outs], axis=-2)
    sens = np.concatenate([o[2] for o in outs], axis=-1)
    recs = np.concatenate([o[3] for o in outs], axis=0) if record else None
    stats = None
    if chord:
        bc = carry[-1]
        stats = dict(full_steps=int(bc.full), rejected_steps=int(bc.rejected), worst_residual=float(bc.worst))
    return y, ah, sens, T * substeps, recs, stats


_PRECOMPILED = set()


def precompile_fixed(model, y0, motion, edges, fs, scheme, substeps, rec0=None, ball_solver="full"):
    """Compile the time loop's program for one model in a background thread and return the
    thread (join it before :func:`run_fixed`), or None when this configuration was compiled
    before in this process.  XLA releases the GIL while it compiles, so on a second core this
    overlaps the compilation of the equilibrium at t = 0 (a first simulation: ~1 s).  The thread
    runs one chunk from ``y0`` at rest (``rec0``: a record of the right shape, or None) and
    discards it; an error there is the loop's own and is raised by the real run."""
    leaves, tree = jax.tree_util.tree_flatten(model)
    key = (tree, tuple(np.shape(a) for a in leaves), scheme, int(substeps), rec0 is None, ball_solver)
    if key in _PRECOMPILED:
        return None
    _PRECOMPILED.add(key)
    y0 = np.asarray(y0, np.float64)

    def run():
        try:
            run_fixed(model, y0, np.zeros_like(y0), motion, edges, fs, CHUNK, scheme, substeps, False,
                      None if rec0 is None else np.zeros(np.shape(rec0)), ball_solver)
        except Exception:       # noqa: BLE001 -- the real run raises it
            pass

    th = threading.Thread(target=run, name="bearingsim-precompile", daemon=True)
    th.start()
    return th


def run_adaptive(model, y0, m: Motion, ts, jumps, rtol, atol, coupling):
    """Reference: diffrax Tsit5 + PID (+ spall edges as jump_ts), sensor modes in the ODE."""
    import diffrax

    f, z, g = (np.asarray(v) for v in model.params.modes())
    w = 2 * np.pi * jnp.asarray(f)
    zz, gg = jnp.asarray(z), jnp.asarray(g)
    mr = model.params.resonator_mass * gg if coupling else jnp.zeros_like(gg)
    M = len(f)
    mj = jax.tree_util.tree_map(lambda a: jnp.asarray(a) if isinstance(a, np.ndarray) else a, m)
    scale = jnp.concatenate([jnp.full(5, 1e-6), jnp.full(5, 1e-3), jnp.full(M, 1e-9), jnp.full(M, 1e-6)])

    def full(t, u):
        y = u * scale
        st = jnp.stack(motion_at(mj, model.bearing.n_balls, t))
        zk, vk = y[10:10 + M], y[10 + M:]
        Fk = mr * (w * w * zk + 2 * zz * w * vk)
        dy = model.rhs(y[:10], st, jnp.sum(Fk))
        ah = dy[8]
        ak = -2 * zz * w * vk - w * w * zk - ah
        return jnp.concatenate([dy, vk, ak]), ah, ak

    term = diffrax.ODETerm(lambda t, u, args: full(t, u)[0] / scale)
    ctrl = diffrax.PIDController(rtol=rtol, atol=atol, pcoeff=0.2, icoeff=0.4)
    if len(jumps):
        ctrl = diffrax.ClipStepSizeController(ctrl, jump_ts=jnp.asarray(jumps))
    u0 = jnp.concatenate([y0, jnp.zeros(2 * M)]) / scale
    sol = diffrax.diffeqsolve(term, diffrax.Tsit5(), ts[0], ts[-1], None, u0,
                              saveat=diffrax.SaveAt(ts=jnp.asarray(ts)), stepsize_controller=ctrl,
                              max_steps=1 << 24, throw=False)
    us = sol.ys

    def post(t, u):
        du, ah, ak = full(t, u)
        return u[:10] * scale[:10], du[8:10], ah + jnp.sum(gg * ak)

    y, ah, sens = jax.jit(jax.vmap(post), compiler_options=compiler_options())(jnp.asarray(ts), us)
    return np.asarray(y), np.asarray(ah), np.asarray(sens), int(sol.stats["num_steps"])
