"""The x-t heat map: contact force over contact index and time, from the whole-chain time data a run
has (a LAMMPS dump, enough snapshots or enough history contacts; never interpolated), reduced by block
maxima to a drawable size."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.colors import LogNorm, Normalize
from matplotlib.figure import Figure

from granchain.results import RunResult
from granchain.workflows.plots.canvas import (
    CONTACT_LABEL,
    PlotError,
    _cmap,
    _label,
    _plain,
    _save,
    _time_unit,
    _write_csv,
    canvas,
    check_formats,
)
from granchain.workflows.plots.tables import (
    _histories_table,
    _snapshots_table,
    as_result,
    csv_name,
    force_label,
    static_forces,
)

logger = logging.getLogger(__name__)

#: a heat map needs at least this many frames (times) and this many contacts: fewer, and the
#: picture would be an interpolation of a handful of lines, not the wave
HEATMAP_MIN_FRAMES = 20


HEATMAP_MIN_CONTACTS = 10


#: at most this many cells along each heat-map axis; denser data is reduced by the maximum over
#: blocks (a narrow pulse stays visible, as it would not with plain subsampling)
HEATMAP_MAX_CELLS = 1500


#: the log colour scale spans at most this many decades below the largest force; weaker forces
#: (and open contacts, F = 0) take the colour of the bottom of the scale
HEATMAP_DECADES = 4


@dataclass
class SpaceTime:
    """Contact force over time and contact: what the heat map draws."""

    time: np.ndarray  # (frames,) s
    contacts: np.ndarray  # (contacts,) 1-based contact indices
    force: np.ndarray  # (frames, contacts) N
    source: str  # where the data came from, for the figure


def _dump_file(r: RunResult) -> Path | None:
    """The run directory's whole-chain dump chain.dump, if it has one (never through a link)."""
    if r.path is None:
        return None
    p = Path(r.path) / "chain.dump"
    if p.is_symlink():
        raise PlotError(f"{p}: is a symbolic link; a run directory's files are read only as themselves")
    return p if p.is_file() else None


def _from_dump(r: RunResult, dump: Path) -> SpaceTime:
    """The whole-chain LAMMPS dump (chain.dump, written every [outputs] dump_interval)."""
    from granchain.postprocess.dumps import read_dump
    from granchain.schedule import scene_step_plan, step_times
    from granchain.templates import atom_layout

    scene = r.scene
    times = step_times(scene_step_plan(scene), scene.run.timestep)
    dd = read_dump(dump, times, columns=("d_fc",))
    o, n = atom_layout(scene)["offset"], scene.chain.beads
    force = dd.columns["d_fc"][:, o : o + n - 1]  # contact i lives on bead i's atom
    return SpaceTime(dd.time, np.arange(1, n), force, "whole-chain dump chain.dump")


def _from_snapshots(r: RunResult) -> SpaceTime:
    data = _snapshots_table(r)
    c = {k: data[:, i] for i, k in enumerate(("time", "bead", "displacement", "velocity", "contact_force"))}
    times = np.unique(c["time"])
    beads = np.unique(c["bead"])
    force = np.full((times.size, beads.size), np.nan)
    force[np.searchsorted(times, c["time"]), np.searchsorted(beads, c["bead"])] = c["contact_force"]
    # the last bead has no right-hand contact
    return SpaceTime(times, beads[:-1].astype(int), force[:, :-1], f"snapshots.csv ({times.size} snapshots)")


def _from_histories(r: RunResult) -> SpaceTime:
    header, data = _histories_table(r)
    fcols = [i for i, h in enumerate(header) if h.startswith("force_")]
    contacts = np.array([int(header[i].split("_")[1]) for i in fcols])
    return SpaceTime(data[:, 0], contacts, data[:, fcols], f"histories.csv ({contacts.size} contacts)")


def spacetime_force(run) -> tuple[SpaceTime | None, str]:
    """Contact force over time and the whole chain, from what the run directory has; or None and why not.

    Sources, best first: the whole-chain LAMMPS dump (chain.dump, [outputs] dump_interval); snapshots.csv
    with at least HEATMAP_MIN_FRAMES snapshot times; histories.csv with at least HEATMAP_MIN_CONTACTS
    contacts and HEATMAP_MIN_FRAMES samples. Nothing is interpolated between contacts or frames.
    """
    r = as_result(run)
    if int(r.scene.chain.beads) < 2:  # (its 20 snapshots made a heat map of no column, and max() of it raised)
        return None, "one bead: no bead-bead contact whose force a heat map could show"
    why = []
    dump = _dump_file(r)
    if dump is not None:
        return _from_dump(r, dump), ""
    why.append("no whole-chain dump (chain.dump: a LAMMPS run with [outputs] dump_interval)")
    if np.size(r.solution.snapshot_time):
        st = _from_snapshots(r)
        if st.time.size >= HEATMAP_MIN_FRAMES:
            return st, ""
        why.append(f"snapshots.csv has {st.time.size} snapshot time(s), fewer than {HEATMAP_MIN_FRAMES}")
    else:
        why.append("no snapshots.csv")
    if r.solution.history_contacts:
        st = _from_histories(r)
        if st.contacts.size >= HEATMAP_MIN_CONTACTS and st.time.size >= HEATMAP_MIN_FRAMES:
            return st, ""
        why.append(
            f"histories.csv has {st.contacts.size} contact(s), {st.time.size} sample(s) "
            f"(at least {HEATMAP_MIN_CONTACTS} and {HEATMAP_MIN_FRAMES})"
        )
    else:
        why.append("no histories.csv")
    return None, (
        "no whole-chain time data: "
        + "; ".join(why)
        + f". Set [outputs] dump_interval (LAMMPS), snapshots = [{HEATMAP_MIN_FRAMES} or more times] "
        f"or histories = [{HEATMAP_MIN_CONTACTS} or more contacts]"
    )


