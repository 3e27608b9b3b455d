"""The Dask side of a campaign run: a client on a local cluster of worker processes, an existing
scheduler, or worker jobs on a batch queue (granchain.campaigns.cluster), and the worker plugins that
keep a LAMMPS child per worker and leave Ctrl-C to the driver."""

from __future__ import annotations

import logging
import threading
import uuid
import weakref
from pathlib import Path

from distributed.diagnostics.plugin import WorkerPlugin
from typing_extensions import override

from granchain.campaigns.cluster import ClusterSettings, JobCluster, NoWorkerJobs
from granchain.campaigns.cluster_settings import campaign_security, check_log_directory
from granchain.campaigns.model import CampaignError
from granchain.campaigns.point_task import run_point


def _ignore_sigint(signum, frame) -> None:
    """A worker's SIGINT handler: Ctrl-C belongs to the driver, which stops the cluster."""


def _loop_blocking_sigint():
    """A running Dask IO loop (distributed's LoopRunner, started) whose thread blocks SIGINT.

    Ctrl-C on a terminal reaches every process of the foreground group, local Dask workers included;
    one that gets it while it starts (importing granchain, before :class:`QuietInterrupt` is set up)
    prints a KeyboardInterrupt traceback, and its nanny 'failed to start'. A LocalCluster on this
    loop starts its worker processes from threads of this one, which inherit its signal mask, and
    a process started keeps the mask across exec: a worker starts with SIGINT blocked (pending, never
    raised) until QuietInterrupt ignores it and unblocks it. The driver's main thread is unblocked
    again at once (the loop's thread is made while it is blocked): Ctrl-C stays the driver's.
    """
    import signal

    from distributed.utils import LoopRunner

    runner = LoopRunner()
    if not hasattr(signal, "pthread_sigmask"):
        runner.start()
        return runner
    # multiprocessing's resource tracker, started on a worker's first queue, unblocks SIGINT in the
    # thread that starts it (after starting itself with it blocked): started here first, it is not
    # started again from the loop's thread
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        runner.start()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)
    return runner


class QuietInterrupt(WorkerPlugin):
    """Dask worker plugin: Ctrl-C on a terminal reaches every process of the foreground group; a local
    worker ignores it (no traceback; the driver stops the cluster) through a Python handler, which
    exec resets, so the LAMMPS run a worker has started as a child process still stops at once.

    A local worker starts with SIGINT blocked (:func:`_loop_blocking_sigint`); it is unblocked here,
    once ignored, so that the threads and LAMMPS children the worker starts from now on get it."""

    name = "granchain-quiet-interrupt"

    @override
    def setup(self, worker) -> None:
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, _ignore_sigint)
            if hasattr(signal, "pthread_sigmask"):
                signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})

    @override
    def teardown(self, worker) -> None:
        pass


