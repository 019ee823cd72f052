"""Progress of long work on stderr: a bar on a terminal, plain lines at a steady pace elsewhere.

On a terminal (``stream.isatty()``) the bar is redrawn in place (``\\r``) at each finished item.
Anywhere else — a log file (``nohup deckpound paper ... 2>log``), a pipe, a notebook — a
carriage return would pile up as one endless line, so the progress is written as plain lines:
one at the start, then one whenever :func:`progress_interval` seconds have passed since the last
line (at an item's end, or from a daemon thread between items, so that a case running for
minutes still shows the work is alive), and a final one. A line says what is done, the rate and
the time left::

    deckpound study skew: 12/30 done (40 %), 0.86 per min, 14 min 2 s elapsed, about 21 min left

Items that were already done before the work started (cached cases: :meth:`Progress.skip`)
count as done but not into the rate. The thread holds the bar only weakly and ends with it (or
at :meth:`Progress.close`, or when the last item is done); it needs the interpreter lock to
write, which a case running in this very process may hold (work on worker processes or guarded
children leaves it free).
"""

from __future__ import annotations

import math
import os
import sys
import threading
import time
import weakref
from collections.abc import Callable

from deckpound.models.errors import SceneError

__all__ = ["PROGRESS_INTERVAL", "Progress", "duration_text", "progress_interval"]

#: seconds between two progress lines when stderr is not a terminal; the environment variable
#: ``DECKPOUND_PROGRESS_INTERVAL`` overrides it. The thread looks every quarter interval, so a
#: line follows the previous one within 1.25 intervals (25 s): below the 30 s a log promises
PROGRESS_INTERVAL = 20.0
#: the environment variable of :func:`progress_interval`
INTERVAL_VARIABLE = "DECKPOUND_PROGRESS_INTERVAL"


def progress_interval() -> float:
    """Seconds between progress lines off a terminal: ``DECKPOUND_PROGRESS_INTERVAL`` when set
    (a number > 0), else :data:`PROGRESS_INTERVAL`."""
    text = os.environ.get(INTERVAL_VARIABLE, "").strip()
    if not text:
        return PROGRESS_INTERVAL
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise SceneError(
            INTERVAL_VARIABLE,
            f"must be a number of seconds > 0 (the time between progress lines), got {text!r}",
        )
    return value


def duration_text(seconds: float) -> str:
    """'42 s', '3 min 5 s', '2 h 7 min' (rounded to whole seconds / minutes)."""
    s = max(0, int(round(seconds)))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60} s"
    return f"{s // 3600} h {(s % 3600) // 60} min"


def _rate_text(per_second: float) -> str:
    if per_second >= 1.0:
        return f"{per_second:.3g} per s"
    if per_second * 60.0 >= 1.0:
        return f"{per_second * 60.0:.3g} per min"
    return f"{per_second * 3600.0:.3g} per h"


#: when the last progress line was written, per clock (the threads fill silences only)
_LAST_LINE: dict[Callable[[], float], float] = {}


def _tick_loop(ref: weakref.ref, stop: threading.Event, wait: float) -> None:
    """The daemon thread: a line whenever one is due, until the bar ends or is gone."""
    while not stop.wait(wait):
        bar = ref()
        if bar is None:
            return
        bar.tick()
        del bar  # hold the bar only while ticking: it ends when its owner drops it


