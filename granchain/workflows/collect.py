"""A deck that stands alone: render a directory plain LAMMPS can run anywhere, and collect it back.

    granchain render SCENE --out DIR     render_dir: DIR/deck.lmp, chain.data, scene.toml (the scene as
                                         run, "auto" values planned), plan.json (the planner's choices)
    cd DIR && lmp -in deck.lmp           or mpirun -np N lmp -in deck.lmp, on this machine or a cluster
    granchain collect DIR                collect: DIR becomes the run directory `granchain run --backend
                                         lammps` writes (peaks.csv, summary.json, energy.csv, ...)

The deck writes every result granchain needs as files (its results dump, templates.RESULT_COLUMNS,
the run's last step and time, energy.txt, the history and snapshot dumps), and collect turns them
into a RunResult through the same function the in-process run uses (runner.lammps_result). What
only the plain run's log knows (LAMMPS's version, the ranks, the loop times) is read from
log.lammps; summary.json's provenance says the run was collected and what was not recorded.

collect refuses, with a CollectError saying what to do: a directory without deck.lmp, chain.data or
scene.toml; a scene.toml whose content hash is not the one render wrote into the deck; a run that
has not finished (no results dump: the log's last lines are in the message); a file it reads or
copies that is a symbolic link, not a regular file, larger than it reads, or damaged (it names the
file). Nothing is written then; the files it adds are written aside and renamed into place,
summary.json last. The directory may come from someone else: nothing in it makes collect read or
write outside it, or outside --out.
"""

from __future__ import annotations

import fnmatch
import json
import math
import os
import re
import shutil
import warnings
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from granchain import safe_files
from granchain.backends import LAMMPS
from granchain.exceptions import GranchainError
from granchain.lammps.runner import (
    OUTPUT_GLOBS,
    LammpsError,
    LammpsRunResult,
    ResultsError,
    invariant_from_lammps,
    output_files,
)
from granchain.peaks import mark_reflection_pending
from granchain.results import RunResult, scene_hash
from granchain.rundir import RunDirError, write_run_dir
from granchain.scene import load_scene, parse_scene
from granchain.templates import RESULTS_DUMP, RUN_END_FILE
from granchain.workflows.plan import Plan, PlanChoice, refined_plan

#: what granchain render --out writes (plan.json only when something was planned)
RENDER_FILES = ("deck.lmp", "chain.data", "scene.toml")
PLAN_FILE = "plan.json"
LOG_FILE = "log.lammps"

#: the deck's line naming its scene's content hash (templates/chain.lmp.j2)
_HASH_LINE = re.compile(r"^# Scene sha256: ([0-9a-f]{64})\b", re.M)
_RENDERED_BY = re.compile(r"^# Rendered by granchain (\S+) from ", re.M)
_MONTHS = {m: i + 1 for i, m in enumerate("Jan Feb Mar Apr May Jun Jul Aug Sep Oct Nov Dec".split())}

#: the most collect reads from a text file it takes whole (scene, deck, plan, log, run end), bytes
TEXT_LIMIT = 256 * 1024 * 1024
#: the most it reads into memory from one of LAMMPS's result files (dumps, energy samples, histories)
DATA_LIMIT = 2 * 1024**3
#: the files collect reads or copies (beside OUTPUT_GLOBS): each must be a regular file, not a link
_READ_NAMES = ("scene.toml", PLAN_FILE, LOG_FILE, RUN_END_FILE, RESULTS_DUMP, "load_end.txt", "energy.txt")
#: what collect catches from reading LAMMPS's result files: a damaged file (its parser's errors)
_DAMAGED = (ValueError, KeyError, IndexError, TypeError, OverflowError, EOFError, UnicodeError)


class CollectError(GranchainError, RuntimeError):
    """A directory that granchain collect cannot turn into a run directory; the message says why and what to do."""


class NotRefinedWarning(UserWarning):
    """granchain run would have run this planned scene again at a finer step (workflows.plan.refined_plan);
    the plain-LAMMPS run was run once, at the step planned before any run."""


def scene_file_text(scene) -> str:
    """scene.toml as a run directory holds it (results.write_run_dir): the file's own text, or the
    canonical TOML of a planned scene."""
    return scene.source_text if scene.source_text else scene.to_toml()


def plan_to_dict(plan) -> dict | None:
    """The planner's choices as plan.json holds them (the same record as summary.json's provenance.plan)."""
    if plan is None:
        return None
    return {
        "method": plan.method,
        "rtol": plan.rtol,
        "omega_max": plan.omega_max,
        "stable_timestep": plan.stable_timestep,
        "choices": [{"name": c.name, "value": c.value, "reason": c.reason} for c in plan.choices],
    }


