"""granchain: stress waves in 1D chains of spheres, LAMMPS cross-checked against a reference solver.

The public API is small::

    import granchain

    scene = granchain.load_scene("default")            # a bundled name or a .toml path
    scene = granchain.parse_scene(toml_text)           # or a scene written inline
    plan = granchain.plan(scene, rtol=1e-3, method="verlet")
    result = granchain.run(scene, backend="lammps")    # plans "auto" values for Verlet itself
    result.peaks                                       # pandas DataFrame by contact (units in .attrs)
    result.histories, result.snapshots                 # xarray Datasets (units in .attrs), or None
    result.summary["observables"]                      # summary.json as a dict
    fig = result.plot("peaks")                         # a matplotlib Figure; nothing saved or shown
    same = granchain.load_run("runs/default-lammps")   # a run directory back as the same result
    results = granchain.run_many(scenes, backend="lammps", out="runs/ensemble")  # each as run() runs it
    cmp = granchain.compare(scene)                     # LAMMPS vs reference: cmp.table, cmp.ok

Every error a user can cause is a :class:`GranchainError`. Importing granchain (or drawing through
it) never changes matplotlib's backend: figures are made without pyplot.

This package root is the public API's facade: it sits above every layer (it imports the workflows,
lazily) and no module of granchain imports it (pyproject.toml, [tool.importlinter]).
"""

from __future__ import annotations

from granchain._version import __version__
from granchain.exceptions import GranchainError

__all__ = [
    "GranchainError",
    "__version__",
    "campaign",
    "compare",
    "figure",
    "load_campaign",
    "load_dump",
    "load_run",
    "load_scene",
    "parse_scene",
    "plan",
    "provenance_packages",
    "run",
    "run_many",
]


def _scene(scene):
    """A Scene as it is; a bundled scene's name or a .toml path loaded (load_scene)."""
    from pathlib import Path

    if isinstance(scene, (str, Path)):
        return load_scene(scene)
    return scene


def _plot_result(result, kind: str = "peaks", **kw):
    """RunResult.plot's figure function: granchain.workflows.plots, imported when first drawn."""
    from granchain.workflows.plots import plot_result

    return plot_result(result, kind, **kw)


def _with_figures(result):
    """result, with RunResult.plot able to draw (the figure functions are loaded on first use)."""
    from granchain import results

    if results._PLOTTER is None:
        results.register_plotter(_plot_result)
    return result


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


def parse_scene(text: str, source: str = "<notebook>"):
    """A scene from TOML text (a scene written inline, e.g. in a notebook), validated.

    Parameters
    ----------
    text : str
        The scene file's text (``granchain scenes NAME`` prints one to start from).
    source : str
        A name for the scene in messages and provenance.

    Returns
    -------
    granchain.scene.Scene

    Raises
    ------
    GranchainError
        (``SceneError``) an invalid entry; the message names the key and the fix.
    """
    from granchain.scene import parse_scene as _parse

    return _parse(text, source=source)


def plan(scene, rtol: float | None = None, method: str | None = None):
    """The planner's choices for a scene: every "auto" value, and the time step when rtol is given.

    Parameters
    ----------
    scene : granchain.scene.Scene or str or pathlib.Path
        From :func:`load_scene` or :func:`parse_scene`, or a bundled scene's name or a .toml path.
    rtol : float, optional
        Relative tolerance of the peak forces; sets the time step (default: only "auto" values are
        chosen, the time step for 1e-3).
    method : {None, "rk4", "verlet"}
        The integrator the plan is for: the reference's RK4, or velocity Verlet (reference Verlet
        and LAMMPS); None: the one :func:`run` uses on the reference for this scene (RK4, or Verlet
        on a scene with velocity-dependent damping). The same rtol needs a finer Verlet step.

    Returns
    -------
    granchain.workflows.plan.Plan
        ``plan.scene`` is concrete (no "auto" left); ``plan.choices`` holds each choice and its reason;
        ``plan.omega_max`` and ``plan.stable_timestep`` the frequency bound and stability limit.
    """
    from granchain.backends import REFERENCE
    from granchain.workflows.plan import plan_scene
    from granchain.workflows.run import integrator

    scene = _scene(scene)
    return plan_scene(scene, rtol=rtol, method=integrator(REFERENCE, method, scene))


