"""Run directories someone else may have prepared: --overwrite replaces only a directory granchain
wrote, no symbolic link planted in one makes granchain read or write outside it, a damaged file is
one error line. The accuracy study's directory follows the same rules."""

import json
import os
import subprocess
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain import rundir, safe_files
from granchain.cli import main
from granchain.rundir import RunDirError, read_peaks, read_summary
from granchain.safe_files import MARKER
from granchain.workflows.run import run_scene

from .conftest import make_scene, make_scene_text

SMALL = dict(beads=20, end_time=5e-5, timestep=5e-8, outputs="histories = [1, 5]\nsnapshots = [2e-5]")
RUN_FILES = ["scene.toml", "summary.json", "peaks.csv", "histories.csv", "snapshots.csv", "energy.csv"]


@pytest.fixture(scope="module")
def result():
    return run_scene(make_scene(**SMALL))


@pytest.fixture
def scene_file(tmp_path) -> Path:
    p = tmp_path / "s.toml"
    p.write_text(make_scene_text(**SMALL))
    return p


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    assert err.startswith("granchain: error: "), err
    assert err.count("granchain: error:") == 1, err
    return err


# ------------------------------------------------------------------------------ --overwrite


def test_overwrite_refuses_a_directory_granchain_did_not_write(scene_file, tmp_path, capsys):
    d = tmp_path / "d"
    (d / "sub").mkdir(parents=True)
    (d / "precious.txt").write_text("keep")
    assert main(["run", str(scene_file), "--out", str(d), "--overwrite"]) == 2
    err = one_error_line(capsys)
    assert str(d) in err
    assert "not written by granchain" in err
    assert "choose another --out" in err
    assert (d / "precious.txt").read_text() == "keep"
    assert (d / "sub").is_dir()


def test_overwrite_replaces_a_run_directory_granchain_marked_and_no_other(scene_file, tmp_path, capsys):
    d = tmp_path / "d"
    assert main(["run", str(scene_file), "--out", str(d)]) == 0
    assert (d / MARKER).is_file()
    assert main(["run", str(scene_file), "--out", str(d), "--overwrite"]) == 0
    (d / MARKER).unlink()  # granchain's own files, but no marker: not provably granchain's
    capsys.readouterr()  # (the runs above said what their short end time did not measure)
    assert main(["run", str(scene_file), "--out", str(d), "--overwrite"]) == 2
    assert "not written by granchain" in one_error_line(capsys)
    assert (d / "summary.json").is_file()


def test_a_copied_marker_that_is_a_link_does_not_count(result, tmp_path):
    d = tmp_path / "d"
    d.mkdir()
    rundir.write_run_dir(result, tmp_path / "real")
    os.symlink(tmp_path / "real" / MARKER, d / MARKER)
    (d / "precious.txt").write_text("keep")
    with pytest.raises(RunDirError, match="not written by granchain"):
        rundir.write_run_dir(result, d, overwrite=True)
    assert (d / "precious.txt").read_text() == "keep"


def test_out_that_is_a_link_is_refused(result, tmp_path):
    target = tmp_path / "elsewhere"
    rundir.write_run_dir(result, target)
    os.symlink(target, tmp_path / "link")
    with pytest.raises(RunDirError, match="symbolic link"):
        rundir.write_run_dir(result, tmp_path / "link", overwrite=True)
    assert target.is_dir()
    assert (target / "summary.json").is_file()


# ------------------------------------------------------------------------- planted links


@pytest.mark.parametrize("name", ["summary.json", "peaks.csv"])
def test_readers_refuse_a_planted_link(result, tmp_path, name):
    d = rundir.write_run_dir(result, tmp_path / "r")
    secret = tmp_path / "secret"
    secret.write_bytes((d / name).read_bytes())  # even a valid file is not read through a link
    (d / name).unlink()
    os.symlink(secret, d / name)
    with pytest.raises(RunDirError, match="symbolic link"):
        read_summary(d) if name == "summary.json" else read_peaks(d)


def test_extra_files_are_copied_only_when_regular(result, tmp_path):
    secret = tmp_path / "secret"
    secret.write_text("SECRET")
    os.symlink(secret, tmp_path / "leak.dump")
    with pytest.raises(RunDirError, match="symbolic link"):
        rundir.write_run_dir(result, tmp_path / "r", extra_files={"leak.dump": tmp_path / "leak.dump"})
    assert not (tmp_path / "r").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


@pytest.mark.parametrize("name", RUN_FILES + [MARKER])
def test_a_link_planted_in_a_directory_being_replaced_is_never_written_through(result, tmp_path, name):
    d = rundir.write_run_dir(result, tmp_path / "r")
    victim = tmp_path / "victim"
    victim.write_text("VICTIM")
    (d / name).unlink()
    os.symlink(victim, d / name)
    if name == MARKER:  # the marker a link: not granchain's any more
        with pytest.raises(RunDirError, match="not written by granchain"):
            rundir.write_run_dir(result, d, overwrite=True)
    else:
        rundir.write_run_dir(result, d, overwrite=True)
        assert not (d / name).is_symlink()
    assert victim.read_text() == "VICTIM"