def plan_from_dict(data: dict | None, scene):
    if data is None:
        return None
    return Plan(
        scene=scene,
        rtol=float(data["rtol"]),
        method=str(data["method"]),
        choices=[PlanChoice(str(c["name"]), float(c["value"]), str(c["reason"])) for c in data["choices"]],
        omega_max=float(data["omega_max"]),
        stable_timestep=float(data["stable_timestep"]),
    )


def render_dir(scene, out: str | Path, plan=None, given=None) -> Path:
    """Write a directory that plain LAMMPS runs as it is (`lmp -in deck.lmp` inside it): deck.lmp,
    chain.data, scene.toml (the scene as run) and, when the scene was planned, plan.json (the plan,
    and the scene as given, with its "auto" values: collect checks whether granchain run would have
    refined the step). The scene must be concrete (planned). out must not exist; the directory
    appears complete or not at all."""
    out = Path(out)
    if out.exists() or out.is_symlink():
        raise RunDirError(f"{out}: already exists; granchain render --out writes a new directory: choose another")
    files = LAMMPS.input_files(scene)
    files["scene.toml"] = scene_file_text(scene)
    if plan is not None:
        record = plan_to_dict(plan)
        if given is not None:
            record["scene_as_given"] = scene_file_text(given)
        files[PLAN_FILE] = json.dumps(record, indent=2) + "\n"
    parent = out.resolve().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise RunDirError(f"{parent}: cannot create the directory ({e.strerror}); choose another --out") from None
    try:
        with safe_files.atomic_directory(out, None) as tmp:
            for name, text in files.items():
                (tmp / name).write_text(text)
    except OSError as e:
        raise RunDirError(f"{out}: could not write the deck directory ({e}); nothing was left behind") from None
    return out


@dataclass
class LammpsLog:
    """What a plain LAMMPS run's log.lammps says about the run."""

    version_text: str | None  # "22 Jul 2025 - Update 4"
    version: int | None  # 20250722, as the Python module's lammps.version() reports it
    ranks: int | None  # MPI ranks ("Loop time of ... on N procs")
    threads: int | None  # OpenMP threads per rank
    loop_time: float  # s, LAMMPS's loop times added up (every run command)
    total_wall_time: str | None  # "H:MM:SS", once LAMMPS has ended normally
    text: str

    def tail(self, lines: int = 8) -> str:
        return "\n".join(self.text.strip().splitlines()[-lines:])[-1500:]


def read_log(path: Path) -> LammpsLog:
    """What a LAMMPS log says about its run (a CollectError if it is not LAMMPS's, or larger than
    TEXT_LIMIT)."""
    try:
        text = safe_files.read_bytes(path, TEXT_LIMIT).decode("utf-8", "replace")
    except OSError as e:
        raise CollectError(f"{path}: cannot be read ({e})") from None
    m = re.search(r"^LAMMPS \((\d{1,2}) (\w{3}) (\d{4})([^)]*)\)", text, re.M)
    version_text = version = None
    if m:
        version_text = f"{m.group(1)} {m.group(2)} {m.group(3)}{m.group(4)}"
        if m.group(2) in _MONTHS:
            version = int(m.group(3)) * 10000 + _MONTHS[m.group(2)] * 100 + int(m.group(1))
    loops = re.findall(r"^Loop time of (\S+) on (\d+) procs", text, re.M)
    for t, n in loops:
        try:
            ok = math.isfinite(float(t)) and float(t) >= 0 and 0 < int(n) < 10**9
        except ValueError:
            ok = False
        if not ok:
            raise CollectError(
                f"{path}: 'Loop time of {t[:40]} on {n[:20]} procs' is not LAMMPS's (a time and a number of ranks): "
                "the log is damaged; run 'lmp -in deck.lmp' in this directory again"
            )
    if not math.isfinite(sum(float(t) for t, _ in loops)):  # each finite, e.g. 1e308 twice
        raise CollectError(
            f"{path}: its 'Loop time of' lines add up to more than any run takes: the log is damaged; "
            "run 'lmp -in deck.lmp' in this directory again"
        )
    threads = re.search(r"using (\d{1,9}) OpenMP thread", text)
    wall = re.search(r"^Total wall time: (\S+)", text, re.M)
    return LammpsLog(
        version_text=version_text,
        version=version,
        ranks=int(loops[-1][1]) if loops else None,
        threads=int(threads.group(1)) if threads else None,
        loop_time=sum(float(t) for t, _ in loops),
        total_wall_time=wall.group(1) if wall else None,
        text=text,
    )


