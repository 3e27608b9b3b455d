"""The wave speed's note on a window whose contacts differ counts what it lists: the contacts' stretches
of one kind and the beads' stretches of one radius and material, each named as such, each count the
number of its items; no "X to X" range (a same-radius chain of two materials: "radius 2.38 mm").
Before: "3 uniform stretches" followed by a list of 2 bead stretches, "radii 2.38 to 2.38 mm", a taper's
"15 uniform stretches; ... 16 stretches" in one sentence."""

import re
import warnings

import pytest
from hypothesis import given, settings

from granchain.postprocess.observables import (
    _NAMED_STRETCHES,
    _window_beads,
    _window_contacts,
    periodic_cell,
    uniform_sections,
)
from granchain.scene import parse_scene
from granchain.workflows.run import run_scene

from .scenegen import scene_texts

LIST_CONTACTS = re.compile(r"contacts in (\d+) stretches of one kind: ([\d, -]+?)(?:;|\)|$)")
COUNT_CONTACTS = re.compile(r"contacts \d+-\d+ in (\d+) stretches of one kind")
LIST_BEADS = re.compile(r"beads in (\d+) stretches of one radius and material: (.*)")
COUNT_BEADS = re.compile(r"beads \d+-\d+ in (\d+) stretches of one radius and material")
SAME_RANGE = re.compile(r"(\d[\d.e+-]*) to \1 ")


def bead_stretches(scene) -> int:
    """The window's beads in runs of one radius and material, counted here on their own."""
    a, b = scene.window
    kinds = list(zip(scene.bead_radii[a - 1 : b + 1], scene.bead_materials[a - 1 : b + 1], strict=True))
    return 1 + sum(1 for x, y in zip(kinds[:-1], kinds[1:], strict=True) if x != y)


def check_counts(scene, contacts_text: str, beads_text: str) -> None:
    n_contacts, n_beads = len(uniform_sections(scene)), bead_stretches(scene)
    m = LIST_CONTACTS.search(contacts_text)
    if m:
        assert int(m.group(1)) == len(m.group(2).split(", ")) == n_contacts, contacts_text
    else:
        m = COUNT_CONTACTS.search(contacts_text)
        assert m, contacts_text
        assert int(m.group(1)) == n_contacts > _NAMED_STRETCHES, contacts_text
    if n_beads == 1:
        assert "stretches" not in beads_text, beads_text
    elif m := LIST_BEADS.search(beads_text):
        assert int(m.group(1)) == len(re.findall(r"\b\d+(?:-\d+)? of R = ", m.group(2))) == n_beads, beads_text
    else:
        m = COUNT_BEADS.search(beads_text)
        assert m, beads_text
        assert int(m.group(1)) == n_beads > _NAMED_STRETCHES, beads_text
    assert not SAME_RANGE.search(beads_text), beads_text


@settings(max_examples=150, deadline=None)
@given(text=scene_texts(max_beads=60))
def test_counts_equal_the_items_listed(text):
    scene = parse_scene(text, source="generated.toml")
    if not scene.per_bead or periodic_cell(scene):
        return  # no stretches: a uniform chain, or a periodic window named by its cell
    check_counts(scene, _window_contacts(scene), _window_beads(scene))


def run_note(text: str) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = run_scene(parse_scene(text, source="t.toml"))
    return r.observables_notes()["wave_speed"]


#: one material or the other, bead by bead, in no repeating cell
MIXED = (
    "["
    + ", ".join('"stainless-steel-316"' if c == "s" else '"aluminium-6061-t6"' for c in "saasassassasaasssaasasaassas")
    + "]"
)


def chain(radius: str, material: str, beads: int) -> str:
    return (
        f'[chain]\nbeads = {beads}\nradius = {radius}\nmaterial = {material}\n[contact]\nlaw = "hertz"\n'
        '[loading]\nkind = "velocity"\nvelocity = 0.5\n[run]\nend_time = "auto"\ntimestep = "auto"\n'
        "[outputs]\npeak_force = true\n"
    )


@pytest.mark.parametrize(
    "text",
    [
        # two radii: 3 contact stretches (an interface contact between), 2 bead stretches
        chain("[" + ", ".join(["0.00238"] * 10 + ["0.00476"] * 10) + "]", '"stainless-steel-316"', 20),
        # one radius, two materials in no repeating cell over the window: many bead stretches, one radius
        chain("0.00238", MIXED, 28),
        # a taper: every bead its own radius
        chain("0.004", '"brass"', 24).replace("[contact]", "taper = 0.98\n[contact]"),
    ],
    ids=["two-radii", "same-radius-two-materials", "taper"],
)
def test_notes_of_runs(text):
    scene = parse_scene(text, source="t.toml")
    note = run_note(text)
    inside = note.split("(law constants or bead masses: ", 1)[1]
    contacts_text, beads_text = inside.split("; ", 1)
    if len(uniform_sections(scene)) > 1:
        check_counts(scene, contacts_text, beads_text.split("): the front's", 1)[0])
    else:
        assert not SAME_RANGE.search(note), note
