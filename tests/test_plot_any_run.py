"""Every run directory granchain run writes can be plotted: the peak figure of a run without a bead-bead
peak (one bead: a striker, a wall, a kick) is drawn with a panel that says why and gives the end
contacts' peaks, never a log axis with nothing positive on it (which matplotlib refused)."""

import re
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from granchain.scene import parse_scene
from granchain.workflows import plots
from granchain.workflows.load import load_run
from granchain.workflows.run import run_scene

from .scenegen import overlap_fraction, scene_texts

ONE_BEAD = {
    "striker": 'kind = "striker"\nvelocity = 0.5\nmass = 0.02',
    "kick": 'kind = "velocity"\nvelocity = 0.5',
    "step": 'kind = "step"\namplitude = 20.0\nduration = 2e-5',
}


def one_bead_text(loading: str, wall: bool, precompression: float = 0.0) -> str:
    text = (
        '[chain]\nbeads = 1\nradius = 2.38e-3\nmaterial = "stainless-steel-316"\n[contact]\nlaw = "hertz"\n'
        f'[loading]\n{loading}\n[run]\nend_time = "auto"\ntimestep = "auto"\n[outputs]\npeak_force = true\n'
    )
    if wall:
        text += '[boundary]\nfar_end = "wall"\n'
    if precompression:
        text += f"[precompression]\nforce = {precompression!r}\n"
    return text


def run_dir(text: str, out):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the planner's and the run's warnings: not the point here
        run_scene(parse_scene(text, source="generated.toml"), out=out)
    return out


def texts_of(fig) -> list[str]:
    return [t.get_text() for ax in fig.axes for t in ax.texts]


@pytest.mark.parametrize(
    ("kind", "wall", "f0"),
    [("striker", False, 0.0), ("kick", True, 0.0), ("kick", True, 10.0), ("step", True, 0.0)],
)
def test_one_bead_run_plots(tmp_path, kind, wall, f0):
    out = run_dir(one_bead_text(ONE_BEAD[kind], wall, f0), tmp_path / "run")
    made = plots.plot_run(out)  # log axes, as granchain plot draws them: raised ValueError before
    assert (out / "peaks.png") in made
    fig = load_run(out).plot("peaks")
    text = " ".join(texts_of(fig))
    assert "one bead" in text
    assert "\\x" not in text  # a number's no-break space to its unit drawn as itself, not escaped as \xa0
    s = load_run(out).summary
    # the panel gives the end contacts' peaks the run has (the striker's, the wall's)
    for name, who in (("striker_peak_force", "striker's"), ("wall_peak_force", "wall's")):
        assert (s.get(name) is not None) == (who in text)
    assert plots.figure_peaks(out, log=False) is not None


def _few_beads(draw_beads: int, text: str) -> str:
    """A generated uniform chain cut to draw_beads beads (its history contacts dropped)."""
    text = re.sub(r"^beads = \d+$", f"beads = {draw_beads}", text, count=1, flags=re.M)
    return re.sub(r"^histories = .*\n", "", text, flags=re.M)


@st.composite
def _small_texts(draw):
    text = draw(scene_texts(max_beads=14))
    uniform = "material = [" not in text and "taper" not in text
    if uniform and draw(st.booleans()):
        # one bead needs a striker or a wall to touch, and a precompressed one a wall to carry its push
        # (the scene reader refuses either otherwise)
        struck = 'kind = "striker"' in text and "[precompression]" not in text
        touches = struck or 'far_end = "wall"' in text
        text = _few_beads(draw(st.sampled_from([1, 2])) if touches else 2, text)
    return text


ONE_BILINEAR_BEAD_ON_A_WALL = (
    '[chain]\nbeads = 1\nradius = 0.0078125\nmaterial = "aluminium-6061-t6"\n[contact]\nlaw = "bilinear"\n'
    'unloading_coeff = 0.0\nplastic_stiffness = 1000000.0\n[loading]\nkind = "step"\namplitude = 1.0\n'
    'duration = 1e-06\n[run]\nend_time = "auto"\ntimestep = "auto"\n[outputs]\npeak_force = true\n'
    '[boundary]\nfar_end = "wall"\n'
)


def small_scene_texts():
    """Generated scenes of 12-14 beads, and uniform ones cut to 1 or 2 beads (the runs without a
    bead-bead peak or with one contact), under loads the laws describe (scenegen.scenes' filter)."""
    return _small_texts().filter(lambda t: overlap_fraction(parse_scene(t, source="generated.toml")) < 0.05)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=small_scene_texts())
@example(text=ONE_BILINEAR_BEAD_ON_A_WALL)  # CI: the bilinear law's model curves took max() of no contacts
def test_plot_never_raises_on_generated_runs(tmp_path_factory, text):
    out = run_dir(text, tmp_path_factory.mktemp("gen") / "run")
    for log in (True, False):
        made = plots.plot_run(out, log=log)
        assert (out / "peaks.png") in made
    r = load_run(out)
    fig = r.plot("peaks")
    panel = " ".join(texts_of(fig))
    reached = plots.load_peaks(r).reached
    # a panel text exactly where no bead-bead peak is drawn
    assert bool(panel) == (not np.any(reached)), panel
