"""Figures of a finished run (a RunResult, in memory or loaded), of its run directory, and of a compare
directory (LAMMPS against the reference).

The figure functions (figure_peaks, figure_histories, figure_snapshots, figure_heatmap; figure(result,
kind); RunResult.plot) take a RunResult or a run directory and return a matplotlib Figure: not saved,
not shown, and made without pyplot, so importing or calling them never changes matplotlib's backend
or pyplot's figures (a notebook shows a returned Figure as the cell's value; ``fig.savefig`` writes it).
plot_peaks, plot_histories, plot_snapshots and plot_heatmap return the same Figure and save it only
when asked (``save=`` a directory, or True for the run's own, with the plotted data as CSV).

plot_run and plot_compare write each figure in every requested format (``formats``: any of png,
pdf, svg), with the CSV of its plotted data beside it (``<figure>_plot.csv``), atomically and never
through a symbolic link (granchain.safe_files): a link planted there (peaks.png -> a file elsewhere)
is refused with a PlotError naming it, its target left alone. Axis labels use matplotlib's mathtext
(``$F_{i,i+1}$``: no TeX installation needed).

Run directory (plot_run):
histories       contact forces and bead velocities vs time at the recorded contacts (Fig. 5a, 5b)
peaks           peak force vs contact, log axes, with the models that apply (Figs. 6, 7); open
                markers: peaks that are not complete (peaks.csv's ``complete`` column, if present)
snapshots       force and velocity along the chain at the snapshot times, with the running
                peak-force envelope (Figs. 2, 8, 9)
heatmap         contact force over contact index and time (an x-t diagram), from the whole-chain
                time data the run has (see spacetime_force); skipped, with the reason, when it has
                none: a heat map is never interpolated from a few contacts or frames

Compare directory (plot_compare; ``granchain compare`` writes lammps/ and reference/ beside
compare.csv):
compare_histories   LAMMPS and reference force histories overlaid, their difference below
compare_peaks       LAMMPS and reference peak force along the chain, their relative difference below
"""

from __future__ import annotations

import csv
import io
import logging
import textwrap
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.cm import ScalarMappable
from matplotlib.colors import LogNorm, Normalize
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, MaxNLocator

from granchain import safe_files
from granchain.errors import GranchainError, UsageError
from granchain.physics.predictions import applicability
from granchain.results import RunResult, printable, register_plotter
from granchain.workflows.load import LoadRunError, load_run

logger = logging.getLogger(__name__)

#: figure formats plot_run and plot_compare write (matplotlib's savefig, by file suffix)
FORMATS = ("png", "pdf", "svg")
DPI = 120

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


class PlotError(GranchainError, ValueError):
    """A directory that cannot be plotted (not a run or compare directory, or missing data)."""


# ---------------------------------------------------------------------------------------------
# formats, files and text


def check_formats(formats: str | Iterable[str]) -> tuple[str, ...]:
    """The figure formats asked for, checked: a comma-separated string or an iterable of names."""
    if isinstance(formats, str):
        formats = formats.split(",")
    fmts = [str(f).strip().lower().lstrip(".") for f in formats]
    fmts = [f for f in fmts if f]
    if not fmts:
        raise UsageError(f"no figure format given: choose one or more of {', '.join(FORMATS)} (e.g. png,pdf)")
    bad = [f for f in fmts if f not in FORMATS]
    if bad:
        raise UsageError(
            f"unknown figure format {bad[0]!r}: choose one or more of {', '.join(FORMATS)} (e.g. --format png,pdf)"
        )
    return tuple(dict.fromkeys(fmts))


class ChainFigure(Figure):
    """A matplotlib Figure made outside pyplot that a notebook shows by itself (``_repr_png_``), even
    before pyplot has chosen a backend; otherwise a plain Figure (``savefig``, ``axes``, ...)."""

    def _repr_png_(self) -> bytes:
        buf = io.BytesIO()
        self.savefig(buf, format="png", bbox_inches="tight")
        return buf.getvalue()


def _new_figure(**kw) -> Figure:
    """A Figure outside pyplot: no backend is chosen or changed, no global figure list grows."""
    return ChainFigure(**kw)


def _unsafe(e: OSError) -> PlotError:
    return PlotError(f"{e}; nothing was written there")


def save_figure(fig: Figure, base: Path, formats=("png",)) -> list[Path]:
    """fig as base.<format> for each format, written atomically and never through a symbolic link
    (granchain.safe_files: a link planted at the name is refused, its target untouched)."""
    out = []
    for fmt in check_formats(formats):
        p = base.with_name(f"{base.name}.{fmt}")
        try:
            safe_files.save_figure(fig, p, format=fmt, dpi=DPI, metadata={"Date": None} if fmt == "svg" else None)
        except safe_files.UnsafeFileError as e:
            raise _unsafe(e) from None
        out.append(p)
    return out