# ------------------------------------------------------------------------- damaged files


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    name=st.sampled_from(["summary.json", "peaks.csv"]),
    content=st.one_of(
        st.binary(max_size=200),
        st.text(max_size=200),
        st.just("[" * 50_000 + "]" * 50_000),
        st.just("contact,peak_force\nabc,def\n"),
        st.just("peak_force\n1.0\n"),
        st.just('"a string"'),
    ),
)
def test_a_damaged_summary_or_peak_table_is_a_run_dir_error(result, tmp_path_factory, name, content):
    d = rundir.write_run_dir(result, tmp_path_factory.mktemp("d") / "r")
    (d / name).write_bytes(content if isinstance(content, bytes) else content.encode())
    try:
        out, refused = read_summary(d) if name == "summary.json" else read_peaks(d), None
    except RunDirError as e:
        out, refused = None, str(e)
    if refused is not None:
        assert str(d / name) in refused
    else:  # what parses is what a reader gets: a JSON object, a table with whole contact numbers
        assert isinstance(out, dict)
        if name == "peaks.csv":
            assert out["contact"].dtype.kind in "iu"


# ---------------------------------------------------------------------------- accuracy


@pytest.fixture(scope="module")
def study():
    from granchain.workflows.accuracy import accuracy_study

    return accuracy_study(make_scene(beads=20, end_time=5e-5, timestep=1e-8), methods=("rk4",), levels=2, repeats=1)


def test_accuracy_refuses_a_non_empty_directory_without_overwrite(study, tmp_path):
    from granchain.workflows.accuracy import write_study

    d = tmp_path / "acc"
    d.mkdir()
    (d / "precious.txt").write_text("keep")
    with pytest.raises(RunDirError, match="already exists.*--overwrite"):
        write_study(study, d)
    with pytest.raises(RunDirError, match="not written by granchain"):
        write_study(study, d, overwrite=True)
    assert sorted(p.name for p in d.iterdir()) == ["precious.txt"]
    empty = tmp_path / "empty"
    empty.mkdir()
    files = write_study(study, empty)  # an empty directory is taken
    assert all(f.stat().st_size > 0 for f in files)
    assert (empty / MARKER).is_file()
    assert write_study(study, empty, overwrite=True) == files


def test_accuracy_title_is_not_mathtext(study, tmp_path):
    from dataclasses import replace

    from granchain.workflows.accuracy import write_study

    odd = replace(study, scene=replace(study.scene, title="$\\frac{1}{$ \x1b[2J"))
    files = write_study(odd, tmp_path / "acc")
    assert files[1].stat().st_size > 1000


@pytest.fixture
def read_only_dir(tmp_path):
    """A directory nothing can be written in: chmod for a user; for root (whom chmod does not stop) a
    tmpfs mounted read-only, where the machine lets root mount one."""
    d = tmp_path / "ro"
    d.mkdir()
    if os.geteuid() != 0:
        d.chmod(0o555)
        yield d
        d.chmod(0o755)
        return
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m,ro", "tmpfs", str(d)], capture_output=True)
    if r.returncode != 0:
        pytest.skip(f"root cannot mount a read-only tmpfs here: {r.stderr.decode().strip()}")
    try:
        yield d
    finally:
        subprocess.run(["umount", str(d)], check=False)


def test_read_only_directories_are_one_error_line(study, result, read_only_dir, scene_file, capsys):
    from granchain.workflows.accuracy import write_study

    with pytest.raises(RunDirError, match="not writable|Read-only|Permission"):
        write_study(study, read_only_dir / "acc")
    with pytest.raises(RunDirError, match="not writable|Read-only|Permission"):
        rundir.write_run_dir(result, read_only_dir / "r")
    assert main(["run", str(scene_file), "--out", str(read_only_dir / "r")]) == 2
    one_error_line(capsys)


def test_write_helpers_leave_nothing_on_a_full_disk(tmp_path, monkeypatch):
    """A write that fails midway (ENOSPC) leaves the old file, and no temporary file."""
    p = tmp_path / "f.json"
    safe_files.write_text(p, json.dumps({"old": 1}))

    class Full(Exception):
        pass

    def interrupted_write():
        with safe_files.open_for_write(p) as fh:
            fh.write("partial")
            raise Full

    with pytest.raises(Full):
        interrupted_write()
    assert json.loads(p.read_text()) == {"old": 1}
    assert sorted(x.name for x in tmp_path.iterdir()) == ["f.json"]


def test_only_the_marker_makes_a_directory_granchains(tmp_path):
    d = tmp_path / "compare"
    for sub in ("lammps", "reference"):
        (d / sub).mkdir(parents=True)
        for name in ("summary.json", "peaks.csv", "scene.toml", "peaks.png", "peaks_plot.csv"):
            (d / sub / name).write_text("x")
    for name in ("compare.csv", "compare.md", "compare_peaks.png", "compare_peaks_plot.csv"):
        (d / name).write_text("x")
    assert not rundir.owned_by_granchain(d)  # granchain's names, but anyone can write those
    safe_files.mark_owned(d, "compare")
    assert rundir.owned_by_granchain(d)
    assert not rundir.owned_by_granchain(tmp_path / "nothing")
