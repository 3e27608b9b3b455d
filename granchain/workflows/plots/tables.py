"""A run's data as the figures read it: the peak table, the histories and snapshots as their CSV files
have them, and a RunResult from a result or a run directory."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from granchain.physics.effects.gravity import scene_static_forces
from granchain.results import RunResult
from granchain.workflows.load import LoadRunError, load_run
from granchain.workflows.plots.canvas import (
    PlotError,
)


@dataclass
class Peaks:
    """peaks.csv of a run directory, with or without its complete column."""

    contact: np.ndarray  # 1-based
    peak_force: np.ndarray  # N
    time_of_peak: np.ndarray  # s; nan where the wave never reached the contact
    complete: np.ndarray  # bool; all True when the file has no complete column
    has_complete: bool  # whether the file has a complete column
    error: np.ndarray | None = None  # peak_force_error (N; nan where not estimated), None without the column

    @property
    def reached(self) -> np.ndarray:
        """Contacts with a peak: reached by the wave (a time of peak) and a positive force."""
        return np.isfinite(self.time_of_peak) & (self.peak_force > 0)


def load_peaks(run) -> Peaks:
    """The peak table of a run (a RunResult or a run directory; the complete column is optional)."""
    df = as_result(run).peaks
    has = "complete" in df.columns
    contact = df.index.to_numpy().astype(float)
    complete = df["complete"].to_numpy(bool) if has else np.ones(contact.shape, bool)
    error = df["peak_force_error"].to_numpy(float) if "peak_force_error" in df.columns else None
    return Peaks(contact, df["peak_force"].to_numpy(float), df["time_of_peak"].to_numpy(float), complete, has, error)


def static_forces(r: RunResult) -> np.ndarray | None:
    """Each contact's static force (N; scene_static_forces: the N-1 bead-bead contacts, then a wall's),
    the force the run reports its forces above (F - F_static, as leading_peak_force); None where every
    contact starts unloaded (no precompression, no gravity): the figures then show the contact force."""
    static = scene_static_forces(r.scene)
    return static if np.any(static) else None


def one_static_force(static: np.ndarray) -> bool:
    """Whether every contact has one static force (F0 alone; gravity gives each its own)."""
    return bool(np.allclose(static, static[0], rtol=1e-12, atol=0.0))


def force_label(static: np.ndarray | None, what: str, symbol: str, total: str, split: bool = False) -> str:
    """An axis label saying which force it shows: `total` without a static force (or no contact); else the
    dynamic force `symbol` less F_0 (one value on every contact, given in the label) or less F_{0,i} (each
    contact's own: gravity's weight above it), in the peaks figure's words ("dynamic peak force $F_p -
    F_0$"); split: the unit on a second line (a short panel's axis holds no longer line)."""
    if static is None or not np.size(static):
        return total
    gap = "\n" if split else " "
    if one_static_force(static):
        return rf"dynamic {what} ${symbol} - F_0${gap}(N, $F_0$ = {float(static[0]):g} N)"
    return rf"dynamic {what} ${symbol} - F_{{0,i}}${gap}(N)"


def dynamic_peaks(r: RunResult, pk: Peaks) -> tuple[Peaks, str, str, str, str]:
    """The peaks the run reports (above each contact's own static force under precompression or gravity,
    as leading_peak_force is; else the contact force), the y axes' labels saying which force they are, the
    CSV column's name and the markers' legend."""
    static = static_forces(r)
    label = force_label(static, "peak force", "F_p", r"peak contact force $F_p$ (N)")
    if static is None:
        return pk, label, r"$F_p \,/\, (E^* R^{*2})$ (1)", "peak_force", "peak force"
    index = np.clip(pk.contact.astype(int) - 1, 0, static.size - 1)
    dynamic = dataclasses.replace(pk, peak_force=pk.peak_force - static[index])
    if one_static_force(static):
        what, f0 = "peak force above F0", "F_0"
    else:  # gravity: the weight above each contact, with any precompression (the legend says so)
        what, f0 = r"peak force above $F_{0,i}$, each contact's static force", "F_{0,i}"
    return dynamic, label, rf"$(F_p - {f0}) \,/\, (E^* R^{{*2}})$ (1)", "dynamic_peak_force", what


def dynamic_histories(r: RunResult) -> tuple[list[str], np.ndarray, np.ndarray | None]:
    """The histories as the figures show them: _histories_table's header and data with each contact's
    force less its static force (static_forces) where it has one, and those static forces (None: the
    contact force as it is)."""
    header, data = _histories_table(r)
    static = static_forces(r)
    if static is not None:
        data = data.copy()
        for i, h in enumerate(header):
            if h.startswith("force_"):
                data[:, i] -= static[int(h.split("_")[1]) - 1]
    return header, data, static


def csv_name(name: str, static: np.ndarray | None) -> str:
    """A figure's CSV column of a force as plotted: dynamic_<name> where it is the dynamic force (as
    peaks.csv's dynamic_peak_force), name as it is otherwise."""
    return name if static is None else f"dynamic_{name}"


def as_result(run) -> RunResult:
    """A RunResult as it is, or a run directory read back (granchain.load_run); a directory that is not
    one is a PlotError."""
    if isinstance(run, RunResult):
        return run
    run = Path(run)
    try:
        return load_run(run)
    except LoadRunError as e:
        raise PlotError(str(e)) from None


def _histories_table(r: RunResult) -> tuple[list[str], np.ndarray]:
    """The histories as histories.csv has them: header and (samples, 1 + 2 contacts) data."""
    s = r.solution
    c = [i + 1 for i in s.history_contacts]
    header = ["time", *[f"force_{i}" for i in c], *[f"velocity_{i}" for i in c]]
    t = np.asarray(s.history_time, float)
    f = np.asarray(s.history_force, float).reshape(t.size, len(c))
    v = np.asarray(s.history_velocity, float).reshape(t.size, len(c))
    return header, np.column_stack([t, f, v])


def _snapshots_table(r: RunResult) -> np.ndarray:
    """The snapshots as snapshots.csv has them: rows (time, bead, displacement, velocity, contact_force)."""
    s, n = r.solution, int(r.scene.chain.beads)
    t = np.asarray(s.snapshot_time, float)
    k = t.size
    force = np.column_stack([np.asarray(s.snapshot_force, float).reshape(k, n - 1), np.zeros(k)])
    return np.column_stack(
        [
            np.repeat(t, n),
            np.tile(np.arange(1, n + 1, dtype=float), k),
            np.asarray(s.snapshot_displacement, float).reshape(k * n),
            np.asarray(s.snapshot_velocity, float).reshape(k * n),
            force.reshape(k * n),
        ]
    )
