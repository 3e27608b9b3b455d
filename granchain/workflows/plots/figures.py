"""The figures of a run (a RunResult or a run directory): histories, peaks with the models that apply,
snapshots, the heat map; returned as Figures, saved when asked, or all written into the run directory
(plot_run)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from granchain.physics.predictions import applicability
from granchain.postprocess.observables import END_PEAKS
from granchain.postprocess.sensors import sensor_static_forces
from granchain.results import RunResult
from granchain.workflows.plots.canvas import (
    CONTACT_LABEL,
    LEGEND_MAX,
    PlotError,
    _cmap,
    _error_bars,
    _label,
    _legend_label,
    _peak_markers,
    _plain,
    _save,
    _time_unit,
    _write_csv,
    canvas,
    check_formats,
    log_axes_ticks,
)
from granchain.workflows.plots.spacetime import (
    _draw_heatmap,
    figure_heatmap,
    spacetime_force,
    write_heatmap,
)
from granchain.workflows.plots.tables import (
    _snapshots_table,
    as_result,
    csv_name,
    dynamic_histories,
    dynamic_peaks,
    force_label,
    load_peaks,
    static_forces,
)

#: the velocity panel of a run whose histories are its sensor beads' only
NO_VELOCITIES = (
    "no bead velocity histories: they are recorded at the beads of [outputs] histories' contacts\n"
    "(sensors record their bead's average force only)"
)


def _draw_histories(r: RunResult, ax=None):
    """(Figure, CSV header, CSV columns) of the histories (the contacts' and the sensor beads'), or None
    without any; drawn into ax (forces, velocities) when given (canvas)."""
    sensed = r.solution.sensor_history_time
    if not r.solution.history_contacts and not sensed.size:
        return None
    summary = r.summary
    header, data, static = dynamic_histories(r)  # the dynamic force under precompression or gravity
    factor, unit = _time_unit(float(np.max(data[:, 0])) if data.size else float(np.max(sensed, initial=0.0)))
    t = data[:, 0] * factor
    fcols = [i for i, h in enumerate(header) if h.startswith("force_")]
    vcols = [i for i, h in enumerate(header) if h.startswith("velocity_")]
    contacts = [int(header[i].split("_")[1]) for i in fcols]
    many = len(fcols) > LEGEND_MAX
    cmap = _cmap("viridis")
    norm = Normalize(min(contacts), max(contacts)) if many else None
    fig, (ax1, ax2), root, given = canvas(ax, 2, figsize=(8, 7), layout="constrained" if many else None)
    for i in fcols:
        c = int(header[i].split("_")[1])
        kw = {"color": cmap(norm(c))} if many else {"label": rf"$F_{{{c},{c + 1}}}$"}
        ax1.plot(t, data[:, i], lw=1, **kw)
    sensor_header, sensor_cols = _sensor_lines(r, ax1, factor, data[:, 0], static)
    for i in vcols:
        c = int(header[i].split("_")[1])
        kw = {"color": cmap(norm(c))} if many else {"label": rf"$v_{{{c}}}$"}
        ax2.plot(t, data[:, i], lw=1, **kw)
    ax1.set_ylabel(_histories_label(static, int(r.scene.chain.beads), bool(sensed.size)))
    ax2.set_ylabel(r"bead velocity $v_i$ (m/s)")
    if not vcols:  # sensors only: a legend of nothing drawn warned, and the empty panel said nothing
        ax2.text(0.5, 0.5, NO_VELOCITIES, transform=ax2.transAxes, ha="center", va="center", fontsize=9, color="0.3")
        ax2.set_yticks([])  # (no scale to read)
    ax2.set_xlabel(rf"time $t$ ({unit})")
    ax1.set_title(f"Contact force and bead velocity histories — {_label(summary)}", fontsize=10)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    if many:
        cb = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=[ax1, ax2], label=r"contact / bead $i$ (index)")
        cb.ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    else:
        ax1.legend(fontsize=8)
        if vcols:
            ax2.legend(fontsize=8)
        if not given:
            fig.tight_layout()
    names = [header[0], *[csv_name(header[i], static) for i in fcols], *[header[i] for i in vcols], *sensor_header]
    return root, names, [data[:, 0] if fcols else sensed, *[data[:, i] for i in fcols + vcols], *sensor_cols]


def _histories_label(static: np.ndarray | None, beads: int, sensed: bool) -> str:
    """The histories' force axis label: which force it shows (tables.force_label), the sensors' too."""
    sensor = r"sensor $(F_{i-1,i} + F_{i,i+1})/2$"
    if static is None:
        return r"contact force $F_{i,i+1}$" + (f", {sensor}" if sensed else "") + " (N)"
    if beads < 2:  # a sensor alone, on the wall's contact: no bead-bead contact's F_0 to name
        return f"dynamic {sensor}\nless its static force (N)"
    label = force_label(static[: beads - 1], "contact force", "F_{i,i+1}", "", split=True)
    # a sensor's static force is its own two contacts' average (bead 1's under a velocity load: F0 / 2)
    return label.replace("\n(N", f",\n{sensor} less its static\n(N", 1) if sensed else label


def _sensor_lines(
    r: RunResult, ax, factor: float, times: np.ndarray, static: np.ndarray | None
) -> tuple[list[str], list[np.ndarray]]:
    """Each sensor bead's average force history (postprocess.sensors) on ax, dashed beside the contacts',
    less its static average force where the contacts have a static force (as sensor_peak_force is), and
    its CSV columns where its samples are the contact histories' (times; without contact histories, its
    own)."""
    s = r.solution
    if not s.sensor_history_time.size:
        return [], []
    header, cols = [], []
    rest = sensor_static_forces(r.scene) if static is not None else np.zeros(len(s.sensor_beads))
    for k, bead in enumerate(s.sensor_beads):
        f = s.sensor_history_force[:, k] - rest[k]
        ax.plot(s.sensor_history_time * factor, f, lw=1.2, ls="--", color=f"C{k % 10}", label=f"sensor bead {bead}")
        header.append(f"sensor_{csv_name('force', static)}_bead_{bead}")
        cols.append(f)
    same = not times.size or np.array_equal(times, s.sensor_history_time)
    return (header, cols) if same else ([], [])


def figure_histories(run, ax=None) -> Figure:
    """Contact force and bead velocity histories at the recorded contacts (Fig. 5a, 5b) of a RunResult
    or run directory, as a Figure (not saved); ax: (top, bottom) Axes to draw into (canvas), their
    Figure returned. PlotError when the run recorded none."""
    drawn = _draw_histories(as_result(run), ax)
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

    if np.size(contacts) == 0:  # one bead: no bead-bead contact to draw a model along
        return {}
    return scene.contact.law_class.model_curves(scene, contacts, applies)


def _end_peaks_text(summary: dict, scene) -> str:
    """The end contacts' peaks of a run's summary (END_PEAKS), as a sentence ("" without them)."""
    out = []
    for obs in END_PEAKS.values():
        value, static = summary.get(obs.name), obs.static_force(scene)
        if value is None or not np.isfinite(value):
            continue
        what = "peak" if summary.get(obs.complete_field) is not False else "largest force so far"
        nb = "\N{NO-BREAK SPACE}"  # a number and its unit on one line of the wrapped panel text
        total = f" above F0 (total {value:.4g}{nb}N)" if static else ""
        out.append(f"{obs.label} contact {what} {value - static:.4g}{nb}N{total}")
    return "; ".join(out)


def _no_peaks_text(r: RunResult) -> str:
    """Why a peak figure shows no bead-bead peak, and the end contacts' peaks (summary.json) it has instead."""
    n = int(r.scene.chain.beads)
    if n < 2:
        why = "one bead: no bead-bead contact to plot"
    else:
        why = f"no contact reached by the wave when the run ended (t = {float(r.summary['end_time']):.4g} s)"
    ends = _end_peaks_text(r.summary, r.scene)
    return why + (f"; {ends} (summary.json)" if ends else "")


