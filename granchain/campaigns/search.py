"""The search kind: for each outer point, bisect one key until a predicate of the run flips.

The bracket starts as the [search] range; both ends are run first (in parallel), and the predicate must
differ between them (otherwise it never flips in the range: that outer point is reported as such).
Then the midpoint (geometric for scale = "log", arithmetic for "linear") replaces the end whose
predicate it shares, until the bracket is within the tolerance: log, hi/lo - 1 <= tolerance; linear,
hi - lo <= tolerance. The transition is the bracket's midpoint, within half the tolerance of every value
where the predicate flips inside the final bracket (one flip if the predicate is monotonic in the key).
The outer points' bisections run side by side, each one run at a time. Every run is a point of the
workspace like a grid's: cached, resumable, in the table.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from granchain import safe_files
from granchain.campaigns import workspace as wsp
from granchain.campaigns.model import Campaign, CampaignError, Predicate, Search, params_text


def expected_runs(search: Search) -> int:
    """Runs one bisection takes: both ends, then halvings until the bracket is within the tolerance."""
    if search.scale == "log":
        ratio = math.log(search.high / search.low) / math.log1p(search.tolerance)
    else:
        ratio = (search.high - search.low) / search.tolerance
    return 2 + max(0, math.ceil(math.log2(ratio))) if ratio > 1 else 2


def predicate_quantity(job_dir: str | Path, predicate: Predicate) -> tuple[float | None, str | None]:
    """(the predicate's quantity for a complete run, None) or (None, why it cannot be measured)."""
    run = Path(job_dir) / wsp.RUN_DIR
    if predicate.quantity == "pulses":
        from granchain.postprocess.response_regimes import count_pulses

        force = read_history(run, predicate.contact)
        if force is None:
            return None, f"no force history of contact {predicate.contact} (add it to the scene's [outputs] histories)"
        return float(count_pulses(force, static_force=static_force(wsp.read_json(run / "summary.json")))), None
    summary = wsp.read_json(run / "summary.json") or {}
    value = summary.get("observables", {}).get(predicate.quantity)
    if value is None:
        why = summary.get("observables_missing", {}).get(predicate.quantity, "not measured")
        return None, f"{predicate.quantity} was not measured: {why}"
    return float(value), None


def static_force(summary) -> float:
    """A run's precompression F0 from its summary.json as read (observables.static_force; 0 without
    one, or where the file does not give a positive number): pulses are counted on the dynamic force
    F - F0."""
    obs = summary.get("observables") if isinstance(summary, dict) else None
    f0 = obs.get("static_force") if isinstance(obs, dict) else None
    ok = isinstance(f0, (int, float)) and not isinstance(f0, bool) and math.isfinite(f0) and f0 > 0
    return float(f0) if ok else 0.0


#: the largest histories.csv a search reads (a point's history of one chain: far below)
HISTORY_LIMIT = 1 << 30


def read_history(run_dir: Path, contact: int) -> np.ndarray | None:
    """Contact `contact`'s force history from a run directory's histories.csv (None if absent or
    unreadable: a link, a damaged or oversized file; read without following links)."""
    path = Path(run_dir) / "histories.csv"
    try:
        text = safe_files.read_text(path, HISTORY_LIMIT)
    except (OSError, UnicodeDecodeError):
        return None
    header = text.split("\n", 1)[0].strip().split(",")
    col = f"force_{contact}"
    if col not in header:
        return None
    try:
        data = np.loadtxt(io.StringIO(text), delimiter=",", skiprows=1, usecols=[header.index(col)], ndmin=1)
    except ValueError:
        return None
    return np.asarray(data, dtype=float)


@dataclass
class Bisection:
    """One outer point's search: the bracket [a, b] of the key with the predicate at each end.

    Attributes
    ----------
    index : int
        The outer point's place in the grid, from 0.
    outer : dict
        Its grid parameters (the outer keys).
    search : Search
        The [search] table.
    status : str
        "running", "found" (the bracket is within the tolerance), "no flip" (the predicate is the
        same at both ends of the range) or "failed" (a run gave no quantity; ``message`` says why).
    message : str or None
        Why it has no transition.
    a, b : float or None
        The bracket's ends, in the key's unit: a where the predicate is as at ``search.low``, b
        where it is as at ``search.high`` (set once both ends have run).
    holds_a, holds_b : bool or None
        The predicate at each end.
    quantity_a, quantity_b : float or None
        The predicate's quantity at each end.
    requested : set of float
        Values whose run has been asked for.
    results : dict
        Value -> (quantity, whether the predicate holds) of every run finished.
    runs : int
        Runs finished (cached ones included).
    counted : bool
        The progress display's total has been corrected for what this bisection took.
    """

    index: int
    outer: dict
    search: Search
    status: str = "running"  # running | found | no flip | failed
    message: str | None = None
    a: float | None = None
    b: float | None = None
    holds_a: bool | None = None
    holds_b: bool | None = None
    quantity_a: float | None = None
    quantity_b: float | None = None
    requested: set = field(default_factory=set)
    results: dict = field(default_factory=dict)  # value -> (quantity, holds)
    runs: int = 0
    counted: bool = False  # the progress display's total has been corrected for this bisection

    def needed(self) -> list[float]:
        """Values to run now (none while a requested one is still out)."""
        if self.status != "running":
            return []
        s = self.search
        ends = [v for v in (s.low, s.high) if v not in self.requested]
        if ends:
            return ends
        if s.low not in self.results or s.high not in self.results:
            return []
        if self.a is None:
            self._start()
            if self.status != "running":
                return []
        if s.converged(self.a, self.b):
            self.status = "found"
            return []
        mid = s.midpoint(self.a, self.b)
        if mid in self.requested:
            return []
        return [mid]

    def _start(self) -> None:
        s = self.search
        (qa, ha), (qb, hb) = self.results[s.low], self.results[s.high]
        self.a, self.b, self.holds_a, self.holds_b, self.quantity_a, self.quantity_b = s.low, s.high, ha, hb, qa, qb
        if ha == hb:
            self.status = "no flip"
            self.message = (
                f"{s.predicate.text} is {'true' if ha else 'false'} at both ends of {s.key}'s range "
                f"[{s.low:g}, {s.high:g}] ({s.predicate.quantity} = {qa:g} and {qb:g}"
                + (f"; {params_text(self.outer)}" if self.outer else "")
                + "): it never flips in the range; widen [search] range"
            )

    def record(self, value: float, quantity: float | None, why: str | None) -> None:
        """The run at `value` finished: its quantity, or why there is none (a failed run)."""
        self.runs += 1
        if self.status != "running":
            return
        if quantity is None:
            self.status = "failed"
            self.message = f"the run at {self.search.key} = {value:g} gives no {self.search.predicate.quantity}: {why}"
            return
        holds = self.search.predicate.holds(quantity)
        self.results[value] = (quantity, holds)
        if self.a is None:  # an end of the range
            return
        if holds == self.holds_a:
            self.a, self.quantity_a = value, quantity
        else:
            self.b, self.quantity_b = value, quantity

    def row(self) -> dict:
        """Its row of the search table: the outer parameters, the final bracket (KEY_low, KEY_high),
        ``transition`` (the bracket's midpoint) and ``transition_error`` (its half width, (b - a) / 2),
        ``width`` (in the tolerance's measure), the predicate and its quantity at each end, runs,
        status and message; the bracket's columns blank unless found."""
        s = self.search
        row = dict(self.outer)
        done = self.status == "found"
        row[f"{s.key}_low"] = self.a if done else None
        row[f"{s.key}_high"] = self.b if done else None
        row["transition"] = s.midpoint(self.a, self.b) if done else None
        row["transition_error"] = abs(self.b - self.a) / 2 if done else None  # the bracket's half width
        row["width"] = s.width(self.a, self.b) if done else None
        row["predicate"] = s.predicate.text
        row["quantity_low"] = self.quantity_a if self.a is not None else None
        row["quantity_high"] = self.quantity_b if self.b is not None else None
        row["runs"] = self.runs
        row["status"] = self.status
        row["message"] = self.message
        return row


def run_search(campaign: Campaign, runner, on_progress=None) -> tuple[list, list[dict]]:
    """Run a search campaign; returns (the evaluated points as (point, job id, outer index, point key),
    one row per outer point). on_progress(evaluated, rows) is called after each finished run (the
    caller keeps the workspace's record current, so a killed driver leaves a readable table)."""
    from distributed import as_completed

    from granchain.campaigns.campaign_progress import CampaignProgress

    s = campaign.search
    outers = campaign.grid()
    bis = [Bisection(i, o, s) for i, o in enumerate(outers)]
    per = expected_runs(s)
    prog = CampaignProgress(per * len(bis), "search", runner.stream, workers=runner.ex.nworkers)
    runner.report.points = 0
    evaluated: list = []
    waiting: dict = {}
    ac = None  # made with the first submission (it needs the client)
    prepared = False

    def request(b: Bisection, value: float) -> None:
        nonlocal prepared, ac
        b.requested.add(value)
        try:
            point = campaign.point({**b.outer, s.key: value}, b.index, len(bis))
        except CampaignError as e:
            b.status, b.message = "failed", str(e)
            return
        job = runner.job(point)
        runner.report.points += 1
        evaluated.append((point, job.id, b.index, wsp.point_key(job.cached_statepoint)))
        if not runner.needs_run(job):
            q, why = _quantity(job.path, s.predicate)
            prog.update(wsp.DONE)
            b.record(value, q, why)
            return
        if not prepared:
            runner.prepare()
            prepared = True
        fut = runner.submit(job, point)
        runner.report.ran += 1
        waiting[fut] = (b, value, point, job)
        if ac is None:
            ac = as_completed([fut])
        else:
            ac.add(fut)
        prog.update(pending=len(waiting))

    def advance(b: Bisection) -> None:
        while True:
            need = b.needed()
            if not need:
                break
            for v in need:
                request(b, v)
        if b.status != "running" and not b.counted and not any(w[0] is b for w in waiting.values()):
            # the display's total: what this bisection took instead of what it was expected to
            b.counted = True
            prog.update(total=prog.total - per + b.runs)

    try:
        for b in bis:
            advance(b)
        for fut in ac if ac is not None else ():
            b, value, point, job = waiting.pop(fut)
            prog.pending = len(waiting)
            r = runner.collect(fut, point.params, prog)
            if r["status"] == "done":
                q, why = _quantity(job.path, s.predicate)
            else:
                q, why = None, r.get("message")
            b.record(value, q, why)
            advance(b)
            if on_progress is not None:
                on_progress(evaluated, [x.row() for x in bis])
    finally:
        prog.close()
    return evaluated, [b.row() for b in bis]


def _quantity(job_dir, predicate: Predicate) -> tuple[float | None, str | None]:
    state = wsp.job_state(job_dir)
    if state == "failed":
        rec = wsp.read_json(Path(job_dir) / wsp.FAILURE) or {}
        return None, f"the run failed: {rec.get('message', '?')}"
    if state != "done":
        return None, "the run did not complete"
    return predicate_quantity(job_dir, predicate)
