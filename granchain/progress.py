"""Progress of long runs on stderr: a tqdm bar on a terminal, plain lines elsewhere.

    with Progress(total_steps, "reference rk4") as p:
        next_check = p.start()
        for step in ...:
            if step == next_check:
                next_check = p.update(step)  # cheap; returns the step at which to call again
        p.finish(step)                       # the run's own last step (a run may stop early)

Nothing is shown for a run that ends within DELAY seconds. On a terminal (stderr.isatty()) a tqdm
bar with elapsed time and ETA appears after DELAY seconds and redraws at most every REDRAW seconds;
otherwise one plain line (formatted by tqdm.format_meter) after DELAY seconds, then every LINE_EVERY
seconds, and a last line when the run ends. Nothing at all inside `quiet()` or with GRANCHAIN_QUIET=1
(the command line's --quiet).

The price: update() reads the clock and returns the next step to call it at, chosen so that calls
are about CHECK_EVERY seconds apart (at least MIN_STRIDE steps); the caller's loop pays one integer
comparison per step. See benchmarks/bench_progress.py for the measured cost.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from contextlib import contextmanager

from tqdm import tqdm

#: seconds before anything is shown (runs shorter than this print nothing)
DELAY = 2.0
#: seconds between two plain lines when stderr is not a terminal
LINE_EVERY = 5.0
#: seconds between two redraws of the terminal bar
REDRAW = 0.5
#: target seconds between two update() calls of a step loop, and the smallest stride in steps
CHECK_EVERY = 0.1
MIN_STRIDE = 16

BAR_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| {n}/{total} steps [{elapsed}<{remaining}, {rate_fmt}]"
LINE_FORMAT = "{desc}: {percentage:3.0f}% ({n}/{total} steps) [{elapsed} elapsed, {remaining} left, {rate_fmt}]"
LINE_FORMAT_NO_TOTAL = "{desc}: {n} steps [{elapsed} elapsed, {rate_fmt}]"

_quiet = 0
#: what the runs started in this thread are (labelled): "error-bar companion at 2 dt" ...
_label = threading.local()


def is_quiet() -> bool:
    """Whether progress is switched off (inside quiet(), or GRANCHAIN_QUIET set to anything but 0/empty)."""
    return _quiet > 0 or os.environ.get("GRANCHAIN_QUIET", "") not in ("", "0")


@contextmanager
def quiet(enabled: bool = True):
    """No progress output inside this block (enabled=False: no change, for `with quiet(args.quiet):`)."""
    global _quiet
    if not enabled:
        yield
        return
    _quiet += 1
    try:
        yield
    finally:
        _quiet -= 1


@contextmanager
def labelled(text: str):
    """Progress lines of the runs started inside this block (in this thread) say what they are for,
    e.g. ``with labelled("error-bar companion at 2 dt"):`` -> "granchain: error-bar companion at 2 dt:
    reference rk4: 40% ..."."""
    old = getattr(_label, "text", "")
    _label.text = f"{old}{text}: "
    try:
        yield
    finally:
        _label.text = old


class Progress:
    """Progress of a run of `total` steps, shown on `stream` (default: sys.stderr at creation)."""

    def __init__(self, total: int | None, desc: str, stream=None):
        self.total = int(total) if total else 0
        self.desc = f"granchain: {getattr(_label, 'text', '')}{desc}"
        self.stream = sys.stderr if stream is None else stream
        self.disabled = is_quiet() or self.stream is None
        self.tty = bool(not self.disabled and getattr(self.stream, "isatty", lambda: False)())
        self.t0 = time.perf_counter()
        self.n = 0
        self.stride = MIN_STRIDE
        self._t_check = self.t0
        self._n_check = 0
        self._bar: tqdm | None = None
        self._next_line = self.t0 + DELAY
        self._lines = 0
        self._closed = False

    # ---- the step loop's side
    def start(self, total: int | None = None) -> int:
        """Set the total (if known only now); returns the first step at which to call update()."""
        if total:
            self.total = int(total)
        return -1 if self.disabled else MIN_STRIDE

    def update(self, n: int) -> int:
        """The run has done n steps; returns the next step at which to call update() again."""
        if self.disabled:
            return -1
        now = time.perf_counter()
        # stride: about CHECK_EVERY seconds of steps at the rate since the last call
        dt = now - self._t_check
        if dt > 0 and n > self._n_check:
            self.stride = max(MIN_STRIDE, int((n - self._n_check) * CHECK_EVERY / dt))
        self._t_check, self._n_check = now, n
        self._show(n, now)
        return n + self.stride

    def finish(self, n: int) -> None:
        """The run ended after n steps (fewer than the total if it stopped early): show it done."""
        if self.disabled or self._closed:
            return
        if n < self.total or not self.total:
            self.total = n  # a run that stopped early is complete at its last step
        self._show(n, time.perf_counter(), final=True)
        self.close()

    def close(self) -> None:
        """End the display (a run that raised leaves its bar where it stopped, on its own line)."""
        if self._closed:
            return
        self._closed = True
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> Progress:
        """The progress itself: ``with Progress(...) as p``."""
        return self

    def __exit__(self, *exc) -> None:
        """Close the display, whether the run ended or raised (the exception propagates)."""
        self.close()

    # ---- display
    def _show(self, n: int, now: float, final: bool = False) -> None:
        self.n = n
        if self._closed or now - self.t0 < DELAY:
            return
        if self.tty:
            if self._bar is None:
                self._bar = tqdm(
                    total=self.total or None,
                    desc=self.desc,
                    unit="step",
                    unit_scale=True,
                    file=self.stream,
                    mininterval=REDRAW,
                    dynamic_ncols=True,
                    bar_format=BAR_FORMAT if self.total else None,
                    leave=True,
                    delay=1e-9,  # not drawn at creation (at 0 steps) but by the update below
                )
                # elapsed time and the first rate from the start of the run, not from the bar's (tqdm's clock
                # is time.time)
                self._bar.start_t = self._bar.last_print_t = time.time() - (now - self.t0)
            if final:
                self._bar.total = self.total
            self._bar.update(n - self._bar.n)
        elif (final and self._lines) or now >= self._next_line:
            self._line(n, now)
            self._next_line = now + LINE_EVERY

    def _line(self, n: int, now: float) -> None:
        text = tqdm.format_meter(
            n,
            self.total or None,
            now - self.t0,
            prefix=self.desc,
            unit="step",
            unit_scale=True,
            bar_format=LINE_FORMAT if self.total else LINE_FORMAT_NO_TOTAL,
        )
        try:
            print(text, file=self.stream, flush=True)
        except (OSError, ValueError):  # a closed or broken stderr: progress is not worth failing a run
            self.disabled = True
        self._lines += 1


__all__ = ["Progress", "quiet", "is_quiet", "DELAY", "LINE_EVERY"]