class Progress:
    """Progress of ``total`` items on ``stream`` (stderr by default; silent when ``enabled`` is
    False or there is nothing to do). See the module docstring for the two forms.

    ``log_only``: silent on a terminal (an outer progress of stages, whose inner work draws
    its own bars); ``eta``: say the time left (off for stages of unequal length); ``note``
    (attribute): what is being done now, appended to the lines. The thread's lines fill the
    silences only: none while another progress of the same clock has written within the
    interval (the stages of ``paper`` stay quiet while a study reports its cases).

    ``clock`` (seconds, monotonic), ``interval`` (seconds between lines; default
    :func:`progress_interval`) and ``ticker`` (start the thread; tests drive :meth:`tick`
    themselves) are for tests and callers with their own pace.
    """

    def __init__(
        self,
        total: int,
        title: str,
        enabled: bool = True,
        *,
        stream=None,
        clock: Callable[[], float] = time.monotonic,
        interval: float | None = None,
        ticker: bool = True,
        log_only: bool = False,
        eta: bool = True,
    ):
        self.total, self.done, self.title = total, 0, title
        self.enabled = enabled and total > 0
        self.eta, self.note = eta, ""
        self.stream = stream if stream is not None else sys.stderr
        self.clock = clock
        if interval is None:
            interval = progress_interval() if self.enabled else PROGRESS_INTERVAL
        self.interval = interval
        self.skipped = 0  # done before the work started: not in the rate
        self.t0 = clock()
        self.last_line = -math.inf
        self.closed = False
        self._bar_width = 0  # length of the last bar drawn (a shorter one is padded)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        try:
            self.tty = bool(self.stream.isatty())
        except (AttributeError, ValueError, OSError):  # no isatty, or a closed stream
            self.tty = False
        if log_only and self.tty:
            self.enabled = False
        if not self.enabled:
            return
        if self.tty:
            self._draw()
            return
        self._line()
        if ticker:
            weakref.finalize(self, self._stop.set)
            threading.Thread(
                target=_tick_loop,
                args=(weakref.ref(self), self._stop, min(self.interval / 4.0, 5.0)),
                name=f"deckpound progress {title}",
                daemon=True,
            ).start()

    # -- the caller's side ----------------------------------------------------------------------
    def skip(self, n: int) -> None:
        """``n`` items were done before the work started (cached): done, not in the rate."""
        if n:
            self.skipped += n
            self.advance(n)

    def advance(self, n: int = 1) -> None:
        """``n`` more items done."""
        if not n:
            return
        with self._lock:
            self.done += n
            if not self.enabled or self.closed:
                return
            if self.tty:
                self._draw()
            elif self.done >= self.total:
                self._final()
            elif self.clock() - self.last_line >= self.interval:
                self._line()

    def tick(self) -> None:
        """Write a line off a terminal when one is due (the thread calls this)."""
        with self._lock:
            if self.enabled and not self.tty and not self.closed and self.done < self.total:
                last = max(self.last_line, _LAST_LINE.get(self.clock, -math.inf))
                if self.clock() - last >= self.interval:
                    self._line()

    def close(self) -> None:
        """End the progress: the thread stops; a bar left unfinished (an interrupt) ends its
        line so the next message starts one, and off a terminal a last line says where the
        work stopped."""
        with self._lock:
            self._stop.set()
            if self.closed or not self.enabled:
                self.closed = True
                return
            self.closed = True
            if self.done < self.total:
                if self.tty:
                    self._write("\n")
                else:
                    self._line("stopped at ")

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- text -----------------------------------------------------------------------------------
    def _elapsed(self) -> float:
        return max(self.clock() - self.t0, 0.0)

    def _rate(self) -> float | None:
        """Items per second over the work of this run (skipped items excluded)."""
        worked, elapsed = self.done - self.skipped, self._elapsed()
        return worked / elapsed if worked > 0 and elapsed > 0 else None

    def _line(self, prefix: str = "") -> None:
        elapsed, rate = self._elapsed(), self._rate()
        pct = 100.0 * self.done / self.total
        text = f"deckpound {self.title}: {prefix}{self.done}/{self.total} done ({pct:.0f} %)"
        if not self.eta:
            text += f", {duration_text(elapsed)} elapsed"
        elif rate is None:
            text += f", {duration_text(elapsed)} elapsed, rate and time left after the first"
        else:
            left = (self.total - self.done) / rate
            text += (
                f", {_rate_text(rate)}, {duration_text(elapsed)} elapsed, "
                f"about {duration_text(left)} left"
            )
        if self.note:
            text += f"; now: {self.note}"
        self._stamp()
        self._write(text + "\n")

    def _stamp(self) -> None:
        self.last_line = _LAST_LINE[self.clock] = self.clock()

    def _final(self) -> None:
        rate = self._rate()
        text = f"deckpound {self.title}: {self.done}/{self.total} done in "
        text += duration_text(self._elapsed())
        if rate is not None and self.eta:
            text += f" ({_rate_text(rate)})"
        self.closed = True
        self._stop.set()
        self._stamp()
        self._write(text + "\n")

    def _draw(self) -> None:
        width = 30
        fill = int(width * min(self.done, self.total) / self.total)
        elapsed, rate = self._elapsed(), self._rate()
        text = (
            f"\r{self.title} [{'#' * fill}{'.' * (width - fill)}] "
            f"{self.done}/{self.total} {elapsed:6.1f} s"
        )
        if rate is not None and self.done < self.total:
            text += f", ~{duration_text((self.total - self.done) / rate)} left "
        text, self._bar_width = text.ljust(self._bar_width), len(text)
        if self.done >= self.total:
            text += "\n"
            self.closed = True
        self._write(text)

    def _write(self, text: str) -> None:
        # one write per line: the CLI's stderr filter decides per line (deckpound's own lines
        # and \r bars pass)
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):  # a closed or full stderr loses the progress, not the work
            pass
