"""The command line for scripts and shared scenes: ``python -m granchain``, ``--version``, strict JSON
from run, plan, compare and predict (``--json``), and scene text printed with its control characters
escaped (a shared scene's title cannot retitle the terminal or clear it)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from hypothesis import given
from hypothesis import strategies as st

import granchain
from granchain.cli import main

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


@pytest.mark.parametrize("command", ["run", "plan", "compare", "predict"])
def test_json_for_scripts(command, scene_file, tmp_path, capfd):
    args = [command, str(scene_file), "--json"]
    if command in ("run", "compare"):
        args += ["--out", str(tmp_path / "out"), "-q"]
    assert main(args) == 0
    out, err = capfd.readouterr()
    data = json.loads(out, parse_constant=lambda c: pytest.fail(f"not strict JSON: {c}"))
    no_control(out)  # JSON escapes the title's control characters itself
    if command == "run":
        assert data["run_dir"] == str(tmp_path / "out")
        assert data["backend"] == "reference"
        assert data["title"] == "evil \x1b]0;owned\x07\x1b[2J end"
        assert data["observables"]["wave_speed"] > 0
        assert "provenance" in data
        data.pop("run_dir")
        kept = json.loads(json.dumps(granchain.load_run(tmp_path / "out").summary), parse_constant=lambda c: None)
        assert data == kept  # summary.json, NaN as null
    elif command == "plan":
        assert data["method"] == "rk4"
        assert data["timestep"] > 0
        assert data["steps"] * 16 == data["bead_steps"]
        assert "timestep" in {c["name"] for c in data["choices"]}
        assert data["units"]["timestep"] == "s"
    elif command == "compare":
        assert data["ok"] is True
        assert data["differ"] == []
        rows = {r["quantity"]: r for r in data["rows"]}
        assert rows
        assert all({"unit", "lammps", "reference", "ok"} <= set(r) for r in rows.values())
        assert data["compare_dir"] == str(tmp_path / "out")
    else:
        assert isinstance(data, list)
        assert {"name", "value", "unit"} <= set(data[0])


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
