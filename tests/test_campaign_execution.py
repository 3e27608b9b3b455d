"""Campaigns on Dask, end to end (slow): LAMMPS points equal to `granchain run` to the bit, kill -9 of
the driver or of a worker and the rerun that completes only what is missing, an external scheduler,
a worker running another granchain, and a search finding the single-wave to train transition."""

from __future__ import annotations

from pathlib import Path

import pytest

from granchain.campaigns.spec import CampaignError, parse_campaign

from .test_campaigns import REFERENCE_GRID, campaign_text, complete_jobs, peaks_text


@pytest.mark.slow
def test_lammps_grid_of_27_points_equals_granchain_run_bit_for_bit(tmp_path):
    """27 LAMMPS points (3 x 3 x 3) on two local workers; each run directory's peaks.csv is the one
    `granchain run --backend lammps` writes for the same scene (run_scene here), to the bit."""
    import signac

    from granchain.campaigns.run import run_campaign
    from granchain.scene import scene_from_dict
    from granchain.workflows.run import run_scene

    body = """
    [vary]
    "loading.amplitude" = { log = [1.0, 100.0], num = 3 }
    "loading.duration" = [1e-6, 2e-6, 4e-6]
    "chain.beads" = [16, 18, 20]
    """
    c = parse_campaign(campaign_text(body, campaign='backend = "lammps"\nerror_estimate = false'))
    ws = tmp_path / "ws"
    tables, report = run_campaign(c, ws, workers=2)
    df = tables["table"]
    assert (report.points, report.done, report.failed) == (27, 27, 0)
    assert len(df) == 27
    assert set(df["status"]) == {"done"}
    assert df["bead_steps"].gt(0).all()
    project = signac.get_project(str(ws), search=False)
    assert len(project) == 27
    for job in project:
        assert set(job.statepoint()["code"]) == {"granchain", "source", "plugin"}
        scene = scene_from_dict(job.statepoint()["scene"])
        out = tmp_path / f"direct-{job.id}"
        run_scene(scene, backend="lammps", out=out)
        assert peaks_text(Path(job.path) / "run") == peaks_text(out), job.id


def _table_without_timing(df):
    from granchain.campaigns.table import TIMING_COLUMNS

    return df.drop(columns=list(TIMING_COLUMNS))


FORTY = """
[vary]
"loading.amplitude" = { log = [1.0, 100.0], num = 8 }
"loading.duration" = { linear = [1e-6, 5e-6], num = 5 }
"""


@pytest.mark.slow
def test_kill_9_of_the_driver_then_rerun_runs_only_the_missing_points(tmp_path):
    """kill -9 of `granchain campaign run` in the middle of 40 points: its local workers go with it,
    nothing half-written looks complete; the rerun runs exactly the missing points, and the final table
    equals an uninterrupted campaign's (but for the wall times)."""
    import os
    import signal
    import subprocess
    import sys
    import time

    from granchain.campaigns.run import run_campaign

    path = tmp_path / "forty.toml"
    path.write_text(campaign_text(FORTY, campaign='backend = "reference"\nmethod = "verlet"'))
    ws = tmp_path / "ws"
    cmd = [sys.executable, "-m", "granchain.cli", "campaign", "run", str(path), "--out", str(ws), "--workers", "2"]
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.time() + 300
    while time.time() < deadline and (not (ws / "workspace").is_dir() or len(complete_jobs(ws)) < 12):
        time.sleep(0.05)
    os.kill(p.pid, signal.SIGKILL)
    p.wait()
    time.sleep(3)  # the workers notice their parent is gone
    left = subprocess.run(["ps", "-o", "pid=", "-g", str(p.pid)], capture_output=True, text=True).stdout.split()
    assert left == [], "worker processes outlived the driver"
    before = complete_jobs(ws)
    assert 12 <= len(before) < 40, len(before)
    mtimes = {j: (ws / "workspace" / j / "run" / "summary.json").stat().st_mtime_ns for j in before}
    tables, report = run_campaign(path, ws, workers=2)
    assert report.cached == len(before)
    assert report.ran == 40 - len(before)  # only the missing points ran
    assert report.done == 40 - len(before)
    assert all((ws / "workspace" / j / "run" / "summary.json").stat().st_mtime_ns == t for j, t in mtimes.items())
    clean, _ = run_campaign(path, tmp_path / "clean", workers=2)
    assert _table_without_timing(tables["table"]).equals(_table_without_timing(clean["table"]))