_save = save_figure


def _write_csv(path: Path, header: list[str], columns: list[np.ndarray]) -> None:
    text = io.StringIO()
    w = csv.writer(text)
    w.writerow(header)
    for row in zip(*columns, strict=True):
        w.writerow([repr(float(x)) for x in row])
    try:
        safe_files.write_text(path, text.getvalue())
    except safe_files.UnsafeFileError as e:
        raise _unsafe(e) from None


def _cmap(name: str):
    return matplotlib.colormaps[name]


def _plain(text: str) -> str:
    """User text (a scene title) shown as is: a $ would start mathtext; control characters escaped."""
    return printable(str(text)).replace("$", r"\$")


def _method_label(summary: dict) -> str:
    return _plain(f"({summary['method']}, ") + rf"$\Delta t$ = {summary['timestep']:g} s)"


def _label(summary: dict) -> str:
    return _plain(summary["backend"]) + " " + _method_label(summary)


def _time_unit(t_max: float) -> tuple[float, str]:
    """Factor and mathtext unit for a time axis running to t_max seconds."""
    for factor, unit in ((1.0, "s"), (1e3, "ms"), (1e6, r"$\mu$s")):
        if t_max * factor >= 1.0:
            return factor, unit
    return 1e9, "ns"


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


#: marker size (points) of the peak-force markers; an error bar is drawn where it reaches beyond one
MARKER_SIZE = 3.0


def _error_bars(ax, x: np.ndarray, y: np.ndarray, err: np.ndarray | None, color, label: str = "") -> int:
    """Error bars of the measured peak-force errors (granchain.workflows.errors) where they reach beyond
    the marker, decided in display space once the axes' limits are final; returns how many were drawn."""
    if err is None:
        return 0
    ok = np.isfinite(err) & np.isfinite(y) & (err > 0)
    if not ok.any():
        return 0
    fig = ax.figure
    radius = 0.5 * MARKER_SIZE * fig.dpi / 72.0  # pixels
    lo = np.where(ok, np.maximum(y - np.where(ok, err, 0.0), np.finfo(float).tiny), y)
    pts = lambda v: ax.transData.transform(np.column_stack([x, v]))[:, 1]  # noqa: E731
    centre, top, bottom = pts(y), pts(np.where(ok, y + np.where(ok, err, 0.0), y)), pts(lo)
    big = ok & ((top - centre > radius) | (centre - bottom > radius))
    if big.any():
        ax.errorbar(x[big], y[big], yerr=err[big], fmt="none", ecolor=color, elinewidth=0.8, capsize=2, label=label)
    return int(big.sum())


def _plain_log_ticks(*axes) -> None:
    """Plain numbers on log y axes spanning less than a decade (not 4.2 x 10^4 on every minor tick)."""
    lo, hi = axes[0].get_ylim()
    if lo > 0 and hi / lo < 10.0:
        for ax in axes:
            for set_fmt in (ax.yaxis.set_major_formatter, ax.yaxis.set_minor_formatter):
                set_fmt(FuncFormatter(lambda v, _: f"{v:.6g}"))


def _legend_label(model_label: str) -> str:
    """A model_curves label for a legend: its formulas in mathtext."""
    return model_label.replace("(1+beta)/2", r"$(1+\beta)/2$")


# ---------------------------------------------------------------------------------------------
# a run directory


#: more lines than this (snapshot times, history contacts) and they are coloured by a colour bar, not
#: named in a legend
LEGEND_MAX = 8


