"""The data engine (issue 25): every item from its key, identical bytes for any chunk size,
reproducible from the seed, one device-program call per chunk, the device and codec choices."""
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

import bearingsim.datasets as dsm
from bearingsim.datasets import draw_labels, item_keys, make_dataset
from bearingsim.datasets.progress import PHASES
from bearingsim.errors import InputError

sys.path.insert(0, str(Path(__file__).parent))
from test_dataset import spec  # noqa: E402


def _bytes(path):
    with h5py.File(path, "r") as f:
        return f["signals"][()].tobytes(), f["labels"][()].tobytes(), f["transfer_path"][()].tobytes()


def spec20():
    """20 items (two CPU micro-batches of 16, the second padded)."""
    return spec().with_value("dataset.count", 20)


@pytest.fixture(scope="module")
def chunked(tmp_path_factory):
    """The 20-item spec at chunk 16 (2 chunks: 16 and 4 items) and chunk 64 (1 chunk of all 20
    items, five micro-batches of 4), the second twice (reproducibility), counting the
    device-program calls."""
    d = tmp_path_factory.mktemp("engine")
    calls = []
    mp = pytest.MonkeyPatch()
    mp.setenv("BEARINGSIM_THREADS", "2")        # chunks and micro-batches side by side (make test sets 1)
    real = dsm.program.device_program
    mp.setattr(dsm.program, "device_program", lambda plan, pad, *a: (calls.append(pad.size), real(plan, pad, *a))[1])
    try:
        out = {}
        for name, chunk in (("c16", 16), ("c64", 64), ("c64b", 64)):
            n0 = len(calls)
            events = []                                 # the progress events (test_make_dataset_reports_...)
            out[name] = (make_dataset(spec20(), d / f"{name}.h5", progress=events.append, chunk=chunk), calls[n0:],
                         events)
    finally:
        mp.undo()
    return d, out


def test_identical_bytes_across_chunk_sizes(chunked):
    """Chunk 16 (two chunks) and chunk 64 (one chunk of the 20 items, five micro-batches of 4,
    run two at a time): the same bytes of signals, labels and transfer paths (every program runs on
    micro-batches of the platform's fixed width, dataset.micro_batch)."""
    d, out = chunked
    assert out["c16"][0].chunk == 16 and out["c64"][0].chunk == 20 and out["c16"][0].failed == 0
    assert _bytes(d / "c16.h5") == _bytes(d / "c64.h5")


def test_make_dataset_reports_every_phase_in_order(chunked):
    """Progress (issue 34, bearingsim.datasets.progress), reported to a callable on the runs above
    (chunk 16: two chunks side by side, one wave; chunk 64: one chunk): preparing (before the
    items are drawn), compiling, simulating, writing, done, in order; no remaining time, as no
    chunk finished after the first wave (nothing measured to base it on)."""
    for name in ("c16", "c64"):
        events = chunked[1][name][2]
        phases = [e.phase for e in events]
        assert [p for k, p in enumerate(phases) if k == 0 or p != phases[k - 1]] == list(PHASES), name
        assert events[0].total == 0 and events[-1].done == events[-1].total == 20
        assert all(e.remaining is None and e.rate is None for e in events)


def test_reproducible_from_the_seed(chunked):
    """Same spec and seed: the same bytes of signals, labels and transfer paths; another seed
    draws other items; each item's stored key is fold_in(PRNGKey(seed), index)."""
    import jax
    d, _ = chunked
    assert _bytes(d / "c64.h5") == _bytes(d / "c64b.h5")
    lab = draw_labels(spec())
    for i in (0, 5):
        k = np.asarray(jax.random.fold_in(jax.random.PRNGKey(7), i)).astype(np.uint64)
        assert lab["key"][i] == (k[0] << np.uint64(32)) | k[1]
    assert np.array_equal(item_keys(7, 2, start=4), item_keys(7, 6)[4:])
    other = draw_labels(spec().with_value("dataset.seed", 8))
    assert not np.array_equal(other["speed_rpm"], lab["speed_rpm"])


def test_an_item_does_not_depend_on_the_count():
    """An item's draws come from its key only: the first items of a larger data set (same class
    blocks) draw the same speed, loads and defect."""
    small = draw_labels(spec().with_value("dataset.healthy_fraction", 0.0))
    big = draw_labels(spec().with_value("dataset.healthy_fraction", 0.0).with_value("dataset.count", 40))
    for f in ("speed_rpm", "radial_N", "spall_length_mm", "key", "realism_seed", "signal_gain"):
        assert np.array_equal(small[f], big[f][:6]), f


