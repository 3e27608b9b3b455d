"""A LAMMPS instance kept across runs (issue 18 item 4; granchain.lammps.server, worker --serve).

Real LAMMPS runs, no mocks: a kept instance gives the files a fresh process gives, to the bit, for
scenes of every law and effect run one after another on the same child; a crash, a LAMMPS error or a
deck that exits LAMMPS fails its run only and the next run gets a new child; Ctrl-C leaves no work
directory and no child; the parent process never imports lammps.
"""

import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.lammps import server
from granchain.lammps.runner import LammpsError, cleanup, run_deck
from granchain.scene import parse_scene
from granchain.templates import render_deck

from .conftest import make_scene, make_scene_text
from .scenegen import scenes

#: files of a work directory that hold no result: the worker's report and stderr (times, instance)
NOT_RESULTS = {"worker.json", "worker.err", "log.lammps"}
#: lines of log.lammps that hold measured times (the rest of the log is the same to the byte)
TIMING = re.compile(
    r"^(Loop time of|Performance:|Total wall time:|\S+% CPU use|\w+\s+\|)|CPU = \S+ seconds|^\s*\d+(\.\d+)?% "
)


def log_without_times(path: Path) -> list[str]:
    return [line for line in path.read_text().splitlines() if not TIMING.search(line)]


def outputs(work: Path) -> dict[str, bytes]:
    """Every file a deck wrote (its results, dumps, energy samples, progress), by name, as bytes."""
    return {p.name: p.read_bytes() for p in sorted(work.iterdir()) if p.name not in NOT_RESULTS}


def run(scene, tmp: Path, name: str):
    """(worker report, its files, log.lammps without times) or the LammpsError's LAMMPS message."""
    d = render_deck(scene)
    work = tmp / name
    try:
        info, _ = run_deck(d.deck, d.data, work_dir=work, total_steps=d.total_steps)
    except LammpsError as e:
        return None, e.lammps_message, None
    return info, outputs(work), log_without_times(work / "log.lammps")


def same_as_fresh(scenes_: list, tmp: Path) -> list[dict]:
    """Run the scenes one after another on one kept instance, then each in a fresh process: the same
    files to the bit (and the same log but for the times), or the same LAMMPS error."""
    served = []
    with server.persistent():
        for k, sc in enumerate(scenes_):
            served.append(run(sc, tmp, f"served-{k}"))
    for k, sc in enumerate(scenes_):
        info, files, log = run(sc, tmp, f"fresh-{k}")
        s_info, s_files, s_log = served[k]
        assert (info is None) == (s_info is None), (k, files if info is None else s_files)
        assert s_files == files, (k, sc.source)
        assert s_log == log, k
    return [info for info, _, _ in served]


EFFECTS = {
    "hertz, wall, histories and a snapshot": make_scene_text(
        beads=24, law="hertz", end_time=6e-5, timestep=5e-8, outputs="histories = [1, 5]\nsnapshots = [3e-5]"
    )
    + '[boundary]\nfar_end = "wall"\n',
    "bilinear, striker": make_scene_text(
        beads=12, law="bilinear", end_time=5e-5, timestep=5e-8, loading='kind = "striker"\nvelocity = 1.0\nmass = 0.01'
    ),
    "thornton, dashpot": make_scene_text(beads=30, law="thornton", end_time=5e-5, timestep=5e-8)
    + "[damping]\ndashpot = 5.0\n",
    "hertz, precompression, step load": make_scene_text(
        beads=16,
        law="hertz",
        end_time=4e-5,
        timestep=5e-8,
        loading='kind = "step"\namplitude = 20.0\nduration = 1e-5',
        outputs="histories = [2]",
    )
    + "[precompression]\nforce = 5.0\n",
    "bilinear, 50 beads, wall": make_scene_text(beads=50, law="bilinear", end_time=3e-5, timestep=5e-8)
    + '[boundary]\nfar_end = "wall"\n',
}


