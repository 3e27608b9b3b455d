"""The run directory: where a RunResult is written (atomically) and read back from.

    scene.toml      the scene as given
    summary.json    RunResult.summary() (provenance, price, observables, checks)
    peaks.csv       one row per reported contact (granchain.results describes the columns)
    histories.csv   time, force_<i>, velocity_<i> for each requested contact i (if requested)
    snapshots.csv   time, bead, displacement, velocity, contact_force (if requested)
    energy.csv      time, kinetic, potential, dissipated, work

The directory is written under a hidden temporary name and renamed into place at the end, so an
interrupted run never leaves a directory that looks complete.
"""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
from pathlib import Path

import numpy as np

from granchain.errors import GranchainError
from granchain.results import RunResult


class RunDirError(GranchainError, RuntimeError):
    """The run directory cannot be written (exists, not writable, disk full, ...)."""


def check_output_dir(out: str | Path, overwrite: bool = False) -> Path:
    """Fail early (before a run starts) if the run directory cannot be created."""
    out = Path(out)
    if out.exists() and not overwrite:
        raise RunDirError(f"{out}: already exists; choose another --out or pass --overwrite to replace it")
    if out.exists() and not out.is_dir():
        raise RunDirError(f"{out}: exists and is not a directory; choose another --out")
    parent = out.resolve().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise RunDirError(
            f"{parent}: cannot create the parent directory of the run ({e.strerror}); choose another --out"
        ) from None
    if not os.access(parent, os.W_OK):
        raise RunDirError(f"{parent}: is not writable; choose another --out")
    return out


def _write_csv(path: Path, header: list[str], rows) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for row in rows:
            w.writerow([_fmt(x) for x in row])


def _fmt(x) -> str:
    if isinstance(x, str):
        return x
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    x = float(x)
    return repr(x) if math.isfinite(x) else "nan"  # (math, not numpy: a third of a small run directory's write)


def write_run_dir(result: RunResult, out: str | Path, overwrite: bool = False, extra_files: dict | None = None) -> Path:
    """Write the run directory atomically; returns its path.

    extra_files: name -> text or source Path, copied in as well (e.g. a LAMMPS deck and log).
    """
    out = check_output_dir(out, overwrite)
    parent = out.resolve().parent
    tmp = parent / f".{out.name}.partial-{os.getpid()}"
    for stale in parent.glob(f".{out.name}.partial-*"):  # left by a killed writer (or this pid's past)
        pid = stale.name.rsplit("-", 1)[-1]
        if stale == tmp or (pid.isdigit() and not pid_alive(int(pid))):
            shutil.rmtree(stale, ignore_errors=True)
    try:
        tmp.mkdir()
        _write_contents(result, tmp, extra_files or {})
        if out.exists():
            old = parent / f".{out.name}.old-{os.getpid()}"
            os.replace(out, old)
            os.replace(tmp, out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, out)
    except OSError as e:
        shutil.rmtree(tmp, ignore_errors=True)
        raise RunDirError(f"{out}: could not write the run directory ({e}); nothing was left behind") from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out


def pid_alive(pid: int) -> bool:
    """Whether a process exists (stale partial run and LAMMPS work directories name their writer)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _write_contents(result: RunResult, d: Path, extra_files: dict) -> None:
    sc, s = result.scene, result.solution
    (d / "scene.toml").write_text(sc.source_text if sc.source_text else sc.to_toml())
    contacts = np.asarray(sc.peak_contacts, dtype=int)
    idx = contacts - 1
    header = [
        "contact",
        "peak_force",
        "time_of_peak",
        "peak_force_nondim",
        "complete",
        "leading_pulse_force",
        "arrival_time",
    ]
    columns = [
        contacts,
        s.peak_force[idx],
        s.time_of_peak[idx],
        s.peak_force[idx] / sc.force_scale,
        s.complete[idx].astype(int),
        s.leading_pulse_force[idx],
        s.leading_pulse_time[idx],
    ]
    e = result.errors
    if e is not None and e.peak_force is not None:
        # nan where there is no estimate; error_status says why (granchain.errorbars)
        header += ["peak_force_error", "time_of_peak_error", "error_status"]
        status = [str(x).replace(",", ";") for x in e.peak_force.status[idx]]  # one CSV cell each
        columns += [e.peak_force.error[idx], e.time_of_peak.error[idx], status]
    _write_csv(d / "peaks.csv", header, zip(*columns, strict=True))
    if s.history_contacts:
        cols = [f"force_{i + 1}" for i in s.history_contacts] + [f"velocity_{i + 1}" for i in s.history_contacts]
        _write_csv(
            d / "histories.csv",
            ["time", *cols],
            (
                np.concatenate(([t], f, v))
                for t, f, v in zip(s.history_time, s.history_force, s.history_velocity, strict=True)
            ),
        )
    if s.snapshot_time.size:
        n = sc.chain.beads

        def rows():
            for k, t in enumerate(s.snapshot_time):
                f = np.append(s.snapshot_force[k], 0.0)  # bead N has no right-hand contact
                for b in range(n):
                    yield (t, b + 1, s.snapshot_displacement[k, b], s.snapshot_velocity[k, b], f[b])

        _write_csv(d / "snapshots.csv", ["time", "bead", "displacement", "velocity", "contact_force"], rows())
    _write_csv(
        d / "energy.csv",
        ["time", "kinetic", "potential", "dissipated", "work"],
        zip(s.energy_time, s.kinetic, s.potential, s.dissipated, s.work, strict=True),
    )
    for name, content in extra_files.items():
        if isinstance(content, Path):
            shutil.copyfile(content, d / name)
        else:
            (d / name).write_text(content)
    # summary last: its presence marks a complete directory even before the rename
    (d / "summary.json").write_text(json.dumps(result.summary(), indent=2, default=_json_default) + "\n")


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(repr(o))


def read_peaks(run_dir: str | Path) -> dict[str, np.ndarray]:
    """peaks.csv of a run directory as arrays (contact is 1-based; complete, where present, is bool)."""
    data = np.genfromtxt(Path(run_dir) / "peaks.csv", delimiter=",", names=True, ndmin=1, dtype=None, encoding="utf-8")
    out = {name: np.asarray(data[name]) for name in data.dtype.names}
    if "complete" in out:
        out["complete"] = out["complete"] == 1
    return out


def read_summary(run_dir: str | Path) -> dict:
    return json.loads((Path(run_dir) / "summary.json").read_text())
