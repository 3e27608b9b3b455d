"""granchain compare's schedule on two cores (issue 18 item 5): LAMMPS runs in a thread of the main
process alongside the reference (at once, or after the reference's own run while a worker process
makes the RK4 companions), and the result is what one run after the other writes (one core): the
same files, the same errors, the same refusals before any run."""

import json
import os
import threading
import time
from concurrent.futures import Future
from dataclasses import replace
from pathlib import Path

import pytest

import granchain.lammps.runner as runner
import granchain.workflows.compare_backends as compare_mod
import granchain.workflows.run as run_mod
from granchain.backends import REFERENCE, backend_named
from granchain.cli import main
from granchain.lammps.runner import LammpsError, work_dirs
from granchain.scene import parse_scene
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import UnstableTimestepError, plan_for, shared_reference_runs
from granchain.workflows.shared_runs import Abandoned, SharedRuns

from .test_error_estimate import BILINEAR_CHAIN as ERROR_ESTIMATE_CHAIN

#: test_error_estimate's invented bilinear chain, with histories and a snapshot written
BILINEAR_CHAIN = ERROR_ESTIMATE_CHAIN + "histories = [1, 12]\nsnapshots = [1e-5]\n"

#: summary.json's keys that hold times, prices and provenance: they differ from run to run
VARYING = {"wall_time", "extra", "price", "provenance"}
VARYING_ERRORS = {"companion_wall_time", "overhead"}


def scene_file(tmp_path: Path, factor: float = 1.0) -> tuple[Path, float]:
    """The bilinear chain with a fixed step (factor times LAMMPS's planned one): with checked bars
    LAMMPS's RK4 companions are then the reference's own (errors.against_rk4_because), shared."""
    sc, _ = plan_for(parse_scene(BILINEAR_CHAIN, source="b.toml"), "lammps", None, 1e-3)
    dt = sc.run.timestep * factor
    p = tmp_path / "b.toml"
    text = BILINEAR_CHAIN.replace('timestep = "auto"', f"timestep = {dt!r}")
    p.write_text(text.replace('end_time = "auto"', f"end_time = {sc.run.end_time!r}"))
    return p, dt


def compare(p: Path, out: Path, estimate: str = "on") -> int:
    return main(["compare", str(p), "--out", str(out), "--error-estimate", estimate, "--quiet"])


def contents(d: Path) -> dict:
    """Every file of a compare directory, summary.json without its times, prices and provenance."""
    got = {}
    for f in sorted(d.rglob("*")):
        if not f.is_file() or f.name == "log.lammps":  # (LAMMPS's log has its own timings)
            continue
        if f.name == "summary.json":
            s = {k: v for k, v in json.loads(f.read_text()).items() if k not in VARYING}
            if s.get("errors"):
                s["errors"] = {k: v for k, v in s["errors"].items() if k not in VARYING_ERRORS}
            got[str(f.relative_to(d))] = s
        else:
            got[str(f.relative_to(d))] = f.read_bytes()
    return got


#: this process's LAMMPS work directories when the current test started: pytest-xdist runs many tests in
#: one process, and some (e.g. those that call run_lammps and drop the work directory it returns) leave
#: theirs behind; the checks here count only the directories made during their own test
_before: set = set()


@pytest.fixture(autouse=True)
def _work_dirs_before():
    global _before
    _before = {d for d, pid, _ in work_dirs() if pid == os.getpid()}


def own_work_dirs() -> list:
    return [d for d, pid, _ in work_dirs() if pid == os.getpid() and d not in _before]


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    """(scene file, its step, the compare directories one core writes (one run after the other) with
    the error estimate on and off); the decks name the scene file, so the tests compare its runs."""
    tmp = tmp_path_factory.mktemp("serial")
    p, dt = scene_file(tmp)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(run_mod, "available_cores", lambda: 1)
        for estimate in ("on", "off"):
            assert compare(p, tmp / estimate, estimate) == 0
    return p, dt, {e: contents(tmp / e) for e in ("on", "off")}