def _draw_histories(r: RunResult):
    """(Figure, CSV header, CSV columns) of the histories, or None without any."""
    if not r.solution.history_contacts:
        return None
    summary = r.summary
    header, data = _histories_table(r)
    factor, unit = _time_unit(float(np.max(data[:, 0])) if data.size else 0.0)
    t = data[:, 0] * factor
    fcols = [i for i, h in enumerate(header) if h.startswith("force_")]
    vcols = [i for i, h in enumerate(header) if h.startswith("velocity_")]
    contacts = [int(header[i].split("_")[1]) for i in fcols]
    many = len(fcols) > LEGEND_MAX
    cmap = _cmap("viridis")
    norm = Normalize(min(contacts), max(contacts)) if many else None
    fig = _new_figure(figsize=(8, 7), layout="constrained" if many else None)
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    for i in fcols:
        c = int(header[i].split("_")[1])
        kw = {"color": cmap(norm(c))} if many else {"label": rf"$F_{{{c},{c + 1}}}$"}
        ax1.plot(t, data[:, i], lw=1, **kw)
    for i in vcols:
        c = int(header[i].split("_")[1])
        kw = {"color": cmap(norm(c))} if many else {"label": rf"$v_{{{c}}}$"}
        ax2.plot(t, data[:, i], lw=1, **kw)
    ax1.set_ylabel(r"contact force $F_{i,i+1}$ (N)")
    ax2.set_ylabel(r"bead velocity $v_i$ (m/s)")
    ax2.set_xlabel(rf"time $t$ ({unit})")
    ax1.set_title(f"Contact force and bead velocity histories — {_label(summary)}", fontsize=10)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    if many:
        cb = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=[ax1, ax2], label=r"contact / bead $i$")
        cb.ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    else:
        ax1.legend(fontsize=8)
        ax2.legend(fontsize=8)
        fig.tight_layout()
    return fig, [header[0], *[header[i] for i in fcols + vcols]], [data[:, 0], *[data[:, i] for i in fcols + vcols]]


def figure_histories(run) -> Figure:
    """Contact force and bead velocity histories at the recorded contacts (Fig. 5a, 5b) of a RunResult
    or run directory, as a Figure (not saved). PlotError when the run recorded none."""
    drawn = _draw_histories(as_result(run))
    if drawn is None:
        raise PlotError("this run recorded no histories: set [outputs] histories = [contacts] in the scene")
    return drawn[0]


def write_histories(run, formats=("png",)) -> list[Path]:
    """(plot_run) histories.<format> and histories_plot.csv in a run directory; [] when it has no histories."""
    r = as_result(run)
    drawn = _draw_histories(r)
    if drawn is None:
        return []
    fig, header, cols = drawn
    made = _save(fig, r.path / "histories", formats)
    _write_csv(r.path / "histories_plot.csv", header, cols)
    return made


def model_curves(scene, contacts: np.ndarray, skipped: dict[str, str] | None = None) -> dict[str, np.ndarray]:
    """Model peak force vs contact, for the models that apply to the scene (predictions.applicability).

    The curves are the scene's contact law's (ContactLaw.model_curves). skipped: if given, filled with
    label -> reason for each model left out because it does not apply.
    """

    def applies(name: str, label: str) -> bool:
        verdict = applicability(name, scene)
        if not verdict.applies and skipped is not None:
            skipped[label] = verdict.reason
        return verdict.applies

    return scene.contact.law_class.model_curves(scene, contacts, applies)


def _peak_markers(
    ax, contacts, peak, reached, complete, has_complete: bool, label: str, color=None, open_note: str = ""
) -> None:
    """Peak forces of the reached contacts as markers: filled where the peak is complete, open where it
    is not (when known)."""
    full = reached & complete
    (line,) = ax.plot(contacts[full], peak[full], "o", ms=MARKER_SIZE, color=color, label=label)
    part = reached & ~complete
    if has_complete and part.any():
        ax.plot(
            contacts[part],
            peak[part],
            "o",
            ms=4,
            mfc="none",
            color=line.get_color(),
            label=f"peak not complete at the end of the run (open marker{open_note})",
        )


