r"""No text from a scene or a file name reaches a LAMMPS deck except as an inert one-line comment.

The title and the scene's source (a file name) are the only free texts the templates write; they go
through the `comment` filter. LAMMPS reads a deck line by line (C fgets: only '\n' ends a line), joins
a line whose last non-blank character is '&' to the next one, keeps reading while a line has an odd
number of triple quotes, loses the line end after a NUL, then drops everything from the first '#'
outside quotes. `lammps_lines` below does the same, so a deck's commands can be compared with those of
the same scene under a plain title: they must be identical, line for line. The other string-valued
scene fields (law, loading kind, far end, material names) are checked against fixed sets when the
scene is read: any other text is refused.
"""

import json
import tomllib
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from granchain.cli import bundled_scenes
from granchain.physics import materials as mat
from granchain.scene import FAR_ENDS, LAWS, LOADING_KINDS, SceneError, parse_scene, scene_from_dict
from granchain.templates import render_deck

from .conftest import make_scene

BLANK = " \t\n\v\f\r"  # C isspace in the "C" / UTF-8 locales

BASE_TEXT = bundled_scenes()["elastic-step-40N"]  # fixed timestep and end time: renders as it is
BASE = parse_scene(BASE_TEXT, source="elastic-step-40N.toml")
PLAIN = render_deck(replace(BASE, title="plain title", source="plain.toml"))

# characters and words that have broken decks or could: line ends of C and of str.splitlines, NUL,
# LAMMPS's continuation, comment, variable and quote characters, a lone surrogate (os.fsdecode of a
# non-UTF-8 file name), commands
TOKENS = [
    "\n", "\r", "\r\n", "\v", "\f", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\u2029", "\x00", "\t",
    "\x7f", "\udcff", "\ufeff", "\u00a0", " ", "&", "& ", "&\v", "&\u00a0", "$", "${x}", "$(quit)", "$x",
    "#", '"', '"""', "'", "\u201c", "\u201d", "\\", "shell touch pwned", "quit", "include x", "x",
]  # fmt: skip
NASTY = st.one_of(
    st.text(),
    st.lists(st.sampled_from(TOKENS), max_size=12).map("".join),
    st.lists(st.one_of(st.sampled_from(TOKENS), st.text(max_size=3)), max_size=8).map("".join),
)
FAST = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def lammps_lines(deck: str) -> list[str]:
    """The deck's input lines as LAMMPS's Input::file() assembles them (input.cpp)."""
    out, buf = [], ""
    pieces = deck.split("\n")
    for k, piece in enumerate(pieces):
        buf += piece
        if k == len(pieces) - 1:  # end of file: a pending line is still read
            if buf:
                out.append(buf)
            break
        if "\0" in buf:  # strlen() stops at the NUL: the line end is lost, reading goes on
            buf = buf[: buf.index("\0")]
            continue
        s = buf.rstrip(BLANK)
        if s.endswith("&"):  # continuation: '&' and the line end removed
            buf = s[:-1]
            continue
        if buf.count('"""') % 2:  # an open triple quote: the next line is part of this one
            buf += "\n"
            continue
        out.append(s)
        buf = ""
    return out


def command_part(line: str) -> str:
    """What LAMMPS executes of an input line: everything before the first '#' outside quotes
    (Input::parse(), single, double and triple quotes)."""
    quote, i = "", 0
    while i < len(line):
        if not quote:
            if line[i] == "#":
                return line[:i].strip(BLANK)
            if line.startswith('"""', i):
                quote, i = '"""', i + 3
                continue
            if line[i] in "\"'":
                quote = line[i]
        elif line.startswith(quote, i):
            i += len(quote)
            quote = ""
            continue
        i += 1
    return line.strip(BLANK)


def commands(deck: str) -> list[str]:
    return [command_part(line) for line in lammps_lines(deck)]


def assert_same_commands(deck, plain=PLAIN):
    """The deck's lines, as text and as LAMMPS reads them, match the plain deck's one for one, and
    every line that differs is a comment in both."""
    d, p = deck.deck, plain.deck
    d.encode("utf-8")  # the deck can be written (Path.write_text) whatever the text was
    assert "\0" not in d
    assert d.count("\n") == p.count("\n")
    assert len(d.splitlines()) == len(p.splitlines())
    assert len(lammps_lines(d)) == len(lammps_lines(p))
    assert commands(d) == commands(p)
    for a, b in zip(d.splitlines(), p.splitlines(), strict=True):
        assert a == b or (a.startswith("#") and b.startswith("#")), (a, b)
    assert deck.data == plain.data  # the data file carries no scene text
    assert deck.total_steps == plain.total_steps


def toml_string(text: str) -> str:
    """A TOML basic string holding text (every character escaped that TOML does not take raw)."""
    return '"' + "".join(c if c.isprintable() and c not in '"\\' else f"\\U{ord(c):08X}" for c in text) + '"'


def test_plain_decks_match_the_model():
    """The line model reads the rendered decks as plain one-command-per-line text."""
    lines = PLAIN.deck.splitlines()
    assert lammps_lines(PLAIN.deck) == [line.rstrip(BLANK) for line in lines]
    assert "units           si" in commands(PLAIN.deck)
    assert lammps_lines('# a &\nb\n# c """\nd\n"""\ne\nf\0\ng\n') == ["# a b", '# c """\nd\n"""', "e", "fg"]
    assert command_part('print "a # b" # c') == 'print "a # b"'


