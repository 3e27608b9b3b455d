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
"""

from __future__ import annotations

import logging
import os
import socket
import sys
import threading
import time
import traceback
import uuid
import warnings
import weakref
from dataclasses import dataclass, field
from pathlib import Path

from distributed.diagnostics.plugin import WorkerPlugin
from tqdm import tqdm

from granchain import progress
from granchain.campaigns import workspace as wsp
from granchain.campaigns.cluster import ClusterSettings, JobCluster, NoWorkerJobs
from granchain.campaigns.spec import Campaign, CampaignError, Point, params_text
from granchain.errors import GranchainError

# ------------------------------------------------------------------------------------ the task


def run_point(payload: dict) -> dict:
    """Run one point in a worker: write its run directory into its job directory, or failure.json.

    payload: job_dir, scene (canonical dict), source, backend, method, rtol, error_estimate, code.
    Returns {"job", "status": "done" | "failed", "message", "wall_time", "run_time", "warnings", "host", "pid"}
    (also written to the job directory's task.json).
    """
    t0 = time.perf_counter()
    job = Path(payload["job_dir"])
    before = finished_before(job, payload)
    if before is not None:
        return before
    caught: list[str] = []
    status, message, detail, run_time = "done", None, None, None
    try:
        mine = wsp.code_version(payload["backend"])
        if mine != payload["code"]:
            raise CampaignError(
                f"this worker ({socket.gethostname()}) runs {wsp.code_text(mine)}, the campaign "
                f"{wsp.code_text(payload['code'])}: install the same granchain on every worker"
            )
        from granchain.scene import scene_from_dict
        from granchain.workflows.run import run_scene

        with progress.quiet(), warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            scene = scene_from_dict(payload["scene"], source=payload["source"])
            t_run = time.perf_counter()
            run_scene(
                scene,
                backend=payload["backend"],
                method=payload["method"],
                rtol=payload["rtol"],
                error_estimate=payload["error_estimate"],
                out=job / wsp.RUN_DIR,
                overwrite=True,
                np_=payload.get("ranks", 1),
            )
        run_time = time.perf_counter() - t_run
        caught = [str(x.message).splitlines()[0] for x in w]
        (job / wsp.FAILURE).unlink(missing_ok=True)
    except Exception as e:  # noqa: BLE001 - recorded with its message; the campaign goes on
        status, message = "failed", one_line(e)
        if not isinstance(e, GranchainError):  # a bug: keep where it happened
            detail = traceback.format_exc()
        try:
            wsp.write_json(
                job / wsp.FAILURE,
                {"message": message, "type": type(e).__name__, "traceback": detail, "host": socket.gethostname()},
            )
        except OSError:  # a full or read-only disk: the point stays failed, its record below says why
            pass
    wall = time.perf_counter() - t0
    record = {
        "job": job.name,
        "status": status,
        "message": message,
        "wall_time": wall,
        "run_time": run_time,  # run_scene alone (the run and its run directory); the rest is the machinery's
        "warnings": caught,
        "host": socket.gethostname(),
        "pid": os.getpid(),
        "ranks": payload.get("ranks", 1),
        "token": payload.get("token"),
    }
    try:
        wsp.write_json(job / wsp.TASK, record)
    except OSError:  # the record is a courtesy; the run directory is what counts
        pass
    return record


def finished_before(job: Path, payload: dict) -> dict | None:
    """The status of a point that is complete already, without running it again; None: run it.

    A task Dask runs a second time (its worker, or the worker's batch job, ended before the scheduler
    heard the result) finds its own run directory complete, with its own token in task.json: that
    run stands. A point another campaign completed meanwhile stands too, unless this run reruns
    everything (``rerun``)."""
    if wsp.job_state(job) != "done":
        return None
    rec = wsp.read_json(job / wsp.TASK)
    token = payload.get("token")
    mine = isinstance(rec, dict) and token is not None and rec.get("token") == token
    if not mine and payload.get("rerun"):
        return None
    out = {
        "job": job.name,
        "status": "done",
        "message": None,
        "wall_time": 0.0,
        "run_time": None,
        "warnings": [],
        "host": socket.gethostname(),
        "pid": os.getpid(),
        "repeated": True,
    }
    if mine:
        out.update({k: rec[k] for k in ("wall_time", "run_time", "warnings") if k in rec})
    return out


def one_line(e: BaseException) -> str:
    """An exception as one line: a GranchainError's message; anything else with its type."""
    text = " ".join(str(e).split()) or type(e).__name__
    return text if isinstance(e, GranchainError) else f"{type(e).__name__}: {text}"


# -------------------------------------------------------------------------------- the progress


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
        return min(self.pending, self.workers)

    def _postfix(self) -> str:
        text = f"done {self.done}, running {self.running}, failed {self.failed}"
        jobs = self.jobs() if self.jobs is not None else None
        return f"{text}; {jobs}" if jobs else text

    def update(self, done: int = 0, failed: int = 0, pending: int | None = None, total: int | None = None) -> None:
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
        if self.disabled:
            return
        if self._bar is not None:
            self._bar.set_postfix_str(self._postfix())
            self._bar.close()
            self._bar = None
        elif time.perf_counter() - self.t0 >= progress.DELAY:
            self._line(time.perf_counter())


# -------------------------------------------------------------------------------- the executor


def _ignore_sigint(signum, frame) -> None:
    """A worker's SIGINT handler: Ctrl-C belongs to the driver, which stops the cluster."""


class QuietInterrupt(WorkerPlugin):
    """Dask worker plugin: Ctrl-C on a terminal reaches every process of the foreground group; a local
    worker ignores it (no traceback; the driver stops the cluster) through a Python handler, which
    exec resets, so the LAMMPS run a worker has started as a child process still stops at once."""

    name = "granchain-quiet-interrupt"

    def setup(self, worker) -> None:
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, _ignore_sigint)

    def teardown(self, worker) -> None:
        pass