def test_kept_instance_equals_fresh_process_for_every_law_and_effect(tmp_path):
    sc = [parse_scene(text, source=name) for name, text in EFFECTS.items()]
    infos = same_as_fresh(sc + sc[:2], tmp_path)  # and the first two again, after the others
    # one child ran all of them (a kept instance, not a fresh process each time)
    assert [i["instance_runs"] for i in infos] == list(range(1, len(infos) + 1))


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(scenes_=st.lists(scenes(max_beads=24, auto=False), min_size=2, max_size=3))
def test_kept_instance_equals_fresh_process_property(scenes_, tmp_path_factory):
    """Any valid scenes (every law, loading kind and effect scenegen draws; 1e-4 s at dt = 1e-8 s),
    run one after another on one kept instance: each as in a fresh process, to the bit (a scene
    the run watch stops fails alike, and the next one runs on a new child)."""
    same_as_fresh(scenes_, tmp_path_factory.mktemp("run"))


def poisoned_deck(deck: str) -> str:
    """A deck leaving settings a fresh instance would not have: other units, newton off, a soft halt
    that ended its run, another neighbour setting, and every variable name of `deck` defined as an
    index-style variable (`clear` keeps variables; the next deck's definitions would be refused)."""
    names = sorted(set(re.findall(r"(?m)^variable\s+(\w+)", deck)))
    assert names
    return "".join(f"variable {n} index 7\n" for n in names) + textwrap.dedent("""
        units lj
        newton off
        variable hs equal step
        atom_style atomic
        region box block 0 1 0 1 0 1
        create_box 1 box
        create_atoms 1 single 0.5 0.5 0.5
        mass 1 1.0
        pair_style zero 1.0
        pair_coeff * *
        neighbor 0.5 bin
        fix 1 all nve
        fix h all halt 5 v_hs > 3 error soft
        run 100
        run 10
        """)


def test_a_used_instance_is_cleared_for_the_next_deck(tmp_path):
    """What the deck before left (variables, which `clear` keeps; units, newton, a halted run) does not
    reach the next deck."""
    sc = parse_scene(EFFECTS["thornton, dashpot"], source="t")
    d = render_deck(sc)
    with server.persistent():
        info, _ = run_deck(poisoned_deck(d.deck), d.data, work_dir=tmp_path / "poison")
        assert info["instance_runs"] == 1
        info, _ = run_deck(d.deck, d.data, work_dir=tmp_path / "served")
        assert info["instance_runs"] == 2
    run_deck(d.deck, d.data, work_dir=tmp_path / "fresh")
    assert outputs(tmp_path / "served") == outputs(tmp_path / "fresh")
    assert log_without_times(tmp_path / "served" / "log.lammps") == log_without_times(tmp_path / "fresh" / "log.lammps")


SMALL = make_scene(beads=10, end_time=2e-5, timestep=5e-8)


def failing_decks(deck: str) -> dict[str, str]:
    before_run = deck.index("\nrun ")
    return {
        # the run watch's way of stopping a run: fix halt ... error hard
        "halt": deck[:before_run]
        + "\nvariable hs equal step\nfix myhalt all halt 10 v_hs > 50 error hard message yes"
        + deck[before_run:],
        "unknown command": deck[:before_run] + "\nbogus_command 1 2" + deck[before_run:],
        "exit": deck[:before_run] + "\nquit 3" + deck[before_run:],  # LAMMPS ends the process
    }


