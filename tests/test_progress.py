"""Progress of long runs: a tqdm bar on a terminal, plain lines otherwise, nothing when quiet;
LAMMPS's progress is LAMMPS's own step count. A failed LAMMPS run leaves no work directory."""

import io
import os
import subprocess
import sys
import tempfile
import types

import pytest

import granchain.progress as gp
from granchain.lammps import runner
from granchain.reference.solver import ChainProblem, InvariantError, solve_chain
from granchain.templates import render_deck
from granchain.workflows.run import run_scene

from .conftest import make_scene

PULSE = 'kind = "impulse"\nimpulse = 0.4\nduration = 1e-6'


@pytest.fixture
def shown(monkeypatch):
    """Show progress from the first step (a fake short threshold), and record every call: {desc: [(kind, n)]}."""
    monkeypatch.setattr(gp, "DELAY", 0.0)
    monkeypatch.delenv("GRANCHAIN_QUIET", raising=False)
    calls: dict[str, list[tuple[str, int]]] = {}
    update, finish = gp.Progress.update, gp.Progress.finish

    def rec_update(self, n):
        calls.setdefault(self.desc, []).append(("update", n))
        return update(self, n)

    def rec_finish(self, n):
        calls.setdefault(self.desc, []).append(("finish", n))
        return finish(self, n)

    monkeypatch.setattr(gp.Progress, "update", rec_update)
    monkeypatch.setattr(gp.Progress, "finish", rec_finish)
    return calls


class Terminal(io.StringIO):
    def isatty(self):
        return True


def _solve(method="verlet", **kw):
    sc = make_scene(beads=40, end_time=2e-4, timestep=1e-8)  # 20000 steps, well under a second
    return solve_chain(ChainProblem.from_scene(sc), sc.run.end_time, sc.run.timestep, method, **kw)


@pytest.mark.parametrize("method", ["verlet", "rk4"])
def test_reference_reports_increasing_steps_ending_at_the_total(shown, capsys, method):
    sol = _solve(method)
    calls = shown[f"granchain: reference {method}"]
    steps = [n for _, n in calls]
    assert len(calls) > 3
    assert calls[-1] == ("finish", sol.steps)
    assert sol.steps == 20000
    assert all(a < b for a, b in zip(steps[:-2], steps[1:-1], strict=True))  # updates strictly increase
    assert steps[-2] <= steps[-1]
    err = capsys.readouterr().err
    # stderr is not a terminal here: plain lines, no carriage returns or bar, the last one complete
    lines = err.splitlines()
    assert lines
    assert "\r" not in err
    assert all(line.startswith(f"granchain: reference {method}: ") for line in lines)
    assert "100% (20000/20000 steps)" in lines[-1]
    assert "elapsed" in lines[-1]
    assert "left" in lines[-1]


def test_reference_stopped_early_ends_complete_at_its_last_step(shown, capsys):
    sc = make_scene(beads=40, end_time=5e-4, timestep=1e-8)
    sol = solve_chain(ChainProblem.from_scene(sc), 5e-4, 1e-8, "verlet", stop_after=10)
    assert sol.steps < 50000
    assert shown["granchain: reference verlet"][-1] == ("finish", sol.steps)
    assert f"100% ({sol.steps}/{sol.steps} steps)" in capsys.readouterr().err.splitlines()[-1]


def test_update_calls_are_spaced_out_in_time(shown):
    # the solver asks for the clock only every ~CHECK_EVERY seconds of steps, not every step
    sol = _solve()
    n_updates = sum(kind == "update" for kind, _ in shown["granchain: reference verlet"])
    assert n_updates <= max(10, 3 * sol.wall_time / gp.CHECK_EVERY + 10)
    assert n_updates < sol.steps / 100


