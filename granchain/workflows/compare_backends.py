"""granchain compare: the same scene on LAMMPS and on the reference solver, one table."""

from __future__ import annotations

import threading
from pathlib import Path

from granchain.backends import LAMMPS, REFERENCE
from granchain.postprocess.comparison_table import compare_runs, write_compare
from granchain.rundir import RunDirError, check_output_dir, owned_by_granchain, write_run_dir
from granchain.safe_files import UnsafeFileError, atomic_directory
from granchain.workflows import run as run_module
from granchain.workflows.error_estimates import rk4_companions
from granchain.workflows.run import (
    calculate_scene,
    check_resources,
    method_choice,
    plan_for,
    run_scene,
    shared_reference_runs,
)
from granchain.workflows.shared_runs import Abandoned


def reference_method(scene, method: str | None = None) -> tuple[str, str | None]:
    """The reference's integrator in a compare of this scene, and why where the scene chose it.

    method: the user's choice, kept; None: the reference's default for the scene
    (workflows.run.method_choice: RK4, but Verlet on a scene with velocity-dependent damping, whose peaks RK4 reads
    as a different quantity from LAMMPS's Verlet, comparison_table.peak_definition; the reference's
    Verlet is still the independent numpy solver, and defines a peak as LAMMPS does).

    Parameters
    ----------
    scene : granchain.scene.Scene
        The scene compared.
    method : str or None
        The reference's integrator the user asked for (None: not asked).

    Returns
    -------
    (str, str or None)
        The integrator, and the reason it was chosen for this scene (None where the user chose it or
        it is the default RK4).
    """
    return method_choice(REFERENCE, method, scene)


def compare_scene(
    scene,
    rtol: float = 1e-3,
    out: str | Path | None = None,
    overwrite: bool = False,
    method: str | None = None,
    np_: int = 1,
    reference_scene=None,
    error_estimate: bool | str = False,
):
    """Run LAMMPS and the reference on a scene; returns (rows, lammps result, reference result).

    A scene with "auto" values is planned separately for each backend's integrator (LAMMPS: velocity
    Verlet; the reference: method), the time step for rtol / 2 each; lam.scene and ref.scene are
    the scenes each one ran.

    method: the reference's integrator; None: RK4, or Verlet on a scene with velocity-dependent damping
    (reference_method: the same definition of a peak as LAMMPS's).

    error_estimate: give each run its measured error bars (companions at 2 dt and 4 dt; "checked": RK4's
    also checked by a run at dt / 2); a
    difference then fails only beyond rtol plus both runs' errors, and the table shows them.
    reference_scene: give the reference a different scene (only to show that a physics mismatch is
    caught; `granchain compare` never does this). out: a directory with lammps/, reference/,
    compare.csv and compare.md, written atomically.
    """
    run_module.check_error_estimate(error_estimate)
    method, why_method = reference_method(scene, method)
    if out is not None:
        check_output_dir(out, overwrite)
    # each backend runs the step planned for its own integrator; with timestep = "auto" each is
    # planned for half the compare tolerance, so that two runs each within it differ by less than it
    plan_rtol = rtol / 2 if scene.run.timestep is None else None
    # (run_scene plans each one, and runs it again finer if its measured peaks fell far below the
    # force scale: granchain.workflows.plan.refined_plan)
    lam_scene, _ = plan_for(scene, LAMMPS, None, plan_rtol)
    # (a bad scene fails before any run)
    ref_scene, _ = plan_for(reference_scene or scene, REFERENCE, method, plan_rtol)
    check_resources(lam_scene, LAMMPS, np_)
    # LAMMPS's plugin is built or found now, so that a missing compiler or a failed build is said
    # before any run (the reference's starts first, below)
    LAMMPS.prepare()
    prefetch = _shared_companions(ref_scene, method, lam_scene, error_estimate)
    ref_kw = dict(backend=REFERENCE, method=method, rtol=plan_rtol, error_estimate=error_estimate)
    lam_kw = dict(backend=LAMMPS, np_=np_, rtol=plan_rtol, error_estimate=error_estimate)
    with shared_reference_runs(prefetch) as shared:
        if np_ == 1 and run_module.available_cores() >= 2:
            # LAMMPS (a child process) runs alongside the reference, from a thread of this process,
            # once both runs' checks and warnings are done (the reference's first): at once if the
            # second core is free, else (a worker makes companions there) after the reference's own
            # run, while this process waits for them (on Table I they take longer than that run)
            ref, lam_calc = _alongside(
                shared, reference_scene or scene, ref_kw, scene, lam_kw, after_ref_run=bool(prefetch)
            )
        else:  # one core (or LAMMPS on several ranks): one after the other, the reference first
            ref = run_scene(reference_scene or scene, **ref_kw)
            lam_calc = calculate_scene(scene, **lam_kw)
    lam = lam_calc.result
    ref.method_reason = why_method  # (its run was given the method: the reason is the compare's)
    try:
        rows = compare_runs(lam, ref, rtol)
        if out is not None:
            _write_compare_dir(out, overwrite, rows, lam_calc, ref)
    finally:
        lam_calc.discard()
    return rows, lam, ref


