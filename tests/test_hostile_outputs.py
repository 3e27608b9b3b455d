"""Output directories and terminal output on a hostile or constrained machine: ``--overwrite`` never
deletes a directory without granchain's marker, whatever names it holds; ``plot`` into a directory it
cannot write is one error line; granchain's terminal output never crashes on an encoding."""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
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


# ------------------------------------------------------------------------------ plot where it cannot write


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    base = tmp_path_factory.mktemp("plot")
    (base / "s.toml").write_text(make_scene_text(**SMALL, outputs="histories = [1, 5]"))
    assert main(["run", str(base / "s.toml"), "--out", str(base / "run"), "-q"]) == 0
    return base / "run"


def granchain(*args, user: str | None = None, env=None) -> subprocess.CompletedProcess:
    """``granchain ARGS`` in a subprocess (as ``user``, when given, through setpriv)."""
    cmd = [sys.executable, "-m", "granchain", *args]
    if user is not None:
        cmd = ["setpriv", f"--reuid={user}", f"--regid={user}", "--clear-groups", "--", *cmd]
    env = {**os.environ, **(env or {})}
    encoding = env.get("PYTHONIOENCODING", "utf-8").split(":")[0] or "utf-8"  # stdout's, as granchain's
    return subprocess.run(cmd, capture_output=True, encoding=encoding, env=env, timeout=120)


@contextlib.contextmanager
def tmpfs(where: Path, size: str) -> Iterator[Path]:
    """A tmpfs of ``size`` mounted at ``where`` for the block (skipped where mounting is not allowed)."""
    where.mkdir()
    made = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)], capture_output=True)
    if made.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({made.stderr.decode().strip()}): needs root in a privileged container")
    try:
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], check=True)


def _read_only_mode(d: Path) -> dict:
    """The directory made 0555 (its files 0444), plotted by a user other than root (root ignores modes)."""
    if not shutil.which("setpriv"):
        pytest.skip("no setpriv to run granchain as another user")
    for p in [d, *d.iterdir()]:
        p.chmod(0o555 if p.is_dir() else 0o444)
    home = d.parent / "home"
    home.mkdir(mode=0o777)
    home.chmod(0o777)
    return {"user": "65534", "env": {"HOME": str(home), "MPLCONFIGDIR": str(home)}}


def _fill(d: Path) -> None:
    with contextlib.suppress(OSError), (d.parent / "filler").open("wb") as fh:
        while True:
            fh.write(b"\0" * 65536)
            fh.flush()


@pytest.mark.skipif(not sys.platform.startswith("linux") or os.geteuid() != 0, reason="mounts and setpriv as root")
@pytest.mark.parametrize("case", ["mode 0555, another user", "read-only mount", "full disk"])
def test_plot_where_it_cannot_write_is_one_error_line_naming_the_directory(run_dir, case):
    base = Path(tempfile.mkdtemp(prefix="granchain-plot-"))  # (not below pytest's 0700 tmp: another user reaches it)
    base.chmod(0o755)
    with contextlib.ExitStack() as stack:
        stack.callback(shutil.rmtree, base, ignore_errors=True)
        where = base if case.startswith("mode") else stack.enter_context(tmpfs(base / "m", "2m"))
        d = where / "run"
        shutil.copytree(run_dir, d)
        kw = {}
        if case.startswith("mode"):
            kw = _read_only_mode(d)
        elif case == "read-only mount":
            subprocess.run(["mount", "-o", "remount,ro", str(where)], check=True)
        else:
            _fill(d)
        before = {p.name: p.read_bytes() for p in d.iterdir()}
        done = granchain("plot", str(d), **kw)
        assert done.returncode == 2, done.stderr
        err = one_error_line(done.stderr)
        assert f"{d}: cannot write" in err
        fix = "free some space" if case == "full disk" else "make it writable"
        assert fix in err
        assert {p.name: p.read_bytes() for p in d.iterdir()} == before  # nothing half-written left


# ------------------------------------------------------------------------------ terminal encodings


TITLE = "Kette \u2013 Sto\xdfwelle \xfc, \u9707\u6ce2 \U0001f30a"


@pytest.mark.parametrize("command", ["run", "plan", "plot"])
@pytest.mark.parametrize("env", [{"PYTHONIOENCODING": "ascii"}, {"PYTHONIOENCODING": "latin-1:strict"}])
def test_non_ascii_titles_and_paths_on_an_ascii_terminal_print_escaped_never_crash(tmp_path, command, env):
    scene = tmp_path / "s.toml"
    scene.write_text(f'title = "{TITLE}"\n' + make_scene_text(**SMALL), encoding="utf-8")
    out = tmp_path / f"L\xe4ufe {TITLE}"
    args = {"run": ["run", str(scene), "--out", str(out)], "plan": ["plan", str(scene)], "plot": ["plot", str(out)]}
    if command == "plot":
        assert main(["run", str(scene), "--out", str(out), "-q"]) == 0
    done = granchain(*args[command], env=env)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    shown = done.stdout.encode(env["PYTHONIOENCODING"].split(":")[0]).decode("unicode_escape")  # escapes read back
    assert (str(out) if command == "plot" else TITLE) in shown
