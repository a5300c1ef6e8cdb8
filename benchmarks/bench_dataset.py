"""The data engine's targets (issue 25): prints every figure with the device it ran on.

    python benchmarks/bench_dataset.py [--quick] [--device cpu|gpu] [--codecs-only]

Rows (issue 32's table): ``bearingsim dataset`` of 16 items with an empty cache and warm (min and
median of three runs); the four-class spec (1000 x 0.1 s at 48 kHz, every ingredient on) as a
whole command, warm; 10^5 items on a GPU (only where JAX sees one); ``--workers 2`` against
in-process; ``bearingsim simulate cwru_6205`` and ``bearingsim static demo`` with an empty cache
and warm; host memory; identical bytes across chunk sizes; and the writer: /signals codecs
(write MB/s, read MB/s, size for 2000 x 4800 float32 samples) and the chunk files (.npy folder vs
npz).  Every command runs in a fresh process with the XLA defaults users get; "empty cache" is a
new cache folder, "warm" the benchmark's own folder after one run of the same command (never a
cache of an earlier session).  Each data set line prints how many programs the process traced,
loaded and compiled (:func:`bearingsim.programs.counts`).  ``--quick``: 64 items instead of 1000,
10^3 instead of 10^5, one run per warm figure, 200 codec items.
"""
from __future__ import annotations

import argparse
import atexit
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
PY = sys.executable


