"""Resources guarded before anything runs: steps over the limit, more memory than this machine has
available, more disk than is free at the output are refused with the estimate and the way out; a
long run is announced. The command-line cases run in a subprocess under a timeout: without the
guards they ran (for years, or until the machine ran out of memory or disk)."""

from __future__ import annotations

import subprocess
import sys
import time
import warnings

import pytest

from granchain.scene import load_scene, parse_scene
from granchain.workflows import guards
from granchain.workflows import run as run_module
from granchain.workflows.guards import LongRunWarning, ResourceError, check_run, estimate
from granchain.workflows.run import run_scene


def scene_text(beads=100, end_time=7e-4, timestep=5e-8, outputs="peak_force = true\n") -> str:
    return (
        f'[chain]\nbeads = {beads}\nradius = 4.76e-3\nmaterial = "brass"\n[contact]\nlaw = "hertz"\n'
        '[loading]\nkind = "impulse"\nimpulse = 0.4\nduration = 1e-6\n'
        f"[run]\nend_time = {end_time!r}\ntimestep = {timestep!r}\n[outputs]\n{outputs}"
    )


def cli(tmp_path, text: str, *args: str, env=None, timeout: float = 60.0):
    """(exit code, stderr, seconds) of `granchain run` on the scene text in a subprocess."""
    import os

    path = tmp_path / "scene.toml"
    path.write_text(text)
    started = time.monotonic()
    r = subprocess.run(
        [sys.executable, "-m", "granchain", "run", str(path), "--out", str(tmp_path / "out"), "--quiet", *args],
        capture_output=True,
        text=True,
        timeout=timeout,  # a run that starts instead of being refused fails here
        env={**os.environ, **(env or {})},
        cwd=tmp_path,
    )
    return r.returncode, r.stderr, time.monotonic() - started


def refused(rc: int, err: str, tmp_path, *words: str) -> None:
    assert rc == 2, err
    assert "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.startswith("granchain: error:")]
    assert len(lines) == 1, err
    for word in words:
        assert word in lines[0], lines[0]
    assert not (tmp_path / "out").exists()


def test_a_femtosecond_time_step_is_refused_by_the_step_limit_with_the_fix(tmp_path):
    rc, err, seconds = cli(tmp_path, scene_text(timestep=1e-15))
    refused(rc, err, tmp_path, "7e+11 steps", "end_time", "timestep", "GRANCHAIN_MAX_STEPS")
    assert seconds < 30


def test_histories_that_need_more_memory_than_the_machine_has_are_refused(tmp_path):
    # 1e9 steps, a sample of 99 contacts every step: terabytes of histories held until written
    outputs = f"histories = {list(range(1, 100))}\nhistory_interval = 5e-8\n"
    rc, err, _ = cli(tmp_path, scene_text(end_time=50.0, outputs=outputs))
    refused(rc, err, tmp_path, "memory", "TB", "history_interval")


def test_a_dump_larger_than_the_free_disk_is_refused_before_lammps_starts(tmp_path):
    # 1.4e6 frames of 1e5 beads: about 32 TB of chain.dump
    text = scene_text(beads=100_000, end_time=7e-2, outputs="dump_interval = 5e-8\n")
    rc, err, _ = cli(tmp_path, text, "--backend", "lammps")
    refused(rc, err, tmp_path, "chain.dump", "free", "dump_interval")


def test_the_step_limit_is_stated_and_can_be_raised(tmp_path, monkeypatch):
    sc = parse_scene(scene_text(end_time=1e-4))  # 2000 steps
    monkeypatch.setenv("GRANCHAIN_MAX_STEPS", "1000")
    with pytest.raises(ResourceError, match="2e\\+03 steps.*limit of 1e\\+03"):
        run_scene(sc)
    monkeypatch.setenv("GRANCHAIN_MAX_STEPS", "3000")
    assert run_scene(sc).peak_table.size == 99
    monkeypatch.setenv("GRANCHAIN_MAX_STEPS", "lots")
    with pytest.raises(Exception, match="GRANCHAIN_MAX_STEPS = 'lots' is invalid"):
        run_scene(sc)


def _never_run(*args, **kwargs):
    raise AssertionError("a run started although the guards should have refused it")


