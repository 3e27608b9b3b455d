"""scene -> backend -> RunResult -> run directory."""

from __future__ import annotations

import os
import sys
import warnings
from contextlib import contextmanager, nullcontext
from datetime import UTC, datetime
from pathlib import Path

from granchain.backends import BACKENDS, METHODS, REFERENCE, Backend, Calculation, backend_named
from granchain.exceptions import UsageError
from granchain.invariants import InvariantError
from granchain.peaks import mark_reflection_pending
from granchain.results import RunResult
from granchain.rundir import check_output_dir, write_run_dir
from granchain.workflows import shared_runs
from granchain.workflows.guards import DUMP_FRAME_HEADER_BYTES as DUMP_FRAME_HEADER_BYTES
from granchain.workflows.guards import DUMP_LINE_BYTES as DUMP_LINE_BYTES
from granchain.workflows.guards import check_run, written_sizes
from granchain.workflows.guards import output_sizes as output_sizes
from granchain.workflows.shared_runs import Abandoned


def run_reference(scene, method: str = "rk4") -> RunResult:
    """Run the pure-Python reference solver on a scene; a broken invariant stops it with the fix."""
    with _with_fix(scene, method):
        return REFERENCE.calculate(scene, method).result


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


def method_choice(backend: str | Backend, method: str | None, scene) -> tuple[str, str | None]:
    """The integrator a run of this scene with ``method`` uses on this backend, and why where the
    scene chose it: every entry point (run, the API, compare, campaigns, the planner's notes) asks
    here.

    Parameters
    ----------
    backend : str or Backend
        The backend, or its name.
    method : str or None
        The integrator asked for (kept), or None: the backend's default for this scene
        (Backend.default_method: the reference's RK4, or Verlet on a scene with velocity-dependent damping).
    scene : granchain.scene.Scene
        The scene to run.

    Returns
    -------
    (str, str or None)
        The integrator, and the reason the scene chose it (None where it was asked for or is the
        backend's plain default).

    Raises
    ------
    UsageError
        ``method`` is not known, or not one this backend runs.
    """
    backend = backend_named(backend)
    if method not in (None, *METHODS):
        raise UsageError(f"method = {method!r} is not known; choose {' or '.join(METHODS)}")
    if method is None:
        return backend.default_method(scene)
    return backend.integrator(method, scene), None


def integrator(backend: str | Backend, method: str | None, scene) -> str:
    """The integrator a run of this scene uses on a backend (method_choice without its reason):
    reference rk4 (default; verlet on a scene with velocity-dependent damping) or verlet; LAMMPS velocity Verlet."""
    return method_choice(backend, method, scene)[0]


def ranks_refused(np_, backend: Backend) -> str:
    """The refusal of MPI ranks on a backend that runs in one process."""
    mpi = " or ".join(f"--backend {b.name}" for b in BACKENDS.values() if b.mpi)
    return f"--np = {np_}: the {backend.name} backend runs in one process; MPI ranks are for {mpi} (drop --np)"


