"""Comparison.plot() and ``ax=`` on the figure functions (issue 43 item 4): Comparison.plot(kind) is the
figure ``granchain plot COMPARE_DIR`` writes (the same artists with the same data, drawn from the runs in
memory instead of the directory read back), and a figure function given ``ax`` draws into those axes,
returns their Figure and makes no other figure (pyplot's list of figures untouched)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.figure import Figure

import granchain
from granchain.cli import main
from granchain.workflows import plots
from granchain.workflows.plots import overlays
from tests.figure_checks import check_figure

SCENE = """title = "comparison figure: 16 brass beads"
[chain]
beads = 16
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "impulse"
impulse = 0.05
duration = 1e-6
[run]
end_time = 6e-5
timestep = "auto"
[outputs]
histories = [1, 8]
snapshots = [{snapshots}]
"""


#: 20 snapshot times: enough for the heat map (spacetime_force) and a colour bar on the snapshots
SCENE = SCENE.format(snapshots=", ".join(f"{t:.3g}" for t in np.linspace(3e-6, 5.7e-5, 20)))


@pytest.fixture(scope="module")
def comparison(tmp_path_factory):
    out = tmp_path_factory.mktemp("cmp") / "compare"
    return granchain.compare(granchain.parse_scene(SCENE), rtol=1e-3, out=out, error_estimate=True)


def artists(fig: Figure) -> list[dict]:
    """What a figure shows, per axes (its secondary axes too): texts, scales, limits, every line's and
    collection's data and the legend's entries."""
    out = []
    axes = [*fig.axes, *(c for a in fig.axes for c in a.child_axes)]
    for ax in axes:
        legend = ax.get_legend()
        out.append(
            {
                "texts": (
                    getattr(ax, "get_title", str)(),  # (a secondary axis has no title)
                    ax.get_xlabel(),
                    ax.get_ylabel(),
                    *(t.get_text() for t in ax.texts),
                ),
                "scales": (ax.get_xscale(), ax.get_yscale()),
                "limits": (*ax.get_xlim(), *ax.get_ylim()),
                "lines": [(ln.get_label(), np.asarray(ln.get_xydata(), float)) for ln in ax.lines],
                "collections": [np.asarray(c.get_offsets(), float) for c in ax.collections],
                "legend": [t.get_text() for t in legend.get_texts()] if legend else [],
            }
        )
    return out


def assert_same_artists(a: Figure, b: Figure) -> None:
    got, want = artists(a), artists(b)
    assert len(got) == len(want)
    for g, w in zip(got, want, strict=True):
        assert g["texts"] == w["texts"]
        assert g["scales"] == w["scales"]
        assert g["legend"] == w["legend"]
        np.testing.assert_allclose(g["limits"], w["limits"], rtol=1e-12)
        assert [label for label, _ in g["lines"]] == [label for label, _ in w["lines"]]
        for (_, x), (_, y) in zip(g["lines"], w["lines"], strict=True):
            np.testing.assert_array_equal(x, y)  # the same numbers, NaN where NaN
        assert len(g["collections"]) == len(w["collections"])
        for x, y in zip(g["collections"], w["collections"], strict=True):
            np.testing.assert_array_equal(x, y)


def cli_figures(compare_dir, monkeypatch) -> dict[str, Figure]:
    """The Figures ``granchain plot COMPARE_DIR`` writes, by file name (compare_peaks, ...), as drawn."""
    made = {}
    real = overlays._save

    def keep(fig, base, formats):
        made[base.name] = fig
        return real(fig, base, formats)

    monkeypatch.setattr(overlays, "_save", keep)
    assert main(["plot", str(compare_dir)]) == 0
    return made


def test_comparison_plot_is_the_figure_of_granchain_plot(comparison, monkeypatch, capsys):
    assert comparison.ok
    written = cli_figures(comparison.path, monkeypatch)
    assert set(written) == {"compare_peaks", "compare_histories"}
    for kind in plots.COMPARE_FIGURES:
        fig = comparison.plot(kind)
        assert isinstance(fig, Figure)
        assert len(fig.axes) == 2
        assert_same_artists(fig, written[f"compare_{kind}"])
    with pytest.raises(plots.PlotError, match="unknown comparison figure 'nope'"):
        comparison.plot("nope")


def test_comparison_figures_from_memory_directory_or_pair_are_one_and_readable(comparison):
    for kind in plots.COMPARE_FIGURES:
        check_figure(comparison.plot(kind))  # tick labels over log axes, no text cut off, units on axes
    # a Comparison drawn from the runs in memory, a directory read back, and the pair: the same figure
    assert_same_artists(plots.figure_compare(comparison.path), comparison.plot())
    assert_same_artists(plots.figure_compare((comparison.lammps, comparison.reference)), comparison.plot())


def test_ax_draws_into_the_given_axes_and_makes_no_figure(comparison):
    before = plt.get_fignums()
    run = comparison.reference
    cases = [
        (lambda ax: comparison.plot("peaks", ax=ax), comparison.plot("peaks"), 2),
        (lambda ax: comparison.plot("histories", ax=ax), comparison.plot("histories"), 2),
        (lambda ax: run.plot("peaks", ax=ax), run.plot("peaks"), 1),
        (lambda ax: run.plot("histories", ax=ax), run.plot("histories"), 2),
        (lambda ax: run.plot("snapshots", ax=ax), run.plot("snapshots"), 2),
        (lambda ax: run.plot("heatmap", ax=ax), run.plot("heatmap"), 1),
        (lambda ax: plots.plot_peaks(run, log=False, ax=ax), plots.figure_peaks(run, log=False), 1),
    ]
    for draw, alone, panels in cases:
        host = Figure()
        axes = host.subplots(panels, 1)
        given = axes if panels > 1 else [axes]
        assert draw(axes) is host
        # drawn into them: none replaced, none added but a colour bar's (which takes its room from them)
        assert host.axes[:panels] == list(given)
        assert all(getattr(a, "_colorbar", None) is not None for a in host.axes[panels:])
        assert all(a.lines or a.collections for a in given)
        # the same data lines (error bars, "_" labels, are drawn where they reach beyond the marker on
        # these axes' own size: docs of canvas._error_bars)
        for a, b in zip(given, alone.axes[:panels], strict=True):
            mine, theirs = ([ln for ln in x.lines if not ln.get_label().startswith("_")] for x in (a, b))
            assert [ln.get_label() for ln in mine] == [ln.get_label() for ln in theirs]
            for x, y in zip(mine, theirs, strict=True):
                np.testing.assert_array_equal(x.get_xydata(), y.get_xydata())
    assert plt.get_fignums() == before  # no pyplot figure made


def test_ax_that_does_not_fit_the_figure_is_refused(comparison):
    host = Figure()
    one, two = host.subplots(2, 1)
    with pytest.raises(plots.PlotError, match="a sequence of 2 matplotlib Axes"):
        comparison.plot("peaks", ax=one)
    with pytest.raises(plots.PlotError, match="one matplotlib Axes"):
        comparison.reference.plot("peaks", ax=(one, two))
    with pytest.raises(plots.PlotError, match="same figure"):
        comparison.plot("peaks", ax=(one, Figure().subplots()))