def test_a_chunk_is_one_device_program_call(chunked):
    """simulate_chunk makes exactly one device_program call per chunk, on the chunk padded to
    whole micro-batches (no per-item call from the host)."""
    _, out = chunked
    W = dsm.micro_batch("cpu")
    assert W == 4
    assert out["c16"][1] == [16, 4] and out["c64"][1] == [20]


def test_a_chunk_makes_no_host_round_trip(tmp_path):
    """With its inputs on the device, a chunk's program transfers nothing between host and
    device until it returns (jax.transfer_guard)."""
    import jax
    case = spec(extra='background = "random"\n')
    plan = {}
    real = dsm.runner.simulate_chunk

    def grab(p, k, *a, **kw):
        plan["p"] = p
        return real(p, k, *a, **kw)
    mp = pytest.MonkeyPatch()
    mp.setattr(dsm.runner, "simulate_chunk", grab)
    mp.setenv("BEARINGSIM_THREADS", "1")        # the chunks one after the other: simulate_chunk itself
    try:
        make_dataset(case, tmp_path / "g.h5", progress=False)
    finally:
        mp.undo()
    p = plan["p"]
    idx = np.asarray(p.items(0))
    pad = np.concatenate([idx, np.repeat(idx[-1:], p.width - idx.size)])
    before = dsm.plan_program(p)[0].calls
    with jax.transfer_guard("disallow"):
        out = dsm.program.device_program(p, pad)
    assert dsm.plan_program(p)[0].calls - before == 2          # prepare + run: one micro-batch
    assert out["signals"].shape[0] == p.width and np.all(out["result"] == 0)


def test_device_and_codec_choices(tmp_path):
    import jax
    assert dsm.resolve_device("cpu").platform == "cpu"
    if not any(d.platform == "gpu" for d in jax.devices()):
        with pytest.raises(InputError, match='jax\\[cuda12\\]'):
            dsm.resolve_device("gpu")
    with pytest.raises(InputError, match="device must be one of"):
        dsm.resolve_device("tpu9")
    cpu = jax.devices("cpu")[0]
    import os
    assert dsm.default_chunk(cpu, 4800, 10 ** 6) == 16 * (os.cpu_count() or 1)
    assert dsm.default_chunk(cpu, 4800, 5) == 5
    with pytest.raises(InputError, match="compression must be one of"):
        make_dataset(spec(), tmp_path / "x.h5", progress=False, compression="zip")
    assert not (tmp_path / "x.h5").exists()


def test_a_warm_process_loads_the_chunk_programs(tmp_path, monkeypatch):
    """Issue 32: the chunk's programs (states and Newton check, time loop, signal stage, label
    draws) are traced once per configuration and loaded, not traced, by the next process (here:
    the memory of this one forgotten, its files kept), with the same bytes.  Over 20 s: it
    traces the chunk programs once more on purpose (the cold half)."""
    from bearingsim import programs
    monkeypatch.setattr(programs, "program_dir", lambda: tmp_path / "programs")
    c = spec().with_value("dataset.count", 3)
    programs.forget()
    before = programs.counts()
    make_dataset(c, tmp_path / "cold.h5", progress=False)
    cold = programs.counts()
    assert cold["traced"] - before["traced"] >= 4 and cold["loaded"] == before["loaded"]
    programs.forget()
    make_dataset(c, tmp_path / "warm.h5", progress=False)
    warm = programs.counts()
    assert warm["traced"] == cold["traced"], "a warm start traced a program again"
    # the chunk programs (states and Newton check, time loop, signal stage, label draws) loaded; the
    # host solves of the substeps (run_settings) not even loaded: their result is read (warm.memo)
    assert warm["loaded"] - cold["loaded"] >= 4
    assert warm["memo_hits"] - cold["memo_hits"] == 1 and cold["memo_hits"] == before["memo_hits"]
    assert _bytes(tmp_path / "cold.h5") == _bytes(tmp_path / "warm.h5")


def test_a_rounded_chunk_says_so(chunked, tmp_path, monkeypatch):
    """Issue 35: a chunk that is not a whole number of micro-batches was rounded up without a
    word; now a SettingWarning says from what to what (and the bytes are those of chunk 16; this
    run one chunk after the other, that one side by side: threads change no byte)."""
    from bearingsim.errors import SettingWarning
    monkeypatch.setenv("BEARINGSIM_THREADS", "1")
    d, _ = chunked
    with pytest.warns(SettingWarning, match="dataset.chunk 5 rounded up to 8 items"):
        s = make_dataset(spec20(), tmp_path / "c5.h5", progress=False, chunk=5)
    assert s.chunk == 8
    assert _bytes(tmp_path / "c5.h5") == _bytes(d / "c16.h5")
