"""Data sets (and large studies) on a Dask cluster: ``bearingsim dataset SPEC -o F --workers N``
(a local cluster of N worker processes) or ``--scheduler ADDRESS|FILE`` (an existing cluster:
``tcp://host:8786`` or the scheduler file of ``dask scheduler --scheduler-file``).

The unit of work is one chunk, :func:`bearingsim.datasets.simulate_chunk` (plan, k): the same
function the in-process loop calls, so a data set has the same bytes on any number of workers
(each item's realism seed comes from (seed, item index), every chunk is padded to the same batch
shape, so every worker runs the same compiled program).  :class:`DaskRunner` sends the plan once
to every worker (``scatter(broadcast=True)``), keeps at most ``in_flight`` chunks submitted
(2 per worker), and hands back each finished chunk as it completes; the client writes it to the
resumable ``.partial/`` folder at once and drops it (memory bounded by ``in_flight`` chunks on
the client, one on each worker).  A chunk whose worker dies is run again elsewhere (the
scheduler's ``allowed-failures``, 3 by default; ``retries`` for an exception in the task).

Workers compile once each (the jitted programs live as long as the worker process) and share the
persistent JAX compilation cache of the client's ``JAX_COMPILATION_CACHE_DIR`` when one is set
(a path every worker can read and write: on a cluster, a shared file system): the worker plugin
:class:`JaxWorkerSetup` sets it on every worker, including workers that join or restart later,
and imports bearingsim there before the first task arrives.

Dask is an optional dependency (``pip install bearingsim[distributed]``); nothing imports this
module unless a cluster is asked for.  Errors: no Dask -> :class:`~bearingsim.errors.InputError`
(exit 2, with the pip command); a scheduler that cannot be reached, or a chunk that killed its
workers too often -> :class:`~bearingsim.errors.ClusterError` (exit 5).
"""
from __future__ import annotations

import logging
import os
import sys
from contextlib import contextmanager
from pathlib import Path

from ..errors import ClusterError, InputError

try:                                   # optional: the module imports without Dask
    from distributed import WorkerPlugin as _PluginBase
except ImportError:                    # pragma: no cover - exercised by the no-Dask test via sys.modules
    _PluginBase = object

__all__ = ["DaskRunner", "JaxWorkerSetup", "INSTALL", "require_dask", "CONNECT_TIMEOUT_S"]

#: how to install the optional dependency
INSTALL = "pip install 'bearingsim[distributed]'"
#: seconds the client waits for a scheduler before giving up
CONNECT_TIMEOUT_S = 10