def _block_max(a: np.ndarray, axis: int, max_cells: int) -> tuple[np.ndarray, int]:
    """Reduce axis of a to at most max_cells by the maximum over blocks; returns (reduced, block)."""
    n = a.shape[axis]
    block = -(-n // max_cells)
    if block <= 1:
        return a, 1
    pad = (-n) % block
    a = np.moveaxis(a, axis, 0)
    a = np.concatenate([a, np.full((pad, *a.shape[1:]), np.nan)]) if pad else a
    red = np.nanmax(a.reshape(-1, block, *a.shape[1:]), axis=1)
    return np.moveaxis(red, 0, axis), block


def heatmap_data(st: SpaceTime, max_cells: int = HEATMAP_MAX_CELLS) -> SpaceTime:
    """What the heat map draws: st reduced by block maxima to at most max_cells per axis."""
    force, bt = _block_max(st.force, 0, max_cells)
    force, bc = _block_max(force, 1, max_cells)
    time = st.time[::bt] if bt > 1 else st.time
    contacts = st.contacts[::bc] if bc > 1 else st.contacts
    source = st.source + (f", maximum over blocks of {bt} frames x {bc} contacts" if bt * bc > 1 else "")
    return SpaceTime(time, contacts, force, source)


def dynamic_spacetime(r: RunResult, st: SpaceTime) -> tuple[SpaceTime, np.ndarray | None]:
    """st with each contact's force less its static force (tables.static_forces: F0, gravity's weight
    above it), the force the run reports, and those static forces; st itself where there are none."""
    static = static_forces(r)
    if static is None:
        return st, None
    force = st.force - static[np.asarray(st.contacts, dtype=int) - 1]
    return SpaceTime(st.time, st.contacts, force, st.source), static


def _draw_heatmap(r: RunResult, st: SpaceTime, ax=None):
    st, static = dynamic_spacetime(r, st)  # before the block maxima: each contact less its own
    st = heatmap_data(st)
    summary = r.summary
    factor, unit = _time_unit(float(np.nanmax(st.time)))
    f = np.where(np.isfinite(st.force), st.force, 0.0)
    fmax = float(f.max())
    positive = f[f > 0]
    log_scale = positive.size > 0 and positive.min() < fmax / 100.0
    base = _cmap("magma")
    cmap = base.with_extremes(under=base(0.0))
    if log_scale:
        norm = LogNorm(vmin=fmax * 10.0**-HEATMAP_DECADES, vmax=fmax, clip=False)
        f = np.where(f > 0, f, norm.vmin * 0.5)  # open contacts: the colour below the scale
    else:
        norm = Normalize(vmin=0.0, vmax=fmax if fmax > 0 else 1.0)
    fig, ax, root, given = canvas(ax, 1, figsize=(8, 6))
    mesh = ax.pcolormesh(st.contacts, st.time * factor, f, shading="nearest", cmap=cmap, norm=norm, rasterized=True)
    # below the scale: open contacts and weak ones on a log scale, a dynamic force below zero (unloading
    # below the static force) on either
    below = log_scale or bool(np.any(f < norm.vmin))
    cb = fig.colorbar(mesh, ax=ax, extend="min" if below else "neither")
    contacts = None if static is None else static[: int(r.scene.chain.beads) - 1]  # the bead-bead ones
    label = force_label(contacts, "contact force", "F_{i,i+1}", r"contact force $F_{i,i+1}$ (N)")
    cb.set_label(label[:-1] + (", log scale" if log_scale else "") + ")")
    ax.set_xlabel(CONTACT_LABEL)
    ax.set_ylabel(rf"time $t$ ({unit})")
    ax.set_title(f"Contact force over the chain and time — {_label(summary)}\nfrom {_plain(st.source)}", fontsize=9)
    if not given:
        fig.tight_layout()
    return root, ["time", *[csv_name(f"force_{c}", static) for c in st.contacts]], [st.time, *st.force.T]


def figure_heatmap(run, ax=None) -> Figure:
    """The x-t diagram of contact force of a RunResult or run directory, as a Figure (not saved), from
    its whole-chain time data (spacetime_force); PlotError, with the reason, when it has none. ax: an
    Axes to draw into (canvas; its colour bar takes room from it), its Figure returned."""
    r = as_result(run)
    st, why = spacetime_force(r)
    if st is None:
        raise PlotError(why)
    return _draw_heatmap(r, st, ax)[0]


def write_heatmap(run_dir, formats=("png",), skipped: dict[str, str] | None = None) -> list[Path]:
    """(plot_run) The x-t diagram of contact force (heatmap.<format>); [] and the reason in skipped["heatmap"] (and
    the log) when the run directory has no whole-chain time data."""
    formats = check_formats(formats)
    r = as_result(run_dir)
    st, why = spacetime_force(r)
    if st is None:
        if skipped is not None:
            skipped["heatmap"] = why
        (logger.info if skipped is not None else logger.warning)("%s: heat map not drawn: %s", r.path, why)
        return []
    fig, header, cols = _draw_heatmap(r, st)
    made = _save(fig, r.path / "heatmap", formats)
    _write_csv(r.path / "heatmap_plot.csv", header, cols)
    return made
