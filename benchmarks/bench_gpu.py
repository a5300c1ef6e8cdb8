"""Issue 32's GPU figures in one short run (a device lease is ~15 minutes): what a user meets.

    python benchmarks/bench_gpu.py [--out DIR] [--widths 8192,16384,32768] [--big 100000] [--budget-s 420]

Rows, each a fresh process with the XLA defaults users get (the benchmark's own cache folders,
never an earlier session's):

1. ``bearingsim dataset`` of the four-class spec, 16 items of 0.1 s at 48 kHz: empty cache, then
   warm (min / median of three runs);
2. the GPU micro-batch width W (:data:`bearingsim.datasets.MICRO_BATCH`): per W, one process
   runs a W-item data set twice, the first call traces, compiles and runs, the second runs warm
   in the same process (items/s of the whole call: labels, programs, signal stage, writing); the
   device's peak memory per item and sample says what W the card holds;
3. 10^5 items as a whole command, warm cache, at the fastest W of row 2 (fewer items where the
   budget would not hold them, with the figure scaled and marked so).

Variants of row 1 (the twelfth session's runs, docs/scale.md): ``--small-width W`` (row 1's W),
``--xla-flags=FLAGS`` (XLA_FLAGS of the measured processes; give it with ``=``: the value starts
with ``--``), ``--keep-small NAME`` (OUT/NAME.h5 kept) and ``--compare A,B`` (whether two kept files
hold the same bytes); ``--widths ""`` and ``--big 0`` skip rows 2 and 3.

Each figure is printed as it comes and appended to ``--out``/gpu.txt (a lease can end early).
On a machine without a GPU it says so and stops (CI never runs it).
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_dataset import PY, _env, counts_of, spec_file  # noqa: E402

#: the prelude of a measured process: the micro-batch width W set for the GPU (the share of
#: memory lifted so that the width asked for is the width run), then ``bearingsim`` as a user
#: calls it, each call timed, the device's peak memory and the program counts printed
CODE = """
import sys, time
W = int(sys.argv[1]); n_calls = int(sys.argv[2]); args = sys.argv[3:]
import bearingsim.datasets.program as P
if W:
    P.MICRO_BATCH["gpu"] = P.MICRO_BATCH["cpu"] = W
    P.GPU_MEMORY_SHARE = 1.0
from bearingsim.app.cli import main
for i in range(n_calls):
    a = [x.replace("CALL", str(i)) for x in args]
    t0 = time.perf_counter(); rc = main(a); print("CALL", i, rc, time.perf_counter() - t0, flush=True)
    if rc:
        sys.exit(rc)
