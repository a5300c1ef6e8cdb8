"""Data sets at scale (issue 22): in-process vs a local Dask cluster, identical bytes, client costs.

    python benchmarks/bench_scale.py            # the table (~5-10 min on 2 cores)
    python benchmarks/bench_scale.py --quick    # 160 items instead of 1000

Rows: 1000 x 0.1 s four-class items (cases/dataset_cwru_4class.toml) in-process after compile
(the same run twice in one process; the second is timed) with its CPU use (user+sys / wall:
XLA already uses both cores in-process), the same on a LocalCluster of 1 and 2 workers (start-up
included, compilation cache warm), the bytes of `signals` and `labels` of the three files
compared, the client's own cost per chunk (write of the chunk file, pickling of the result) vs
the chunk's compute, the network volume per 1000 items, the cold worker (start + first chunk
minus a warm chunk), and the client's peak memory for 10^5 items streamed through a 2-worker
cluster with a cheap stand-in chunk function (zeros of the real shapes: the real one would take
hours here; what is measured is the client's streaming, not the physics).

The machine is shared (other jobs run): timings are noisy; ratios are from one run.
"""
from __future__ import annotations

import argparse
import os
import pickle
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SPEC = ROOT / "cases" / "dataset_cwru_4class.toml"


def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


class Timed:
    """A runner wrapper: per chunk, the time the client spends on it after it arrived (writing
    the chunk file) and when it arrived."""

    def __init__(self, runner=None):
        from bearingsim.datasets import serial_imap

        self.imap_of = runner.imap if runner is not None else serial_imap
        self.client_s, self.arrivals, self.sizes = [], [], []

    def imap(self, fn, shared, items):
        from bearingsim.datasets import simulate_chunk

        if fn is simulate_chunk:
            self.t_call = time.perf_counter()
        for x, r in self.imap_of(fn, shared, items):
            now = time.perf_counter()
            if fn is simulate_chunk:
                self.arrivals.append(now)
                t0 = time.perf_counter()
                self.sizes.append(len(pickle.dumps(r, protocol=5)))
                pickle.loads(pickle.dumps(r, protocol=5))
                self.pickle_s = getattr(self, "pickle_s", 0.0) + time.perf_counter() - t0
            yield x, r
            if fn is simulate_chunk:
                self.client_s.append(time.perf_counter() - now)


def run(case, out, workers=None, timed=None):
    from bearingsim.datasets import make_dataset
    from bearingsim.datasets.distributed import DaskRunner

    t0, c0 = time.perf_counter(), cpu()
    if workers is None:
        s = make_dataset(case, out, progress=False, runner=timed)
        start = 0.0
    else:
        with DaskRunner(workers=workers) as r:
            start = time.perf_counter() - t0
            tm = Timed(r) if timed is None else timed
            tm.imap_of = r.imap
            s = make_dataset(case, out, progress=False, runner=tm)
    return time.perf_counter() - t0, cpu() - c0, start, s


def same(a, b):
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        return (fa["signals"][()].tobytes() == fb["signals"][()].tobytes()
                and fa["labels"][()].tobytes() == fb["labels"][()].tobytes())


def client_memory(n, tmp):
    """Peak RSS of a client streaming n items through 2 workers (stand-in chunk function)."""
    code = f"""
import resource, sys, time
import numpy as np
import bearingsim.datasets as dsm
from bearingsim.case import load_case
from bearingsim.datasets.distributed import DaskRunner

def cheap_chunk(plan, k):
    idx = plan.items(k)
    T = int(round(plan.duration * plan.fs))
    z = np.zeros(idx.size)
    return dict(index=idx, signals=np.zeros((idx.size, T), np.float32), result=np.zeros(idx.size, np.int32),
                ball_iterations=np.ones(idx.size, np.int32), **{{k: z for k in dsm.CHUNK_FIELDS if k != "result"}})

class Cheap:
    def __init__(self, r): self.r = r
    def imap(self, fn, shared, items):
        fn = {{dsm.simulate_chunk: cheap_chunk}}[fn]
        return self.r.imap(fn, shared, items)

if __name__ == "__main__":
    dsm.runner.run_settings = lambda *a: 1
    case = load_case("{SPEC}").with_value("dataset.count", {n})
    t0 = time.perf_counter()
    with DaskRunner(workers=2) as r:
        s = dsm.make_dataset(case, "{tmp}/big.h5", progress=False, runner=Cheap(r))
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024, time.perf_counter() - t0)
"""
    f = Path(tmp) / "client_memory.py"
    f.write_text(code)
    out = subprocess.run([sys.executable, str(f)], capture_output=True, text=True, cwd=tmp)
    if out.returncode:
        raise RuntimeError(out.stderr[-2000:])
    peak, secs = out.stdout.split()[-2:]
    (Path(tmp) / "big.h5").unlink(missing_ok=True)
    return float(peak), float(secs)