class PersistentLammps(WorkerPlugin):
    """Dask worker plugin: the worker's single-rank LAMMPS runs reuse a LAMMPS child process kept
    alive between points (granchain.lammps.server), which ends with the worker."""

    name = "granchain-persistent-lammps"

    def setup(self, worker) -> None:
        from granchain.lammps import server

        server.enable()

    def teardown(self, worker) -> None:
        from granchain.lammps import server

        server.shutdown()


class Executor:
    """A Dask client made on first use: a LocalCluster of `workers` processes (one thread each), the
    scheduler at `scheduler`, or worker jobs on a batch queue (`cluster`, granchain.campaigns.cluster).

    ranks: MPI ranks per point (a local worker or a job's worker gets that many cores).
    log_directory: where batch jobs write their output.
    """

    #: workers keep a LAMMPS child for their next points (PersistentLammps); False: a fresh process
    #: per LAMMPS point, as before (benchmarks/bench_campaigns.py compares the two)
    reuse_lammps = True

    def __init__(
        self,
        workers: int | None = None,
        scheduler: str | None = None,
        cluster: ClusterSettings | None = None,
        ranks: int = 1,
        log_directory=None,
    ):
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
            raise CampaignError(f"--workers = {workers!r}: give a whole number of worker processes >= 1")
        if workers is not None and scheduler is not None:
            raise CampaignError("--workers and --scheduler: the scheduler's cluster has its own workers; give one")
        if cluster is not None and cluster.batch and (workers is not None or scheduler is not None):
            raise CampaignError(
                f"--cluster {cluster.kind} with --workers or --scheduler: the jobs are the workers (--jobs, "
                "--cores-per-job); give one"
            )
        self.workers, self.scheduler = workers, scheduler
        self.batch = cluster if cluster is not None and cluster.batch else None
        self.ranks = ranks
        self.log_directory = log_directory
        self.client = None
        self.cluster = None
        self.jobs: JobCluster | None = None
        self.failure: BaseException | None = None  # what ended the batch jobs' upkeep (NoWorkerJobs)
        self._upkeep = None
        self._stop = threading.Event()
        self.futures: weakref.WeakSet = weakref.WeakSet()

    @property
    def nworkers(self) -> int:
        if self.client is not None:
            try:
                return max(1, sum(self.client.nthreads().values()))
            except Exception:  # noqa: BLE001 - only for the progress display
                return 1
        if self.batch is not None:
            return self.batch.jobs * self.batch.workers_per_job(self.ranks)
        return self.workers or max(1, _cores() // self.ranks)

    def slot_cores(self) -> int:
        """The cores one worker may give its point (for ranks = "auto")."""
        if self.batch is not None:
            return self.batch.cores(self.ranks) // self.batch.workers_per_job(self.ranks)
        return max(1, _cores() // (self.workers or max(1, _cores() // self.ranks)))

    def jobs_text(self) -> str | None:
        return None if self.jobs is None else self.jobs.counts.text()

    def start(self):
        if self.client is not None:
            return self.client
        from distributed import Client, LocalCluster

        if self.batch is not None:
            self.jobs = JobCluster(self.batch, self.ranks, self.log_directory)
            self.client = self.jobs.start()
            if self.reuse_lammps and self.ranks == 1:
                self.client.register_plugin(PersistentLammps())
            self._upkeep = threading.Thread(target=self._keep_jobs, name="granchain-jobs", daemon=True)
            self._upkeep.start()
            return self.client
        if self.scheduler is not None:
            try:
                self.client = Client(self.scheduler, timeout="20s")
            except (OSError, TimeoutError) as e:
                raise CampaignError(
                    f"--scheduler {self.scheduler}: cannot connect ({e}); is the scheduler running "
                    "(dask scheduler, or a dask-jobqueue cluster's scheduler_address)?"
                ) from None
            if self.reuse_lammps:
                try:
                    self.client.register_plugin(PersistentLammps())
                except Exception as e:  # distributed re-raises a worker's failure as a bare Exception
                    if "PersistentLammps" not in str(e) and "granchain" not in str(e):
                        raise
                    self.close()
                    raise CampaignError(
                        f"--scheduler {self.scheduler}: a worker cannot load this granchain's worker plugin "
                        f"({e}): it runs another granchain; install the same granchain on every worker"
                    ) from None
            return self.client
        self.cluster = LocalCluster(
            n_workers=self.workers or max(1, _cores() // self.ranks),
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            # no dashboard; the scheduler's HTTP routes on a free port (the default 8787 may be taken)
            scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
            silence_logs=logging.ERROR,
        )
        self.client = Client(self.cluster)
        self.client.register_plugin(QuietInterrupt())
        if self.reuse_lammps:
            self.client.register_plugin(PersistentLammps())
        return self.client

    def _keep_jobs(self) -> None:
        """The batch jobs' upkeep, in a thread: poll the queue, replace ended jobs; when none is left
        (NoWorkerJobs), cancel what is queued so that the driver's wait ends, and keep the reason."""
        while not self._stop.wait(JobCluster.POLL):
            try:
                self.jobs.poll(force=True)
            except NoWorkerJobs as e:
                self.failure = e
                try:
                    self.client.cancel([f for f in self.futures if not f.done()], force=True)
                except Exception:  # noqa: BLE001 - the client may be closing
                    pass
                return
            except Exception:  # noqa: BLE001 - a queue command failing once is retried at the next poll
                continue

    def submit(self, payload: dict):
        client = self.start()
        key = f"granchain-point-{Path(payload['job_dir']).name[:12]}-{uuid.uuid4().hex[:8]}"
        fut = client.submit(run_point, payload, key=key, pure=False)
        self.futures.add(fut)  # cancelled together when no batch job is left (_keep_jobs)
        return fut

    def check_failure(self) -> None:
        """Raise what stopped the batch jobs (NoWorkerJobs), if anything did."""
        if self.failure is not None:
            raise CampaignError(f"campaign stopped: {self.failure}")

    def close(self) -> None:
        self._stop.set()
        if self._upkeep is not None and self._upkeep is not threading.current_thread():
            self._upkeep.join(timeout=10)
        self._upkeep = None
        things = (self.client, self.cluster)
        self.client = self.cluster = None
        for thing in things:
            if thing is not None:
                try:
                    thing.close()
                except Exception:  # noqa: BLE001 - closing after Ctrl-C may find it half gone
                    pass
        if self.jobs is not None:
            self.jobs.close()  # cancels every job this run submitted, and only those


def _cores() -> int:
    from granchain.workflows.run import available_cores

    return available_cores()


# ------------------------------------------------------------------------------------ the run


@dataclass
class RunReport:
    """What one `campaign run` did (counts are points)."""

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
        self.method = _method(campaign)
        self.code = wsp.code_version(campaign.backend)
        self.project = wsp.create_workspace(ws)
        self._stale = wsp.stale_versions(self.project, self.code)
        self.report = RunReport()
        self.in_flight: dict = {}  # future key -> job directory
        self.token = uuid.uuid4().hex  # this campaign run's: a task Dask runs twice finds its own result

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

    def job(self, point: Point):
        sp = wsp.statepoint(
            point.scene_dict, self.c.backend, self.method, self.c.rtol, self.c.error_estimate, self.code
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
        return {
            "ranks": self.ranks(point),
            "token": self.token,
            "rerun": self.rerun,
            "job_dir": str(Path(job.path).resolve()),
            "scene": point.scene_dict,
            "source": f"campaign point ({params_text(point.params)})",
            "backend": self.c.backend,
            "method": self.method,
            "rtol": self.c.rtol,
            "error_estimate": self.c.error_estimate,
            "code": self.code,
        }

    def prepare(self) -> None:
        """Before any run: the LAMMPS plugin is built here once (not by each local worker at once)."""
        if self.c.backend == "lammps" and self.ex.scheduler is None:
            from granchain.lammps.build import build_plugin

            build_plugin()

    def collect(self, future, params: dict, prog: CampaignProgress) -> dict:
        """A finished future's status (a lost task counts as lost, not failed)."""
        self.in_flight.pop(future.key, None)
        try:
            r = future.result()
        except Exception as e:  # noqa: BLE001 - a worker died (KilledWorker) or the task was cancelled
            r = {"status": "lost", "message": one_line(e)}
        if r["status"] == "done":
            self.report.done += 1
            prog.update(done=1)
        elif r["status"] == "failed":
            self.report.failed += 1
            self.report.messages.append((params, r["message"]))
            prog.update(failed=1)
        else:
            self.report.lost += 1
            self.report.messages.append((params, r["message"]))
            prog.update(failed=1)
        return r

    def say(self, text: str) -> None:
        if not progress.is_quiet():
            print(f"granchain: {text}", file=self.stream, flush=True)

    def say_plan(self, todo: int) -> None:
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


def _method(c: Campaign) -> str:
    from granchain.workflows.run import integrator

    return integrator(c.backend, c.method)


def preflight(campaign: Campaign, points: list[Point]) -> None:
    """Plan every point and check its time step against the stability limit before anything runs:
    one bad point is reported with its parameters and nothing starts."""
    from granchain.workflows.run import check_resources, check_timestep, integrator, plan_for

    method = integrator(campaign.backend, campaign.method)
    said: list[str] = []  # what the ranks rule says of the points, once for the campaign
    for p in points:
        try:
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
