"""Scenes and plans in a notebook (issue 43 item 6): Scene.replace changes keys as the scene reader
reads a file with them changed, and Scene and Plan show themselves in one short line and a small
HTML table."""

from __future__ import annotations

import dataclasses
import re
import tomllib
from html.parser import HTMLParser

import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

from granchain.campaigns.model import scene_numbers
from granchain.scene import SceneError, bundled_scenes, dump_toml, load_scene, parse_scene
from granchain.workflows.plan import plan_scene
from tests.scenegen import scene_texts

#: a number as it is printed: its mantissa's digits
NUMBER = re.compile(r"(\d+(?:\.\d*)?)(?:e[+-]?\d+)?")


class _LongNumbers:
    """search(text): a number printed with more than 7 significant digits (Python's repr of an
    inexact float, 400000.00000000006), or None."""

    @staticmethod
    def search(text: str):
        return next((m for m in NUMBER.finditer(text) if len(m.group(1).replace(".", "").lstrip("0")) > 7), None)


LONG_DIGITS = _LongNumbers()


def _without_text(scene):
    return dataclasses.replace(scene, source_text=None)


def _read_changed(scene, key: str, value):
    """The oracle: the scene's TOML (to_toml) with the key changed in its table, read by parse_scene."""
    data = tomllib.loads(scene.to_toml())
    *tables, last = key.split(".")
    node = data
    for t in tables:
        node = node.setdefault(t, {})
    node[last] = value
    return parse_scene(dump_toml(data), source=scene.source)


def _outcome(fn):
    try:
        return "ok", fn()
    except SceneError as e:
        return "refused", str(e)


values = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False),
    st.floats(min_value=1e-9, max_value=1e6),
    st.integers(-5, 500),
    st.sampled_from(["auto", "x", ""]),
    st.booleans(),
)


@settings(max_examples=40)
@given(text=scene_texts(), data=st.data())
def test_replace_reads_as_the_toml_with_that_key_changed(text, data):
    """For a generated scene and any of its number keys, replace(key, value) is the scene its TOML
    with that key changed reads as (the same SceneError message where the reader refuses it), with
    that text as its source_text; the original scene is left as it was."""
    scene = parse_scene(text, source="generated.toml")
    before = dataclasses.replace(scene)
    key = data.draw(st.sampled_from(sorted(scene_numbers(tomllib.loads(scene.to_toml())))), label="key")
    value = data.draw(st.one_of(st.just(scene_numbers(tomllib.loads(scene.to_toml()))[key] * 1.5), values))
    got = _outcome(lambda: scene.replace(key, value))
    expected = _outcome(lambda: _read_changed(scene, key, value))
    event(got[0])
    assert got[0] == expected[0], (got, expected)
    if got[0] == "ok":
        assert _without_text(got[1]) == _without_text(expected[1])
        assert parse_scene(got[1].source_text, source=scene.source) == dataclasses.replace(
            got[1], source_text=got[1].source_text
        )
    else:
        assert got[1] == expected[1]
    assert scene == before


@pytest.mark.parametrize("name", ["default", "classic-struck-taper", "effect-precompression"])
def test_replace_in_both_forms_and_the_readers_messages(name):
    """replace(key, value) and replace({key: value, ...}) agree; several keys are validated together;
    a bad value, an unknown key and a key through a value give the reader's message naming the key."""
    scene = load_scene(name)
    key = "loading.velocity" if scene.loading.kind in ("velocity", "striker") else "loading.duration"
    value = 1.25 * getattr(scene.loading, key.split(".")[1])
    one, both = scene.replace(key, value), scene.replace({key: value})
    assert one == both
    assert one.source == scene.source
    assert getattr(one.loading, key.split(".")[1]) == value
    assert scene.replace({key: value, "precompression.force": 1.0}).effects.precompression == 1.0
    with pytest.raises(SceneError) as bad:
        scene.replace(key, -1.0)
    assert str(bad.value) == _outcome(lambda: _read_changed(scene, key, -1.0))[1]
    assert f"[loading] {key.split('.')[1]} = -1.0 is invalid" in str(bad.value)
    with pytest.raises(SceneError, match=f"unknown key '{key[8:-1]}' = 1.0; did you mean '{key[8:]}'"):
        scene.replace(key[:-1], 1.0)
    with pytest.raises(SceneError, match=r"cannot set 'title\.x': title is .*, not a table \(set 'title' itself\)"):
        scene.replace("title.x", 1.0)
    with pytest.raises(TypeError, match="needs the key's new value"):
        scene.replace(key)