def _shared_companions(ref_scene, method: str, lam_scene, error_estimate: bool | str) -> list:
    """The RK4 error-bar companions at 2 dt and 4 dt of both runs, (scene, "rk4") each: LAMMPS's are the
    reference's own when both run the same step (a bilinear or Thornton scene with a fixed step), each
    made once; they are started at once in a worker process on a second core (shared_reference_runs),
    while this one runs the reference and LAMMPS. None without error bars."""
    prefetch = []
    if error_estimate:
        for sc, m, backend in ((ref_scene, method, REFERENCE), (lam_scene, "verlet", LAMMPS)):
            prefetch += [(c, "rk4") for c in rk4_companions(sc, m, error_estimate == "checked", backend.numpy_speed)]
    return prefetch


def _write_compare_dir(out, overwrite: bool, rows, lam_calc, ref) -> None:
    """lammps/, reference/, compare.csv and compare.md into `out`: written aside and renamed into place
    with granchain's marker; an existing directory is replaced only when granchain wrote it
    (safe_files.atomic_directory)."""
    try:
        with atomic_directory(out, "compare", overwrite=overwrite, owned=owned_by_granchain) as tmp:
            write_run_dir(lam_calc.result, tmp / LAMMPS.name, extra_files=lam_calc.files)
            write_run_dir(ref, tmp / REFERENCE.name)
            write_compare(rows, tmp)
    except UnsafeFileError as e:
        raise RunDirError(str(e)) from None


def _alongside(shared, ref_scene, ref_kw: dict, lam_scene, lam_kw: dict, after_ref_run: bool):
    """(reference result, LAMMPS Calculation): LAMMPS's calculate_scene in a thread alongside the
    reference's run_scene here.

    The reference's checks and warnings come first, then LAMMPS's (the thread's calculate_scene waits for
    them before its run); an error in either stops both before any run. LAMMPS then starts at once
    or, after_ref_run, once the reference's own run is made (its error estimate then waits for the
    companions a worker process makes: this process and LAMMPS use the core it leaves idle). The
    errors raised are those of the runs one after the other: the reference's if it failed (LAMMPS's
    run is then given up and its work directory removed), else LAMMPS's.
    """
    checked, go = threading.Event(), threading.Event()
    box: dict = {}

    def lammps_checked() -> None:  # LAMMPS's calculate_scene, after its checks: wait for the reference's go
        checked.set()
        go.wait()
        if "stop" in box:
            raise Abandoned("the reference's run failed before LAMMPS's started")

    def lammps() -> None:
        try:
            box["result"] = calculate_scene(lam_scene, before_run=lammps_checked, **lam_kw)
        except BaseException as e:  # given to the main thread
            box["error"] = e
        finally:
            checked.set()

    thread = threading.Thread(target=lammps, name="granchain-compare-lammps", daemon=True)

    def start_lammps() -> None:  # the reference's run_scene, after its checks
        thread.start()
        checked.wait()
        if "error" in box:  # LAMMPS's checks failed: before any run
            thread.join()
            raise box["error"]
        if not after_ref_run:
            go.set()

    try:
        ref = run_scene(ref_scene, before_run=start_lammps, after_run=go.set, **ref_kw)
    except BaseException:
        box["stop"] = True
        shared.abandon()  # LAMMPS's waits for shared companions give up
        go.set()
        if thread.ident is not None:  # started (LAMMPS finishes a run it began: a child process)
            thread.join()
        got = box.get("result")
        if got is not None:
            got.discard()
        raise
    go.set()  # (the reference's run_scene calls after_run unless it raised)
    thread.join()
    if "error" in box:
        raise box["error"]
    return ref, box["result"]
