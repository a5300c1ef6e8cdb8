"""Dynamic-layer benchmark (issue 9 targets): CWRU 6205, 0.021 in rectangular spall, 1797 rpm.

  (a) bearingsim.dynamics.simulate, single item, 48 kHz: wall seconds per simulated second after
      compilation (target <= 1 s: faster than real time), steps per second;
  (b) scipy.integrate.solve_ivp (RK45) on the same 10 equations of motion with a plain numpy
      right-hand side (bearing force: the omega = 0 closed-form Jones balls of
      benchmarks/reference_scipy.static_balls, cheaper than the Newton the JAX side does, so the
      ratio is conservative), the resonator applied afterwards as in bearingsim: ratio (target
      >= 50 x).  Simulates --scipy-duration s and scales;
  (c) the data set spec cases/dataset_cwru.toml (1000 items of 0.1 s, realism as in the spec)
      through bearingsim.datasets.make_dataset, after a compile run: wall time (target <= 60 s)
      and peak RSS (target <= 2 GB);
  (d) compile time of a simulation with an empty compilation cache (a fresh process; target
      <= 10 s): first call minus a second call.

Issue 11 (the same targets for the new defect classes): (a) and the wall ratio of (b) are also
printed for the inner-race (cases/cwru_6205_inner.toml) and ball (cases/cwru_6205_ball.toml)
cases (the scipy baseline is the outer-race one: its right-hand side costs the same for every
class), and (c) for the four-class spec cases/dataset_cwru_4class.toml (--count4 items).

The machine (2 cores) may be shared: the numbers are indicative.
Usage: python benchmarks/bench_dynamics.py [--duration 1.0] [--count 1000] [--count4 1000]
       [--classes outer,inner,ball] [--no-compile]
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import os
import pathlib
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

_HERE = pathlib.Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("reference_scipy", _HERE / "reference_scipy.py")
ref = importlib.util.module_from_spec(_spec)
sys.modules["reference_scipy"] = ref
_spec.loader.exec_module(ref)


def rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def scipy_baseline(case, res, duration, rtol=1e-5):
    """RK45 on the same 10 states (atol on um and mm/s); numpy RHS, closed-form ball forces."""
    from scipy.integrate import solve_ivp

    b = case.bearing()
    d = case.dynamics_settings()
    geom = ref.Geometry(b.n_balls, float(b.ball_diameter), float(b.pitch_diameter), float(b.f_inner),
                        float(b.f_outer), float(b.free_contact_angle))
    sp = case.spall()
    spall = dict(center=float(sp.center), extent=float(sp.extent), depth=float(sp.depth),
                 profile=sp.profile)
    F = np.asarray(case.loads())[:3]
    ms, mh, kh, ch = d["shaft_mass"], d["housing_mass"], d["housing_stiffness"], d["housing_damping"]
    cb = np.asarray(res.contact_damping)
    wc = 2 * np.pi * res.frequencies.ftf
    th0 = float(case.cage_angle)
    tilts = np.asarray(res.quasi_static.displacement)[3:]
    Z = b.n_balls
    S = np.array([1e-6] * 5 + [1e-3] * 5)

    def rhs(t, u):
        y = u * S
        psi = th0 + wc * t + 2 * np.pi * np.arange(Z) / Z
        q = (y[0] - y[3], y[1] - y[4], y[2], tilts[0], tilts[1])
        H = ref.depth_profile(geom, spall, psi)
        st = ref.static_balls(geom, q, psi, H)
        R = np.array([np.sum(st["Hf"] * np.cos(psi)), np.sum(st["Hf"] * np.sin(psi)), np.sum(st["G"])])
        vs, vh = y[5:8], y[8:10]
        Fd = cb * (vs - np.array([vh[0], vh[1], 0.0]))
        a_s = (F - R - Fd) / ms
        a_h = (R[:2] + Fd[:2] - kh * y[3:5] - ch * vh) / mh
        return np.concatenate([vs, vh, a_s, a_h]) / S

    y0 = np.concatenate([np.asarray(res.shaft_displacement[0]), np.asarray(res.housing_displacement[0]),
                         np.zeros(5)]) / S
    t = time.perf_counter()
    out = solve_ivp(rhs, (0.0, duration), y0, method="RK45", rtol=rtol, atol=rtol,
                    t_eval=np.arange(int(duration * 48000)) / 48000.0)
    return time.perf_counter() - t, out


_COMPILE_SNIPPET = """
import time, numpy as np
t = time.perf_counter()
import bearingsim
from bearingsim import dynamics as dyn
from bearingsim.case import load_case
c = load_case("cwru_6205")
kw = dict(theta0=c.cage_angle, progress=False, realism=dyn.Realism.from_settings(c.dynamics_settings()))
p = dyn.DynamicsParameters.from_settings(c.dynamics_settings())
t0 = time.perf_counter()
dyn.simulate(c.bearing(), c.operation(), c.loads(), c.spall(), p, 0.05, 48000.0, **kw)
t1 = time.perf_counter()
dyn.simulate(c.bearing(), c.operation(), c.loads(), c.spall(), p, 0.05, 48000.0, **kw)
t2 = time.perf_counter()
print(f"{t0 - t:.2f} {t1 - t0:.2f} {t2 - t1:.2f}")
"""


_DATASET_SNIPPET = """
import json, pathlib, resource, sys, tempfile, time
import bearingsim
from bearingsim.case import load_case
from bearingsim.datasets import make_dataset
rss = lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
spec = load_case(pathlib.Path(sys.argv[1]))
count = int(sys.argv[2])
chunk = int(spec.data["dataset"]["chunk"])
with tempfile.TemporaryDirectory() as tmp:
    # the compile run: the same items (the same Newton step count and substeps, chosen from the
    # drawn items' extremes) over one 1024-sample block -- the program of the measured run
    fs0 = float(spec.dynamics_settings()["sample_rate"])
    warm = spec.with_value("dataset.count", count).with_value("dataset.duration_s", 1024.0 / fs0)
    make_dataset(warm, pathlib.Path(tmp) / "warm.h5", progress=False)
    rss0 = rss()
    t, c = time.perf_counter(), time.process_time()
    s = make_dataset(spec.with_value("dataset.count", count), pathlib.Path(tmp) / "full.h5", progress=True)
    el, cpu = time.perf_counter() - t, time.process_time() - c
    size = (pathlib.Path(tmp) / "full.h5").stat().st_size / 1e6
    import h5py
    with h5py.File(pathlib.Path(tmp) / "full.h5", "r") as f:
        its, subs = int(f.attrs["ball_iterations"]), int(f.attrs["substeps"])