@pytest.mark.parametrize(
    "title",
    [
        "x\nshell touch pwned",  # the exploit: a new command line
        "x &",  # continues the title's comment onto the next deck line
        "x & \v\f",
        'x """',  # an open triple quote: every following line joins this comment
        "x\0",  # NUL: the line end is lost
        "x\rshell touch pwned\u2028shell touch pwned\x85y",
        "${undefined} $(quit) $x",
        "Stoßwelle “““ & é",
    ],
)
def test_known_exploits_are_comments(title):
    deck = render_deck(replace(BASE, title=title, source=title))
    assert_same_commands(deck)
    assert not [line for line in lammps_lines(deck.deck) if command_part(line).split()[:1] == ["shell"]]
    assert not [line for line in deck.deck.splitlines() if line.split()[:1] == ["shell"]]


def test_builtin_granular_yardstick_ignores_the_title():
    """The yardstick deck (render_deck(scene, yardstick="builtin")) has the same commands whatever words
    a title holds (the deck it extends splits at blocks, never at the text)."""
    words = "neighbor # ---- contact law fix             watch_energy"
    evil = replace(BASE, title=words, source=words)
    plain = replace(BASE, title="plain title", source="plain.toml")
    d, p = render_deck(evil, yardstick="builtin").deck, render_deck(plain, yardstick="builtin").deck
    assert commands(d) == commands(p)
    assert len(d.splitlines()) == len(p.splitlines())
    assert "pair_style      granular" in commands(d)


@FAST
@given(title=NASTY, source=NASTY)
def test_title_and_source_are_inert(title, source):
    assert_same_commands(render_deck(replace(BASE, title=title, source=source)))


@FAST
@given(title=NASTY, name=NASTY)
def test_scene_file_title_and_name_are_inert(title, name):
    """The same through a scene file's text: title as TOML, the file name as the scene's source."""
    assume(not any(0xD800 <= ord(c) <= 0xDFFF for c in title))  # TOML holds no surrogates
    text = f"title = {toml_string(title)}\n" + BASE_TEXT.split("\n", 1)[1]
    scene = parse_scene(text, source=name)
    assert scene.title == title
    assert scene.source == name
    assert_same_commands(render_deck(scene))


def _field_cases():
    """(scene dict with the text at one string field, the values that field accepts)."""
    base = tomllib.loads(BASE_TEXT)
    striker = {**base, "loading": {"kind": "striker", "velocity": 1.0, "material": "brass"}}

    def at(d, section, key):
        def put(text):
            e = json.loads(json.dumps(d))
            e.setdefault(section, {})[key] = text
            return e

        return put

    def per_bead(text):
        e = json.loads(json.dumps(base))
        e["chain"]["material"] = ["brass"] * (e["chain"]["beads"] - 1) + [text]
        return e

    return {
        "contact.law": (at(base, "contact", "law"), LAWS),
        "loading.kind": (at(base, "loading", "kind"), LOADING_KINDS),
        "boundary.far_end": (at(base, "boundary", "far_end"), FAR_ENDS),
        "chain.material": (at(base, "chain", "material"), tuple(mat.MATERIALS)),
        "chain.material[]": (per_bead, tuple(mat.MATERIALS)),
        "loading.material (striker)": (at(striker, "loading", "material"), tuple(mat.MATERIALS)),
    }


FIELDS = _field_cases()


@pytest.mark.parametrize("field", sorted(FIELDS))
@settings(max_examples=60, deadline=None)
@given(text=NASTY)
def test_other_string_fields_refuse_free_text(field, text):
    """Law, loading kind, far end and material names are names from fixed sets: other text is refused."""
    make, allowed = FIELDS[field]
    assume(text not in allowed)
    with pytest.raises(SceneError):
        scene_from_dict(make(text), source="t.toml")


def test_field_cases_accept_a_name():
    """The refusals above are the fields' own: each case takes a name from its set."""
    for make, allowed in FIELDS.values():
        scene_from_dict(make(allowed[0]), source="t.toml")


@pytest.mark.parametrize("where", ["title", "source"])
def test_scene_text_runs_nothing_in_lammps(tmp_path, where):
    """The issue's exploit on real LAMMPS: a title or file name with a line break and a shell command
    (plus the continuation and triple-quote tricks) runs nothing and drops no command: the run gives
    the plain deck's results."""
    from granchain.lammps.runner import LammpsError, read_results, run_deck

    pwned = tmp_path / "pwned"
    evil = f'x\nshell touch {pwned}\n# """ &'
    sc = make_scene(beads=10, end_time=2e-6, timestep=1e-8)
    plain = render_deck(replace(sc, title="plain", source="plain.toml"))
    deck = render_deck(replace(sc, **{"title": "plain", "source": "plain.toml", where: evil}))
    try:
        _, w1 = run_deck(deck.deck, deck.data, work_dir=tmp_path / "evil")
    except LammpsError as e:  # the old decks ran the shell command, then lost the rest to the triple quote
        w1, failure = None, e
    assert not pwned.exists(), "LAMMPS ran the shell command from the scene's text"
    assert w1 is not None, failure
    assert not [line for line in deck.deck.splitlines() if line.split()[:1] == ["shell"]]
    _, w2 = run_deck(plain.deck, plain.data, work_dir=tmp_path / "plain")
    a, b = read_results(w1), read_results(w2)
    assert a.keys() == b.keys()
    for key in b:
        np.testing.assert_array_equal(a[key], b[key])
