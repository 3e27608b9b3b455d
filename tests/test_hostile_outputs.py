"""Output directories and terminal output on a hostile or constrained machine: ``--overwrite`` never
deletes a directory without granchain's marker, whatever names it holds; ``plot`` into a directory it
cannot write is one error line; granchain's terminal output never crashes on an encoding."""

from __future__ import annotations

from pathlib import Path

import pytest

from granchain.cli import main
from granchain.safe_files import MARKER

from .conftest import make_scene_text

SMALL = dict(beads=20, end_time=5e-5, timestep=5e-8)


def one_error_line(err: str) -> str:
    assert "Traceback" not in err, err
    assert err.startswith("granchain: error: "), err
    assert err.count("granchain: error:") == 1, err
    return err


@pytest.fixture
def scene_file(tmp_path) -> Path:
    p = tmp_path / "s.toml"
    p.write_text(make_scene_text(**SMALL))
    return p


# ------------------------------------------------------------------------------ --overwrite


def users_directory(d: Path) -> dict[str, str]:
    """A directory of the user's that looks like one granchain wrote before its marker existed
    (a summary.json, files matching granchain's old patterns, a lammps/ of the same): what it holds."""
    files = {
        "summary.json": '{"mine": true}',
        "holiday.png": "photo",
        "draft.pdf": "thesis",
        "lammps/summary.json": "{}",
        "lammps/log.lammps": "my own LAMMPS log",
    }
    for name, text in files.items():
        (d / name).parent.mkdir(parents=True, exist_ok=True)
        (d / name).write_text(text)
    return files


@pytest.mark.parametrize("command", ["run", "compare"])
def test_overwrite_leaves_an_unmarked_directory_with_granchains_names_alone(scene_file, tmp_path, capsys, command):
    d = tmp_path / "d"
    files = users_directory(d)
    argv = [command, str(scene_file), "--out", str(d), "--overwrite"]
    if command == "compare":
        argv += ["--method", "rk4"]  # (refused before anything runs: the backend does not matter)
    assert main(argv) == 2
    err = one_error_line(capsys.readouterr().err)
    assert str(d) in err
    assert f"no {MARKER} marker" in err
    assert "choose another --out" in err
    assert "remove that directory yourself" in err
    assert {n: (d / n).read_text() for n in files} == files
    assert not (d / MARKER).exists()
