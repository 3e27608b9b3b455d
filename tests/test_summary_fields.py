"""summary.json's observables and sensors are type-checked when a run is loaded, from the observable
registry's declarations (Observable.kinds, postprocess.observables.kinds): a field of the wrong kind is
one LoadRunError naming it; every field a real run writes is declared, so none goes unchecked.

Fails before: ``observables`` was MapOf(ANY) and ``sensors`` unchecked, so a summary.json with garbage
in event_contact_max_forces, spatial_decay_contacts, wave_speed_sections or sensors loaded.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.postprocess.observables import OBSERVABLES, SENSOR_OBSERVABLES, kinds
from granchain.rundir import write_run_dir
from granchain.scene import load_scene, parse_scene
from granchain.workflows.load import LoadRunError, load_run
from granchain.workflows.run import run_scene

from .test_companion_event import walled_text

#: a chain of two materials, whose wave speed is fitted per uniform stretch (wave_speed_sections)
TWO_STRETCHES = (
    '[chain]\nbeads = 20\nradius = 4.76e-3\nmaterial = ["brass", "brass", "brass", "brass", "brass", "brass", '
    '"brass", "brass", "brass", "brass", "aluminium-6061-t6", "aluminium-6061-t6", "aluminium-6061-t6", '
    '"aluminium-6061-t6", "aluminium-6061-t6", "aluminium-6061-t6", "aluminium-6061-t6", "aluminium-6061-t6", '
    '"aluminium-6061-t6", "aluminium-6061-t6"]\n[contact]\nlaw = "hertz"\n[loading]\nkind = "impulse"\n'
    'impulse = 0.1\nduration = 1e-6\n[run]\nend_time = "auto"\ntimestep = "auto"\n[outputs]\npeak_force = true\n'
    "window = [2, 18]\n"
)


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> list[Path]:
    """Real run directories between them writing every kind of observable field: a precompressed walled
    taper under a striker with the event, its maxima at a contact and a sensor, and error bars; a
    harmonic drive above the cutoff (spectral fields); a chain of two stretches (wave_speed_sections)."""
    root = tmp_path_factory.mktemp("made")
    walled = parse_scene(walled_text(6, "stainless-steel-316", 0.93, 2.0, 0.3, "pre"), source="walled.toml")
    runs = [
        run_scene(walled, error_estimate=True),
        run_scene(load_scene("harmonic-above-cutoff")),
        run_scene(parse_scene(TWO_STRETCHES, source="two.toml")),
    ]
    return [write_run_dir(r, root / f"run{k}") for k, r in enumerate(runs)]


def _summary(d: Path) -> dict:
    return json.loads((d / "summary.json").read_text())


def test_every_field_a_run_writes_is_declared_and_of_its_kind(made):
    """Every key of a real run's observables is declared by the registry (so checked), each kind is
    written by some run, and the real files load."""
    declared = kinds()
    seen: set[str] = set()
    for d in made:
        load_run(d)
        obs = _summary(d)["observables"]
        assert set(obs) <= set(declared), set(obs) - set(declared)
        seen |= {k for k, v in obs.items() if v not in (None, [])}
    assert {declared[k] for k in seen} == set(declared.values())
    # every registered observable's value and companions are among the declared keys
    for obs in OBSERVABLES.values():
        assert {obs.name, *obs.companions} <= set(declared), obs.name


#: a value of each JSON shape, to put where another kind belongs
GARBAGE = {
    "text": "big",
    "flag": True,
    "object": {"a": 1},
    "number": 1.5,
    "list of text": ["x"],
    "list of objects": [{"speed": "fast"}],
    "list of flags": [True],
}
#: which garbage is not of each kind (an integer kind refuses 1.5; a list kind refuses a number)
WRONG = {
    "number": ["text", "flag", "object", "list of text"],
    "integer": ["text", "flag", "object", "number", "list of text"],
    "numbers": ["text", "number", "object", "list of text", "list of flags"],
    "integers": ["text", "number", "object", "list of text", "list of flags"],
    "sections": ["text", "number", "object", "list of text", "list of objects"],
}


def _wrong_for(key: str):
    return st.sampled_from(WRONG[kinds()[key]])


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_a_mutated_observable_field_is_refused_with_one_message_naming_it(made, tmp_path_factory, data):
    """Any declared observable field set to a value not of its kind: one LoadRunError, one line, naming
    summary.json and observables.<field>."""
    key = data.draw(st.sampled_from(sorted(kinds())), label="field")
    garbage = data.draw(_wrong_for(key), label="garbage")
    d = tmp_path_factory.mktemp("damaged") / "run"
    shutil.copytree(made[data.draw(st.integers(0, len(made) - 1), label="run")], d)
    s = _summary(d)
    s["observables"][key] = GARBAGE[garbage]
    (d / "summary.json").write_text(json.dumps(s))
    with pytest.raises(LoadRunError) as e:
        load_run(d)
    message = str(e.value)
    assert "\n" not in message
    assert str(d / "summary.json") in message
    assert f"observables.{key}" in message, message


SENSOR_FIELDS = ["beads", "static_force", *SENSOR_OBSERVABLES, "missing", "note"]


#: each sensors field with garbage not of its kind (text is the note's kind)
SENSOR_DAMAGE = [
    (field, garbage)
    for field in SENSOR_FIELDS
    for garbage in ("text", "list of text", "number")
    if (field, garbage) != ("note", "text")
]


@pytest.mark.parametrize(("field", "garbage"), SENSOR_DAMAGE)
def test_a_mutated_sensor_field_is_refused_naming_it(made, tmp_path, field, garbage):
    """summary.json's sensors: each field of the wrong kind is refused, naming sensors.<field>."""
    d = tmp_path / "run"
    shutil.copytree(made[0], d)
    s = _summary(d)
    s["sensors"][field] = GARBAGE[garbage]
    (d / "summary.json").write_text(json.dumps(s))
    with pytest.raises(LoadRunError, match=rf"sensors\.{field}"):
        load_run(d)


def test_a_mutated_error_bar_is_refused_naming_it(made, tmp_path):
    """An observable's bar whose status is not text, or an end peak's bar whose error is text."""
    for where, edit in (
        (
            "errors.observables.wall_impulse.status",
            lambda s: s["errors"]["observables"]["wall_impulse"].update(status=3),
        ),
        (
            "errors.end_peaks.wall_peak_force.error",
            lambda s: s["errors"]["end_peaks"]["wall_peak_force"].update(error="x"),
        ),
    ):
        d = tmp_path / where
        shutil.copytree(made[0], d)
        s = _summary(d)
        edit(s)
        (d / "summary.json").write_text(json.dumps(s))
        with pytest.raises(LoadRunError, match=where.replace(".", r"\.")):
            load_run(d)
