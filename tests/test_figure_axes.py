"""Figures fit for a paper (issue 43 items 2 and 3): on every bundled scene (reference backend) and on
generated ones, every figure of a run has tick labels across its data on each log axis, no text beyond
the canvas and a unit on every axis label; the models' footnotes are whole; under precompression or
gravity the peaks figure shows the dynamic force the run reports, and says so."""

from __future__ import annotations

import functools
import re
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from granchain.physics.effects.gravity import scene_static_forces
from granchain.scene import bundled_scenes, parse_scene
from granchain.workflows import plots
from granchain.workflows.plots.figures import model_curves
from granchain.workflows.run import run_scene

from .figure_checks import check_every_figure, check_figure, drawn
from .scenegen import PEAKS, brass_text
from .test_plot_any_run import small_scene_texts

#: the bundled scenes checked in the fast set (each run and its figures drawn in 1-3 s: a uniform chain,
#: one bead, gravity, precompression, a taper); the others's runs take 1-26 s each: checked in the slow set
#: beside their compare (tests/test_postprocess.py)
FAST = {"classic-two-spheres", "default", "effect-gravity", "effect-precompression", "effect-tapered"}


def _run(text: str, source: str, backend: str = "reference"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the planner's warnings: not the point here
        return run_scene(parse_scene(text, source=source), backend=backend)


@functools.lru_cache(maxsize=4)
def _bundled(name: str):
    """A bundled scene's reference run (shared by this module's tests)."""
    return _run(bundled_scenes()[name], name)


@pytest.mark.parametrize("name", sorted(FAST))
def test_every_figure_of_a_bundled_scene(name):
    """The other bundled scenes' figures are checked in the slow set on the reference run that
    test_postprocess's compare of every bundled scene makes (one run of each, not two)."""
    check_every_figure(_bundled(name))


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=small_scene_texts())
def test_every_figure_of_a_generated_scene(text):
    """On LAMMPS, as test_plot_any_run's generated runs: CI's derandomized draw plans a run of minutes on
    the reference (its fixed price per step)."""
    check_every_figure(_run(text, "generated.toml", backend="lammps"))


@pytest.mark.parametrize("name", ["effect-precompression", "effect-gravity"])
def test_the_peaks_figure_shows_the_dynamic_force_the_run_reports(name):
    """The markers are F_p less each contact's own static force (F0; under gravity also the weight above),
    as leading_peak_force and max_peak_force are, and the axis says so."""
    result = _bundled(name)
    fig = plots.figure(result, "peaks")
    ax = fig.axes[0]
    assert "dynamic" in ax.get_ylabel()
    assert re.search(r"F_\{?0", ax.get_ylabel())
    peaks = result.peaks
    static = scene_static_forces(result.scene)[peaks.index.to_numpy() - 1]
    dynamic = peaks["peak_force"].to_numpy(float) - static
    x = np.concatenate([line.get_xdata() for line in ax.lines if line.get_marker() == "o"])
    y = np.concatenate([line.get_ydata() for line in ax.lines if line.get_marker() == "o"])
    order = np.argsort(x)
    on = np.isin(peaks.index.to_numpy(), x)
    assert np.array_equal(y[order], dynamic[on])
    m = result.observables()["max_peak_force"]
    assert float(np.max(y)) == pytest.approx(m, rel=1e-12)


def test_the_models_footnote_is_whole_and_inside_the_canvas():
    """Every model left out is named with its whole reason (no "..."), the lines inside the figure."""
    result = _bundled("effect-precompression")
    fig = plots.figure(result, "peaks")
    drawn(fig)
    note = " ".join(" ".join(t.get_text() for t in fig.texts).split())
    skipped: dict[str, str] = {}
    model_curves(result.scene, plots.load_peaks(result).contact, skipped)
    assert skipped
    for label, reason in skipped.items():
        assert label in note
        assert " ".join(reason.split()) in note
    assert not re.search(r"\.\.\.|…", note)
    check_figure(fig)


def test_compare_figures_of_a_precompressed_chain(tmp_path):
    """A compare directory (two reference runs here: the figures read run directories alike): the peak
    profiles are the dynamic forces compare reports, and both figures keep the three rules."""
    from granchain.workflows.plots.overlays import compare_peaks, figure_compare

    text = brass_text(20, 'kind = "velocity"\nvelocity = 0.5\n', PEAKS + "histories = [1, 5, 10]\n")
    text += "[precompression]\nforce = 20.0\n"
    for name, method in (("lammps", "verlet"), ("reference", "rk4")):
        run_scene(parse_scene(text, source="cmp.toml"), backend="reference", method=method, out=tmp_path / name)
    p = compare_peaks(tmp_path)
    total = plots.load_peaks(tmp_path / "reference").peak_force
    assert np.array_equal(p.reference, total[p.contact - 1] - 20.0)
    assert "dynamic" in p.label
    check_figure(figure_compare(tmp_path, "peaks"))
    check_figure(figure_compare(tmp_path, "histories"))


@settings(max_examples=200, deadline=None)
@given(lo=st.floats(1e-9, 1e9), decades=st.floats(0.05, 0.999))
@example(lo=1.0000000000000003e-09, decades=0.75)  # its two-digit end rounded to 1e-9, below lo: no label near lo
def test_a_log_axis_under_a_decade_has_a_label_near_each_end(lo, decades):
    """Evenly spaced labels on a log axis leave its bottom bare (a 7-contact chain's x axis 0.88..7.7 got
    2, 4, 6: log10(2/0.88) = 0.36, above a third of its 0.94 decades): log_ticks puts one near each end,
    the rule figure_checks holds every figure to."""
    from matplotlib.figure import Figure

    from granchain.workflows.plots.canvas import log_ticks

    hi = lo * 10**decades
    ax = Figure().add_subplot()
    ax.set_xscale("log")
    ax.set_xlim(lo, hi)
    log_ticks(ax.xaxis, lo, hi)
    ticks = np.array([t for t in ax.xaxis.get_majorticklocs() if lo <= t <= hi])
    reach = max(decades / 3, np.log10(1.5))
    assert ticks.size
    assert np.min(np.abs(np.log10(ticks / lo))) <= reach
    assert np.min(np.abs(np.log10(ticks / hi))) <= reach


def test_the_models_note_is_whole_under_axes_the_caller_gave():
    """Drawn into a caller's axes (ax=), the peaks figure writes no figure-wide footnote and lays
    nothing out: the note on the models left out is under those axes, every reason whole."""
    from matplotlib.figure import Figure

    result = _bundled("effect-precompression")
    host = Figure(figsize=(6, 4))
    ax = host.subplots()
    position = ax.get_position().bounds
    assert plots.figure(result, "peaks", ax=ax) is host
    assert not host.texts  # nothing across the caller's figure
    assert ax.get_position().bounds == position  # no tight_layout of the caller's figure
    note = " ".join(" ".join(t.get_text() for t in ax.texts).split())
    skipped: dict[str, str] = {}
    model_curves(result.scene, plots.load_peaks(result).contact, skipped)
    assert skipped
    for label, reason in skipped.items():
        assert label in note
        assert " ".join(reason.split()) in note