@dataclass
class CollectedRunResult(LammpsRunResult):
    """A RunResult made from a plain-LAMMPS run: its provenance says so ("collected")."""

    collected: dict = field(default_factory=dict)

    def provenance(self) -> dict:
        """The run's provenance, with where and how the collected run was made."""
        p = super().provenance()
        p["collected"] = self.collected
        return p


def _check_is_render_dir(d: Path) -> None:
    if not d.is_dir():
        raise CollectError(
            f"{d}: no such directory; give a directory written by 'granchain render SCENE --out DIR' and run by LAMMPS"
        )
    _check_files(d)
    missing = [f for f in RENDER_FILES if not (d / f).is_file()]
    if missing:
        raise CollectError(
            f"{d}: has no {', '.join(missing)}: not a directory of 'granchain render SCENE --out DIR' "
            "(collect needs the deck, its data file and the scene it was rendered from)"
        )


def _collected_name(name: str) -> bool:
    return name in RENDER_FILES or name in _READ_NAMES or any(fnmatch.fnmatch(name, g) for g in OUTPUT_GLOBS)


def _check_files(d: Path) -> None:
    """Every file of d collect reads or copies is a regular file (not a symbolic link, a FIFO or a
    device), no larger than it reads; else a CollectError naming it."""
    try:
        with os.scandir(d) as it:
            entries = sorted(it, key=lambda e: e.name)
    except OSError as e:
        raise CollectError(f"{d}: cannot be listed ({e.strerror})") from None
    for e in entries:
        if not _collected_name(e.name):
            continue
        path = d / e.name
        if e.is_symlink():
            raise CollectError(
                f"{path}: is a symbolic link; collect reads and copies only the files LAMMPS wrote in this "
                "directory, never a link's target: remove the link (or copy the file it points to in its place)"
            )
        if not e.is_file(follow_symlinks=False):
            raise CollectError(f"{path}: is not a regular file; collect reads only regular files here: remove it")
        limit = TEXT_LIMIT if e.name in RENDER_FILES or e.name in _READ_NAMES[:4] else DATA_LIMIT
        if e.name in RENDER_FILES or e.name in _READ_NAMES or e.name.startswith(("snapshot_", "histories.")):
            size = e.stat(follow_symlinks=False).st_size
            if size > limit:
                raise CollectError(
                    f"{path}: is {size} bytes, more than the {limit} collect reads from it (damaged, or not what the "
                    "deck writes): run 'lmp -in deck.lmp' in this directory again"
                )


def _check_disk(d: Path, files: dict, out: Path) -> None:
    """Refuse collect --out when the files it copies need more disk than is free there."""
    need = sum(p.stat(follow_symlinks=False).st_size for p in files.values())
    parent = out.absolute().parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    try:
        free = shutil.disk_usage(parent).free
    except OSError:
        return
    if need > free:
        raise CollectError(
            f"{d}: its LAMMPS files take {need / 1e9:.3g} GB, {free / 1e9:.3g} GB is free where --out {out} goes: "
            "free some space or choose another --out (or collect in place, without --out)"
        )


def _check_scene_matches_deck(d: Path, scene, deck: str) -> None:
    m = _HASH_LINE.search(deck)
    if m is None:
        raise CollectError(
            f"{d / 'deck.lmp'}: carries no '# Scene sha256:' line, so scene.toml cannot be checked against it; "
            "render the scene again with 'granchain render SCENE --out DIR' and run that deck"
        )
    have = scene_hash(scene)
    if m.group(1) != have:
        raise CollectError(
            f"{d / 'scene.toml'}: does not match deck.lmp (the deck was rendered from a scene with sha256 "
            f"{m.group(1)[:16]}..., scene.toml's is {have[:16]}...); put back the scene.toml that "
            "'granchain render --out' wrote beside this deck, or render and run the scene again"
        )