@pytest.mark.slow
def test_kill_9_of_a_worker_loses_only_its_point_in_flight(tmp_path):
    """kill -9 of one local worker process in the middle of 40 points: Dask starts another and runs
    the lost point again; the campaign completes every point."""
    import os
    import signal
    import subprocess
    import sys
    import time

    path = tmp_path / "forty.toml"
    path.write_text(campaign_text(FORTY, campaign='backend = "reference"\nmethod = "verlet"\nerror_estimate = false'))
    ws = tmp_path / "ws"
    cmd = [
        sys.executable,
        "-m",
        "granchain.cli",
        "campaign",
        "run",
        str(path),
        "--out",
        str(ws),
        "--workers",
        "2",
        "-q",
    ]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.time() + 300
    while time.time() < deadline and (not (ws / "workspace").is_dir() or len(complete_jobs(ws)) < 8):
        time.sleep(0.05)
    ps = subprocess.run(["ps", "-ww", "-o", "pid=,args=", "-g", str(p.pid)], capture_output=True, text=True).stdout
    workers = [int(line.split()[0]) for line in ps.splitlines() if "spawn_main" in line]
    assert len(workers) == 2, ps
    os.kill(workers[0], signal.SIGKILL)
    out, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    assert "40 points: 0 complete before, 40 run now, 0 failed" in out
    assert len(complete_jobs(ws)) == 40


@pytest.mark.slow
def test_an_external_dask_scheduler_and_two_workers_give_the_same_table(tmp_path):
    """`dask scheduler` and two `dask worker` processes on localhost; `granchain campaign run
    --scheduler` gives the table a local cluster gives (but for the wall times)."""
    import json
    import os
    import shutil
    import signal
    import subprocess
    import sys
    import time

    from granchain.campaigns.run import run_campaign
    from granchain.cli import main

    dask = shutil.which("dask", path=os.path.dirname(sys.executable)) or shutil.which("dask")
    assert dask, "the dask command (dask[distributed]) is not installed"
    path = tmp_path / "c.toml"
    path.write_text(campaign_text(REFERENCE_GRID, campaign='backend = "reference"\nmethod = "verlet"'))
    sfile = tmp_path / "scheduler.json"
    procs = []
    try:
        procs.append(
            subprocess.Popen(
                [
                    dask,
                    "scheduler",
                    "--host",
                    "127.0.0.1",
                    "--port",
                    "0",
                    "--no-dashboard",
                    "--scheduler-file",
                    str(sfile),
                ],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                start_new_session=True,
            )
        )
        deadline = time.time() + 60
        while not sfile.is_file() and time.time() < deadline:
            time.sleep(0.1)
        address = json.loads(sfile.read_text())["address"]
        for _ in range(2):
            procs.append(
                subprocess.Popen(
                    [dask, "worker", address, "--nthreads", "1", "--nworkers", "1", "--no-dashboard"],
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                    start_new_session=True,
                )
            )
        ws = tmp_path / "remote"
        assert main(["campaign", "run", str(path), "--out", str(ws), "--scheduler", address, "-q"]) == 0
        import granchain

        remote = granchain.load_campaign(ws)
        hosts = {json.loads((ws / "workspace" / j / "task.json").read_text())["pid"] for j in remote["job"]}
        assert len(hosts) == 2, "both workers ran points"
    finally:
        for p in procs:
            os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            p.wait(timeout=30)
    local, _ = run_campaign(path, tmp_path / "local", workers=2)
    assert _table_without_timing(remote).equals(_table_without_timing(local["table"]))


@pytest.mark.slow
def test_a_worker_running_another_granchain_is_named_before_any_point(tmp_path):
    """A `dask worker` whose granchain lacks this one's worker plugin (an older install): one
    CampaignError naming the fix when the executor connects, not distributed's bare traceback."""
    import json
    import os
    import shutil
    import signal
    import subprocess
    import sys
    import time

    from granchain.campaigns.execute import Executor

    old = tmp_path / "old-install" / "granchain"
    (old / "campaigns").mkdir(parents=True)
    (old / "__init__.py").write_text('__version__ = "0.0.1"\n')
    (old / "campaigns" / "__init__.py").write_text("")
    (old / "campaigns" / "execute.py").write_text("def run_point(payload):\n    return {}\n")
    dask = shutil.which("dask", path=os.path.dirname(sys.executable)) or shutil.which("dask")
    assert dask, "the dask command (dask[distributed]) is not installed"
    sfile = tmp_path / "scheduler.json"
    procs = []
    try:
        procs.append(
            subprocess.Popen(
                [
                    dask,
                    "scheduler",
                    "--host",
                    "127.0.0.1",
                    "--port",
                    "0",
                    "--no-dashboard",
                    "--scheduler-file",
                    str(sfile),
                ],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                start_new_session=True,
            )
        )
        deadline = time.time() + 60
        while not sfile.is_file() and time.time() < deadline:
            time.sleep(0.1)
        address = json.loads(sfile.read_text())["address"]
        procs.append(
            subprocess.Popen(
                [dask, "worker", address, "--nthreads", "1", "--no-dashboard"],
                env=dict(os.environ, PYTHONPATH=str(old.parent)),
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                start_new_session=True,
            )
        )
        from distributed import Client

        with Client(address, timeout="30s") as c:
            c.wait_for_workers(1, timeout=60)
        ex = Executor(scheduler=address)
        with pytest.raises(CampaignError, match="install the same granchain on every worker"):
            ex.start()
        assert ex.client is None, "the executor let go of the scheduler"
    finally:
        for p in procs:
            os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            p.wait(timeout=30)


