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
from .scenegen import LONG_TITLE, PEAKS, brass_text, figure_scene_texts

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


#: the first failure of figure_scene_texts' draws: a title of three lines (wrapped when drawn) laid out
#: as one, its first line above the canvas (a single bead's panel; 3 px on a longer chain)
LONG_TITLE_ON_ONE_BEAD = (
    f'title = "{LONG_TITLE}"\n[chain]\nbeads = 1\nradius = 0.0078125\nmaterial = "aluminium-6061-t6"\n'
    '[contact]\nlaw = "bilinear"\nunloading_coeff = 0.0\nplastic_stiffness = 1000000.0\n[loading]\n'
    'kind = "step"\namplitude = 1.0\nduration = 1e-06\n[boundary]\nfar_end = "wall"\n[run]\n'
    'end_time = 0.0002457336425581325\ntimestep = "auto"\n[outputs]\npeak_force = true\n'
)
GENERATED = {"deadline": None, "suppress_health_check": [HealthCheck.too_slow, HealthCheck.filter_too_much]}


#: a run with sensor beads and no contact histories: its velocity panel empty, its legend() warned
SENSORS_ONLY = (
    '[chain]\nbeads = 2\nradius = 0.0078125\nmaterial = "aluminium-6061-t6"\n[contact]\nlaw = "bilinear"\n'
    'unloading_coeff = 0.0\nplastic_stiffness = 1000000.0\n[loading]\nkind = "step"\namplitude = 1.0\n'
    'duration = 1e-06\n[run]\nend_time = 0.0001233939587222168\ntimestep = "auto"\n[outputs]\n'
    "peak_force = true\nsensors = [2]\n"
)

#: one bead with 20 snapshots: the heat map's x-t diagram had no contact column (max() of nothing raised)
ONE_BEAD_SNAPSHOTS = (
    '[chain]\nbeads = 1\nradius = 0.0078125\nmaterial = "aluminium-6061-t6"\n[contact]\nlaw = "bilinear"\n'
    'unloading_coeff = 0.0\nplastic_stiffness = 1000000.0\n[loading]\nkind = "velocity"\nvelocity = 1.0\n'
    '[boundary]\nfar_end = "wall"\n[run]\nend_time = 0.0002447336425581325\ntimestep = "auto"\n[outputs]\n'
    f"peak_force = true\nsnapshots = {[0.0002447336425581325 * (i + 1) / 20 for i in range(20)]!r}\n"
)


def _check_generated(text: str, log: bool, compare: bool) -> None:
    """Every figure of a generated scene's reference run (the peaks on log or linear axes), and with
    compare both compare figures of it against the same scene's reference Verlet run standing in for
    LAMMPS (as test_compare_figures_of_a_precompressed_chain: the figures read any pair alike)."""
    result = _run(text, "generated.toml")
    check_every_figure(result, log=log)
    if not compare:
        return
    from granchain.workflows.plots.overlays import figure_compare

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        verlet = run_scene(parse_scene(text, source="cmp.toml"), backend="reference", method="verlet")
    for kind in plots.COMPARE_FIGURES:
        try:
            fig = figure_compare((verlet, result), kind)
        except plots.PlotError:  # no common force history: no overlay to draw
            continue
        check_figure(fig)


@settings(max_examples=3, **GENERATED)
@given(text=figure_scene_texts(), log=st.booleans(), compare=st.booleans())
def test_every_figure_of_a_generated_scene(text, log, compare):
    """figure_scene_texts' cheap scenes (1-12 beads, at most FIGURE_STEPS steps on the reference): 3 in
    the fast set, 30 in the slow one."""
    _check_generated(text, log, compare)


@pytest.mark.slow
@settings(max_examples=30, **GENERATED)
@given(text=figure_scene_texts(), log=st.booleans(), compare=st.booleans())
@example(text=LONG_TITLE_ON_ONE_BEAD, log=True, compare=False)
@example(text=SENSORS_ONLY, log=False, compare=False)
@example(text=ONE_BEAD_SNAPSHOTS, log=False, compare=False)
def test_every_figure_of_30_generated_scenes(text, log, compare):
    """The acceptance's 30 generated scenes (issue 43), every figure of each."""
    _check_generated(text, log, compare)


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