print(json.dumps(dict(its=its, subs=subs, el=el, cpu=cpu, failed=int(s.failed), messages="; ".join(s.message()), size=size,
                      rss0=rss0, rss=rss(), chunk=chunk, duration=spec.data["dataset"]["duration_s"],
                      fs=spec.dynamics_settings()["sample_rate"])))
"""


def dataset_run(spec_name, count):
    """(c): make_dataset of ``count`` items after a one-chunk compile run, in a fresh process (its
    peak RSS is the data set's own, not this process's compiled programs)."""
    out = subprocess.run([sys.executable, "-c", _DATASET_SNIPPET, str(_HERE.parent / "cases" / f"{spec_name}.toml"),
                          str(count)], capture_output=False, stdout=subprocess.PIPE, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def single_item(dyn, case, duration, label):
    """(a) for one case at 48 kHz without realism: (result, wall s per simulated s, CPU s)."""
    b, op, F, sp = case.bearing(), case.operation(), case.loads(), case.spall()
    p = dyn.DynamicsParameters.from_settings(case.dynamics_settings())
    kw = dict(theta0=case.cage_angle, progress=False)
    t = time.perf_counter()
    res = dyn.simulate(b, op, F, sp, p, 0.05, 48000.0, **kw)
    first = time.perf_counter() - t
    dyn.simulate(b, op, F, sp, p, 0.05, 48000.0, record_balls=False, **kw)   # its own program

    def best(**extra):
        walls, cpus = [], []
        for _ in range(2):
            t, c = time.perf_counter(), time.process_time()
            r = dyn.simulate(b, op, F, sp, p, duration, 48000.0, **kw, **extra)
            walls.append(time.perf_counter() - t)
            cpus.append(time.process_time() - c)
        return r, min(walls), min(cpus)

    res, jax_el, jax_cpu = best()
    _, jax_lean, lean_cpu = best(record_balls=False)
    rate = jax_el / duration
    print(f"{label}, 48 kHz, {res.scheme}, {res.substeps} step/sample, "
          f"{res.ball_iterations} ball Newton step(s)): {duration} s simulated in {jax_el:.2f} s "
          f"wall ({jax_cpu:.2f} s CPU) with per-ball records ({jax_lean:.2f} s wall, {lean_cpu:.2f} s "
          f"CPU without): {rate:.2f} s per simulated second "
          f"(target <= 1), {res.num_steps / jax_el:.0f} steps/s; first call (this process, cached "
          f"compilation) {first:.1f} s")
    return res, rate, jax_cpu


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--scipy-duration", type=float, default=0.02)
    ap.add_argument("--count", type=int, default=1000, help="data set items (0: skip (c))")
    ap.add_argument("--count4", type=int, default=1000,
                    help="four-class data set items (0: skip; the 1000-item time is scaled)")
    ap.add_argument("--classes", default="outer,inner,ball",
                    help="defect classes for (a) (outer always; inner, ball: issue 11)")
    ap.add_argument("--no-compile", action="store_true", help="skip (d)")
    args = ap.parse_args()

    import bearingsim  # noqa: F401  (x64)
    from bearingsim import dynamics as dyn
    from bearingsim.case import load_case

    print("machine: 2 shared cores; figures are indicative (other work may run at the same time)")
    case = load_case(_HERE.parent / "cases" / "cwru_6205.toml")
    res, rate, jax_cpu = single_item(dyn, case, args.duration, "(a) simulate (CWRU 6205, 0.021 in")
    others = []
    for cls in [c for c in args.classes.split(",") if c in ("inner", "ball")]:
        oc = load_case(_HERE.parent / "cases" / f"cwru_6205_{cls}.toml")
        others.append((cls,) + single_item(dyn, oc, args.duration, f"(a) {cls} class (cwru_6205_{cls}"))

    c = time.process_time()
    sc_el, out = scipy_baseline(case, res, args.scipy_duration)
    sc_cpu = time.process_time() - c
    sc_rate = sc_el / args.scipy_duration
    print(f"(b) scipy solve_ivp RK45 (numpy RHS, rtol = atol = 1e-5): {args.scipy_duration} s simulated "
          f"in {sc_el:.2f} s ({sc_cpu:.2f} s CPU), {out.nfev} RHS evaluations, status {out.status}: "
          f"{sc_rate:.1f} s per simulated second; bearingsim is {sc_rate / rate:.0f} x faster in wall "
          f"time, {sc_cpu / args.scipy_duration / (jax_cpu / args.duration):.0f} x in CPU time (target >= 50)")
    for cls, _, r_o, cpu_o in others:
        print(f"(b) {cls} class: bearingsim is {sc_rate / r_o:.0f} x faster than the (outer-race) scipy "
              f"baseline in wall time, {sc_cpu / args.scipy_duration / (cpu_o / args.duration):.0f} x in "
              f"CPU time (target >= 50)")

    for spec, count, what in (("dataset_cwru", args.count, "data set"),
                              ("dataset_cwru_4class", args.count4, "four-class data set")):
        if count <= 0:
            continue
        r = dataset_run(spec, count)
        print(f"(c) {what} {count} x {r['duration']} s at {r['fs']:.0f} Hz (chunks of {r['chunk']}, a fresh "
              f"process; {r['its']} ball Newton step(s), {r['subs']} step(s)/sample): {r['el']:.1f} s wall ({r['cpu']:.1f} s CPU) after compilation, {count / r['el']:.1f} "
              f"items/s: 1000 items in ~{1000 * r['el'] / count:.0f} s (target <= 60 s), {r['failed']} failed "
              f"({r['messages'] or 'none'}), file {r['size']:.0f} MB; peak RSS {r['rss']:.0f} MB (before "
              f"{r['rss0']:.0f} MB; target <= 2048)")

    if not args.no_compile:
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, JAX_COMPILATION_CACHE_DIR=cache)
            outp = subprocess.run([sys.executable, "-c", _COMPILE_SNIPPET], env=env, capture_output=True,
                                  text=True, check=True).stdout.split()
        imp, c1, c2 = (float(v) for v in outp[-3:])
        print(f"(d) empty compilation cache, fresh process: import {imp:.1f} s, first 0.05 s simulation "
              f"{c1:.1f} s, second {c2:.2f} s: compilation ~{c1 - c2:.1f} s (target <= 10 s)")


if __name__ == "__main__":
    main()
