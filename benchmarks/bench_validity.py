"""Never a silent wrong answer: random valid cases through the batched solver (issue 8).

Draws N random cases per (ball count, raceway control, spall profile) -- geometry, combined loads
up to 20 kN, speeds up to 20 000 rpm, spalls up to 1 mm deep (a fifth healthy) -- solves them as
one batch, and re-checks every item reported converged in numpy from its per-ball output:
no loaded contact with |alpha| >= 90 deg, ring and ball equilibrium to 1e-8 of the load scale,
everything finite.  Prints counts: converged, flagged (by result code) and converged-but-invalid
(must be 0).

Then (issue 27) the verdicts of the Python API and of the command line on the same 1000 random
cases of the Harris 218 (the demo bearing; 0-12 000 rpm, thrust 0-20 kN, radial loads to 6 kN,
moments to 200 N m, a third with the demo spall): ``bearingsim.solve`` against
``workflows.solve_case`` of the case file (what ``bearingsim static`` runs), and the command's
exit code on a sample; prints how many codes differ (target 0) and how many converged states have
a loaded contact at or beyond a shoulder (target 0).

    python benchmarks/bench_validity.py [N_PER_GROUP] [N_VERDICT]   (defaults 200 -> 2400 cases; 1000)
"""
from __future__ import annotations

import functools
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

import bearingsim as bs
from bearingsim.physics import jones
from bearingsim.xla import compiler_options

GROUPS = [(z, c, p) for z, c in ((7, "outer"), (12, "inner"), (14, "outer"), (24, "equal"),
                                 (9, "inner"), (16, "equal"))
          for p in ("ball-path", "rectangular")]


def draw(rng, n):
    D = rng.uniform(5e-3, 25e-3, n)
    cols = dict(
        D=D, dm=D * rng.uniform(3.5, 8.0, n), fi=rng.uniform(0.505, 0.54, n),
        fo=rng.uniform(0.505, 0.54, n), a0=np.radians(rng.uniform(0.0, 40.0, n)),
        rpm=rng.choice([0.0, 3000.0, 7600.0, 12000.0, 20000.0], n),
        Fx=rng.uniform(-20000, 20000, n), Fy=rng.uniform(-5000, 5000, n), Fa=rng.uniform(0, 20000, n),
        Mx=rng.uniform(-50, 50, n), My=rng.uniform(-50, 50, n), cage=rng.uniform(0, 2 * np.pi, n),
        c=rng.uniform(0, 2 * np.pi, n), ext=np.radians(rng.uniform(1.0, 15.0, n)),
        depth=rng.choice([0.0, 0.05e-3, 0.3e-3, 0.5e-3, 1.0e-3], n))
    return cols


@functools.lru_cache(maxsize=None)
def batch_solver(Z, control, profile, speed_steps=1):
    def one(geo, w, F, spall, cage):
        b = bs.Bearing(Z, *geo)
        sp = bs.Spall(spall[0], spall[1], spall[2], profile)
        return jones.solve_state(b, bs.Operation(w, control), F, cage_angle=cage, spall=sp,
                                 speed_steps=speed_steps)

    return jax.jit(jax.vmap(one), compiler_options=compiler_options())