#: the footnotes' font size (points) and the characters a line of it holds across the peaks figure's
#: 8 inches (about 0.55 of the size per character: 175; wrapped shorter to keep clear of the edges)
FOOTNOTE_SIZE = 6.0
FOOTNOTE_WIDTH = 150


def _footnote_lines(skipped: dict[str, str], width: int = FOOTNOTE_WIDTH) -> list[str]:
    """The models not drawn and why: one line per reason (the models it holds for named together),
    wrapped whole at width characters, never cut."""
    by_reason: dict[str, list[str]] = {}
    for label, reason in skipped.items():
        by_reason.setdefault(reason, []).append(label)
    lines = []
    for reason, labels in by_reason.items():
        lines += textwrap.wrap(_plain(f"not drawn, {'; '.join(labels)}: {reason}"), width=width)
    return lines


def _footnote(fig: Figure, skipped: dict[str, str]) -> None:
    """The models not drawn and why, under the axes (_footnote_lines), with the axes laid out above it."""
    lines = _footnote_lines(skipped)
    fig.text(0.01, 0.01, "\n".join(lines), fontsize=FOOTNOTE_SIZE, va="bottom", ha="left", color="0.3")
    height = 72.0 * fig.get_figheight()  # points
    fig.tight_layout(rect=(0, (1.25 * FOOTNOTE_SIZE * len(lines) + 8.0) / height, 1, 1))


