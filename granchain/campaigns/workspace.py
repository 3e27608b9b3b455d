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
      trials.csv, trials.parquet     an optimize campaign: one row per trial, its design and objective

The state point is what computes the point: the canonical scene (granchain.scene.scene_to_dict of the
validated scene), the backend, the method, rtol, whether errors are estimated, and the code, which is
granchain's version, the hash of its sources (source_hash) and, for LAMMPS, the plugin's hash
(granchain.lammps.build.plugin_key). The same
scene written differently is the same job. A point computed by other code has another job id: it is
not reused, and reported as stale.

signac's own tools (``signac.get_project(WS)``, ``project.find_jobs(...)``) and row read the workspace.

A workspace may be shared or copied from someone else, so nothing in it is trusted: a symbolic link
where granchain reads or writes (campaign.toml, base.toml, campaign.json, the tables, plots/,
workspace/, a job directory or a file in one) is refused or left out, every file is read bounded
(granchain.safe_files), and a point counts as complete only if its run directory's summary.json and
scene.toml parse and match its state point (job_state). A job directory whose state point is
damaged (signac_statepoint.json that does not parse or is not its directory's hash) or that is a link
is moved aside, to WS/damaged/, by ``campaign run``: its point runs again.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import time
import warnings
from pathlib import Path

from granchain import safe_files
from granchain._version import __version__
from granchain.backends import backend_named
from granchain.campaigns.model import DONE, FAILED, MISSING, CampaignError

RUN_DIR = "run"
FAILURE = "failure.json"
TASK = "task.json"
RECORD = "campaign.json"
STATEPOINT = "signac_statepoint.json"
#: where campaign run moves a damaged job directory (its state point unreadable, or a link) and a
#: point's run directory that is a link
DAMAGED = "damaged"
#: the names granchain reads or writes at the top of a workspace: none may be a symbolic link
WORKSPACE_NAMES = (
    "campaign.toml",
    "base.toml",
    RECORD,
    "table.csv",
    "table.parquet",
    "search.csv",
    "search.parquet",
    "trials.csv",
    "trials.parquet",
    "plots",
    "workspace",
    ".signac",
    ".signac/config",  # signac reads it: a link there would have it read a file outside the workspace
    DAMAGED,
)
#: the most read from one JSON file of a workspace (bytes)
JSON_LIMIT = 64 * 1024 * 1024
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
    code = {"granchain": __version__, "source": source_hash(), **backend_named(backend).code_version()}
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
    return json.dumps({k: v for k, v in dict(sp).items() if k != "code"}, sort_keys=True, default=plain)


def plain(o):
    """json.dumps' default for a scene's values: a mapping as a dict, a tuple as a list."""
    if hasattr(o, "items"):
        return dict(o.items())
    if isinstance(o, (list, tuple)):
        return list(o)
    raise TypeError(repr(o))


class WorkspaceWriteError(CampaignError, OSError):
    """A workspace file that cannot be written (full disk, read-only, a link at its name): a user's
    error (one line) that code catching OSError still catches."""

    def __init__(self, code: int | None, message: str):
        super().__init__(message)
        self.errno, self.strerror = code, message

    def __str__(self) -> str:
        """The message alone (OSError's would put the errno in front)."""
        return self.strerror


def check_links(ws: str | Path) -> None:
    """Refuse a workspace with a symbolic link where granchain reads or writes (WORKSPACE_NAMES)."""
    ws = Path(ws)
    for name in WORKSPACE_NAMES:
        if os.path.islink(ws / name):
            raise CampaignError(
                f"{ws / name}: is a symbolic link; granchain reads and writes a workspace only inside it: remove "
                "the link (or copy what it points to in its place)"
            )


def job_dirs(ws: str | Path) -> dict[str, dict | None]:
    """Job id -> state point of every job directory of the workspace; None for one that is damaged:
    a link, not a directory, or a signac_statepoint.json that does not parse or does not hash to the
    directory's name. Read without signac (which stops at the first damaged one)."""
    out: dict[str, dict | None] = {}
    root = Path(ws) / "workspace"
    if os.path.islink(root) or not root.is_dir():
        return out
    with os.scandir(root) as it:
        for e in it:
            out[e.name] = read_statepoint(Path(e.path)) if e.is_dir(follow_symlinks=False) else None
    return out


def read_statepoint(job_dir: Path) -> dict | None:
    """A job directory's state point; None when it is damaged: not a JSON object, or not the state
    point whose hash names the directory."""
    from signac.job import calc_id

    sp = read_json(Path(job_dir) / STATEPOINT)
    try:
        return sp if isinstance(sp, dict) and calc_id(sp) == Path(job_dir).name else None
    except (TypeError, ValueError, RecursionError):
        return None


#: a job directory without a state point made within this many seconds is not set aside (another
#: driver's signac may be between making it and writing its state point)
SETTLE = 30.0


def _mtime(d: Path) -> float:
    try:
        return os.lstat(d).st_mtime
    except OSError:
        return 0.0


def set_aside_damaged(ws: str | Path) -> list[str]:
    """Move damaged job directories (job_dirs: None) to WS/damaged/, with a warning naming them; their
    points run again. Returns the job ids moved."""
    ws = Path(ws)
    moved = []
    now = time.time()
    for job, sp in sorted(job_dirs(ws).items()):
        if sp is not None:
            continue
        d = ws / "workspace" / job
        if not os.path.islink(d) and not os.path.lexists(d / STATEPOINT) and _mtime(d) > now - SETTLE:
            continue  # being made right now (signac makes the directory, then writes its state point)
        os.replace(ws / "workspace" / job, _damaged_place(ws, job))  # a link is moved as a link, never followed
        moved.append(job)
    if moved:
        warnings.warn(
            f"{ws}: {len(moved)} job director{'y' if len(moved) == 1 else 'ies'} with a damaged state point "
            f"({STATEPOINT} unreadable or not the directory's hash, or a symbolic link) moved to {ws / DAMAGED}: "
            f"{', '.join(moved[:5])}{' ...' if len(moved) > 5 else ''}; their points run again",
            stacklevel=2,
        )
    return moved


def _damaged_place(ws: Path, name: str) -> Path:
    """A free name in WS/damaged/ (made if needed) for something set aside: name, name.1, name.2, ..."""
    dest_dir = ws / DAMAGED
    dest_dir.mkdir(exist_ok=True)
    dest, k = dest_dir / name, 1
    while os.path.lexists(dest):
        dest, k = dest_dir / f"{name}.{k}", k + 1
    return dest


def set_aside_run_links(ws: str | Path) -> list[str]:
    """Move a point's run directory that is a symbolic link to WS/damaged/<job>.run: the link itself,
    never followed (what it points to is not read, written or removed), with a warning naming it.
    granchain writes a point's run only in its own job directory, so a point whose run is a link could
    never complete; set aside, it runs again (one that failed for it before, with --retry-failed).
    Returns the job ids whose run was moved."""
    ws = Path(ws)
    moved = []
    for job, sp in sorted(job_dirs(ws).items()):
        run = ws / "workspace" / job / RUN_DIR
        if sp is None or not os.path.islink(run):
            continue
        os.replace(run, _damaged_place(ws, f"{job}.{RUN_DIR}"))
        moved.append(job)
    if moved:
        n = len(moved)
        warnings.warn(
            f"{ws}: {n} point{'s' if n != 1 else ''} had a symbolic link as {'their' if n != 1 else 'its'} run "
            f"directory (workspace/<job>/{RUN_DIR}, not followed): the link{'s' if n != 1 else ''} moved to "
            f"{ws / DAMAGED}, what {'they point' if n != 1 else 'it points'} to untouched: "
            f"{', '.join(moved[:5])}{' ...' if n > 5 else ''}; {'these points run' if n != 1 else 'the point runs'} "
            "again (one that failed before, with --retry-failed)",
            stacklevel=2,
        )
    return moved


def create_workspace(ws: str | Path):
    """Open the workspace, making it if needed; refuse a directory that is something else, or one
    with a symbolic link where granchain writes; set damaged job directories and run directories that
    are links aside."""
    import signac

    ws = Path(ws)
    if os.path.islink(ws):
        raise CampaignError(f"{ws}: is a symbolic link; give the workspace's own path as --out")
    check_links(ws)
    if ws.exists() and not ws.is_dir():
        raise CampaignError(f"{ws}: exists and is not a directory; choose another --out")
    if ws.is_dir() and any(ws.iterdir()) and not (ws / ".signac").is_dir():
        raise CampaignError(
            f"{ws}: is not empty and not a campaign workspace (no .signac); choose a new or empty --out directory"
        )
    try:
        ws.mkdir(parents=True, exist_ok=True)
        if not os.access(ws, os.W_OK):
            raise PermissionError(13, "not writable")
        project = _signac(signac.init_project, ws)
        set_aside_damaged(ws)
        set_aside_run_links(ws)
        return project
    except OSError as e:
        raise CampaignError(
            f"{ws}: cannot create or write the workspace ({e.strerror}); make it writable or choose another --out"
        ) from None


def open_workspace(ws: str | Path):
    """An existing workspace (granchain campaign run --out WS made it)."""
    import signac

    ws = Path(ws)
    check_links(ws)
    if not (ws / ".signac").is_dir() or not (ws / RECORD).is_file():
        raise CampaignError(
            f"{ws}: is not a campaign workspace (no .signac or {RECORD}); give the --out directory of "
            "'granchain campaign run'"
        )
    return _signac(signac.get_project, ws, search=False)


def _signac(open_project, ws: Path, **kw):
    """signac's project of ws; its errors opening it (a damaged .signac/config, another schema) as a
    CampaignError."""
    from signac.errors import Error

    try:
        return open_project(str(ws), **kw)
    except (Error, ValueError, OSError, LookupError) as e:  # (not UTF-8: UnicodeDecodeError; no config: LookupError)
        why = " ".join(str(e).split())[:200]
        raise CampaignError(
            f"{ws / '.signac' / 'config'}: signac cannot open the workspace ({why}); it is damaged or another "
            "signac's: run the campaign into a new --out"
        ) from None


def job_state(job_dir: str | Path, sp: dict | None = None) -> str:
    """'done' (its run directory is complete and is this point's: run_is_complete), 'failed'
    (failure.json) or 'missing'. sp: the job's state point, read from the job directory if not given."""
    d = Path(job_dir)
    if os.path.islink(d) or not d.is_dir():
        return MISSING
    if sp is None:
        sp = read_json(d / STATEPOINT)
    if isinstance(sp, dict) and run_is_complete(d / RUN_DIR, sp):
        return DONE
    if isinstance(read_json(d / FAILURE), dict):
        return FAILED
    return MISSING


def run_is_complete(run: Path, sp: dict) -> bool:
    """Whether run is a complete run directory of the state point sp: not a link; its summary.json a
    JSON object of sp's backend and method whose scene hash is its scene.toml's; that scene.toml a
    valid scene with every value sp's scene gives (the "auto" ones, the time step, end time and
    sampling intervals are the planner's)."""
    from granchain.scene import parse_scene, scene_to_dict

    if os.path.islink(run) or not run.is_dir():
        return False
    summary = read_json(run / "summary.json")
    if not isinstance(summary, dict):
        return False
    if summary.get("backend") != sp.get("backend") or summary.get("method") != sp.get("method"):
        return False
    try:
        text = safe_files.read_bytes(run / "scene.toml", JSON_LIMIT)
        recorded = summary["provenance"]["scene"]["sha256"]
    except (OSError, KeyError, TypeError):
        return False
    if hashlib.sha256(text).hexdigest() != recorded:
        return False
    try:
        scene = scene_to_dict(parse_scene(text.decode("utf-8"), source=str(run / "scene.toml")))
    except Exception:  # noqa: BLE001 - any scene that does not load is not this point's
        return False
    return _agrees(sp.get("scene"), json.loads(json.dumps(scene)))


#: scene keys the run may have set otherwise than the state point gives them (the planner's step,
#: end time and sampling intervals, with an rtol): not compared
_PLANNED = ("timestep", "end_time", "history_interval", "dump_interval")


def _agrees(given, ran) -> bool:
    """Every value of the state point's scene (given) is the run's (ran), "auto" and planned ones aside."""
    if given == "auto":
        return True
    if isinstance(given, dict):
        return isinstance(ran, dict) and all(k in _PLANNED or _agrees(v, ran.get(k)) for k, v in given.items())
    return given == ran


def read_json(path: Path):
    """A workspace JSON file's content, or None when it is missing, a link, not a regular file,
    larger than JSON_LIMIT, or not JSON."""
    try:
        return json.loads(safe_files.read_text(path, JSON_LIMIT))
    except (OSError, ValueError, RecursionError):
        return None


def write_text(path: Path, text: str) -> None:
    """Write a workspace's text file (campaign.toml, base.toml) aside and rename it into place,
    refusing a link at path; a failure (a full disk, read-only) is a WorkspaceWriteError naming it."""
    try:
        safe_files.write_text(path, text)
    except OSError as e:
        raise WorkspaceWriteError(
            e.errno, f"{path}: cannot be written ({e.strerror or e}); free some space or fix the workspace"
        ) from None


def write_json(path: Path, data) -> None:
    """Write aside and rename (a reader never sees half a file, a full disk leaves no temporary
    file); a link at path is refused (a WorkspaceWriteError, as is a file that cannot be written)."""
    write_text(path, json.dumps(data, indent=1, default=plain) + "\n")


def stale_versions(project, code: dict) -> dict[str, dict]:
    """point key -> code of a complete job of the same point computed by other code."""
    out: dict[str, dict] = {}
    root = Path(project.path)
    for job, sp in job_dirs(root).items():
        if sp is None:  # damaged: not a result of any code
            continue
        other = sp.get("code", {})
        if not isinstance(other, dict):
            continue
        if other != code and job_state(root / "workspace" / job, sp) == "done":
            out[point_key(sp)] = dict(other)
    return out


def code_text(code: dict) -> str:
    """A code record (code_version) for messages: 'granchain 1.0, source 0123abcd..., plugin ...'."""
    return ", ".join(f"{k} {v}" for k, v in code.items())


def measurable_missing(summary) -> dict[str, str]:
    """summary.json's observables_missing without those its scene never measures
    (observables_inapplicable: a wall's on a free chain), name -> reason: what a point could measure and
    did not (the campaign's ``unmeasured``)."""
    summary = summary if isinstance(summary, dict) else {}
    never = summary.get("observables_inapplicable")
    never = set(never) if isinstance(never, list) else set()
    missing = summary.get("observables_missing")
    missing = missing if isinstance(missing, dict) else {}
    return {str(k): str(v) for k, v in missing.items() if k not in never}
