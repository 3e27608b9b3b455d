"""scene -> backend -> RunResult -> run directory."""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import numpy as np

from granchain.invariants import ENERGY_WATCH, MOMENTUM_WATCH, OVERLAP_WATCH, InvariantError
from granchain.reference.solver import ChainProblem, solve_chain
from granchain.results import RunResult, check_output_dir, write_run_dir
from granchain.templates import history_stride, stop_force_floor

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
        # blow-up and garbage detectors (granchain.invariants), not accuracy targets
        max_overlap=OVERLAP_WATCH * float(min(scene.bead_radii)),
        energy_watch=ENERGY_WATCH,
        momentum_watch=MOMENTUM_WATCH,
    )


class UnstableTimestepError(ValueError):
    """The scene's time step is above the stability limit the planner predicts."""


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


def run_scene(
    scene,
    backend: str = "reference",
    method: str | None = None,
    out: str | Path | None = None,
    overwrite: bool = False,
    np_: int = 1,
    keep_files: bool = False,
    force: bool = False,
) -> RunResult:
    """Run a scene on a backend; if out is given, write the run directory (checked before the run).

    reference: method rk4 (default) or verlet. lammps: velocity Verlet with granchain's pair
    styles, np_ MPI ranks; the run directory also gets the deck, data file, log and dumps.
    keep_files (lammps): keep LAMMPS's work directory and list its files in result.extra["_files"]
    and ["_work"], for a caller that writes the run directory itself and then removes "_work".
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend = {backend!r} is not known; choose one of {', '.join(BACKENDS)}")
    if out is not None:
        check_output_dir(out, overwrite)
    if not force:
        check_timestep(scene, "rk4" if backend == "reference" and method in (None, "rk4") else "verlet")
    if backend == "reference":
        result = run_reference(scene, method or "rk4")
        if out is not None:
            write_run_dir(result, out, overwrite=overwrite)
        return result
    if method not in (None, "verlet"):
        raise ValueError(f"method = {method!r}: the LAMMPS backend integrates with velocity Verlet only")
    from granchain.lammps.runner import cleanup, output_files, run_lammps

    with _with_fix(scene, "verlet"):
        result, work = run_lammps(scene, np_=np_)
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
