"""The dynamics of a data set on the device program (issue 25): 1000 four-class-like items of
0.1 s at 48 kHz (random speed, loads, pit locations and sizes with depth_rule "pit", sensor
modes) through dynamics.chunk_program, chunk by chunk (prepare with the pit rule + run), twice
in one process (the second pass is warm).  Dynamics only: no background, noise, pass
variability or writing.

Usage: python benchmarks/bench_chunk_program.py CHUNK [ITERATIONS]
       (ITERATIONS: force one Newton step count instead of the per-chunk menu)
Pin it to one core (taskset -c 0) for the steadiest figure on a shared machine."""
import time, sys, numpy as np, jax, jax.numpy as jnp, jax.tree_util as tu, collections
from bearingsim import dynamics as dyn
from bearingsim.case import load_case
C = int(sys.argv[1]); NT = 1000
c = load_case("cases/dataset_cwru_4class.toml"); b = c.bearing(); d = c.dynamics_settings()
realism = dyn.Realism.from_settings(d); p0 = dyn.DynamicsParameters.from_settings(d)
rng = np.random.default_rng(5)
speed = rng.uniform(1720, 1800, NT); loads = np.zeros((NT, 5)); loads[:, 0] = rng.uniform(20, 400, NT); loads[:, 2] = rng.uniform(10, 150, NT)
loc = rng.integers(0, 3, NT); center = np.where(loc == 0, rng.choice([0, 0, np.pi/2, -np.pi/2, np.pi], NT), rng.uniform(0, 2*np.pi, NT))
w = rng.uniform(0.1778e-3, 1.016e-3, NT)
extent = np.where(loc == 2, w / (0.5 * float(b.ball_diameter)), w / (0.5 * float(b.pitch_diameter)))
depth = np.where(rng.random(NT) < 0.25, 0.0, 1.0)
modes = [rng.uniform(lo, hi, (NT, 2)) for lo, hi in ((1500, 5500), (0.01, 0.08), (0.3, 10))]
params = tu.tree_map(lambda a: jnp.broadcast_to(a, (C,)) if a.ndim == 0 else a, p0)
prog = dyn.chunk_program(b, realism=realism, samples=4800, max_speed_rpm=1800)
def chunk(k):
    i = np.arange(k, k + C) % NT
    a = jax.device_put((dyn.item_keys(0, i), speed[i], loads[i], np.zeros(C), loc[i], center[i], extent[i], depth[i], tuple(m[i] for m in modes), params))
    return prog(*a, pit=(jnp.asarray(w[i]), jnp.full(C, 0.2794e-3)), iterations=(int(sys.argv[2]) if len(sys.argv) > 2 else None))
t = time.perf_counter(); out = chunk(0); jax.block_until_ready(out["sensor"]); print("first chunk (compile)", round(time.perf_counter() - t, 1), flush=True)
for rep in range(2):
  t, c0 = time.perf_counter(), time.process_time(); its = []; calls0 = prog.calls
  for k in range(0, NT, C):
    out = chunk(k); its.append(out["ball_iterations"])
  jax.block_until_ready(out["sensor"])
  print(rep, "programs", prog.calls - calls0, f"chunk {C}: {NT} items x 0.1 s: wall {time.perf_counter() - t:.1f} s, cpu {time.process_time() - c0:.1f} s, counts per chunk {collections.Counter(its)}", flush=True)