def test_a_campaign_point_sets_its_keys_as_replace_does():
    """A campaign point's scene is the base scene's replace with its keys (one setter for both), and
    a key through a value is refused with the setter's message, naming the point."""
    from granchain.campaigns.spec import CampaignError, parse_campaign

    text = '[campaign]\nbase = "default"\n[vary]\n"loading.impulse" = [0.2, 0.3]\n"run.end_time" = [5e-4]\n'
    base = load_scene("default")
    with pytest.raises(
        CampaignError, match=r"point 1 of 1 .*: cannot set 'chain.radius.x': chain.radius is 0.00476, not"
    ):
        parse_campaign('[campaign]\nbase = "default"\n[vary]\n"chain.radius.x" = [1.0]\n').points()
    for point in parse_campaign(text).points():
        changes = {k: v for k, v in point.params.items() if "." in k}
        assert _without_text(point.scene) == _without_text(
            dataclasses.replace(base.replace(changes), source=point.scene.source)
        )


class _Cells(HTMLParser):
    def __init__(self):
        super().__init__()
        self.tags, self.text = [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)

    def handle_data(self, data):
        self.text.append(data)


def _html_cells(markup: str) -> tuple[list[str], str]:
    p = _Cells()
    p.feed(markup)
    return p.tags, "".join(p.text)


@pytest.mark.parametrize("name", sorted(bundled_scenes()))
def test_scene_shows_itself_in_one_short_line_and_a_table(name):
    """Every bundled scene's repr is one line of at most 400 characters naming its source, beads,
    law, loading and effects, its floats as a researcher writes them; its HTML a table of the same."""
    scene = load_scene(name)
    line = repr(scene)
    assert "\n" not in line
    assert len(line) <= 400
    assert line.startswith("<Scene ")
    assert name in line
    assert scene.contact.law in line
    assert scene.loading.kind in line
    assert not LONG_DIGITS.search(line), line
    declared = tomllib.loads(scene.to_toml())
    for section in ("precompression", "damping", "gravity", "boundary"):
        assert (f"{section}." in line) == (section in declared), section
    tags, text = _html_cells(scene._repr_html_())
    assert tags[0] == "table"
    assert scene.contact.law in text
    assert scene.loading.kind in text
    assert not LONG_DIGITS.search(text)


def test_a_scene_title_cannot_inject_markup_or_move_the_cursor():
    """A title of markup and control characters is shown escaped in both reprs."""
    scene = load_scene("default").replace("title", "<script>alert(1)</script>\x1b]0;x\x07")
    assert "\x1b" not in repr(scene)
    assert "\\x1b" in repr(scene)
    tags, text = _html_cells(scene._repr_html_())
    assert "script" not in tags
    assert "<script>" in text


@pytest.mark.parametrize("name", ["default", "effect-gravity", "thornton-short-impulse"])
def test_plan_shows_itself_in_one_short_line_and_a_table_of_its_reasons(name):
    """A Plan's repr is one line naming the integrator, rtol and each choice with its unit; its HTML a
    table with each choice's reason."""
    plan = plan_scene(load_scene(name), rtol=1e-3)
    line = repr(plan)
    assert "\n" not in line
    assert len(line) <= 400
    assert line.startswith(f"<Plan {plan.method} for rtol 0.001")
    assert not LONG_DIGITS.search(line), line
    for c in plan.choices:
        assert f"{c.name} = " in line
    tags, text = _html_cells(plan._repr_html_())
    assert tags[0] == "table"
    for c in plan.choices:
        assert c.reason in text


@pytest.mark.parametrize("name", sorted(bundled_scenes()))
def test_dimensionless_units_are_written_one_way(name):
    """Every unit granchain writes of a bundled scene's quantities (the model predictions, the
    observables, peaks.csv's columns) says dimensionless as "1", never "-"."""
    from granchain.physics.predictions import predict
    from granchain.postprocess.observables import units
    from granchain.results import PEAK_UNITS

    scene = plan_scene(load_scene(name), rtol=1e-2).scene
    written = [p.unit for p in predict(scene)] + list(units().values()) + list(PEAK_UNITS.values())
    assert "-" not in written