def main():
    from bearingsim.case import load_case

    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="160 items instead of 1000; 10^4 for the memory row")
    a = ap.parse_args()
    n = 160 if a.quick else 1000
    n_big = 10_000 if a.quick else 100_000
    case = load_case(SPEC).with_value("dataset.count", n)
    chunk = int(case.data["dataset"]["chunk"])
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        # in-process: the first run compiles (and fills the persistent cache the workers read)
        t_first, _, _, _ = run(case, tmp / "warm.h5")
        tm = Timed()
        t_in, c_in, _, s = run(case, tmp / "in.h5", timed=tm)
        chunk_s = float(np.median(np.diff(tm.arrivals)))          # in-process: one chunk's compute
        t_w1, _, start1, _ = run(case, tmp / "w1.h5", workers=1)
        tw = Timed()
        t_w2, c_w2, start2, _ = run(case, tmp / "w2.h5", workers=2, timed=tw)
        ident = same(tmp / "in.h5", tmp / "w1.h5") and same(tmp / "in.h5", tmp / "w2.h5") and \
            same(tmp / "in.h5", tmp / "warm.h5")
        client = np.median(tw.client_s) + tw.pickle_s / len(tw.sizes)
        per_1000 = sum(tw.sizes) * 1000 / n
        cold = start2 + (tw.arrivals[0] - tw.t_call) - chunk_s    # start + first chunk - a warm one
        peak, secs_big = client_memory(n_big, tmp)

    gain = t_in / t_w2
    print(f"bench_scale: {n} x 0.1 s four-class items ({SPEC.name}), chunk {chunk}; shared 2-core machine: noisy\n")
    print(f"| figure | measured | target |")
    print(f"|---|---|---|")
    print(f"| {n} items in-process, first run (compiles) | {t_first:.1f} s | - |")
    print(f"| {n} items in-process, after compile | {t_in:.1f} s, CPU use {c_in / t_in:.2f} cores | <= 30 s x {n}/1000 |")
    print(f"| {n} items, `--workers 1` (start-up {start1:.1f} s included) | {t_w1:.1f} s | - |")
    print(f"| {n} items, `--workers 2` (start-up {start2:.1f} s included) vs in-process | {t_w2:.1f} s: {gain:.2f}x | >= 1.3x |")
    print(f"| client cost per chunk (write + pickle) vs chunk compute | {1e3 * client:.1f} ms vs {chunk_s:.2f} s: "
          f"{100 * client / chunk_s:.1f} % | <= 5 % |")
    print(f"| same bytes in signals and labels: in-process, 1, 2 workers | {'identical' if ident else 'DIFFERENT'} | identical |")
    print(f"| network volume per 1000 items (results) | {per_1000 / 1e6:.1f} MB | - |")
    print(f"| cold worker (start-up + first chunk - a warm chunk; compilation cache warm) | {cold:.1f} s | - |")
    print(f"| peak client memory, {n_big} items streamed (stand-in chunks) | {peak / 1e9:.2f} GB ({secs_big:.0f} s) | <= 1 GB |")
    print(f"| items/s: in-process {n / t_in:.1f}, 2 workers {n / t_w2:.1f} ({n / t_w2 / 2:.1f} per worker) | | |")


if __name__ == "__main__":
    main()
