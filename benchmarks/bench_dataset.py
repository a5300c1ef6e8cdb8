"""The data engine's targets (issue 25): prints every figure with the device it ran on.

    python benchmarks/bench_dataset.py [--quick] [--device cpu|gpu] [--codecs-only]

Rows: the four-class spec (1000 x 0.1 s at 48 kHz, every ingredient on) as a whole command with a
warm compilation cache; ``bearingsim dataset`` of 16 items; 10^5 items on a GPU (only where JAX
sees one); one CWRU rig simulation per simulated second; host memory; identical bytes across
chunk sizes; and the writer: /signals codecs (write MB/s, read MB/s, size for 2000 x 4800
float32 samples) and the chunk files (.npy folder vs npz).  ``--quick``: 64 items instead of
1000, 10^3 instead of 10^5, 200 codec items (the figures are then extrapolated and say so).
"""
from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
PY = sys.executable


def _env():
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.setdefault("JAX_COMPILATION_CACHE_DIR", str(ROOT / ".jax_cache"))
    env.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.5")
    return env


def command(args, tmp):
    """Wall seconds and peak RSS (bytes) of ``bearingsim ARGS`` in a fresh process."""
    code = ("import resource, sys; from bearingsim.app.cli import main; rc = main(sys.argv[1:]); "
            "print('RSS', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024); sys.exit(rc)")
    t0 = time.perf_counter()
    p = subprocess.run([PY, "-c", code, *args], env=_env(), cwd=tmp, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(p.stdout[-2000:] + p.stderr[-2000:])
    rss = int([ln for ln in p.stdout.splitlines() if ln.startswith("RSS")][-1].split()[1])
    return wall, rss, p.stdout


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
    with tempfile.TemporaryDirectory() as tmp:
        n = 64 if a.quick else 1000
        spec = spec_file(tmp, n)
        command(["dataset", str(spec_file(tmp, 16, name="warm.toml")), "-o", "warm.h5"] + dflag, tmp)  # warm cache
        wall, rss, _ = command(["dataset", str(spec), "-o", "big.h5"] + dflag, tmp)
        est = wall if n == 1000 else None
        rows.append((f"1000 x 0.1 s four-class at 48 kHz, whole command, warm cache"
                     + ("" if n == 1000 else f" (measured {n} items: {wall:.1f} s)"), "<= 12 s",
                     f"{wall:.1f} s" if est else "not measured at 1000 (--quick)", est is not None and est <= 12))
        wall16, _, _ = command(["dataset", str(spec_file(tmp, 16, name="s16.toml")), "-o", "s16.h5"] + dflag, tmp)
        rows.append(("bearingsim dataset of 16 items, warm cache, whole command", "<= 4 s", f"{wall16:.1f} s",
                     wall16 <= 4))
        rows.append((f"host memory, {n} items streamed (peak RSS)", "<= 2 GB (10^5 items)", f"{rss / 1e9:.2f} GB",
                     rss <= 2e9))
        if dev.platform == "gpu":
            m = 1000 if a.quick else 100000
            w, _, _ = command(["dataset", str(spec_file(tmp, m, chunk=0, name="gpu.toml")), "-o", "g.h5"] + dflag, tmp)
            rows.append((f"GPU, {m} items of 0.1 s at 48 kHz, whole command", ">= 2000 items/s",
                         f"{m / w:.0f} items/s", m / w >= 2000))
        else:
            rows.append(("one GPU, 10^5 items", "<= 60 s", "not measured (no GPU)", None))
        t0 = time.perf_counter()
        command(["simulate", "cwru_6205", "-o", "sim.h5"], tmp)
        sim = time.perf_counter() - t0
        rows.append(("a CWRU rig simulation, whole command (s, incl. start-up)", "<= 0.3 s / simulated s",
                     f"{sim:.1f} s", None))
        same = identical_bytes(tmp, a.device)
        rows.append(("same spec, chunk 2 vs chunk 8 (8 items)", "identical", same, same == "identical"))
    print(f"\ntargets (device: {where}):")
    print(f"{'figure':78s} {'target':>24s} {'measured':>28s}  met")
    for name, target, got, met in rows:
        print(f"{name:78s} {target:>24s} {got:>28s}  {'-' if met is None else ('yes' if met else 'NO')}")


if __name__ == "__main__":
    main()