def require_dask():
    """Import dask.distributed, or raise :class:`InputError` saying how to install it."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise InputError("--workers / --scheduler run on a Dask cluster, and Dask is not installed: "
                         f"{INSTALL}") from None
    return distributed


class JaxWorkerSetup(_PluginBase):
    """Worker plugin: the JAX compilation cache on ``cache_dir`` (if given) and bearingsim
    imported (float64 on, the XLA options set) when the worker starts, before its first task."""

    name = "bearingsim-jax-setup"

    def __init__(self, cache_dir=None, min_compile_time_s=None):
        self.cache_dir = None if cache_dir is None else str(cache_dir)
        self.min_compile_time_s = min_compile_time_s

    def setup(self, worker=None):
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            # Ctrl-C in a terminal reaches every process of the group: the client stops the run
            # and closes the cluster; a worker does not die of it on its own (nor print a traceback)
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        if self.cache_dir:
            os.environ["JAX_COMPILATION_CACHE_DIR"] = self.cache_dir
            if self.min_compile_time_s is not None:
                os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"] = str(self.min_compile_time_s)
        # bearingsim is imported already (this module is part of it, unpickled on the worker):
        # float64 on and the XLA options set before JAX loads here
        import jax

        if self.cache_dir:
            Path(self.cache_dir).mkdir(parents=True, exist_ok=True)
            jax.config.update("jax_compilation_cache_dir", self.cache_dir)
            if self.min_compile_time_s is not None:
                jax.config.update("jax_persistent_cache_min_compile_time_secs", float(self.min_compile_time_s))


def _scheduler_target(scheduler: str) -> dict:
    """``Client`` keyword for ``--scheduler``: an existing file is a scheduler file."""
    p = Path(scheduler)
    if "://" not in scheduler and (p.suffix == ".json" or p.exists()):
        if not p.is_file():
            raise ClusterError(f"--scheduler {scheduler}: no such scheduler file (start the scheduler "
                               "with `dask scheduler --scheduler-file FILE`, or give its address tcp://HOST:PORT)")
        return {"scheduler_file": str(p)}
    return {"address": scheduler}


class DaskRunner:
    """A Dask cluster for :func:`bearingsim.datasets.make_dataset` (``runner=``), as a context
    manager: ``workers`` starts a local cluster of that many single-threaded worker processes,
    ``scheduler`` connects to an existing one (address or scheduler file).  ``imap`` runs
    ``fn(shared, item)`` for every item with at most ``in_flight`` tasks at once (default 2 per
    worker) and yields ``(item, result)`` as they finish.  ``cache_dir``: the workers' JAX
    compilation cache (default: the client's ``JAX_COMPILATION_CACHE_DIR``)."""

    def __init__(self, workers=None, scheduler=None, *, in_flight=None, retries=2, cache_dir=None,
                 timeout=CONNECT_TIMEOUT_S):
        if (workers is None) == (scheduler is None):
            raise InputError("give one of --workers N (a local cluster) or --scheduler ADDRESS|FILE")
        if workers is not None and int(workers) < 1:
            raise InputError(f"--workers {workers}: give at least 1 worker process")
        self.workers = None if workers is None else int(workers)
        self.scheduler = scheduler
        self.in_flight = in_flight
        self.retries = int(retries)
        self.cache_dir = cache_dir if cache_dir is not None else os.environ.get("JAX_COMPILATION_CACHE_DIR")
        self.timeout = timeout
        self.client = None
        self.cluster = None
        self.log = None

    # ------------------------------------------------------------------ lifetime
    def __enter__(self):
        require_dask()
        for name in ("distributed", "tornado"):       # the client speaks through bearingsim's messages
            logging.getLogger(name).setLevel(logging.ERROR)
        try:
            self._start()
        except BaseException:                 # Ctrl-C while the workers start: none is left running
            self.close()
            raise
        return self

    def _start(self):
        from distributed import Client, LocalCluster

        min_t = os.environ.get("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS")
        try:
            if self.workers is not None:
                # the scheduler first (in this process), then the workers: an interrupt while they
                # start finds self.cluster set, and close() stops every worker process.  The worker
                # processes' stderr is a log file (self.log), not the terminal: their start-up
                # messages (and a worker killed by a Ctrl-C that reached the whole process group
                # while it imported) do not mix with the progress bar and bearingsim's one line
                self.cluster = LocalCluster(n_workers=0, threads_per_worker=1, processes=True,
                                            dashboard_address=":0",      # a free port: no clash, no warning
                                            silence_logs=logging.ERROR)
                self.client = Client(self.cluster)
                with self._stderr_to_log():
                    self.cluster.scale(self.workers)
                    self.client.wait_for_workers(self.workers)
            else:
                self.client = Client(timeout=self.timeout, **_scheduler_target(self.scheduler))
        except ClusterError:
            raise
        except (OSError, TimeoutError, ValueError) as e:
            self.close()
            where = f"the Dask scheduler at {self.scheduler}" if self.scheduler else "a local Dask cluster"
            raise ClusterError(f"cannot reach {where} within {self.timeout} s ({type(e).__name__}: "
                               f"{str(e).splitlines()[0] if str(e) else 'no reply'})",
                               "check the address (tcp://HOST:PORT) or scheduler file, that the scheduler "
                               "runs and that this machine can reach its port") from None
        self.client.register_plugin(JaxWorkerSetup(self.cache_dir, min_t))

    @contextmanager
    def _stderr_to_log(self):
        import tempfile

        fd, self.log = tempfile.mkstemp(prefix="bearingsim-dask-workers-", suffix=".log")
        sys.stderr.flush()
        saved = os.dup(2)
        os.dup2(fd, 2)
        os.close(fd)
        try:
            yield
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)

    def __exit__(self, *exc):
        self.close()
        return False

    def close(self):
        logging.disable(logging.CRITICAL)          # workers stopped mid-start log their failure
        try:
            for obj in (self.client, self.cluster):
                if obj is not None:
                    try:
                        obj.close()
                    except BaseException:           # closing after an interrupt: nothing to save
                        pass
        finally:
            logging.disable(logging.NOTSET)
            self.client = self.cluster = None
            if self.log:
                Path(self.log).unlink(missing_ok=True)
                self.log = None

    @property
    def n_workers(self) -> int:
        return len(self.client.scheduler_info(n_workers=-1)["workers"]) if self.client else 0

    # ------------------------------------------------------------------ work
    def imap(self, fn, shared, items):
        """``(item, fn(shared, item))`` for every item, in completion order, at most ``in_flight``
        submitted at a time; ``shared`` is sent once to every worker."""
        from distributed import as_completed
        from distributed.scheduler import KilledWorker

        items = list(items)
        if not items:
            return
        [shared_f] = self.client.scatter([shared], broadcast=True, hash=False)   # one object, even a tuple
        pending = iter(items)
        owner = {}
        ac = as_completed()

        def limit():
            return self.in_flight or max(2, 2 * self.n_workers)

        def submit_more():
            while len(owner) < limit():
                x = next(pending, _END)
                if x is _END:
                    return
                f = self.client.submit(fn, shared_f, x, pure=False, retries=self.retries,
                                       key=f"{getattr(fn, '__name__', 'task')}-{x if isinstance(x, int) else len(owner)}-{os.urandom(4).hex()}")
                owner[f] = x
                ac.add(f)

        try:
            submit_more()
            for f in ac:
                x = owner.pop(f)
                try:
                    r = f.result()
                except KilledWorker as e:
                    raise ClusterError(f"a task of {getattr(fn, '__name__', 'the run')} killed its worker "
                                       f"process {e.args[1] if len(e.args) > 1 else ''} times over (out of memory?)",
                                       "give the workers more memory, or a smaller [dataset] chunk") from None
                f.release()
                yield x, r
                del r
                submit_more()
        finally:
            for f in owner:
                f.cancel()
            owner.clear()
            shared_f.release()


class _End:
    pass


_END = _End()
