"""Every "auto"-able key of the scene schema, "auto" or a number, through every command that takes a scene.

The keys are found from the scene reader itself, not listed here: the schema is every table's known
keys as the reader declares them (its ``_Section.finish`` calls while it reads the base scenes), and a
key is "auto"-able where the reader accepts ``"auto"`` for it. A new "auto"-able key is then drawn
here without a change to this file. Each draw sets every such key of a small base scene (each law,
loading kind and effect) to "auto" or to a valid number (the planner's own value for it, or a part of
that), and every command that takes a scene (COMMANDS: `plan`, `predict`, `render`, `submit`, `run` on
the reference; slow: `compare` on LAMMPS and the reference, `campaign run` of a one-point campaign,
`compare-laws`, `accuracy`) must each run or give one `granchain: error:` line and exit 2: never a
traceback (an exception escaping granchain.cli.main fails the test with its traceback). The commands
run in-process; a run of more than GRANCHAIN_MAX_STEPS steps is refused, so each stays short.
"""

from __future__ import annotations

import contextlib
import copy
import functools
import io

import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from granchain.cli import main
from granchain.scene import AUTO, SceneError, scene_from_dict, scene_to_dict
from granchain.scene.section import _Section
from tests.test_hostile_scenes import scene_text

#: small scenes (a few beads, microseconds) of each law, loading kind and effect; the "auto"-able keys
#: are set by each draw
BASES: list[dict] = [
    {
        "chain": {"beads": 4, "radius": 4.76e-3, "material": "brass"},
        "contact": {"law": "hertz"},
        "loading": {"kind": "impulse", "impulse": 0.01, "duration": 1e-6},
        "run": {},
        "outputs": {"peak_force": True, "histories": [1, 2]},
    },
    {
        "chain": {"beads": 4, "radius": 4.76e-3, "material": "brass"},
        "contact": {"law": "hertz"},
        "loading": {"kind": "impulse", "impulse": 0.01, "duration": 1e-6},
        "run": {},
        "outputs": {"peak_force": True, "window": [1, 2]},
        "precompression": {"force": 5.0},
    },
    {
        "chain": {
            "beads": 3,
            "radius": 5e-3,
            "material": {"density": 7800.0, "youngs_modulus": 2e11, "poisson_ratio": 0.3, "yield_strength": 5e8},
        },
        "contact": {"law": "bilinear", "unloading_coeff": 0.8},
        "loading": {"kind": "step", "amplitude": 40.0, "duration": 1e-6},
        "run": {},
        "outputs": {"peak_force": [1, 2], "histories": [2]},
        "damping": {"dashpot": 2.0},
        "precompression": {"force": 2.0},
    },
    {
        "chain": {"beads": 4, "radius": 4.76e-3, "material": "brass"},
        "contact": {"law": "thornton", "yield_pressure": 3.25e9},
        "loading": {"kind": "velocity", "velocity": 0.5},
        "run": {"stop_after_contact": 2},
        "outputs": {"peak_force": True, "histories": [1]},
        "boundary": {"far_end": "wall"},
    },
    {
        "chain": {"beads": 3, "radius": 4.76e-3, "material": "stainless-steel-316", "taper": 0.97},
        "contact": {"law": "hertz"},
        "loading": {"kind": "striker", "velocity": 0.5, "radius": 4e-3, "mass": 2e-3},
        "run": {},
        "outputs": {"peak_force": True, "histories": [2]},
        "precompression": {"force": 1.0},
    },
]

#: a base whose every key may be "auto" at once (no wall, no taper): the planner's values come from it
PLANNED_BASE = BASES[0]


def _table(data: dict, section: str) -> dict | None:
    """data's table of a section ("chain", or dotted: "chain.material"), made if absent; None where
    the scene gives that key another value (material = "brass": no [chain.material] table)."""
    table = data
    for part in section.split("."):
        table = table.setdefault(part, {})
        if not isinstance(table, dict):
            return None
    return table


def _set(data: dict, section: str, key: str, value) -> bool:
    """Set a key of data's section to value; False where the scene has no such table (_table)."""
    table = _table(data, section)
    if table is not None:
        table[key] = value
    return table is not None


def _parses(data: dict) -> bool:
    try:
        scene_from_dict(copy.deepcopy(data), source="probe.toml")
    except SceneError:
        return False
    return True


@functools.cache
def schema() -> tuple[tuple[str, str], ...]:
    """Every (section, key) of the scene schema, as the reader declares it: the known keys of every
    table it finishes reading (granchain.scene.section._Section.finish) over the base scenes."""
    seen: dict[tuple[str, str], None] = {}
    finish = _Section.finish

    def recording(self, known):
        seen.update(dict.fromkeys((self.name, k) for k in known))
        return finish(self, known)

    _Section.finish = recording
    try:
        for base in BASES:
            for run in ({"end_time": 1e-5, "timestep": 1e-8}, {"end_time": AUTO, "timestep": AUTO}):
                assert _parses({**base, "run": {**base["run"], **run}}), base
    finally:
        _Section.finish = finish
    return tuple(seen)


