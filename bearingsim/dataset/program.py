"""The device program of a data set: one chunk of items in, its signals and simulated labels out.

:func:`simulate_chunk` (plan, k) is the unit of work (in-process and on the Dask workers).  It
pads chunk ``k`` to ``plan.chunk`` items (one compiled program for every chunk) and calls
:func:`device_program` once: the one place that calls the dynamics batch
(:func:`bearingsim.dynamics.simulate_batch`) and the signal stage (:func:`signal_stage`:
background, fault-level (SNR) scaling, flags).  The integrator plugs the jitted dynamics batch
and the pure-JAX signal stage in here; nothing else in the package changes.

Also here: the per-item inputs the program needs before it runs (the pit effective depths,
:func:`pit_depths`, and the run settings, :func:`run_settings`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import dynamics
from ..case.units import to_si
from .spec import DatasetResult, item_locations

__all__ = ["CHUNK_FIELDS", "BACKGROUND_FIELDS", "Physics", "BackgroundSpec", "background_spec", "item_background",
           "device_program", "signal_stage", "simulate_chunk", "pit_depths", "pit_depths_batch", "run_settings"]

BACKGROUND_FIELDS = ("background_noise_rms_m_s2", "background_shaft_rms_m_s2", "background_line_rms_m_s2",
                     "background_knock_rate_Hz")
#: the per-item label fields a chunk file carries (besides index and signals)
CHUNK_FIELDS = ("result", "bpfo_Hz", "bpfi_Hz", "bsf_Hz", "pass_jitter_percent", "pass_delay_sd_percent",
                "pass_amplitude_cv_percent", "signal_gain", "snr_dB") + BACKGROUND_FIELDS


@dataclass(frozen=True, eq=False)
class Physics:
    """The built physics objects every item of a data set shares (SI; no case file)."""

    bearing: object
    params: object              # dynamics.DynamicsParameters
    realism: object             # dynamics.Realism
    control: str
    hertz_method: str
    cage_angle: float
    profile: str

    @classmethod
    def of_case(cls, case):
        d = case.dynamics_settings()
        return cls(case.bearing(), dynamics.DynamicsParameters.from_settings(d), dynamics.Realism.from_settings(d),
                   case.data["operation"]["raceway_control"], case.hertz_method, float(case.cage_angle),
                   case.data.get("defect", {}).get("profile", "rectangular"))


@dataclass(frozen=True)
class BackgroundSpec:
    """The data set's ``background`` setting: ``kind`` "machine" (``fixed``: the case's
    [background]) or "random" (drawn per item, broadband rms in ``rms`` m/s^2)."""

    kind: str
    fixed: object = None
    rms: tuple = (0.2, 2.0)


def background_spec(case, ds):
    """The :class:`BackgroundSpec` of the [dataset] ``background`` key (None for "none")."""
    from .. import background as bgm

    kind = ds.get("background", "none")
    if kind == "none":
        return None
    fixed = None
    if kind == "machine":
        sec = case.si("background") if "background" in case.data else {}
        fixed = bgm.Background(tuple(sec.get("shaft_amplitudes") or ()), float(sec.get("line_frequency", 60.0)),
                               tuple(sec.get("line_amplitudes") or ()), float(sec.get("noise_rms", 0.0)),
                               tuple(sec.get("psd_frequencies") or ()), tuple(sec.get("psd_levels") or ()),
                               tuple(sec.get("modulation_depths") or ()), float(sec.get("knock_rate", 0.0)),
                               float(sec.get("knock_amplitude", 0.0)), float(sec.get("knock_frequency", 3000.0)),
                               float(sec.get("knock_damping_ratio", 0.05)))
    return BackgroundSpec(kind, fixed, tuple(ds.get("background_rms_m_s2", (0.2, 2.0))))


def item_background(spec, fs):
    """A function (realism seed, shaft Hz, T) -> (background record, labels) of ``spec`` (a
    :class:`BackgroundSpec`; None for none)."""
    from .. import background as bgm

    if spec is None:
        return None

    def draw(seed, shaft_hz, T):
        rng = np.random.default_rng(np.random.SeedSequence([int(seed), 11]))
        bg = spec.fixed if spec.kind == "machine" else bgm.random_background(rng, fs, {"noise_rms_m_s2": spec.rms})
        return bgm.background_signal(rng, T, fs, shaft_hz, bg), bg.as_labels()
    return draw


def signal_stage(a, fault_class, gain, snr_target, seeds, speed_rpm, fs, background, fault_snr):
    """Sensor signals of a chunk from the dynamics' (m, T) accelerations ``a``: each item's
    background added, its fault level scaled (the drawn ``gain``, or with ``fault_snr`` the gain
    that puts the fault signal ``snr_target`` dB over the item's background).  Returns (signals,
    gain, snr_dB, background labels).  The background records are drawn per item from the seeds
    (host NumPy) until the pure-JAX signal stage replaces this function."""
    m, T = a.shape
    gain = np.asarray(gain, float).copy()
    bg_labels = {k: np.zeros(m) for k in BACKGROUND_FIELDS}
    if background is None:
        return a * gain[:, None], gain, np.zeros(m), bg_labels
    draw = item_background(background, fs)
    x = np.zeros_like(a)
    for j in range(m):                       # host draws: replaced by the device signal stage
        x[j], lb = draw(seeds[j], speed_rpm[j] / 60.0, T)
        for k in BACKGROUND_FIELDS:
            bg_labels[k][j] = lb[k]
    s = np.sqrt(np.mean((a - a.mean(1, keepdims=True)) ** 2, axis=1))
    rb = np.sqrt(np.mean(x * x, axis=1))
    with np.errstate(divide="ignore", invalid="ignore"):
        if fault_snr:
            gain = np.where((fault_class > 0) & (s > 0.0), 10.0 ** (snr_target / 20.0) * rb / s, gain)
        snr = np.where((s > 0.0) & (rb > 0.0), 20.0 * np.log10(gain * s / rb), 0.0)
    return gain[:, None] * a + x, gain, snr, bg_labels


def device_program(plan, pad):
    """The chunk's program on the padded item indices ``pad`` (``plan.chunk`` of them): the
    dynamics batch, then the signal stage.  Returns a dict of (chunk,) / (chunk, T) host arrays."""
    import equinox as eqx

    p, ph, lab = plan, plan.physics, plan.lab
    params = ph.params
    if p.modes is not None:
        params = eqx.tree_at(lambda q: (q.resonance_frequency, q.resonance_damping_ratio, q.resonance_gain),
                             params, tuple(np.asarray(p.modes[pad][..., j]) for j in range(3)))
    strike = lab["strike_probability"][pad]
    loads = np.zeros((pad.size, 5))
    loads[:, 0], loads[:, 2] = lab["radial_N"][pad], lab["axial_N"][pad]
    res = dynamics.simulate_batch(
        ph.bearing, lab["speed_rpm"][pad], loads, p.center[pad], p.extent[pad], p.depth[pad], ph.profile, params,
        p.duration, p.fs, ph.cage_angle, location=p.loc[pad], slots=p.slots, realism=ph.realism,
        seeds=lab["realism_seed"][pad], control=ph.control, hertz_method=ph.hertz_method,
        ball_iterations=p.ball_iterations, substeps=p.substeps, unbridged=p.unbridged[pad],
        strike=strike if np.any(strike < 1.0) else None)
    a = np.asarray(res.sensor_acceleration, float)
    sig, gain, snr, bg = signal_stage(a, lab["fault_class"][pad], lab["signal_gain"][pad], lab["snr_dB"][pad],
                                      lab["realism_seed"][pad], lab["speed_rpm"][pad], p.fs, p.background,
                                      p.fault_snr)
    code = np.asarray(res.result).astype(np.int32)
    code = np.where((code == 0) & ~np.all(np.isfinite(sig), axis=1), int(DatasetResult.nonfinite_signal), code)
    code = np.where(p.pit_ok[pad], code, int(DatasetResult.pit_contact))
    ok = code == 0
    n = pad.size
    rl = res.realism
    out = dict(signals=np.where(ok[:, None], sig, 0.0).astype(np.float32), result=code,
               pass_jitter_percent=np.array([r["pass_jitter_percent"] for r in rl]),
               pass_delay_sd_percent=np.array([r.get("pass_delay_sd_percent", 0.0) for r in rl]),
               pass_amplitude_cv_percent=np.array([r.get("pass_amplitude_cv_percent", 0.0) for r in rl]),
               signal_gain=gain, snr_dB=snr, **bg)
    for k in ("bpfo_Hz", "bpfi_Hz", "bsf_Hz"):
        v = np.broadcast_to(np.asarray(getattr(res, k), float), (n,))
        out[k] = np.where(np.isfinite(v) & ok, v, 0.0)
    return out


def simulate_chunk(plan, k: int) -> dict:
    """Chunk ``k`` of a data set: the arrays of its chunk file (``index``, ``signals`` and the
    per-item label fields the simulation fills, :data:`CHUNK_FIELDS`).  A pure function of (plan,
    k): every item's draws come from its own key, so the in-process loop and any Dask worker give
    the same bytes.  Runs on ``plan.device`` (a JAX platform name; None: JAX's default)."""
    import contextlib

    import jax

    idx = plan.items(k)
    m = idx.size
    pad = np.concatenate([idx, np.repeat(idx[-1:], plan.chunk - m)])
    where = jax.default_device(jax.devices(plan.device)[0]) if plan.device else contextlib.nullcontext()
    with where:
        out = device_program(plan, pad)
    return dict(index=idx, **{name: v[:m] for name, v in out.items()})


def pit_depths(physics, lab, chunk, slots, profile=None, imap=None):
    """(depth in m, ok, unbridged fraction) per item for ``[dataset] depth_rule = "pit"`` (and
    for the pass-to-pass variability, which scales with the unbridged fraction of the item's
    pit under the same contact, :func:`bearingsim.pit.pit_unbridged_fraction`): every fault item's defect
    is a round EDM pit of diameter ``spall_length_mm`` and machined depth ``spall_depth_mm``
    narrower than the ball's contact ellipse, and the simulation takes the depth that loses the
    same Hertz load (:func:`bearingsim.pit.pit_depth_of_solution`: the ball keeps rolling on
    the raceway beside the pit; the groove rule of the machined depth would let it drop by its
    sag over the chord, ~w^2 / 4D, and its impacts grow with the square of the size).

    ``physics``: a :class:`Physics` (or a case, whose physics is built).  Each item's healthy
    contact at its own speed and loads comes from one batched quasi-static solve per ``chunk``
    items (:func:`bearingsim.dynamics.quasi_static_batch` with depth-0 slots: the program the
    simulation compiles anyway), with ball 0 at the pit for an outer-race pit and at the
    load-zone centre (azimuth 0: the radial load is along +x) for an inner-race or ball pit.
    ``ok`` is False where that state did not converge (the item is then flagged ``pit_contact``);
    healthy items get 0 (depth and fraction).  ``imap`` runs the batches (in this process by
    default; :mod:`bearingsim.distributed` on a Dask cluster): each is :func:`pit_depths_batch`
    of the same items, so the numbers do not depend on where it ran."""
    if not isinstance(physics, Physics):
        physics = Physics.of_case(physics)
    profile = physics.profile if profile is None else profile
    n = lab.size
    out, ok, unbridged = np.zeros(n), np.ones(n, bool), np.zeros(n)
    faulty = np.flatnonzero(~lab["healthy"])
    batches = [faulty[k:k + chunk] for k in range(0, faulty.size, chunk)]
    run = imap or (lambda fn, shared, items: ((x, fn(shared, x)) for x in items))
    for idx, (d, good, u) in run(pit_depths_batch, (physics, lab, chunk, slots, profile), batches):
        out[idx], ok[idx], unbridged[idx] = d, good, u
    return out, ok, unbridged


def pit_depths_batch(shared, idx):
    """(depth in m, ok, unbridged fraction) of the fault items ``idx`` (at most ``chunk``; padded
    to ``chunk`` so that every batch is one program): one batch of :func:`pit_depths`; ``shared``
    is ``(physics, lab, chunk, slots, profile)``."""
    import jax
    import jax.numpy as jnp

    from ..kinematics import Operation
    from ..pit import pit_depth_of_solution, pit_unbridged_fraction

    ph, lab, chunk, slots, profile = shared
    b = ph.bearing
    loc = item_locations(lab)
    w = to_si(lab["spall_length_mm"], "mm")
    machined = to_si(lab["spall_depth_mm"], "mm")
    center = to_si(lab["spall_center_deg"], "deg")
    out, ok, unbridged = np.zeros(idx.size), np.ones(idx.size, bool), np.zeros(idx.size)
    pad = np.concatenate([idx, np.repeat(idx[-1:], chunk - idx.size)])
    m = pad.size
    one = jnp.ones(m)
    op = Operation(jnp.asarray(2 * np.pi * lab["speed_rpm"][pad] / 60.0), ph.control, one, one)
    F = np.zeros((m, 5))
    F[:, 0], F[:, 2] = lab["radial_N"][pad], lab["axial_N"][pad]
    th = np.where(loc[pad] == "outer", center[pad], 0.0)
    zero = np.zeros(m)
    slots_h = dynamics.defect_slots(loc[pad], zero, zero, zero, profile, slots)
    sols = dynamics.quasi_static_batch(b, op, jnp.asarray(F), jnp.asarray(th), slots_h, ph.hertz_method)
    host = jax.tree_util.tree_map(np.asarray, sols)
    for j, i in enumerate(idx):     # the integrator replaces this loop with the device pit depths (l1)
        if int(host.result[j]) != 0:
            ok[j] = False
            continue
        sol_j = jax.tree_util.tree_map(lambda a: a[j], host)
        out[j] = pit_depth_of_solution(sol_j, b, 0, str(loc[i]), w[i], machined[i]).depth
        unbridged[j] = pit_unbridged_fraction(sol_j, b, 0, str(loc[i]), w[i])
    return out, ok, unbridged


def run_settings(physics, lab, extent, depth, center, fs):
    """(ball Newton steps, substeps) for the whole data set: :func:`dynamics.batch_settings` on
    the extreme items of every class (:func:`dynamics.extreme_items`: fastest, slowest, most and
    least loaded, largest defect), the largest count, fixed once so that no chunk recompiles."""
    from ..defect import Spall
    from ..jones import load_vector
    from ..kinematics import Operation
    from .spec import slots_of

    ph = physics
    slots = slots_of(lab)
    loc = item_locations(lab)
    load = lab["radial_N"] + lab["axial_N"]
    size = np.asarray(extent, float) * np.asarray(depth, float)
    check = dynamics.extreme_items(lab["fault_class"], lab["speed_rpm"], load, size)
    its, subs = [], []
    for i in check:
        op = Operation.from_rpm(float(lab["speed_rpm"][i]), ph.control, True, True)
        F = load_vector(axial=float(lab["axial_N"][i]), radial_x=float(lab["radial_N"][i]))
        sp = tuple(Spall(float(center[i]) if L == loc[i] else 0.0, float(extent[i]) if L == loc[i] else 0.0,
                         float(depth[i]) if L == loc[i] else 0.0, ph.profile, L, 0) for L in slots)
        it, sub = dynamics.batch_settings(ph.bearing, op, F, sp, ph.cage_angle, fs, ph.params, ph.hertz_method)
        if it is not None:
            its.append(it)
            subs.append(sub)
    it = dynamics.next_iterations(its)
    return it, max(subs, default=1)
