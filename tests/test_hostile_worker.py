"""kill -9 of `granchain run --backend lammps` takes its LAMMPS worker with it: the worker must not
run to the end (parent 1), writing into a work directory nobody reads. Real runs of the CLI and LAMMPS,
one rank and two (under mpirun, whose proxies stand between granchain and the worker)."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .conftest import make_scene_text

#: a LAMMPS run of about a minute (20000 beads, 100000 steps): it is killed after a second
LONG = make_scene_text(beads=20000, end_time=5e-3, timestep=5e-8)


def workers_of(pid: int) -> list[int]:
    """The granchain.lammps.worker processes descended from pid (through mpirun and its proxies)."""
    parents, cmdlines = {}, {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as f:
                stat = f.read().decode("utf-8", "replace")
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                cmdlines[int(entry)] = f.read().replace(b"\0", b" ").decode("utf-8", "replace")
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()
        if fields[0] != "Z":
            parents[int(entry)] = int(fields[1])
        if not stat[stat.index("(") + 1 : stat.rindex(")")].startswith("python"):  # mpirun names it too
            cmdlines.pop(int(entry))
    found = []
    for p, cmd in cmdlines.items():
        if "granchain.lammps.worker" not in cmd or p not in parents:
            continue
        q, seen = p, 0
        while q in parents and q > 1 and seen < 10:
            q, seen = parents[q], seen + 1
            if q == pid:
                found.append(p)
                break
    return found


def every_worker_named_by(cmd_part: str) -> list[int]:
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/cmdline", "rb") as f:
                    if cmd_part.encode() in f.read():
                        with open(f"/proc/{entry}/stat", "rb") as g:
                            if g.read().decode().rsplit(")", 1)[1].split()[0] != "Z":
                                out.append(int(entry))
            except OSError:
                pass
    return out


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc to find the worker")
@pytest.mark.parametrize("np_", [1, 2], ids=["one rank", "mpirun -np 2"])
def test_kill_9_of_granchain_run_takes_the_lammps_worker_with_it(tmp_path, np_):
    scene = tmp_path / "long.toml"
    scene.write_text(LONG)
    cli = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "granchain.cli",
            "run",
            str(scene),
            "--backend",
            "lammps",
            "--np",
            str(np_),
            "--out",
            str(tmp_path / "out"),
            "--quiet",
        ],  # fmt: skip
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,  # its own group: only the kill below reaches it
        cwd=tmp_path,
    )
    workers: list[int] = []
    try:
        deadline = time.monotonic() + 120  # the plugin may be built first
        while time.monotonic() < deadline and len(workers) < np_:
            assert cli.poll() is None, cli.stderr.read().decode()[-3000:]
            workers = workers_of(cli.pid)
            time.sleep(0.1)
        assert len(workers) == np_, "no LAMMPS worker started"
        time.sleep(1.0)  # LAMMPS is running the deck now
        assert all(Path(f"/proc/{w}").exists() for w in workers)
        os.kill(cli.pid, signal.SIGKILL)
        t0 = time.monotonic()
        alive = workers
        while alive and time.monotonic() - t0 < 3.0:
            alive = [w for w in workers if w in every_worker_named_by("granchain.lammps.worker")]
            time.sleep(0.05)
        assert not alive, f"LAMMPS workers {alive} outlived kill -9 of granchain run by 3 s"
        assert not (tmp_path / "out").exists()
    finally:
        if cli.poll() is None:
            cli.kill()
        cli.wait()
        for w in workers:  # (only if they outlived it: the failure above says so)
            if w in every_worker_named_by("granchain.lammps.worker"):
                os.kill(w, signal.SIGKILL)