def _draw_peaks(r: RunResult, log: bool = True):
    summary = r.summary
    scene = r.scene
    pk = load_peaks(r)
    contacts, peak = pk.contact, pk.peak_force
    skipped: dict[str, str] = {}
    curves = model_curves(scene, contacts, skipped)
    fig = _new_figure(figsize=(8, 5))
    ax = fig.subplots()
    # on log axes, the tiny peaks of contacts the front is still reaching at the end of the run (not
    # complete) would squash the profile into a line: the axis is set by the complete peaks, the rest
    # are counted in the legend (and kept in peaks_plot.csv)
    done = pk.reached & pk.complete
    floor, note = None, ""
    if log and pk.has_complete and done.any():
        floor = float(peak[done].min()) / 1.5
        below = int(np.sum(pk.reached & ~pk.complete & (peak < floor)))
        if below:
            note = f"; {below} below the axis"
        else:
            floor = None
    label = f"peak force — {_label(summary)}"
    _peak_markers(ax, contacts, peak, pk.reached, pk.complete, pk.has_complete, label, open_note=note)
    for name, y in curves.items():
        ax.plot(contacts, y, "-", lw=1.2, label=_legend_label(name))
    if log:
        ax.set_xscale("log")
        ax.set_yscale("log")
    if floor is not None:
        tops = [float(peak[pk.reached].max()), *(float(np.nanmax(y)) for y in curves.values() if np.isfinite(y).any())]
        ax.set_ylim(floor, 1.3 * max(tops))
    ax.set_xlabel(r"contact $i$ (between bead $i$ and $i+1$)")
    ax.set_ylabel(r"peak contact force $F_p$ (N)")
    sec = ax.secondary_yaxis("right", functions=(lambda f: f / scene.force_scale, lambda g: g * scene.force_scale))
    sec.set_ylabel(r"$F_p \,/\, (E^* R^{*2})$")
    if log:
        _plain_log_ticks(ax, sec)
    ax.set_title(_plain(scene.title or "peak force along the chain"), fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    if skipped:  # say which models are left out, and why
        note = "\n".join(
            _plain(textwrap.shorten(f"not drawn, {label}: {reason}", width=160, placeholder=" ..."))
            for label, reason in skipped.items()
        )
        fig.text(0.01, 0.01, note, fontsize=6, va="bottom", ha="left", color="0.3")
        fig.tight_layout(rect=(0, 0.025 * (len(skipped) + 1), 1, 1))
    else:
        fig.tight_layout()
    err = None if pk.error is None else np.where(pk.reached, pk.error, np.nan)
    if _error_bars(ax, contacts, peak, err, "0.25", "measured error (dt, 2 dt, 4 dt), where beyond the marker"):
        ax.legend(fontsize=8)
    header, cols = ["contact", "peak_force"], [contacts, peak]
    if pk.error is not None:
        header, cols = [*header, "peak_force_error"], [*cols, pk.error]
    if pk.has_complete:
        header, cols = [*header, "complete"], [*cols, pk.complete.astype(float)]
    return fig, [*header, *curves], [*cols, *curves.values()]


def figure_peaks(run, log: bool = True) -> Figure:
    """Peak force vs contact (log axes unless log=False) with the models that apply (Figs. 6, 7), of a
    RunResult or run directory, as a Figure (not saved); open markers: peaks not complete."""
    return _draw_peaks(as_result(run), log)[0]


def write_peaks(run, log: bool = True, formats=("png",)) -> list[Path]:
    """(plot_run) peaks.<format> and peaks_plot.csv in a run directory."""
    r = as_result(run)
    fig, header, cols = _draw_peaks(r, log)
    made = _save(fig, r.path / "peaks", formats)
    _write_csv(r.path / "peaks_plot.csv", header, cols)
    return made


def _draw_snapshots(r: RunResult):
    if not np.size(r.solution.snapshot_time):
        return None
    summary = r.summary
    data = _snapshots_table(r)
    pk = load_peaks(r)
    times = np.unique(data[:, 0])
    factor, unit = _time_unit(float(times.max()))
    many = times.size > LEGEND_MAX
    cmap = _cmap("viridis")
    norm = Normalize(times.min() * factor, times.max() * factor) if many else None
    fig = _new_figure(figsize=(9, 7), layout="constrained" if many else None)
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    cols = {"time": [], "bead": [], "velocity": [], "contact_force": []}
    for t in times:
        rows = data[data[:, 0] == t]
        kw = {"color": cmap(norm(t * factor))} if many else {"label": rf"$t$ = {t * factor:g} {unit}"}
        ax1.plot(rows[:-1, 1], rows[:-1, 4], lw=1, **kw)
        ax2.plot(rows[:, 1], rows[:, 3], lw=1, **kw)
        for k, c in zip(cols, (rows[:, 0], rows[:, 1], rows[:, 3], rows[:, 4]), strict=True):
            cols[k].append(c)
    ax1.plot(pk.contact, pk.peak_force, "k--", lw=1, label="peak-force envelope (whole run)")
    ax1.set_ylabel(r"contact force $F_{i,i+1}$ (N)")
    ax2.set_ylabel(r"bead velocity $v_i$ (m/s)")
    ax2.set_xlabel(r"bead / contact index $i$")
    ax1.set_title(f"Force and velocity along the chain — {_label(summary)}", fontsize=10)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    ax1.legend(fontsize=8)
    if not many:
        ax2.legend(fontsize=8)
    if many:
        fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=[ax1, ax2], label=rf"snapshot time $t$ ({unit})")
    else:
        fig.tight_layout()
    return fig, list(cols), [np.concatenate(v) for v in cols.values()]


def figure_snapshots(run) -> Figure:
    """Force and velocity along the chain at the snapshot times with the running peak-force envelope
    (Figs. 2, 8, 9), of a RunResult or run directory, as a Figure (not saved). PlotError without any."""
    drawn = _draw_snapshots(as_result(run))
    if drawn is None:
        raise PlotError("this run took no snapshots: set [outputs] snapshots = [times] in the scene")
    return drawn[0]


