"""scene -> backend -> RunResult -> run directory."""

from __future__ import annotations

import os
import threading
import warnings
from concurrent.futures import FIRST_COMPLETED, Future, wait
from contextlib import contextmanager
from dataclasses import replace
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from granchain.errors import UsageError
from granchain.invariants import ENERGY_WATCH, MOMENTUM_WATCH, OVERLAP_WATCH, InvariantError
from granchain.peaks import lead_floor, stop_force_floor
from granchain.problem import ChainProblem
from granchain.reference.solver import solve_chain
from granchain.results import RunResult
from granchain.rundir import check_output_dir, write_run_dir
from granchain.schedule import history_stride
from granchain.workflows.guards import DUMP_FRAME_HEADER_BYTES as DUMP_FRAME_HEADER_BYTES
from granchain.workflows.guards import DUMP_LINE_BYTES as DUMP_LINE_BYTES
from granchain.workflows.guards import check_run, output_sizes

BACKENDS = ("reference", "lammps")


def run_reference(scene, method: str = "rk4") -> RunResult:
    """Run the pure-Python reference solver on a scene; a broken invariant stops it with the fix."""
    with _with_fix(scene, method), np.errstate(over="ignore", invalid="ignore"):  # the watch reports blow-ups
        sol = _solve_scene(scene, method)
    return RunResult(scene=scene, backend="reference", solution=sol)


@contextmanager
def _with_fix(scene, method: str):
    """Re-raise an InvariantError with the fix: the time step the planner would choose."""
    try:
        yield
    except InvariantError as e:
        from granchain.workflows.plan import plan_scene

        safe = plan_scene(scene, rtol=1e-3, method=method).scene.run.timestep
        raise InvariantError(
            e.invariant,
            e.time,
            e.step,
            e.contact,
            e.detail,
            f"the time step {scene.run.timestep:g} s is too large for this run: the planner would "
            f'choose {safe:.3g} s (set timestep = "auto" or use --rtol)'
            + (
                "; if the load itself drives overlaps this large, the contact law does not describe it: reduce the load"
                if e.invariant.startswith("overlap")
                else ""
            ),
        ) from None


def _solve_scene(scene, method: str):
    return solve_chain(
        ChainProblem.from_scene(scene),
        scene.run.end_time,
        scene.run.timestep,
        method,
        histories=tuple(i - 1 for i in scene.outputs.histories),
        history_stride=history_stride(scene),
        snapshots=scene.outputs.snapshots,
        stop_after=None if scene.run.stop_after_contact is None else scene.run.stop_after_contact - 1,
        stop_floor=stop_force_floor(scene),
        lead_floor=lead_floor(scene),
        # blow-up and garbage detectors (granchain.invariants), not accuracy targets
        max_overlap=OVERLAP_WATCH * float(min(scene.bead_radii)),
        energy_watch=ENERGY_WATCH,
        momentum_watch=MOMENTUM_WATCH,
    )


class UnstableTimestepError(UsageError):
    """The scene's time step is above the stability limit the planner predicts."""


class AccuracyWarning(UserWarning):
    """A fixed time step the planner's error model predicts will miss the run's tolerance."""


#: fewer beads per MPI rank than this and the ranks spend the step exchanging ghosts: a 1D chain
#: has two neighbours per bead, so each rank's work is its beads and its talk is two ghost beads
#: per step whatever the length; warned about before the run
MIN_BEADS_PER_RANK = 1000


class SmallChainRanksWarning(UserWarning):
    """More MPI ranks than a chain this short can use: the run is slower, its results the same."""


def integrator(backend: str, method: str | None) -> str:
    """The integrator a backend runs: reference rk4 (default) or verlet; LAMMPS velocity Verlet."""
    if backend not in BACKENDS:
        raise UsageError(f"backend = {backend!r} is not known; choose one of {', '.join(BACKENDS)}")
    if method not in (None, "rk4", "verlet"):
        raise UsageError(f"method = {method!r} is not known; choose rk4 or verlet")
    if backend == "lammps":
        if method not in (None, "verlet"):
            raise UsageError(f"method = {method!r}: the LAMMPS backend integrates with velocity Verlet only")
        return "verlet"
    return method or "rk4"


