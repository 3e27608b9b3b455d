"""Running a campaign's points on Dask: a local cluster of worker processes, or an existing scheduler.

Each task runs one point (:func:`run_point`, in a worker process) and writes the point's run directory
into the workspace itself (the workspace is on a filesystem every worker sees: a laptop's disk, a
cluster's shared filesystem), then returns a small status dict. The driver only submits, counts and
reads the workspace back; it keeps no result that is not on disk. Hence:

* a point whose run directory is complete is not run again (``rerun`` forces it);
* a failing point (bad physics, a broken invariant, a LAMMPS error, a bug) is recorded in its job
  directory with a one-line message (failure.json) and the campaign goes on; it is not retried
  unless ``retry_failed`` (or ``rerun``);
* Ctrl-C cancels what is queued and stops the workers; kill -9 of the driver takes its local workers
  with it (Dask's worker processes exit when their parent dies); a killed worker loses the point it was
  running (Dask resubmits it elsewhere; after three lost workers the point is reported as lost, not
  failed); in every case the next run completes only what is missing, and since a run directory is
  written aside and renamed into place, an interrupted point never looks complete.

One LAMMPS instance per running point: each LAMMPS run is a child process of its worker
(granchain.lammps.runner), and a worker keeps that child, with its LAMMPS instance and plugin loaded,
for its next points (:class:`PersistentLammps`, granchain.lammps.server: no start-up per point). A
child that crashed or reported a LAMMPS error fails its point only; the next point gets a new child.

The modules: point_task (the task in a worker), dask_executor (the Dask client and its workers),
campaign_progress (the progress line) and this one (the driver: what to run, submitting, collecting).
"""

from __future__ import annotations

import sys
import uuid
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from granchain import progress
from granchain.backends import backend_named
from granchain.campaigns import workspace as wsp
from granchain.campaigns.campaign_progress import CampaignProgress
from granchain.campaigns.dask_executor import Executor, PersistentLammps, QuietInterrupt
from granchain.campaigns.model import Campaign, CampaignError, Point, params_text
from granchain.campaigns.point_task import finished_before, one_line, run_point
from granchain.exceptions import GranchainError


@dataclass
class RunReport:
    """What one `campaign run` did (counts are points).

    Attributes
    ----------
    points : int
        The campaign's points (a search's: the runs its bisections asked for).
    cached : int
        Complete before this run, not run again.
    ran : int
        Submitted to Dask by this run.
    done, failed : int
        Completed, and failed (failure.json), in this run.
    failed_before : int
        Failed before and not retried (``retry_failed``).
    lost : int
        Without a result: a worker running it was lost three times, or its task was cancelled.
    stale : int
        Computed before by other code, so run again.
    stale_codes : list of dict
        That other code (granchain version, source hash, plugin hash), each once.
    messages : list of tuple
        (params, message) of the points that failed or were lost.
    """

    points: int = 0
    cached: int = 0  # complete before this run, not run again
    ran: int = 0  # submitted to Dask by this run
    done: int = 0  # completed by this run
    failed: int = 0  # failed in this run (failure.json)
    failed_before: int = 0  # failed before and not retried
    lost: int = 0  # no result (a worker lost three times)
    stale: int = 0  # computed before by other code: run again
    stale_codes: list = field(default_factory=list)
    messages: list = field(default_factory=list)  # (params, message) of the failures