def test_short_run_prints_nothing_by_default(capsys, monkeypatch):
    monkeypatch.delenv("GRANCHAIN_QUIET", raising=False)
    assert gp.DELAY >= 1.0
    # the progress module's clock advances 1 us a reading: the run ends within DELAY however loaded
    # the machine is (the rule tested is "a run that ends within DELAY prints nothing", not a speed)
    ticks = iter(range(10**9))
    clock = types.SimpleNamespace(perf_counter=lambda: next(ticks) * 1e-6, time=lambda: next(ticks) * 1e-6)
    monkeypatch.setattr(gp, "time", clock)
    _solve()
    assert capsys.readouterr().err == ""


def test_quiet_prints_nothing(shown, capsys, monkeypatch):
    with gp.quiet():
        assert gp.is_quiet()
        _solve()
        runner.sweep_stale_work_dirs()
    assert not gp.is_quiet()
    with gp.quiet(False):
        assert not gp.is_quiet()
    monkeypatch.setenv("GRANCHAIN_QUIET", "1")
    _solve()
    p = gp.Progress(100, "x", stream=Terminal())
    p.start()
    p.update(50)
    p.finish(100)
    assert p.stream.getvalue() == ""
    assert capsys.readouterr().err == ""


def test_terminal_gets_a_tqdm_bar(monkeypatch):
    monkeypatch.setattr(gp, "DELAY", 0.0)
    monkeypatch.delenv("GRANCHAIN_QUIET", raising=False)
    term = Terminal()
    with gp.Progress(1000, "demo", stream=term) as p:
        p.start()
        for n in range(100, 1001, 100):
            p.update(n)
        p.finish(1000)
    out = term.getvalue()
    assert out.startswith("\rgranchain: demo:")
    assert out.endswith("\n")
    last = out.rstrip("\n").split("\r")[-1]
    assert "100%|" in last
    assert "1000/1000 steps" in last
    assert "step/s" in last
    assert p._bar is None  # closed


def test_plain_lines_every_few_seconds(monkeypatch):
    monkeypatch.setattr(gp, "DELAY", 0.0)
    monkeypatch.setattr(gp, "LINE_EVERY", 3600.0)
    monkeypatch.delenv("GRANCHAIN_QUIET", raising=False)
    out = io.StringIO()
    p = gp.Progress(1000, "demo", stream=out)
    for n in range(100, 1001, 100):
        p.update(n)
    p.finish(1000)
    lines = out.getvalue().splitlines()
    assert len(lines) == 2  # the first, then none within LINE_EVERY, then the last
    assert lines[0].startswith("granchain: demo:  10% (100/1000 steps)")
    assert lines[1].startswith("granchain: demo: 100% (1000/1000 steps)")


def test_a_run_that_raises_closes_its_bar(monkeypatch):
    monkeypatch.setattr(gp, "DELAY", 0.0)
    monkeypatch.delenv("GRANCHAIN_QUIET", raising=False)
    term = Terminal()

    def interrupted():
        with gp.Progress(1000, "demo", stream=term) as p:
            p.update(300)
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        interrupted()
    assert term.getvalue().endswith("\n")
    assert "300/1000" in term.getvalue()


# ---- LAMMPS: the step count is LAMMPS's own


def test_lammps_progress_is_lammps_step_count(shown, monkeypatch, tmp_path):
    # 80000 steps take 0.3 s on a 2-core runner (LAMMPS at ~270k steps/s): looking every 5 ms sees
    # about 12 of its 40 progress lines, where every 50 ms saw 1 or 2 (CI of 6b369ef failed on 1)
    monkeypatch.setattr(runner, "POLL_INTERVAL", 0.005)
    sc = make_scene(beads=200, end_time=8e-4, timestep=1e-8)  # 80000 steps
    deck = render_deck(sc)
    stride = int(deck.deck.split("fix             progress all print ")[1].split()[0])
    assert stride == 2000  # 400000 bead-steps apart
    res, work = runner.run_lammps(sc, work_dir=tmp_path / "w")
    text = (work / "progress.txt").read_text().splitlines()
    assert text[0] == "# step"
    written = [int(float(x)) for x in text[1:]]
    assert written == list(range(0, deck.total_steps + 1, stride))  # LAMMPS wrote them, from its setup on
    calls = shown["granchain: LAMMPS"]
    updates = [n for kind, n in calls if kind == "update"]
    assert calls[-1] == ("finish", res.solution.steps)
    assert res.solution.steps == deck.total_steps == 80000
    assert updates == sorted(updates)
    seen = {n for n in updates if n}
    assert len(seen) >= 2, seen
    assert seen <= set(written)


