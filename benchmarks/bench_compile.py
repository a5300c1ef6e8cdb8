"""Compile times of the quasi-static entry points in a fresh process with an EMPTY compilation
cache (issue 8 targets: solve <= 5 s, solve_batch <= 5 s, sweep <= 8 s).

Each entry point runs in its own subprocess with ``JAX_COMPILATION_CACHE_DIR`` pointing at a new
empty folder; compile time = first call - best of three later calls (tracing included).
    python benchmarks/bench_compile.py
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

SNIPPET = r"""
import json, time, numpy as np, jax
import bearingsim as bs
from bearingsim.physics.sweep import sweep
b = bs.Bearing(16, 22.225e-3, 125.26e-3, 0.5232, 0.5232, np.radians(40.0))
op = bs.Operation.from_rpm(10000.0)
F = bs.Loads(axial=10000.0, radial_x=3000.0)
sp = bs.Spall(0.0, np.radians(3.0), 0.3e-3, "rectangular")
L = np.tile(np.asarray(F), (1000, 1)) * np.linspace(0.8, 1.2, 1000)[:, None]
angles = np.linspace(-np.pi / 16, np.pi / 16, 360)
calls = {
    "solve": lambda: bs.solve(b, op, F).result,
    "solve (spall)": lambda: bs.solve(b, op, F, spall=sp).result,
    "solve_batch": lambda: bs.solve_batch(b, op, L).result,
    "sweep": lambda: sweep(b, op, F, sp, angles=angles).result,
}
f = calls[NAME]
t = time.perf_counter(); jax.block_until_ready(f()); first = time.perf_counter() - t
rest = []
for _ in range(3):
    t = time.perf_counter(); jax.block_until_ready(f()); rest.append(time.perf_counter() - t)
print(json.dumps(dict(first=first, run=min(rest))))
"""

TARGETS = {"solve": 5.0, "solve (spall)": 5.0, "solve_batch": 5.0, "sweep": 8.0}


def main():
    print(f"{'entry point':<16}{'compile s':>11}{'run s':>10}{'target s':>10}")
    out = {}
    for name, target in TARGETS.items():
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, JAX_COMPILATION_CACHE_DIR=cache)
            r = subprocess.run([sys.executable, "-c", f"NAME = {name!r}\n" + SNIPPET], env=env,
                               capture_output=True, text=True, check=True)
        d = json.loads(r.stdout.strip().splitlines()[-1])
        comp = d["first"] - d["run"]
        out[name] = comp
        print(f"{name:<16}{comp:11.2f}{d['run']:10.4f}{target:10.1f}  {'met' if comp <= target else 'NOT met'}")
    return out


if __name__ == "__main__":
    main()