@pytest.mark.slow
def test_search_finds_the_single_wave_to_train_transition_following_a_to_the_minus_one_sixth(tmp_path):
    """Fig. 1's search (the bundled granchain/campaigns/fig1-transition.toml): at three amplitudes
    (10, 100, 1000 N) bisect the loading time T until the pulse count at contact 20 goes from 1 to more,
    to 0.2%; T_c(A) ~ A^(-1/6) within 2% in the exponent
    (measured: -0.16661, 0.03% off; a Hertz chain is self-similar under F -> A F, t -> A^(-1/6) t)."""
    from importlib import resources

    import numpy as np

    from granchain.campaigns.run import run_campaign
    from granchain.campaigns.spec import load_campaign_file

    c = load_campaign_file(resources.files("granchain.campaigns") / "fig1-transition.toml")
    tables, report = run_campaign(c, tmp_path / "ws", workers=2)
    s = tables["search"]
    assert list(s["status"]) == ["found"] * 3
    assert (s["width"] <= 0.002).all()
    assert list(s["quantity_low"]) == [1.0] * 3
    assert (s["quantity_high"] >= 2).all()
    slope = np.polyfit(np.log(s["loading.amplitude"]), np.log(s["transition"]), 1)[0]
    assert abs(slope / (-1 / 6) - 1) < 0.02, slope
    assert len(tables["table"]) == report.points == s["runs"].sum()
    again, report2 = run_campaign(c, tmp_path / "ws", workers=2)  # every bisection step from the cache
    assert report2.ran == 0
    assert again["search"].equals(s)


@pytest.mark.slow
def test_ctrl_c_while_the_local_workers_start_is_one_message_and_no_traceback(tmp_path):
    """Ctrl-C (SIGINT to the foreground process group, as a terminal sends it) the moment a local
    worker process exists, while it still imports: exit 130, one 'interrupted' line naming the
    workspace, no traceback (a worker's KeyboardInterrupt, a nanny that 'failed to start'); the
    workspace resumes."""
    import os
    import signal
    import subprocess
    import sys
    import time

    path = tmp_path / "c.toml"
    path.write_text(campaign_text(REFERENCE_GRID))
    ws = tmp_path / "ws"
    cmd = [sys.executable, "-m", "granchain.cli", "campaign", "run", str(path), "--out", str(ws), "--workers", "1"]

    def as_from_a_terminal():  # a test runner's worker (pytest-xdist) may ignore SIGINT, which a child inherits
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    p = subprocess.Popen(
        cmd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=as_from_a_terminal,
    )
    deadline = time.time() + 120
    worker = False
    while time.time() < deadline and p.poll() is None and not worker:
        # -ww: without it ps cuts args at $COLUMNS (80 on many CI hosts) before "spawn_main" on a long venv path
        ps = subprocess.run(["ps", "-ww", "-o", "args=", "-g", str(p.pid)], capture_output=True, text=True).stdout
        worker = any("spawn_main" in line for line in ps.splitlines())
        time.sleep(0.02)
    assert worker, p.communicate()
    os.killpg(p.pid, signal.SIGINT)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert "Traceback" not in err, err
    assert "failed to start" not in err, err
    said = [line for line in err.splitlines() if "interrupted" in line]
    assert len(said) == 1, err
    assert str(ws) in said[0], err
    again = subprocess.run(cmd + ["-q"], capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    import re

    m = re.search(r"campaign +12 points: (\d+) complete before, (\d+) run now, 0 failed\n", again.stdout)
    assert m, again.stdout
    assert int(m[1]) + int(m[2]) == 12
