"""Static (quasi-static Jones) benchmark: plain scipy reference vs bearingsim (JAX).

Harris 218 at 10 000 rpm, outer raceway control, loads around Fa = 22 250 N + Fr = 5 000 N.

  (a) scipy reference (benchmarks/reference_scipy.py), one cold solve per load case
      (rigid-ring static start -> full 2Z+5 hybr solve at speed), averaged over N_REF loads,
      with its structured finite-difference Jacobian (the baseline the ratio uses); (a') the
      same with MINPACK's dense finite-difference Jacobian, for information;
  (b) bearingsim.solve, one load case per call, after compilation;
  (c) bearingsim.solve_batch on an (N_BATCH, 5) load array, time per state after compilation;
  (d) first-call compile time of bearingsim.solve and of bearingsim.solve_batch.

Prints a table and the ratios: per-state speed-up of (c) over (a) (target >= 300x), of (b) over
(a) (target >= 60x).  Compile times in a fresh process with an empty cache: bench_compile.py.  Usage: python benchmarks/bench_static.py [--n-batch 1000]
"""
from __future__ import annotations

import argparse
import importlib.util
import math
import os
import pathlib
import sys
import time

import numpy as np

_HERE = pathlib.Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("reference_scipy", _HERE / "reference_scipy.py")
ref = importlib.util.module_from_spec(_spec)
sys.modules.setdefault("reference_scipy", ref)
_spec.loader.exec_module(ref)

import bearingsim as bs  # noqa: E402

RPM = 10000.0


def load_cases(n, seed=0):
    """[Fx, Fy, Fz, Mx, My] around Fa = 22 250 N, Fr = 5 000 N (radial direction varied)."""
    rng = np.random.default_rng(seed)
    Fa = 22250.0 * rng.uniform(0.7, 1.3, n)
    Fr = 5000.0 * rng.uniform(0.5, 1.5, n)
    phi = rng.uniform(-0.3, 0.3, n)
    L = np.zeros((n, 5))
    L[:, 0] = Fr * np.cos(phi)
    L[:, 1] = Fr * np.sin(phi)
    L[:, 2] = Fa
    L[0] = [5000.0, 0.0, 22250.0, 0.0, 0.0]          # the nominal case first
    return L


