"""The companion runs of an error estimate: each run, timed, its failure said in the report."""

from __future__ import annotations

import time
from contextlib import contextmanager

from granchain.exceptions import GranchainError
from granchain.progress import labelled
from granchain.richardson import CHECK_FACTOR
from granchain.workflows.errorbars.facts import companion_scene
from granchain.workflows.errorbars.report import ErrorReport


@contextmanager
def kept_lammps():
    """Within, single-rank LAMMPS runs share one kept LAMMPS child (granchain.lammps.server): of two
    LAMMPS companions the second does not pay LAMMPS's start-up again (process, import, plugin load),
    which alone costs more than a short run's integration. Companions of other backends start none."""
    from granchain.lammps import server

    with server.persistent():
        yield


def _richardson_runs(
    report: ErrorReport, scene, run_one, stable_timestep: float, factors: tuple[float, ...] = (2.0, 4.0)
) -> list | None:
    """The companions at 2 dt and (where stable, and in factors) 4 dt, their steps and wall times into
    the report; None when there is no estimate (report.why_none says why)."""
    dt = scene.run.timestep
    runs = []
    for factor in factors:
        if factor * dt > stable_timestep:
            if factor == 2.0:
                report.why_none = (
                    f"2 dt = {2 * dt:.3g} s is above the stability limit {stable_timestep:.3g} s: "
                    "no companion run, no estimate"
                )
                return None
            break
        t0 = time.perf_counter()
        try:
            with labelled(f"error-bar companion at {factor:g} dt"):
                runs.append(run_one(companion_scene(scene, factor)).solution)
            # (a run shared or made ahead by granchain compare returns at once: its own wall time)
            t0 = min(t0, time.perf_counter() - runs[-1].wall_time)
        except GranchainError as e:  # a coarser run broke an invariant: the run itself stands
            first_line = str(e).splitlines()[0] if str(e) else type(e).__name__
            if factor == 2.0:
                report.why_none = f"the 2 dt companion run failed ({first_line}): no estimate"
                return None
            report.why_none_4dt = f"the 4 dt companion run failed ({first_line}): order not checked"
            break
        report.wall_times.append(time.perf_counter() - t0)
        report.timesteps.append(factor * dt)
        report.steps.append(int(runs[-1].steps))
    return runs


def _check_run(report: ErrorReport, scene, run_one):
    """The run at dt / 2 that checks Richardson's bars (check_because), its step and wall time into the
    report (its price counts with the companions'); None if it failed (report.why_unchecked says so)."""
    t0 = time.perf_counter()
    try:
        with labelled(f"error-bar check at {CHECK_FACTOR:g} dt"):
            sol = run_one(companion_scene(scene, CHECK_FACTOR)).solution
        t0 = min(t0, time.perf_counter() - sol.wall_time)
    except GranchainError as e:
        first_line = str(e).splitlines()[0] if str(e) else type(e).__name__
        report.why_unchecked = f"the run at dt / 2 that checks the estimates failed ({first_line}): not checked"
        return None
    report.check_wall_time = time.perf_counter() - t0
    report.wall_times.append(report.check_wall_time)
    report.check_timestep = CHECK_FACTOR * scene.run.timestep
    report.check_steps = int(sol.steps)
    return sol


def rk4_runs(report: ErrorReport, scene, run_rk4, factors) -> list | None:
    """The RK4 runs a Verlet run is measured against, at the factors' steps (against_rk4_factors), their
    steps and wall times into the report; None when one failed (report.why_none says so)."""
    dt = scene.run.timestep
    runs = []
    for factor in factors:
        t0 = time.perf_counter()
        try:
            with labelled(f"error-bar companion (RK4) at {factor:.3g} dt"):
                companion = run_rk4(companion_scene(scene, factor))
        except GranchainError as e:
            first_line = str(e).splitlines()[0] if str(e) else type(e).__name__
            report.why_none = f"the RK4 companion run at {factor:g} dt failed ({first_line}): no estimate"
            return None
        runs.append(companion.solution)
        # the companion's own price: a run shared with another (granchain compare's
        # shared_reference_runs) or made ahead in a worker returns at once, but it cost its wall time
        report.wall_times.append(max(time.perf_counter() - t0, companion.solution.wall_time))
        report.timesteps.append(factor * dt)
        report.steps.append(int(companion.solution.steps))
    return runs