def run(
    scene,
    backend: str = "reference",
    method: str | None = None,
    rtol: float | None = None,
    out=None,
    error_estimate: bool | str = False,
    **kw,
):
    """Run a scene and return its result.

    Parameters
    ----------
    scene : granchain.scene.Scene or str or pathlib.Path
        From :func:`load_scene` or :func:`parse_scene` (or a bundled scene's name or a .toml path);
        "auto" values are planned for the integrator this backend runs.
    backend : str or granchain.backends.Backend
        A key of ``granchain.backends.BACKENDS``: "reference" (the pure-Python reference solver) or
        "lammps" (LAMMPS with granchain's pair styles).
    method : {None, "rk4", "verlet"}
        Reference integrator: None runs RK4, or velocity Verlet on a scene with velocity-dependent damping (where
        RK4's peak is the elastic force where the overlap turns and it gives no error bars; the
        reason is printed once and kept in ``result.summary["method_reason"]``); LAMMPS runs velocity
        Verlet only.
    rtol : float, optional
        Plan the time step for this relative tolerance (otherwise a fixed step is checked against
        1e-3 and an ``AccuracyWarning`` says when the planner's error model predicts it misses).
    out : str or pathlib.Path, optional
        Write a run directory there (refused before the run if it exists; ``overwrite=True``).
    error_estimate : bool or "checked", default False
        Also run the scene at 2 dt and 4 dt and give every peak and observable a measured error
        estimate (``result.errors``; the ``*_error`` columns of peaks.csv). ``granchain run``
        does this by default. "checked": with RK4, also a run at dt / 2 that withholds an estimate
        it contradicts (twice the run's cost more; docs/error-bars.md).
    **kw
        ``overwrite``, ``np_`` (LAMMPS MPI ranks), ``oversubscribe``, ``force`` (run above the
        predicted stability limit).

    Returns
    -------
    granchain.results.RunResult
        ``result.peaks``: pandas DataFrame by contact (peak_force N, time_of_peak s, complete,
        errors; units in ``.attrs["units"]``); ``result.histories`` / ``result.snapshots``: xarray
        Datasets (None when not asked for); ``result.energy``: DataFrame by time;
        ``result.summary``: the summary written to ``summary.json`` (a dict; calling it works too);
        ``result.plot(kind)``: a matplotlib Figure; ``result.scene``: the scene as run;
        ``result.plan``: the plan (or None); ``result.path``: the run directory when ``out`` was given.
    """
    from pathlib import Path

    from granchain.workflows.run import run_scene

    result = run_scene(
        _scene(scene), backend=backend, method=method, rtol=rtol, out=out, error_estimate=error_estimate, **kw
    )
    if out is not None:
        result.path = Path(out)
    return _with_figures(result)


def run_many(
    scenes,
    backend: str = "reference",
    method: str | None = None,
    rtol: float | None = None,
    out=None,
    error_estimate: bool | str = False,
    overwrite: bool = False,
    np_: int = 1,
    force: bool = False,
):
    """Run many scenes (an ensemble you build): each result the one :func:`run` gives that scene alone.

    Every scene is read, planned and checked before anything runs; the scenes are then run in groups
    of what they share (backend, integrator, planned time step), the shared work done once per group
    (on LAMMPS all runs go to one kept LAMMPS process instead of starting one per run; docs/api.md).

    Parameters
    ----------
    scenes : iterable of Scene, str or pathlib.Path
        Scenes from :func:`load_scene` or :func:`parse_scene` (or bundled names or .toml paths).
    backend, method, rtol, error_estimate
        As :func:`run`'s, for every scene.
    out : str or pathlib.Path or sequence of them, optional
        A directory (scene i's run directory is ``out/00000``, ``out/00001``, ...) or one run
        directory per scene. A run directory that already holds this scene's complete run (same
        backend, integrator, rtol, error bars) is read back, not run again: running an ensemble
        again resumes it.
    overwrite : bool
        Run every scene again and replace its run directory.
    np_, force
        As :func:`run`'s ``np_`` (LAMMPS MPI ranks) and ``force``.

    Returns
    -------
    list of granchain.results.RunResult
        In the scenes' order, ``result.path`` set with ``out``.

    Raises
    ------
    GranchainError
        (``UsageError``) not a list of scenes, an empty one, an entry that is not a scene, ``out``
        not one per scene; or any refusal :func:`run` makes before its run, raised before the first
        run, with a note naming the scene's position (``scenes[i]``). A run that fails raises as in
        :func:`run`, its position noted.
    """
    from granchain.campaigns.ensemble import run_many as _run_many

    results = _run_many(
        scenes,
        backend=backend,
        method=method,
        rtol=rtol,
        out=out,
        error_estimate=error_estimate,
        overwrite=overwrite,
        np_=np_,
        force=force,
    )
    return [_with_figures(r) for r in results]


