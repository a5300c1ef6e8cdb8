"""The progress of a data set run (issue 34: "dataset: no progress bar on a 212 s run (estimate
38 s)"): the phases are reported from the first second and in order, compiling among them, and a
remaining time exists only once it can be measured (after the first wave of chunks, which carries
the compilation), never as a guess.  make_dataset's own reports: test_dataset_engine.py
(test_make_dataset_reports_every_phase_in_order, on the runs it makes anyway)."""
import io

import pytest

from bearingsim.datasets.progress import Display, RunProgress
from bearingsim.errors import InvalidStateError


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_the_remaining_time_is_measured_after_the_first_wave_only():
    """Two chunks of 32 at once (the first wave: 100 s, compiling), then 20 s per chunk: no
    remaining time during the wave nor at its end; then 32 items in 20 s = 1.6 items/s, measured
    after the wave (the compile-inclusive average, 64 / 120 s, would say 0.53)."""
    clock, events = Clock(), []
    p = RunProgress(events.append, clock=clock)
    clock.t = 5.0
    p.start(total=128, done=0, wave_items=64)
    for dt in (100.0, 0.5, 20.0, 20.0):
        clock.t += dt
        p.advance(32)
    p.report("writing")
    p.report("done")
    assert [e.phase for e in events] == ["preparing", "compiling", "compiling", "simulating", "simulating",
                                         "simulating", "writing", "done"]
    assert all(e.remaining is None and e.rate is None for e in events[:4])       # nothing measured yet
    assert events[4].rate == pytest.approx(32 / 20.0, rel=1e-12)                 # exact arithmetic
    assert events[4].remaining == pytest.approx(32 / 1.6, rel=1e-12)
    assert events[5].remaining == 0.0 and events[-1].remaining is None
    assert events[0].elapsed == 0.0 and events[1].elapsed == 5.0


def test_a_resumed_run_measures_from_its_own_items_and_the_phases_only_go_forward():
    clock, events = Clock(), []
    p = RunProgress(events.append, clock=clock)
    p.start(total=100, done=60, wave_items=20)          # 60 items kept from an interrupted run
    clock.t = 50.0
    p.advance(20)
    assert events[-1].phase == "simulating" and events[-1].remaining is None
    clock.t = 60.0
    p.advance(20)
    assert events[-1].rate == pytest.approx(2.0, rel=1e-12) and events[-1].done == 100
    with pytest.raises(InvalidStateError, match="'compiling' after 'simulating'"):
        p.report("compiling")
    with pytest.raises(InvalidStateError, match="one of preparing"):
        p.report("resting")


def test_a_log_gets_one_line_per_phase_and_says_the_remaining_time_is_not_yet_measured():
    """Not a terminal (a log file, CI): tqdm would show nothing; lines say each phase, and the
    compiling one says that the remaining time comes once measured."""
    out = io.StringIO()
    clock = Clock()
    p = RunProgress(Display("dataset", out), clock=clock)
    p.start(total=64, done=0, wave_items=32)
    clock.t = 2.0
    p.advance(16)                       # within LOG_EVERY s of the last line, same phase: no line
    clock.t = 100.0
    p.advance(16)                       # the wave's end: "simulating"
    clock.t = 130.0
    p.advance(32)
    p.report("writing")
    lines = out.getvalue().splitlines()
    assert [line.split(":")[1].split()[0] for line in lines] == ["preparing", "compiling", "simulating",
                                                                 "simulating", "writing"]
    assert "remaining time: measured once a chunk finishes" in lines[1]
    assert "left" not in "".join(lines[:3]) and "~0:00 left at the measured 1.07 items/s" in lines[3]