def check(Z, control, geo, w, sol):
    """numpy re-check of one converged item: (inverted contacts, ring error, ball error)."""
    D, dm, fi, fo, a0 = geo
    b = bs.Bearing(Z, *geo)
    lam_i, lam_o = bs.Operation(w, control).factors
    ai, ao, Qi, Qo, Mg, Fc, psi = (np.asarray(x) for x in (
        sol.alpha_inner, sol.alpha_outer, sol.Q_inner, sol.Q_outer, sol.gyroscopic_moment,
        sol.centrifugal, sol.azimuth))
    G = Qi * np.sin(ai) + lam_i * Mg / D * np.cos(ai)
    H = Qi * np.cos(ai) - lam_i * Mg / D * np.sin(ai)
    Ri = float(b.inner_groove_radius)
    m = Ri * G - lam_i * fi * Mg
    r1 = G - Qo * np.sin(ao) - lam_o * Mg / D * np.cos(ao)
    r2 = H - Qo * np.cos(ao) + lam_o * Mg / D * np.sin(ao) + Fc
    R = np.array([np.sum(H * np.cos(psi)), np.sum(H * np.sin(psi)), np.sum(G),
                  np.sum(m * np.sin(psi)) / Ri, -np.sum(m * np.cos(psi)) / Ri])
    F = np.asarray(sol.loads) * np.array([1, 1, 1, 1 / Ri, 1 / Ri])
    scale = max(np.max(np.abs(F)), np.max(Qo), np.max(Qi), 1.0)
    inverted = np.sum((Qi > 0) & (np.cos(ai) <= 0)) + np.sum((Qo > 0) & (np.cos(ao) <= 0))
    finite = all(np.all(np.isfinite(np.asarray(x))) for x in (ai, ao, Qi, Qo, sol.displacement, sol.stiffness))
    return int(inverted), np.max(np.abs(R - F)) / scale, max(np.abs(r1).max(), np.abs(r2).max()) / scale, finite


def main(n=200, seed=0):
    rng = np.random.default_rng(seed)
    total = dict(cases=0, converged=0, invalid=0)
    codes_all = {}
    t_all = 0.0
    for Z, control, profile in GROUPS:
        c = draw(rng, n)
        geo = np.stack([c[k] for k in ("D", "dm", "fi", "fo", "a0")], axis=1)
        F = np.stack([c[k] for k in ("Fx", "Fy", "Fa", "Mx", "My")], axis=1)
        spall = np.stack([c[k] for k in ("c", "ext", "depth")], axis=1)
        w = c["rpm"] * np.pi / 30
        f = batch_solver(Z, control, profile)
        t0 = time.perf_counter()
        args = [jnp.asarray(a) for a in (geo, w, F, spall, c["cage"])]
        sol = f(*args)
        codes = np.asarray(sol.result)
        redo = np.flatnonzero(codes != 0)
        if redo.size:   # as solve / solve_batch do: failed items again in 8 speed steps
            r = batch_solver(Z, control, profile, 8)(*[a[redo] for a in args])
            ok = np.asarray(r.result) == 0
            idx = jnp.asarray(redo[ok])
            sol = jax.tree_util.tree_map(lambda a, b_: a.at[idx].set(b_[jnp.asarray(ok)]), sol, r)
            codes = np.asarray(sol.result)
        t_all += time.perf_counter() - t0
        bad = []
        for k in np.flatnonzero(codes == 0):
            one = jax.tree_util.tree_map(lambda a: a[k], sol)
            inv, ering, eball, finite = check(Z, control, geo[k], w[k], one)
            if inv or ering > 1e-8 or eball > 1e-8 or not finite:
                bad.append((k, inv, ering, eball, finite))
        for code, cnt in zip(*np.unique(codes, return_counts=True)):
            codes_all[int(code)] = codes_all.get(int(code), 0) + int(cnt)
        total["cases"] += n
        total["converged"] += int(np.sum(codes == 0))
        total["invalid"] += len(bad)
        print(f"Z={Z:2d} {control:5s} {profile:11s}: converged {np.sum(codes == 0):4d}/{n}, "
              f"codes {dict(zip(*[a.tolist() for a in np.unique(codes, return_counts=True)]))}, "
              f"converged-but-invalid {len(bad)}", flush=True)
        for row in bad[:3]:
            print("   invalid:", row, {k: float(v[row[0]]) for k, v in c.items()})
    print(f"\n{total['cases']} random cases: {total['converged']} converged and valid, "
          f"{total['cases'] - total['converged']} flagged "
          f"({', '.join(f'{bs.RESULTS.of(k).name}: {v}' for k, v in sorted(codes_all.items()) if k)}), "
          f"converged but invalid: {total['invalid']} (target 0); solve time {t_all:.1f} s")
    return total


