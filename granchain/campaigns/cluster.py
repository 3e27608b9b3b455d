"""Campaign workers as batch jobs: SLURM (or PBS) through dask-jobqueue, the jobs watched and replaced.

``granchain campaign run FILE --cluster slurm`` (or a ``[cluster]`` table in the campaign file; a flag
wins) starts a Dask scheduler in the driver and asks the queue for ``jobs`` worker jobs of
``cores_per_job`` cores each; a job runs ``cores_per_job // ranks`` Dask worker processes of one
thread, each running one point at a time on ``ranks`` MPI ranks (:class:`ClusterSettings`). The
driver (:class:`JobCluster`):

* keeps the ids of every job it submitted, and cancels those (and only those) when it ends, on
  Ctrl-C too;
* polls the queue (``squeue`` for SLURM; for PBS the Dask workers that connected) to show jobs
  pending / running in the progress line;
* replaces a job that ended before the campaign did (cancelled, timed out, a node failure) with a
  new one, up to ``replacements`` times; then, with no job left, it stops with a message naming the
  jobs and their states (:class:`NoWorkerJobs`): the next ``campaign run`` runs only what is missing.

Everything in a ``[cluster]`` table is a name or a number checked against a strict pattern: a
campaign file is shared, and nothing in it reaches the job script but these values. What a job must
run before its worker starts (``source venv/bin/activate``, ``module load``) is a command-line or API
setting of the user who runs the campaign (``--prologue``), never a file's. The settings and their
checks are granchain.campaigns.cluster_settings'; this module re-exports them.
"""

from __future__ import annotations

import shutil
import subprocess
import time
import weakref
from dataclasses import dataclass
from pathlib import Path

from granchain.campaigns.cluster_settings import (
    SUBMIT,
    ClusterError,
    ClusterSettings,
    campaign_security,
    check,
    check_log_directory,
    describe,
    from_table,
    merge,
    private_cluster_class,
    private_directory,
    remove_directory,
)
from granchain.exceptions import GranchainError

#: job states that SLURM reports for a job that holds no running worker any more
ENDED = {
    "BOOT_FAIL",
    "CANCELLED",
    "COMPLETED",
    "DEADLINE",
    "FAILED",
    "NODE_FAIL",
    "OUT_OF_MEMORY",
    "PREEMPTED",
    "REVOKED",
    "SPECIAL_EXIT",
    "TIMEOUT",
}


class NoWorkerJobs(GranchainError, RuntimeError):
    """Every worker job ended and the replacement limit is reached: the campaign cannot go on."""


@dataclass
class JobState:
    """One submitted job as the driver last saw it.

    Attributes
    ----------
    job_id : str
        The queue's id of the job.
    name : str
        dask-jobqueue's name of it (its workers are named ``<name>-<i>``).
    state : str
        The queue's state (PENDING, RUNNING, one of ENDED), "ENDED" for a job the queue no longer
        knows, or RUNNING for one whose workers connected where the queue cannot be asked.
    seen_running : bool
        It has run (a worker of it connected, or the queue said RUNNING).
    ended_at : float or None
        When the driver saw it end (time.monotonic), or None.
    """

    job_id: str
    name: str
    state: str = "PENDING"
    seen_running: bool = False
    ended_at: float | None = None


@dataclass
class JobCounts:
    """The batch jobs as the driver last counted them, for the progress line."""

    pending: int = 0
    running: int = 0
    ended: int = 0
    replaced: int = 0

    why: str = ""  # why the pending jobs wait, as the queue says (Resources, Priority, ...)

    def text(self) -> str:
        """'jobs 1 pending (Priority), 2 running, 1 ended (1 replaced)'."""
        t = f"jobs {self.pending} pending" + (f" ({self.why})" if self.pending and self.why else "")
        t += f", {self.running} running"
        return t + (f", {self.ended} ended ({self.replaced} replaced)" if self.ended else "")