def available_cores() -> int:
    """Cores this process may run on (the affinity mask where the OS has one)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def check_resources(scene, backend: str | Backend, np_: int, oversubscribe: bool = False, out=None, given=None) -> None:
    """Refuse a run that cannot run as asked before anything runs: more steps than the step limit,
    more memory than this machine has available or more disk than is free at `out` (and LAMMPS's work
    directory), with the estimate and the fix (granchain.workflows.guards.check_run, for a planned
    scene; oversubscribe: the run's cores are not this machine's -- a cluster job, a campaign's
    workers -- so neither are its memory and disk, and only the steps are checked); an MPI request
    with ranks on the reference backend or more ranks than cores (unless oversubscribe). Warns below
    MIN_BEADS_PER_RANK beads per rank (slow, not wrong: a user testing MPI on a short chain may mean
    it) and about a long run. given: the scene before planning, if planned (whose step is the planner's)."""
    backend = backend_named(backend)
    if not isinstance(np_, int) or np_ < 1:
        raise UsageError(f"--np = {np_!r}: the number of MPI ranks must be a whole number >= 1")
    if not scene.needs_plan:
        planned_step = given is not None and given.run.timestep is None
        check_run(scene, backend, out=out, machine=not oversubscribe, stacklevel=3, planned_step=planned_step)
    if np_ == 1:
        return
    if not backend.mpi:
        raise UsageError(ranks_refused(np_, backend))
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


class PlanExtendedWarning(UserWarning):
    """A planned run is run again, longer: it ended before measuring its window
    (granchain.workflows.plan.extended_plan says why)."""


@contextmanager
def shared_reference_runs(prefetch=()):
    """Inside this block a reference run of a scene and integrator made once is not made again.

    granchain compare needs the same RK4 runs twice: the reference's error-bar companions at 2 dt and
    4 dt, and LAMMPS's (a bilinear or Thornton Verlet run is measured against RK4 at 2 dt and 4 dt,
    errors.against_rk4_because): the same companion scene, integrator and step, so the same numbers.
    Each caller gets its own RunResult (a shallow copy) around the shared solution. Yields the
    SharedRuns (granchain.workflows.shared_runs): threads may run inside the block (compare runs
    LAMMPS in one); a thread still running must be joined before the block is left
    (SharedRuns.abandon() makes its waits give up).

    prefetch: (scene, method) pairs that will be asked for, started at once in one worker process
    where this process may run on two cores or more (the pure-Python solver is single-threaded:
    the companions run while this process runs the reference's own run and LAMMPS). A prefetched run
    that failed in the worker is made again here when asked for, so its error is raised as before.
    """
    with shared_runs.sharing(prefetch, _prefetched_run if available_cores() >= 2 else None) as shared:
        yield shared


def _prefetched_run(scene, method: str):
    """A reference run in the prefetch worker: no progress lines, None if it failed (made again then)."""
    os.environ["GRANCHAIN_QUIET"] = "1"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return run_reference(scene, method)
    except Exception:
        return None


def _execute(scene, backend: Backend, method: str, np_: int) -> Calculation:
    """One run of a concrete scene: its result, and its work files if the backend keeps any."""
    shared = shared_runs.current()
    if backend is REFERENCE:  # the yardstick's runs: made once inside a shared_reference_runs() block
        return _cut_off(
            Calculation(run_reference(scene, method) if shared is None else shared.get((scene, method), run_reference))
        )
    if shared is not None and shared.abandoned:
        raise Abandoned("not started: the block is being left")
    with _with_fix(scene, method):
        return _cut_off(backend.calculate(scene, method, np_))


def _cut_off(calc: Calculation) -> Calculation:
    """calc with the peaks a wall's reflection may still exceed not complete (peaks.reflection_pending),
    every backend's the same way: a peak the run's end cut off is not one."""
    mark_reflection_pending(calc.result.scene, calc.result.solution)
    return calc


def _extended(given, plan, result):
    """The extended plan when a run of the planner's end time ended before measuring its window (else
    None)."""
    if plan is None:
        return None
    from granchain.workflows.plan import extended_plan

    return extended_plan(given, plan, result.solution)


def _refined(given, plan, result):
    """The refined plan when a planned run's peaks missed rtol by the error model (else None)."""
    if plan is None:
        return None
    from granchain.workflows.plan import refined_plan

    return refined_plan(given, plan, result.solution)


def _estimate_errors(result, plan, backend: Backend, method: str, np_: int, checked: bool = False):
    """The run's companions at 2 dt and 4 dt (and with ``checked`` RK4's check at dt / 2) and its
    ErrorReport (granchain.workflows.error_estimates)."""
    from granchain.workflows.error_estimates import estimate_errors
    from granchain.workflows.plan import plan_scene

    stable = (plan if plan is not None else plan_scene(result.scene, method=method)).stable_timestep

    def run_one(scene):  # a companion on the run's own backend: its work files are not wanted
        companion = _execute(scene, backend, method, np_)
        companion.discard()
        return companion.result

    def run_rk4(scene):  # the independent reference with event location (errors.against_rk4_because)
        return _execute(scene, REFERENCE, "rk4", 1).result

    return estimate_errors(
        result,
        run_one,
        method,
        stable,
        run_rk4=run_rk4,
        checked=checked,
        absolute_positions=backend.absolute_positions,
        numpy_speed=backend.numpy_speed,
    )


class OutputSizeWarning(UserWarning):
    """The requested dumps or history files will be larger than OUTPUT_WARN_BYTES."""


#: a dump or history file larger than this is announced before the run (with the interval that fits)
OUTPUT_WARN_BYTES = 1e9


def output_size_warning(scene, backend: str | Backend = REFERENCE) -> str | None:
    """A sentence naming each file the backend writes (the run directory's tables, its work_files)
    that will exceed OUTPUT_WARN_BYTES, and the interval that fits: the reference writes no chain.dump."""
    parts = []
    for name, size in written_sizes(scene, backend).items():
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

    plan = plan_scene(scene, rtol=rtol, method=integrator(backend, method, scene))
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


def _run_again(calc, plan, backend, method: str, np_: int, choice: str, how: str, category) -> Calculation:
    """Discard calc and run plan's scene instead, announced by a `category` warning that gives the plan's
    reason for its new `choice` (its part after "; <how> "), and warned and checked as a first run is
    (more steps, larger files); the warnings name run_scene's caller."""
    calc.discard()
    scene = plan.scene
    value = getattr(scene.run, choice)
    reason = next(c.reason for c in plan.choices if c.name == choice).split(f"; {how} ", 1)[-1]
    warnings.warn(
        f"{scene.source}: running again with {choice} = {value:.4g} s: {how} {reason}", category, stacklevel=5
    )
    msg = output_size_warning(scene, backend)
    if msg:
        warnings.warn(msg, OutputSizeWarning, stacklevel=5)
    check_run(scene, backend, stacklevel=6, planned_step=True)
    return _execute(scene, backend, method, np_)


def _finish(calc, given, scene, plan, backend, method: str, np_: int, rtol, error_estimate, after_run) -> Calculation:
    """The Calculation of run_scene's run of the planned scene made again finer if its plan is
    refined (_refined), then after_run() (if given), then its error estimate if asked for; on any
    error its work directory is removed (the warnings name run_scene's caller, as run_scene's own do)."""
    try:
        refined = _refined(given, plan, calc.result)
        if refined is not None:  # the measured peaks were far below the force scale: run again, finer
            plan = refined
            calc = _run_again(calc, plan, backend, method, np_, "timestep", "refined", PlanRefinedWarning)
        extended = _extended(given, plan, calc.result)
        if extended is not None:  # the run ended before measuring its window: once more, longer
            plan = extended
            calc = _run_again(calc, plan, backend, method, np_, "end_time", "extended", PlanExtendedWarning)
        result = calc.result
        result.plan = plan
        if after_run is not None:
            after_run()
        if error_estimate:
            checked = error_estimate == "checked"
            result.errors = _estimate_errors(result, plan, backend, method, np_, checked)
            worst, target = result.errors.error_estimate, (plan.rtol if plan is not None else rtol or 1e-3)
            if worst is not None and worst > target:  # measured, not predicted: say so after the run
                what = "bound on the error (it may overstate it)" if result.errors.peak_bounds else "measured error"
                warnings.warn(
                    f"{scene.source}: the {what} of the peak force at contact "
                    f"{result.errors.error_estimate_contact} is {worst:.2g}, above rtol {target:g} (peaks.csv "
                    f"peak_force_error; a smaller [run] timestep or --rtol brings it down)",
                    AccuracyWarning,
                    stacklevel=4,
                )
    except BaseException:  # an error estimate failed or was interrupted: no work directory left behind
        calc.discard()
        raise
    return calc


def run_scene(
    scene,
    backend: str | Backend = "reference",
    method: str | None = None,
    out: str | Path | None = None,
    overwrite: bool = False,
    np_: int = 1,
    force: bool = False,
    rtol: float | None = None,
    oversubscribe: bool = False,
    error_estimate: bool | str = False,
    before_run=None,
    after_run=None,
    planned=None,
) -> RunResult:
    """Run a scene on a backend; if out is given, write the run directory (checked before the run).

    reference: method rk4 (default; verlet on a scene with velocity-dependent damping, method_choice) or verlet.
    lammps: velocity Verlet with granchain's pair styles, np_ MPI ranks; the run directory also gets
    the deck, data file, log and dumps (the backend's work files, removed once copied). The other
    arguments are calculate_scene's; planned: plan_for(scene, backend, method, rtol) made already
    (granchain.campaigns.ensemble plans every point before any runs, to group them), not made again.
    """
    calc = _calculate(
        scene,
        backend,
        method,
        out,
        overwrite,
        np_,
        force,
        rtol,
        oversubscribe,
        error_estimate,
        before_run,
        after_run,
        planned,
    )
    try:
        if out is not None:
            write_run_dir(calc.result, out, overwrite=overwrite, extra_files=calc.files or None)
    finally:
        calc.discard()
    return calc.result


def calculate_scene(
    scene,
    backend: str | Backend = "reference",
    method: str | None = None,
    out: str | Path | None = None,
    overwrite: bool = False,
    np_: int = 1,
    force: bool = False,
    rtol: float | None = None,
    oversubscribe: bool = False,
    error_estimate: bool | str = False,
    before_run=None,
    after_run=None,
) -> Calculation:
    """Check, plan and run a scene on a backend: its Calculation, whose work files (a LAMMPS run's
    deck, log and dumps) the caller copies into a run directory and then removes (Calculation.discard).

    A scene with "auto" values, or any scene when rtol is given, is planned first for the
    integrator this backend runs (result.plan). A fixed time step that the planner's error model
    says misses rtol (default 1e-3) gives an AccuracyWarning before the run. out: the run directory
    the caller will write, checked before the run (its disk too).
    error_estimate: also run the scene at 2 dt and 4 dt and estimate every number's error
    (granchain.workflows.error_estimates; result.errors, peaks.csv's *_error columns, summary.json);
    "checked": RK4's estimates also checked by a run at dt / 2 (error_estimates.check_because).
    before_run: called once after the scene's checks and warnings, before its first run; after_run:
    called once the run is made (and made again finer if refined), before its error estimate
    (granchain compare starts LAMMPS alongside the reference at one of them); what they raise stops
    the run.
    """
    return _calculate(
        scene, backend, method, out, overwrite, np_, force, rtol, oversubscribe, error_estimate, before_run, after_run
    )


def check_error_estimate(error_estimate) -> None:
    """Refuse an error_estimate that is not True, False or "checked" (before any run)."""
    if error_estimate not in (True, False, "checked"):
        raise UsageError(f'error_estimate = {error_estimate!r} is invalid: True, False or "checked"')


def _calculate(
    scene,
    backend,
    method,
    out,
    overwrite,
    np_,
    force,
    rtol,
    oversubscribe,
    error_estimate,
    before_run,
    after_run,
    planned=None,
):
    """calculate_scene's work (its warnings name the caller of run_scene or calculate_scene); planned:
    plan_for's (scene, plan) of this scene, backend, method and rtol, made already."""
    started = datetime.now(UTC)
    check_error_estimate(error_estimate)
    backend = backend_named(backend)
    method, why = method_choice(backend, method, scene)
    if why is not None:  # the scene chose the integrator: said once, and kept in summary.json
        from granchain.progress import is_quiet

        if not is_quiet():
            print(f"granchain: the {backend.name} backend runs {why}", file=sys.stderr, flush=True)
    given = scene
    scene, plan = plan_for(scene, backend, method, rtol) if planned is None else planned
    check_resources(scene, backend, np_, oversubscribe, out=out, given=given)
    if out is not None:
        check_output_dir(out, overwrite)
    if not force:
        check_timestep(scene, method)
    if plan is None or not any(c.name == "timestep" for c in plan.choices):  # a fixed step: does it do?
        msg = timestep_warning(scene, method, 1e-3 if rtol is None else rtol)
        if msg:
            warnings.warn(msg, AccuracyWarning, stacklevel=3)
    msg = output_size_warning(scene, backend)
    if msg:
        warnings.warn(msg, OutputSizeWarning, stacklevel=3)
    if before_run is not None:
        before_run()
    # with an error estimate the run and its companions share one kept LAMMPS child: the companions
    # do not pay LAMMPS's start-up (process, import, plugin load) again, which alone costs more than a
    # short run's integration (benchmarks/RESULTS.md, the price of error bars)
    from granchain.workflows.error_estimates import kept_lammps

    with kept_lammps() if error_estimate else nullcontext():
        calc = _execute(scene, backend, method, np_)
        calc = _finish(calc, given, scene, plan, backend, method, np_, rtol, error_estimate, after_run)
    calc.result.started_utc = started
    calc.result.method_reason = why
    return calc