def write_snapshots(run, formats=("png",)) -> list[Path]:
    """(plot_run) snapshots.<format> and snapshots_plot.csv in a run directory; [] when it has no snapshots."""
    r = as_result(run)
    drawn = _draw_snapshots(r)
    if drawn is None:
        return []
    fig, header, cols = drawn
    made = _save(fig, r.path / "snapshots", formats)
    _write_csv(r.path / "snapshots_plot.csv", header, cols)
    return made


# ---------------------------------------------------------------------------------------------
# the x-t heat map


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


def _draw_heatmap(r: RunResult, st: SpaceTime):
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
    fig = _new_figure(figsize=(8, 6))
    ax = fig.subplots()
    mesh = ax.pcolormesh(st.contacts, st.time * factor, f, shading="nearest", cmap=cmap, norm=norm, rasterized=True)
    cb = fig.colorbar(mesh, ax=ax, extend="min" if log_scale else "neither")
    cb.set_label(r"contact force $F_{i,i+1}$ (N)" + (", log scale" if log_scale else ""))
    ax.set_xlabel(r"contact $i$ (between bead $i$ and $i+1$)")
    ax.set_ylabel(rf"time $t$ ({unit})")
    ax.set_title(f"Contact force over the chain and time — {_label(summary)}\nfrom {_plain(st.source)}", fontsize=9)
    fig.tight_layout()
    return fig, ["time", *[f"force_{c}" for c in st.contacts]], [st.time, *st.force.T]


def figure_heatmap(run) -> Figure:
    """The x-t diagram of contact force of a RunResult or run directory, as a Figure (not saved), from
    its whole-chain time data (spacetime_force); PlotError, with the reason, when it has none."""
    r = as_result(run)
    st, why = spacetime_force(r)
    if st is None:
        raise PlotError(why)
    return _draw_heatmap(r, st)[0]


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


def _saved(fig: Figure, r: RunResult, name: str, header, cols, save, formats) -> Figure:
    """fig, and, when save is a directory (True: the run's own), name.<format> and name_plot.csv in it."""
    if save is None or save is False:
        return fig
    d = r.path if save is True else Path(save)
    if d is None:
        raise PlotError("save=True writes into the run's directory, and this result has none: give save=DIRECTORY")
    _save(fig, Path(d) / name, formats)
    _write_csv(Path(d) / f"{name}_plot.csv", header, cols)
    return fig


def plot_peaks(run, log: bool = True, save=None, formats=("png",)) -> Figure:
    """figure_peaks, written too when asked: save a directory (True: the run directory) gets
    peaks.<format> for each format and peaks_plot.csv (the plotted data). Returns the Figure."""
    r = as_result(run)
    fig, header, cols = _draw_peaks(r, log)
    return _saved(fig, r, "peaks", header, cols, save, formats)


def plot_histories(run, save=None, formats=("png",)) -> Figure:
    """figure_histories, written too when asked (save: as plot_peaks)."""
    r = as_result(run)
    drawn = _draw_histories(r)
    if drawn is None:
        figure_histories(r)  # raises, with the fix
    return _saved(drawn[0], r, "histories", drawn[1], drawn[2], save, formats)


def plot_snapshots(run, save=None, formats=("png",)) -> Figure:
    """figure_snapshots, written too when asked (save: as plot_peaks)."""
    r = as_result(run)
    drawn = _draw_snapshots(r)
    if drawn is None:
        figure_snapshots(r)  # raises, with the fix
    return _saved(drawn[0], r, "snapshots", drawn[1], drawn[2], save, formats)


def plot_heatmap(run, save=None, formats=("png",)) -> Figure:
    """figure_heatmap, written too when asked (save: as plot_peaks)."""
    r = as_result(run)
    st, why = spacetime_force(r)
    if st is None:
        raise PlotError(why)
    fig, header, cols = _draw_heatmap(r, st)
    return _saved(fig, r, "heatmap", header, cols, save, formats)


#: the figures of a run: figure(result, kind) and RunResult.plot(kind)
FIGURES = {
    "peaks": figure_peaks,
    "histories": figure_histories,
    "snapshots": figure_snapshots,
    "heatmap": figure_heatmap,
}


def figure(run, kind: str = "peaks", **kw) -> Figure:
    """One figure of a RunResult or run directory, as a matplotlib Figure (not saved, not shown).

    Parameters
    ----------
    run : granchain.results.RunResult or str or pathlib.Path
        A result (granchain.run, granchain.load_run) or a run directory.
    kind : {"peaks", "histories", "snapshots", "heatmap"}
        Which figure (FIGURES).
    **kw
        For "peaks": ``log`` (default True: log axes).

    Returns
    -------
    matplotlib.figure.Figure
        Made without pyplot: ``fig.savefig(path)`` writes it; a notebook shows it as a cell's value.

    Raises
    ------
    PlotError
        kind is unknown, or the run has no data for it (the message says what to set in the scene).
    """
    if kind not in FIGURES:
        raise PlotError(f"unknown figure {kind!r}: choose one of {', '.join(FIGURES)}")
    return FIGURES[kind](run, **kw)