import jax
s = jax.devices()[0].memory_stats() or {}
print("PEAK", s.get("peak_bytes_in_use", 0), s.get("bytes_limit", 0))
from bearingsim import programs
c = programs.counts()
print("COUNTS", c["traced"], c["loaded"], c["compiled"], c["compile_cache_hits"])
"""


#: XLA flags of every measured process (``--xla-flags``; users' default: none)
XLA_FLAGS = ""


def measured(W, n_calls, args, tmp, cache=None, timeout=None):
    """(whole wall, [per-call seconds], peak device bytes, stdout) of one process."""
    env = _env(cache)
    if XLA_FLAGS:
        env["XLA_FLAGS"] = XLA_FLAGS
    t0 = time.perf_counter()
    p = subprocess.run([PY, "-c", CODE, str(W), str(n_calls), *args], env=env, cwd=tmp,
                       capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(p.stdout[-1500:] + p.stderr[-2500:])
    calls = [float(ln.split()[3]) for ln in p.stdout.splitlines() if ln.startswith("CALL ")]
    peak = [int(ln.split()[1]) for ln in p.stdout.splitlines() if ln.startswith("PEAK")]
    return wall, calls, (peak[-1] if peak else 0), p.stdout


def small(ds, tmp, say, W=0, keep=None):
    """Row 1: the 16-item data set, empty cache (the benchmark's own, empty at its start), then
    warm (min / median of three); ``W`` the micro-batch width (0: the shipped rule); ``keep`` a
    path to copy the last warm run's file to (to compare the bytes of two variants)."""
    tag = f" (W {W}{', XLA_FLAGS ' + XLA_FLAGS if XLA_FLAGS else ''})" if (W or XLA_FLAGS) else ""
    w, calls, _, out = measured(W, 1, ds, tmp)
    say(f"16 items{tag}, whole command, empty cache: {w:.1f} s (the call {calls[0]:.1f} s); {counts_of(out)}")
    walls, inproc = [], []
    for _ in range(3):
        w, calls, _, out = measured(W, 1, ds, tmp)
        walls.append(w)
        inproc.append(calls[0])
    walls.sort()
    inproc.sort()
    say(f"16 items{tag}, whole command, warm: min {walls[0]:.1f} / median {walls[1]:.1f} s (target <= 5 s); "
        f"the call min {inproc[0]:.2f} / median {inproc[1]:.2f} s in-process; {counts_of(out)}")
    if keep:
        shutil.copy(Path(tmp) / ds[ds.index("-o") + 1].replace("CALL", "0"), keep)


def compare(out, names, say):
    """Say whether the kept files ``names`` (OUT/NAME.h5) of two variants hold the same bytes."""
    import h5py
    import numpy as np
    got = []
    for n in names:
        with h5py.File(Path(out) / f"{n}.h5", "r") as h:
            got.append((h["signals"][()].astype(float), h["labels"][()].tobytes()))
    (x, la), (y, lb) = got
    if np.array_equal(x, y) and la == lb:
        say(f"{names[0]} vs {names[1]}: identical signals and labels")
        return
    peak = np.maximum(np.abs(x).max(axis=1), 1e-300)
    say(f"{names[0]} vs {names[1]}: labels {'identical' if la == lb else 'DIFFER'}; signals differ by <= "
        f"{np.max(np.abs(x - y).max(axis=1) / peak):.1e} of the item's peak")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.environ.get("OUT", "."))
    ap.add_argument("--widths", default="8192,16384,32768")
    ap.add_argument("--big", type=int, default=100000)
    ap.add_argument("--budget-s", type=float, default=420.0, help="stop starting new rows after this")
    ap.add_argument("--no-small", action="store_true", help="skip row 1 (the 16-item figures)")
    ap.add_argument("--device", default="gpu", help="cpu: try the script's flow on a CPU (small --widths)")
    ap.add_argument("--small-width", type=int, default=0, help="row 1's W (0: the shipped rule)")
    ap.add_argument("--xla-flags", default="", help="XLA_FLAGS of the measured processes (default: none)")
    ap.add_argument("--keep-small", default="", help="copy row 1's last file to OUT/NAME.h5")
    ap.add_argument("--compare", default="", help="A,B: compare OUT/A.h5 and OUT/B.h5 (kept by --keep-small) and stop")
    a = ap.parse_args()
    if a.compare:
        compare(a.out, a.compare.split(","), print)
        return 0
    global XLA_FLAGS
    XLA_FLAGS = a.xla_flags
    start = time.perf_counter()
    log = Path(a.out) / "gpu.txt"

    def say(s):
        print(s, flush=True)
        with open(log, "a") as f:
            f.write(s + "\n")

    import jax
    gpus = [d for d in jax.devices() if d.platform == a.device]
    if not gpus:
        say(f"no GPU: JAX sees {jax.devices()}; nothing measured")
        return 0
    dev = gpus[0]
    lim = (dev.memory_stats() or {}).get("bytes_limit", 0)
    say(f"device {dev.device_kind}, jax {jax.__version__}, bytes_limit {lim / 2**30:.1f} GiB, "
        f"{os.cpu_count()} cores visible; python {sys.version.split()[0]}")
    with tempfile.TemporaryDirectory() as tmp:
        s16 = str(spec_file(tmp, 16, name="s16.toml"))
        ds = ["dataset", s16, "-o", "s16-CALL.h5", "--device", a.device]
        if not a.no_small:
            small(ds, tmp, say, a.small_width, a.keep_small and str(Path(a.out) / f"{a.keep_small}.h5"))
        rate = {}
        for W in [int(x) for x in a.widths.split(",") if x.strip()]:
            left = a.budget_s - (time.perf_counter() - start)
            if left < 60:
                say(f"W {W}: skipped, {left:.0f} s of the budget left")
                continue
            sw = str(spec_file(tmp, W, chunk=0, name=f"w{W}.toml"))
            try:
                w, calls, peak, out = measured(W, 2, ["dataset", sw, "-o", f"w{W}-CALL.h5", "--device", a.device],
                                               tmp, timeout=max(60.0, left))
            except (RuntimeError, subprocess.TimeoutExpired) as e:
                say(f"W {W}: failed: {str(e)[-800:]}")
                continue
            rate[W] = W / calls[1]
            say(f"W {W}: first call (trace, compile, run) {calls[0]:.1f} s; warm call {calls[1]:.1f} s = "
                f"{rate[W]:.0f} items/s; peak device memory {peak / 2**30:.2f} GiB = "
                f"{peak / (W * 4800):.0f} B per item and sample; {counts_of(out)}")
        if not rate or a.big <= 0:
            say(f"bench_gpu: {time.perf_counter() - start:.0f} s in all")
            return 0 if (rate or a.widths.strip() == "") else 1
        best = max(rate, key=rate.get)
        left = a.budget_s + 150 - (time.perf_counter() - start)
        m = a.big
        while m > 1000 and m / rate[best] * 1.3 + 30 > left:
            m //= 2
        sb = str(spec_file(tmp, m, chunk=0, name="big.toml"))
        bd = ["dataset", sb, "-o", "big.h5", "--device", a.device]
        try:
            w, calls, peak, out = measured(best, 1, bd, tmp, timeout=max(60.0, left))
        except (RuntimeError, subprocess.TimeoutExpired) as e:
            say(f"{m} items at W {best}: failed: {str(e)[-800:]}")
            return 1
        note = "" if m == a.big else f" (measured {m}; {a.big} scaled: {w * a.big / m:.0f} s)"
        say(f"{m} items of 0.1 s at 48 kHz, whole command, warm, W {best}: {w:.1f} s = {m / w:.0f} items/s"
            f"{note} (target <= 60 s for 10^5); {counts_of(out)}")
    say(f"bench_gpu: {time.perf_counter() - start:.0f} s in all")
    return 0


if __name__ == "__main__":
    sys.exit(main())
