"""Figures (granchain.workflows.plots): formats, the LAMMPS-vs-reference overlay, the x-t heat map.

Fast: every run directory here comes from the reference solver on a 24-bead chain (well under a
second each). A compare directory is what ``granchain compare`` writes, lammps/ and reference/ run
directories side by side; here both are reference runs (Verlet in lammps/, RK4 in reference/), which
is all plot_compare reads: it compares two run directories, whichever backend wrote them.
"""

import logging
import shutil
import warnings
import xml.etree.ElementTree as ET

import matplotlib.pyplot as plt
import numpy as np
import pytest

from granchain.exceptions import GranchainError, UsageError
from granchain.schedule import step_plan, step_times
from granchain.workflows import plots
from granchain.workflows.plots import (
    FORMATS,
    HEATMAP_MAX_CELLS,
    SpaceTime,
    canvas,
    check_formats,
    compare_histories,
    compare_peaks,
    heatmap_data,
    load_peaks,
    plot_compare,
    plot_run,
    spacetime_force,
)
from granchain.workflows.run import run_scene

from .conftest import make_scene

BEADS = 24
DT = 2e-8
END = 1.2e-4  # the leading wave is about two thirds down the chain: some peaks are not complete
SNAPSHOTS = np.linspace(4e-6, END, 25)


def scene(outputs: str, timestep: float = DT):
    return make_scene(beads=BEADS, end_time=END, timestep=timestep, outputs=outputs)


