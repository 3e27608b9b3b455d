"""Run directories: the documented files and columns, atomic writes, clear CLI errors."""

import csv
import json
import subprocess
import sys

import numpy as np
import pytest

from granchain import rundir
from granchain.cli import main
from granchain.rundir import RunDirError, read_peaks, read_summary
from granchain.safe_files import MARKER
from granchain.workflows.run import run_scene

from .conftest import make_scene, make_scene_text


def test_run_writes_documented_files(tmp_path):
    sc = make_scene(
        outputs="histories = [1, 5]\nsnapshots = [5e-5]\npeak_force = [1, 2, 10]", end_time=1e-4, timestep=5e-8
    )
    out = tmp_path / "run"
    res = run_scene(sc, out=out)
    names = {p.name for p in out.iterdir()}
    assert names == {"scene.toml", "summary.json", "peaks.csv", "histories.csv", "snapshots.csv", "energy.csv", MARKER}
    s = read_summary(out)
    for key in ("backend", "timestep", "steps", "wall_time", "observables"):
        assert key in s
    assert s["backend"] == "reference"
    assert s["steps"] == res.solution.steps
    with open(out / "peaks.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == [
        "contact",
        "peak_force",
        "time_of_peak",
        "peak_force_nondim",
        "complete",
        "leading_pulse_force",
        "arrival_time",
    ]
    assert [int(r[0]) for r in rows[1:]] == [1, 2, 10]
    p = read_peaks(out)
    assert np.array_equal(p["peak_force"], res.solution.peak_force[[0, 1, 9]])  # full precision
    assert np.allclose(p["peak_force_nondim"], p["peak_force"] / sc.force_scale, rtol=1e-15)
    with open(out / "histories.csv") as fh:
        assert next(csv.reader(fh)) == ["time", "force_1", "force_5", "velocity_1", "velocity_5"]
    with open(out / "snapshots.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["time", "bead", "displacement", "velocity", "contact_force"]
    assert len(rows) == 1 + 30
    assert (out / "scene.toml").read_text() == sc.source_text


def test_no_dump_files_without_histories_or_snapshots(tmp_path):
    run_scene(make_scene(end_time=5e-5, timestep=5e-8), out=tmp_path / "r")
    assert not (tmp_path / "r" / "histories.csv").exists()
    assert not (tmp_path / "r" / "snapshots.csv").exists()


def test_existing_directory_refused_before_running(tmp_path, monkeypatch):
    (tmp_path / "r").mkdir()
    ran = []
    monkeypatch.setattr("granchain.workflows.run.run_reference", lambda *a, **k: ran.append(1))
    with pytest.raises(RunDirError, match="already exists.*--overwrite"):
        run_scene(make_scene(), out=tmp_path / "r")
    assert not ran


def test_interrupted_write_leaves_nothing(tmp_path, monkeypatch):
    sc = make_scene(end_time=5e-5, timestep=5e-8)
    res = run_scene(sc)

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(rundir, "_write_csv", boom)
    with pytest.raises(KeyboardInterrupt):
        rundir.write_run_dir(res, tmp_path / "r")
    assert list(tmp_path.iterdir()) == []


def test_overwrite_replaces_atomically(tmp_path):
    sc = make_scene(end_time=5e-5, timestep=5e-8)
    res = run_scene(sc)
    rundir.write_run_dir(res, tmp_path / "r")
    (tmp_path / "r" / "stale.txt").write_text("old")
    rundir.write_run_dir(res, tmp_path / "r", overwrite=True)
    assert not (tmp_path / "r" / "stale.txt").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]


def test_unwritable_parent(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(RunDirError, match="cannot create the parent"):
        rundir.check_output_dir(blocker / "sub" / "run")


def test_cli_bad_scene_is_a_clear_error(tmp_path, capsys):
    p = tmp_path / "bad.toml"
    p.write_text(make_scene_text().replace("radius = 4.76e-3", "radius = -1.0"))
    assert main(["run", str(p), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "bad.toml" in err
    assert "radius" in err
    assert "-1.0" in err
    assert "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_cli_run_predict_scenes(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(make_scene_text(end_time=5e-5, timestep=5e-8))
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--method", "verlet"]) == 0
    assert read_summary(tmp_path / "o")["method"] == "verlet"
    assert "leading_peak_force" in capsys.readouterr().out
    assert main(["predict", str(p), "--json"]) == 0
    preds = json.loads(capsys.readouterr().out)
    assert any(x["name"] == "short_load_peak_force" for x in preds)
    assert main(["scenes"]) == 0
    assert "default" in capsys.readouterr().out


def test_console_script_default_scene(tmp_path):
    # the README's first command: the console script on the bundled default scene
    r = subprocess.run(
        [sys.executable, "-m", "granchain.cli", "run", "--out", str(tmp_path / "d")],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    s = read_summary(tmp_path / "d")
    assert s["observables"]["leading_peak_force"] > 0
    assert s["observables"]["wave_speed"] > 0
