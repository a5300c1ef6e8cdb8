"""Bearing-set benchmark (issue 21): the shaft solve on N bearings (bearingsim.physics.shaft).

Harris 218 DB pair, 40 mm apart, rigid preload 2000 N (set solve, docs/model.md section 10).

  (a) scipy reference (benchmarks/reference_scipy.py: solve_set, every ball of both bearings and
      the shaft in one hybr system from the static solution), one cold solve per load case at
      10 000 rpm, averaged over N_REF load cases;
  (b) bearingsim.physics.shaft.solve_set_batch on (N_BATCH, 5) load cases at 10 000 rpm, time per state
      after compilation; agreement with (a) on the same cases (max relative difference);
  (c) a speed study of the DB pair: 200 speeds 0..15 000 rpm with the offset fixed at standstill
      (rigid preload), FIRST call in a fresh process with an EMPTY compilation cache (run in a
      subprocess with JAX_COMPILATION_CACHE_DIR pointing to a new temporary directory).

Targets: (b) >= 200x per state over (a), agreement <= 1e-9 relative; (c) <= 10 s.
Usage: python benchmarks/bench_sets.py [--n-ref 4] [--n-batch 256]
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

_HERE = pathlib.Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("reference_scipy", _HERE / "reference_scipy.py")
ref = importlib.util.module_from_spec(_spec)
sys.modules.setdefault("reference_scipy", ref)
_spec.loader.exec_module(ref)

RPM = 10000.0
P = 2000.0
Z_POS = (0.0, 0.04)

_STUDY = r'''
import time
t0 = time.perf_counter()
import jax.numpy as jnp, numpy as np
import bearingsim as bs
from bearingsim.physics import shaft
b = bs.Bearing(16, 22.225e-3, 125.26e-3, 0.5232, 0.5232, np.deg2rad(40.0))
bset = shaft.BearingSet.arrangement("DB", b, 0.04, 2000.0)
speeds = jnp.linspace(0.0, 15000.0, 200)
t1 = time.perf_counter()
c1 = time.process_time()
sol = shaft.solve_set_batch(bset, bs.Operation.from_rpm(speeds), jnp.zeros((200, 5)))
ok = int(np.sum(np.asarray(sol.result) == 0))
t2 = time.perf_counter()
print(f"{t2 - t1:.3f} {t1 - t0:.3f} {ok} {float(sol.axial_load[-1, 0]):.1f} {time.process_time() - c1:.3f}")
'''


def load_cases(n, seed=0):
    rng = np.random.default_rng(seed)
    L = np.zeros((n, 5))
    L[:, 0] = rng.uniform(0.0, 1500.0, n)
    L[:, 1] = rng.uniform(-500.0, 500.0, n)
    L[:, 2] = rng.uniform(-2500.0, 2500.0, n)
    L[:, 3] = rng.uniform(-20.0, 20.0, n)
    L[:, 4] = rng.uniform(-20.0, 20.0, n)
    return L


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n-ref", type=int, default=4)
    ap.add_argument("--n-batch", type=int, default=256)
    args = ap.parse_args(argv)

    import jax
    import jax.numpy as jnp
    import bearingsim as bs
    from bearingsim.physics import shaft

    g = ref.HARRIS_218
    loads = load_cases(args.n_batch)
    # (a) the scipy reference
    t = time.perf_counter()
    refs = [ref.solve_set([g, g], Z_POS, [1, -1], [P, P], (0, 0), loads[i], RPM) for i in range(args.n_ref)]
    t_ref = (time.perf_counter() - t) / args.n_ref
    n_conv = sum(r["converged"] for r in refs)

    # (b) bearingsim, batched
    b = bs.Bearing(g.Z, g.D, g.dm, g.fi, g.fo, g.alpha0)
    bset = shaft.BearingSet([b, b], Z_POS, [1, -1], [P, P])
    op = bs.Operation.from_rpm(RPM)
    t = time.perf_counter()
    sol = shaft.solve_set_batch(bset, op, jnp.asarray(loads))
    jax.block_until_ready(sol.displacement)
    t_first = time.perf_counter() - t
    t = time.perf_counter()
    sol = shaft.solve_set_batch(bset, op, jnp.asarray(loads))
    jax.block_until_ready(sol.displacement)
    t_batch = (time.perf_counter() - t) / args.n_batch
    ok = int(np.sum(np.asarray(sol.result) == 0))
    worst = 0.0
    for i, r in enumerate(refs):
        if not r["converged"]:
            continue
        R = np.stack([np.asarray(sol.bearings[k].loads[i]) for k in range(2)])[:, :3]
        worst = max(worst, float(np.max(np.abs(R - r["R"][:, :3])) / np.max(np.abs(r["R"][:, :3]))))
        Q = np.asarray(sol.bearings[0].Q_inner[i])
        worst = max(worst, float(np.max(np.abs(Q - r["bearings"][0]["Q_i"])) / np.max(r["bearings"][0]["Q_i"])))

    # (c) speed study, fresh process, empty cache
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, JAX_COMPILATION_CACHE_DIR=cache)
        t = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", _STUDY], env=env, capture_output=True, text=True, check=True)
        t_proc = time.perf_counter() - t
    study, imp, n_ok, pre15, cpu_s = out.stdout.split()

    cpu = os.cpu_count()
    print(f"bearing-set benchmark (Harris 218 DB pair, rigid preload {P:.0f} N, {RPM:.0f} rpm; "
          f"{cpu} CPU cores, shared: timings are noisy)")
    print(f"(a) scipy reference, cold solve per state      {t_ref * 1e3:10.1f} ms  ({n_conv}/{args.n_ref} converged)")
    print(f"(b) bearingsim solve_set_batch, per state      {t_batch * 1e3:10.3f} ms  ({ok}/{args.n_batch} converged; "
          f"first call incl. compile {t_first:.1f} s)")
    print(f"    speed-up per state (a)/(b)                 {t_ref / t_batch:10.0f} x   (target >= 200 x)")
    print(f"    max relative difference (b) vs (a)         {worst:10.2e}     (target <= 1e-9)")
    print(f"(c) DB speed study, 200 speeds, first call, empty cache: {float(study):.2f} s wall, "
          f"{float(cpu_s):.2f} s CPU (target <= 10 s; + import {float(imp):.1f} s; process {t_proc:.1f} s; {n_ok}/200 converged; "
          f"operating preload at 15 krpm {float(pre15):.0f} N)")


if __name__ == "__main__":
    main()