class Runner:
    """The driver's side of one `campaign run`: jobs for points, what to submit, what is cached."""

    def __init__(self, campaign: Campaign, ws, executor: Executor, rerun=False, retry_failed=False, stream=None):
        self.c, self.ws = campaign, Path(ws)
        self.ex = executor
        self.rerun, self.retry_failed = rerun, retry_failed
        self.stream = sys.stderr if stream is None else stream
        self.methods: dict[str, str | None] = {}  # the integrators its points run, each with its reason
        self.code = wsp.code_version(campaign.backend)
        self.project = wsp.create_workspace(ws)
        self._stale = wsp.stale_versions(self.project, self.code)
        self.report = RunReport()
        self.in_flight: dict = {}  # future key -> job directory
        self.token = uuid.uuid4().hex  # this campaign run's: a task Dask runs twice finds its own result
        self.record: dict | None = None  # campaign.json as this run wrote it last (run.write_record)

    def submit(self, job, point: Point):
        """Submit one point's run (the job directory counts as in flight until collected)."""
        fut = self.ex.submit(self.payload(job, point))
        self.in_flight[fut.key] = Path(job.path)
        return fut

    def forget_interrupted(self, since: float) -> None:
        """After Ctrl-C: a point in flight whose run was stopped by it (a LAMMPS child gets the signal
        too) is missing, not failed: remove the failure.json written since the interrupt."""
        for job_dir in self.in_flight.values():
            f = job_dir / wsp.FAILURE
            try:
                if f.stat().st_mtime >= since - 1.0:
                    f.unlink()
            except OSError:
                pass

    def method(self, point: Point) -> str:
        """The integrator this point runs: [campaign] method, or the backend's default for the point's
        scene (workflows.run.method_choice: the reference's Verlet where the point has velocity-dependent damping),
        said once per campaign run where the scene chose it."""
        method, why = point_method(self.c, point.scene)
        if why is not None and method not in self.methods:
            self.say(
                f"points with {point.scene.damping.phrase}: the {self.c.backend} backend runs {why}; their state "
                "points say "
                f'{method}, so results of them made with another method are not theirs ([campaign] method = "rk4" '
                "runs and finds those)"
            )
        self.methods.setdefault(method, why)
        return method

    @property
    def record_method(self) -> tuple[str | None, str | None]:
        """(method, reason) for the campaign's record: the one integrator its points ran so far (None
        when they ran several: each point's state point names its own), and why the scene chose it
        where it did (None where no point's scene did); before any point, the base scene's."""
        if not self.methods:
            from granchain.scene import scene_from_dict

            return point_method(self.c, scene_from_dict(self.c.base, source=self.c.base_source))
        only = next(iter(self.methods)) if len(self.methods) == 1 else None
        return only, next((why for why in self.methods.values() if why is not None), None)

    def job(self, point: Point):
        """The point's signac job, created if new: its state point is the canonical scene, backend,
        method (the one the point runs: method), rtol, error_estimate and the code
        (granchain.campaigns.workspace.statepoint)."""
        sp = wsp.statepoint(
            point.scene_dict, self.c.backend, self.method(point), self.c.rtol, self.c.error_estimate, self.code
        )
        job = self.project.open_job(sp)
        job.init()
        return job

    def needs_run(self, job) -> bool:
        """Whether this point must run now (and count what is cached, failed or stale)."""
        state = wsp.job_state(job.path)
        if self.rerun:
            return True
        if state == "done":
            self.report.cached += 1
            return False
        if state == "failed" and not self.retry_failed:
            self.report.failed_before += 1
            return False
        other = self._stale.get(wsp.point_key(job.cached_statepoint))
        if other is not None:
            self.report.stale += 1
            if other not in self.report.stale_codes:
                self.report.stale_codes.append(other)
        return True

    def ranks(self, point: Point) -> int:
        """MPI ranks for this point: [campaign] ranks, or for "auto" the plan's --np auto rule
        (granchain.schedule.auto_ranks) over the cores one worker may use."""
        return point_ranks(self.c, point.scene, self.ex.slot_cores())

    def payload(self, job, point: Point) -> dict:
        """What run_point needs in the worker: the job directory, the canonical scene, the backend,
        method, rtol, error_estimate and code, the point's MPI ranks, and this run's token."""
        return {
            "ranks": self.ranks(point),
            "token": self.token,
            "rerun": self.rerun,
            "job_dir": str(Path(job.path).resolve()),
            "scene": point.scene_dict,
            "source": f"campaign point ({params_text(point.params)})",
            "backend": self.c.backend,
            "method": self.method(point),
            "rtol": self.c.rtol,
            "error_estimate": self.c.error_estimate,
            "code": self.code,
        }

    def prepare(self) -> None:
        """Before any run: the LAMMPS plugin is built here once (not by each local worker at once)."""
        if self.ex.scheduler is None:
            backend_named(self.c.backend).prepare()

    def collect(self, future, params: dict, prog: CampaignProgress) -> dict:
        """A finished future's status (a lost task counts as lost, not failed)."""
        self.in_flight.pop(future.key, None)
        try:
            r = future.result()
        except Exception as e:  # noqa: BLE001 - a worker died (KilledWorker) or the task was cancelled
            r = {"status": "lost", "message": one_line(e)}
        if r["status"] == "done":
            self.report.done += 1
        elif r["status"] == "failed":
            self.report.failed += 1
            self.report.messages.append((params, r["message"]))
        else:
            r["status"] = "lost"
            self.report.lost += 1
            self.report.messages.append((params, r["message"]))
        prog.update(r["status"])
        return r

    def say(self, text: str) -> bool:
        """'granchain: text' on the driver's stream, unless quiet; whether it was said."""
        if progress.is_quiet():
            return False
        print(f"granchain: {text}", file=self.stream, flush=True)
        return True

    def say_plan(self, todo: int) -> None:
        """Before the runs: the points, how many are complete, to run, failed before, and stale."""
        r = self.report
        parts = [f"{r.points} points", f"{r.cached} complete", f"{todo} to run"]
        if r.failed_before:
            parts.append(f"{r.failed_before} failed before (not retried: --retry-failed)")
        self.say("campaign: " + ", ".join(parts))
        if r.stale:
            codes = "; ".join(wsp.code_text(c) for c in r.stale_codes)
            self.say(
                f"campaign: {r.stale} of them are stale: computed by other code ({codes}), not by "
                f"{wsp.code_text(self.code)}; they run again"
            )