def _loads(row):
    Fx, Fy, Fz, Mx, My = (float(v) for v in row)
    return bs.Loads(axial=Fz, radial_x=Fx, radial_y=Fy, moment_x=Mx, moment_y=My)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n-ref", type=int, default=20, help="load cases for (a) and (b)")
    ap.add_argument("--n-batch", type=int, default=1000, help="batch size for (c)")
    ap.add_argument("--repeat", type=int, default=3, help="repeats of the batched call (best taken)")
    args = ap.parse_args(argv)

    g = ref.HARRIS_218
    bearing = bs.Bearing(g.Z, g.D, g.dm, g.fi, g.fo, g.alpha0)
    op = bs.Operation.from_rpm(RPM)
    L_ref = load_cases(args.n_ref, seed=0)
    L_batch = load_cases(args.n_batch, seed=1)

    # (a) scipy reference
    t_ref, ref_sols = [], []
    for row in L_ref:
        t0 = time.perf_counter()
        s = ref.solve(g, row, speed_rpm=RPM)
        t_ref.append(time.perf_counter() - t0)
        ref_sols.append(s)
    n_ref_conv = sum(s["converged"] for s in ref_sols)
    # (a') the same with MINPACK's own dense finite-difference Jacobian (naive baseline)
    t_naive, n_naive_conv = [], 0
    for row in L_ref:
        t0 = time.perf_counter()
        s = ref.solve(g, row, speed_rpm=RPM, jacobian="hybr")
        t_naive.append(time.perf_counter() - t0)
        n_naive_conv += s["converged"]

    # (d) + (b) bearingsim single solve: first call compiles
    t0 = time.perf_counter()
    sol = bs.solve(bearing, op, _loads(L_ref[0]))
    sol.displacement.block_until_ready()
    t_first_single = time.perf_counter() - t0
    t_bs, bs_sols = [], []
    for row in L_ref:
        t0 = time.perf_counter()
        sol = bs.solve(bearing, op, _loads(row))
        sol.displacement.block_until_ready()
        t_bs.append(time.perf_counter() - t0)
        bs_sols.append(sol)
    t_compile_single = t_first_single - float(np.median(t_bs))

    # (c) batched
    Lb = np.asarray(L_batch)
    t0 = time.perf_counter()
    bsol = bs.solve_batch(bearing, op, Lb)
    bsol.displacement.block_until_ready()
    t_first_batch = time.perf_counter() - t0
    t_batch = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        bsol = bs.solve_batch(bearing, op, Lb)
        bsol.displacement.block_until_ready()
        t_batch.append(time.perf_counter() - t0)
    t_batch_best = min(t_batch)
    t_compile_batch = t_first_batch - t_batch_best
    n_batch_conv = int(np.sum(np.asarray(bsol.result) == 0))

    # agreement of (b) with (a) (sanity; the real cross-check is tests/test_reference_crosscheck.py)
    da = max(np.degrees(np.abs(np.asarray(b.alpha_inner) - s["alpha_i"])).max() for b, s in zip(bs_sols, ref_sols))
    dQ = max((np.abs(np.asarray(b.Q_outer) - s["Q_o"]).max() / s["Q_o"].max()) for b, s in zip(bs_sols, ref_sols))

    per_ref = float(np.mean(t_ref))
    per_bs = float(np.mean(t_bs))
    per_batch = t_batch_best / args.n_batch
    try:
        load = "%.2f %.2f %.2f" % os.getloadavg()
    except OSError:
        load = "n/a"

    print(f"Harris 218, {RPM:.0f} rpm, outer control, Fa~22250 N + Fr~5000 N "
          f"(cpus {os.cpu_count()}, load avg {load})")
    print(f"{'method':<52}{'time/state':>14}{'converged':>12}")
    print("-" * 78)
    print(f"{'(a) scipy reference, cold solve (mean of %d)' % args.n_ref:<52}"
          f"{per_ref * 1e3:>11.2f} ms{n_ref_conv:>7d}/{args.n_ref}")
    lbl = "(a') same, hybr's dense FD Jacobian (naive)"
    print(f"{lbl:<52}"
          f"{np.mean(t_naive) * 1e3:>11.2f} ms{n_naive_conv:>7d}/{args.n_ref}")
    print(f"{'(b) bearingsim.solve, after compile (mean of %d)' % args.n_ref:<52}"
          f"{per_bs * 1e3:>11.2f} ms{sum(int(b.result) == 0 for b in bs_sols):>7d}/{args.n_ref}")
    print(f"{'(c) bearingsim.solve_batch (%d states, best of %d)' % (args.n_batch, args.repeat):<52}"
          f"{per_batch * 1e6:>11.2f} us{n_batch_conv:>7d}/{args.n_batch}")
    print(f"{'(d) compile, bearingsim.solve first call':<52}{t_compile_single:>12.2f} s")
    print(f"{'    compile, bearingsim.solve_batch first call':<52}{t_compile_batch:>12.2f} s")
    print("-" * 78)
    ss = per_ref / per_bs
    print(f"speed-up (b) single vs (a) scipy:       {ss:10.1f} x   (target >= 60 x: "
          f"{'met' if ss >= 60 else 'NOT met'})")
    sp = per_ref / per_batch
    print(f"speed-up (c) batched vs (a) scipy:      {sp:10.1f} x   (target >= 300 x: "
          f"{'met' if sp >= 300 else 'NOT met'})")
    ct = max(t_compile_single, t_compile_batch)
    print(f"speed-up (c) batched vs (a') naive scipy: {np.mean(t_naive) / per_batch:8.1f} x")
    print(f"compile time (max of single, batch):    {ct:10.2f} s   (with this process's cache "
          "settings; empty-cache figures: bench_compile.py)")
    print(f"(b) vs (a): max |d alpha_i| {da:.2e} deg, max |d Q_o|/Q_o,max {dQ:.2e}")
    return dict(per_ref=per_ref, per_bs=per_bs, per_batch=per_batch, compile_single=t_compile_single,
                compile_batch=t_compile_batch, speedup=sp)


if __name__ == "__main__":
    main()
