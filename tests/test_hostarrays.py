"""NumPy outside a program, JAX inside (bearingsim.hostarrays): the same values both ways, and a
warm `bearingsim static` that lowers its two kept programs and no eager operation."""
import os
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bearingsim as bs
from bearingsim.hostarrays import f64, host, traced, xp
from bearingsim.physics.jones import PRESSURE_WARNING
from bearingsim.physics.kinematics import defect_frequencies


def test_concrete_values_are_numpy_and_traced_ones_stay_jax():
    assert isinstance(f64(1.5), np.ndarray) and f64(1.5).dtype == np.float64
    assert isinstance(f64(jnp.ones(2)), np.ndarray)                 # a concrete JAX array too
    assert host(jnp.ones(2)).__class__ is np.ndarray and host(3) == 3
    seen = {}

    @jax.jit
    def f(x):
        seen["traced"], seen["xp"] = traced(x), xp(x, 1.0)
        return f64(x) * 2.0

    assert float(f(1.25)) == 2.5
    assert seen == {"traced": True, "xp": jnp}
    assert xp(np.ones(1), 2.0) is np


def test_the_nouns_made_in_numpy_are_those_made_in_jax_to_the_bit():
    """Operation.from_rpm, the load vector, the raceway radii and the defect frequencies: NumPy
    (concrete) against the same function traced under jit (XLA): equal bits (exact arithmetic and
    cos, which NumPy and XLA's CPU backend compute alike)."""
    b = bs.Bearing(9, 7.94e-3, 39.04e-3, 0.52, 0.52, np.radians(3.0))
    host_side = (bs.Operation.from_rpm(1797.3).speed, bs.Loads(axial=43.7, radial_x=100.0, moment_y=0.25),
                 b.outer_raceway_radius, b.inner_raceway_radius, b.ball_azimuths(0.3),
                 *defect_frequencies(b, 29.955))

    @jax.jit
    def traced_side(rpm, ax, rx, my, bb, cage, hz):
        return (bs.Operation.from_rpm(rpm).speed, bs.Loads(axial=ax, radial_x=rx, moment_y=my),
                bb.outer_raceway_radius, bb.inner_raceway_radius, bb.ball_azimuths(cage),
                *defect_frequencies(bb, hz))

    dev = traced_side(1797.3, 43.7, 100.0, 0.25, b, 0.3, 29.955)
    assert all(isinstance(v, np.ndarray | np.generic) for v in host_side)
    for h, d in zip(host_side, dev):
        np.testing.assert_array_equal(np.asarray(h), np.asarray(d))


def test_a_solutions_properties_read_on_the_host_equal_jax(b218):
    sol = bs.solve(b218, bs.Operation.from_rpm(10000.0), bs.Loads(axial=17800.0, radial_x=3000.0))
    assert isinstance(sol.max_pressure, np.generic | np.ndarray)
    assert sol.max_pressure == float(jnp.maximum(jnp.max(sol.p_max_inner), jnp.max(sol.p_max_outer)))
    assert bool(sol.overloaded) == (float(jnp.maximum(jnp.max(sol.p_max_inner), jnp.max(sol.p_max_outer)))
                                    > PRESSURE_WARNING)
    # a mean: NumPy's pairwise and XLA's reduction may sum in another order (round-off)
    assert sol.cage_speed == pytest.approx(float(jnp.mean(sol.orbital_speed)), rel=1e-15)
    assert bool(sol.converged) is True


SCRIPT = r"""
import jax.monitoring
from bearingsim.app.commands import load_case
from bearingsim.app.workflows import static_command
events = []
jax.monitoring.register_event_duration_secs_listener(
    lambda e, d, **k: events.append(e) if e == "/jax/core/compile/jaxpr_to_mlir_module_duration" else None)
static_command(load_case("demo"), say=lambda *a: None)
print("LOWERED", len(events))
"""


def test_a_warm_static_call_lowers_its_two_programs_and_nothing_eager():
    """`bearingsim static demo` in a fresh process, after a first one filled the caches: the Jones
    state and the contact limits (kept programs, loaded) are the only programs lowered; before
    the host side went to NumPy, 20 eager operations were lowered too (~40 ms each warm on a 2-core
    CPU: 1.6 of a 4.2 s command with the import, docs/scale.md)."""
    env = dict(os.environ)
    out = [subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, timeout=300)
           for _ in range(2)]
    assert all(p.returncode == 0 for p in out), out[-1].stderr[-2000:]
    assert out[-1].stdout.split()[-1] == "2", out[-1].stdout