def plot_result(result: RunResult, kind: str = "peaks", **kw) -> Figure:
    """RunResult.plot: figure(result, kind, **kw)."""
    return figure(result, kind, **kw)


register_plotter(plot_result)


def plot_run(run_dir, log: bool = True, formats=("png",), skipped: dict[str, str] | None = None) -> list[Path]:
    """Every figure of a run directory, in each format, with its plotted data (<figure>_plot.csv), written
    in it without following symbolic links; returns the figure files.

    skipped: if given, filled with figure -> reason for each figure that could not be drawn (the heat map
    of a run without whole-chain time data); the reason is also logged.
    """
    formats = check_formats(formats)
    r = as_result(run_dir)
    if r.path is None:
        raise PlotError("plot_run writes into a run directory: give its path (or figure(result, kind) for a Figure)")
    return [
        *write_peaks(r, log, formats),
        *write_histories(r, formats),
        *write_snapshots(r, formats),
        *write_heatmap(r, formats, skipped),
    ]


# ---------------------------------------------------------------------------------------------
# a compare directory: LAMMPS against the reference


def is_compare_dir(path: str | Path) -> bool:
    """A directory written by granchain compare: lammps/ and reference/ run directories."""
    p = Path(path)
    return (p / "lammps" / "summary.json").exists() and (p / "reference" / "summary.json").exists()


@dataclass
class HistoryOverlay:
    """One contact's force history in both runs, on one time grid, and their difference (N)."""

    contact: int
    time: np.ndarray  # s
    lammps: np.ndarray
    reference: np.ndarray
    difference: np.ndarray  # lammps - reference
    grid: str  # how the two runs' samples were put on one time grid


@dataclass
class PeakOverlay:
    """Peak force along the chain in both runs and their relative difference."""

    contact: np.ndarray
    lammps: np.ndarray
    reference: np.ndarray
    relative_difference: np.ndarray  # (lammps - reference) / reference; nan where either is not reached
    reached: np.ndarray  # reached in both runs (Peaks.reached)
    complete: np.ndarray  # complete in both runs (all True without the complete column)
    has_complete: bool  # either peaks.csv has a complete column
    lammps_error: np.ndarray | None = None  # LAMMPS's measured peak-force errors (None: not estimated)


def _spline(t: np.ndarray, f: np.ndarray, at: np.ndarray) -> np.ndarray:
    """f(t) at the times at, by a cubic spline through the samples (repeated times: the last sample)."""
    from scipy.interpolate import CubicSpline

    keep = np.append(np.diff(t) > 0, True)
    return CubicSpline(t[keep], f[keep])(at)


def _on_one_grid(t_a, f_a, t_b, f_b, name_a: str, name_b: str):
    """Two sampled series on one time grid: as they are if the grids coincide, else the finer one
    interpolated (cubic spline: a linear one's error, h^2 F''/8, would swamp the difference of two
    converged runs) to the coarser one's samples within both runs' time span."""
    if min(t_a.size, t_b.size) < 2:
        raise PlotError("a force history with fewer than two samples cannot be compared")
    if t_a.shape == t_b.shape and np.allclose(t_a, t_b, rtol=0.0, atol=1e-9 * max(float(np.max(t_a)), 1e-300)):
        return t_a, f_a, f_b, "both on the same sample times"
    h_a, h_b = np.median(np.diff(t_a)), np.median(np.diff(t_b))
    if h_a >= h_b:
        keep = (t_a >= t_b[0]) & (t_a <= t_b[-1])
        t = t_a[keep]
        return t, f_a[keep], _spline(t_b, f_b, t), f"{name_b} interpolated (cubic spline) to the {name_a} samples"
    keep = (t_b >= t_a[0]) & (t_b <= t_a[-1])
    t = t_b[keep]
    return t, _spline(t_a, f_a, t), f_b[keep], f"{name_a} interpolated (cubic spline) to the {name_b} samples"


def _compare_runs(d: Path) -> tuple[RunResult, RunResult]:
    """The lammps/ and reference/ runs of a compare directory (neither may be a symbolic link)."""
    for name in ("lammps", "reference"):
        if (d / name).is_symlink():
            raise PlotError(f"{d / name}: is a symbolic link; a compare directory's runs are read only as themselves")
    return as_result(d / "lammps"), as_result(d / "reference")