def available_cores() -> int:
    """Cores this process may run on (the affinity mask where the OS has one)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def check_resources(scene, backend: str, np_: int, oversubscribe: bool = False, out=None, given=None) -> None:
    """Refuse a run that cannot run as asked before anything runs: more steps than the step limit,
    more memory than this machine has available or more disk than is free at `out` (and LAMMPS's work
    directory), with the estimate and the fix (granchain.workflows.guards.check_run, for a planned
    scene; oversubscribe: the run's cores are not this machine's -- a cluster job, a campaign's
    workers -- so neither are its memory and disk, and only the steps are checked); an MPI request
    with ranks on the reference backend or more ranks than cores (unless oversubscribe). Warns below
    MIN_BEADS_PER_RANK beads per rank (slow, not wrong: a user testing MPI on a short chain may mean
    it) and about a long run. given: the scene before planning, if planned (whose step is the planner's)."""
    if not isinstance(np_, int) or np_ < 1:
        raise UsageError(f"--np = {np_!r}: the number of MPI ranks must be a whole number >= 1")
    if not scene.needs_plan:
        planned_step = given is not None and given.run.timestep is None
        check_run(scene, backend, out=out, machine=not oversubscribe, stacklevel=3, planned_step=planned_step)
    if np_ == 1:
        return
    if backend != "lammps":
        raise UsageError(
            f"--np = {np_}: the {backend} backend runs in one process; MPI ranks are for --backend lammps (drop --np)"
        )
    cores = available_cores()
    if np_ > cores and not oversubscribe:
        raise UsageError(
            f"--np = {np_}: this machine has {cores} cores; more ranks than cores share them and run slower "
            f"than --np {cores} (use --np {cores}, or --oversubscribe if you mean it)"
        )
    beads = scene.chain.beads
    if beads is not None and beads < MIN_BEADS_PER_RANK * np_:
        best = max(1, beads // MIN_BEADS_PER_RANK)
        warnings.warn(
            f"--np = {np_}: {beads} beads over {np_} ranks is {beads // np_} beads per rank; below "
            f"{MIN_BEADS_PER_RANK} per rank the ranks spend their time exchanging ghosts, not computing, and "
            f"this run will be slower than --np {best} (the results are the same)",
            SmallChainRanksWarning,
            stacklevel=2,
        )


def timestep_warning(scene, method: str, rtol: float) -> str | None:
    """A sentence when the scene's fixed time step misses rtol by the planner's error model, naming
    the step that would meet it; None when it meets it."""
    from granchain.workflows.plan import damping_rate, plan_scene, predicted_error

    plan = plan_scene(scene, method=method, rtol=None)
    predicted = predicted_error(method, plan.omega_max, damping_rate(scene), scene.run.timestep)
    if predicted <= rtol * (1 + 1e-9):  # a step planned for this rtol meets it, up to rounding
        return None
    good = plan_scene(scene, rtol=rtol, method=method).scene.run.timestep
    return (
        f"{scene.source}: [run] timestep = {scene.run.timestep:g} s is too coarse for rtol {rtol:g} with {method}: "
        f"the planner's error model predicts a relative error of {predicted:.2g} in the peak forces; "
        f'timestep = {good:.3g} s would meet rtol (or set timestep = "auto")'
    )


class PlanRefinedWarning(UserWarning):
    """A planned run is run again at a finer step: its measured peaks fell far below its force scale
    (granchain.workflows.plan.refined_plan says why)."""


class Abandoned(Exception):
    """A run or a wait for a shared run given up: the shared_reference_runs() block is being left
    after another run failed (granchain compare's LAMMPS run in a thread, when the reference's failed)."""


class SharedRuns:
    """The reference runs made inside one shared_reference_runs() block, shared by threads.

    runs: (scene, method) -> the RunResult, or a Future of it: a prefetch in the worker process or a
    run being made by another thread (waited for; made again here if it failed, as serially).
    """

    def __init__(self):
        self.runs: dict = {}
        self.lock = threading.Lock()
        self._stop = Future()

    def abandon(self) -> None:
        """Give up: runs not yet started and waits for shared runs raise Abandoned from now on."""
        if not self._stop.done():
            self._stop.set_result(None)

    @property
    def abandoned(self) -> bool:
        return self._stop.done()

    def wait(self, future):
        """The future's result (None if it failed with an Exception); Abandoned if given up first."""
        done, _ = wait([future, self._stop], return_when=FIRST_COMPLETED)
        if future not in done:
            raise Abandoned("the shared run is no longer waited for")
        try:
            return future.result()
        except Exception:  # failed in the worker, the worker died, or another thread's run failed
            return None


#: the SharedRuns of the shared_reference_runs() block this process is in, else None
_shared_runs: SharedRuns | None = None


@contextmanager
def shared_reference_runs(prefetch=()):
    """Inside this block a reference run of a scene and integrator made once is not made again.

    granchain compare needs the same RK4 runs twice: the reference's error-bar companions at 2 dt and
    4 dt, and LAMMPS's (a bilinear or Thornton Verlet run is measured against RK4 at 2 dt and 4 dt,
    errors.against_rk4_because): the same companion scene, integrator and step, so the same numbers.
    Each caller gets its own RunResult (a shallow copy) around the shared solution. Yields the
    SharedRuns: threads may run inside the block (compare runs LAMMPS in one); a thread still running
    must be joined before the block is left (SharedRuns.abandon() makes its waits give up).

    prefetch: (scene, method) pairs that will be asked for, started at once in one worker process
    where this process may run on two cores or more (the pure-Python solver is single-threaded:
    the companions run while this process runs the reference's own run and LAMMPS). A prefetched run
    that failed in the worker is made again here when asked for, so its error is raised as before.
    """
    global _shared_runs
    outer = _shared_runs
    _shared_runs = SharedRuns() if outer is None else outer
    pool = None
    try:
        todo = [k for k in dict.fromkeys(prefetch) if k not in _shared_runs.runs]
        if todo and available_cores() >= 2:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("fork"))
            for scene, method in todo:
                _shared_runs.runs[(scene, method)] = pool.submit(_prefetched_run, scene, method)
        yield _shared_runs
    finally:
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
        _shared_runs = outer


def _prefetched_run(scene, method: str):
    """A reference run in the prefetch worker: no progress lines, None if it failed (made again then)."""
    os.environ["GRANCHAIN_QUIET"] = "1"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return run_reference(scene, method)
    except Exception:
        return None


def _shared_run(scene, method: str):
    """The shared reference run of (scene, method): made here, or waited for if prefetched or being
    made by another thread. A prefetch not started yet is made here at once rather than after the
    worker's queue; one that failed (or whose worker died), and another thread's run that raised,
    are made again here, so that this caller gets the run's own error as it would serially."""
    shared, key = _shared_runs, (scene, method)
    while True:
        with shared.lock:
            got = shared.runs.get(key)
            if got is None or (isinstance(got, Future) and got.cancel()):
                mine = Future()  # made here: another thread asking meanwhile waits for it
                mine.set_running_or_notify_cancel()
                shared.runs[key] = mine
                break
        if isinstance(got, RunResult):
            return replace(got, extra=dict(got.extra))
        result = shared.wait(got)
        with shared.lock:
            if shared.runs.get(key) is got:
                if result is None:
                    del shared.runs[key]
                else:
                    shared.runs[key] = result
    try:
        if shared.abandoned:
            raise Abandoned("not started: the block is being left")
        result = run_reference(scene, method)
    except BaseException as e:
        with shared.lock:
            if shared.runs.get(key) is mine:
                del shared.runs[key]
        mine.set_exception(e)
        raise
    with shared.lock:
        shared.runs[key] = result
    mine.set_result(result)
    return replace(result, extra=dict(result.extra))


def _execute(scene, backend: str, method: str, np_: int):
    """(result, LAMMPS work directory or None): one run of a concrete scene."""
    if backend == "reference":
        if _shared_runs is None:
            return run_reference(scene, method), None
        return _shared_run(scene, method), None
    if _shared_runs is not None and _shared_runs.abandoned:
        raise Abandoned("not started: the block is being left")
    from granchain.lammps.runner import run_lammps

    with _with_fix(scene, "verlet"):
        return run_lammps(scene, np_=np_)


def _refined(given, plan, result):
    """The refined plan when a planned run's peaks missed rtol by the error model (else None)."""
    if plan is None:
        return None
    from granchain.workflows.plan import refined_plan

    return refined_plan(given, plan, result.solution)


def _estimate_errors(result, plan, backend: str, method: str, np_: int):
    """The run's companions at 2 dt and 4 dt and its ErrorReport (granchain.workflows.errors)."""
    from granchain.lammps.runner import cleanup
    from granchain.workflows.errors import estimate_errors
    from granchain.workflows.plan import plan_scene

    stable = (plan if plan is not None else plan_scene(result.scene, method=method)).stable_timestep

    def run_one(scene):
        companion, work = _execute(scene, backend, method, np_)
        if work is not None:
            cleanup(work)
        return companion

    def run_rk4(scene):  # the independent reference with event location (errors.against_rk4_because)
        return _execute(scene, "reference", "rk4", 1)[0]

    return estimate_errors(result, run_one, method, stable, run_rk4=run_rk4)


class OutputSizeWarning(UserWarning):
    """The requested dumps or history files will be larger than OUTPUT_WARN_BYTES."""


#: a dump or history file larger than this is announced before the run (with the interval that fits)
OUTPUT_WARN_BYTES = 1e9


def output_size_warning(scene) -> str | None:
    """A sentence naming each file that will exceed OUTPUT_WARN_BYTES and the interval that fits."""
    parts = []
    for name, size in output_sizes(scene).items():
        if size > OUTPUT_WARN_BYTES:
            key = "dump_interval" if name == "chain.dump" else "history_interval"
            now = getattr(scene.outputs, key) or scene.run.timestep
            fits = now * size / OUTPUT_WARN_BYTES
            parts.append(f"{name} about {size / 1e9:.3g} GB ([outputs] {key} >= {fits:.3g} s keeps it under 1 GB)")
    if not parts:
        return None
    return f"{scene.source}: this run will write " + "; ".join(parts)


def plan_for(scene, backend: str = "reference", method: str | None = None, rtol: float | None = None):
    """(scene, plan): the scene planned for the integrator this backend runs, or (scene, None) when
    nothing is "auto" and no rtol is given."""
    if not scene.needs_plan and rtol is None:
        return scene, None
    from granchain.workflows.plan import plan_scene

    plan = plan_scene(scene, rtol=rtol, method=integrator(backend, method))
    return plan.scene, plan


def check_timestep(scene, method: str) -> None:
    """Refuse a time step above the predicted stability limit (before anything runs)."""
    from granchain.workflows.plan import plan_scene

    plan = plan_scene(scene, method=method)
    if scene.run.timestep > plan.stable_timestep:
        safe = plan_scene(scene, rtol=1e-3, method=method).scene.run.timestep
        raise UnstableTimestepError(
            f"{scene.source}: [run] timestep = {scene.run.timestep:g} s is above the stability limit "
            f"{plan.stable_timestep:.3g} s that {method} has for the stiffest contact this run will see "
            f"(omega_max = {plan.omega_max:.3g} rad/s); use timestep <= {plan.stable_timestep:.3g} s (the planner "
            f'would choose {safe:.3g} s for rtol 1e-3, or set timestep = "auto"), or pass --force'
        )


def _finish(result, work, given, scene, plan, backend: str, method: str, np_: int, rtol, error_estimate, after_run):
    """(result, work directory): run_scene's run of the planned scene made again finer if its plan is
    refined (_refined), then after_run() (if given), then its error estimate if asked for; on any error
    its work directory is removed (the warnings name run_scene's caller, as run_scene's own do)."""
    try:
        refined = _refined(given, plan, result)
        if refined is not None:  # the measured peaks were far below the force scale: run again, finer
            from granchain.lammps.runner import cleanup

            if work is not None:
                cleanup(work)
            plan = refined
            scene = refined.scene
            warnings.warn(
                f"{scene.source}: running again at timestep = {scene.run.timestep:.4g} s: "
                + "refined "
                + next(c.reason for c in plan.choices if c.name == "timestep").split("; refined ", 1)[-1],
                PlanRefinedWarning,
                stacklevel=3,
            )
            msg = output_size_warning(scene)
            if msg:
                warnings.warn(msg, OutputSizeWarning, stacklevel=3)
            check_run(scene, backend, stacklevel=4, planned_step=True)  # finer: more steps, larger files
            result, work = _execute(scene, backend, method, np_)
        result.plan = plan
        if after_run is not None:
            after_run()
        if error_estimate:
            result.errors = _estimate_errors(result, plan, backend, method, np_)
            worst, target = result.errors.error_estimate, (plan.rtol if plan is not None else rtol or 1e-3)
            if worst is not None and worst > target:  # measured, not predicted: say so after the run
                warnings.warn(
                    f"{scene.source}: the measured error of the peak force at contact "
                    f"{result.errors.error_estimate_contact} is {worst:.2g}, above rtol {target:g} (peaks.csv "
                    f"peak_force_error; a smaller [run] timestep or --rtol brings it down)",
                    AccuracyWarning,
                    stacklevel=3,
                )
    except BaseException:  # an error estimate failed or was interrupted: no work directory left behind
        if work is not None:
            from granchain.lammps.runner import cleanup

            cleanup(work)
        raise
    return result, work


def run_scene(
    scene,
    backend: str = "reference",
    method: str | None = None,
    out: str | Path | None = None,
    overwrite: bool = False,
    np_: int = 1,
    keep_files: bool = False,
    force: bool = False,
    rtol: float | None = None,
    oversubscribe: bool = False,
    error_estimate: bool = False,
    before_run=None,
    after_run=None,
) -> RunResult:
    """Run a scene on a backend; if out is given, write the run directory (checked before the run).

    reference: method rk4 (default) or verlet. lammps: velocity Verlet with granchain's pair
    styles, np_ MPI ranks; the run directory also gets the deck, data file, log and dumps.
    A scene with "auto" values, or any scene when rtol is given, is planned first for the
    integrator this backend runs (result.plan). A fixed time step that the planner's error model
    says misses rtol (default 1e-3) gives an AccuracyWarning before the run.
    keep_files (lammps): keep LAMMPS's work directory and list its files in result.extra["_files"]
    and ["_work"], for a caller that writes the run directory itself and then removes "_work".
    error_estimate: also run the scene at 2 dt and 4 dt and estimate every number's error
    (granchain.workflows.errors; result.errors, peaks.csv's *_error columns, summary.json).
    before_run: called once after the scene's checks and warnings, before its first run; after_run:
    called once the run is made (and made again finer if refined), before its error estimate
    (granchain compare starts LAMMPS alongside the reference at one of them); what they raise stops
    the run.
    """
    started = datetime.now(UTC)
    method = integrator(backend, method)
    given = scene
    scene, plan = plan_for(scene, backend, method, rtol)
    check_resources(scene, backend, np_, oversubscribe, out=out, given=given)
    if out is not None:
        check_output_dir(out, overwrite)
    if not force:
        check_timestep(scene, method)
    if plan is None or not any(c.name == "timestep" for c in plan.choices):  # a fixed step: does it do?
        msg = timestep_warning(scene, method, 1e-3 if rtol is None else rtol)
        if msg:
            warnings.warn(msg, AccuracyWarning, stacklevel=2)
    msg = output_size_warning(scene)
    if msg:
        warnings.warn(msg, OutputSizeWarning, stacklevel=2)
    if before_run is not None:
        before_run()
    result, work = _execute(scene, backend, method, np_)
    result, work = _finish(result, work, given, scene, plan, backend, method, np_, rtol, error_estimate, after_run)
    result.started_utc = started
    if backend == "reference":
        if out is not None:
            write_run_dir(result, out, overwrite=overwrite)
        return result
    from granchain.lammps.runner import cleanup, output_files

    if keep_files:  # the caller writes the run directory later and removes the work directory
        result.extra["_files"] = output_files(work)
        result.extra["_work"] = work
        return result
    try:
        if out is not None:
            write_run_dir(result, out, overwrite=overwrite, extra_files=output_files(work))
    finally:
        cleanup(work)
    return result
