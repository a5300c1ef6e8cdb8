"""Where a warm 16-item GPU data set's seconds go: cProfile of the whole command (start-up, program
loads, the call) and a device trace of a second call in the same process, summarised per GPU line
and per kernel name.  ``python benchmarks/profile_gpu_small.py`` on a machine with a GPU; writes
OUT/profile.txt (``$OUT`` or the current folder)."""
from __future__ import annotations

import glob
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_dataset import PY, _env, spec_file  # noqa: E402

CODE = r'''
import cProfile, pstats, sys, time, io
S, OUT = sys.argv[1], sys.argv[2]
t0 = time.perf_counter()
pr = cProfile.Profile(); pr.enable()
from bearingsim.app.cli import main
main(["dataset", S, "-o", "b.h5"])
pr.disable()
print("WHOLE first call in a fresh process", round(time.perf_counter() - t0, 2))
s = io.StringIO(); pstats.Stats(pr, stream=s).sort_stats("cumulative").print_stats(45); print(s.getvalue()[-9000:])
s = io.StringIO(); pstats.Stats(pr, stream=s).sort_stats("tottime").print_stats(20); print(s.getvalue()[-4000:])
import jax
jax.profiler.start_trace(OUT + "/trace")
t1 = time.perf_counter(); main(["dataset", S, "-o", "c.h5"]); print("SECOND call traced", round(time.perf_counter() - t1, 2))
jax.profiler.stop_trace()
'''


def summarise(out):
    import jax
    lines = []
    for p in glob.glob(f"{out}/trace/**/*.xplane.pb", recursive=True):
        pd = jax.profiler.ProfileData.from_file(p)
        for pl in pd.planes:
            if not pl.name.startswith("/device:"):
                continue
            for ln in pl.lines:
                by, n, busy, lo, hi = {}, 0, 0.0, None, None
                for ev in ln.events:
                    n += 1
                    busy += ev.duration_ns
                    lo = ev.start_ns if lo is None else min(lo, ev.start_ns)
                    hi = ev.end_ns if hi is None else max(hi, ev.end_ns)
                    c = by.setdefault(ev.name, [0, 0.0])
                    c[0] += 1
                    c[1] += ev.duration_ns
                if not n:
                    continue
                lines.append(f"{pl.name} | {ln.name}: {n} events, busy {busy / 1e9:.3f} s over a span of "
                             f"{(hi - lo) / 1e9:.3f} s")
                for name, (k, d) in sorted(by.items(), key=lambda kv: -kv[1][1])[:15]:
                    lines.append(f"    {d / 1e9:8.3f} s  {k:8d} x  {name[:110]}")
    return lines


def main():
    out = os.environ.get("OUT", ".")
    tmp = tempfile.mkdtemp()
    s16 = str(spec_file(tmp, 16, name="s16.toml"))
    env = _env()
    warm = subprocess.run([PY, "-c", "import sys; from bearingsim.app.cli import main; sys.exit(main(sys.argv[1:]))",
                           "dataset", s16, "-o", "a.h5"], env=env, cwd=tmp, capture_output=True, text=True)
    print("warm-up rc", warm.returncode, warm.stderr[-500:], flush=True)
    p = subprocess.run([PY, "-c", CODE, s16, out], env=env, cwd=tmp, capture_output=True, text=True)
    text = p.stdout + p.stderr[-3000:]
    text += "\n".join(summarise(out))
    Path(out, "profile.txt").write_text(text)
    print(text[-11000:])
    for f in glob.glob(f"{out}/trace/**/*.xplane.pb", recursive=True):
        if os.path.getsize(f) > 40 << 20:
            os.remove(f)


if __name__ == "__main__":
    main()
