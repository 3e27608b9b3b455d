"""A campaign's progress on stderr: points done, running and failed, with an ETA."""

from __future__ import annotations

import sys
import time

from tqdm import tqdm

from granchain import progress


class CampaignProgress:
    """done / running / failed with an ETA on stderr: a tqdm bar on a terminal, a line every
    progress.LINE_EVERY seconds otherwise; nothing when quiet (granchain.progress)."""

    def __init__(self, total: int, desc: str = "campaign", stream=None, workers: int = 1):
        self.stream = sys.stderr if stream is None else stream
        self.disabled = progress.is_quiet() or self.stream is None
        self.tty = bool(not self.disabled and getattr(self.stream, "isatty", lambda: False)())
        self.total, self.done, self.failed, self.pending, self.workers = total, 0, 0, 0, max(1, workers)
        self.desc = f"granchain: {desc}"
        self.t0 = time.perf_counter()
        self._next_line = self.t0 + progress.DELAY
        #: a callable giving the batch jobs' line ("jobs 1 pending, 2 running"), or None
        self.jobs = None
        self._bar = None
        if self.tty:
            self._bar = tqdm(total=total, desc=self.desc, unit="pt", file=self.stream, dynamic_ncols=True, leave=True)

    @property
    def running(self) -> int:
        """Points running now: those submitted and not finished, at most one per worker."""
        return min(self.pending, self.workers)

    def _postfix(self) -> str:
        text = f"done {self.done}, running {self.running}, failed {self.failed}"
        jobs = self.jobs() if self.jobs is not None else None
        return f"{text}; {jobs}" if jobs else text

    def update(self, done: int = 0, failed: int = 0, pending: int | None = None, total: int | None = None) -> None:
        """Count points done and failed (added), set the points submitted and not finished and the
        total (a search's changes as bisections end), and show it: the bar at once, a line when one
        is due."""
        self.done += done
        self.failed += failed
        if pending is not None:
            self.pending = pending
        if total is not None:
            self.total = total
        if self.disabled:
            return
        n = self.done + self.failed
        if self._bar is not None:
            if total is not None:
                self._bar.total = total
            self._bar.set_postfix_str(self._postfix(), refresh=False)
            self._bar.update(n - self._bar.n)
            return
        now = time.perf_counter()
        if now >= self._next_line:
            self._line(now)
            self._next_line = now + progress.LINE_EVERY

    def _line(self, now: float) -> None:
        n = self.done + self.failed
        text = tqdm.format_meter(n, self.total or None, now - self.t0, prefix=self.desc, unit="pt")
        try:
            print(f"{text} ({self._postfix()})", file=self.stream, flush=True)
        except (OSError, ValueError):
            self.disabled = True

    def close(self) -> None:
        """Show the final counts: close the bar, or a last line if the campaign took long enough to show any."""
        if self.disabled:
            return
        if self._bar is not None:
            self._bar.set_postfix_str(self._postfix())
            self._bar.close()
            self._bar = None
        elif time.perf_counter() - self.t0 >= progress.DELAY:
            self._line(time.perf_counter())
