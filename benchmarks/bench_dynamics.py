"""Dynamic-layer benchmark: CWRU 6205, 0.021 in rectangular spall, 1797 rpm, 48 kHz output.

  (a) bearingsim.dynamics.simulate: wall seconds per simulated second (after compilation),
      for --duration s (default 0.25) at the case tolerances (rtol = atol = 1e-5);
  (b) scipy.integrate.solve_ivp (RK45, same rtol; atol on the same um / mm/s scaled state) on
      the same equations of motion with a plain numpy right-hand side.  Its bearing force is
      the omega = 0 closed-form Jones ball (benchmarks/reference_scipy.static_balls: collinear
      contacts, K at each contact angle) -- at 1797 rpm within ~1e-5 of the full ball
      equilibrium (F_c ~ 0.2 N), and cheaper than the Newton the JAX side does, so the ratio
      is conservative.  Simulates --scipy-duration s (default 0.02) and scales;
  (c) simulate_batch: --n-batch labelled signals of --batch-duration s (default 1000 x 0.1 s),
      varying load (800-1200 N), spall depth and extent; wall time and peak RSS (getrusage).

Targets: (a) <= 2 s per simulated second; (c) <= 60 s for 1000 signals.
Usage: python benchmarks/bench_dynamics.py [--duration 0.25] [--n-batch 1000]
"""
from __future__ import annotations

import argparse
import importlib.util
import pathlib
import resource
import sys
import time

import numpy as np

_HERE = pathlib.Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("reference_scipy", _HERE / "reference_scipy.py")
ref = importlib.util.module_from_spec(_spec)
sys.modules["reference_scipy"] = ref
_spec.loader.exec_module(ref)


def rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def scipy_baseline(case, res, duration, rtol, atol):
    """RK45 on the same 12 states; numpy RHS with the closed-form ball forces."""
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
    mr = d["resonator_mass"]
    wn = 2 * np.pi * d["resonance_frequency"]
    kr, cr = mr * wn ** 2, 2 * d["resonance_damping_ratio"] * mr * wn
    cb = np.asarray(res.contact_damping)
    wc = 2 * np.pi * res.frequencies["ftf_Hz"]
    th0 = float(case.cage_angle)
    tilts = np.asarray(res.quasi_static.displacement)[3:]
    Z = b.n_balls
    S = np.array([1e-6] * 6 + [1e-3] * 6)

    def rhs(t, u):
        y = u * S
        psi = th0 + wc * t + 2 * np.pi * np.arange(Z) / Z
        q = (y[0] - y[3], y[1] - y[4], y[2], tilts[0], tilts[1])
        H = ref.depth_profile(geom, spall, psi)
        st = ref.static_balls(geom, q, psi, H)
        R = np.array([np.sum(st["Hf"] * np.cos(psi)), np.sum(st["Hf"] * np.sin(psi)), np.sum(st["G"])])
        vs, vh, vr = y[6:9], y[9:11], y[11]
        vrel = vs - np.array([vh[0], vh[1], 0.0])
        Fd = cb * vrel
        a_s = (F - R - Fd) / ms
        Fr = kr * (y[5] - y[3]) + cr * (vr - vh[0])
        a_h = (R[:2] + Fd[:2] - kh * y[3:5] - ch * vh + np.array([Fr, 0.0])) / mh
        a_r = -Fr / mr
        return np.concatenate([vs, vh, [vr], a_s, a_h, [a_r]]) / S

    y0 = np.concatenate([np.asarray(res.shaft_displacement[0]), np.asarray(res.housing_displacement[0]),
                         [float(res.housing_displacement[0, 0])], np.zeros(6)]) / S
    t = time.perf_counter()
    out = solve_ivp(rhs, (0.0, duration), y0, method="RK45", rtol=rtol, atol=atol,
                    t_eval=np.arange(int(duration * 48000)) / 48000.0)
    el = time.perf_counter() - t
    return el, out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=0.25)
    ap.add_argument("--scipy-duration", type=float, default=0.02)
    ap.add_argument("--n-batch", type=int, default=1000)
    ap.add_argument("--batch-duration", type=float, default=0.1)
    ap.add_argument("--batch-chunk", type=int, default=100)
    args = ap.parse_args()

    import bearingsim  # noqa: F401  (x64)
    from bearingsim import dynamics as dyn
    from bearingsim.case import load_case

    case = load_case(_HERE.parent / "cases" / "cwru_6205.toml")
    d = case.dynamics_settings()
    b, op, F, sp = case.bearing(), case.operation(), case.loads(), case.spall()
    p = dyn.DynamicsParameters.from_settings(d)
    kw = dict(theta0=case.cage_angle, rtol=d["rtol"], atol=d["atol"], progress=False)

    t = time.perf_counter()
    res = dyn.simulate(b, op, F, sp, p, args.duration, 48000.0, **kw)
    first = time.perf_counter() - t
    t = time.perf_counter()
    res = dyn.simulate(b, op, F, sp, p, args.duration, 48000.0, **kw)
    jax_el = time.perf_counter() - t
    t = time.perf_counter()
    res2 = dyn.simulate(b, op, F, sp, p, args.duration, 48000.0, ball_iterations=res.ball_iterations, **kw)
    jax_el2 = time.perf_counter() - t
    jax_rate = jax_el2 / args.duration
    print(f"(a) bearingsim.simulate: {args.duration} s simulated, {res.num_steps} steps "
          f"({res.num_steps / args.duration:.0f} steps per simulated s), {res.ball_iterations} ball "
          f"Newton steps; first call {first:.1f} s (compile), then {jax_el:.2f} s incl. the "
          f"lean-solver check, {jax_el2:.2f} s without: {jax_rate:.2f} s per simulated second "
          f"(target <= 2)")

    sc_el, out = scipy_baseline(case, res, args.scipy_duration, d["rtol"], d["atol"])
    sc_rate = sc_el / args.scipy_duration
    print(f"(b) scipy solve_ivp RK45 (numpy RHS): {args.scipy_duration} s simulated in {sc_el:.2f} s, "
          f"{out.nfev} RHS evaluations, status {out.status}: {sc_rate:.1f} s per simulated second")
    print(f"    speed-up of bearingsim over scipy: {sc_rate / jax_rate:.1f} x")

    if args.n_batch > 0:
        n = args.n_batch
        rng = np.random.default_rng(0)
        loads = np.tile(np.asarray(F), (n, 1))
        loads[:, 0] = rng.uniform(800.0, 1200.0, n)
        depth = rng.uniform(0.3, 1.0, n) * float(sp.depth)
        extent = rng.uniform(0.5, 1.0, n) * float(sp.extent)
        speed = np.full(n, 1797.0)
        chunk = min(args.batch_chunk, n)
        rss0 = rss_mb()
        t = time.perf_counter()
        codes = []
        steps = []
        for k in range(0, n, chunk):
            sl = slice(k, min(k + chunk, n))
            m = sl.stop - sl.start
            pad = lambda a: np.concatenate([a[sl], np.repeat(a[sl][-1:], chunk - m, axis=0)])
            r = dyn.simulate_batch(b, pad(speed), pad(loads), np.zeros(chunk), pad(extent), pad(depth),
                                   "rectangular", p, args.batch_duration, 48000.0,
                                   theta0=case.cage_angle, rtol=d["rtol"], atol=d["atol"])
            codes.append(np.asarray(r.result)[:m])
            steps.append(np.asarray(r.num_steps)[:m])
            if k == 0:
                t_first = time.perf_counter() - t
        el = time.perf_counter() - t
        codes = np.concatenate(codes)
        print(f"(c) simulate_batch: {n} signals x {args.batch_duration} s in chunks of {chunk}: "
              f"{el:.1f} s total (first chunk incl. compile {t_first:.1f} s), "
              f"{(el - t_first) / max(1, n - chunk):.3f} s per signal after compile; "
              f"{int(np.sum(codes != 0))} failed; mean steps {np.mean(np.concatenate(steps)):.0f}; "
              f"peak RSS {rss_mb():.0f} MB (before {rss0:.0f} MB) (target <= 60 s)")


if __name__ == "__main__":
    main()
