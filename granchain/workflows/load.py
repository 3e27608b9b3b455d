"""A run directory read back into the RunResult that wrote it (granchain.load_run).

A directory of ``granchain run`` (either backend), of ``granchain collect``, or a campaign point's
(its job directory holds the run directory ``run/``) becomes the same result type the run returned
(RunResult, LammpsRunResult, CollectedRunResult), equal to the in-memory result for everything the
directory keeps:

    summary.json    result.summary (as written: provenance, price, observables, error estimates);
                    the solution's method, step, steps, end and wall time, conservation record;
                    result.plan, started_utc, finished_utc, command from its provenance
    scene.toml      result.scene (parsed, source as the summary names it)
    peaks.csv       result.peaks (error columns included); the solution's peak_force, time_of_peak,
                    complete, leading pulse at the measured contacts (nan at the others)
    histories.csv   result.histories; snapshots.csv result.snapshots; energy.csv result.energy

What a directory does not keep stays empty: the final state (displacement, velocity, bilinear
history), the minima after each peak, the companion runs' ErrorReport (result.errors is None; their
numbers are in result.summary["errors"] and result.peaks).

Files are read without following symbolic links: a link planted in a shared directory cannot make
granchain read outside it.
"""

from __future__ import annotations

import glob
import io
import json
import os
import time
from datetime import datetime
from pathlib import Path

import numpy as np

from granchain import safe_files
from granchain.backends import BACKENDS, LAMMPS, REFERENCE, FileIOBackend
from granchain.exceptions import GranchainError
from granchain.physics.event import EVENT_FIELDS
from granchain.physics.event import EVENT_MAXIMA_FIELDS as MAXIMA
from granchain.postprocess.observables import end_summary_keys
from granchain.postprocess.sensors import solution_sensor_fields
from granchain.results import ChainSolution, RunResult, StoredRun, printable
from granchain.rundir import SENSORS_CSV
from granchain.workflows.summary_check import SummaryFieldError, check_summary

#: a campaign point's run directory inside its job directory (granchain.campaigns.workspace.RUN_DIR)
CAMPAIGN_RUN_DIR = "run"


class LoadRunError(GranchainError, ValueError):
    """A directory that is not a complete run directory, or whose files cannot be read."""


def run_dir_of(path: str | Path) -> Path:
    """The run directory path names: path itself, or the run/ of a campaign point's job directory."""
    p = Path(path)
    if not p.is_dir():
        raise LoadRunError(f"{p}: no such directory; give a run directory (granchain run --out, collect)")
    if (p / "summary.json").exists() or (p / "summary.json").is_symlink():
        return p
    if (p / CAMPAIGN_RUN_DIR / "summary.json").exists():
        if (p / CAMPAIGN_RUN_DIR).is_symlink():  # a job directory's run/ is read only as itself
            raise LoadRunError(
                f"{p / CAMPAIGN_RUN_DIR}: is a symbolic link; a campaign point's run/ is read only as itself"
            )
        return p / CAMPAIGN_RUN_DIR
    lam, ref = p / LAMMPS.name, p / REFERENCE.name  # a compare directory's two runs
    if (lam / "summary.json").exists() and (ref / "summary.json").exists():
        raise LoadRunError(
            f"{p}: a compare directory (granchain compare): load each run, load_run('{lam}') and load_run('{ref}')"
        )
    raise LoadRunError(
        f"{p}: not a complete run directory (no summary.json; an interrupted run or a directory of "
        "'granchain render' not yet collected: run 'granchain collect' on it)"
    )


def read_text(d: Path, name: str) -> str:
    """The text of file name in directory d: a regular file, never read through a symbolic link, of
    bounded size (granchain.safe_files); anything else is a LoadRunError naming the file and the fix.
    A UTF-8 byte-order mark (as spreadsheet programs save a CSV file) is not part of the text."""
    path = d / name
    try:
        return safe_files.read_text(path).removeprefix("\ufeff")
    except FileNotFoundError:
        raise LoadRunError(f"{path}: missing; the run directory is incomplete") from None
    except safe_files.UnsafeFileError as e:
        raise LoadRunError(str(e)) from None
    except OSError as e:
        raise LoadRunError(f"{path}: cannot be read ({e.strerror})") from None