def _env(cache=None):
    """The environment of a measured command: ``cache`` a compilation + program cache folder
    (None: the benchmark's shared warm folder)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("XLA_FLAGS", None)                      # users' default optimisation level
    env["JAX_COMPILATION_CACHE_DIR"] = str(cache or WARM)
    env.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")
    return env


#: the shared cache of the warm figures (a fresh folder per benchmark run: what a user's cache
#: holds after one run of each command, never an earlier session's)
WARM = Path(tempfile.mkdtemp(prefix="bench-dataset-cache-"))
atexit.register(shutil.rmtree, WARM, True)


def command(args, tmp, cache=None):
    """Wall seconds, peak RSS (bytes) and stdout of ``bearingsim ARGS`` in a fresh process;
    the process's program counts (traced / loaded / compiled) are in the last line."""
    code = ("import resource, sys; from bearingsim.app.cli import leave, main; rc = main(sys.argv[1:]); "
            "from bearingsim import programs; c = programs.counts(); "
            "print('COUNTS', c['traced'], c['loaded'], c['compiled'], c['compile_cache_hits']); "
            "print('RSS', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024); leave(rc)")
    t0 = time.perf_counter()
    p = subprocess.run([PY, "-c", code, *args], env=_env(cache), cwd=tmp, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(p.stdout[-2000:] + p.stderr[-2000:])
    rss = int([ln for ln in p.stdout.splitlines() if ln.startswith("RSS")][-1].split()[1])
    return wall, rss, p.stdout


def counts_of(out) -> str:
    """'traced T, loaded L, compiled C' of a command's stdout."""
    t, lo, c, hits = [ln for ln in out.splitlines() if ln.startswith("COUNTS")][-1].split()[1:]
    return f"traced {t}, loaded {lo}, compiled {c} ({hits} from the cache)"


def runs(args, tmp, n=3, cache=None):
    """(min, median, the last run's stdout) of ``n`` runs of a command."""
    walls, out = [], ""
    for _ in range(n):
        w, _, out = command(args, tmp, cache)
        walls.append(w)
    return min(walls), float(np.median(walls)), out


def fresh_cache(tmp, name):
    d = Path(tmp) / f"empty-{name}"
    d.mkdir()
    return d


def spec_file(tmp, count, chunk=None, duration=0.1, fs=None, name="spec.toml"):
    from bearingsim.case import load_case
    c = load_case("dataset_cwru_4class").with_value("dataset.count", count).with_value("dataset.duration_s", duration)
    if chunk is not None:
        c = c.with_value("dataset.chunk", chunk)
    if fs is not None:
        c = c.with_value("dynamics.sample_rate_Hz", fs)
    p = Path(tmp) / name
    p.write_text(c.text)
    return p


def codecs(n_items, T=4800):
    """/signals codecs on realistic float32 signals: resonant noise with impacts."""
    import h5py
    from scipy.signal import lfilter

    from bearingsim.datasets.writer import COMPRESSIONS, compression_options
    from bearingsim.errors import InputError
    rng = np.random.default_rng(0)
    x = rng.standard_normal((n_items, T))
    r, w = 0.99, 2 * np.pi * 3000 / 48000
    x = lfilter([1, 0, -1], [1, -2 * r * np.cos(w), r * r], x, axis=1) * 0.5
    x[:, ::400] += 20.0
    x = x.astype(np.float32)
    MB = x.nbytes / 1e6
    rows = []
    opts = {}
    for name in COMPRESSIONS:
        try:
            opts[name] = compression_options(name)
        except InputError:          # zstd without hdf5plugin
            pass
    try:
        import hdf5plugin
        opts["blosc-lz4 (not offered)"] = dict(hdf5plugin.Blosc(cname="lz4", clevel=5, shuffle=hdf5plugin.Blosc.SHUFFLE))
    except ImportError:
        pass
    with tempfile.TemporaryDirectory() as d:
        for name, kw in opts.items():
            p = Path(d) / f"{name}.h5"
            t0 = time.perf_counter()
            with h5py.File(p, "w") as f:
                s = f.create_dataset("s", shape=x.shape, dtype="f4", chunks=(1, T), **kw)
                for k in range(0, n_items, 64):
                    s[k:k + 64] = x[k:k + 64]
            wt = time.perf_counter() - t0
            t0 = time.perf_counter()
            with h5py.File(p, "r") as f:
                y = f["s"][()]
            rt = time.perf_counter() - t0
            assert np.array_equal(x, y)
            rows.append((name, MB / wt, MB / rt, p.stat().st_size / x.nbytes))
        for name in ("npz", "npy folder"):
            t0 = time.perf_counter()
            for k in range(0, n_items, 64):
                if name == "npz":
                    np.savez(Path(d) / f"c{k}.npz", signals=x[k:k + 64], index=np.arange(64))
                else:
                    q = Path(d) / f"c{k}"
                    q.mkdir()
                    np.save(q / "signals.npy", x[k:k + 64])
                    np.save(q / "index.npy", np.arange(64))
            wt = time.perf_counter() - t0
            t0 = time.perf_counter()
            for k in range(0, n_items, 64):
                if name == "npz":
                    with np.load(Path(d) / f"c{k}.npz") as c:
                        c["signals"]
                else:
                    np.load(Path(d) / f"c{k}" / "signals.npy")
            rows.append((f"chunk files: {name}", MB / wt, MB / (time.perf_counter() - t0), 1.0))
    return MB, rows


def identical_bytes(tmp, device):
    import h5py
    spec = spec_file(tmp, 8, duration=0.01, fs=24000, name="small.toml")
    out = []
    for chunk in (2, 8):
        f = Path(tmp) / f"c{chunk}.h5"
        command(["dataset", str(spec), "-o", str(f), "--chunk", str(chunk)] + (["--device", device] if device else []), tmp)
        with h5py.File(f, "r") as h:
            out.append((h["signals"][()].astype(float), h["labels"][()].tobytes()))
    (x, la), (y, lb) = out
    if np.array_equal(x, y) and la == lb:
        return "identical"
    peak = np.maximum(np.abs(x).max(axis=1), 1e-300)
    return (f"labels {'identical' if la == lb else 'DIFFER'}; signals differ by <= "
            f"{np.max(np.abs(x - y).max(axis=1) / peak):.1e} of the item's peak")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--device", choices=("cpu", "gpu"))
    ap.add_argument("--codecs-only", action="store_true")
    a = ap.parse_args()
    import jax
    dev = jax.devices(a.device)[0] if a.device else jax.devices()[0]
    where = f"{dev.platform} ({dev.device_kind}, {os.cpu_count()} cores visible)"
    print(f"device: {jax.devices()}; runs on {where}")
    rows = []
    MB, crow = codecs(200 if a.quick else 2000)
    print(f"\n/signals codecs, {MB:.0f} MB of float32 ({'200' if a.quick else '2000'} x 4800):")
    print(f"{'codec':24s} {'write MB/s':>10s} {'read MB/s':>10s} {'size':>6s}")
    for name, w, r, s in crow:
        print(f"{name:24s} {w:10.0f} {r:10.0f} {s:6.3f}")
    if a.codecs_only:
        return
    dflag = ["--device", a.device] if a.device else []
    R = 1 if a.quick else 3
    with tempfile.TemporaryDirectory() as tmp:
        s16 = str(spec_file(tmp, 16, name="s16.toml"))
        w, _, out = command(["dataset", s16, "-o", "cold.h5"] + dflag, tmp, fresh_cache(tmp, "ds"))
        rows.append(("16 items, bearingsim dataset, empty cache", "-", f"{w:.1f} s", None))
        print(f"16 items, empty cache: {w:.1f} s; {counts_of(out)}", flush=True)
        command(["dataset", s16, "-o", "warm.h5"] + dflag, tmp)                    # warms WARM
        lo, med, out = runs(["dataset", s16, "-o", "s16.h5"] + dflag, tmp, R)
        label = "gpu" if dev.platform == "gpu" else "2 cores" if os.cpu_count() == 2 else f"{os.cpu_count()} cores"
        rows.append((f"16 items, bearingsim dataset, warm, {label} (min / median of {R})",
                     "<= 5 s" if dev.platform == "gpu" else "<= 4 s", f"{lo:.1f} / {med:.1f} s",
                     lo <= (5 if dev.platform == "gpu" else 4)))
        print(f"16 items, warm: {lo:.1f} / {med:.1f} s; {counts_of(out)}", flush=True)
        n = 64 if a.quick else 1000
        spec = spec_file(tmp, n)
        wall, rss, out = command(["dataset", str(spec), "-o", "big.h5"] + dflag, tmp)
        est = wall if n == 1000 else None
        rows.append((f"1000 x 0.1 s four-class at 48 kHz, whole command, warm cache"
                     + ("" if n == 1000 else f" (measured {n} items: {wall:.1f} s)"), "<= 15 s",
                     f"{wall:.1f} s" if est else "not measured at 1000 (--quick)", est is not None and est <= 15))
        print(f"{n} items, warm: {wall:.1f} s; {counts_of(out)}", flush=True)
        rows.append((f"host memory, {n} items streamed (peak RSS)", "<= 2 GB (10^5 items)", f"{rss / 1e9:.2f} GB",
                     rss <= 2e9))
        if dev.platform == "gpu":
            m = 1000 if a.quick else 100000
            w, _, _ = command(["dataset", str(spec_file(tmp, m, chunk=0, name="gpu.toml")), "-o", "g.h5"] + dflag, tmp)
            rows.append((f"GPU, {m} items of 0.1 s at 48 kHz, whole command", "<= 60 s for 10^5",
                         f"{w:.1f} s, {m / w:.0f} items/s", m == 100000 and w <= 60))
        else:
            rows.append(("one GPU, 10^5 items", "<= 60 s", "not measured (no GPU)", None))
        if dev.platform == "cpu":
            m = 64 if a.quick else 256
            sw = str(spec_file(tmp, m, chunk=16, name="workers.toml"))
            one, _, _ = command(["dataset", sw, "-o", "w1.h5"], tmp)
            command(["dataset", sw, "-o", "w2w.h5", "--workers", "2"], tmp)      # the workers' programs kept
            two, _, _ = command(["dataset", sw, "-o", "w2.h5", "--workers", "2"], tmp)
            rows.append((f"--workers 2 vs in-process, {m} items, warm (in-process / workers)", ">= 1.0x",
                         f"{one / two:.2f}x ({one:.1f} / {two:.1f} s)", one / two >= 1.0))
        w, _, out = command(["simulate", "cwru_6205", "-o", "sim0.h5"], tmp, fresh_cache(tmp, "sim"))
        rows.append(("bearingsim simulate cwru_6205, whole command, empty cache", "<= 15 s", f"{w:.1f} s", w <= 15))
        print(f"simulate, empty cache: {w:.1f} s; {counts_of(out)}", flush=True)
        command(["simulate", "cwru_6205", "-o", "sim1.h5"], tmp)
        lo, med, out = runs(["simulate", "cwru_6205", "-o", "sim.h5"], tmp, R)
        rows.append((f"bearingsim simulate cwru_6205, whole command, warm (min / median of {R})", "<= 3 s",
                     f"{lo:.1f} / {med:.1f} s", lo <= 3))
        print(f"simulate, warm: {lo:.1f} / {med:.1f} s; {counts_of(out)}", flush=True)
        w, _, out = command(["static", "demo"], tmp, fresh_cache(tmp, "static"))
        rows.append(("first bearingsim static call, empty cache", "<= 4 s", f"{w:.1f} s", w <= 4))
        command(["static", "demo"], tmp)
        lo, med, out = runs(["static", "demo"], tmp, R)
        rows.append((f"bearingsim static demo, second run (min / median of {R})", "<= 1.0 s",
                     f"{lo:.2f} / {med:.2f} s", lo <= 1.0))
        print(f"static demo, warm: {lo:.2f} / {med:.2f} s; {counts_of(out)}", flush=True)
        same = identical_bytes(tmp, a.device)
        rows.append(("same spec, chunk 2 vs chunk 8 (8 items)", "identical", same, same == "identical"))
    print(f"\ntargets (device: {where}):")
    print(f"{'figure':78s} {'target':>24s} {'measured':>28s}  met")
    for name, target, got, met in rows:
        print(f"{name:78s} {target:>24s} {got:>28s}  {'-' if met is None else ('yes' if met else 'NO')}")


if __name__ == "__main__":
    main()