def point_ranks(campaign: Campaign, scene, slot_cores: int) -> int:
    """A point's MPI ranks: [campaign] ranks as given, or for "auto" one rank per
    MPI_CROSSOVER_BEADS / 2 beads, at most `slot_cores` (granchain.schedule.auto_ranks)."""
    if campaign.ranks != "auto":
        return campaign.ranks
    from granchain.schedule import auto_ranks

    return auto_ranks(planned_beads(campaign, scene), max(1, slot_cores))


def planned_beads(campaign: Campaign, scene) -> int:
    """The point's chain length as it will run (chain.beads = "auto" planned)."""
    if isinstance(scene.chain.beads, int):
        return scene.chain.beads
    from granchain.workflows.run import plan_for

    return plan_for(scene, campaign.backend, campaign.method, campaign.rtol)[0].chain.beads


def point_method(c: Campaign, scene) -> tuple[str, str | None]:
    """The integrator a point of this scene runs, and why where its scene chose it
    (workflows.run.method_choice)."""
    from granchain.workflows.run import method_choice

    return method_choice(c.backend, c.method, scene)


def preflight(campaign: Campaign, points: list[Point]) -> None:
    """Plan every point and check its time step against the stability limit before anything runs:
    one bad point is reported with its parameters and nothing starts."""
    from granchain.workflows.run import check_resources, check_timestep, plan_for

    said: list[str] = []  # what the ranks rule says of the points, once for the campaign
    for p in points:
        try:
            method, _ = point_method(campaign, p.scene)
            scene, _ = plan_for(p.scene, campaign.backend, method, campaign.rtol)
            check_timestep(scene, method)
            if isinstance(campaign.ranks, int) and campaign.ranks > 1:  # the cores are the job's, not ours
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    check_resources(scene, campaign.backend, campaign.ranks, oversubscribe=True)
                said += [f"point {p.index + 1}: {w.message}" for w in caught]
        except GranchainError as e:
            raise CampaignError(
                f"{campaign.source}: point {p.index + 1} ({params_text(p.params)}) cannot run: {e}"
            ) from None
    if said:
        more = f" (and {len(said) - 1} more points)" if len(said) > 1 else ""
        warnings.warn(f"{campaign.source}: ranks = {campaign.ranks}: {said[0]}{more}", UserWarning, stacklevel=2)


def run_grid(campaign: Campaign, runner: Runner, points: list[Point]) -> RunReport:
    """Run every point of a grid that is not complete yet."""
    from distributed import wait
    from distributed.client import FuturesCancelledError

    r = runner.report
    r.points = len(points)
    todo = []
    for p in points:
        job = runner.job(p)
        if runner.needs_run(job):
            todo.append((p, job))
    runner.say_plan(len(todo))
    if not todo:
        return r
    runner.prepare()
    prog = CampaignProgress(len(todo), "campaign", runner.stream, workers=runner.ex.nworkers)
    prog.jobs = runner.ex.jobs_text
    futures = {}
    try:
        for p, job in todo:
            futures[runner.submit(job, p)] = p
        r.ran = len(futures)
        prog.update(pending=len(futures))
        waiting = set(futures)
        while waiting:  # as_completed, with a look at the workers (and the batch jobs) every second
            try:
                done, waiting = wait(waiting, timeout=1.0, return_when="FIRST_COMPLETED")
            except TimeoutError:
                done = set()
            except FuturesCancelledError:  # no batch job left (Executor._keep_jobs): each one collected as lost
                done = {f for f in waiting if f.done()}
                waiting = waiting - done
            prog.workers = runner.ex.nworkers
            for fut in done:
                runner.collect(fut, futures[fut].params, prog)
            prog.update(pending=len(waiting))
    finally:
        prog.close()
    return r


__all__ = [
    "Campaign",
    "CampaignError",
    "CampaignProgress",
    "Executor",
    "PersistentLammps",
    "Point",
    "QuietInterrupt",
    "RunReport",
    "Runner",
    "finished_before",
    "one_line",
    "planned_beads",
    "point_ranks",
    "preflight",
    "run_grid",
    "run_point",
]