def _lay_out(fig, ax, skipped: dict[str, str], given: bool) -> None:
    """The peaks figure's layout: the models not drawn and why in a footnote under the axes; on axes
    the caller gave, the same note under their x label, wrapped to their width, and the caller's
    layout left alone."""
    if given and skipped:
        # characters across the axes at the footnote's size (a character about 0.55 em wide)
        width = ax.get_position().width * fig.get_figwidth() * 72.0 / (0.55 * FOOTNOTE_SIZE)
        ax.annotate(
            "\n".join(_footnote_lines(skipped, max(40, int(width)))),
            xy=(0.0, 0.0),
            xycoords="axes fraction",
            xytext=(0.0, -36.0),
            textcoords="offset points",
            va="top",
            fontsize=FOOTNOTE_SIZE,
            color="0.3",
        )
    elif skipped:  # say which models are left out, and why
        _footnote(fig, skipped)
    elif not given:
        fig.tight_layout()


def _draw_peaks(r: RunResult, log: bool = True, ax=None):
    summary = r.summary
    scene = r.scene
    pk, ylabel, nondim_label, column, what = dynamic_peaks(r, load_peaks(r))
    contacts, peak = pk.contact, pk.peak_force
    skipped: dict[str, str] = {}
    curves = model_curves(scene, contacts, skipped)
    fig, ax, root, given = canvas(ax, 1, figsize=(8, 5))
    # a log axis needs a positive value to show: a run without a reached bead-bead peak (one bead, or a
    # run ended before the wave reached contact 1) and without a model curve gets linear axes and says why
    positive = pk.reached.any() or any(np.any(np.isfinite(y) & (y > 0)) for y in curves.values())
    log = log and bool(positive)
    if not pk.reached.any():
        ax.text(
            0.5,
            0.5,
            "\n".join(textwrap.wrap(_plain(_no_peaks_text(r)), width=70)),
            transform=ax.transAxes,
            ha="center",
            va="center",
            fontsize=9,
            color="0.3",
        )
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
    label = f"{what} — {_label(summary)}"
    _peak_markers(ax, contacts, peak, pk.reached, pk.complete, pk.has_complete, label, open_note=note)
    for name, y in curves.items():
        ax.plot(contacts, y, "-", lw=1.2, label=_legend_label(name))
    if log:
        ax.set_xscale("log")
        ax.set_yscale("log")
    if floor is not None:
        tops = [float(peak[pk.reached].max()), *(float(np.nanmax(y)) for y in curves.values() if np.isfinite(y).any())]
        ax.set_ylim(floor, 1.3 * max(tops))
    ax.set_xlabel(CONTACT_LABEL)
    ax.set_ylabel(ylabel)
    # the nondimensional force F / (E* R*^2) as a right axis where one scale holds for every contact: on a
    # chain whose beads differ each contact has its own pair's E* R*^2 (peaks.csv's peak_force_nondim), and
    # one axis in bead 1's would read the others' wrong, so there is none
    secondary = []
    if not positive:  # nothing drawn: no scale to read (the panel text says why)
        ax.set_xticks([])
        ax.set_yticks([])
    elif not scene.per_bead:
        fs = scene.force_scale
        sec = ax.secondary_yaxis("right", functions=(lambda f: f / fs, lambda g: g * fs))
        sec.set_ylabel(nondim_label)
        secondary.append((sec, fs))
    if log:
        log_axes_ticks(ax, *secondary)
    ax.set_title(_plain(scene.title or "peak force along the chain"), fontsize=9)
    ax.grid(alpha=0.3, which="both")
    if positive:  # (a legend of nothing drawn: none)
        ax.legend(fontsize=8)
    _lay_out(fig, ax, skipped, given)
    err = None if pk.error is None else np.where(pk.reached, pk.error, np.nan)
    if _error_bars(ax, contacts, peak, err, "0.25", "measured error (dt, 2 dt, 4 dt), where beyond the marker"):
        ax.legend(fontsize=8)
    header, cols = ["contact", column], [contacts, peak]
    if pk.error is not None:
        header, cols = [*header, "peak_force_error"], [*cols, pk.error]
    if pk.has_complete:
        header, cols = [*header, "complete"], [*cols, pk.complete.astype(float)]
    return root, [*header, *curves], [*cols, *curves.values()]


def figure_peaks(run, log: bool = True, ax=None) -> Figure:
    """Peak force vs contact (log axes unless log=False) with the models that apply (Figs. 6, 7), of a
    RunResult or run directory, as a Figure (not saved); open markers: peaks not complete. ax: an Axes
    to draw into (canvas), its Figure returned."""
    return _draw_peaks(as_result(run), log, ax)[0]


def write_peaks(run, log: bool = True, formats=("png",)) -> list[Path]:
    """(plot_run) peaks.<format> and peaks_plot.csv in a run directory."""
    r = as_result(run)
    fig, header, cols = _draw_peaks(r, log)
    made = _save(fig, r.path / "peaks", formats)
    _write_csv(r.path / "peaks_plot.csv", header, cols)
    return made


