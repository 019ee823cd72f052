"""Progress of long work (issue 32, item 4): plain lines at a steady pace off a terminal (done /
total, rate, time left; no carriage return), a bar on a terminal. A fake clock drives the pace:
no real waiting, no timing assertion."""

from __future__ import annotations

import io
import re

import pytest

from deckpound.compare.progress import (
    PROGRESS_INTERVAL,
    Progress,
    duration_text,
    progress_interval,
)
from deckpound.models.errors import SceneError


class Clock:
    """A clock the test moves by hand [s]."""

    def __init__(self):
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


LINE = re.compile(
    r"^deckpound study skew: (\d+)/30 done \(\d+ %\), ([\d.]+) per (s|min|h), "
    r"(.+) elapsed, about (.+) left$"
)


def test_log_lines_at_the_interval_with_counts_rate_and_time_left():
    clock, log = Clock(), io.StringIO()
    bar = Progress(30, "study skew", stream=log, clock=clock, interval=30.0, ticker=False)
    bar.skip(6)  # cached: done at once, not in the rate
    assert log.getvalue().splitlines() == [
        "deckpound study skew: 0/30 done (0 %), 0 s elapsed, rate and time left after the first"
    ]
    clock.now += 29.0
    bar.tick()  # not due yet
    assert len(log.getvalue().splitlines()) == 1
    clock.now += 1.0
    bar.tick()  # due, although no case finished: a long case still shows the work is alive
    assert log.getvalue().splitlines()[-1].startswith("deckpound study skew: 6/30 done (20 %)")
    for _ in range(4):  # 4 cases in the next 2 minutes
        clock.now += 30.0
        bar.advance()
    lines = log.getvalue().splitlines()
    assert len(lines) == 6
    m = LINE.match(lines[-1])
    assert m, lines[-1]
    # 4 worked cases in 150 s: 1.6 per min; 20 left: 12 min 30 s
    assert (m.group(1), m.group(2), m.group(3)) == ("10", "1.6", "min")
    assert m.group(4) == "2 min 30 s" and m.group(5) == "12 min 30 s"
    bar.advance(20)
    assert log.getvalue().splitlines()[-1] == (
        "deckpound study skew: 30/30 done in 2 min 30 s (9.6 per min)"
    )
    bar.tick()
    bar.close()  # nothing after the final line
    assert len(log.getvalue().splitlines()) == 7
    assert "\r" not in log.getvalue()


def test_items_finishing_faster_than_the_interval_write_no_more_lines():
    clock, log = Clock(), io.StringIO()
    bar = Progress(100, "stress", stream=log, clock=clock, interval=10.0, ticker=False)
    for _ in range(99):
        clock.now += 1.0
        bar.advance()
    lines = log.getvalue().splitlines()
    assert len(lines) == 1 + 9  # the start, then one per 10 s
    assert all(line.startswith("deckpound stress: ") for line in lines)
    bar.close()  # stopped before the end: where it stopped
    assert log.getvalue().splitlines()[-1].startswith("deckpound stress: stopped at 99/100 done")


def test_the_thread_writes_between_items():
    """With a tiny interval the daemon thread writes on its own; it stops with the bar."""
    import time

    log = io.StringIO()
    bar = Progress(3, "paper", stream=log, interval=0.01)
    deadline = time.monotonic() + 30.0  # a bound for a loaded machine, not a measurement
    while len(log.getvalue().splitlines()) < 3 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert len(log.getvalue().splitlines()) >= 3
    bar.advance(3)
    final = log.getvalue()
    time.sleep(0.05)
    assert log.getvalue() == final  # the thread ended with the last item
    assert re.match(r"deckpound paper: 3/3 done in \d+ s", final.splitlines()[-1])
    assert "\r" not in final


def test_terminal_draws_a_bar_in_place():
    clock, term = Clock(), Terminal()
    bar = Progress(4, "sequence", stream=term, clock=clock, interval=30.0, ticker=False)
    clock.now += 10.0
    bar.advance()
    clock.now += 100.0
    bar.tick()  # no timed lines on a terminal
    bar.advance(3)
    text = term.getvalue()
    assert text.startswith("\rsequence [") and text.count("\r") == 3 and text.endswith("\n")
    assert "[#######.......................] 1/4" in text and "~30 s left" in text
    assert "[##############################] 4/4" in text
    assert "deckpound" not in text


def test_silent_when_disabled_or_empty():
    log = io.StringIO()
    Progress(5, "bench", enabled=False, stream=log).advance(5)
    Progress(0, "bench", stream=log).close()
    assert log.getvalue() == ""


def test_interval_from_the_environment(monkeypatch):
    monkeypatch.delenv("DECKPOUND_PROGRESS_INTERVAL", raising=False)
    assert progress_interval() == PROGRESS_INTERVAL <= 30.0 / 1.25  # a line within 30 s
    monkeypatch.setenv("DECKPOUND_PROGRESS_INTERVAL", "2.5")
    assert progress_interval() == 2.5
    assert Progress(2, "x", stream=io.StringIO(), ticker=False).interval == 2.5
    for bad in ("0", "-1", "soon", "nan"):
        monkeypatch.setenv("DECKPOUND_PROGRESS_INTERVAL", bad)
        with pytest.raises(SceneError, match="DECKPOUND_PROGRESS_INTERVAL.*seconds > 0"):
            progress_interval()


def test_duration_text():
    assert [duration_text(s) for s in (0.4, 42, 185, 7620)] == [
        "0 s",
        "42 s",
        "3 min 5 s",
        "2 h 7 min",
    ]


def test_run_cases_reports_to_a_log(monkeypatch, capsys):
    """run_cases off a terminal: a start line and a final line, counts of cached cases."""
    from deckpound.compare import cases as cases_mod
    from deckpound.models.scene_io import load_scene

    scene = load_scene("saiidi-4span", ["run.duration=0.05", "excitation.duration=0.2"])
    log = io.StringIO()
    monkeypatch.setattr("sys.stderr", log)
    out = cases_mod.run_cases(
        [cases_mod.Case("a", "compliance", scene)], workers=1, title="study quick"
    )
    assert list(out) == ["a"]
    lines = log.getvalue().splitlines()
    progress = [x for x in lines if x.startswith("deckpound study quick: ")]
    assert progress[0].startswith("deckpound study quick: 0/1 done")
    assert re.match(r"deckpound study quick: 1/1 done in \d", progress[-1])
    assert "\r" not in log.getvalue()
