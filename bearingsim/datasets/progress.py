"""The progress of a data set run (:func:`bearingsim.datasets.runner.make_dataset`): its phases from
the first second, and a remaining time measured from the run's own throughput, never guessed.

A run goes through :data:`PHASES` in order: ``preparing`` (the labels, the transfer paths and the
time step, whose search compiles the quasi-static programs on a first run), ``compiling`` (the
first wave of chunks: the chunk programs compile on a first run, or load from the cache, and run
once), ``simulating`` (the chunks after the first wave), ``writing`` (the HDF5 file) and ``done``.
The first wave (as many chunks as run at once) carries the compilation, so the throughput is
measured from the end of that wave on: ``rate`` (items/s) and ``remaining`` (s) are None until a
chunk has finished after it, and then the items finished since over the time since.  A run of one
wave (few chunks) never shows a remaining time: there is nothing measured to base it on.

``make_dataset(progress=)``: True shows a bar on a terminal (tqdm, refreshed every second so
that the elapsed time moves while a phase compiles) and otherwise lines on stdout, one per phase
and chunk (a log file, CI; at most one per :data:`LOG_EVERY` s within a phase); False shows
nothing; a callable receives every :class:`ProgressEvent`.
"""
from __future__ import annotations

import sys
import threading
import time
from dataclasses import dataclass

from tqdm import tqdm

from ..errors import InvalidStateError

__all__ = ["PHASES", "LOG_EVERY", "ProgressEvent", "RunProgress", "Display", "event_text"]

#: a log (not a terminal) gets a line per phase and at most one per this many seconds between
LOG_EVERY = 10.0
#: the phases of a run, in order
PHASES = ("preparing", "compiling", "simulating", "writing", "done")
#: what each phase does, as the bar and the lines say it
_SAY = {"preparing": "preparing (labels, time step; compiles on a first run)",
        "compiling": "compiling and running the first chunks (the programs load from the cache after a first run)",
        "simulating": "simulating", "writing": "writing the HDF5 file", "done": "done"}


@dataclass(frozen=True)
class ProgressEvent:
    """One report of a run: ``phase`` (one of :data:`PHASES`), ``done`` / ``total`` items,
    ``elapsed`` s since the run began, ``rate`` items/s measured after the first wave (None
    before), ``remaining`` s at that rate (None before)."""

    phase: str
    done: int
    total: int
    elapsed: float
    rate: float | None = None
    remaining: float | None = None


def _clock(s: float) -> str:
    s = int(round(s))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


def event_text(e: ProgressEvent) -> str:
    """One line: the phase, the items, the elapsed time and, once measured, the remaining time."""
    left = (f", ~{_clock(e.remaining)} left at the measured {e.rate:.3g} items/s"
            if e.remaining is not None else
            ", remaining time: measured once a chunk finishes after the first ones" if e.phase == "compiling"
            else "")
    items = f"{e.done}/{e.total} items, " if e.total else ""
    return f"dataset: {_SAY[e.phase]}: {items}{_clock(e.elapsed)} elapsed{left}"


class RunProgress:
    """The phases and the finished items of a run; reports a :class:`ProgressEvent` to ``callback``
    at each phase and each finished chunk; ``clock``: the time (s)."""

    def __init__(self, callback, clock=time.perf_counter):
        self.callback = callback
        self.clock = clock
        self.t0 = clock()
        self.phase_name = None
        self.done = self.total = 0
        self.wave_items = 1
        self.first = 0
        self.mark = None               # (time, done) at the end of the first wave
        self.report("preparing")

    def start(self, total: int, done: int, wave_items: int):
        """The items (``done`` already finished: a resumed run) and the items of the first wave."""
        self.total, self.done, self.wave_items = int(total), int(done), max(1, int(wave_items))
        self.first = self.done
        self.report("compiling")

    def advance(self, items: int):
        """``items`` more finished."""
        self.done += int(items)
        now = self.clock()
        if self.mark is None and self.done - self.first >= self.wave_items:
            self.mark = (now, self.done)
            self.report("simulating", now)
        else:
            self.report(self.phase_name, now)

    def rate(self, now=None):
        """Items/s since the end of the first wave (None before a chunk finished after it)."""
        if self.mark is None:
            return None
        t, d = self.mark
        now = self.clock() if now is None else now
        return (self.done - d) / (now - t) if self.done > d and now > t else None

    def report(self, phase, now=None):
        if phase not in PHASES:
            raise InvalidStateError(f"progress phase {phase!r}: one of {', '.join(PHASES)}")
        if self.phase_name is not None and PHASES.index(phase) < PHASES.index(self.phase_name):
            raise InvalidStateError(f"progress phase {phase!r} after {self.phase_name!r}: the phases run in "
                                    f"the order {', '.join(PHASES)}")
        self.phase_name = phase
        now = self.clock() if now is None else now
        r = self.rate(now)
        left = (self.total - self.done) / r if r and phase == "simulating" else None
        self.callback(ProgressEvent(phase, self.done, self.total, now - self.t0, r, left))


#: the bar before the items are drawn (no total yet), and after
_EARLY = "{desc}: [{elapsed}{postfix}]"
_FULL = "{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} [{elapsed}{postfix}]"


class Display:
    """What ``progress=True`` shows: a tqdm bar on a terminal (stderr; refreshed every second), else
    lines on stdout (``stream``: where, for tests).  ``close()`` stops the refresh and closes the bar."""

    def __init__(self, desc, stream=None):
        # the bar on stderr when it is a terminal (tqdm's convention); else the lines on stdout, beside
        # the command's other output, so that stderr keeps only errors and warnings (one line each)
        tty = bool(getattr(sys.stderr, "isatty", lambda: False)())
        self.stream = stream if stream is not None else sys.stderr if tty else sys.stdout
        self.desc = desc
        self.bar = None
        self.last = None
        self.said = 0.0
        self.stop = threading.Event()
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def __call__(self, e: ProgressEvent):
        if not self.tty:          # a log: every phase, and the chunks at most every LOG_EVERY seconds
            if self.last is None or e.phase != self.last.phase or e.elapsed - self.said >= LOG_EVERY:
                print(event_text(e), file=self.stream, flush=True)
                self.said = e.elapsed
            self.last = e
            return
        self.last = e
        if self.bar is None:
            self.bar = tqdm(total=e.total or None, initial=0, desc=self.desc, unit="item", file=self.stream,
                            dynamic_ncols=True, bar_format=_EARLY)
            threading.Thread(target=self._tick, daemon=True).start()
        if e.total and self.bar.total != e.total:
            self.bar.total = e.total
            self.bar.bar_format = _FULL
        self.bar.n = e.done
        left = f", ~{_clock(e.remaining)} left ({e.rate:.3g} item/s measured)" if e.remaining is not None else ""
        self.bar.set_postfix_str(f"{e.phase}{left}", refresh=False)
        self.bar.refresh()

    def _tick(self):
        while not self.stop.wait(1.0):
            bar = self.bar
            if bar is not None:
                bar.refresh()

    def close(self):
        self.stop.set()
        if self.bar is not None:
            self.bar.close()
