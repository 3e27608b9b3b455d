"""An ensemble the user builds: many scenes run as each would run alone, grouped by what they share.

run_many(scenes, ...) returns, in the scenes' order, the RunResults ``granchain.run`` gives each scene
singly (the same summaries: every observable, error bar and status). Before anything runs, every
scene is read, its integrator chosen and its "auto" values planned, and every check a single run
makes before it starts is made (the step limit, the stability limit, the run directory): a bad scene
stops the ensemble before its first run, its position named. The points are then run in groups of
what they share -- the backend, the integrator and the planned time step -- and the work a point
shares with its group is done once: its plan is not made again (run_scene's ``planned``), and on
LAMMPS the whole ensemble runs on one kept LAMMPS child (granchain.lammps.server) instead of starting
LAMMPS (process, import, plugin load: about 0.2 s) for each run. Batching a group's chains into one
LAMMPS instance (issue 44 item 1) would slot in at run_group.

With ``out`` every point's run directory is written (``out/00000``, ``out/00001``, ... or the paths
given); a point whose directory already holds a complete run of the same scene, backend, integrator,
rtol and error bars is read back (granchain.workflows.load.load_run) instead of run again, so running
an ensemble again resumes it and a second run over a finished one runs nothing (``overwrite=True``
runs every point again).
"""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Iterable
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path

from granchain.backends import Backend, backend_named
from granchain.campaigns import workspace as wsp
from granchain.exceptions import UsageError

#: the name of point i's run directory under an ``out`` directory
POINT_DIR = "{:05d}"


@dataclass
class Point:
    """One scene of the ensemble, prepared: as given, planned, its integrator and run directory."""

    index: int
    given: object  # the Scene as given ("auto" values allowed)
    planned: tuple  # plan_for's (concrete scene, Plan or None)
    method: str
    out: Path | None
    done: bool = False  # out holds this point's complete run already: read back, not run

    @property
    def group(self) -> tuple:
        """What the point shares with its group: its integrator and planned time step."""
        return (self.method, self.planned[0].run.timestep)


def _scene_at(i: int, scene):
    """Scene i as a Scene: a Scene as it is, a bundled name or a .toml path loaded."""
    from granchain.scene import Scene, load_scene

    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, (str, Path)):
        try:
            return load_scene(scene)
        except Exception as e:
            e.add_note(f"(scenes[{i}] of run_many)")
            raise
    raise UsageError(
        f"scenes[{i}] = {type(scene).__name__!s}: each scene must be a granchain Scene (load_scene, "
        "parse_scene), a bundled scene's name or a .toml path"
    )


def _scene_list(scenes) -> list:
    """The scenes as a list of Scenes (UsageError: not a collection of scenes, or empty)."""
    from granchain.scene import Scene

    if isinstance(scenes, (str, Path, Scene)) or not isinstance(scenes, Iterable):
        raise UsageError(
            f"scenes = {type(scenes).__name__}: run_many takes a list of scenes (granchain.run runs one scene)"
        )
    scenes = [_scene_at(i, s) for i, s in enumerate(scenes)]
    if not scenes:
        raise UsageError("scenes is empty: give run_many at least one scene")
    return scenes


def _out_dirs(out, n: int) -> list:
    """Each point's run directory: None each without out; out/00000, ... under a directory; or the
    n paths given (UsageError: another count, or one path twice)."""
    if out is None:
        return [None] * n
    if isinstance(out, (str, os.PathLike)):
        return [Path(out) / POINT_DIR.format(i) for i in range(n)]
    try:
        dirs = [Path(p) for p in out]
    except TypeError:
        raise UsageError(
            f"out = {out!r}: a directory (str or Path) or one run directory per scene (a list of them)"
        ) from None
    if len(dirs) != n:
        raise UsageError(f"out: {len(dirs)} run directories for {n} scenes; give one per scene, or one directory")
    seen: dict[Path, int] = {}
    for i, d in enumerate(dirs):
        j = seen.setdefault(d.absolute(), i)
        if j != i:
            raise UsageError(f"out[{i}] = {d}: is out[{j}] too; each scene needs its own run directory")
    return dirs


def _prepare(i, given, out, backend: Backend, method, rtol, np_, force, overwrite, error_estimate) -> Point:
    """Point i chosen, planned and checked as run_scene would before its run (its warnings are left to
    the run: run_scene makes them again, once)."""
    from granchain.workflows.run import check_output_dir, check_resources, check_timestep, method_choice, plan_for

    try:
        chosen, _ = method_choice(backend, method, given)
        planned = plan_for(given, backend, chosen, rtol)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            check_resources(planned[0], backend, np_, False, out=out, given=given)
        if not force:
            check_timestep(planned[0], chosen)
        done = out is not None and not overwrite and _complete(out, given, backend, chosen, planned[1], error_estimate)
        if out is not None and not done:
            check_output_dir(out, overwrite)
    except Exception as e:
        e.add_note(f"(scenes[{i}] of run_many: {given.source})")
        raise
    return Point(i, given, planned, chosen, out, done)


