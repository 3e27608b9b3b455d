"""The deck builder's templates: the built-in granular yardstick extends the chain deck (template
inheritance) and differs from it only in the blocks it overrides; what it cannot run it refuses; the
template environment keeps its safety properties (StrictUndefined, one printable line per value)."""

import re
from dataclasses import replace

import jinja2
import pytest
from hypothesis import given

from granchain.cli import resolve_scene
from granchain.exceptions import UsageError
from granchain.scene import SceneError, parse_scene
from granchain.templates import _env, render_deck

from .conftest import make_scene, make_scene_text
from .test_deck_safety import BASE, FAST, NASTY, assert_same_commands

BUILTIN_LINES = {  # the lines of the yardstick's own blocks (contact, energy_watch)
    "pair_style      granular",
    "comm_modify     vel yes",
    "# no energy balance: pair_style granular tallies no contact energy",
}


def without_blocks(deck: str) -> list[str]:
    """The deck's lines without the contact block (from '# ---- contact law' to the blank line) and
    the run watch's energy balance (from '# energy balance' to 'fix watch_energy' or, with fix chain/energy,
    'fix_modify energy watch'; or its absence)."""
    deck = re.sub(r"^# ---- contact law.*?\n\n", "\n", deck, count=1, flags=re.M | re.S)
    end = r"(?:fix             watch_energy |fix_modify      energy watch )"
    deck = re.sub(r"^# energy balance.*?^" + end + r".*?\n", "", deck, count=1, flags=re.M | re.S)
    return deck.replace("# no energy balance: pair_style granular tallies no contact energy\n", "").splitlines()


STOP_TEXT = make_scene_text(beads=20).replace("[run]", "[run]\nstop_after_contact = 3")
YARDSTICK_SCENES = {
    "force load": lambda: make_scene(beads=20, outputs="histories = [1, 5]\nsnapshots = [1e-4]"),
    "velocity load": lambda: make_scene(beads=20, loading='kind = "velocity"\nvelocity = 1.0'),
    "striker": lambda: resolve_scene("effect-striker"),
    "taper": lambda: resolve_scene("effect-tapered"),
    "stop_after_contact": lambda: parse_scene(STOP_TEXT),
}


@pytest.mark.parametrize("name", sorted(YARDSTICK_SCENES))
def test_yardstick_overrides_only_its_blocks(name):
    """The yardstick's deck is the chain deck with its contact block (pair_style granular) and no
    energy balance; its results dump writes the result columns it declares; the data file is the same."""
    sc = YARDSTICK_SCENES[name]()
    ours, yard = render_deck(sc), render_deck(sc, yardstick="builtin")
    assert yard.data == ours.data
    assert yard.total_steps == ours.total_steps
    a, b = without_blocks(ours.deck), without_blocks(yard.deck)
    assert len(a) == len(b)
    differ = [(x, y) for x, y in zip(a, b, strict=True) if x != y]
    assert [y for _, y in differ] == [
        "write_dump      all custom peaks.dump id x vx d_fpeak d_tpeak modify format float %.17g sort id"
    ]
    assert BUILTIN_LINES <= set(yard.deck.splitlines())
    assert not re.search(r"^pair_style\s+chain/", yard.deck, re.M)
    assert "watch_energy" not in yard.deck
    assert "fix             contact all property/atom d_fc d_fprev d_fprev2 d_fpeak d_tpeak ghost yes" in yard.deck


@pytest.mark.parametrize(
    ("scene", "why"),
    [
        ("plastic-short-impulse", "the bilinear law"),
        ("thornton-short-impulse", "the thornton law"),
        ("effect-dashpot", "a dashpot"),
        ("effect-wall", "a wall"),
    ],
)
def test_yardstick_refuses_what_it_cannot_run(scene, why):
    """A chain the built-in granular style cannot run as ours does (the old spliced decks failed in
    LAMMPS for these: an undefined compute 'dissipated' or group 'mobile') is refused."""
    with pytest.raises(SceneError, match=f"cannot run a chain with {why}"):
        render_deck(resolve_scene(scene), yardstick="builtin")


def test_yardstick_refuses_a_second_material():
    sc = make_scene(beads=12)
    mixed = replace(sc, chain=replace(sc.chain, materials=("brass",) * 6 + ("chrome-steel-52100",) * 6))
    with pytest.raises(SceneError, match="another material"):
        render_deck(mixed, yardstick="builtin")
    with pytest.raises(UsageError, match="yardstick = 'lj' is unknown"):
        render_deck(sc, yardstick="lj")


PLAIN_YARDSTICK = render_deck(replace(BASE, title="plain title", source="plain.toml"), yardstick="builtin")


@FAST
@given(title=NASTY, source=NASTY)
def test_yardstick_title_and_source_are_inert(title, source):
    assert_same_commands(render_deck(replace(BASE, title=title, source=source), yardstick="builtin"), PLAIN_YARDSTICK)


def test_template_values_are_strict_single_lines():
    """StrictUndefined: a value the templates read that is not there is an error; a value that is
    not one printable line is an error (free text goes through the comment filter)."""
    env = _env()
    with pytest.raises(jinja2.UndefinedError):
        env.from_string("{{ scene.loading.amplitud }}").render(scene=BASE)
    with pytest.raises(ValueError, match="not one line of printable text"):
        env.from_string("{{ scene.title }}").render(scene=replace(BASE, title="x\nshell touch pwned"))
    assert env.from_string("{{ scene.title | comment }}").render(scene=replace(BASE, title="x\ny")) == "x y"


def test_decks_reuse_the_compiled_templates(monkeypatch):
    """One jinja2 environment per process keeps the compiled templates: a second deck compiles none
    (compiling them all again costs 40-70 ms of every campaign point, and a decorator on the wrong
    function would do that unnoticed)."""
    scenes = [BASE, resolve_scene("effect-precompression")]
    for sc in scenes:  # (first use: every template they include compiled once)
        render_deck(sc)
    compiled = []
    real = jinja2.Environment.compile

    def counting(self, *args, **kwargs):
        compiled.append(args[1] if len(args) > 1 else kwargs.get("name"))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(jinja2.Environment, "compile", counting)
    for sc in scenes:
        render_deck(sc)
    assert compiled == []
    assert _env() is _env()
