"""What every figure of granchain shares: figures made outside pyplot, the formats and files they are
written to (atomically, never through a symbolic link: granchain.safe_files), the plotted data as CSV,
the text on them (user text shown as is, time units), and the peak-force markers and error bars."""

from __future__ import annotations

import csv
import errno
import io
from collections.abc import Iterable
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, FuncFormatter, LogLocator, MaxNLocator, NullFormatter, NullLocator

from granchain import safe_files
from granchain.exceptions import GranchainError, UsageError
from granchain.results import printable


class PlotError(GranchainError, ValueError):
    """A directory that cannot be plotted (not a run or compare directory, or missing data)."""


#: figure formats plot_run and plot_compare write (matplotlib's savefig, by file suffix)
FORMATS = ("png", "pdf", "svg")


DPI = 120


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

    def _wrap_titles(self) -> None:
        """Every axes title wrapped inside the figure's width: a scene's title is the user's text, of
        any length, and a title wider than the figure is cut at its edges."""
        for ax in self.axes:
            ax.title.set_wrap(True)

    def tight_layout(self, *args, **kw) -> None:
        """matplotlib's tight_layout around the titles as they are drawn (wrapped): laid out on one
        line, a wrapped title's first lines rose above the canvas (a generated scene's long title)."""
        self._wrap_titles()
        super().tight_layout(*args, **kw)

    def draw(self, renderer) -> None:
        """Draw the figure with every axes title wrapped (_wrap_titles; a constrained layout, made
        while drawing, already sees them wrapped)."""
        self._wrap_titles()
        super().draw(renderer)


def _new_figure(**kw) -> Figure:
    """A Figure outside pyplot: no backend is chosen or changed, no global figure list grows."""
    return ChainFigure(**kw)


def canvas(ax, panels: int = 1, **figure_kw):
    """Where a figure is drawn: (figure to draw on, its axes, the Figure to return, whether given).

    Parameters
    ----------
    ax : matplotlib.axes.Axes or sequence of Axes or None
        None: a new figure outside pyplot (``_new_figure(**figure_kw)``), with ``panels`` axes stacked
        and sharing x. Else the axes to draw into, one per panel (a single Axes for a one-panel
        figure, (top, bottom) for a two-panel one: a list, tuple or ``fig.subplots(2, 1)``'s array),
        left as they are shared or laid out.
    panels : int
        How many axes the figure draws on.

    Returns
    -------
    tuple
        (the figure or subfigure the axes are on, the Axes or tuple of Axes, the root Figure, given):
        given is True when ax was given, and then the figure's layout is the caller's (no
        tight_layout, no constrained layout, no figure-wide text).
    """
    from matplotlib.axes import Axes

    if ax is None:
        height = figure_kw.pop("height_ratios", None)
        fig = _new_figure(**figure_kw)
        if panels == 1:
            return fig, fig.subplots(), fig, False
        axes = fig.subplots(panels, 1, sharex=True, gridspec_kw={"height_ratios": height} if height else None)
        return fig, tuple(axes), fig, False
    # (a list, a tuple or the array of Axes fig.subplots returns, flattened top to bottom)
    many = isinstance(ax, (list, tuple, np.ndarray))
    axes = tuple(np.asarray(ax, dtype=object).ravel()) if many else (ax,)
    if len(axes) != panels or not all(isinstance(a, Axes) for a in axes):
        want = "one matplotlib Axes" if panels == 1 else f"a sequence of {panels} matplotlib Axes (top to bottom)"
        raise PlotError(f"ax: this figure draws on {want}, got {ax!r}")
    host = axes[0].get_figure(root=False)
    if any(a.get_figure(root=False) is not host for a in axes):
        raise PlotError("ax: the axes of one figure must all be on the same figure")
    return host, axes[0] if panels == 1 else axes, axes[0].get_figure(root=True), True


def _unsafe(e: OSError) -> PlotError:
    return PlotError(f"{e}; nothing was written there")


def _not_written(path: Path, e: OSError) -> PlotError:
    """A figure or its CSV that could not be written (a read-only directory, a full disk): one
    sentence naming the directory and the fix. (Written atomically: nothing half-written is left.)"""
    if isinstance(e, safe_files.UnsafeFileError):
        return _unsafe(e)
    where = path.parent
    if e.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        fix = "make it writable, or copy the directory somewhere writable and plot the copy"
    elif e.errno in (errno.ENOSPC, errno.EDQUOT):
        fix = "free some space there (or copy the directory to another disk and plot the copy)"
    else:
        fix = "check that directory, or copy it somewhere else and plot the copy"
    return PlotError(f"{where}: cannot write {path.name} there ({e.strerror or e}); {fix}")