def _csv(d: Path, name: str, **kw):
    import pandas as pd

    # numbers exactly as written (repr): pandas 3 parses them so by default, pandas 2 with round_trip
    exact = {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
    try:
        return pd.read_csv(io.StringIO(read_text(d, name)), **exact, **kw)
    except (ValueError, pd.errors.ParserError) as e:
        raise LoadRunError(f"{d / name}: not a granchain CSV table ({e})") from None


def _peak_column(path: Path, name: str, cells: np.ndarray) -> np.ndarray:
    """One column of peaks.csv (read as text) as the array granchain wrote: contact whole numbers,
    complete 0 or 1, error_status text, every other column floats ("nan" where not measured)."""
    if name == "error_status":
        return cells.astype(object)
    try:
        if name == "contact":
            return cells.astype(np.int64)
        if name == "complete":
            if not np.isin(cells, ("0", "1")).all():
                raise ValueError("not 0 or 1")
            return cells == "1"
        return cells.astype(np.float64)
    except (ValueError, OverflowError):
        bad = next((str(x) for x in cells if not _parses(x, name)), "?")
        what = {"contact": "a contact number", "complete": "0 or 1"}.get(name, "a number")
        raise LoadRunError(
            f"{path}: column {printable(name)!r} holds {printable(bad[:40])!r}, not {what}; the table is damaged "
            "(edited, or not granchain's): run the scene again"
        ) from None


def _parses(cell, name: str) -> bool:
    try:
        if name == "contact":
            int(cell)
        elif name == "complete":
            return cell in ("0", "1")
        else:
            float(cell)
    except (ValueError, OverflowError):
        return False
    return True


def _read_peaks(d: Path, beads: int) -> dict[str, np.ndarray]:
    """peaks.csv's columns (see RunResult.peaks); its contacts those of a chain of beads beads."""
    path = d / "peaks.csv"
    df = _csv(d, "peaks.csv", dtype=str, keep_default_na=False)
    out = {str(h): _peak_column(path, str(h), df[h].to_numpy(dtype=str)) for h in df.columns}
    if "contact" not in out or "peak_force" not in out:
        raise LoadRunError(f"{path}: has no contact or peak_force column; not the peak table granchain writes")
    c = out["contact"]
    wrong = c[(c < 1) | (c > beads - 1)]
    if wrong.size:
        raise LoadRunError(
            f"{path}: contact {wrong[0]} is not a contact of the {beads}-bead chain of scene.toml (contacts are "
            f"numbered 1 to {beads - 1}); the table is damaged or another scene's: run the scene again"
        )
    if np.unique(c).size != c.size:
        raise LoadRunError(f"{path}: names a contact twice; the table is damaged: run the scene again")
    return out


def _scene(d: Path, summary: dict):
    from granchain.scene import SceneError, parse_scene

    text = read_text(d, "scene.toml")
    try:
        return parse_scene(text, source=summary.get("scene_source") or str(d / "scene.toml"))
    except SceneError as e:  # named by the scene's own source: say which run directory's it is
        raise LoadRunError(f"{d / 'scene.toml'}: {printable(str(e), 500)}") from None


def _time(text: str | None) -> datetime | None:
    return None if text is None else datetime.fromisoformat(text)


def _solution(d: Path, scene, summary: dict, peaks: dict) -> ChainSolution:
    n = int(scene.chain.beads)
    idx = np.asarray(peaks["contact"], dtype=np.int64) - 1

    def along(name: str, fill=np.nan, dtype=np.float64):
        a = np.full(n - 1, fill, dtype=dtype)
        if name in peaks:
            a[idx] = peaks[name]
        return a

    c = summary.get("conservation") or {}
    price = summary.get("price") or {}
    kw: dict = {}
    if (d / "energy.csv").exists() or (d / "energy.csv").is_symlink():
        e = _csv(d, "energy.csv")
        kw.update({k: e[k].to_numpy(np.float64) for k in ("kinetic", "potential", "dissipated", "work")})
        kw["energy_time"] = e["time"].to_numpy(np.float64)
    if (d / "histories.csv").exists() or (d / "histories.csv").is_symlink():
        h = _csv(d, "histories.csv")
        fcols = [x for x in h.columns if x.startswith("force_")]
        vcols = [f"velocity_{x.split('_', 1)[1]}" for x in fcols]
        if list(h.columns) != ["time", *fcols, *vcols]:
            raise LoadRunError(
                f"{d / 'histories.csv'}: columns {', '.join(map(str, h.columns))}; granchain writes time, "
                "force_<i>... then velocity_<i>... (damaged: run the scene again)"
            )
        kw["history_contacts"] = tuple(int(x.split("_", 1)[1]) - 1 for x in fcols)
        kw["history_time"] = h["time"].to_numpy(np.float64)
        kw["history_force"] = h[fcols].to_numpy(np.float64)
        kw["history_velocity"] = h[vcols].to_numpy(np.float64)
    if (d / "snapshots.csv").exists() or (d / "snapshots.csv").is_symlink():
        s = _csv(d, "snapshots.csv")
        t = s["time"].to_numpy(np.float64)
        times = t[::n] if t.size else t  # n rows (beads 1..N) per snapshot, in order
        if t.size != times.size * n or not np.array_equal(s["bead"].to_numpy()[:n], np.arange(1, n + 1)):
            raise LoadRunError(f"{d / 'snapshots.csv'}: not {n} rows (beads 1..{n}) per snapshot time")
        kw["snapshot_time"] = times
        kw["snapshot_displacement"] = s["displacement"].to_numpy(np.float64).reshape(times.size, n)
        kw["snapshot_velocity"] = s["velocity"].to_numpy(np.float64).reshape(times.size, n)
        kw["snapshot_force"] = s["contact_force"].to_numpy(np.float64).reshape(times.size, n)[:, : n - 1]
    kw.update(_sensors(d, scene, summary))
    steps = int(summary["steps"])
    return ChainSolution(
        method=summary["method"],
        timestep=float(summary["timestep"]),
        steps=steps,
        wall_time=float(summary["wall_time"]),
        end_time=float(summary["end_time"]),
        peak_force=along("peak_force"),
        time_of_peak=along("time_of_peak"),
        complete=along("complete", False, bool),
        leading_pulse_force=along("leading_pulse_force"),
        leading_pulse_time=along("arrival_time"),
        impulse_delivered=float(c.get("impulse_delivered", 0.0)),
        momentum=float(c.get("momentum", 0.0)),
        extra_steps=max(int(price.get("steps", steps)) - steps, 0),
        **{k: summary.get(k) for k in end_summary_keys()},  # the end contacts' peaks
        **{k: v for k, v in (summary.get("event") or {}).items() if k in EVENT_FIELDS},
        **{k: np.asarray(v, dtype=float) for k, v in (summary.get("event_maxima") or {}).items() if k in MAXIMA},
        **kw,
    )


def _sensors(d: Path, scene, summary: dict) -> dict:
    """A run directory's sensor beads as the solution holds them: their peaks from summary.json's
    ``sensors`` (postprocess.sensors.solution_sensor_fields) and their histories from sensors.csv."""
    kw = solution_sensor_fields(scene, summary.get("sensors"))
    if kw and ((d / SENSORS_CSV).exists() or (d / SENSORS_CSV).is_symlink()):
        h = _csv(d, SENSORS_CSV)
        cols = [f"force_bead_{b}" for b in kw["sensor_beads"]]
        if list(h.columns) != ["time", *cols]:
            raise LoadRunError(
                f"{d / SENSORS_CSV}: columns {', '.join(map(str, h.columns))}; granchain writes time, "
                f"{', '.join(cols)} (damaged: run the scene again)"
            )
        kw["sensor_history_time"] = h["time"].to_numpy(np.float64)
        kw["sensor_history_force"] = h[cols].to_numpy(np.float64)
    return kw


#: how many times load_run reads a directory that another process is replacing meanwhile
_ATTEMPTS = 8


class _Changed(Exception):
    """The run directory changed while it was read (run --overwrite, collect): read it again."""


def _identity(path: Path, fd: int | None = None):
    """What tells one summary.json from the next written at the same path: its inode, size and
    modification time, None if absent. ``fd``: the file held open, whose inode no new file can take
    (a freed inode number is reused, and times are coarser than a fast writer)."""
    try:
        st = os.fstat(fd) if fd is not None else os.lstat(path)
    except OSError:
        return None
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


def load_run(path: str | Path) -> RunResult:
    """A run directory read back as the RunResult that wrote it (see the module docstring).

    Every file is one run's: a directory replaced while it is read (``granchain run --overwrite``,
    ``granchain collect``) is read again, so the result never mixes the tables of two runs.

    Parameters
    ----------
    path : str or pathlib.Path
        A run directory (``granchain run --out``, ``granchain collect``), or a campaign point's job
        directory (its ``run/``).

    Returns
    -------
    granchain.results.RunResult
        LammpsRunResult for a LAMMPS run, CollectedRunResult for a collected one; ``result.path`` is
        the directory.

    Raises
    ------
    LoadRunError
        (a GranchainError) the directory is missing, incomplete, holds a file that is a symbolic
        link or not granchain's, or a summary.json field of the wrong type (named).
    """
    for attempt in range(_ATTEMPTS):
        try:
            return _load_once(Path(path))
        except _Changed:
            time.sleep(0.002 * 2**attempt)
    raise LoadRunError(
        f"{path}: changed each of the {_ATTEMPTS} times it was read (another process is writing it: "
        "granchain run --overwrite or collect); load it when that has finished"
    )


def _being_replaced(p: Path) -> bool:
    """Whether p is absent because atomic_directory is between its two renames (its old or its new
    version is beside it under a hidden name), or its summary.json because collect is renaming its
    new files in (safe_files.atomic_files: they are written in p/.collect-PID first)."""
    if not os.path.lexists(p):
        return any(p.parent.glob(f".{glob.escape(p.name)}.[op][la]*-*"))
    return not os.path.lexists(p / "summary.json") and any(p.glob(".collect-*"))


def _load_once(p: Path) -> RunResult:
    """load_run's one reading of the directory; _Changed when summary.json is not the same file at
    the end of it as at its start (the directory was replaced or rewritten meanwhile)."""
    try:
        d = run_dir_of(p)
    except LoadRunError:
        if _being_replaced(p) or os.path.lexists(p / "summary.json"):  # (absent a moment ago)
            raise _Changed from None
        raise
    try:  # held open while the directory is read: its inode stays this file's
        held = os.open(d / "summary.json", os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        held = None  # missing or a link: _read_run says so
    try:
        before = _identity(d / "summary.json", held) if held is not None else None
        try:
            result = _read_run(d)
        except LoadRunError:
            if _identity(d / "summary.json") != before or _being_replaced(p):
                raise _Changed from None
            raise
        if before is None or _identity(d / "summary.json") != before:
            raise _Changed
        return result
    finally:
        if held is not None:
            os.close(held)


def _read_summary(d: Path) -> dict:
    """summary.json, parsed and checked against its schema (workflows.summary_check)."""
    where = d / "summary.json"
    try:
        summary = json.loads(read_text(d, "summary.json"))
    except (json.JSONDecodeError, RecursionError) as e:
        raise LoadRunError(f"{where}: not JSON ({str(e)[:200]}); the run directory is damaged") from None
    try:
        check_summary(summary)
    except SummaryFieldError as e:
        raise LoadRunError(
            f"{where}: {printable(str(e), 300)}; not the summary granchain writes (damaged or edited): "
            "run the scene again"
        ) from None
    return summary


def _read_run(d: Path) -> RunResult:
    summary = _read_summary(d)
    scene = _scene(d, summary)
    peaks = _read_peaks(d, int(scene.chain.beads))
    try:
        solution = _solution(d, scene, summary, peaks)
    except (KeyError, TypeError, ValueError, IndexError) as e:
        raise LoadRunError(
            f"{d}: its summary.json or tables do not fit together ({type(e).__name__}: {printable(str(e), 300)}); "
            "the run directory is damaged: run the scene again"
        ) from None
    prov = summary.get("provenance") or {}
    from granchain.workflows.collect import plan_from_dict

    kw = {
        "scene": scene,
        "backend": summary["backend"],
        "solution": solution,
        "extra": dict(summary.get("extra") or {}),
        "plan": plan_from_dict(prov.get("plan"), scene),
        "started_utc": _time(prov.get("started_utc")) if prov.get("start_time") == "measured" else None,
        "command": prov.get("command"),
        "method_reason": summary.get("method_reason"),
        "path": d,
        "stored": StoredRun(summary=summary, peaks=peaks),
    }
    if prov.get("finished_utc"):
        kw["finished_utc"] = _time(prov["finished_utc"])
    backend = BACKENDS.get(summary["backend"])
    if backend is None:
        return RunResult(**kw)
    if isinstance(backend, FileIOBackend) and "collected" in prov:  # a run made elsewhere, collected
        from granchain.workflows.collect import CollectedRunResult

        return CollectedRunResult(**kw, collected=prov["collected"])
    return backend.result_type(**kw)