def run(sc, out, method="rk4"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a fixed time step may draw an AccuracyWarning: not the point here
        run_scene(sc, method=method, out=out)
    return out


@pytest.fixture(scope="module")
def snaps_run(tmp_path_factory):
    """Many snapshots (a heat map from snapshots.csv), three history contacts."""
    times = ", ".join(repr(float(t)) for t in SNAPSHOTS)
    return run(scene(f"histories = [1, 5, 10]\nsnapshots = [{times}]"), tmp_path_factory.mktemp("p") / "snaps")


@pytest.fixture(scope="module")
def all_histories_run(tmp_path_factory):
    """Histories at every contact, no snapshots (a heat map from histories.csv)."""
    contacts = ", ".join(str(i) for i in range(1, BEADS))
    return run(scene(f"histories = [{contacts}]"), tmp_path_factory.mktemp("p") / "hist")


@pytest.fixture(scope="module")
def compare_dir(tmp_path_factory):
    """A compare directory of two runs on the same time step (Verlet in lammps/, RK4 in reference/)."""
    d = tmp_path_factory.mktemp("p") / "cmp"
    sc = scene("histories = [1, 5, 10]\nsnapshots = [6e-5]")
    run(sc, d / "lammps", method="verlet")
    run(sc, d / "reference", method="rk4")
    return d


@pytest.fixture(scope="module")
def compare_dir_two_grids(tmp_path_factory):
    """lammps/ (Verlet) ran half the time step of reference/ (RK4) and samples its histories every step,
    the reference every other step: the two histories are on different grids, the reference's coarser."""
    d = tmp_path_factory.mktemp("p") / "cmp2"
    out = "histories = [1, 5, 10]\nhistory_interval = {}"
    run(scene(out.format(DT / 2), timestep=DT / 2), d / "lammps", method="verlet")
    run(scene(out.format(2 * DT)), d / "reference", method="rk4")
    return d


def set_complete(run_dir, complete=None):
    """Rewrite peaks.csv with the given complete column (0/1), or without one (None): run directories
    are written with or without it depending on the granchain version, and the plots read both."""
    path = run_dir / "peaks.csv"
    header, *rows = [line.split(",") for line in path.read_text().splitlines()]
    if "complete" in header:  # the columns from complete on (complete, leading_pulse_force, arrival_time)
        k = header.index("complete")
        header, rows = header[:k], [r[:k] for r in rows]
    if complete is not None:
        header, rows = [*header, "complete"], [[*r, str(int(c))] for r, c in zip(rows, complete, strict=True)]
    path.write_text("\n".join(",".join(r) for r in [header, *rows]) + "\n")


def front_incomplete(run_dir):
    """complete = 0 for the last few reached contacts (the front at the end of the run), 1 elsewhere."""
    pk = load_peaks(run_dir)
    last = np.flatnonzero(pk.reached)[-3:]
    complete = np.ones(pk.contact.size, bool)
    complete[last] = False
    return complete


def copy(src, tmp_path, name="run"):
    dst = tmp_path / name
    shutil.copytree(src, dst)
    return dst


def assert_valid(path, fmt):
    data = path.read_bytes()
    if fmt == "png":
        assert data.startswith(b"\x89PNG\r\n\x1a\n"), path
    elif fmt == "pdf":
        assert data.startswith(b"%PDF"), path
    else:
        assert ET.fromstring(data).tag.endswith("svg"), path
    assert len(data) > 5_000, path


# ---- formats


def test_every_figure_in_every_format(snaps_run, tmp_path):
    r = copy(snaps_run, tmp_path)
    skipped = {}
    made = plot_run(r, formats=FORMATS, skipped=skipped)
    assert skipped == {}
    stems = ("peaks", "histories", "snapshots", "heatmap")
    assert sorted(p.name for p in made) == sorted(f"{s}.{f}" for s in stems for f in FORMATS)
    for p in made:
        assert_valid(p, p.suffix[1:])
    for s in stems:
        assert (r / f"{s}_plot.csv").exists()


def test_default_format_is_png_alone(compare_dir, tmp_path):
    r = copy(compare_dir / "reference", tmp_path)
    made = plot_run(r)
    assert {p.suffix for p in made} == {".png"}
    assert not list(r.glob("*.pdf"))
    assert not list(r.glob("*.svg"))


def test_compare_in_every_format(compare_dir, tmp_path):
    d = copy(compare_dir, tmp_path)
    made = plot_compare(d, formats="svg,pdf,png")
    assert sorted(p.name for p in made) == sorted(
        f"{s}.{f}" for s in ("compare_histories", "compare_peaks") for f in FORMATS
    )
    for p in made:
        assert p.parent == d
        assert_valid(p, p.suffix[1:])


def test_format_names():
    assert check_formats("png, PDF,.svg") == ("png", "pdf", "svg")
    assert check_formats(["pdf", "pdf"]) == ("pdf",)


@pytest.mark.parametrize("formats", [("png", "jpg"), "png,eps", "", ()])
def test_unknown_or_no_format_is_a_usage_error_before_anything_is_written(formats, compare_dir, tmp_path):
    d = copy(compare_dir, tmp_path)
    before = sorted(p.name for p in d.rglob("*"))
    with pytest.raises(UsageError, match="png, pdf, svg") as e:
        plot_run(d / "reference", formats=formats)
    assert isinstance(e.value, GranchainError)
    assert isinstance(e.value, ValueError)
    if formats and formats != ():
        assert "unknown figure format" in str(e.value)
    with pytest.raises(UsageError):
        plot_compare(d, formats=formats)
    assert sorted(p.name for p in d.rglob("*")) == before


# ---- the heat map


def test_heatmap_skipped_with_a_reason_without_whole_chain_time_data(compare_dir, tmp_path, caplog):
    r = copy(compare_dir / "reference", tmp_path)  # 3 history contacts, 1 snapshot, no dump
    st, why = spacetime_force(r)
    assert st is None
    for word in ("no whole-chain time data", "chain.dump", "dump_interval", "snapshots.csv has 1", "3 contact"):
        assert word in why
    skipped = {}
    made = plot_run(r, skipped=skipped)
    assert skipped == {"heatmap": why}
    assert not list(r.glob("heatmap*"))
    assert {p.stem for p in made} == {"peaks", "histories", "snapshots"}
    # without a skipped dict the reason is logged as a warning, not lost
    with caplog.at_level(logging.WARNING, logger=plots.__name__):
        plot_run(r)
    assert any("heat map not drawn" in m and "dump_interval" in m for m in caplog.messages)


def test_heatmap_from_snapshots_is_the_snapshot_forces(snaps_run):
    st, why = spacetime_force(snaps_run)
    assert why == ""
    assert "snapshots.csv" in st.source
    assert np.allclose(st.time, SNAPSHOTS, rtol=1e-12)
    assert np.array_equal(st.contacts, np.arange(1, BEADS))
    data = np.genfromtxt(snaps_run / "snapshots.csv", delimiter=",", names=True)
    for k, t in enumerate(st.time):
        rows = data[data["time"] == t]
        assert np.array_equal(st.force[k], rows["contact_force"][:-1])  # bead N has no contact
    # the picture is the wave: the most loaded contact moves down the chain as time goes on (a diagonal band)
    lead = st.contacts[np.argmax(st.force, axis=1)]
    assert np.corrcoef(st.time, lead)[0, 1] > 0.95
    assert lead[-1] > lead[0] + 10


def test_heatmap_from_histories_at_every_contact(all_histories_run, tmp_path):
    r = copy(all_histories_run, tmp_path)
    st, why = spacetime_force(r)
    assert why == ""
    assert "histories.csv" in st.source
    assert np.array_equal(st.contacts, np.arange(1, BEADS))
    made = plot_run(r, formats=("png",))
    assert r / "heatmap.png" in made
    plotted = np.genfromtxt(r / "heatmap_plot.csv", delimiter=",", names=True)
    assert np.array_equal(plotted["force_7"], heatmap_data(st).force[:, 6])  # block maxima past 1500 frames


def write_dump(path, steps, force):
    """A whole-chain LAMMPS text dump as granchain's decks write it (chain_dump.lmp.j2): d_fc on each bead."""
    n = force.shape[1] + 1
    with open(path, "w") as fh:
        for step, f in zip(steps, force, strict=True):
            fh.write(f"ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{n}\n")
            fh.write("ITEM: BOX BOUNDS ss pp pp\n0 1\n-0.1 0.1\n-0.1 0.1\n")
            fh.write("ITEM: ATOMS id x y z vx vy vz d_fc v_vel v_ux\n")
            for b, fc in enumerate(np.append(f, 0.0)):
                fh.write(f"{b + 1} {b * 0.01} 0 0 0 0 0 {float(fc)!r} 0 0\n")


def test_heatmap_from_a_whole_chain_dump(all_histories_run, tmp_path):
    # a chain.dump of every other history sample, as a LAMMPS run with dump_interval writes it: frames
    # named by step number, which the heat map turns into times with the run's step plan
    r = copy(all_histories_run, tmp_path)
    hist = np.genfromtxt(r / "histories.csv", delimiter=",", skip_header=1)[::2]
    times = step_times(step_plan(END, DT, 1e-6), DT)
    steps = np.searchsorted(times, hist[:, 0] * (1 - 1e-12))
    assert np.allclose(times[steps], hist[:, 0], rtol=1e-12, atol=0)
    force = hist[:, 1:BEADS]
    write_dump(r / "chain.dump", steps, force)
    st, why = spacetime_force(r)
    assert why == ""
    assert "chain.dump" in st.source
    assert np.array_equal(st.time, times[steps])
    assert st.time.size >= 20
    assert np.array_equal(st.force, force)
    made = plot_run(r, formats=("png", "svg"))
    assert {r / "heatmap.png", r / "heatmap.svg"} <= set(made)


def test_heatmap_reduction_keeps_the_peaks():
    rng = np.random.default_rng(1)
    force = rng.random((3 * HEATMAP_MAX_CELLS + 7, 40))
    force[1234, 17] = 99.0
    st = heatmap_data(SpaceTime(np.arange(force.shape[0]) * 1e-6, np.arange(1, 41), force, "test"))
    assert st.force.shape == (HEATMAP_MAX_CELLS, 40) or st.force.shape[0] <= HEATMAP_MAX_CELLS
    assert st.force.max() == 99.0
    assert st.time.size == st.force.shape[0]
    assert "maximum over blocks of 4 frames" in st.source


# ---- the LAMMPS-vs-reference overlay


def test_overlay_difference_is_the_difference_of_the_two_runs(compare_dir, tmp_path):
    d = copy(compare_dir, tmp_path)
    for sub in ("lammps", "reference"):
        set_complete(d / sub, front_incomplete(d / sub))
    overlays, why = compare_histories(d)
    assert why == ""
    assert [o.contact for o in overlays] == [1, 5, 10]
    lam = np.genfromtxt(d / "lammps" / "histories.csv", delimiter=",", names=True)
    ref = np.genfromtxt(d / "reference" / "histories.csv", delimiter=",", names=True)
    for o in overlays:
        assert o.grid == "both on the same sample times"
        assert np.array_equal(o.time, lam["time"])
        assert np.array_equal(o.lammps, lam[f"force_{o.contact}"])
        assert np.array_equal(o.reference, ref[f"force_{o.contact}"])
        assert np.array_equal(o.difference, lam[f"force_{o.contact}"] - ref[f"force_{o.contact}"])
        assert 0 < np.max(np.abs(o.difference)) < 1e-2 * np.max(o.reference)  # Verlet vs RK4: small, not zero
    p = compare_peaks(d)
    a, b = load_peaks(d / "lammps"), load_peaks(d / "reference")
    assert np.array_equal(p.contact, a.contact)
    assert np.array_equal(p.lammps, a.peak_force)
    ok = a.reached & b.reached
    assert np.array_equal(p.reached, ok)
    assert np.array_equal(p.relative_difference[ok], (a.peak_force[ok] - b.peak_force[ok]) / b.peak_force[ok])
    assert np.all(np.isnan(p.relative_difference[~ok]))
    assert p.has_complete
    assert p.complete.any()
    assert not p.complete.all()
    # the figures' CSVs hold what was plotted
    plot_compare(d)
    h = np.genfromtxt(d / "compare_histories_plot.csv", delimiter=",", names=True)
    for o in overlays:
        rows = h[h["contact"] == o.contact]
        assert np.array_equal(rows["difference"], o.difference)
    c = np.genfromtxt(d / "compare_peaks_plot.csv", delimiter=",", names=True)
    assert np.array_equal(c["relative_difference"], p.relative_difference, equal_nan=True)


def test_overlay_on_two_time_grids_interpolates_the_finer_run(compare_dir_two_grids):
    overlays, _ = compare_histories(compare_dir_two_grids)
    ref = np.genfromtxt(compare_dir_two_grids / "reference" / "histories.csv", delimiter=",", names=True)
    for o in overlays:
        assert "LAMMPS interpolated (cubic spline) to the reference samples" == o.grid
        assert np.array_equal(o.time, ref["time"])  # the coarser grid
        assert np.array_equal(o.reference, ref[f"force_{o.contact}"])
        assert np.array_equal(o.difference, o.lammps - o.reference)
        # a linear interpolation's error (h^2 F''/8) would be of the order of 1e-3 of the peak here
        assert np.max(np.abs(o.difference)) < 1e-3 * np.max(o.reference)


def test_plot_compare_needs_a_compare_directory(compare_dir):
    with pytest.raises(GranchainError, match="not a compare directory"):
        plot_compare(compare_dir / "reference")


def test_overlay_without_histories_is_skipped_with_a_reason(compare_dir, tmp_path):
    d = copy(compare_dir, tmp_path)
    (d / "lammps" / "histories.csv").unlink()
    skipped = {}
    made = plot_compare(d, skipped=skipped)
    assert [p.name for p in made] == ["compare_peaks.png"]
    assert "lammps/histories.csv missing" in skipped["compare_histories"]


# ---- peaks.csv with and without the complete column


def test_incomplete_peaks_get_open_markers(compare_dir, tmp_path):
    r = copy(compare_dir / "reference", tmp_path)
    set_complete(r, front_incomplete(r))
    pk = load_peaks(r)
    assert pk.has_complete
    assert (pk.reached & ~pk.complete).any()
    fig, ax = plt.subplots()
    canvas._peak_markers(ax, pk.contact, pk.peak_force, pk.reached, pk.complete, pk.has_complete, "run")
    filled, hollow = ax.lines
    assert np.array_equal(filled.get_xdata(), pk.contact[pk.reached & pk.complete])
    assert np.array_equal(hollow.get_xdata(), pk.contact[pk.reached & ~pk.complete])
    assert hollow.get_markerfacecolor() == "none"
    assert filled.get_markerfacecolor() != "none"
    plt.close(fig)


def test_peaks_csv_without_the_complete_column(compare_dir, tmp_path):
    d = copy(compare_dir, tmp_path)
    for sub in ("lammps", "reference"):
        set_complete(d / sub, None)
        assert (d / sub / "peaks.csv").read_text().startswith("contact,peak_force,time_of_peak,peak_force_nondim\n")
    pk = load_peaks(d / "reference")
    assert not pk.has_complete
    assert pk.complete.all()
    made = plot_run(d / "reference") + plot_compare(d)
    assert all(p.exists() for p in made)
    assert "complete" not in (d / "reference" / "peaks_plot.csv").read_text().splitlines()[0]
    assert not compare_peaks(d).has_complete
    # and with it, the column is carried into the plotted data
    set_complete(d / "reference", front_incomplete(d / "reference"))
    plot_run(d / "reference")
    assert (d / "reference" / "peaks_plot.csv").read_text().splitlines()[0].startswith("contact,peak_force,complete")


def test_a_dollar_in_the_title_is_text_not_mathtext(compare_dir, tmp_path):
    r = copy(compare_dir / "reference", tmp_path)
    toml = (r / "scene.toml").read_text()
    (r / "scene.toml").write_text('title = "costs $5 and $F_{x$"\n' + toml)
    assert plot_run(r)  # an unbalanced $...$ would make matplotlib's mathtext raise


def test_error_bars_only_where_larger_than_the_marker():
    """Issue 15 item 6: an error bar is drawn where it reaches beyond the marker, in display space."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from granchain.workflows.plots.canvas import _error_bars

    fig, ax = plt.subplots(figsize=(6, 4), dpi=100)
    x = np.arange(1.0, 6.0)
    y = np.array([100.0, 80.0, 60.0, 40.0, 20.0])
    ax.set_xlim(0, 6)
    ax.set_ylim(0, 120)
    # 1 pixel is 120 N / ~300 px = 0.4 N: 1e-3 N hides in the marker, 10 N does not; nan: no estimate
    err = np.array([1e-3, 10.0, np.nan, 0.0, 30.0])
    assert _error_bars(ax, x, y, err, "k") == 2
    assert _error_bars(ax, x, y, None, "k") == 0
    ax.set_yscale("log")
    ax.set_ylim(1.0, 1e3)
    assert _error_bars(ax, x, y, np.full(5, 1e-2), "k") == 0  # 0.01% of the value: inside the marker
    plt.close(fig)


# ---- figures as objects: returned, not saved, matplotlib's state untouched

#: a fresh interpreter: imports granchain, draws every figure of a run directory through the API, and
#: reports matplotlib's backend setting before and after (rcParams._get: reading it resolves nothing)
BACKEND_PROBE = r"""
import json, sys
import matplotlib
import matplotlib.figure
{use}
before = str(matplotlib.rcParams._get("backend"))
import granchain
import granchain.workflows.plots
after_import = str(matplotlib.rcParams._get("backend"))
r = granchain.load_run(sys.argv[1])
figs = [r.plot(k) for k in ("peaks", "histories", "snapshots", "heatmap")] + [granchain.figure(sys.argv[1])]
print(json.dumps({{
    "before": before,
    "after_import": after_import,
    "after_plot": str(matplotlib.rcParams._get("backend")),
    "pyplot": "matplotlib.pyplot" in sys.modules,
    "figures": all(isinstance(f, matplotlib.figure.Figure) for f in figs),
}}))
"""


@pytest.mark.parametrize("use", ["", 'matplotlib.use("svg")', 'matplotlib.use("pdf")'])
def test_importing_and_plotting_never_change_the_backend(snaps_run, use):
    import json
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    out = subprocess.run(
        [sys.executable, "-c", BACKEND_PROBE.format(use=use), str(snaps_run)],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        check=True,
    )
    got = json.loads(out.stdout)
    assert got["before"] == got["after_import"] == got["after_plot"]
    assert not got["pyplot"]  # figures are made without pyplot: no backend is even chosen
    assert got["figures"]


def test_figures_are_returned_and_nothing_is_written(snaps_run, tmp_path):
    from matplotlib.figure import Figure

    import granchain

    r = copy(snaps_run, tmp_path)
    before = sorted(p.name for p in r.iterdir())
    figs_before = plt.get_fignums()
    result = granchain.load_run(r)
    for kind in ("peaks", "histories", "snapshots", "heatmap"):
        fig = result.plot(kind)
        assert isinstance(fig, Figure)
        assert fig.axes
    assert isinstance(plots.figure(r, "peaks", log=False), Figure)
    assert sorted(p.name for p in r.iterdir()) == before  # save only when asked
    assert plt.get_fignums() == figs_before  # pyplot's figure list untouched
    fig = result.plot("peaks")
    fig.savefig(tmp_path / "asked.png")
    assert_valid(tmp_path / "asked.png", "png")
    with pytest.raises(GranchainError, match="unknown figure 'nope'"):
        result.plot("nope")


def test_an_in_memory_result_plots_the_same_data_as_its_directory(tmp_path):
    import granchain

    sc = scene("histories = [1, 5, 10]\nsnapshots = [6e-5]")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mem = granchain.run(sc, out=tmp_path / "r")
    loaded = granchain.load_run(tmp_path / "r")
    for kind in ("peaks", "histories", "snapshots"):
        a, b = mem.plot(kind), loaded.plot(kind)
        for ax_a, ax_b in zip(a.axes, b.axes, strict=True):
            for la, lb in zip(ax_a.lines, ax_b.lines, strict=True):
                np.testing.assert_array_equal(la.get_xydata(), lb.get_xydata())


@pytest.mark.parametrize("name", ["peaks.png", "peaks_plot.csv", "heatmap.png"])
def test_plot_never_writes_through_a_link_planted_in_the_run_directory(snaps_run, tmp_path, capsys, name):
    from granchain.cli import main

    r = copy(snaps_run, tmp_path)
    victim = tmp_path / "victim"
    victim.write_text("precious\n")
    (r / name).unlink(missing_ok=True)
    (r / name).symlink_to(victim)
    assert main(["plot", str(r)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("granchain: error: ")
    assert name in err
    assert "symbolic link" in err
    assert victim.read_text() == "precious\n"
    assert (r / name).is_symlink()


def test_a_linked_run_inside_a_compare_directory_is_refused(compare_dir, tmp_path):
    d = tmp_path / "cmp"
    shutil.copytree(compare_dir, d)
    shutil.move(d / "lammps", tmp_path / "elsewhere")
    (d / "lammps").symlink_to(tmp_path / "elsewhere")
    with pytest.raises(GranchainError, match="symbolic link"):
        plot_compare(d)


def test_control_characters_of_a_title_are_escaped_in_figures(compare_dir, tmp_path):
    import granchain

    r = copy(compare_dir / "reference", tmp_path)
    toml = (
        (r / "scene.toml").read_text().split("\n", 1)[1]
        if (r / "scene.toml").read_text().startswith("title")
        else (r / "scene.toml").read_text()
    )
    (r / "scene.toml").write_text('title = "bell \\u0007 esc \\u001b[2J"\n' + toml)
    fig = granchain.load_run(r).plot("peaks")
    title = fig.axes[0].get_title()
    assert "\x07" not in title
    assert "\x1b" not in title
    assert "\\x1b[2J" in title


@pytest.mark.parametrize("kind", ["peaks", "histories", "snapshots", "heatmap"])
def test_plot_functions_return_figures_and_save_only_when_asked(snaps_run, tmp_path, kind):
    from matplotlib.figure import Figure

    r = copy(snaps_run, tmp_path)
    before = sorted(p.name for p in r.iterdir())
    plot = getattr(plots, f"plot_{kind}")
    assert isinstance(plot(r), Figure)
    assert sorted(p.name for p in r.iterdir()) == before
    elsewhere = tmp_path / "figures"
    elsewhere.mkdir()
    assert isinstance(plot(r, save=elsewhere, formats="png,svg"), Figure)
    assert sorted(p.name for p in elsewhere.iterdir()) == sorted([f"{kind}.png", f"{kind}.svg", f"{kind}_plot.csv"])
    assert_valid(elsewhere / f"{kind}.png", "png")
    plot(r, save=True)
    assert (r / f"{kind}.png").exists()
    assert (r / f"{kind}_plot.csv").exists()


def test_a_long_title_is_wrapped_inside_the_figure(tmp_path):
    """A scene title far wider than the figure is drawn on several lines within the figure's width."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from granchain.workflows.plots.canvas import ChainFigure

    fig = ChainFigure(figsize=(6.4, 4.8))
    ax = fig.add_subplot()
    ax.set_title("a scene title that describes its chain in far too many words, " * 4, fontsize=9)
    FigureCanvasAgg(fig).draw()
    box = ax.title.get_window_extent(fig.canvas.get_renderer())
    assert box.x0 >= 0
    assert box.x1 <= fig.bbox.x1