def save_figure(fig: Figure, base: Path, formats=("png",)) -> list[Path]:
    """fig as base.<format> for each format, written atomically and never through a symbolic link
    (granchain.safe_files: a link planted at the name is refused, its target untouched)."""
    out = []
    for fmt in check_formats(formats):
        p = base.with_name(f"{base.name}.{fmt}")
        try:
            safe_files.save_figure(fig, p, format=fmt, dpi=DPI, metadata={"Date": None} if fmt == "svg" else None)
        except OSError as e:  # the filesystem's answer (a link refused, read-only, full), not a bug
            raise _not_written(p, e) from None
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
    except OSError as e:
        raise _not_written(path, e) from None


def _cmap(name: str):
    return matplotlib.colormaps[name]


def _plain(text: str) -> str:
    """User text (a scene title) shown as is: a $ would start mathtext; control characters escaped (a
    no-break space kept: the figures' own texts hold a number to its unit with one)."""
    return printable(str(text), keep="\N{NO-BREAK SPACE}").replace("$", r"\$")


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


#: the contact axis's label: a contact's index (the unit every axis label ends with, in parentheses)
CONTACT_LABEL = r"contact $i$ between bead $i$ and $i+1$ (index)"


#: marker size (points) of the peak-force markers; an error bar is drawn where it reaches beyond one
MARKER_SIZE = 3.0


def _error_bars(ax, x: np.ndarray, y: np.ndarray, err: np.ndarray | None, color, label: str = "") -> int:
    """Error bars of the measured peak-force errors (granchain.workflows.error_estimates) where they reach beyond
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


#: a log axis spanning fewer decades than this gets evenly spaced ticks in plain numbers (7500, 8000, ...),
#: one spanning fewer than LOG_SUBS_DECADES ticks at 1, 2 and 5 of each decade; a wider one a tick per
#: decade: every log axis has tick labels across its data, not one at 100 N below points at 179 N
LOG_PLAIN_DECADES = 1.0
LOG_SUBS_DECADES = 3.0


def _plain_number(v, _pos=None) -> str:
    return f"{v:.6g}"


def log_ticks(axis, lo: float, hi: float) -> None:
    """Tick labels across a log axis's range lo..hi (> 0): evenly spaced plain numbers where it spans less
    than LOG_PLAIN_DECADES, 1, 2 and 5 of each decade below LOG_SUBS_DECADES, matplotlib's decades above."""
    if not (lo > 0 and hi > lo):
        return
    decades = float(np.log10(hi / lo))
    if decades >= LOG_SUBS_DECADES:
        return
    if decades < LOG_PLAIN_DECADES:
        axis.set_major_locator(FixedLocator(_plain_log_ticks(lo, hi)))
        axis.set_minor_locator(NullLocator())
    else:
        axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        axis.set_minor_locator(LogLocator(subs=np.arange(2.0, 10.0)))
    axis.set_major_formatter(FuncFormatter(_plain_number))
    axis.set_minor_formatter(NullFormatter())


def _two_digits(x: float, up: bool) -> float:
    """x rounded to two significant digits, up or down: never past x the other way (x = 1e-9 (1 + 3e-16)
    rounds up to 10 x 1e-10, which is 1e-9, below x: the next two-digit number, 1.1e-9, is taken)."""
    scale = 10.0 ** (np.floor(np.log10(x)) - 1)
    k = (np.ceil if up else np.floor)(x / scale * (1 - 1e-12 if up else 1 + 1e-12))
    value = float(k * scale)
    if value < x if up else value > x:
        value = float((k + 1 if up else k - 1) * scale)
    return value


def _plain_log_ticks(lo: float, hi: float) -> list[float]:
    """Evenly spaced plain numbers across lo..hi (less than a decade), and the two-digit numbers just
    inside each end where the even ones leave it bare: on a log axis even steps crowd the top and leave
    the bottom wide (1..7 got 2, 4, 6: no label within a third of the span of 1)."""
    ticks = [t for t in MaxNLocator(nbins=6, steps=[1, 2, 2.5, 5, 10]).tick_values(lo, hi) if lo <= t <= hi]
    span = np.log10(hi / lo)
    for end in (_two_digits(lo, up=True), _two_digits(hi, up=False)):
        if lo <= end <= hi and all(abs(np.log10(end / t)) > 0.1 * span for t in ticks):
            ticks.append(end)
    return sorted(ticks)


def log_axes_ticks(ax, *secondary) -> None:
    """log_ticks on each log axis of ax at its view limits, and on the secondary y axes drawn beside it
    (each (axes, factor): its values are ax's divided by factor)."""
    if ax.get_xscale() == "log":
        log_ticks(ax.xaxis, *sorted(ax.get_xlim()))
    if ax.get_yscale() == "log":
        lo, hi = sorted(ax.get_ylim())
        log_ticks(ax.yaxis, lo, hi)
        for sec, factor in secondary:
            log_ticks(sec.yaxis, lo / factor, hi / factor)


def _legend_label(model_label: str) -> str:
    """A model_curves label for a legend: its formulas in mathtext."""
    return model_label.replace("(1+beta)/2", r"$(1+\beta)/2$")


#: more lines than this (snapshot times, history contacts) and they are coloured by a colour bar, not
#: named in a legend
LEGEND_MAX = 8


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
