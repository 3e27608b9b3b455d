"""The run directory: where a RunResult is written (atomically) and read back from.

    scene.toml      the scene as given
    summary.json    RunResult.summary() (provenance, price, observables, checks)
    peaks.csv       one row per reported contact (granchain.results describes the columns)
    histories.csv   time, force_<i>, velocity_<i> for each requested contact i (if requested)
    snapshots.csv   time, bead, displacement, velocity, contact_force (if requested)
    energy.csv      time, kinetic, potential, dissipated, work

The directory is written under a hidden temporary name and renamed into place at the end, so an
interrupted run never leaves a directory that looks complete. It carries granchain's marker
(granchain.safe_files.MARKER): ``--overwrite`` replaces only a directory granchain wrote, never one
that holds anything else. Reads and writes never follow a symbolic link planted in it.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import warnings
from pathlib import Path

import numpy as np

from granchain import safe_files
from granchain.exceptions import GranchainError
from granchain.results import RunResult, peak_columns


class RunDirError(GranchainError, RuntimeError):
    """The run directory cannot be written (exists, not writable, disk full, ...) or read (missing,
    damaged, a symbolic link)."""


def owned_by_granchain(d: str | Path) -> bool:
    """Whether granchain wrote the directory d: only its marker (safe_files.MARKER) says so.

    A directory without it is the user's, whatever it holds: a ``summary.json`` beside a
    ``holiday.png`` is not proof (names are anyone's), so ``--overwrite`` never deletes it; the
    refusal says to choose another ``--out`` or remove the directory by hand."""
    return safe_files.is_owned(d)


def check_output_dir(out: str | Path, overwrite: bool = False) -> Path:
    """Fail early (before a run starts) if the run directory cannot be created: it exists (without
    overwrite), it is not a directory granchain wrote (with overwrite: owned_by_granchain), it is a
    symbolic link, or its parent cannot be made or written."""
    out = Path(out)
    try:
        safe_files.check_replaceable(out, overwrite, owned=owned_by_granchain)
    except OSError as e:
        raise RunDirError(str(e)) from None
    parent = out.absolute().parent
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
    with safe_files.create_new(path) as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for row in rows:
            w.writerow(_formatted(row))


def _write_columns(path: Path, header: list[str], columns) -> None:
    """_write_csv of the rows zip(*columns) makes, each column formatted once (_formatted)."""
    _write_csv(path, header, zip(*(_formatted(col) for col in columns), strict=True))


def _formatted(values) -> list:
    """[_fmt(x) for x in values], a numpy array of floats or integers at once: its tolist() gives
    the same doubles and integers as Python numbers, so the same text (_fmt's per-value checks were
    a third of a small run directory's write; benchmarks/RESULTS.md, 2026-12-03)."""
    if isinstance(values, np.ndarray) and values.ndim == 1:
        if values.dtype.kind == "f":
            return [repr(x) if math.isfinite(x) else "nan" for x in values.tolist()]
        if values.dtype.kind in "iu":
            return [str(x) for x in values.tolist()]
    return [_fmt(x) for x in values]


def _fmt(x) -> str:
    if isinstance(x, str):
        return x
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    x = float(x)
    return repr(x) if math.isfinite(x) else "nan"  # (math, not numpy: a third of a small run directory's write)


#: a run directory's sensor bead histories: time, then force_bead_<i> of each sensor bead i
SENSORS_CSV = "sensors.csv"


def write_run_dir(result: RunResult, out: str | Path, overwrite: bool = False, extra_files: dict | None = None) -> Path:
    """Write the run directory atomically; returns its path.

    extra_files: name -> text or source Path, copied in as well (e.g. a LAMMPS deck and log; only a
    regular file is copied, never a symbolic link's target). overwrite replaces only a directory
    granchain wrote (check_output_dir).
    """
    out = check_output_dir(out, overwrite)
    try:
        with safe_files.atomic_directory(out, "run", overwrite=overwrite, owned=owned_by_granchain) as tmp:
            _write_contents(result, tmp, extra_files or {})
    except OSError as e:
        raise RunDirError(f"{out}: could not write the run directory ({e}); nothing was left behind") from None
    return out


def _write_contents(result: RunResult, d: Path, extra_files: dict) -> None:
    sc, s = result.scene, result.solution
    _write_new(d / "scene.toml", sc.source_text if sc.source_text else sc.to_toml())
    cols = peak_columns(result)  # the one source of peaks.csv and RunResult.peaks
    cols["complete"] = cols["complete"].astype(int)
    header, columns = list(cols), list(cols.values())
    _write_columns(d / "peaks.csv", header, columns)
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
    if s.sensor_history_time.size:  # each sensor bead's average force (postprocess.sensors)
        cols = [f"force_bead_{b}" for b in s.sensor_beads]
        _write_csv(
            d / SENSORS_CSV,
            ["time", *cols],
            (np.append(t, f) for t, f in zip(s.sensor_history_time, s.sensor_history_force, strict=True)),
        )
    if s.snapshot_time.size:
        n = sc.chain.beads

        def rows():
            for k, t in enumerate(s.snapshot_time):
                f = np.append(s.snapshot_force[k], 0.0)  # bead N has no right-hand contact
                for b in range(n):
                    yield (t, b + 1, s.snapshot_displacement[k, b], s.snapshot_velocity[k, b], f[b])

        _write_csv(d / "snapshots.csv", ["time", "bead", "displacement", "velocity", "contact_force"], rows())
    _write_columns(
        d / "energy.csv",
        ["time", "kinetic", "potential", "dissipated", "work"],
        [s.energy_time, s.kinetic, s.potential, s.dissipated, s.work],
    )
    for name, content in extra_files.items():
        if Path(name).name != name or name.startswith("."):
            raise ValueError(f"extra file name {name!r}: a plain file name")  # a bug, not the user's
        if isinstance(content, Path):
            safe_files.copy_file(content, d / name, limit=None)
        else:
            _write_new(d / name, content)
    # summary last: its presence marks a complete directory even before the rename
    _write_new(d / "summary.json", json.dumps(result.summary(), indent=2, default=_json_default) + "\n")


def _write_new(path: Path, text: str) -> None:
    with safe_files.create_new(path) as fh:
        fh.write(text)


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(repr(o))


#: the most a reader takes from a run directory's peaks.csv or summary.json (bytes)
READ_LIMIT = 256 * 1024 * 1024


def _read_text(path: Path) -> str:
    try:
        return safe_files.read_text(path, limit=READ_LIMIT)
    except FileNotFoundError:
        raise RunDirError(f"{path}: missing; give a run directory granchain wrote (granchain run --out)") from None
    except OSError as e:
        raise RunDirError(f"{path}: cannot be read ({e})") from None


def read_peaks(run_dir: str | Path) -> dict[str, np.ndarray]:
    """peaks.csv of a run directory as arrays (contact is 1-based; complete, where present, is bool).

    A missing, damaged or linked file is a RunDirError naming it."""
    path = Path(run_dir) / "peaks.csv"
    text = _read_text(path)
    try:
        if not text.strip():
            raise ValueError("empty")
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a damaged table's warnings (lines of other widths): refused
            data = np.genfromtxt(io.StringIO(text), delimiter=",", names=True, ndmin=1, dtype=None, encoding="utf-8")
        names = data.dtype.names
        if not names or "contact" not in names:
            raise ValueError("no 'contact' column")
        out = {name: np.asarray(data[name]) for name in names}
        if out["contact"].dtype.kind not in "iu":
            raise ValueError("the contact column is not whole numbers")
    except (ValueError, TypeError, IndexError, UserWarning) as e:
        raise RunDirError(f"{path}: is not the peak table granchain writes ({e}); run the scene again") from None
    if "complete" in out:
        out["complete"] = out["complete"] == 1
    return out


def read_summary(run_dir: str | Path) -> dict:
    """summary.json of a run directory (a RunDirError naming it when missing, damaged or linked)."""
    path = Path(run_dir) / "summary.json"
    text = _read_text(path)
    try:
        data = json.loads(text)
    except (ValueError, RecursionError) as e:
        raise RunDirError(f"{path}: is not JSON ({str(e)[:200]}); damaged: run the scene again") from None
    if not isinstance(data, dict):
        raise RunDirError(f"{path}: is not the summary granchain writes (not a JSON object); run the scene again")
    return data
