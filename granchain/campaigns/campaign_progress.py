"""A campaign's progress on stderr: points done, running, failed and missing, with an ETA; a finished
point is counted under the word the campaign table's status column gives it (workspace.job_state)."""

from __future__ import annotations

import sys
import time

from tqdm import tqdm

from granchain import progress
from granchain.campaigns.model import DONE, FAILED, MISSING

#: the outcome of a point's task (point_task.run_point's status; "lost": no result came back) as the
#: table's status column names it: a lost point has neither a run nor a failure.json, so it is missing
STATUS_OF_OUTCOME = {DONE: DONE, FAILED: FAILED, "lost": MISSING}


class CampaignProgress:
    """done / running / failed / missing with an ETA on stderr: a tqdm bar on a terminal, a line every
    progress.LINE_EVERY seconds otherwise; nothing when quiet (granchain.progress). A finished point
    is counted under its status in the table's words (STATUS_OF_OUTCOME)."""

    def __init__(self, total: int, desc: str = "campaign", stream=None, workers: int = 1):
        self.stream = sys.stderr if stream is None else stream
        self.disabled = progress.is_quiet() or self.stream is None
        self.tty = bool(not self.disabled and getattr(self.stream, "isatty", lambda: False)())
        self.total, self.pending, self.workers = total, 0, max(1, workers)
        #: finished points by status, in the table's words (missing: lost in flight)
        self.finished = {DONE: 0, FAILED: 0, MISSING: 0}
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

    @property
    def n_finished(self) -> int:
        """Points finished, whatever their status."""
        return sum(self.finished.values())

    def _postfix(self) -> str:
        f = self.finished
        text = f"{DONE} {f[DONE]}, running {self.running}, {FAILED} {f[FAILED]}"
        if f[MISSING]:
            text += f", {MISSING} {f[MISSING]}"
        jobs = self.jobs() if self.jobs is not None else None
        return f"{text}; {jobs}" if jobs else text

    def update(self, outcome: str | None = None, pending: int | None = None, total: int | None = None) -> None:
        """Count one finished point by its task's outcome (a key of STATUS_OF_OUTCOME), set the points
        submitted and not finished and the total (a search's changes as bisections end), and show it:
        the bar at once, a line when one is due."""
        if outcome is not None:
            self.finished[STATUS_OF_OUTCOME[outcome]] += 1
        if pending is not None:
            self.pending = pending
        if total is not None:
            self.total = total
        if self.disabled:
            return
        n = self.n_finished
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
        text = tqdm.format_meter(self.n_finished, self.total or None, now - self.t0, prefix=self.desc, unit="pt")
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