def _check_finished(d: Path, scene, log: LammpsLog | None) -> None:
    missing = [f for f in (RUN_END_FILE, RESULTS_DUMP) if not (d / f).is_file()]
    if not missing:
        if log is None or log.total_wall_time is not None:
            return
        raise CollectError(
            f"{d}: the LAMMPS run did not finish: {LOG_FILE} does not end with LAMMPS's 'Total wall time' (LAMMPS "
            f"is still running, or was stopped; the {RESULTS_DUMP} here may be an earlier run's). Last lines of "
            f"{LOG_FILE}:\n{log.tail()}"
        )
    if log is None:
        raise CollectError(
            f"{d}: LAMMPS has not run here (no {LOG_FILE}, no {RESULTS_DUMP}); run 'lmp -in deck.lmp' "
            "(or 'mpirun -np N lmp -in deck.lmp') in this directory, then collect it"
        )
    why = ""
    broken = invariant_from_lammps(LammpsError(log.tail(40), log.tail(40)), scene)
    if broken is not None:
        why = f" LAMMPS stopped it: {broken}."
    elif "ERROR" in log.tail(40):
        why = " LAMMPS stopped with an error (below)."
    raise CollectError(
        f"{d}: the LAMMPS run did not finish: there is no {' and no '.join(missing)}, which the deck writes at "
        f"its very end.{why} Last lines of {LOG_FILE}:\n{log.tail()}"
    )


def _finished_utc(d: Path) -> datetime:
    return datetime.fromtimestamp((d / RESULTS_DUMP).stat().st_mtime, UTC)


def collect(run_dir: str | Path, out: str | Path | None = None, overwrite: bool = False) -> RunResult:
    """Turn a directory of 'granchain render --out' that plain LAMMPS ran into a run directory.

    out None: the run directory's files (peaks.csv, summary.json, energy.csv, histories.csv,
    snapshots.csv) are added to run_dir itself, beside LAMMPS's; otherwise a new run directory out
    is written as `granchain run --out` writes one (overwrite: replace it). Returns the RunResult.
    """
    d = Path(run_dir)
    _check_is_render_dir(d)
    scene = load_scene(d / "scene.toml")
    try:
        deck = safe_files.read_bytes(d / "deck.lmp", TEXT_LIMIT).decode("utf-8", "replace")
    except OSError as e:
        raise CollectError(f"{d / 'deck.lmp'}: cannot be read ({e})") from None
    _check_scene_matches_deck(d, scene, deck)
    log = read_log(d / LOG_FILE) if (d / LOG_FILE).is_file() else None
    _check_finished(d, scene, log)
    if log is None:
        raise CollectError(
            f"{d}: the run finished but left no {LOG_FILE}; collect reads LAMMPS's version, ranks and wall "
            "time from it: run the deck with LAMMPS's default log ('lmp -in deck.lmp'), or copy log.lammps back"
        )
    plan, plan_record = _read_plan(d, scene)
    extra = {
        "lammps_version": log.version,
        "ranks": log.ranks,
        "startup_time": None,
        "process_time": None,
        "plugin_build_time": None,
    }
    try:
        with warnings.catch_warnings():  # an empty file is refused below: no warning before the message
            warnings.filterwarnings("ignore", message="loadtxt: input contained no data")
            base = LAMMPS.read_results(scene, d, log.loop_time, extra)
    except ResultsError as e:
        raise CollectError(
            f"{d}: the LAMMPS run's results cannot be read: {e}. Last lines of {LOG_FILE}:\n{log.tail()}"
        ) from None
    except FileNotFoundError as e:
        raise CollectError(
            f"{e.filename or d}: missing; the deck writes it during the run: run 'lmp -in deck.lmp' in {d} again"
        ) from None
    except _DAMAGED as e:  # a result file that is not what the deck writes (damaged, edited, another deck's)
        raise CollectError(_damaged_message(d, scene, e)) from None
    mark_reflection_pending(base.scene, base.solution)  # as workflows.run marks granchain's own runs
    rendered = _RENDERED_BY.search(deck)
    refinement = _refinement(d, plan_record, plan, base)
    result = CollectedRunResult(
        scene=base.scene,
        backend=base.backend,
        solution=base.solution,
        extra=base.extra,
        plan=plan,
        finished_utc=_finished_utc(d),
        collected={
            "from": "a plain LAMMPS run of the deck (lmp -in deck.lmp or mpirun -np N lmp -in deck.lmp), "
            "collected by granchain collect",
            "run_dir": str(d.resolve()),
            "lammps_version": log.version_text,
            "ranks": log.ranks,
            "openmp_threads": log.threads,
            "lammps_total_wall_time": log.total_wall_time,
            "rendered_by_granchain": rendered.group(1) if rendered else None,
            "collected_utc": datetime.now(UTC).isoformat(timespec="milliseconds"),
            "how": f"wall_time: LAMMPS's loop times added up ({LOG_FILE}); finished_utc: the modification time of "
            f"{RESULTS_DUMP}; started_utc: estimated from them",
            "not_recorded": "the LAMMPS run's command line and host: command, cwd and host are granchain "
            "collect's, and lammps.plugin is this machine's plugin",
            "not_refined": refinement,
        },
    )
    if out is not None:
        files = output_files(d)
        _check_disk(d, files, Path(out))
        write_run_dir(result, out, overwrite=overwrite, extra_files=files)
    else:
        _write_in_place(result, d)
    return result


