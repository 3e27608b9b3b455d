"""Every section of a rendered deck ends its last line: no LAMMPS command is glued onto the end of the
line before it. A template whose last line ends in a block tag loses that line's newline to
trim_blocks; event.lmp.j2 did, so a run with [outputs] event = true and no stop check (a given end
time) rendered "fix event ... 0.0thermo_style ..." and LAMMPS refused the deck. Checked on generated
scenes with and without the event and the stop check, and by a real LAMMPS run of such a scene."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.scene import parse_scene
from granchain.templates.deck import PLUGIN_DECK_OPTIONS, render_deck
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import run_scene

from .scenegen import figure_scene_texts

TEMPLATES = Path(__file__).resolve().parent.parent / "granchain" / "templates"


def command_words() -> set[str]:
    """The first word of every command line of every deck template (the LAMMPS commands the decks use)."""
    words = set()
    for path in TEMPLATES.glob("*.lmp.j2"):
        for line in path.read_text().splitlines():
            m = re.match(r"([a-z_]+)\s", line)
            if m and not line.startswith("{"):
                words.add(m.group(1))
    return words


WORDS = command_words()


def glued(line: str) -> str | None:
    """A token of the line that is a command word with the end of another line before it: the decks pad
    a command to its arguments' column with two spaces or more ("fix             stop ..."), so a word
    followed by such padding that is no command but ends in one ("0.0thermo_style") is a glued line."""
    for m in re.finditer(r"(\S+)\s{2,}", line):
        token = m.group(1)
        if token not in WORDS and any(token.endswith(w) for w in WORDS):
            return token
    return None


def test_the_command_words_are_the_decks_commands():
    assert {"fix", "unfix", "thermo_style", "pair_style", "compute", "variable"} <= WORDS
    assert glued("fix             event all chain/event 10 9 0.0 7e-08 0 0.0thermo_style    custom step") == (
        "0.0thermo_style"
    )
    assert glued("unfix           load") is None


@settings(max_examples=30, deadline=None)
@given(text=figure_scene_texts(), event=st.booleans())
def test_no_deck_line_holds_two_commands(text, event):
    """Generated scenes (given end times and the planner's, so with and without a stop check), the
    wall's event asked for where there is a wall, in both deck forms."""
    scene = parse_scene(text)
    if event and scene.effects.far_end == "wall":
        scene = scene.replace("outputs.event", True)
    planned = plan_scene(scene).scene
    for deck in (render_deck(planned), render_deck(planned, options=PLUGIN_DECK_OPTIONS)):
        for line in deck.deck.splitlines():
            if not line.startswith("#"):
                assert glued(line) is None, line


def _walled(end: str) -> str:
    return f"""[chain]
beads = 4
radius = 2.38e-3
material = "stainless-steel-316"
[contact]
law = "hertz"
[loading]
kind = "striker"
velocity = 0.3
[boundary]
far_end = "wall"
[outputs]
event = true
[run]
end_time = {end}
timestep = "auto"
"""


def test_an_event_run_with_a_given_end_time_runs_on_lammps(tmp_path):
    """The planner's end time, given by hand: LAMMPS runs the deck (it refused it), and the wall's largest
    force over the event is the reference's to the run's rtol."""
    planned = plan_scene(parse_scene(_walled('"auto"'))).scene.run.end_time
    scene = parse_scene(_walled(repr(2.0 * planned)))
    run_scene(scene, backend="lammps", out=tmp_path / "l")
    run_scene(scene, backend="reference", method="verlet", out=tmp_path / "r")
    lmp, ref = (json.loads((tmp_path / d / "summary.json").read_text())["observables"] for d in "lr")
    assert lmp["wall_max_force"] == pytest.approx(ref["wall_max_force"], rel=1e-6)