def _complete(out: Path, given, backend: Backend, method: str, plan, error_estimate) -> bool:
    """Whether out holds a complete run of this scene (the campaign's test, wsp.run_is_complete), on
    this backend and integrator, planned for the same rtol, with error bars if and only if asked for."""
    from granchain.scene import scene_to_dict

    sp = {"backend": backend.name, "method": method, "scene": json.loads(json.dumps(scene_to_dict(given)))}
    if not wsp.run_is_complete(out, sp):
        return False
    summary = wsp.read_json(out / "summary.json")
    stored_plan = (summary.get("provenance") or {}).get("plan")
    rtol = None if plan is None else plan.rtol
    if (None if not isinstance(stored_plan, dict) else stored_plan.get("rtol")) != rtol:
        return False
    return (summary.get("errors") is not None) == bool(error_estimate)


def _kept(backend: Backend, np_: int) -> bool:
    """Whether the runs go to a kept LAMMPS child (server.persistent): single-rank LAMMPS runs."""
    return backend.name == "lammps" and np_ == 1


def run_group(points: list[Point], backend: Backend, method, rtol, error_estimate, np_, force, overwrite) -> dict:
    """Run one group's points (one integrator and time step) on their backend: index -> RunResult.
    method: the integrator asked for (None: each scene's default, its reason kept in the summary as a
    single run keeps it).

    On LAMMPS every single-rank run of the group goes to one kept LAMMPS child (server.persistent; run_many
    holds it across the groups)."""
    from granchain.lammps import server
    from granchain.workflows.load import load_run
    from granchain.workflows.run import run_scene

    results = {}
    with server.persistent() if _kept(backend, np_) else nullcontext():
        for p in points:
            if p.done:
                results[p.index] = load_run(p.out)
                continue
            try:
                results[p.index] = run_scene(
                    p.given,
                    backend=backend,
                    method=method,
                    rtol=rtol,
                    out=p.out,
                    overwrite=overwrite,
                    error_estimate=error_estimate,
                    np_=np_,
                    force=force,
                    planned=p.planned,
                )
            except Exception as e:
                e.add_note(f"(scenes[{p.index}] of run_many: {p.given.source})")
                raise
    return results


def run_many(
    scenes,
    backend: str | Backend = "reference",
    method: str | None = None,
    rtol: float | None = None,
    out=None,
    error_estimate: bool | str = False,
    overwrite: bool = False,
    np_: int = 1,
    force: bool = False,
) -> list:
    """Run many scenes, each as run_scene runs it alone, grouped by backend, integrator and time step.

    Parameters
    ----------
    scenes : iterable of Scene, str or pathlib.Path
        The scenes (a bundled scene's name or a .toml path is loaded).
    backend, method, rtol, error_estimate, np_, force
        As granchain.run's, for every scene.
    out : str, pathlib.Path or sequence of them, optional
        A directory (point i's run directory is ``out/00000``-style, POINT_DIR), or one run directory
        per scene. A complete run of the same point there is read back, not run again.
    overwrite : bool
        Run every point again and replace its run directory.

    Returns
    -------
    list of RunResult
        In the scenes' order; ``result.path`` is the point's run directory with ``out``.

    Raises
    ------
    UsageError
        Not a list of scenes, an empty one, a scene of another type, or ``out`` not one per scene;
        before anything runs, also every refusal a single run makes before its run (with a note
        naming the scene's position). A run that fails raises as granchain.run does, its position noted.
    """
    from granchain.lammps import server
    from granchain.workflows.run import check_error_estimate

    check_error_estimate(error_estimate)
    backend = backend_named(backend)
    given = _scene_list(scenes)
    outs = _out_dirs(out, len(given))
    points = [
        _prepare(i, s, o, backend, method, rtol, np_, force, overwrite, error_estimate)
        for i, (s, o) in enumerate(zip(given, outs, strict=True))
    ]
    groups: dict[tuple, list[Point]] = {}
    for p in points:
        groups.setdefault(p.group, []).append(p)
    results: dict[int, object] = {}
    with server.persistent() if _kept(backend, np_) else nullcontext():  # one LAMMPS child for every group
        for members in groups.values():
            results.update(run_group(members, backend, method, rtol, error_estimate, np_, force, overwrite))
    for p in points:
        if p.out is not None:
            results[p.index].path = p.out
    return [results[i] for i in range(len(points))]