@pytest.mark.parametrize("estimate", ["on", "off"])
def test_two_cores_write_what_one_core_writes(serial, tmp_path, monkeypatch, estimate):
    """LAMMPS runs in a thread alongside the reference: at once without companions (the second core
    is free), after the reference's own run with them (a worker makes them on the second core); the
    same files as one run after the other."""
    p, dt, serial = serial
    events, threads = [], []
    lammps_started = threading.Event()
    real_lammps, real_reference = runner.run_lammps, run_mod.run_reference
    real_run, real_calculate = compare_mod.run_scene, compare_mod.calculate_scene

    def lammps(scene, *a, **k):
        events.append("lammps")
        lammps_started.set()
        return real_lammps(scene, *a, **k)

    def reference(scene, method="rk4"):
        if scene.run.timestep == dt:
            events.append("reference")
            if estimate == "off":  # LAMMPS runs alongside: it starts while the reference runs
                assert lammps_started.wait(60), "LAMMPS did not start while the reference ran"
        got = real_reference(scene, method)
        events.append(f"reference at {scene.run.timestep / dt:g} dt done")
        return got

    def run_scene(scene, **kw):
        threads.append((backend_named(kw["backend"]).name, threading.current_thread() is threading.main_thread()))
        return real_run(scene, **kw)

    def calculate_scene(scene, **kw):
        threads.append((backend_named(kw["backend"]).name, threading.current_thread() is threading.main_thread()))
        return real_calculate(scene, **kw)

    monkeypatch.setattr(runner, "run_lammps", lammps)
    monkeypatch.setattr(run_mod, "run_reference", reference)
    monkeypatch.setattr(compare_mod, "run_scene", run_scene)
    monkeypatch.setattr(compare_mod, "calculate_scene", calculate_scene)
    monkeypatch.setattr(run_mod, "available_cores", lambda: 2)
    assert compare(p, tmp_path / "c", estimate) == 0
    assert sorted(threads) == [("lammps", False), ("reference", True)]
    if estimate == "on":  # the companions were made by the worker (its runs are counted there)
        # (the reference's RK4 companions made by the worker; LAMMPS's own run, then its companions at 2 dt
        # and 4 dt: bounds on this bilinear chain, errors.bounded_because)
        assert events == ["reference", "reference at 1 dt done", "lammps", "lammps", "lammps"]
    else:
        assert events.index("lammps") < events.index("reference at 1 dt done")
    got = contents(tmp_path / "c")
    assert got.keys() == serial[estimate].keys()
    for name in got:
        assert got[name] == serial[estimate][name], name
    assert own_work_dirs() == []


def test_one_core_runs_one_after_the_other(tmp_path, monkeypatch):
    p, _ = scene_file(tmp_path)
    threads = []
    real_run, real_calculate = compare_mod.run_scene, compare_mod.calculate_scene

    def run_scene(scene, **kw):
        threads.append((backend_named(kw["backend"]).name, threading.current_thread() is threading.main_thread()))
        return real_run(scene, **kw)

    def calculate_scene(scene, **kw):
        threads.append((backend_named(kw["backend"]).name, threading.current_thread() is threading.main_thread()))
        return real_calculate(scene, **kw)

    monkeypatch.setattr(compare_mod, "run_scene", run_scene)
    monkeypatch.setattr(compare_mod, "calculate_scene", calculate_scene)
    monkeypatch.setattr(run_mod, "available_cores", lambda: 1)
    assert compare(p, tmp_path / "c", "off") == 0
    assert threads == [("reference", True), ("lammps", True)]


def _fails_in_worker(scene, method):
    return None  # as _prefetched_run when the run raised there


def _worker_dies(scene, method):
    os._exit(3)