def compare_histories(compare_dir: str | Path) -> tuple[list[HistoryOverlay], str]:
    """The force histories of both runs of a compare directory, per common history contact, with their
    difference; or [] and why not."""
    d = Path(compare_dir)
    ra, rb = _compare_runs(d)
    missing = [
        f"{name}/histories.csv" for name, r in (("lammps", ra), ("reference", rb)) if not r.solution.history_contacts
    ]
    if missing:
        return [], f"no force histories to compare ({' and '.join(missing)} missing: [outputs] histories)"
    a, b = (dict(zip(*_histories_table(r)[0:1], _histories_table(r)[1].T, strict=True)) for r in (ra, rb))
    contacts = sorted(
        {int(k.split("_")[1]) for k in a if k.startswith("force_")}
        & {int(k.split("_")[1]) for k in b if k.startswith("force_")}
    )
    if not contacts:
        return [], "the two runs have no history contact in common"
    out = []
    for c in contacts:
        t, fa, fb, grid = _on_one_grid(a["time"], a[f"force_{c}"], b["time"], b[f"force_{c}"], "LAMMPS", "reference")
        out.append(HistoryOverlay(c, t, fa, fb, fa - fb, grid))
    return out, ""


def compare_peaks(compare_dir: str | Path) -> PeakOverlay:
    """The peak-force profiles of both runs of a compare directory, over their common contacts."""
    a, b = (load_peaks(r) for r in _compare_runs(Path(compare_dir)))
    contacts, ia, ib = np.intersect1d(a.contact, b.contact, return_indices=True)
    fa, fb = a.peak_force[ia], b.peak_force[ib]
    reached = a.reached[ia] & b.reached[ib]
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(reached, (fa - fb) / fb, np.nan)
    return PeakOverlay(
        contacts.astype(int),
        fa,
        fb,
        rel,
        reached,
        a.complete[ia] & b.complete[ib],
        a.has_complete or b.has_complete,
        None if a.error is None else a.error[ia],
    )


def _plot_compare_histories(d: Path, la: str, lr: str, formats, skipped) -> list[Path]:
    overlays, why = compare_histories(d)
    if not overlays:
        if skipped is not None:
            skipped["compare_histories"] = why
        (logger.info if skipped is not None else logger.warning)("%s: history overlay not drawn: %s", d, why)
        return []
    t_max = max(float(np.max(o.time)) for o in overlays)
    factor, unit = _time_unit(t_max)
    many = len(overlays) > LEGEND_MAX  # then coloured by contact (a colour bar), line styles in the legend
    cmap = _cmap("viridis")
    norm = Normalize(overlays[0].contact, overlays[-1].contact) if many else None
    fig = _new_figure(figsize=(9, 7.5), layout="constrained" if many else None)
    ax1, ax2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2.2, 1]})
    for k, o in enumerate(overlays):
        color = cmap(norm(o.contact)) if many else f"C{k % 10}"
        sub = f"{o.contact},{o.contact + 1}"
        lab = (lambda text: "_" + text) if many else (lambda text: text)  # "_...": not in the legend
        ax1.plot(o.time * factor, o.lammps, "-", color=color, lw=2.2, alpha=0.45, label=lab(rf"$F_{{{sub}}}$ LAMMPS"))
        ax1.plot(o.time * factor, o.reference, "--", color=color, lw=1.0, label=lab(rf"$F_{{{sub}}}$ reference"))
        ax2.plot(o.time * factor, o.difference, "-", color=color, lw=1.0, label=lab(rf"$F_{{{sub}}}$"))
    if many:
        ax1.plot([], [], "-", color="0.4", lw=2.2, alpha=0.45, label="LAMMPS")
        ax1.plot([], [], "--", color="0.4", lw=1.0, label="reference")
        cb = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=[ax1, ax2], label=r"contact $i$")
        cb.ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax2.axhline(0.0, color="0.5", lw=0.6)
    ax1.set_ylabel(r"contact force $F_{i,i+1}$ (N)")
    ax2.set_ylabel(r"$F^{\mathrm{LAMMPS}} - F^{\mathrm{ref}}$ (N)")
    ax2.set_xlabel(rf"time $t$ ({unit})")
    peak = max(float(np.max(np.abs(o.reference))) for o in overlays) or 1.0
    sec = ax2.secondary_yaxis("right", functions=(lambda x: x / peak, lambda y: y * peak))
    sec.set_ylabel(r"$/\ \max\,|F^{\mathrm{ref}}|$", fontsize=9)
    ax1.set_title(f"Force histories: LAMMPS {la}, wide pale lines; reference {lr}, dashed", fontsize=9)
    ax2.set_title(f"difference, LAMMPS − reference; {_plain(overlays[0].grid)}", fontsize=8)
    ax1.legend(fontsize=7, ncol=1 if many else min(3, len(overlays)))
    if not many:
        ax2.legend(fontsize=7, ncol=min(3, len(overlays)))
        fig.tight_layout()
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    made = _save(fig, d / "compare_histories", formats)
    rows = [
        (o.contact, t, fa, fb, df)
        for o in overlays
        for t, fa, fb, df in zip(o.time, o.lammps, o.reference, o.difference, strict=True)
    ]
    _write_csv(
        d / "compare_histories_plot.csv",
        ["contact", "time", "lammps", "reference", "difference"],
        [np.array(c, dtype=float) for c in zip(*rows, strict=True)] if rows else [np.zeros(0)] * 5,
    )
    return made


