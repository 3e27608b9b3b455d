"""What every section of `granchain reproduce` shares: the rows of printed numbers, the section's
result, running its campaigns (cached in the report's workspace) and reading their run directories.

A section never computes a number outside a campaign: every run is a campaign point in
``OUT/ws/<campaign>/`` (a signac workspace, docs/campaigns.md), so a second call finds every point
complete and runs nothing; only the figures and the report are drawn again.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from granchain import safe_files
from granchain.exceptions import GranchainError

#: verdicts a row can get
AGREES, DISAGREES, NOT_YET, NO_CLAIM = "agrees", "disagrees", "not yet reproduced", "no comparison"


@dataclass
class Row:
    """One printed number of the paper against ours.

    tol: the paper's own stated error, relative (e.g. 0.03 for "a 3% error"); where the paper states
    none, the precision of the printed number (half a unit of its last digit), and tol_source says which.
    """

    key: str  # stable id: "<section>.<name>" (tests match rows with docs/paper-discrepancies.md by it)
    quantity: str
    unit: str
    paper: float | None
    paper_text: str = ""
    ours: float | None = None
    ours_error: float | None = None
    model: float | None = None
    tol: float | None = None
    tol_source: str = ""
    reason: str = ""  # why we disagree (or what the comparison means)
    verdict: str = ""

    def judge(self) -> Row:
        """Give the row its verdict, unless it has one already; returns the row.

        "not yet reproduced" without a finite value of ours, "no comparison" without a printed
        value, else "agrees" when |ours - paper| <= tol |paper| + our error bar (tol: the row's, or
        half a unit of the printed number's last digit), and "disagrees" otherwise.
        """
        if self.verdict:
            return self
        if self.ours is None or not math.isfinite(self.ours):
            self.verdict = NOT_YET
        elif self.paper is None:
            self.verdict = NO_CLAIM
        else:
            tol = self.tol if self.tol is not None else printed_precision(self.paper_text, self.paper)
            err = self.ours_error if self.ours_error is not None and math.isfinite(self.ours_error) else 0.0
            self.verdict = AGREES if abs(self.ours - self.paper) <= tol * abs(self.paper) + err else DISAGREES
        return self


def printed_precision(text: str, value: float) -> float:
    """Half a unit of the last printed digit, relative to the value ("0.719" -> 0.0005/0.719)."""
    s = (text or repr(value)).strip().split()[0].rstrip(".")
    digits = len(s.split(".", 1)[1]) if "." in s else 0
    return 0.5 * 10.0**-digits / abs(value) if value else 0.0


@dataclass
class Figure:
    """A figure of a section: the file OUT/figures/<name>.png and its caption in the report."""

    name: str  # file stem under OUT/figures
    caption: str  # what it shows, and how it differs from the paper's


@dataclass
class SectionResult:
    """One section of the report: the printed numbers it checks (rows), its figures and notes,
    whether it reproduced its part of the paper, and the campaigns it ran with their cost beside
    the paper's."""

    key: str
    title: str
    rows: list[Row] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    reproduced: bool = True  # False: "not yet reproduced", with the reason in notes
    campaigns: list[str] = field(default_factory=list)  # workspace names under OUT/ws
    cost: dict = field(default_factory=dict)  # runs, wall_time, bead_steps (ours)
    paper_cost: str = ""  # the paper's setup, in words
    paper_bead_steps: float | None = None
    failed: bool = False  # the section raised (a bug or a failed run); notes say what


def not_yet(key: str, title: str, why: str) -> SectionResult:
    """A section that is not reproduced, with why in its notes."""
    return SectionResult(key, title, notes=[f"Not yet reproduced: {why}"], reproduced=False)


class ReproduceDirError(GranchainError):
    """A directory of `reproduce`'s OUT it will not write into (a symbolic link planted there)."""


def output_file(path: Path) -> Path:
    """``path``, a file `reproduce` writes afresh on every call (report, rows, figure), made safe
    to write: a symbolic link planted there is removed, never written through (the file is
    granchain's output, drawn again from the cache), and the caller writes it atomically
    (safe_files), so a kill leaves the old file or the new one, never a truncated one."""
    if safe_files.is_link(path):
        os.unlink(path)
    return path


def output_dir(path: Path, what: str) -> Path:
    """Make the directory ``path`` of OUT (``what`` says what it holds), refusing a symbolic link
    there: what `reproduce` writes stays inside OUT. Returns ``path``."""
    if safe_files.is_link(path):
        raise ReproduceDirError(
            f"{path}: is a symbolic link; reproduce writes {what} only inside --out "
            "(remove the link, or move the directory it points to in its place)"
        )
    path.mkdir(parents=True, exist_ok=True)
    return path


class Context:
    """One `reproduce` call: where it writes, how it runs campaigns, what they did."""

    def __init__(self, out: Path, quick: bool, workers=None, scheduler=None, stream=None):
        self.out, self.quick = Path(out), quick
        self.workers, self.scheduler, self.stream = workers, scheduler, stream
        self.fig_dir = self.out / "figures"
        if safe_files.is_link(self.fig_dir):  # figures are drawn again on every call: a link is not ours
            os.unlink(self.fig_dir)
        output_dir(self.fig_dir, "its figures")
        self.reports: dict[str, object] = {}  # campaign name -> RunReport

    @property
    def mode(self) -> str:
        """The mode, "quick" or "full": the prefix of every campaign's workspace name."""
        return "quick" if self.quick else "full"

    def campaign(self, name: str, spec: dict):
        """Run (or find complete) one campaign in OUT/ws/<mode>-<name>; returns that workspace
        directory (``points`` reads its table) and keeps the campaign's report (points run, cached,
        failed) for the report's metadata."""
        from granchain.campaigns.run import run_campaign

        output_dir(self.out / "ws", "its campaign workspaces")  # the cache: refused, not replaced
        ws = output_dir(self.out / "ws" / f"{self.mode}-{name}", "a campaign's workspace")
        tables, report = run_campaign(spec, ws, workers=self.workers, scheduler=self.scheduler, stream=self.stream)
        self.reports[f"{self.mode}-{name}"] = report
        return ws

    def figure(self, fig, name: str) -> Path:
        """Save a matplotlib figure as OUT/figures/<name>.png and close it; returns the path."""
        path = output_file(self.fig_dir / f"{name}.png")
        safe_files.save_figure(fig, path, dpi=110)
        import matplotlib.pyplot as plt

        plt.close(fig)
        return path


# ----------------------------------------------------------------- reading a campaign's results


def points(ws: Path):
    """The campaign's points table (pandas), with the run directory of each point as column `run`."""
    from granchain.campaigns.run import load_campaign

    df = load_campaign(ws, table="points")
    df["run"] = [ws / "workspace" / str(j) / "run" for j in df["job"]]
    return df


def failed(df) -> list[str]:
    """What went wrong at the points of a campaign table that are not done: "status: message" each."""
    bad = df[df["status"] != "done"]
    return [f"{r.get('status')}: {r.get('message')}" for _, r in bad.iterrows()]


def cost_of(*tables) -> dict:
    """What the done points of campaign tables cost together: runs, wall_time (s) and bead_steps."""
    runs, wall, bs = 0, 0.0, 0.0
    for df in tables:
        done = df[df["status"] == "done"]
        runs += len(done)
        wall += float(np.nansum(done["wall_time"].astype(float)))
        bs += float(np.nansum(done["bead_steps"].astype(float)))
    return {"runs": runs, "wall_time": wall, "bead_steps": bs}


def read_csv(path: Path) -> dict[str, np.ndarray]:
    """A CSV file with a header row, as one array per column name."""
    data = np.genfromtxt(path, delimiter=",", names=True, ndmin=1, dtype=None, encoding="utf-8")
    return {n: np.asarray(data[n]) for n in data.dtype.names}


def peaks(run: Path) -> dict[str, np.ndarray]:
    """A run directory's peaks.csv, one array per column (granchain.rundir.read_peaks)."""
    from granchain.rundir import read_peaks

    return read_peaks(run)


def summary(run: Path) -> dict:
    """A run directory's summary.json (granchain.rundir.read_summary)."""
    from granchain.rundir import read_summary

    return read_summary(run)


def histories(run: Path) -> dict[str, np.ndarray]:
    """A run directory's histories.csv, one array per column (time, force_<i>, velocity_<i>)."""
    return read_csv(Path(run) / "histories.csv")


def snapshots(run: Path) -> list[tuple[float, dict[str, np.ndarray]]]:
    """[(time, {bead, velocity, contact_force, displacement})] in time order."""
    d = read_csv(Path(run) / "snapshots.csv")
    out = []
    for t in np.unique(d["time"]):
        sel = d["time"] == t
        out.append((float(t), {k: v[sel] for k, v in d.items() if k != "time"}))
    return out


def observable(run: Path, name: str) -> tuple[float | None, float | None]:
    """An observable of summary.json with its measured error (None where there is none)."""
    s = summary(run)
    v = s.get("observables", {}).get(name)
    e = ((s.get("errors") or {}).get("observables") or {}).get(name) or {}
    return (None if v is None else float(v)), (None if e.get("error") is None else float(e["error"]))


def scene_of(run: Path):
    """The scene a run directory was run from (its scene.toml: the scene as given)."""
    from granchain.scene import load_scene

    return load_scene(Path(run) / "scene.toml")


def campaign_section(ctx: Context, key: str, title: str, name: str, spec: dict, doc: str):
    """A section built on one campaign: its result (campaign named, cost counted, the module's
    docstring after its first paragraph as notes) and the campaign's points table."""
    res = SectionResult(key, title)
    ws = ctx.campaign(name, spec)
    res.campaigns.append(ws.name)
    df = points(ws)
    res.cost = cost_of(df)
    res.notes.append(doc.split("\n\n", 1)[1].strip())
    return res, df
