"""Faults: Ctrl-C or a killed process in the middle of a run, a full disk, a plugin that
fails to build. Each gives a clear message, leaves no run directory that looks complete, and a
rerun starts cleanly. These run the real `granchain` command in its own process."""

import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from granchain import safe_files
from granchain.lammps import build

from .conftest import make_scene_text

#: a reference run of half a minute (RK4, 300 beads, 400k steps); it is interrupted after 3 s
LONG = make_scene_text(beads=300, end_time=2e-2, timestep=5e-8)
SHORT = make_scene_text(beads=20, end_time=5e-5, timestep=5e-8, outputs="histories = [1, 2, 3]")


def granchain(args, tmp_path, preexec_fn=None, **kw):
    env = {**os.environ, "TMPDIR": str(tmp_path / "tmp"), "PYTHONDONTWRITEBYTECODE": "1"}

    def as_from_a_terminal():
        # a terminal's Ctrl-C: a test runner's worker (pytest-xdist) may ignore SIGINT, which a child inherits
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        if preexec_fn is not None:
            preexec_fn()

    (tmp_path / "tmp").mkdir(exist_ok=True)
    return subprocess.Popen(
        [sys.executable, "-m", "granchain.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,  # its own process group: a signal reaches it and its LAMMPS worker, like a terminal's
        preexec_fn=as_from_a_terminal,
        **kw,
    )


def wait_until_running(proc, marker: Path | None = None, timeout=60.0):
    """Wait until the run has started: the LAMMPS work directory exists, or 3 s of CPU were spent."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        assert proc.poll() is None, proc.communicate()
        if marker is not None and any(marker.glob("granchain-lammps-*")):
            time.sleep(0.5)
            return
        if marker is None and time.time() - t0 > 3.0:
            return
        time.sleep(0.05)
    raise AssertionError("the run did not start")


def nothing_left(tmp_path, out):
    assert not out.exists()
    assert not list(out.parent.glob(f".{out.name}.*"))  # no hidden partial directory either


@pytest.mark.parametrize("backend", ["reference", "lammps"])
def test_ctrl_c_mid_run(tmp_path, backend):
    scene = tmp_path / "long.toml"
    scene.write_text(LONG if backend == "reference" else make_scene_text(beads=3000, end_time=2e-2, timestep=5e-8))
    out = tmp_path / "out"
    proc = granchain(["run", str(scene), "--backend", backend, "--out", str(out)], tmp_path)
    wait_until_running(proc, tmp_path / "tmp" if backend == "lammps" else None)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted; no run directory was written" in err
    assert "Traceback" not in err
    nothing_left(tmp_path, out)
    assert not list((tmp_path / "tmp").glob("granchain-lammps-*"))  # the work directory went too
    # a rerun to the same place starts cleanly
    scene.write_text(SHORT)
    rerun = granchain(["run", str(scene), "--backend", backend, "--out", str(out)], tmp_path)
    _, err = rerun.communicate(timeout=300)
    assert rerun.returncode == 0, err
    assert (out / "summary.json").exists()


def test_killed_mid_run_then_rerun(tmp_path):
    scene = tmp_path / "long.toml"
    scene.write_text(make_scene_text(beads=3000, end_time=2e-2, timestep=5e-8))
    out = tmp_path / "out"
    proc = granchain(["run", str(scene), "--backend", "lammps", "--out", str(out)], tmp_path)
    wait_until_running(proc, tmp_path / "tmp")
    os.killpg(proc.pid, signal.SIGKILL)  # no handler runs: whatever it had is left as it was
    proc.communicate(timeout=60)
    assert not out.exists()  # the run directory appears only complete, by a rename at the end
    left = list((tmp_path / "tmp").glob("granchain-lammps-*"))
    # a killed writer's hidden partial directory, as a kill during the final write would leave it
    stale = tmp_path / f".out.partial-{safe_files.host_tag()}-{proc.pid}-abcd"  # its lock went with its process
    stale.mkdir()
    (stale / "peaks.csv").write_text("half")
    scene.write_text(SHORT)
    rerun = granchain(["run", str(scene), "--backend", "lammps", "--out", str(out)], tmp_path)
    _, err = rerun.communicate(timeout=300)
    assert rerun.returncode == 0, err
    assert (out / "summary.json").exists()
    assert not stale.exists()  # swept: its process is gone
    assert left
    assert not any(p.exists() for p in left)


def _small_file_limit():
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG instead
    resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))


def test_full_disk_while_writing_the_run_directory(tmp_path):
    # no file may grow past 20 kB: histories.csv cannot be written (as on a full disk)
    scene = tmp_path / "s.toml"
    scene.write_text(SHORT)
    out = tmp_path / "out"
    proc = granchain(["run", str(scene), "--out", str(out)], tmp_path, preexec_fn=_small_file_limit)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2, err
    assert "could not write the run directory" in err
    assert "nothing was left behind" in err
    assert "Traceback" not in err
    nothing_left(tmp_path, out)
    rerun = granchain(["run", str(scene), "--out", str(out)], tmp_path)
    assert rerun.wait(timeout=120) == 0
    assert (out / "summary.json").exists()


def test_plugin_build_failure_is_clear_and_leaves_nothing(tmp_path, monkeypatch):
    fake = tmp_path / "bin" / "g++"
    fake.parent.mkdir()
    fake.write_text("#!/bin/sh\necho 'pair_chain.cpp:1: error: simulated compiler failure' >&2\nexit 1\n")
    fake.chmod(0o755)
    monkeypatch.setenv("CXX", str(fake))
    monkeypatch.setenv("GRANCHAIN_CACHE", str(tmp_path / "cache"))
    with pytest.raises(build.PluginError, match="building the granchain LAMMPS plugin failed(.|\n)*simulated"):
        build.build_plugin()
    leftovers = [p for p in (tmp_path / "cache").rglob("*") if p.is_file()]
    assert leftovers == []  # no half-built plugin, no sources: the next build starts from scratch
    # and the command line says it in one message, before any run
    from granchain.cli import main

    s = tmp_path / "s.toml"
    s.write_text(SHORT)
    assert main(["run", str(s), "--backend", "lammps", "--out", str(tmp_path / "o")]) == 2
    assert not (tmp_path / "o").exists()


def test_compare_says_a_plugin_build_failure_before_the_reference_runs(tmp_path, monkeypatch):
    """compare runs the reference first (its RK4 companions are shared with LAMMPS's): a broken
    plugin build must still fail before any run, with nothing written."""
    import granchain.workflows.run as run_mod
    from granchain.cli import main

    fake = tmp_path / "bin" / "g++"
    fake.parent.mkdir()
    fake.write_text("#!/bin/sh\necho 'pair_chain.cpp:1: error: simulated compiler failure' >&2\nexit 1\n")
    fake.chmod(0o755)
    monkeypatch.setenv("CXX", str(fake))
    monkeypatch.setenv("GRANCHAIN_CACHE", str(tmp_path / "cache"))
    ran = []
    real = run_mod.run_scene
    monkeypatch.setattr(run_mod, "run_scene", lambda *a, **k: ran.append(k.get("backend")) or real(*a, **k))
    import granchain.workflows.compare_backends as compare_mod

    monkeypatch.setattr(compare_mod, "run_scene", run_mod.run_scene)
    s = tmp_path / "s.toml"
    s.write_text(SHORT)
    assert main(["compare", str(s), "--out", str(tmp_path / "o")]) == 2
    assert ran == [], "no backend ran before the build failure was said"
    assert not (tmp_path / "o").exists()