def test_memory_and_disk_refusals_come_before_the_run(tmp_path, monkeypatch):
    sc = parse_scene(scene_text(end_time=1e-4))
    monkeypatch.setattr(run_module, "_execute", _never_run)
    monkeypatch.setattr(guards, "available_memory", lambda: 1e4)
    with pytest.raises(ResourceError, match="memory.*more than the 10 kB this machine has available"):
        run_scene(sc)
    monkeypatch.setattr(guards, "available_memory", lambda: 1e12)
    monkeypatch.setattr(guards, "free_disk", lambda path: 10.0)
    with pytest.raises(ResourceError, match="more than the 10 B free at"):
        run_scene(sc, out=tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_a_cluster_or_campaign_run_is_not_held_to_this_machine_memory(monkeypatch):
    sc = parse_scene(scene_text(end_time=1e-4))
    monkeypatch.setattr(guards, "available_memory", lambda: 1e4)
    run_module.check_resources(sc, "lammps", 1, oversubscribe=True)  # its cores, memory and disk are not ours
    with pytest.raises(ResourceError):
        run_module.check_resources(sc, "reference", 1)
    monkeypatch.setenv("GRANCHAIN_MAX_STEPS", "10")
    with pytest.raises(ResourceError, match="steps"):  # the step limit holds everywhere
        run_module.check_resources(sc, "lammps", 1, oversubscribe=True)


def test_a_long_run_is_announced(monkeypatch):
    sc = parse_scene(scene_text(beads=10_000, end_time=0.5, timestep=5e-8))  # 1e7 steps of 1e4 beads
    with pytest.warns(LongRunWarning, match="steps on 10000 beads: about .* (hours|days)"):
        est = check_run(sc)
    assert est.steps == pytest.approx(1e7)
    assert est.beads == 10_000


def test_estimates_grow_with_what_the_scene_asks_for():
    small = estimate(parse_scene(scene_text()))
    long = estimate(parse_scene(scene_text(end_time=7e-3)))
    wide = estimate(parse_scene(scene_text(beads=10_000)))
    kept = estimate(parse_scene(scene_text(outputs="histories = [1, 2, 3]\nhistory_interval = 5e-8\n")))
    assert long.steps == pytest.approx(10 * small.steps)
    assert long.seconds > small.seconds
    assert wide.memory > 50 * small.memory
    assert wide.disk > small.disk
    assert kept.memory > small.memory
    assert kept.disk > small.disk
    assert "histories.csv" in kept.files
    dumped = parse_scene(scene_text(outputs="dump_interval = 5e-7\n"))
    assert "chain.dump" in estimate(dumped, "lammps").files  # LAMMPS's own file, not the reference's
    assert "chain.dump" not in estimate(dumped, "reference").files


@pytest.mark.parametrize("name", ["default", "plastic-long-load-table1", "effect-striker", "classic-struck-taper"])
def test_bundled_scenes_pass_the_guards_without_a_warning(name):
    from granchain.workflows.run import plan_for

    sc, _ = plan_for(load_scene(name), "reference", None, None)
    with warnings.catch_warnings():
        warnings.simplefilter("error", LongRunWarning)
        est = check_run(sc)
    assert est.steps <= guards.MAX_STEPS


def test_a_dashpot_that_forces_a_tiny_planned_step_is_refused_naming_the_planner_not_timestep(tmp_path):
    text = scene_text(end_time=2e-4, timestep="auto") + "[damping]\ndashpot = 1e12\n"
    rc, err, _ = cli(tmp_path, text.replace("timestep = 'auto'", 'timestep = "auto"'))
    refused(rc, err, tmp_path, "steps", "planner's step", "dashpot")
    assert "[run] timestep =" not in err


def test_kuwabara_kono_damping_that_forces_a_tiny_planned_step_is_refused_naming_its_rate(tmp_path):
    """The refusal names the scene's damping part's rate (the part's noun), not a dashpot it lacks."""
    text = scene_text(end_time=2e-4, timestep="auto") + "[damping]\nkuwabara_kono = 1.0\n"
    rc, err, _ = cli(tmp_path, text.replace("timestep = 'auto'", 'timestep = "auto"'))
    refused(rc, err, tmp_path, "steps", "planner's step", "Kuwabara-Kono damping's rate")
    assert "dashpot" not in err
