"""Under precompression or gravity every figure of a run shows the force the run reports, each contact's
force less its static force (issue 43 item 2), and its axis says so: the histories, the snapshots, the
heat map and the compare overlay of the histories as the peaks figure already did. The static forces
are computed here from the scene's own numbers (F0 plus g times the mass above the contact), not by
granchain."""

from __future__ import annotations

import functools
import re
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings

from granchain import plan
from granchain.scene import bundled_scenes, parse_scene
from granchain.workflows import plots
from granchain.workflows.plots.spacetime import heatmap_data, spacetime_force
from granchain.workflows.run import run_scene

from .figure_checks import check_figure
from .scenegen import PEAKS, brass_text, figure_scene_texts

#: a label of the dynamic force: the word, and F_0 (one static force) or F_{0,i} (each contact's own)
DYNAMIC = re.compile(r"dynamic .*- F_(0\$|\{0,i\}\$)")


def _run(scene, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the planner's warnings: not the point here
        return run_scene(scene, backend="reference", **kw)


def expected_static(scene) -> np.ndarray:
    """Each bead-bead contact's force at rest: F0 plus the weight of the beads above it (bead 1 on top; a
    striker, not a bead of the chain at rest, adds none)."""
    n = int(scene.chain.beads)
    masses = np.asarray(scene.bead_masses, float) if scene.per_bead else np.full(n, float(scene.mass))
    return float(scene.effects.precompression) + float(scene.effects.gravity) * np.cumsum(masses)[: n - 1]


@functools.lru_cache(maxsize=2)
def _bundled(name: str):
    """A bundled scene's reference run with 20 snapshots, the heat map's source, beside its histories."""
    scene = parse_scene(bundled_scenes()[name], source=f"{name}.toml")
    end = float(plan(scene).scene.run.end_time)  # the planned end time (a stop check ends no snapshot's run)
    snapshots = [end * (k + 1) / 20 for k in range(19)] + [end]
    return _run(scene.replace({"run.end_time": end, "outputs.snapshots": snapshots}))


def _tol(static: np.ndarray) -> float:
    """Rounding of F - F_static against F_static's size (N)."""
    return 1e-12 * max(1.0, float(np.max(static, initial=0.0)))


def _says_dynamic(label: str, scene) -> None:
    """The label names the dynamic force; with one static force on every contact, its value. One bead has
    no bead-bead contact: its panels show no contact force (a sensor's: dynamic, said so)."""
    if scene.chain.beads < 2:
        assert "contact force" not in label or "dynamic" not in label, label
        return
    assert DYNAMIC.search(label), label
    f0 = float(scene.effects.precompression)
    if not scene.effects.gravity:
        assert f"$F_0$ = {f0:g} N" in label, label


def check_histories(result) -> None:
    """The force panel's lines: each history contact's force less its static force, then each sensor's
    average force less its own static average; the sampled dynamic force stays at or under the dynamic
    peak the run reports (peaks.csv's, measured at every step)."""
    s, scene = result.solution, result.scene
    try:
        fig = plots.figure(result, "histories")
    except plots.PlotError:
        return
    ax = fig.axes[0]
    _says_dynamic(ax.get_ylabel(), scene)
    static = expected_static(scene)
    lines = ax.lines
    force = np.asarray(s.history_force, float).reshape(np.size(s.history_time), len(s.history_contacts))
    peaks = result.peaks
    for k, c in enumerate(i + 1 for i in s.history_contacts):
        y = np.asarray(lines[k].get_ydata(), float)
        np.testing.assert_allclose(y, force[:, k] - static[c - 1], rtol=0, atol=_tol(static))
        if c in peaks.index and np.isfinite(peaks.loc[c, "time_of_peak"]):
            assert y.max() <= peaks.loc[c, "dynamic_peak_force"] * (1 + 1e-9) + 1e-9 * static[c - 1]
    if np.size(s.sensor_history_time):
        padded = np.concatenate(([0.0], static, [_wall_static(scene, static)]))
        for j, bead in enumerate(s.sensor_beads):
            rest = 0.5 * (padded[bead - 1] + padded[bead])
            y = np.asarray(lines[len(s.history_contacts) + j].get_ydata(), float)
            np.testing.assert_allclose(y, s.sensor_history_force[:, j] - rest, rtol=0, atol=_tol(static))


def _wall_static(scene, static: np.ndarray) -> float:
    """The wall's contact at rest: F0 plus the whole chain's weight (a free end: nothing)."""
    if scene.effects.far_end != "wall":
        return 0.0
    n = int(scene.chain.beads)
    masses = np.asarray(scene.bead_masses, float) if scene.per_bead else np.full(n, float(scene.mass))
    return float(scene.effects.precompression) + float(scene.effects.gravity) * float(np.sum(masses))


def check_snapshots(result) -> None:
    """Each snapshot's force line: the contacts' forces less their static forces; the envelope: the
    dynamic peak force the run reports (peaks.csv's dynamic_peak_force)."""
    s, scene = result.solution, result.scene
    if not np.size(s.snapshot_time):
        return
    ax = plots.figure(result, "snapshots").axes[0]
    _says_dynamic(ax.get_ylabel(), scene)
    static = expected_static(scene)
    force = np.asarray(s.snapshot_force, float).reshape(np.size(s.snapshot_time), -1)
    for k in range(force.shape[0]):
        np.testing.assert_allclose(ax.lines[k].get_ydata(), force[k] - static, rtol=0, atol=_tol(static))
    envelope = ax.lines[-1]
    peaks = result.peaks
    assert np.array_equal(envelope.get_xdata(), peaks.index.to_numpy(float))
    assert np.array_equal(envelope.get_ydata(), peaks["dynamic_peak_force"].to_numpy(float))


def check_heatmap(result) -> None:
    """The heat map's cells: the contacts' forces less their static forces (where above the colour
    scale's bottom; below it every cell has the bottom's colour), its colour bar saying so."""
    st, _ = spacetime_force(result)
    if st is None:
        return
    fig = plots.figure(result, "heatmap")
    bar = next(ax for ax in fig.axes if ax.get_label() == "<colorbar>")
    _says_dynamic(bar.get_ylabel(), result.scene)
    mesh = fig.axes[0].collections[0]
    static = expected_static(result.scene)[st.contacts - 1]
    want = heatmap_data(type(st)(st.time, st.contacts, st.force - static, st.source)).force
    got = np.asarray(mesh.get_array(), float).reshape(want.shape)
    shown = np.isfinite(want) & (want > mesh.norm.vmin)
    assert shown.any()
    np.testing.assert_allclose(got[shown], want[shown], rtol=0, atol=_tol(static))


def check_dynamic_figures(result) -> None:
    """Every figure of a run with static forces shows the dynamic force, and its axis says so."""
    check_histories(result)
    check_snapshots(result)
    check_heatmap(result)
    peaks = plots.figure(result, "peaks").axes[0]
    _says_dynamic(peaks.get_ylabel(), result.scene)


@pytest.mark.parametrize("name", ["effect-precompression", "effect-gravity"])
def test_every_figure_of_a_bundled_scene_shows_the_dynamic_force(name):
    result = _bundled(name)
    assert result.solution.history_contacts
    assert np.size(result.solution.snapshot_time) == 20
    check_dynamic_figures(result)
    for kind in ("histories", "snapshots", "heatmap"):
        check_figure(plots.figure(result, kind))


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(text=figure_scene_texts())
def test_every_figure_of_a_generated_static_scene_shows_the_dynamic_force(text):
    """figure_scene_texts' scenes with a static force (precompression, gravity)."""
    assume("[precompression]" in text or "[gravity]" in text)
    result = _run(parse_scene(text, source="generated.toml"))
    check_dynamic_figures(result)


def test_the_compare_histories_show_the_dynamic_force():
    """Both runs' histories less each contact's static force; their difference is unchanged by it."""
    from granchain.workflows.plots.overlays import compare_histories, figure_compare

    result = _bundled("effect-precompression")
    verlet = _run(result.scene, method="verlet")
    overlays, _ = compare_histories((verlet, result))
    static = expected_static(result.scene)
    assert overlays
    ax = figure_compare((verlet, result), "histories").axes[0]
    _says_dynamic(ax.get_ylabel(), result.scene)
    force = np.asarray(result.solution.history_force, float).reshape(result.solution.history_time.size, -1)
    for k, o in enumerate(overlays):
        assert o.contact == result.solution.history_contacts[k] + 1
        np.testing.assert_allclose(o.reference, force[:, k] - static[o.contact - 1], rtol=0, atol=1e-9)
        np.testing.assert_array_equal(ax.lines[2 * k + 1].get_ydata(), o.reference)


def test_a_chain_without_a_static_force_shows_the_contact_force():
    """No precompression, no gravity: the contact force as it is, labelled as such."""
    text = brass_text(20, 'kind = "velocity"\nvelocity = 0.5\n', PEAKS + "histories = [1, 5, 10]\n")
    result = _run(parse_scene(text, source="free.toml"))
    ax = plots.figure(result, "histories").axes[0]
    assert "dynamic" not in ax.get_ylabel()
    force = np.asarray(result.solution.history_force, float).reshape(result.solution.history_time.size, -1)
    assert np.array_equal(ax.lines[0].get_ydata(), force[:, 0])