@pytest.mark.parametrize("worker", [_fails_in_worker, _worker_dies])
def test_companions_the_worker_did_not_make_are_made_here_once(serial, tmp_path, monkeypatch, worker):
    """A companion that failed in the worker, or whose worker died, is made in this process, once, with
    the same numbers. (With checked bars LAMMPS's thread asks for the reference's RK4 companions too:
    test_error_estimate.test_compare_makes_each_rk4_companion_once.)"""
    p, dt, serial = serial
    made = []
    real = run_mod.run_reference

    def counted(scene, method="rk4"):
        made.append(scene.run.timestep / dt)
        return real(scene, method)

    monkeypatch.setattr(run_mod, "run_reference", counted)
    monkeypatch.setattr(run_mod, "_prefetched_run", worker)
    monkeypatch.setattr(run_mod, "available_cores", lambda: 2)
    assert compare(p, tmp_path / "c") == 0
    # the reference's run and its companion at 2 dt (one on this bilinear chain, errors.one_companion_because;
    # LAMMPS's: its own runs, bounds, errors.bounded_because), each made once
    assert {1.0, 2.0} <= set(made)
    assert len(made) == len(set(made)), sorted(made)
    assert contents(tmp_path / "c") == serial["on"]


def said(err: str) -> str:
    """The error the command line said (after any warnings)."""
    return err[err.index("granchain: error:") :]


def error_of(p: Path, out: Path, monkeypatch, cores: int, estimate: str = "on", capsys=None) -> str:
    monkeypatch.setattr(run_mod, "available_cores", lambda: cores)
    capsys.readouterr()
    assert compare(p, out, estimate) == 2
    assert not out.exists()
    assert own_work_dirs() == []
    return capsys.readouterr().err


@pytest.mark.parametrize("estimate", ["on", "off"])
def test_a_failed_reference_run_raises_its_error_and_leaves_nothing(tmp_path, monkeypatch, capsys, estimate):
    """The reference's own run fails: its error, as one core says it; LAMMPS's run (started alongside,
    or not started) is given up and its work directory removed."""
    p, dt = scene_file(tmp_path)
    lammps_runs = []
    real_lammps, real_reference = runner.run_lammps, run_mod.run_reference

    def lammps(scene, *a, **k):
        lammps_runs.append(scene.run.timestep)
        return real_lammps(scene, *a, **k)

    def reference(scene, method="rk4"):
        got = real_reference(scene, method)
        if scene.run.timestep == dt:  # a broken invariant found at the end of the run
            raise run_mod.InvariantError("energy", 1e-5, 7, 3, "invented for the test", "no fix")
        return got

    monkeypatch.setattr(runner, "run_lammps", lammps)
    monkeypatch.setattr(run_mod, "run_reference", reference)
    one = error_of(p, tmp_path / "one", monkeypatch, 1, estimate, capsys)
    assert "invented for the test" in one
    assert lammps_runs == []
    two = error_of(p, tmp_path / "two", monkeypatch, 2, estimate, capsys)
    assert said(two) == said(one)
    # without companions LAMMPS started alongside and finished its run: its directory is gone
    assert lammps_runs == ([] if estimate == "on" else [dt])


@pytest.mark.parametrize("estimate", ["on", "off"])
def test_a_failed_lammps_run_raises_its_error_after_the_reference(tmp_path, monkeypatch, capsys, estimate):
    """LAMMPS fails (a real LAMMPS error: an unknown command in its deck): the same error on two cores
    as on one, said once the reference's run is done."""
    p, dt = scene_file(tmp_path)
    real_render = runner.render_deck
    done = []

    def broken(scene, *a, **k):
        d = real_render(scene, *a, **k)
        i = d.deck.index("\nrun ")
        return replace(d, deck=d.deck[:i] + "\nbogus_command 1 2" + d.deck[i:])

    real_reference = run_mod.run_reference

    def reference(scene, method="rk4"):
        got = real_reference(scene, method)
        done.append(scene.run.timestep / dt)
        return got

    monkeypatch.setattr(runner, "render_deck", broken)
    monkeypatch.setattr(run_mod, "run_reference", reference)
    one = error_of(p, tmp_path / "one", monkeypatch, 1, estimate, capsys)
    assert "bogus_command" in one
    assert done[0] == 1.0
    done.clear()
    two = error_of(p, tmp_path / "two", monkeypatch, 2, estimate, capsys)
    assert said(two).splitlines()[:2] == said(one).splitlines()[:2]
    assert done[0] == 1.0  # the reference's run was made first (its error would have been said)
    with pytest.raises(LammpsError):
        compare_mod.compare_scene(parse_scene(p.read_text(), source=str(p)), error_estimate=estimate == "on")