@pytest.mark.parametrize("kind", ["halt", "unknown command", "exit"])
def test_a_failing_deck_fails_alone_and_the_next_runs_on_a_new_child(kind, tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    d = render_deck(SMALL)
    with server.persistent():
        info, work = run_deck(d.deck, d.data)
        first = server.children()
        cleanup(work)
        with pytest.raises(LammpsError) as e:
            run_deck(failing_decks(d.deck)[kind], d.data)
        assert {"halt": "Fix halt condition", "unknown command": "Unknown command: bogus_command", "exit": "exit 3"}[
            kind
        ] in str(e.value)
        assert server.children() == []  # that child is gone
        info, work = run_deck(d.deck, d.data)
        assert info["instance_runs"] == 1
        assert server.children() != first
        served = outputs(work)
    assert not list(tmp_path.glob("granchain-lammps-*"))[1:]  # the failed run's work directory is gone
    _, fresh = run_deck(d.deck, d.data, work_dir=tmp_path / "fresh")
    assert served == outputs(fresh)


def test_a_child_killed_mid_run_fails_that_run_only(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    long = render_deck(make_scene(beads=3000, end_time=2e-2, timestep=5e-8))
    d = render_deck(SMALL)
    failure: list[BaseException] = []

    def long_run():
        try:
            run_deck(long.deck, long.data)
        except BaseException as e:  # noqa: BLE001 - looked at below
            failure.append(e)

    with server.persistent():
        info, work = run_deck(d.deck, d.data)
        cleanup(work)
        (child,) = server.children()
        t = threading.Thread(target=long_run)
        t.start()
        deadline = time.time() + 120
        while time.time() < deadline:  # until the long deck has made steps on the same child
            progress = list(tmp_path.glob("granchain-lammps-*/progress.txt"))
            if progress and len(progress[0].read_text().splitlines()) > 1:
                break
            time.sleep(0.05)
        assert server.children() == [child]
        os.kill(child, signal.SIGKILL)
        t.join(60)
        assert not t.is_alive()
        assert isinstance(failure[0], LammpsError)
        assert "LAMMPS failed (exit -9)" in str(failure[0])
        assert not list(tmp_path.glob("granchain-lammps-*"))  # its work directory is gone
        info, work = run_deck(d.deck, d.data)
        assert info["instance_runs"] == 1
        assert server.children() not in ([], [child])
        served = outputs(work)
    _, fresh = run_deck(d.deck, d.data, work_dir=tmp_path / "fresh")
    assert served == outputs(fresh)


def test_a_child_killed_while_idle_is_replaced_without_failing_the_run(tmp_path):
    d = render_deck(SMALL)
    with server.persistent():
        run_deck(d.deck, d.data, work_dir=tmp_path / "a")
        (child,) = server.children()
        os.kill(child, signal.SIGKILL)
        time.sleep(0.2)  # not a timing assertion: the run below must not fail whenever it notices
        info, _ = run_deck(d.deck, d.data, work_dir=tmp_path / "b")
        assert info["instance_runs"] == 1
        assert server.children() != [child]
    assert server.children() == []  # persistent() ended it


#: a parent that runs decks on a kept instance (argv: scene file, number of runs); what it saw, as JSON
PARENT = """
import json, sys
from granchain.lammps import server
from granchain.lammps.runner import run_deck, cleanup
from granchain.scene import parse_scene
from granchain.templates import render_deck

d = render_deck(parse_scene(open(sys.argv[1]).read(), source=sys.argv[1]))
server.enable()
runs = []
try:
    for _ in range(int(sys.argv[2])):
        info, work = run_deck(d.deck, d.data)
        runs.append(info["instance_runs"])
        cleanup(work)
except KeyboardInterrupt:
    print(json.dumps({"interrupted": True, "children": server.children(), "lammps": "lammps" in sys.modules}))
    sys.exit(130)
print(json.dumps({"runs": runs, "children": server.children(), "lammps": "lammps" in sys.modules}))
"""


def parent(tmp_path, scene_text: str, runs: int) -> subprocess.Popen:
    def as_from_a_terminal():  # a test runner's worker (pytest-xdist) may ignore SIGINT, which a child inherits
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    (tmp_path / "scene.toml").write_text(scene_text)
    (tmp_path / "tmp").mkdir()
    return subprocess.Popen(
        [sys.executable, "-c", PARENT, str(tmp_path / "scene.toml"), str(runs)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "TMPDIR": str(tmp_path / "tmp"), "GRANCHAIN_QUIET": "1"},
        start_new_session=True,  # its own process group, as a terminal's foreground job
        preexec_fn=as_from_a_terminal,
    )


def test_the_parent_never_imports_lammps(tmp_path):
    p = parent(tmp_path, make_scene_text(beads=10, end_time=2e-5, timestep=5e-8), 3)
    out, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    seen = json.loads(out)
    assert seen["runs"] == [1, 2, 3]
    assert len(seen["children"]) == 1
    assert seen["lammps"] is False


def test_ctrl_c_mid_run_stops_the_kept_instance_and_leaves_nothing(tmp_path):
    p = parent(tmp_path, make_scene_text(beads=3000, end_time=2e-2, timestep=5e-8), 1)
    deadline = time.time() + 120
    while time.time() < deadline:
        assert p.poll() is None, p.communicate()
        progress = list((tmp_path / "tmp").glob("granchain-lammps-*/progress.txt"))
        if progress and len(progress[0].read_text().splitlines()) > 1:
            break
        time.sleep(0.05)
    ps = subprocess.run(["ps", "-o", "pid=", "-g", str(p.pid)], capture_output=True, text=True).stdout
    group = [int(x) for x in ps.split() if int(x) != p.pid]
    assert group  # the served child
    os.killpg(p.pid, signal.SIGINT)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    seen = json.loads(out)
    assert seen == {"interrupted": True, "children": [], "lammps": False}
    assert not list((tmp_path / "tmp").glob("granchain-lammps-*"))  # no work directory left
    for pid in group:  # the child is gone (not left running on its own)
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)


CAMPAIGN = """
[campaign]
backend = "lammps"
error_estimate = false
[vary]
"loading.amplitude" = [10.0, 1e8, 20.0, 30.0, 40.0]
[scene]
[scene.chain]
beads = 10
radius = 4.76e-3
material = "brass"
[scene.contact]
law = "hertz"
[scene.loading]
kind = "step"
amplitude = 10.0
duration = 1e-6
[scene.run]
end_time = 2e-5
timestep = 5e-8
[scene.outputs]
peak_force = true
histories = [3]
"""


def test_a_campaign_worker_keeps_its_lammps_child(tmp_path, monkeypatch):
    """Five points on one worker, one of them crushing the chain (LAMMPS stops it): that point fails,
    the others run on kept instances, and every run directory's
    peaks.csv and histories.csv are those of a campaign with a fresh process per point."""
    from granchain.campaigns import execute
    from granchain.campaigns.run import run_campaign
    from granchain.campaigns.spec import parse_campaign

    c = parse_campaign(CAMPAIGN, source="reuse.toml")
    _, report = run_campaign(c, tmp_path / "kept", workers=1)
    assert (report.done, report.failed) == (4, 1)
    assert report.messages[0][0] == {"loading.amplitude": 1e8}  # LAMMPS stopped it (an error or the run watch)
    runs = []
    for d in sorted((tmp_path / "kept" / "workspace").iterdir()):
        if (d / "run").is_dir():
            runs.append(json.loads((d / "run" / "summary.json").read_text())["extra"]["instance_run"])
    assert max(runs) >= 2  # later points ran on a kept instance
    monkeypatch.setattr(execute.Executor, "reuse_lammps", False)
    _, report = run_campaign(c, tmp_path / "fresh", workers=1)
    assert (report.done, report.failed) == (4, 1)
    for d in sorted((tmp_path / "fresh" / "workspace").iterdir()):
        kept = tmp_path / "kept" / "workspace" / d.name
        if (d / "run").is_dir():
            assert json.loads((d / "run" / "summary.json").read_text())["extra"]["instance_run"] == 1
            for name in ("peaks.csv", "histories.csv"):
                assert (kept / "run" / name).read_bytes() == (d / "run" / name).read_bytes(), (d.name, name)
        else:
            assert not (kept / "run").exists()
