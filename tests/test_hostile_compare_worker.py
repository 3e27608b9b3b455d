"""A killed `granchain compare` takes its prefetch worker (the reference's error-bar companions,
granchain.workflows.shared_runs) with it: SIGTERM, SIGHUP or kill -9, the caller's pipe reaches
its end (``granchain compare | tee log`` returns) and no process of it is left running."""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import time

import pytest

from .conftest import make_scene_text

#: a reference run of several seconds: the worker is still making the companions when killed
SCENE = make_scene_text(beads=100, end_time=2e-3, timestep=5e-8)


def group(pgid: int) -> list[tuple[int, str]]:
    """The processes of a process group (pid, command line)."""
    ps = subprocess.run(["ps", "-ww", "-o", "pid=,args=", "-g", str(pgid)], capture_output=True, text=True).stdout
    return [(int(line.split(None, 1)[0]), line.split(None, 1)[1]) for line in ps.strip().splitlines()]


def wait_for_eof(fd: int, timeout: float) -> bool:
    """Whether the pipe ``fd`` reaches its end (every writer closed it) within ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while (left := deadline - time.monotonic()) > 0:
        ready, _, _ = select.select([fd], [], [], left)
        if ready and os.read(fd, 65536) == b"":
            return True
    return False


@pytest.mark.skipif(not sys.platform.startswith("linux") or len(os.sched_getaffinity(0)) < 2,
                    reason="the prefetch worker starts on two cores or more; ps -g as on Linux")  # fmt: skip
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGKILL], ids=lambda s: s.name)
def test_a_killed_compare_leaves_no_worker_and_ends_its_pipe(tmp_path, sig):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE)
    p = subprocess.Popen(
        [sys.executable, "-m", "granchain", "compare", str(scene), "--out", str(tmp_path / "c"), "-q"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,  # its own group: whatever it started is found by the group
        # the signals' default action, whatever this test inherited (under nohup SIGHUP is ignored, and
        # compare rightly carries on: exit 0)
        preexec_fn=None if sig == signal.SIGKILL else lambda: signal.signal(sig, signal.SIG_DFL),
    )
    try:
        deadline = time.monotonic() + 60
        while not [pid for pid, _ in group(p.pid) if pid != p.pid]:  # the worker is started
            assert p.poll() is None, p.communicate()
            assert time.monotonic() < deadline, "no prefetch worker started"
            time.sleep(0.05)
        time.sleep(0.5)  # (its initializer has run)
        os.kill(p.pid, sig)
        assert p.wait(timeout=30) == -sig
        assert wait_for_eof(p.stdout.fileno(), 5), f"stdout still held open by {group(p.pid)}"
        deadline = time.monotonic() + 5
        while group(p.pid) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert group(p.pid) == []
    finally:
        for pid, _ in group(p.pid):
            os.kill(pid, signal.SIGKILL)
        p.stdout.close()
        p.stderr.close()