@pytest.mark.filterwarnings("ignore::granchain.workflows.run.AccuracyWarning")  # (the reference's coarse step)
def test_a_step_lammps_refuses_fails_before_any_run(tmp_path, monkeypatch, capsys):
    """A fixed step above Verlet's stability limit but below RK4's: LAMMPS's check refuses it. On two
    cores both runs' checks come before either run, so nothing runs (one core runs the reference
    first, as before); the same error."""
    sc = plan_for(parse_scene(BILINEAR_CHAIN, source="b.toml"), "lammps", None, 1e-3)[0]
    verlet, rk4 = (plan_scene(sc, method=m).stable_timestep for m in ("verlet", "rk4"))
    assert 1.2 * verlet < rk4
    p, _ = scene_file(tmp_path, factor=1.2 * verlet / sc.run.timestep)
    runs = []
    real_lammps, real_reference = runner.run_lammps, run_mod.run_reference
    monkeypatch.setattr(runner, "run_lammps", lambda *a, **k: runs.append("lammps") or real_lammps(*a, **k))
    monkeypatch.setattr(run_mod, "run_reference", lambda *a, **k: runs.append("reference") or real_reference(*a, **k))
    two = error_of(p, tmp_path / "two", monkeypatch, 2, "off", capsys)
    assert "above the stability limit" in said(two)
    assert runs == []
    with pytest.raises(UnstableTimestepError):
        compare_mod.compare_scene(parse_scene(p.read_text(), source=str(p)))
    assert runs == []
    one = error_of(p, tmp_path / "one", monkeypatch, 1, "off", capsys)
    assert said(one) == said(two)
    assert runs == ["reference"]


def test_shared_runs_are_made_once_across_threads_and_waits_give_up_when_abandoned(monkeypatch):
    sc = plan_for(parse_scene(BILINEAR_CHAIN, source="b.toml"), "reference", "rk4", 1e-3)[0]
    made = []
    started, release = threading.Event(), threading.Event()
    real = run_mod.run_reference

    def slow(scene, method="rk4"):
        made.append(threading.current_thread().name)
        started.set()
        release.wait(60)
        return real(scene, method)

    monkeypatch.setattr(run_mod, "run_reference", slow)
    got = {}

    def ask(name):
        got[name] = run_mod._execute(sc, REFERENCE, "rk4", 1).result

    with shared_reference_runs() as shared:
        a = threading.Thread(target=ask, args=("a",), name="a")
        a.start()
        assert started.wait(60)
        b = threading.Thread(target=ask, args=("b",), name="b")
        b.start()
        time.sleep(0.3)  # (b now waits for a's run)
        release.set()
        a.join(60)
        b.join(60)
    assert made == ["a"]  # b waited for a's run
    assert got["a"].solution is got["b"].solution
    assert got["a"] is not got["b"]

    shared = SharedRuns()
    never = Future()
    errors = []

    def wait():
        try:
            shared.wait(never)
        except Abandoned as e:
            errors.append(e)

    t = threading.Thread(target=wait)
    t.start()
    shared.abandon()
    t.join(10)
    assert not t.is_alive()
    assert len(errors) == 1
