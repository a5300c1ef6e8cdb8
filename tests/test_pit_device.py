"""The pit physics, written once in JAX (bearingsim.physics.pit: the data set chunk's program
and the float functions both evaluate it), against the independent NumPy oracle
tests/oracles/pit_numpy.py on the same healthy quasi-static states: the same formulas on the
same 2001 points; scipy's Simpson weights come from the points' actual spacing, the JAX rule's
from the uniform one, which differ by ~2e-9 relative (the quadrature's own error at 2001
points, against 20001, is larger: the integrand has square-root edges), so 1e-7."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from bearingsim.physics import pit
from bearingsim.case import load_case
from bearingsim.physics.jones import load_vector, solve
from bearingsim.physics.kinematics import Operation
from oracles import pit_numpy


@pytest.mark.parametrize("a,b,w,e", [(1e-3, 1e-4, 5e-4, 0.0), (1e-3, 1e-4, 5e-4, 3e-4), (1e-3, 2e-4, 1e-5, 1e-4),
                                     (1e-3, 1e-4, 5e-3, 0.0), (1e-3, 1e-4, 0.0, 0.0), (1e-3, 1e-4, 4e-4, 2e-3)])
def test_load_fraction(a, b, w, e):
    want = pit_numpy.pit_load_fraction(a, b, w, e)
    got = float(jax.jit(pit.load_fraction)(a, b, w, e))
    assert got == pytest.approx(want, rel=1e-7, abs=1e-15)
    # the same formula: eager ops against one compiled program, whose optimised transcendentals
    # (arcsin, sqrt at XLA's default level) differ by ~2e-9 relative
    assert pit.pit_load_fraction(a, b, w, e) == pytest.approx(got, rel=1e-8, abs=1e-300)


def test_depth_and_unbridged_of_states():
    case = load_case("cases/cwru_6205.toml")
    bearing = case.bearing()
    f = jax.jit(pit.pit_of_solution)
    n = 0
    for radial, axial in ((100.0, 43.7), (400.0, 10.0), (20.0, 150.0)):
        sol = solve(bearing, Operation.from_rpm(1797.0, "outer", True, True), load_vector(axial=axial, radial_x=radial))
        host = jax.tree_util.tree_map(np.asarray, sol)
        for li, loc in enumerate(pit.PIT_LOCATIONS):
            for w in (0.1778e-3, 0.5334e-3, 1.016e-3):
                d = pit_numpy.pit_depth_of_solution(host, bearing, 0, loc, w, 0.2794e-3).depth
                u = pit_numpy.pit_unbridged_fraction(host, bearing, 0, loc, w)
                dd, uu = f(sol, bearing, 0, jnp.asarray(li), w, 0.2794e-3)
                assert float(dd) == pytest.approx(d, rel=1e-7, abs=1e-18)
                assert float(uu) == pytest.approx(u, rel=1e-12, abs=1e-15)
                assert pit.pit_depth_of_solution(host, bearing, 0, loc, w, 0.2794e-3).depth == \
                    pytest.approx(d, rel=1e-7, abs=1e-18)
                n += d > 0
    assert n > 10