B218_CASE = """\
title = "random 218"
[bearing]
balls = 16
ball_diameter_mm = 22.225
pitch_diameter_mm = 125.26
inner_groove_curvature = 0.5232
outer_groove_curvature = 0.5232
free_contact_angle_deg = 40.0
[operation]
speed_rpm = {rpm}
cage_angle_deg = {cage}
[load]
axial_N = {Fa}
radial_x_N = {Fx}
radial_y_N = {Fy}
moment_x_Nm = {Mx}
moment_y_Nm = {My}
"""
DEFECT = '[defect]\ncenter_deg = 0.0\nextent_deg = 3.0\ndepth_mm = 0.3\nprofile = "rectangular"\n'


def verdicts(n=1000, seed=27, cli_sample=40, tmp=None):
    """Codes of ``bearingsim.solve`` and of the command line's path on n random 218 cases."""
    import tempfile
    import warnings
    from pathlib import Path

    from bearingsim.app import workflows
    from bearingsim.case import parse_case
    from bearingsim.app.cli import main as cli_main
    from bearingsim.physics.limits import contact_limits

    rng = np.random.default_rng(seed)
    rpm = rng.choice([0.0, 6000.0, 10000.0, 12000.0], n)
    Fa = rng.uniform(0.0, 20000.0, n)
    Fx, Fy = rng.uniform(-6000.0, 6000.0, (2, n))
    Mx, My = rng.uniform(-200.0, 200.0, (2, n))
    cage = rng.uniform(0.0, 22.5, n)
    defect = rng.uniform(size=n) < 1.0 / 3.0
    differ, over, codes = [], 0, {}
    cli_rows = set(rng.choice(n, min(cli_sample, n), replace=False).tolist())
    cli_differ = []
    tmp = Path(tempfile.mkdtemp() if tmp is None else tmp)
    t0 = time.perf_counter()
    for k in range(n):
        text = B218_CASE.format(rpm=rpm[k], cage=cage[k], Fa=Fa[k], Fx=Fx[k], Fy=Fy[k], Mx=Mx[k],
                                My=My[k]) + (DEFECT if defect[k] else "")
        case = parse_case(text, f"r{k}.toml")
        b, op = case.bearing(), case.operation()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            api = bs.solve(b, op, case.loads(), cage_angle=case.cage_angle, spall=case.spall(), throw=False)
            cli = workflows.solve_case(case, throw=False)
        a, c = int(api.result), int(cli.result)
        codes[a] = codes.get(a, 0) + 1
        if a != c:
            differ.append((k, a, c))
        if a == 0 and bool(contact_limits(api, b, op.control).any_over_shoulder):
            over += 1
        if k in cli_rows:               # the command itself: exit 0 for code 0, 3 for a refusal
            p = tmp / f"r{k}.toml"
            p.write_text(text)
            import contextlib
            import io as _io
            with contextlib.redirect_stdout(_io.StringIO()), contextlib.redirect_stderr(_io.StringIO()), \
                    warnings.catch_warnings():
                warnings.simplefilter("ignore")
                rc = cli_main(["static", str(p)])
            if rc != (0 if a == 0 else 3):
                cli_differ.append((k, a, rc))
    dt = time.perf_counter() - t0
    print(f"\nPython API vs command line on {n} random 218 cases (seed {seed}, a third with the demo spall): "
          f"codes differ in {len(differ)} (target 0); `bearingsim static` exit codes checked on {len(cli_rows)}: "
          f"{len(cli_differ)} differ (target 0); converged states with a loaded contact at or beyond a "
          f"shoulder: {over} (target 0); codes "
          f"{', '.join(f'{bs.RESULTS.of(k).name}: {v}' for k, v in sorted(codes.items()))}; {dt:.1f} s")
    for row in (differ + cli_differ)[:5]:
        print("   differs:", row)
    return dict(differ=len(differ), cli_differ=len(cli_differ), over=over, codes=codes)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 200)
    verdicts(int(sys.argv[2]) if len(sys.argv) > 2 else 1000)
