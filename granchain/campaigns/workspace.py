"""The campaign workspace: a signac project with one job directory per point.

    WS/
      .signac/config                 the signac project (signac.init_project)
      workspace/<job id>/            one point: signac names it by the hash of its state point
        signac_statepoint.json       the state point (below), written by signac
        run/                         the point's run directory (granchain.results.write_run_dir:
                                     written aside and renamed, summary.json last): present = complete
        failure.json                 a point that failed: its one-line message (and a bug's traceback)
        task.json                    the task that ran it: host, worker, wall time, warnings
      campaign.toml                  the campaign file as given; base.toml the base scene (canonical)
      campaign.json                  the points of the last campaign run here, in order, with their job ids
      table.csv, table.parquet       one row per point (granchain.campaigns.table)
      search.csv, search.parquet     a search campaign: one row per outer point, its transition

The state point is what computes the point: the canonical scene (granchain.scene.scene_to_dict of the
validated scene), the backend, the method, rtol, whether errors are estimated, and the code, which is
granchain's version, the hash of its sources (source_hash) and, for LAMMPS, the plugin's hash
(granchain.lammps.build.plugin_key). The same
scene written differently is the same job. A point computed by other code has another job id: it is
not reused, and reported as stale.

signac's own tools (``signac.get_project(WS)``, ``project.find_jobs(...)``) and row read the workspace.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
from pathlib import Path

from granchain._version import __version__
from granchain.campaigns.spec import CampaignError

RUN_DIR = "run"
FAILURE = "failure.json"
TASK = "task.json"
RECORD = "campaign.json"
#: version of campaign.json's layout
RECORD_SCHEMA = 1


def code_version(backend: str) -> dict:
    """The code that computes a point: granchain's version, the hash of its Python sources and deck
    templates (source_hash), and the LAMMPS plugin's hash for LAMMPS (hashed once per process: a
    worker checks it for every point)."""
    return dict(_code_version(backend))


@functools.cache
def _code_version(backend: str) -> tuple:
    # the version string alone let two installs that differ in their source (a checkout with local
    # changes, a later commit of the same release) share points and pass the worker's check
    code = {"granchain": __version__, "source": source_hash()}
    if backend == "lammps":
        from granchain.lammps.build import plugin_key

        code["plugin"] = plugin_key()
    return tuple(code.items())


@functools.cache
def source_hash() -> str:
    """sha256 (first 16 hex digits) of granchain's Python sources and LAMMPS deck templates, by path
    relative to the package and content: any change to the code that computes a point changes it
    (the plugin's C++ is hashed on its own, granchain.lammps.build.plugin_key). Bundled scenes are
    inputs, already in the state point; compiled caches (__pycache__) are not sources."""
    return hash_sources(Path(__file__).resolve().parent.parent)


def hash_sources(pkg: Path) -> str:
    """source_hash of the package directory pkg."""
    h = hashlib.sha256()
    for f in sorted(p for p in pkg.rglob("*") if p.suffix in (".py", ".j2") and "__pycache__" not in p.parts):
        h.update(f.relative_to(pkg).as_posix().encode())
        h.update(b"\0")
        h.update(f.read_bytes())
        h.update(b"\0")
    return h.hexdigest()[:16]


def statepoint(scene_dict: dict, backend: str, method: str, rtol: float | None, error_estimate: bool, code: dict):
    """A point's signac state point (JSON: the scene's tuples become lists)."""
    return json.loads(
        json.dumps(
            {
                "scene": scene_dict,
                "backend": backend,
                "method": method,
                "rtol": rtol,
                "error_estimate": error_estimate,
                "code": code,
            }
        )
    )


def point_key(sp) -> str:
    """The state point without its code: the same for one point under two versions of granchain."""
    return json.dumps({k: v for k, v in dict(sp).items() if k != "code"}, sort_keys=True, default=_plain)


def _plain(o):
    if hasattr(o, "items"):
        return dict(o.items())
    if isinstance(o, (list, tuple)):
        return list(o)
    raise TypeError(repr(o))


def create_workspace(ws: str | Path):
    """Open the workspace, making it if needed; refuse a directory that is something else."""
    import signac

    ws = Path(ws)
    if ws.exists() and not ws.is_dir():
        raise CampaignError(f"{ws}: exists and is not a directory; choose another --out")
    if ws.is_dir() and any(ws.iterdir()) and not (ws / ".signac").is_dir():
        raise CampaignError(
            f"{ws}: is not empty and not a campaign workspace (no .signac); choose a new or empty --out directory"
        )
    try:
        ws.mkdir(parents=True, exist_ok=True)
        return signac.init_project(str(ws))
    except OSError as e:
        raise CampaignError(f"{ws}: cannot create the workspace ({e.strerror}); choose another --out") from None


def open_workspace(ws: str | Path):
    """An existing workspace (granchain campaign run --out WS made it)."""
    import signac

    ws = Path(ws)
    if not (ws / ".signac").is_dir() or not (ws / RECORD).is_file():
        raise CampaignError(
            f"{ws}: is not a campaign workspace (no .signac or {RECORD}); give the --out directory of "
            "'granchain campaign run'"
        )
    return signac.get_project(str(ws), search=False)


def job_state(job_dir: str | Path) -> str:
    """'done' (its run directory is complete), 'failed' (failure.json) or 'missing'."""
    d = Path(job_dir)
    if (d / RUN_DIR / "summary.json").is_file():
        return "done"
    if (d / FAILURE).is_file():
        return "failed"
    return "missing"


def read_json(path: Path) -> dict | None:
    try:
        return json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None


def write_json(path: Path, data) -> None:
    """Write aside and rename: a reader never sees half a file."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data, indent=1, default=_plain) + "\n")
    os.replace(tmp, path)


def stale_versions(project, code: dict) -> dict[str, dict]:
    """point key -> code of a complete job of the same point computed by other code."""
    out: dict[str, dict] = {}
    for job in project:
        sp = job.cached_statepoint
        other = dict(sp.get("code", {}))
        if other != code and job_state(job.path) == "done":
            out[point_key(sp)] = other
    return out


def code_text(code: dict) -> str:
    return ", ".join(f"{k} {v}" for k, v in code.items())
