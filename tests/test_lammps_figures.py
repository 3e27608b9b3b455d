"""Figures of generated scenes run on LAMMPS (issue 43 acceptance 2; test_figure_axes draws them on the
reference only): figure_scene_texts' cheap scenes with a whole-chain dump every 1/40 of the run, so the
heat map is drawn from chain.dump as only a LAMMPS run has it, through the same figure checks (tick
labels across the data on each log axis, no text beyond the canvas, a unit on every axis label) and,
under precompression or gravity, the dynamic-force checks of test_dynamic_figures."""

from __future__ import annotations

import warnings

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

import granchain
from granchain.scene import parse_scene

from .figure_checks import check_every_figure
from .scenegen import figure_scene_texts
from .test_dynamic_figures import check_dynamic_figures


def _with_dump(text: str) -> str:
    """The scene with a whole-chain dump 40 times over its run ([outputs] is its last section)."""
    end = float(parse_scene(text, source="generated.toml").run.end_time)
    return text + f"dump_interval = {end / 40.0!r}\n"


@pytest.mark.slow
@settings(
    max_examples=4,
    deadline=None,
    phases=(Phase.explicit, Phase.reuse, Phase.generate),  # no shrinking: each step of it is a LAMMPS run
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.function_scoped_fixture],
)
@given(text=figure_scene_texts(), log=st.booleans())
def test_every_figure_of_a_generated_scene_on_lammps(text, log, tmp_path_factory):
    """4 generated scenes on LAMMPS (2-10 s each, most of it the deck's start), every figure of each."""
    scene = parse_scene(_with_dump(text), source="generated.toml")
    out = tmp_path_factory.mktemp("lammps_figures") / "run"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the planner's warnings: not the point here
        result = granchain.run(scene, backend="lammps", out=out)
    if scene.chain.beads > 1:
        assert (out / "chain.dump").is_file()
    check_every_figure(result, log=log)
    if scene.effects.precompression or scene.effects.gravity:
        check_dynamic_figures(result)
