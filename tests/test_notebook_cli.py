"""The command line for scripts and shared scenes: ``python -m granchain``, ``--version``, strict JSON
from every command with ``--json`` (found in the parser), each with its schema version, and scene text
printed with its control characters escaped (a shared scene's title cannot retitle the terminal or
clear it)."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

import pytest
from hypothesis import given
from hypothesis import strategies as st

import granchain
from granchain.cli import JSON_SCHEMA_VERSION, build_parser, main
from granchain.cli.terminal import SCHEMA_KEY, versioned

#: a title with an OSC (window title), a bell and a clear-screen sequence, as TOML escapes
EVIL_TITLE = r"evil \u001b]0;owned\u0007\u001b[2J end"

SCENE = f'''title = "{EVIL_TITLE}"
[chain]
beads = 16
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "impulse"
impulse = 0.05
duration = 1e-6
[run]
end_time = 6e-5
timestep = "auto"
[outputs]
histories = [1, 8]
'''


@pytest.fixture
def scene_file(tmp_path):
    p = tmp_path / "evil.toml"
    p.write_text(SCENE)
    return p


def no_control(text: str) -> None:
    bad = sorted({hex(ord(c)) for c in text if not c.isprintable() and c not in "\n\t"})
    assert not bad, f"control characters printed: {bad}"


@pytest.mark.parametrize("how", [[sys.executable, "-m", "granchain"], [sys.executable, "-m", "granchain.cli"]])
def test_python_m_granchain_and_version(how):
    out = subprocess.run([*how, "--version"], capture_output=True, text=True, timeout=120, check=True)
    assert out.stdout.strip() == f"granchain {granchain.__version__}"
    out = subprocess.run([*how, "materials", "brass"], capture_output=True, text=True, timeout=120, check=True)
    assert "brass" in out.stdout


@pytest.mark.parametrize("command", ["run", "plan", "compare", "predict"])
def test_scene_text_is_printed_escaped(command, scene_file, tmp_path, capfd):
    args = [command, str(scene_file)]
    if command in ("run", "compare"):
        args += ["--out", str(tmp_path / "out"), "--error-estimate", "off", "-q"]
    assert main(args) == 0
    out, err = capfd.readouterr()
    no_control(out)
    no_control(err)
    if command != "predict":  # predict prints the models, not the scene's text
        assert r"evil \x1b]0;owned\x07\x1b[2J end" in out


def json_commands(parser=None) -> dict[str, set[str]]:
    """Every subcommand (nested ones as "campaign table") whose parser takes --json, with its options:
    read from the CLI's parser, so a new command with --json is tested without editing this file."""
    found = {}

    def walk(p, name):
        options = {o for a in p._actions for o in a.option_strings}
        if "--json" in options:
            found[name] = options
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                for sub, sp in a.choices.items():
                    walk(sp, f"{name} {sub}".strip())

    walk(parser or build_parser(), "")
    return found


def _check_run(data, tmp_path):
    assert data["run_dir"] == str(tmp_path / "out")
    assert data["backend"] == "reference"
    assert data["title"] == "evil \x1b]0;owned\x07\x1b[2J end"
    assert data["observables"]["wave_speed"] > 0
    assert "provenance" in data
    data.pop("run_dir")
    data.pop(SCHEMA_KEY)
    kept = json.loads(json.dumps(granchain.load_run(tmp_path / "out").summary), parse_constant=lambda c: None)
    assert data == kept  # summary.json, NaN as null


def _check_plan(data, tmp_path):
    assert data["method"] == "rk4"
    assert data["timestep"] > 0
    assert data["steps"] * 16 == data["bead_steps"]
    assert "timestep" in {c["name"] for c in data["choices"]}
    assert data["units"]["timestep"] == "s"


