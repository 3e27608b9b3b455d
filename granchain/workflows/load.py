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

import io
import json
from datetime import datetime
from pathlib import Path

import numpy as np

from granchain import safe_files
from granchain.backends import BACKENDS, LAMMPS, REFERENCE, FileIOBackend
from granchain.exceptions import GranchainError
from granchain.results import ChainSolution, RunResult, StoredRun

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
    bounded size (granchain.safe_files); anything else is a LoadRunError naming the file and the fix."""
    path = d / name
    try:
        return safe_files.read_text(path)
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


def _read_peaks(d: Path) -> dict[str, np.ndarray]:
    text = read_text(d, "peaks.csv")
    header = text.split("\n", 1)[0].strip().split(",")
    floats = [h for h in header if h not in ("contact", "complete", "error_status")]
    df = _csv(
        d,
        "peaks.csv",
        keep_default_na=False,
        na_values={h: ["nan"] for h in floats},
        dtype={"error_status": str, "contact": np.int64},
    )
    out: dict[str, np.ndarray] = {}
    for h in header:
        v = df[h].to_numpy()
        if h == "complete":
            v = v.astype(np.int64) == 1
        elif h == "error_status":
            v = v.astype(object)
        elif h != "contact":
            v = v.astype(np.float64)
        out[h] = v
    return out


def _scene(d: Path, summary: dict):
    from granchain.scene import parse_scene

    return parse_scene(read_text(d, "scene.toml"), source=summary.get("scene_source") or str(d / "scene.toml"))


def _time(text: str | None) -> datetime | None:
    return None if text is None else datetime.fromisoformat(text)


def _flag(summary: dict, name: str) -> bool | None:
    """A true/false field of summary.json (None where absent): anything else is a damaged summary."""
    value = summary.get(name)
    if value is not None and not isinstance(value, bool):
        raise ValueError(f"{name} = {value!r} is not true or false")
    return value


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
        wall_peak_force=summary.get("wall_peak_force"),
        wall_peak_complete=_flag(summary, "wall_peak_complete"),
        striker_peak_force=summary.get("striker_peak_force"),
        striker_peak_complete=_flag(summary, "striker_peak_complete"),
        striker_velocity=summary.get("striker_velocity"),
        **kw,
    )


def load_run(path: str | Path) -> RunResult:
    """A run directory read back as the RunResult that wrote it (see the module docstring).

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
        (a GranchainError) the directory is missing, incomplete, or holds a file that is a symbolic
        link or not granchain's.
    """
    d = run_dir_of(path)
    try:
        summary = json.loads(read_text(d, "summary.json"))
    except json.JSONDecodeError as e:
        raise LoadRunError(f"{d / 'summary.json'}: not JSON ({e}); the run directory is damaged") from None
    if not isinstance(summary, dict) or "backend" not in summary or "steps" not in summary:
        raise LoadRunError(f"{d / 'summary.json'}: not a granchain run summary (no backend or steps)")
    scene = _scene(d, summary)
    peaks = _read_peaks(d)
    if "contact" not in peaks or "peak_force" not in peaks:
        raise LoadRunError(
            f"{d / 'peaks.csv'}: has no contact or peak_force column; not the peak table granchain writes"
        )
    try:
        solution = _solution(d, scene, summary, peaks)
    except (KeyError, TypeError, ValueError, IndexError) as e:
        raise LoadRunError(
            f"{d}: its summary.json or tables do not fit together ({type(e).__name__}: {e}); the run directory "
            "is damaged: run the scene again"
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
        "method_reason": summary.get("method_reason") if isinstance(summary.get("method_reason"), str) else None,
        "path": d,
        "stored": StoredRun(summary=summary, peaks=peaks),
    }
    if prov.get("finished_utc"):
        kw["finished_utc"] = _time(prov["finished_utc"])
    backend = BACKENDS.get(summary["backend"]) if isinstance(summary["backend"], str) else None
    if backend is None:
        return RunResult(**kw)
    if isinstance(backend, FileIOBackend) and "collected" in prov:  # a run made elsewhere, collected
        from granchain.workflows.collect import CollectedRunResult

        return CollectedRunResult(**kw, collected=prov["collected"])
    return backend.result_type(**kw)