@functools.cache
def auto_keys() -> tuple[tuple[str, str], ...]:
    """The (section, key) pairs of the schema for which the reader accepts "auto" (in some base scene)."""
    found = []
    for section, key in schema():
        for base in BASES:
            data = copy.deepcopy({**base, "run": {"end_time": 1e-5, "timestep": 1e-8, **base["run"]}})
            if _set(data, section, key, AUTO) and _parses(data):
                found.append((section, key))
                break
    return tuple(found)


@functools.cache
def planned_values() -> dict[tuple[str, str], object]:
    """Each "auto"-able key's value in the planned scene of PLANNED_BASE with every such key "auto": a
    valid number for it."""
    from granchain.workflows.plan import plan_scene

    data = copy.deepcopy(PLANNED_BASE)
    for section, key in auto_keys():
        _set(data, section, key, AUTO)
    planned = scene_to_dict(plan_scene(scene_from_dict(data, source="planned.toml")).scene)
    return {(section, key): _table(planned, section)[key] for section, key in auto_keys()}


def _number(value, part: float):
    """A part of a planned value: a float scaled, an integer scaled and rounded (at least 2)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return value
    if isinstance(value, int):
        return max(2, round(value * part))
    return value * part


@st.composite
def auto_scenes(draw) -> dict:
    """A base scene with every "auto"-able key "auto" or a valid number (the base's own, a planned value
    or a part of it)."""
    data = copy.deepcopy(draw(st.sampled_from(BASES)))
    for section, key in auto_keys():
        table = _table(data, section)
        own = [] if table is None or table.get(key) in (None, AUTO) else [table[key]]  # the base's own value
        planned = planned_values()[(section, key)]
        numbers = [*own, *(_number(planned, part) for part in (1.0, 0.5, 0.25))]
        _set(data, section, key, AUTO if draw(st.booleans()) else draw(st.sampled_from(numbers)))
    return data


def _pinned(base: int, **values: object) -> dict:
    """BASES[base] with the given keys (section__key=value) set, end time and step numbers unless given:
    a draw that crashed before, pinned (@example)."""
    data = copy.deepcopy(BASES[base])
    data["run"].update(end_time=5e-5, timestep=2.5e-7)
    for name, value in values.items():
        _set(data, *name.split("__"), value)
    return data


#: beads = "auto" on a Hertz chain: predict's impact predictions took bead 1's mass of every bead (TypeError)
AUTO_HERTZ_CHAIN = _pinned(0, chain__beads=AUTO)
#: ... on a bilinear chain: its transition contact searched the chain's N - 1 contacts (TypeError)
AUTO_BILINEAR_CHAIN = _pinned(2, chain__beads=AUTO)
#: beads and end_time "auto" on a precompressed chain: the planner's front time asked the chain's N
#: (TypeError in n_contacts)
AUTO_PRECOMPRESSED_CHAIN = _pinned(1, chain__beads=AUTO, run__end_time=AUTO)


def _with(base: int, **auto: object) -> dict:
    """BASES[base] with the given [run], [chain] or [outputs] keys (section__key=value) set, every other
    "auto"-able key at its planned value: a pinned draw."""
    data = copy.deepcopy(BASES[base])
    for section, key in auto_keys():
        _set(data, section, key, planned_values()[(section, key)])
    for name, value in auto.items():
        _set(data, *name.split("__"), value)
    return data


def run_cli(argv: list[str]) -> tuple[int, str]:
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        rc = main(argv)  # an exception escaping main is a traceback: the test fails with it
    return rc, err.getvalue()


#: the exit 1 each command may give on a run that finished: what it did not measure, or differing solvers
EXIT_1 = {"run": "granchain: not measured", "compare": "differ by more than rtol"}

#: the commands drawn here, by the name granchain.cli's parser gives them (campaign: `campaign run` of
#: a one-point campaign file holding the scene)
COMMANDS = ("plan", "predict", "render", "submit", "run", "compare", "compare-laws", "accuracy", "campaign")


def check(argv: list[str], rc: int, err: str) -> None:
    """A command ran (exit 0, or its own exit 1 with its reason) or gave one `granchain: error:` line, exit 2."""
    assert "Traceback" not in err, err
    errors = [line for line in err.splitlines() if line.startswith("granchain: error:")]
    if rc == 2:
        assert len(errors) == 1, err
        assert err.rstrip("\n").endswith(errors[0]), err  # the error is the last line
        return
    assert rc == 0 or (rc == 1 and EXIT_1.get(argv[0], "\0") in err), (argv, rc, err)
    assert not errors, err


def commands(data: dict, tmp_path, names: tuple[str, ...]) -> list[int]:
    """Run each named command on the scene `data` (written to a file), checking each outcome."""
    path = tmp_path / "auto.toml"
    path.write_text(scene_text(data), encoding="utf-8")
    argvs = {
        "plan": ["plan", str(path)],
        "predict": ["predict", str(path)],
        "render": ["render", str(path)],
        "run": ["run", str(path), "--backend", "reference", "--out", str(tmp_path / "run"), "--quiet", "--overwrite"],
        "compare": ["compare", str(path), "--out", str(tmp_path / "compare"), "--overwrite"],
        "campaign": ["campaign", "run", str(_one_point(data, tmp_path)), "--out", str(tmp_path / "ws")],
        "submit": ["submit", str(path), "--out", str(tmp_path / "submit"), "-q"],
        "compare-laws": ["compare-laws", str(path), "--backend", "reference", "--error-estimate", "off"],
        "accuracy": ["accuracy", str(path), "--methods", "rk4", "--levels", "1", "--repeats", "1"],
    }
    codes = []
    for name in names:
        argv = argvs[name]
        if name in ("compare-laws", "accuracy"):
            argv += ["--out", str(tmp_path / name), "--overwrite", "--quiet"]
        if name == "campaign":
            argv += ["--workers", "1", "--rerun", "-q"]
        rc, err = run_cli(argv)
        check(argv, rc, err)
        _event(f"{name}: " + ("refused: " + err.rsplit("is invalid", 1)[0][-60:] if rc == 2 else f"exit {rc}"))
        codes.append(rc)
    return codes


def _event(text: str) -> None:
    """A hypothesis event (its statistics: how many draws ran, how many were refused)."""
    from hypothesis.errors import InvalidArgument

    with contextlib.suppress(InvalidArgument):
        event(text)


def _one_point(data: dict, tmp_path):
    """A campaign file of one point: the scene inline, one value of its radius as the grid."""
    text = '[campaign]\nbackend = "reference"\nerror_estimate = false\n'
    text += f'[vary]\n"chain.radius" = [{data["chain"]["radius"]!r}]\n'
    text += scene_text({"scene": data}).replace("[scene]\n", "", 1)
    path = tmp_path / "one-point.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture(autouse=True)
def short_runs(monkeypatch):
    """A run of more steps than a short one is refused (exit 2, GRANCHAIN_MAX_STEPS), not run for minutes."""
    monkeypatch.setenv("GRANCHAIN_MAX_STEPS", "200000")


SETTINGS = dict(
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture, HealthCheck.data_too_large],
)


def test_the_auto_keys_are_found_in_the_reader_and_each_needs_a_plan():
    """The reader's schema has "auto"-able keys, and a scene with any of them "auto" needs a plan."""
    assert ("chain", "beads") in auto_keys()
    assert ("run", "end_time") in auto_keys()
    assert not scene_from_dict(_with(0), source="probe.toml").needs_plan
    for section, key in auto_keys():
        data = _with(0, **{f"{section}__{key}": AUTO})
        assert scene_from_dict(data, source="probe.toml").needs_plan, (section, key)