def _read_plan(d: Path, scene):
    """(Plan, plan.json's record) of a rendered directory; (None, None) when nothing was planned."""
    if not (d / PLAN_FILE).is_file():
        return None, None
    try:
        record = json.loads(safe_files.read_text(d / PLAN_FILE, TEXT_LIMIT))
        if record is not None and not isinstance(record, dict):
            raise TypeError("not a JSON object")
        return plan_from_dict(record, scene), record
    except (ValueError, KeyError, TypeError, RecursionError, OSError) as e:
        raise CollectError(f"{d / PLAN_FILE}: is not the plan 'granchain render --out' wrote ({e})") from None


def _damaged_message(d: Path, scene, err: Exception) -> str:
    """The message of a result file its reader could not take: each file read alone, the first that
    fails named (only on this error path: a good directory is read once)."""
    from granchain.lammps.readback import SENSORS_DUMP
    from granchain.lammps.runner import read_results
    from granchain.postprocess.dumps import read_dump
    from granchain.postprocess.histories import HISTORY_NPY, read_history_table

    def energy(p):
        e = np.loadtxt(p, comments="#", ndmin=2)
        if e.shape[0] < 1 or e.shape[1] < 4:
            raise ValueError(f"{e.shape[0]} rows of {e.shape[1]} columns")

    def load_end(p):
        if np.loadtxt(p, ndmin=1).size < 2:
            raise ValueError("not 'step x1'")

    probes = [
        (RESULTS_DUMP, lambda p: read_results(d)),
        ("energy.txt", energy),
        ("load_end.txt", load_end),
        (HISTORY_NPY, read_history_table),
        *((f"snapshot_{k}.dump", read_dump) for k in range(len(scene.outputs.snapshots))),
        (SENSORS_DUMP, lambda p: read_dump(p, columns=("d_sfc",))),
    ]
    for name, probe in probes:
        if not (d / name).exists():
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                probe(d / name)
        except Exception as e:  # noqa: BLE001 - a probe of a file already known to be damaged somewhere
            why = " ".join(str(e).split())[:240]
            return (
                f"{d / name}: is not what the deck writes ({type(e).__name__}: {why}); it is damaged or another "
                "run's: run 'lmp -in deck.lmp' in this directory again"
            )
    why = " ".join(str(err).split())[:240]
    return (
        f"{d}: LAMMPS's result files here cannot be read ({type(err).__name__}: {why}); they are damaged or not "
        "this deck's: run 'lmp -in deck.lmp' in this directory again"
    )


def _refinement(d: Path, record: dict | None, plan, result) -> dict | None:
    """Whether granchain run would have run this planned scene again at a finer step (its measured
    peaks fell far below the force scale: workflows.plan.refined_plan); then a NotRefinedWarning and
    {"timestep", "reason"} for the provenance. A plain-LAMMPS run is run once."""
    if plan is None or not record or not isinstance(record.get("scene_as_given"), str):
        return None
    given = parse_scene(record["scene_as_given"], source=f"{d / PLAN_FILE} (scene as given)")
    refined = refined_plan(given, plan, result.solution)
    if refined is None:
        return None
    dt = refined.scene.run.timestep
    reason = next(c.reason for c in refined.choices if c.name == "timestep")
    warnings.warn(
        f"{d}: granchain run would run this scene again at timestep = {dt:.4g} s ("
        + reason.split("; refined ", 1)[-1]
        + f"); this plain-LAMMPS run ran once at {plan.scene.run.timestep:.4g} s: for granchain run's accuracy "
        f"set [run] timestep = {dt:.4g} in the scene, render it again and run that deck",
        NotRefinedWarning,
        stacklevel=3,
    )
    return {"timestep": dt, "reason": reason}


def _write_in_place(result: RunResult, d: Path) -> None:
    """Add the run directory's own files to d: written aside (d/.collect-<pid>), then renamed in one by
    one, summary.json last (its presence marks a complete run directory); a previous collect's
    summary.json goes first. scene.toml stays as it is (the same text)."""
    try:
        with safe_files.atomic_files(d, "summary.json", keep=("scene.toml",), prefix=".collect-") as tmp:
            write_run_dir(result, tmp)
    except OSError as e:
        raise RunDirError(
            f"{d}: could not write the run directory's files ({e}); no summary.json was written"
        ) from None


__all__ = ["CollectError", "CollectedRunResult", "NotRefinedWarning", "collect", "read_log", "render_dir"]
