"""The data set's signal stage: bearingsim.signals.signal_stage.finish_items (one jitted program for
the chunk: pass variation and the sensor modes, background, SNR scaling), first call and warm.  (The
host loop it replaced, dynamics.vary_sensor, left the package with issue 32: a single simulation
now uses the same stage.)  Usage: python benchmarks/bench_signal_stage.py [items] [samples]."""
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

from bearingsim.signals import signal_stage as ss
from bearingsim.dynamics import Realism

N = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
T = int(sys.argv[2]) if len(sys.argv) > 2 else 4800
FS = 48000.0
DS = dict(background="random", background_rms_m_s2=(0.2, 2.0), fault_snr_dB=(0, 25),
          ball_strike_probability=(0.1, 1.0), outer_center_positions_deg=[0, 0, 90, -90, 180],
          resonance_frequency_Hz=(1500, 5500), resonance_damping_ratio=(0.01, 0.08), resonance_gain=(0.3, 10))
REALISM = Realism(0.9, 0.1, 5.0, 0.0, None, 2.334, 9.089)
MODES = ([2977.6, 3356.0], [0.01329, 0.01937], [1.883, 8.852])


def inputs(n, T, P=24, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(T) / FS
    rate = rng.uniform(100, 170, n)
    h = np.sin(2 * np.pi * 3000 * t)[None] * np.exp(-((t[None] * rate[:, None]) % 1) * 30)
    tp = np.full((n, P), np.inf)
    for i in range(n):
        k = int(rate[i] * T / FS)
        tp[i, :k] = (np.arange(k) + 0.2) / rate[i]
    return dict(housing=h, sensor=1.1 * h, pass_times=tp, unbridged=rng.uniform(0, 1, n),
                fault_class=np.arange(n) % 4, shaft_hz=rng.uniform(28.7, 30.0, n))


def main():
    print(f"device: {jax.devices()[0].device_kind} ({jax.default_backend()}), {N} items x {T} samples at {FS:g} Hz")
    inp = inputs(N, T)
    st = ss.SignalSettings.from_dataset(DS, FS, T, REALISM, MODES)
    keys = ss.item_keys(0, np.arange(N))
    fc = jnp.asarray(inp["fault_class"])
    args = [jnp.asarray(inp[k]) for k in ("housing", "sensor", "pass_times", "unbridged")]

    def device():
        d = ss.draw_items(keys, fc, st)
        out, lab = ss.finish_items(keys, *args, fc, jnp.asarray(inp["shaft_hz"]), d, st)
        return jax.block_until_ready((out, lab, d))
    t0 = time.perf_counter()
    device()
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    device()
    warm = time.perf_counter() - t0
    print(f"signal_stage.finish_items (+ draw_items): first call {first:.2f} s (trace + compile or cache load), "
          f"warm {warm:.3f} s = {1e3 * warm / N:.3f} ms/item")


if __name__ == "__main__":
    main()