def test_deck_steps_adds_up_the_runs():
    sc = make_scene(beads=30, end_time=1e-4, timestep=1e-8, outputs="snapshots = [3e-5]")
    deck = render_deck(sc)
    assert runner.deck_steps(deck.deck) == deck.total_steps


# ---- a failed LAMMPS run leaves no work directory


@pytest.fixture
def own_tmp(monkeypatch, tmp_path):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    return tmp_path


def test_lammps_run_that_breaks_an_invariant_leaves_no_work_directory(own_tmp):
    sc = make_scene(beads=100, loading=PULSE, end_time=7e-4, timestep=6e-6)  # energy created: a halted run
    with pytest.raises(InvariantError, match="energy balance"):
        run_scene(sc, backend="lammps", method="verlet", force=True)
    assert not list(own_tmp.glob(f"{runner.WORK_PREFIX}*"))


def test_lammps_error_leaves_no_work_directory_and_keeps_the_log(own_tmp):
    deck = render_deck(make_scene())
    bad = deck.deck.replace("pair_coeff      1 1 ", "pair_coeff      1 1 -")
    with pytest.raises(runner.LammpsError) as e:
        runner.run_deck(bad, deck.data)
    assert not list(own_tmp.glob(f"{runner.WORK_PREFIX}*"))
    msg = str(e.value)
    assert "k must be > 0" in msg
    assert str(own_tmp) not in msg
    assert "last lines of log.lammps" in msg
    assert e.value.deck_line.startswith("pair_coeff")


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_stale_work_directories_are_named_when_they_cannot_be_removed(own_tmp, monkeypatch):
    from granchain import safe_files

    tag = safe_files.host_tag()
    stale = own_tmp / f"{runner.WORK_PREFIX}{_dead_pid()}-{tag}-abcd"  # as a killed run leaves it: unlocked
    stale.mkdir()
    (stale / "log.lammps").write_text("x" * 2000)
    live = own_tmp / f"{runner.WORK_PREFIX}{os.getpid()}-{tag}-efgh"
    live.mkdir()
    held = safe_files.hold_lock(live)  # as a running run holds its work directory (runner.new_work_dir)
    for d in (stale, live, stale / "log.lammps"):  # both old: the lock alone tells them apart
        os.utime(d, (1e9, 1e9))
    text = runner.work_dirs_report()
    assert str(stale) in text
    assert "left by killed runs" in text
    assert str(live) in text
    assert "in use" in text
    monkeypatch.setattr(runner.shutil, "rmtree", lambda *a, **k: None)  # as for another user's directory
    with pytest.warns(runner.StaleWorkDirWarning, match="could not be removed") as w:
        assert runner.sweep_stale_work_dirs() == [stale]
    assert str(stale) in str(w[0].message)
    assert str(live) not in str(w[0].message)
    monkeypatch.undo()
    monkeypatch.setattr(tempfile, "tempdir", str(own_tmp))
    assert runner.sweep_stale_work_dirs() == []
    assert not stale.exists()
    assert live.exists()
    text = runner.work_dirs_report()
    assert "left by killed runs" not in text
    assert "in use" in text
    os.close(held)


def test_a_labelled_run_says_what_it_is_for():
    from granchain.progress import Progress, labelled

    with labelled("error-bar companion at 2 dt"):
        inner = Progress(10, "reference rk4", stream=None)
    after = Progress(10, "reference rk4", stream=None)
    assert inner.desc == "granchain: error-bar companion at 2 dt: reference rk4"
    assert after.desc == "granchain: reference rk4"  # the label ends with its block
