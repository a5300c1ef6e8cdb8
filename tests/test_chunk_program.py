"""A data set chunk as compiled device programs (issue 25, dynamics.chunk_program): every item
equals ``simulate`` of its own settings and key (one engine, issue 32), two device programs per
chunk and no implicit host transfer, and the Newton step count chosen per chunk by the
per-item check."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from bearingsim import dynamics as dyn
from bearingsim.case import load_case
from bearingsim.physics.defect import LOCATIONS, Spall
from bearingsim.physics.hertz import stiffness_curve
from bearingsim.physics.kinematics import Operation

T = 512
FS = 48000.0
MODES = ([2977.6, 3356.0], [0.01329, 0.01937], [1.883, 8.852])


@pytest.fixture(scope="module")
def setup():
    case = load_case("cases/cwru_6205.toml")
    b = case.bearing()
    n = 4
    loc = np.array(["outer", "inner", "ball", "outer"])
    speed = np.array([1797.0, 1750.0, 1780.0, 1730.0])
    loads = np.zeros((n, 5))
    loads[:, 0], loads[:, 2] = [100.0, 250.0, 150.0, 60.0], [43.7, 100.0, 20.0, 30.0]
    center = np.array([0.0, 1.0, 0.5, 0.0])
    extent = np.array([0.027, 0.03, 0.06, 0.0])
    depth = np.array([7e-7, 1e-6, 2e-6, 0.0])            # the last item healthy
    params = dyn.DynamicsParameters(contact_damping_ratio=0.3, resonance_frequency=MODES[0],
                                    resonance_damping_ratio=MODES[1], resonance_gain=MODES[2])
    return dict(b=b, n=n, loc=loc, speed=speed, loads=loads, center=center, extent=extent, depth=depth,
                params=params)


def program_inputs(s):
    n = s["n"]
    p = s["params"]
    pb = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (n,)) if a.ndim == 0 else a, p)
    modes = tuple(jnp.asarray(np.tile(m, (n, 1))) for m in MODES)
    li = jnp.asarray([LOCATIONS.index(L) for L in s["loc"]])
    keys = dyn.item_keys(7, np.arange(n))
    return (keys, jnp.asarray(s["speed"]), jnp.asarray(s["loads"]), jnp.zeros(n), li, jnp.asarray(s["center"]),
            jnp.asarray(s["extent"]), jnp.asarray(s["depth"]), modes, pb)


@pytest.fixture(scope="module")
def program_run(setup):
    prog = dyn.chunk_program(setup["b"], samples=T, sample_rate=FS, realism=dyn.Realism(), max_speed_rpm=1800.0)
    args = jax.device_put(program_inputs(setup))
    out = prog(*args)
    return prog, args, out


def test_an_item_is_simulate_of_its_key(setup, program_run):
    """One engine: an item of the chunk (an inner-race pit, a ball pit; the outer pit with slip
    on is test_an_item_rerun_alone_from_its_key) equals ``simulate`` of its own settings and
    key: the same sensor signal to 1e-6 of its RMS (both solve the
    balls in full with the chunk's Newton count; the paths differ by round-off -- the chunk
    builds the whole record's stages in one program, simulate per 1024-sample chunk -- which the
    contacts' switching amplifies over the record: measured ~1e-8) and the defect frequencies
    to 1e-12."""
    s = setup
    _, args, out = program_run
    it = out["ball_iterations"]
    n_knots = dyn.chunk_program(s["b"], samples=T, sample_rate=FS, max_speed_rpm=1800.0).n_knots
    for i in (1, 2):
        op = Operation.from_rpm(float(s["speed"][i]), "outer", True, True)
        sp = Spall(float(s["center"][i]), float(s["extent"][i]), float(s["depth"][i]), "rectangular", str(s["loc"][i]), 0)
        r = dyn.simulate(s["b"], op, jnp.asarray(s["loads"][i]), sp, s["params"], T / FS, FS, realism=dyn.Realism(),
                         key=args[0][i], n_knots=n_knots, ball_iterations=it, substeps=1, record_balls=False,
                         progress=False, ball_solver="full")
        a = np.asarray(out["sensor"][i])
        assert int(out["result"][i]) == 0 and r.result == 0
        rms = np.sqrt(np.mean(r.sensor_acceleration ** 2))
        assert rms > 0
        assert np.max(np.abs(a - r.sensor_acceleration)) < 1e-6 * rms
        for k in ("bpfo_Hz", "bpfi_Hz", "bsf_Hz"):
            assert float(out[k][i]) == pytest.approx(r.frequencies.hz()[k], rel=1e-12)


def test_pass_times_padded(setup, program_run):
    """Pass times ascending within the record, +inf padded; none for the healthy item; an
    outer pit passes at BPFO (no slip: the intervals are 1 / BPFO within 1e-6)."""
    _, _, out = program_run
    tp = np.asarray(out["pass_times"])
    assert np.all(np.isinf(tp[3]))
    fin = tp[0][np.isfinite(tp[0])]
    assert fin.size >= 1 and np.all(fin >= 0) and np.all(fin <= (T - 1) / FS)
    assert np.all(np.isinf(tp[0][fin.size:]))


def test_a_chunk_is_two_device_programs_without_implicit_transfers(program_run):
    """A chunk runs as two compiled programs (states + check, then the record's time loop) and
    the host reads one integer between them (explicitly); with the inputs on the device no
    implicit host<->device transfer happens (jax.transfer_guard)."""
    prog, args, out = program_run
    before = prog.calls
    with jax.transfer_guard("disallow"):
        out2 = prog(*args)
        jax.block_until_ready(out2["sensor"])
    assert prog.calls - before == 2
    np.testing.assert_array_equal(np.asarray(out2["sensor"]), np.asarray(out["sensor"]))   # reproducible


def test_iteration_choice_per_item_equals_the_host_check(setup, program_run):
    """The per-item count of the vmapped check equals choose_ball_iterations on the same
    quasi-static state (the accuracy check that existed), and the chunk takes the smallest menu
    count covering every item."""
    s = setup
    prog, args, out = program_run
    prep = prog.prepare(*args[1:8])
    needed = np.asarray(prep["needed"])
    curve = stiffness_curve(s["b"], "exact")
    q = np.asarray(prep["sols"].displacement)
    k = np.asarray(prep["spin_ratio"])
    for i in range(s["n"]):
        op = Operation.from_rpm(float(s["speed"][i]), "outer", True, True)
        sp = tuple(Spall(float(s["center"][i]) if L == s["loc"][i] else 0.0,
                         float(s["extent"][i]) if L == s["loc"][i] else 0.0,
                         float(s["depth"][i]) if L == s["loc"][i] else 0.0, "rectangular", L, 0) for L in LOCATIONS)
        it, _ = dyn.choose_ball_iterations(s["b"], op, jnp.asarray(q[i]), sp, curve, 0.0, spin_ratio=float(k[i]))
        assert needed[i] == it
    assert out["ball_iterations"] == dyn.menu_iterations(needed)


def test_menu():
    assert dyn.menu_iterations([1, 1, 1]) == 1
    assert dyn.menu_iterations([1, 3, 2]) == 4
    assert dyn.menu_iterations([2]) == 2
    assert dyn.menu_iterations([1, 0]) == dyn.MENU[-1]          # no count suffices: the largest
    assert dyn.menu_iterations([8, 16]) == 16


def test_pit_depths_inside_the_program(setup, program_run):
    """depth_rule "pit": the program's effective depth and unbridged fraction of each fault
    item equal the NumPy oracle (tests/oracles/pit_numpy.py) on its healthy state with ball 0 at the pit
    (outer) or at azimuth 0 (inner, ball), solved on the host (1e-7: the Simpson weights, see
    tests/test_pit_device.py); healthy items get 0."""
    from bearingsim.physics.jones import solve
    from oracles.pit_numpy import pit_depth_of_solution, pit_unbridged_fraction

    s = setup
    prog, args, _ = program_run
    n = s["n"]
    w = np.array([0.5334e-3, 0.1778e-3, 1.016e-3, 0.5e-3])
    machined = np.full(n, 0.2794e-3)
    prep = prog.prepare(*args[1:8], pit=(jnp.asarray(w), jnp.asarray(machined)))
    got_d, got_u = np.asarray(prep["pit_depth"]), np.asarray(prep["unbridged"])
    assert np.all(np.asarray(prep["pit_ok"]))
    for i in range(n):
        if s["depth"][i] == 0:
            assert got_d[i] == 0 and got_u[i] == 0
            continue
        op = Operation.from_rpm(float(s["speed"][i]), "outer", True, True)
        th = float(s["center"][i]) if s["loc"][i] == "outer" else 0.0
        sol = jax.tree_util.tree_map(np.asarray, solve(s["b"], op, jnp.asarray(s["loads"][i]), cage_angle=th))
        d = pit_depth_of_solution(sol, s["b"], 0, s["loc"][i], w[i], machined[i]).depth
        u = pit_unbridged_fraction(sol, s["b"], 0, s["loc"][i], w[i])
        assert got_d[i] == pytest.approx(d, rel=1e-7)
        assert got_u[i] == pytest.approx(u, rel=1e-9, abs=1e-12)
    # the defective states are solved with these depths
    assert np.all(np.asarray(prep["depth"]) == got_d)
    # depth_rule "machined": the depths as given, the same unbridged fractions
    kept = prog.prepare(*args[1:8], pit=(jnp.asarray(w), jnp.asarray(machined)), keep_depth=True)
    np.testing.assert_array_equal(np.asarray(kept["depth"]), s["depth"])
    np.testing.assert_array_equal(np.asarray(kept["unbridged"]), got_u)
    assert np.all(np.asarray(kept["pit_ok"]))


def test_item_keys_depend_on_seed_and_index_only():
    k = np.asarray(dyn.item_keys(3, np.arange(10)))
    assert k.shape == (10, 2) and k.dtype == np.uint32
    np.testing.assert_array_equal(np.asarray(dyn.item_keys(3, [5, 6])), k[5:7])
    assert len({tuple(r) for r in k}) == 10
    assert not np.array_equal(np.asarray(dyn.item_keys(4, np.arange(10))), k)


def test_an_item_rerun_alone_from_its_key(setup):
    """With slip and speed fluctuation on, simulate(..., key=item key, n_knots=program's) draws
    the item's motion exactly as the chunk program does: the same pass times (1e-9 s) and the
    same sensor signal (1e-6 of its RMS: both solve the balls in full with 4 Newton steps; the
    paths differ by round-off, see test_same_physics_as_the_host_path)."""
    s = setup
    realism = dyn.Realism(slip_percent=0.9, speed_fluctuation_percent=0.1)
    prog = dyn.chunk_program(s["b"], samples=T, sample_rate=FS, realism=realism, max_speed_rpm=1800.0)
    args = program_inputs(s)
    out = prog(*args, iterations=4)
    i = 0
    op = Operation.from_rpm(float(s["speed"][i]), "outer", True, True)
    sp = Spall(float(s["center"][i]), float(s["extent"][i]), float(s["depth"][i]), "rectangular", "outer", 0)
    p = dyn.DynamicsParameters(contact_damping_ratio=0.3, resonance_frequency=MODES[0],
                               resonance_damping_ratio=MODES[1], resonance_gain=MODES[2])
    r = dyn.simulate(s["b"], op, jnp.asarray(s["loads"][i]), sp, p, T / FS, FS, realism=realism, key=args[0][i],
                     n_knots=prog.n_knots, ball_iterations=4, substeps=1, record_balls=False, progress=False,
                     ball_solver="full")
    tp = np.asarray(out["pass_times"][i])
    np.testing.assert_allclose(tp[np.isfinite(tp)], r.pass_times, rtol=0, atol=1e-9)
    a = np.asarray(out["sensor"][i])
    rms = np.sqrt(np.mean(a ** 2))
    assert r.realism["pass_jitter_percent"] == pytest.approx(float(out["pass_jitter_percent"][i]), rel=1e-12)
    assert np.max(np.abs(a - r.sensor_acceleration)) < 1e-6 * rms


def test_the_time_loop_is_one_program_for_every_slip(setup, program_run):
    """Issue 32: the slip and speed fluctuation are data of the time loop
    (:func:`bearingsim.dynamics.motion_realism`), not static settings: a spec with another slip
    runs the compiled loop of the first (one key, no second trace or compile), and the slip is
    applied (the outer pit's passes move).  On the old code (the Realism static) the two keys
    differ."""
    from bearingsim import programs

    prog, args, out = program_run
    other = dyn.chunk_program(setup["b"], samples=T, sample_rate=FS, realism=dyn.Realism(slip_percent=0.2),
                              max_speed_rpm=1800.0)
    assert (other.n_knots, other.P) == (prog.n_knots, prog.P)        # the same shapes
    seen: dict = {}
    programs.record(seen)
    try:
        prog(*args)
        out2 = other(*args)
    finally:
        programs.record(seen, on=False)
    runs = {key for name, key in seen if name.endswith("program._run")}
    assert len(runs) == 1, seen
    a, b = np.asarray(out["sensor"][0]), np.asarray(out2["sensor"][0])
    assert np.max(np.abs(a - b)) > 1e-3 * np.sqrt(np.mean(a ** 2))