def _draw_snapshots(r: RunResult, ax=None):
    if not np.size(r.solution.snapshot_time):
        return None
    summary = r.summary
    data = _snapshots_table(r)
    static = static_forces(r)
    if static is not None:  # each contact's force above its static force, as the run reports it
        n = int(r.scene.chain.beads)
        data[:, 4] -= np.tile(np.append(static[: n - 1], 0.0), data.shape[0] // n)  # bead N: no contact
    pk, *_ = dynamic_peaks(r, load_peaks(r))
    times = np.unique(data[:, 0])
    factor, unit = _time_unit(float(times.max()))
    many = times.size > LEGEND_MAX
    cmap = _cmap("viridis")
    norm = Normalize(times.min() * factor, times.max() * factor) if many else None
    fig, (ax1, ax2), root, given = canvas(ax, 2, figsize=(9, 7), layout="constrained" if many else None)
    cols = {"time": [], "bead": [], "velocity": [], csv_name("contact_force", static): []}
    for t in times:
        rows = data[data[:, 0] == t]
        kw = {"color": cmap(norm(t * factor))} if many else {"label": rf"$t$ = {t * factor:g} {unit}"}
        ax1.plot(rows[:-1, 1], rows[:-1, 4], lw=1, **kw)
        ax2.plot(rows[:, 1], rows[:, 3], lw=1, **kw)
        for k, c in zip(cols, (rows[:, 0], rows[:, 1], rows[:, 3], rows[:, 4]), strict=True):
            cols[k].append(c)
    ax1.plot(pk.contact, pk.peak_force, "k--", lw=1, label="peak-force envelope (whole run)")
    contacts = None if static is None else static[: int(r.scene.chain.beads) - 1]  # the bead-bead ones
    ax1.set_ylabel(force_label(contacts, "contact force", "F_{i,i+1}", r"contact force $F_{i,i+1}$ (N)", split=True))
    ax2.set_ylabel(r"bead velocity $v_i$ (m/s)")
    ax2.set_xlabel(r"bead / contact $i$ (index)")
    ax1.set_title(f"Force and velocity along the chain — {_label(summary)}", fontsize=10)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    ax1.legend(fontsize=8)
    if not many:
        ax2.legend(fontsize=8)
    if many:
        fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=[ax1, ax2], label=rf"snapshot time $t$ ({unit})")
    elif not given:
        fig.tight_layout()
    return root, list(cols), [np.concatenate(v) for v in cols.values()]


def figure_snapshots(run, ax=None) -> Figure:
    """Force and velocity along the chain at the snapshot times with the running peak-force envelope
    (Figs. 2, 8, 9), of a RunResult or run directory, as a Figure (not saved); ax: (top, bottom) Axes to
    draw into (canvas), their Figure returned. PlotError without any."""
    drawn = _draw_snapshots(as_result(run), ax)
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


def plot_peaks(run, log: bool = True, save=None, formats=("png",), ax=None) -> Figure:
    """figure_peaks, written too when asked: save a directory (True: the run directory) gets
    peaks.<format> for each format and peaks_plot.csv (the plotted data). Returns the Figure (ax: as
    figure_peaks)."""
    r = as_result(run)
    fig, header, cols = _draw_peaks(r, log, ax)
    return _saved(fig, r, "peaks", header, cols, save, formats)


def plot_histories(run, save=None, formats=("png",), ax=None) -> Figure:
    """figure_histories, written too when asked (save: as plot_peaks; ax: as figure_histories)."""
    r = as_result(run)
    drawn = _draw_histories(r, ax)
    if drawn is None:
        figure_histories(r)  # raises, with the fix
    return _saved(drawn[0], r, "histories", drawn[1], drawn[2], save, formats)


def plot_snapshots(run, save=None, formats=("png",), ax=None) -> Figure:
    """figure_snapshots, written too when asked (save: as plot_peaks; ax: as figure_snapshots)."""
    r = as_result(run)
    drawn = _draw_snapshots(r, ax)
    if drawn is None:
        figure_snapshots(r)  # raises, with the fix
    return _saved(drawn[0], r, "snapshots", drawn[1], drawn[2], save, formats)


def plot_heatmap(run, save=None, formats=("png",), ax=None) -> Figure:
    """figure_heatmap, written too when asked (save: as plot_peaks; ax: as figure_heatmap)."""
    r = as_result(run)
    st, why = spacetime_force(r)
    if st is None:
        raise PlotError(why)
    fig, header, cols = _draw_heatmap(r, st, ax)
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
        For "peaks": ``log`` (default True: log axes). For every kind: ``ax``, the matplotlib Axes to
        draw into ("peaks", "heatmap": one; "histories", "snapshots": (top, bottom)), whose Figure is
        returned, its layout left to the caller; without it a new Figure outside pyplot.

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
