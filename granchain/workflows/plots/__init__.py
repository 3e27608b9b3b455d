"""Figures of a finished run (a RunResult, in memory or loaded), of its run directory, and of a compare
directory (LAMMPS against the reference).

The figure functions (figure_peaks, figure_histories, figure_snapshots, figure_heatmap; figure(result,
kind); RunResult.plot) take a RunResult or a run directory and return a matplotlib Figure: not saved,
not shown, and made without pyplot, so importing or calling them never changes matplotlib's backend
or pyplot's figures (a notebook shows a returned Figure as the cell's value; ``fig.savefig`` writes it).
plot_peaks, plot_histories, plot_snapshots and plot_heatmap return the same Figure and save it only
when asked (``save=`` a directory, or True for the run's own, with the plotted data as CSV). Each
takes ``ax=``: the matplotlib Axes to draw into (one for peaks and the heat map, (top, bottom) for the
two-panel figures), whose Figure is returned with its layout left to the caller.

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
(figure_compare(source, kind) and Comparison.plot(kind) return either as a Figure, from a Comparison
in memory, a compare directory or a pair of runs; ``ax=``: its (top, bottom) Axes)

Modules: canvas (figures, files, text, markers), tables (a run's data as the figures read it), figures
(a run's figures), spacetime (the heat map), overlays (a compare directory's figures).
"""

from __future__ import annotations

from granchain.results import register_plotter
from granchain.workflows.plots.canvas import FORMATS, PlotError, check_formats, save_figure
from granchain.workflows.plots.figures import (
    FIGURES,
    figure,
    figure_histories,
    figure_peaks,
    figure_snapshots,
    model_curves,
    plot_heatmap,
    plot_histories,
    plot_peaks,
    plot_result,
    plot_run,
    plot_snapshots,
)
from granchain.workflows.plots.overlays import (
    COMPARE_FIGURES,
    HistoryOverlay,
    PeakOverlay,
    compare_histories,
    compare_peaks,
    compared_runs,
    figure_compare,
    is_compare_dir,
    plot_compare,
)
from granchain.workflows.plots.spacetime import (
    HEATMAP_MAX_CELLS,
    SpaceTime,
    figure_heatmap,
    heatmap_data,
    spacetime_force,
)
from granchain.workflows.plots.tables import Peaks, as_result, load_peaks

__all__ = [
    "COMPARE_FIGURES",
    "FIGURES",
    "FORMATS",
    "HEATMAP_MAX_CELLS",
    "HistoryOverlay",
    "PeakOverlay",
    "Peaks",
    "PlotError",
    "SpaceTime",
    "as_result",
    "compared_runs",
    "figure_compare",
    "check_formats",
    "compare_histories",
    "compare_peaks",
    "figure",
    "figure_heatmap",
    "figure_histories",
    "figure_peaks",
    "figure_snapshots",
    "heatmap_data",
    "is_compare_dir",
    "load_peaks",
    "model_curves",
    "plot_compare",
    "plot_heatmap",
    "plot_histories",
    "plot_peaks",
    "plot_result",
    "plot_run",
    "plot_snapshots",
    "save_figure",
    "spacetime_force",
]

register_plotter(plot_result)
