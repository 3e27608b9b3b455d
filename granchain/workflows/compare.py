"""granchain compare: the same scene on LAMMPS and on the reference solver, one table."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from granchain.postprocess.compare import compare_runs, write_compare
from granchain.results import check_output_dir, write_run_dir
from granchain.workflows.errors import rk4_companions
from granchain.workflows.run import check_resources, plan_for, run_scene, shared_reference_runs


def compare_scene(
    scene,
    rtol: float = 1e-3,
    out: str | Path | None = None,
    overwrite: bool = False,
    method: str = "rk4",
    np_: int = 1,
    reference_scene=None,
    error_estimate: bool = False,
):
    """Run LAMMPS and the reference on a scene; returns (rows, lammps result, reference result).

    A scene with "auto" values is planned separately for each backend's integrator (LAMMPS: velocity
    Verlet; the reference: method), the time step for rtol / 2 each; lam.scene and ref.scene are
    the scenes each one ran.

    error_estimate: give each run its measured error bars (companions at 2 dt and 4 dt); a
    difference then fails only beyond rtol plus both runs' errors, and the table shows them.
    reference_scene: give the reference a different scene (only to show that a physics mismatch is
    caught; `granchain compare` never does this). out: a directory with lammps/, reference/,
    compare.csv and compare.md, written atomically.
    """
    if out is not None:
        check_output_dir(out, overwrite)
    # each backend runs the step planned for its own integrator; with timestep = "auto" each is
    # planned for half the compare tolerance, so that two runs each within it differ by less than it
    plan_rtol = rtol / 2 if scene.run.timestep is None else None
    # (run_scene plans each one, and runs it again finer if its measured peaks fell far below the
    # force scale: granchain.workflows.plan.refined_plan)
    lam_scene, _ = plan_for(scene, "lammps", None, plan_rtol)
    # (a bad scene fails before any run)
    ref_scene, _ = plan_for(reference_scene or scene, "reference", method, plan_rtol)
    check_resources(lam_scene, "lammps", np_)
    # the reference runs first (below): LAMMPS's plugin is built or found now, so that a missing
    # compiler or a failed build is said before any run, not after the reference's
    from granchain.lammps.build import build_plugin

    build_plugin()
    # the RK4 error-bar companions at 2 dt and 4 dt: LAMMPS's are the reference's own when both run
    # the same step (a bilinear or Thornton scene with a fixed step), each made once; and they are
    # started at once in a worker process on a second core (shared_reference_runs), while this one
    # runs the reference (first: it asks for them last) and LAMMPS
    prefetch = []
    if error_estimate:
        for sc, m in ((ref_scene, method), (lam_scene, "verlet")):
            prefetch += [(c, "rk4") for c in rk4_companions(sc, m)]
    with shared_reference_runs(prefetch):
        ref = run_scene(
            reference_scene or scene, backend="reference", method=method, rtol=plan_rtol, error_estimate=error_estimate
        )
        lam = run_scene(
            scene, backend="lammps", np_=np_, keep_files=True, rtol=plan_rtol, error_estimate=error_estimate
        )
    files, work = lam.extra.pop("_files"), lam.extra.pop("_work")
    try:
        rows = compare_runs(lam, ref, rtol)
        if out is not None:
            out = Path(out)
            tmp = out.resolve().parent / f".{out.name}.partial-{os.getpid()}"
            shutil.rmtree(tmp, ignore_errors=True)
            try:
                tmp.mkdir(parents=True)
                write_run_dir(lam, tmp / "lammps", extra_files=files)
                write_run_dir(ref, tmp / "reference")
                write_compare(rows, tmp)
                if out.exists():
                    shutil.rmtree(out)
                os.replace(tmp, out)
            finally:
                shutil.rmtree(tmp, ignore_errors=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return rows, lam, ref