def _queue_states(kind: str, ids: list[str]) -> dict[str, str] | None:
    """{job id: state} for these ids as the queue reports them (an id it no longer knows is absent);
    None when the queue cannot be asked (then the Dask workers' connections are all there is)."""
    if kind != "slurm" or not ids or shutil.which("squeue") is None:
        return None
    try:
        r = subprocess.run(
            ["squeue", "-h", "-t", "all", "-o", "%i %T %r", "-j", ",".join(ids)],
            capture_output=True,
            text=True,
            timeout=30,
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    if r.returncode != 0 and "Invalid job id" not in r.stderr:
        return None
    out = {}
    for line in r.stdout.splitlines():
        parts = line.split()
        if len(parts) >= 2:
            out[parts[0]] = parts[1].rstrip("+")
            if len(parts) > 2 and parts[2] != "None":
                _REASONS[parts[0]] = parts[2]
    return out


#: the queue's reason a job waits, by job id (squeue %r), as last seen
_REASONS: dict[str, str] = {}
#: reasons a pending job never starts for: the campaign stops with the reason instead of waiting
HOPELESS = {
    "BadConstraints",
    "InvalidAccount",
    "InvalidQOS",
    "PartitionConfig",
    "PartitionNodeLimit",
    "PartitionTimeLimit",
    "QOSMaxWallDurationPerJobLimit",
    "QOSMaxCpuPerJobLimit",
    "QOSMaxMemoryPerJob",
}


class JobCluster:
    """A dask-jobqueue cluster of worker jobs for one campaign run (see the module docstring).

    Parameters
    ----------
    settings : ClusterSettings
        Checked settings (kind "slurm" or "pbs").
    ranks : int
        MPI ranks per point (each worker process gets this many cores of its job).
    log_directory : path
        Where the jobs' output goes (created).
    """

    #: seconds between two looks at the queue
    POLL = 2.0

    def __init__(self, settings: ClusterSettings, ranks: int = 1, log_directory=None):
        self.s, self.ranks = settings, ranks
        self.log_directory = Path(log_directory) if log_directory else None
        self.cluster = None
        self.jobs: dict[str, JobState] = {}  # job id -> state: every job this run submitted
        self.counts = JobCounts()
        self._last_poll = 0.0
        self._closed = False
        self.private: Path | None = None  # the key files' and job scripts' directory (private_directory)

    # ---------------------------------------------------------------------------- start and close
    def start(self):
        """Start the scheduler and submit the jobs; returns a distributed Client."""
        import dask
        from distributed import Client

        s = check(self.s, ranks=self.ranks)  # the values the job script takes, as used (an API caller's too)
        cmd = SUBMIT[s.kind]
        if shutil.which(cmd) is None:
            raise ClusterError(
                f"--cluster {s.kind}: {cmd} is not on PATH; run the campaign where jobs can be submitted "
                f"(a login node of the {s.kind.upper()} cluster)"
            )
        if self.log_directory is not None:
            from granchain.safe_files import check_not_link

            check_log_directory(self.log_directory)  # into #SBATCH -e/-o, unquoted
            check_not_link(self.log_directory)  # the jobs' output is written there: not through a planted link
            self.log_directory.mkdir(parents=True, exist_ok=True)
        # TLS (granchain.campaigns.cluster_settings): the scheduler binds the cluster's network, where
        # anyone reaching it would run code as the user; the jobs' key files and scripts go in a
        # directory of mode 0700 beside their output (on the filesystem the jobs share)
        self.private = private_directory(self.log_directory)
        # a job that ended is noticed by the driver's own poll (replace_ended); Dask's own timeout before
        # it closes a lost worker's job object stays, but the driver does not wait for it
        dask.config.set({"distributed.scheduler.allowed-failures": 3})
        cls = private_cluster_class(self._cluster_class(), self.private)
        kwargs = dict(
            self.job_options(),
            scheduler_options={"dashboard_address": None},
            security=campaign_security(),
            shared_temp_directory=str(self.private),  # the key files, mode 0600 (dask-jobqueue's)
        )
        try:
            self.cluster = cls(**kwargs)
        except (ValueError, OSError) as e:
            remove_directory(self.private)
            raise ClusterError(f"--cluster {s.kind}: cannot start the scheduler ({e})") from None
        # the key files go when this object does, if close() is never called (the API's callers)
        weakref.finalize(self, remove_directory, self.private, self.cluster)
        self._submit(s.jobs)
        return Client(self.cluster)

    def job_options(self) -> dict:
        """What each worker job's script is made of (dask-jobqueue's Job options: resources, the
        prologue, the worker's arguments, the output directory), from the checked settings."""
        s = self.s
        cores = s.cores(self.ranks)
        processes = s.workers_per_job(self.ranks)
        prologue = [
            *s.prologue,
            "export GRANCHAIN_QUIET=1",
            # a point's mpirun starts its ranks inside this job, on this node (not through srun / pbsdsh)
            "export HYDRA_BOOTSTRAP=fork",
        ]
        lifetime = s.lifetime_seconds()
        kwargs = dict(
            cores=processes,  # Dask threads: one per worker process; the job's cores are job_cpu below
            processes=processes,
            memory=s.memory_text(self.ranks),
            walltime=s.walltime,
            queue=s.queue,
            account=s.account,
            job_name="granchain-worker",
            interface=s.interface,
            job_script_prologue=prologue,
            worker_extra_args=["--lifetime", f"{lifetime}s", "--lifetime-stagger", f"{min(120, lifetime // 10)}s"],
            log_directory=str(self.log_directory) if self.log_directory else None,
            death_timeout=60,
        )
        if s.memory is None and s.kind == "slurm":
            # no --mem unless asked for: the partition's default applies (a node declared without
            # RealMemory has 1 MB to give, and a --mem of any size would keep the job pending forever);
            # the Dask worker's memory limit is still memory_text's
            kwargs["job_directives_skip"] = ["--mem"]
        if s.kind == "slurm":
            kwargs["job_cpu"] = cores
        else:
            mem = s.memory_text(self.ranks).replace(" ", "")
            kwargs["resource_spec"] = f"select=1:ncpus={cores}:mem={mem}"
        return kwargs

    def _cluster_class(self):
        import signal
        import threading

        # importing dask_jobqueue sets SIGINT to sys.exit() (its runner module, at import): Ctrl-C would
        # end the driver with status 0 and no word; the handler it replaced is put back
        main = threading.current_thread() is threading.main_thread()
        before = signal.getsignal(signal.SIGINT) if main else None
        try:
            import dask_jobqueue
        finally:
            if main and before is not None:
                signal.signal(signal.SIGINT, before)
        return dask_jobqueue.SLURMCluster if self.s.kind == "slurm" else dask_jobqueue.PBSCluster

    def job_script(self) -> str:
        """The script each worker job runs (dask-jobqueue's, with these settings)."""
        return self.cluster.job_script()

    def _submit(self, jobs: int) -> None:
        """Scale to `jobs` jobs now (the submissions done before returning: sbatch's refusal is a
        ClusterError here, not a log line later)."""
        self.cluster.scale(jobs=jobs)
        try:
            self.cluster.sync(self.cluster._correct_state)
        except Exception as e:  # noqa: BLE001 - dask-jobqueue raises RuntimeError with the command's stderr
            text = " ".join(str(e).split())
            self.close()
            raise ClusterError(
                f"--cluster {self.s.kind}: the queue refused the worker job ({text[-800:]}); check --queue, "
                "--account, --walltime, --memory and --cores-per-job against the site's limits"
            ) from None
        self._record()

    def _record(self) -> None:
        for name, job in list(self.cluster.workers.items()):
            jid = getattr(job, "job_id", None)
            if jid and jid not in self.jobs:
                self.jobs[jid] = JobState(jid, str(name))

    def close(self) -> None:
        """Close the cluster (dask-jobqueue cancels its jobs), then cancel every job this run submitted
        that the queue still holds: these ids only, never another job of the user's."""
        if self._closed:
            return
        self._closed = True
        if self.cluster is not None:
            try:
                self._record()
            except Exception:  # noqa: BLE001 - closing after Ctrl-C may find it half gone
                pass
            try:
                self.cluster.close(timeout=30)
            except Exception:  # noqa: BLE001
                pass
        self.cancel_all()
        remove_directory(self.private, self.cluster)  # the jobs are cancelled: their key files go

    def cancel_all(self) -> list[str]:
        """Cancel the jobs this run submitted that are still queued or running; returns their ids."""
        ids = list(self.jobs)
        if not ids:
            return []
        states = _queue_states(self.s.kind, ids)
        live = [j for j in ids if states is None or (j in states and states[j] not in ENDED)]
        if live:
            cancel = "scancel" if self.s.kind == "slurm" else "qdel"
            try:
                subprocess.run([cancel, *live], capture_output=True, timeout=60)
            except (OSError, subprocess.TimeoutExpired):
                pass
        return live

    # -------------------------------------------------------------------------------- the upkeep
    def poll(self, force: bool = False) -> JobCounts:
        """Look at the queue (at most every POLL seconds): the counts of pending and running jobs, and
        ended jobs replaced (up to the limit). Raises NoWorkerJobs when every job has ended and none
        may be replaced."""
        now = time.monotonic()
        if not force and now - self._last_poll < self.POLL:
            return self.counts
        self._last_poll = now
        self._record()
        live = self._live_names()
        states = _queue_states(self.s.kind, [j for j, st in self.jobs.items() if st.ended_at is None])
        for jid, st in self.jobs.items():
            if st.ended_at is not None:
                continue
            if states is not None:
                st.state = states.get(jid, "ENDED")
            elif st.name in live:
                st.state = "RUNNING"
            if st.state == "RUNNING" or st.name in live:
                st.seen_running = True
            gone = st.state in ENDED or st.state == "ENDED"
            if states is None and st.seen_running and st.name not in live:
                gone = True  # no queue to ask: its workers left
            if gone:
                st.ended_at = now
        self._replace_ended()
        c = self.counts
        waiting = [j for j, st in self.jobs.items() if st.ended_at is None and st.state == "PENDING"]
        reasons = sorted({_REASONS[j] for j in waiting if j in _REASONS})
        c.why = ", ".join(reasons)
        hopeless = [r for r in reasons if r in HOPELESS]
        if hopeless and not any(st.state == "RUNNING" for st in self.jobs.values() if st.ended_at is None):
            self.cancel_all()
            raise NoWorkerJobs(
                f"the worker jobs {', '.join(waiting)} wait for a reason they never start for ({', '.join(hopeless)}: "
                "see the site's limits with 'scontrol show partition'); fix --queue, --walltime, --cores-per-job, "
                "--memory or --account and run the same command again"
            )
        c.pending = sum(1 for st in self.jobs.values() if st.ended_at is None and st.state != "RUNNING")
        c.running = sum(1 for st in self.jobs.values() if st.ended_at is None and st.state == "RUNNING")
        c.ended = sum(1 for st in self.jobs.values() if st.ended_at is not None)
        if c.pending + c.running == 0:
            ended = ", ".join(f"{j} {st.state}" for j, st in self.jobs.items())
            raise NoWorkerJobs(
                f"every worker job ended ({ended}) and {c.replaced} were replaced, the limit (--replacements "
                f"{self.s.replacement_limit()}); the complete points are kept: run the same command again to run "
                "only the missing ones"
                + (f" (the jobs' output is in {self.log_directory})" if self.log_directory else "")
            )
        return c

    def _live_names(self) -> set[str]:
        """Job names with a Dask worker connected now (a job's workers are named <job name>-<i>)."""
        try:
            info = self.cluster.scheduler_info["workers"].values()
        except Exception:  # noqa: BLE001
            return set()
        names = set()
        for w in info:
            n = str(w.get("name", ""))
            names.add(n)
            names.add(n.rsplit("-", 1)[0])
        return names

    def _replace_ended(self) -> None:
        """Drop the ended jobs from the cluster and submit new ones in their place, within the limit."""
        ended = [st for st in self.jobs.values() if st.ended_at is not None and st.name in self.cluster.workers]
        if not ended:
            return
        names = [st.name for st in ended]

        async def drop():
            for n in names:
                job = self.cluster.workers.pop(n, None)
                self.cluster.worker_spec.pop(n, None)
                if job is not None:
                    try:
                        await job.close()  # cancelling an ended job of ours: harmless
                    except Exception:  # noqa: BLE001
                        pass

        self.cluster.sync(drop)
        room = self.s.replacement_limit() - self.counts.replaced
        want = min(len(names), max(0, room))
        if want:
            # a new job gets a name no job of this run had: distributed closes (cancels) the job under
            # a lost worker's name some seconds after the loss (lost-worker-timeout), and SpecCluster
            # would give the freed name to the replacement
            used = {st.name for st in self.jobs.values()}
            while self.cluster._new_worker_name(self.cluster._i) in used:
                self.cluster._i += 1
            self.counts.replaced += want
            alive = sum(1 for st in self.jobs.values() if st.ended_at is None)
            self.cluster.scale(jobs=min(self.s.jobs, alive + want))
            try:
                self.cluster.sync(self.cluster._correct_state)
            except Exception:  # noqa: BLE001 - a refused replacement: the jobs still alive go on
                pass
            self._record()


__all__ = [
    "SUBMIT",
    "ClusterError",
    "ClusterSettings",
    "JobCluster",
    "NoWorkerJobs",
    "check",
    "describe",
    "from_table",
    "merge",
]