def load_run(path):
    """A run directory read back as the result that wrote it.

    Parameters
    ----------
    path : str or pathlib.Path
        A directory of ``granchain run`` (either backend), of ``granchain collect``, or a campaign
        point's job directory.

    Returns
    -------
    granchain.results.RunResult
        The type :func:`run` returns (a LAMMPS run's LammpsRunResult, a collected run's
        CollectedRunResult), equal to the in-memory result for everything the directory keeps:
        ``peaks``, ``histories``, ``snapshots``, ``energy``, ``summary`` (as written), ``scene``,
        ``plan``; ``result.path`` is the directory. Not kept, so empty: the final state and the
        companion runs' ErrorReport (their numbers are in ``summary["errors"]`` and ``peaks``).

    Raises
    ------
    GranchainError
        (``LoadRunError``) not a complete run directory, or a file in it is a symbolic link or damaged.
    """
    from granchain.workflows.load import load_run as _load

    return _with_figures(_load(path))


def load_dump(path):
    """A run directory's whole-chain dump (chain.dump) as an xarray Dataset: ``load_run(path).dump``.

    Parameters
    ----------
    path : str or pathlib.Path
        A run directory of a LAMMPS run with ``[outputs] dump_interval`` (or its chain.dump).

    Returns
    -------
    xarray.Dataset
        Coordinates time (s), step, bead, contact, radius (m); variables position, displacement (m),
        velocity (m/s) over time x bead, contact_force (N) over time x contact; units in
        ``attrs["units"]``. ``ds.to_netcdf(file)`` stores it and ``xarray.load_dataset(file)`` gives
        it back identical.

    Raises
    ------
    GranchainError
        (``LoadRunError``) not a complete run directory, a file in it is a symbolic link or damaged,
        or the directory has no chain.dump.
    """
    from pathlib import Path

    from granchain.workflows.load import LoadRunError

    path = Path(path)
    run_dir = path.parent if path.name == "chain.dump" else path
    ds = load_run(run_dir).dump
    if ds is None:
        raise LoadRunError(
            f"{run_dir}: has no chain.dump; a LAMMPS run writes it with [outputs] dump_interval "
            "(seconds between frames)"
        )
    return ds


def figure(run, kind: str = "peaks", **kw):
    """One figure of a run as a matplotlib Figure, made without pyplot (not saved, not shown).

    Parameters
    ----------
    run : RunResult or str or pathlib.Path
        A result of :func:`run` or :func:`load_run`, or a run directory.
    kind : {"peaks", "histories", "snapshots", "heatmap"}
        peak force along the chain with the models that apply; force and velocity histories;
        profiles at the snapshot times; the x-t diagram of contact force.
    **kw
        ``log=False``: linear axes for "peaks".

    Returns
    -------
    matplotlib.figure.Figure
        ``fig.savefig("peaks.png")`` writes it; a notebook shows it as a cell's value.
    """
    from granchain.workflows.plots import figure as _figure

    return _figure(run, kind, **kw)


