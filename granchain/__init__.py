"""granchain: stress waves in 1D chains of spheres, LAMMPS cross-checked against a reference solver.

The public API is small::

    import granchain

    scene = granchain.load_scene("default")            # a bundled name or a .toml path
    plan = granchain.plan(scene, rtol=1e-3, method="verlet")
    result = granchain.run(scene, backend="lammps")    # plans "auto" values for Verlet itself
    result.peak_table["peak_force"], result.summary()["observables"]

Every error a user can cause is a :class:`GranchainError`.

This package root is the public API's facade: it sits above every layer (it imports the workflows,
lazily) and no module of granchain imports it (pyproject.toml, [tool.importlinter]).
"""

from __future__ import annotations

from granchain._version import __version__
from granchain.errors import GranchainError

__all__ = ["GranchainError", "__version__", "campaign", "load_campaign", "load_scene", "plan", "run"]


def load_scene(path_or_name):
    """Read and validate a scene.

    Parameters
    ----------
    path_or_name : str or pathlib.Path
        A ``.toml`` scene file, or the name of a bundled scene (``granchain scenes`` lists them).

    Returns
    -------
    granchain.scene.Scene
        The validated scene; values given as ``"auto"`` are chosen by :func:`plan` or :func:`run`.

    Raises
    ------
    GranchainError
        (``SceneError``) the file is missing or invalid; the message names the key and the fix.
    """
    from granchain.scene import load_scene as _load

    return _load(path_or_name)


def plan(scene, rtol: float | None = None, method: str = "rk4"):
    """The planner's choices for a scene: every "auto" value, and the time step when rtol is given.

    Parameters
    ----------
    scene : granchain.scene.Scene
        From :func:`load_scene`.
    rtol : float, optional
        Relative tolerance of the peak forces; sets the time step (default: only "auto" values are
        chosen, the time step for 1e-3).
    method : {"rk4", "verlet"}
        The integrator the plan is for: the reference's RK4, or velocity Verlet (reference Verlet
        and LAMMPS). The same rtol needs a finer Verlet step.

    Returns
    -------
    granchain.workflows.plan.Plan
        ``plan.scene`` is concrete (no "auto" left); ``plan.choices`` holds each choice and its reason;
        ``plan.omega_max`` and ``plan.stable_timestep`` the frequency bound and stability limit.
    """
    from granchain.workflows.plan import plan_scene
    from granchain.workflows.run import integrator

    return plan_scene(scene, rtol=rtol, method=integrator("reference", method))


def run(
    scene,
    backend: str = "reference",
    method: str | None = None,
    rtol: float | None = None,
    out=None,
    error_estimate: bool = False,
    **kw,
):
    """Run a scene and return its result.

    Parameters
    ----------
    scene : granchain.scene.Scene
        From :func:`load_scene`; "auto" values are planned for the integrator this backend runs.
    backend : {"reference", "lammps"}
        The pure-Python reference solver, or LAMMPS with granchain's pair styles.
    method : {None, "rk4", "verlet"}
        Reference integrator (default RK4); LAMMPS runs velocity Verlet only.
    rtol : float, optional
        Plan the time step for this relative tolerance (otherwise a fixed step is checked against
        1e-3 and an ``AccuracyWarning`` says when the planner's error model predicts it misses).
    out : str or pathlib.Path, optional
        Write a run directory there (refused before the run if it exists; ``overwrite=True``).
    error_estimate : bool, default False
        Also run the scene at 2 dt and 4 dt and give every peak and observable a measured error
        estimate (``result.errors``; the ``*_error`` columns of peaks.csv). ``granchain run``
        does this by default.
    **kw
        ``overwrite``, ``np_`` (LAMMPS MPI ranks), ``oversubscribe``, ``force`` (run above the
        predicted stability limit).

    Returns
    -------
    granchain.results.RunResult
        ``result.peak_table``: numpy structured array (contact, peak_force, time_of_peak, complete);
        ``result.summary()``: the summary written to ``summary.json``; ``result.scene``: the scene
        as run; ``result.plan``: the plan (or None).
    """
    from granchain.workflows.run import run_scene

    return run_scene(scene, backend=backend, method=method, rtol=rtol, out=out, error_estimate=error_estimate, **kw)


def campaign(
    spec,
    out,
    workers: int | None = None,
    scheduler: str | None = None,
    rerun: bool = False,
    retry_failed: bool = False,
):
    """Run a campaign (a sweep or a search over scenes) into a workspace and return its table.

    Parameters
    ----------
    spec : str, pathlib.Path or dict
        A campaign file (TOML; docs/campaigns.md), or the same tables as a dict, e.g.
        ``{"campaign": {"base": "default", "backend": "reference"}, "vary": {"loading.impulse": [0.1, 0.4]}}``.
    out : str or pathlib.Path
        The workspace (a signac project; one job directory per point). Points complete there are not
        run again.
    workers : int, optional
        Local Dask worker processes (default: the cores this process may use).
    scheduler : str, optional
        Address of a running Dask scheduler (e.g. one started by dask-jobqueue) instead of a local cluster.
    rerun : bool
        Run every point again. ``retry_failed``: run the points that failed before again.

    Returns
    -------
    pandas.DataFrame
        A grid: one row per point (its parameters, status, pulse count and regime, every observable
        with its error, wall time and bead-steps). A search: one row per outer point with the transition
        (``load_campaign(out, "points")`` has every run). Every point is validated before anything runs
        (a ``GranchainError`` names the bad point); failing points are recorded, not raised.
    """
    from granchain.campaigns.api import run_campaign

    tables, _ = run_campaign(spec, out, workers=workers, scheduler=scheduler, rerun=rerun, retry_failed=retry_failed)
    return tables.get("search", tables["table"])


def load_campaign(ws, table: str | None = None):
    """The table of a campaign workspace as a pandas DataFrame, read from its run directories.

    ``table``: "points" (one row per point), "search" (a search's transitions), or None (a search's
    transitions, a grid's points).
    """
    from granchain.campaigns.api import load_campaign as _load

    return _load(ws, table)