def _plot_compare_peaks(d: Path, la: str, lr: str, formats) -> list[Path]:
    p = compare_peaks(d)
    fig = _new_figure(figsize=(9, 7.5))
    ax1, ax2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2.2, 1]})
    reached = p.reached
    ax1.plot(p.contact[reached], p.reference[reached], "-", color="C1", lw=1.2, label=f"reference {lr}")
    _peak_markers(ax1, p.contact, p.lammps, reached, p.complete, p.has_complete, f"LAMMPS {la}", color="C0")
    # the relative difference spans decades (1e-5 behind the wave, 1e-3 at a front still rising at the
    # end): its size on log axes, its sign by colour; open markers as above
    size = np.abs(p.relative_difference)
    tiny = np.finfo(float).eps
    above = p.relative_difference >= 0
    for side, color, word in ((reached & above, "C0", "above"), (reached & ~above, "C3", "below")):
        for complete, mfc, ms, note in ((True, None, 3, ""), (False, "none", 4, ", not complete")):
            sel = side & (p.complete == complete)
            if sel.any():
                ax2.plot(
                    p.contact[sel],
                    np.maximum(size[sel], tiny),
                    "o",
                    ms=ms,
                    mfc=mfc,
                    color=color,
                    label=f"LAMMPS {word} the reference{note}",
                )
    ax2.set_yscale("log")
    # log axes for a profile that spans decades over its complete peaks (a plastic chain's decay)
    ok = reached & p.complete if (reached & p.complete).any() else reached
    if ok.any() and p.reference[ok].max() / p.reference[ok].min() > 10.0:
        ax1.set_yscale("log")
    ax1.set_ylabel(r"peak contact force $F_p$ (N)")
    ax2.set_ylabel(r"$|F_p^{\mathrm{LAMMPS}} - F_p^{\mathrm{ref}}|\,/\,F_p^{\mathrm{ref}}$")
    ax2.set_xlabel(r"contact $i$ (between bead $i$ and $i+1$)")
    ax1.set_title("Peak force along the chain: LAMMPS vs reference", fontsize=9)
    ax2.set_title("relative difference of the peak force (log scale; colour: its sign)", fontsize=8)
    ax1.legend(fontsize=8)
    if ax2.lines:
        ax2.legend(fontsize=7)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    err = None if p.lammps_error is None else np.where(reached, p.lammps_error, np.nan)
    if _error_bars(ax1, p.contact, p.lammps, err, "C0", "LAMMPS measured error, where beyond the marker"):
        ax1.legend(fontsize=8)
    made = _save(fig, d / "compare_peaks", formats)
    header = ["contact", "lammps", "reference", "relative_difference"]
    cols = [p.contact, p.lammps, p.reference, p.relative_difference]
    if p.has_complete:
        header, cols = [*header, "complete"], [*cols, p.complete.astype(float)]
    _write_csv(d / "compare_peaks_plot.csv", header, cols)
    return made


def plot_compare(compare_dir: str | Path, formats=("png",), skipped: dict[str, str] | None = None) -> list[Path]:
    """The figures of a compare directory (compare_histories, compare_peaks), in each format, written in
    it beside compare.csv; returns the figure files. skipped: as in plot_run."""
    d = Path(compare_dir)
    formats = check_formats(formats)
    if not is_compare_dir(d):
        raise PlotError(
            f"{d}: not a compare directory (granchain compare writes lammps/ and reference/ run directories, "
            "each with a summary.json)"
        )
    la, lr = (_method_label(r.summary) for r in _compare_runs(d))
    return [*_plot_compare_histories(d, la, lr, formats, skipped), *_plot_compare_peaks(d, la, lr, formats)]