def compare(
    scene,
    rtol: float = 1e-3,
    method: str | None = None,
    out=None,
    error_estimate: bool | str = False,
    overwrite: bool = False,
    np_: int = 1,
):
    """Run a scene on LAMMPS and on the reference solver and compare them (``granchain compare``).

    Parameters
    ----------
    scene : granchain.scene.Scene or str or pathlib.Path
        A scene (or a bundled scene's name or a .toml path); "auto" values are planned for each
        backend's integrator, the time step for rtol / 2 each.
    rtol : float
        Tolerance between the two runs (a difference fails beyond rtol plus both measured errors).
    method : {"rk4", "verlet"} or None
        The reference's integrator; None: RK4, or Verlet on a scene with velocity-dependent damping, where RK4's peak is
        the elastic force where the overlap turns and LAMMPS's the total force's maximum (explicit
        "rk4" there: the peak rows are marked not comparable).
    out : str or pathlib.Path, optional
        Write the compare directory (lammps/, reference/, compare.csv, compare.md).
    error_estimate : bool or "checked"
        Give both runs measured error bars (companion runs at 2 dt and 4 dt; "checked": RK4's also
        checked by a run at dt / 2).

    Returns
    -------
    granchain.workflows.comparison_frame.Comparison
        ``.table`` (pandas DataFrame by quantity, units in ``.attrs``), ``.ok``, ``.lammps`` and
        ``.reference`` (RunResults).
    """
    from pathlib import Path

    from granchain.backends import LAMMPS, REFERENCE
    from granchain.workflows.compare_backends import compare_scene
    from granchain.workflows.comparison_frame import Comparison

    rows, lam, ref = compare_scene(
        _scene(scene), rtol=rtol, out=out, overwrite=overwrite, method=method, np_=np_, error_estimate=error_estimate
    )
    if out is not None:
        lam.path, ref.path = Path(out) / LAMMPS.name, Path(out) / REFERENCE.name
    _with_figures(lam)
    return Comparison(rows=rows, lammps=lam, reference=ref, rtol=rtol, path=None if out is None else Path(out))


def provenance_packages(campaign: bool = False) -> dict:
    """The installed versions of the libraries a run goes through (summary.json's
    provenance.packages: numpy, scipy, lammps, MDAnalysis, matplotlib, jinja2, pandas, xarray), and
    with ``campaign=True`` those a campaign runs on too (dask, distributed, signac); None where one
    is not installed."""
    from granchain.results import CAMPAIGN_PACKAGES, RUN_PACKAGES, package_versions

    return package_versions(RUN_PACKAGES + (CAMPAIGN_PACKAGES if campaign else ()))


def campaign(
    spec,
    out,
    workers: int | None = None,
    scheduler: str | None = None,
    rerun: bool = False,
    retry_failed: bool = False,
    cluster=None,
    ranks: int | str | None = None,
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
    cluster : str or dict, optional
        ``"slurm"``, ``"pbs"`` or a dict of settings (docs/clusters.md), over the file's ``[cluster]``.
    ranks : int or "auto", optional
        MPI ranks per LAMMPS point (``"auto"``: the --np auto rule).

    Returns
    -------
    pandas.DataFrame
        A grid: one row per point (its parameters, status, pulse count and regime, every observable
        with its error, wall time and bead-steps). A search: one row per outer point with the transition
        (``load_campaign(out, "points")`` has every run). Every point is validated before anything runs
        (a ``GranchainError`` names the bad point); failing points are recorded, not raised.
    """
    from granchain.campaigns.run import run_campaign

    tables, _ = run_campaign(
        spec,
        out,
        workers=workers,
        scheduler=scheduler,
        rerun=rerun,
        retry_failed=retry_failed,
        cluster=cluster,
        ranks=ranks,
    )
    return tables.get("search", tables["table"])


def load_campaign(ws, table: str | None = None):
    """The table of a campaign workspace as a pandas DataFrame, read from its run directories.

    ``table``: "points" (one row per point), "search" (a search's transitions), or None (a search's
    transitions, a grid's points).
    """
    from granchain.campaigns.run import load_campaign as _load

    return _load(ws, table)