@settings(max_examples=60, **SETTINGS)
@given(auto_scenes())
@example(AUTO_HERTZ_CHAIN)
@example(AUTO_BILINEAR_CHAIN)
@example(AUTO_PRECOMPRESSED_CHAIN)
@example(_pinned(2, chain__beads=AUTO, run__end_time=AUTO))  # precompressed, a step load: its later maximum
def test_plan_predict_and_render_take_every_auto_key(tmp_path, data):
    commands(data, tmp_path, ("plan", "predict", "render", "submit"))


def test_every_command_that_takes_a_scene_is_drawn():
    """Each subcommand of granchain.cli whose parser takes a scene (a `scene` argument) is one of COMMANDS."""
    import argparse

    from granchain.cli import build_parser

    def subcommands(parser):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                yield from action.choices.items()

    takes_a_scene = {name for name, sub in subcommands(build_parser()) if any(a.dest == "scene" for a in sub._actions)}
    assert takes_a_scene <= set(COMMANDS), takes_a_scene - set(COMMANDS)


@settings(max_examples=30, **SETTINGS)
@given(auto_scenes())
@example(AUTO_PRECOMPRESSED_CHAIN)
def test_a_reference_run_takes_every_auto_key(tmp_path, data):
    commands(data, tmp_path, ("run",))


@pytest.mark.slow
@settings(max_examples=4, **SETTINGS)
@given(auto_scenes())
@example(AUTO_PRECOMPRESSED_CHAIN)
def test_compare_campaign_compare_laws_and_accuracy_take_every_auto_key(tmp_path, data):
    commands(data, tmp_path, ("compare", "campaign", "compare-laws", "accuracy"))