class PersistentLammps(WorkerPlugin):
    """Dask worker plugin: the worker's single-rank LAMMPS runs reuse a LAMMPS child process kept
    alive between points (granchain.lammps.server), which ends with the worker."""

    name = "granchain-persistent-lammps"

    @override
    def setup(self, worker) -> None:
        from granchain.lammps import server

        server.enable()

    @override
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
    #: per LAMMPS point (benchmarks/bench_campaigns.py compares the two)
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
        if self.batch is not None and log_directory is not None:
            check_log_directory(log_directory)  # before the workspace is made, before any job
        self.ranks = ranks
        self.log_directory = log_directory
        self.client = None
        self.cluster = None
        self._loop = None  # the local cluster's IO loop (_loop_blocking_sigint), stopped by close()
        self.jobs: JobCluster | None = None
        self.failure: BaseException | None = None  # what ended the batch jobs' upkeep (NoWorkerJobs)
        self._upkeep = None
        self._stop = threading.Event()
        self.futures: weakref.WeakSet = weakref.WeakSet()

    @property
    def nworkers(self) -> int:
        """Points that can run at once: the client's worker threads once it runs; before, the batch
        jobs' workers, or the local workers it will start (--workers, else cores // ranks)."""
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
        """The batch jobs' counts for the progress line (JobCounts.text), or None without batch jobs."""
        return None if self.jobs is None else self.jobs.counts.text()

    def start(self):
        """The Dask client, made on first use: the batch jobs (with their upkeep thread), a client of
        the scheduler, or a LocalCluster of one-thread worker processes; with the worker plugins
        (PersistentLammps if reuse_lammps, on a batch queue for single-rank points only;
        QuietInterrupt on local workers).

        Raises
        ------
        CampaignError
            The scheduler cannot be reached, or its workers run another granchain.
        ClusterError
            The queue cannot take the jobs.
        """
        if self.client is not None:
            return self.client
        if self.batch is not None:
            return self._start_batch()
        if self.scheduler is not None:
            return self._connect_scheduler()
        return self._start_local()

    def _start_batch(self):
        """The batch jobs' client, their upkeep thread started (PersistentLammps for single-rank points)."""
        self.jobs = JobCluster(self.batch, self.ranks, self.log_directory)
        self.client = self.jobs.start()
        if self.reuse_lammps and self.ranks == 1:
            self.client.register_plugin(PersistentLammps())
        self._upkeep = threading.Thread(target=self._keep_jobs, name="granchain-jobs", daemon=True)
        self._upkeep.start()
        return self.client

    def _connect_scheduler(self):
        """A client of the scheduler at --scheduler, its workers checked to load this granchain's plugin."""
        from distributed import Client

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

    def _start_local(self):
        """A LocalCluster of one-thread worker processes over TLS, made in a thread of its own (below)."""
        from distributed import Client, LocalCluster

        self._loop = _loop_blocking_sigint()
        made: dict = {}
        # TLS with this run's own certificate: a plain tcp:// scheduler on a shared machine runs the code
        # of any local user who connects (granchain.campaigns.cluster_settings)
        security = campaign_security()

        def make() -> None:
            try:
                made["cluster"] = LocalCluster(
                    loop=self._loop.loop,
                    n_workers=self.workers or max(1, _cores() // self.ranks),
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                    # no dashboard; the scheduler's HTTP routes on a free port (the default 8787 may be taken)
                    scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                    silence_logs=logging.ERROR,
                    security=security,
                    protocol="tls://",
                )
                made["client"] = Client(made["cluster"])
                made["client"].register_plugin(QuietInterrupt())
                if self.reuse_lammps:
                    made["client"].register_plugin(PersistentLammps())
            except BaseException as e:  # noqa: BLE001 - raised again in the driver's thread
                made["error"] = e

        # made in a thread of its own: Ctrl-C meanwhile (in the driver's thread) lets the start-up end,
        # then the cluster and client made are this executor's to close; interrupted half-way, a
        # LocalCluster is not closed by anyone but distributed's exit handler, which fails loudly
        maker = threading.Thread(target=make, name="granchain-local-cluster", daemon=True)
        maker.start()
        try:
            while maker.is_alive():
                maker.join(0.2)
        finally:
            maker.join()
            self.cluster, self.client = made.get("cluster"), made.get("client")
        if "error" in made:
            raise made["error"]
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
        """Submit one point's task (run_point of the payload, named by its job directory); returns the future."""
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
        """Stop the batch jobs' upkeep, close the client and any cluster this executor started, and
        cancel the batch jobs this run submitted (only those)."""
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
        if self._loop is not None:
            loop, self._loop = self._loop, None
            try:
                loop.stop()
            except Exception:  # noqa: BLE001 - closing after Ctrl-C may find it half gone
                pass
        if self.jobs is not None:
            self.jobs.close()  # cancels every job this run submitted, and only those


def _cores() -> int:
    from granchain.workflows.run import available_cores

    return available_cores()
