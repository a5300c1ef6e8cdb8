"""Data sets on a Dask cluster (bearingsim.datasets.distributed): the same bytes as the in-process run on a
LocalCluster of 2 workers, a worker killed mid-chunk is retried, an interrupted distributed run
resumes without a cluster, the in-process run never imports Dask, a missing Dask or an
unreachable scheduler is one message and an exit code."""
import os
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from bearingsim.app.cli import main
from bearingsim.datasets import Interrupted, make_dataset, partial_path, simulate_chunk

sys.path.insert(0, str(Path(__file__).parent))
from test_dataset import spec as _spec  # noqa: E402


def spec():
    """The tiny spec of test_dataset (6 items of 0.02 s; at chunk 4, the CPU micro-batch
    width: 2 chunks, of 4 and 2 items) with round-pit depths (computed inside the
    chunk program, on the workers)."""
    return _spec(extra='depth_rule = "pit"')

distributed = pytest.importorskip("distributed")


def _no_dask(monkeypatch):
    for name in ("dask", "distributed"):
        monkeypatch.setitem(sys.modules, name, None)      # import dask -> ImportError


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    """The in-process run, with Dask made unimportable (so it cannot have been used)."""
    mp = pytest.MonkeyPatch()
    _no_dask(mp)
    try:
        out = tmp_path_factory.mktemp("serial") / "s.h5"
        make_dataset(spec(), out, progress=False)
    finally:
        mp.undo()
    return out


@pytest.fixture(scope="module")
def runner():
    from bearingsim.datasets.distributed import DaskRunner

    with DaskRunner(workers=2) as r:
        yield r


def _same(a, b):
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        assert fa["signals"][()].tobytes() == fb["signals"][()].tobytes()
        assert fa["labels"][()].tobytes() == fb["labels"][()].tobytes()
        assert np.all(fa["labels"]["result"] == 0)


class _Via:
    """A runner that runs ``fn`` through ``wrap(fn)`` on the cluster (test hooks)."""

    def __init__(self, runner, wrap, stop_after=None):
        self.runner, self.wrap, self.stop_after = runner, wrap, stop_after

    def imap(self, fn, shared, items):
        for n, got in enumerate(self.runner.imap(self.wrap(fn), shared, items), 1):
            yield got
            if fn is simulate_chunk and n == self.stop_after:
                raise KeyboardInterrupt


def _dies_once(marker):
    def wrap(fn):
        def chunk_or_die(shared, k):
            if fn is simulate_chunk and k == 1 and not os.path.exists(marker):
                Path(marker).touch()
                os._exit(1)                                  # the worker process dies mid-chunk
            return fn(shared, k)
        return chunk_or_die
    return wrap


def test_two_workers_same_bytes_with_a_worker_killed(serial, runner, tmp_path):
    """Chunk 1's first worker dies; the scheduler runs it again on a worker; the file is the
    in-process file byte for byte."""
    marker = tmp_path / "died"
    out = tmp_path / "d.h5"
    s = make_dataset(spec(), out, progress=False, runner=_Via(runner, _dies_once(str(marker))))
    assert marker.exists() and s.failed == 0 and not partial_path(out).exists()
    _same(serial, out)


def test_two_workers_and_another_chunk_size(serial, runner, tmp_path):
    """2 workers at chunk 8 (one chunk of two micro-batches, the second padded) give the bytes of
    the in-process run at chunk 4 (two chunks)."""
    out = tmp_path / "c8.h5"
    s = make_dataset(spec(), out, progress=False, runner=runner, chunk=8)
    assert s.chunk == 8 and s.failed == 0
    _same(serial, out)


def test_interrupted_distributed_run_resumes_in_process(serial, runner, tmp_path):
    """Stopped after the first chunk a worker finished: either chunk (4 items or 2; the two
    workers race, seen on a fresh clone as "2 of 6"), one chunk file kept, then continued."""
    out = tmp_path / "i.h5"
    with pytest.raises(Interrupted, match="[24] of 6 items finished"):
        make_dataset(spec(), out, progress=False, runner=_Via(runner, lambda fn: fn, stop_after=1))
    assert not out.exists() and len(list(partial_path(out).glob("chunk_*"))) == 1
    assert not [p for p in tmp_path.rglob("*") if p.name.endswith(".tmp")]
    make_dataset(spec(), out, progress=False)                # no cluster: continues from the chunk
    assert not partial_path(out).exists()
    _same(serial, out)


def test_cli_without_dask_says_how_to_install(monkeypatch, tmp_path, capsys):
    _no_dask(monkeypatch)
    p = tmp_path / "spec.toml"
    p.write_text(spec().text)
    assert main(["dataset", str(p), "-o", str(tmp_path / "x.h5"), "--workers", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pip install 'bearingsim[distributed]'" in err
    assert list(tmp_path.iterdir()) == [p]


def test_unreachable_scheduler_is_one_message(tmp_path, capsys):
    from bearingsim.datasets.distributed import DaskRunner
    from bearingsim.errors import ClusterError

    with pytest.raises(ClusterError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9") as e:
        with DaskRunner(scheduler="tcp://127.0.0.1:9", timeout=1):
            pass
    assert e.value.exit_code == 5
    p = tmp_path / "spec.toml"
    p.write_text(spec().text)
    assert main(["dataset", str(p), "-o", str(tmp_path / "x.h5"), "--scheduler", str(tmp_path / "none.json")]) == 5
    err = capsys.readouterr().err.strip()
    assert "no such scheduler file" in err and "Traceback" not in err
    assert sorted(q.name for q in tmp_path.iterdir()) == ["spec.toml"]


def test_study_on_the_cluster_equals_the_in_process_study(runner):
    """A study of a defect key (one compiled sweep per value) with its sweeps on 2 workers: the
    same numbers as in this process."""
    import jax

    from bearingsim.app.workflows import study_case
    from test_workflows import study

    case = study("defect.depth_mm", [0.0, 0.3])
    here = study_case(case)
    there = study_case(case, runner=runner)
    for a, b in zip(jax.tree_util.tree_leaves(here.solution), jax.tree_util.tree_leaves(there.solution)):
        assert np.asarray(a).tobytes() == np.asarray(b).tobytes()