def _check_compare(data, tmp_path):
    assert data["ok"] is True
    assert data["differ"] == []
    rows = {r["quantity"]: r for r in data["rows"]}
    assert rows
    assert all({"unit", "lammps", "reference", "ok"} <= set(r) for r in rows.values())
    assert data["compare_dir"] == str(tmp_path / "out")


def _check_predict(data, tmp_path):
    assert isinstance(data, list)  # still a list: the version is in each row (docs/notebook.md)
    assert {"name", "value", "unit"} <= set(data[0])


#: what each command's JSON holds beyond the schema version every one carries
JSON_CHECKS = {"run": _check_run, "plan": _check_plan, "compare": _check_compare, "predict": _check_predict}


def test_the_json_checks_name_commands_that_take_json():
    assert set(JSON_CHECKS) <= set(json_commands())


@pytest.mark.parametrize("command", sorted(json_commands()))
def test_json_for_scripts(command, scene_file, tmp_path, capfd):
    """Every --json output is strict JSON with the schema version (JSON_SCHEMA_VERSION): at the top of
    an object, in every row of a list."""
    options = json_commands()[command]
    args = [*command.split(), str(scene_file), "--json"]
    args += ["--out", str(tmp_path / "out")] if "--out" in options else []
    args += ["-q"] if "-q" in options else []
    assert main(args) == 0
    out, err = capfd.readouterr()
    data = json.loads(out, parse_constant=lambda c: pytest.fail(f"not strict JSON: {c}"))
    no_control(out)  # JSON escapes the title's control characters itself
    documents = data if isinstance(data, list) else [data]
    assert documents
    assert all(d[SCHEMA_KEY] == JSON_SCHEMA_VERSION for d in documents)
    assert all(next(iter(d)) == SCHEMA_KEY for d in documents)  # the first key, seen first
    JSON_CHECKS.get(command, lambda data, tmp_path: None)(data, tmp_path)


def test_versioned_refuses_what_cannot_carry_the_version():
    assert versioned({"a": 1}) == {SCHEMA_KEY: JSON_SCHEMA_VERSION, "a": 1}
    assert versioned([{"a": 1}, {}]) == [{SCHEMA_KEY: JSON_SCHEMA_VERSION, "a": 1}, {SCHEMA_KEY: JSON_SCHEMA_VERSION}]
    with pytest.raises(TypeError, match="object or a list of objects"):
        versioned([1, 2])
    with pytest.raises(ValueError, match="schema_version"):
        versioned({SCHEMA_KEY: 0})


def test_errors_and_warnings_are_printed_escaped(tmp_path, capfd):
    bad = tmp_path / "bad\x1b[2J.toml"
    bad.write_text("[chain]\nbeads = -1\n")
    assert main(["run", str(bad)]) == 2
    _, err = capfd.readouterr()
    assert err.startswith("granchain: error: ")
    no_control(err)
    assert r"bad\x1b[2J.toml" in err


@given(text=st.text(), limit=st.one_of(st.none(), st.integers(3, 200)))
def test_printable_text_has_no_control_characters(text, limit):
    """Whatever a scene's text holds, what granchain prints of it moves no cursor and rings no bell,
    and keeps every printable character as it is."""
    from granchain.results import printable

    out = printable(text, limit)
    no_control(out.replace("\n", "").replace("\t", ""))
    assert "\n" not in out
    assert "\t" not in out
    assert "\x1b" not in out
    if limit is not None:
        assert len(out) <= limit
    if text.isprintable() and (limit is None or len(text) <= limit):
        assert out == text


def test_the_api_takes_a_scene_name_or_path_where_it_takes_a_scene(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(SCENE)
    by_path, by_scene = granchain.run(p), granchain.run(granchain.load_scene(p))
    assert by_path.peaks.equals(by_scene.peaks)
    assert granchain.plan("default").scene.chain.beads == granchain.load_scene("default").chain.beads
    with pytest.raises(granchain.GranchainError, match="no such scene file"):
        granchain.run(tmp_path / "missing.toml")
