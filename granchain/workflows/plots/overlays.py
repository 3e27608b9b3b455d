"""The figures of a compare directory (``granchain compare``'s lammps/ and reference/ run directories):
the force histories overlaid with their difference, and the peak force along the chain with the
relative difference."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from granchain.results import RunResult
from granchain.workflows.plots.canvas import (
    CONTACT_LABEL,
    LEGEND_MAX,
    PlotError,
    _cmap,
    _error_bars,
    _method_label,
    _peak_markers,
    _plain,
    _save,
    _time_unit,
    _write_csv,
    canvas,
    check_formats,
    log_axes_ticks,
)
from granchain.workflows.plots.tables import (
    as_result,
    dynamic_histories,
    dynamic_peaks,
    force_label,
    load_peaks,
    static_forces,
)

logger = logging.getLogger(__name__)


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
    #: which force the histories are (tables.force_label: above each contact's static force where it has one)
    label: str = r"contact force $F_{i,i+1}$ (N)"


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
    #: which force the profiles are (tables.dynamic_peaks: above each contact's static force where it has one)
    label: str = r"peak contact force $F_p$ (N)"


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


def compared_runs(source) -> tuple[RunResult, RunResult]:
    """The (LAMMPS, reference) runs of a comparison: a Comparison (granchain.compare; its results in
    memory), a compare directory (read back), or a pair of RunResults or run directories."""
    if hasattr(source, "lammps") and hasattr(source, "reference"):
        return as_result(source.lammps), as_result(source.reference)
    if isinstance(source, (tuple, list)) and len(source) == 2:
        return as_result(source[0]), as_result(source[1])
    d = Path(source)
    if not is_compare_dir(d):
        raise PlotError(
            f"{d}: not a compare directory (granchain compare writes lammps/ and reference/ run directories, "
            "each with a summary.json)"
        )
    return _compare_runs(d)


def compare_histories(compare_dir) -> tuple[list[HistoryOverlay], str]:
    """The force histories of both runs of a comparison (compare_dir: anything compared_runs takes), per
    common history contact, with their difference; or [] and why not."""
    ra, rb = compared_runs(compare_dir)
    missing = [
        f"{name}/histories.csv" for name, r in (("lammps", ra), ("reference", rb)) if not r.solution.history_contacts
    ]
    if missing:
        return [], f"no force histories to compare ({' and '.join(missing)} missing: [outputs] histories)"
    # the dynamic force above each contact's static force where it has one (dynamic_histories), as the
    # runs report it; the same scene's static forces in both, so their difference is the same either way
    a, b = (dict(zip(header, data.T, strict=True)) for header, data, _ in map(dynamic_histories, (ra, rb)))
    static = static_forces(rb)
    contacts = None if static is None else static[: int(rb.scene.chain.beads) - 1]  # the bead-bead ones
    label = force_label(contacts, "contact force", "F_{i,i+1}", HistoryOverlay.label, split=True)
    contacts = sorted(
        {int(k.split("_")[1]) for k in a if k.startswith("force_")}
        & {int(k.split("_")[1]) for k in b if k.startswith("force_")}
    )
    if not contacts:
        return [], "the two runs have no history contact in common"
    out = []
    for c in contacts:
        t, fa, fb, grid = _on_one_grid(a["time"], a[f"force_{c}"], b["time"], b[f"force_{c}"], "LAMMPS", "reference")
        out.append(HistoryOverlay(c, t, fa, fb, fa - fb, grid, label))
    return out, ""


def compare_peaks(compare_dir) -> PeakOverlay:
    """The peak-force profiles of both runs of a comparison (compare_dir: anything compared_runs takes),
    over their common contacts."""
    # the dynamic force above each contact's static force where it has one, as compare's rows are
    (a, label, *_), (b, *_) = (dynamic_peaks(r, load_peaks(r)) for r in compared_runs(compare_dir))
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
        label,
    )


def _draw_compare_histories(overlays: list[HistoryOverlay], la: str, lr: str, ax=None) -> Figure:
    """The force histories of a compare directory's two runs overlaid, their difference below (into
    ax, (top, bottom), when given: canvas)."""
    t_max = max(float(np.max(o.time)) for o in overlays)
    factor, unit = _time_unit(t_max)
    many = len(overlays) > LEGEND_MAX  # then coloured by contact (a colour bar), line styles in the legend
    cmap = _cmap("viridis")
    norm = Normalize(overlays[0].contact, overlays[-1].contact) if many else None
    layout = "constrained" if many else None
    fig, (ax1, ax2), root, given = canvas(ax, 2, figsize=(9, 7.5), layout=layout, height_ratios=[2.2, 1])
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
        cb = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=[ax1, ax2], label=r"contact $i$ (index)")
        cb.ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax2.axhline(0.0, color="0.5", lw=0.6)
    ax1.set_ylabel(overlays[0].label)
    ax2.set_ylabel(r"$F^{\mathrm{LAMMPS}} - F^{\mathrm{ref}}$ (N)")
    ax2.set_xlabel(rf"time $t$ ({unit})")
    peak = max(float(np.max(np.abs(o.reference))) for o in overlays) or 1.0
    sec = ax2.secondary_yaxis("right", functions=(lambda x: x / peak, lambda y: y * peak))
    sec.set_ylabel(r"$/\ \max\,|F^{\mathrm{ref}}|$ (1)", fontsize=9)
    ax1.set_title(f"Force histories: LAMMPS {la}, wide pale lines; reference {lr}, dashed", fontsize=9)
    ax2.set_title(f"difference, LAMMPS − reference; {_plain(overlays[0].grid)}", fontsize=8)
    ax1.legend(fontsize=7, ncol=1 if many else min(3, len(overlays)))
    if not many:
        ax2.legend(fontsize=7, ncol=min(3, len(overlays)))
        if not given:
            fig.tight_layout()
    for a in (ax1, ax2):
        a.grid(alpha=0.3)
    return root


def _plot_compare_histories(d: Path, pair, la: str, lr: str, formats, skipped) -> list[Path]:
    overlays, why = compare_histories(pair)
    if not overlays:
        if skipped is not None:
            skipped["compare_histories"] = why
        (logger.info if skipped is not None else logger.warning)("%s: history overlay not drawn: %s", d, why)
        return []
    made = _save(_draw_compare_histories(overlays, la, lr), d / "compare_histories", formats)
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


def _draw_compare_peaks(p: PeakOverlay, la: str, lr: str, ax=None):
    """(Figure, CSV header, CSV columns) of the peak profiles of a comparison's two runs (into ax,
    (top, bottom), when given: canvas)."""
    fig, (ax1, ax2), root, given = canvas(ax, 2, figsize=(9, 7.5), height_ratios=[2.2, 1])
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
    ax1.set_ylabel(p.label)
    ax2.set_ylabel(r"$|F_p^{\mathrm{LAMMPS}} - F_p^{\mathrm{ref}}|\,/\,F_p^{\mathrm{ref}}$ (1)")
    ax2.set_xlabel(CONTACT_LABEL)
    ax1.set_title("Peak force along the chain: LAMMPS vs reference", fontsize=9)
    ax2.set_title("relative difference of the peak force (log scale; colour: its sign)", fontsize=8)
    ax1.legend(fontsize=8)
    if ax2.lines:
        ax2.legend(fontsize=7)
    for a in (ax1, ax2):
        a.grid(alpha=0.3, which="both")
        log_axes_ticks(a)
    if not given:
        fig.tight_layout()
    err = None if p.lammps_error is None else np.where(reached, p.lammps_error, np.nan)
    if _error_bars(ax1, p.contact, p.lammps, err, "C0", "LAMMPS measured error, where beyond the marker"):
        ax1.legend(fontsize=8)
    header = ["contact", "lammps", "reference", "relative_difference"]
    cols = [p.contact, p.lammps, p.reference, p.relative_difference]
    if p.has_complete:
        header, cols = [*header, "complete"], [*cols, p.complete.astype(float)]
    return root, header, cols


def _plot_compare_peaks(d: Path, pair, la: str, lr: str, formats) -> list[Path]:
    fig, header, cols = _draw_compare_peaks(compare_peaks(pair), la, lr)
    made = _save(fig, d / "compare_peaks", formats)
    _write_csv(d / "compare_peaks_plot.csv", header, cols)
    return made


def plot_compare(compare_dir: str | Path, formats=("png",), skipped: dict[str, str] | None = None) -> list[Path]:
    """The figures of a compare directory (compare_histories, compare_peaks), in each format, written in
    it beside compare.csv; returns the figure files. skipped: as in plot_run."""
    d = Path(compare_dir)
    formats = check_formats(formats)
    pair = compared_runs(d)  # read once, drawn twice
    la, lr = (_method_label(r.summary) for r in pair)
    return [
        *_plot_compare_histories(d, pair, la, lr, formats, skipped),
        *_plot_compare_peaks(d, pair, la, lr, formats),
    ]


#: the figures of a comparison: figure_compare(source, kind) and Comparison.plot(kind)
COMPARE_FIGURES = ("peaks", "histories")


def figure_compare(source, kind: str = "peaks", ax=None) -> Figure:
    """A figure of a comparison, the one ``granchain plot COMPARE_DIR`` writes, as a Figure.

    Parameters
    ----------
    source : granchain.workflows.comparison_frame.Comparison or str or pathlib.Path or tuple
        A Comparison (granchain.compare, its runs in memory: no directory needed), a compare
        directory, or a (LAMMPS, reference) pair of RunResults or run directories (compared_runs).
    kind : {"peaks", "histories"}
        compare_peaks.png's figure (peak force along the chain, the relative difference below) or
        compare_histories.png's (the force histories overlaid, their difference below).
    ax : sequence of two matplotlib Axes, optional
        (top, bottom) to draw into, their Figure returned and its layout left to the caller; without
        it a new Figure outside pyplot (no backend chosen or changed).

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    PlotError
        kind is unknown, ax is not two Axes of one figure, or the runs recorded no common force history
        (kind "histories"; the message says why).
    """
    if kind not in COMPARE_FIGURES:
        raise PlotError(f"unknown comparison figure {kind!r}: choose one of {', '.join(COMPARE_FIGURES)}")
    pair = compared_runs(source)
    la, lr = (_method_label(r.summary) for r in pair)
    if kind == "peaks":
        return _draw_compare_peaks(compare_peaks(pair), la, lr, ax)[0]
    overlays, why = compare_histories(pair)
    if not overlays:
        raise PlotError(why)
    return _draw_compare_histories(overlays, la, lr, ax)
