"""Campaigns and runs on a real SLURM queue (docs/clusters.md): a campaign through --cluster slurm
gives the local table, an MPI point the peaks of --np 2, `submit --wait` the run directory of
`granchain run --np 2`, and a worker job cancelled mid-campaign loses and redoes nothing.

The tests marked `slurm` need a SLURM whose client commands answer here (.ci/slurm-up starts a
one-node one; export the SLURM_CONF it prints). With GRANCHAIN_REQUIRE_SLURM=1 (set by .ci/run) they
fail, with the reason, when it does not answer; otherwise they skip with the reason. Each checks
that it leaves no job of its own in the queue. The scheduler and the workers bind to loopback.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from granchain.campaigns.spec import CampaignError, parse_campaign

from .test_campaigns import REFERENCE_GRID, campaign_text, complete_jobs

#: a 2000-bead chain (two ranks need 1000 beads each: granchain.workflows.run.MIN_BEADS_PER_RANK),
#: short enough for a test: about 4e7 bead-steps, 1-2 s a run
BIG = """
title = "a 2000-bead chain, short"
[chain]
beads = 2000
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "step"
amplitude = 100.0
duration = 2e-6
[run]
end_time = 1e-4
timestep = 1e-8
[outputs]
peak_force = true
histories = [1, 50]
snapshots = [5e-5]
window = [20, 80]
"""

#: a campaign point a little slower than the reference grid's (so that a job can be cancelled mid-run)
SIXTEEN = """
[vary]
"loading.amplitude" = { log = [1.0, 100.0], num = 4 }
"loading.duration" = [1e-6, 2e-6, 3e-6, 4e-6]
"""

SLURM_ARGS = ["--cluster", "slurm", "--interface", "lo", "--walltime", "00:20:00"]


def _slurm_down_reason() -> str | None:
    for cmd in ("sbatch", "squeue", "scontrol", "scancel", "sinfo"):
        if shutil.which(cmd) is None:
            return f"{cmd} is not on PATH (install slurm-client, start SLURM with .ci/slurm-up)"
    conf = os.environ.get("SLURM_CONF", "/etc/slurm/slurm.conf")
    start = "start it with .ci/slurm-up and export the SLURM_CONF it prints"
    try:
        r = subprocess.run(["sinfo", "-h", "-N", "-o", "%T"], capture_output=True, text=True, timeout=20)
    except subprocess.TimeoutExpired:
        return f"sinfo did not answer in 20 s (SLURM_CONF = {conf}); {start}"
    states = r.stdout.split()
    if r.returncode != 0:
        return f"sinfo failed ({' '.join(r.stderr.split())[:300]}); SLURM_CONF = {conf}; {start}"
    if not any(s.rstrip("*~#") in ("idle", "mixed", "allocated", "completing") for s in states):
        return f"no node is up (sinfo: {' '.join(states) or 'no nodes'})"
    return None


@pytest.fixture(scope="module")
def slurm():
    """A SLURM that answers: fail (CI, GRANCHAIN_REQUIRE_SLURM=1) or skip with the reason otherwise."""
    why = _slurm_down_reason()
    if why is not None:
        if os.environ.get("GRANCHAIN_REQUIRE_SLURM") == "1":
            pytest.fail(f"SLURM is required here (GRANCHAIN_REQUIRE_SLURM=1) but is not up: {why}")
        pytest.skip(f"no SLURM: {why}")


def our_jobs() -> list[str]:
    """'id name state' of the queue's granchain jobs."""
    r = subprocess.run(["squeue", "-h", "-o", "%i %j %T"], capture_output=True, text=True, timeout=30)
    return [line for line in r.stdout.splitlines() if " granchain-" in line]


@pytest.fixture
def no_job_left(slurm):
    yield
    deadline = time.time() + 60  # a cancelled job may stay COMPLETING for KillWait seconds
    while our_jobs() and time.time() < deadline:
        time.sleep(0.5)
    left = our_jobs()
    if left:
        subprocess.run(["scancel", *[line.split()[0] for line in left]], timeout=30)
    assert left == [], f"jobs left in the queue: {left}"


def without_timing(df):
    from granchain.campaigns.table import TIMING_COLUMNS

    return df.drop(columns=list(TIMING_COLUMNS))


def write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


# ----------------------------------------------------------------------- without a queue (fast)


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ('kind = "slurmm"', r"\[cluster\] kind = 'slurmm' is invalid: one of local, slurm, pbs"),
        ('queue = "debug\\n#SBATCH --wrap=x"', r"\[cluster\] queue = .* is invalid: a queue name"),
        ('walltime = "1h"', r"\[cluster\] walltime = '1h' is invalid: HH:MM:SS"),
        ("jobs = 0", r"\[cluster\] jobs = 0 is invalid: a whole number from 1"),
        ('memory = "lots"', r"\[cluster\] memory = 'lots' is invalid"),
        ('interface = "no-such-if0"', "this machine has no such network interface"),
        ('prologue = ["rm -rf ~"]', "unknown key 'prologue'.*--prologue flag"),
        ("cores_per_job = 1", r"cores.per.job = 1: a point runs on 2 MPI ranks"),
    ],
)
def test_bad_cluster_tables_get_one_clear_message(table, message):
    campaign = 'backend = "lammps"\nranks = 2' if "cores_per_job" in table else 'backend = "reference"'
    text = campaign_text('[vary]\n"loading.amplitude" = [1.0]\n', campaign=campaign) + f"\n[cluster]\n{table}\n"
    from granchain.campaigns.run import cluster_settings

    def settings():
        c = parse_campaign(text)
        return cluster_settings(c, None, ranks=c.ranks)

    with pytest.raises(CampaignError, match=message):
        settings()


def test_ranks_are_checked_before_anything_runs(tmp_path):
    from granchain.campaigns.run import run_campaign

    with pytest.raises(CampaignError, match="ranks = 2: the reference backend runs a point in one process"):
        parse_campaign(campaign_text('[vary]\n"loading.amplitude" = [1.0]\n', campaign="ranks = 2"))
    with pytest.raises(CampaignError, match=r"ranks = 0 is invalid"):
        parse_campaign(campaign_text('[vary]\n"loading.amplitude" = [1.0]\n', campaign='backend = "lammps"\nranks = 0'))
    # a point that cannot run: refused before the workspace is made, with its parameters
    c = parse_campaign(
        campaign_text('[vary]\n"run.timestep" = [5e-8, 5e-5]\n', campaign='backend = "lammps"\nranks = 2')
    )
    with pytest.raises(CampaignError, match=r"point 2 \(run.timestep = 5e-05\) cannot run"):
        run_campaign(c, tmp_path / "ws")
    assert not (tmp_path / "ws").exists()


def test_a_cluster_without_its_submit_command_is_refused_clearly(tmp_path, monkeypatch):
    from granchain.campaigns.run import run_campaign

    monkeypatch.setenv("PATH", str(tmp_path))  # no sbatch, no qsub
    c = parse_campaign(campaign_text('[vary]\n"loading.amplitude" = [1.0]\n'))
    with pytest.raises(CampaignError, match=r"--cluster pbs: qsub is not on PATH"):
        run_campaign(c, tmp_path / "ws", cluster="pbs")
    assert not (tmp_path / "ws").exists()


@pytest.mark.parametrize("kind", ["slurm", "pbs"])
def test_the_worker_job_script_asks_for_ranks_times_workers_cores(kind):
    """cores_per_job = 4 with ranks = 2: two Dask workers of one thread in a 4-core job; the points'
    mpirun starts its ranks inside the job; the walltime, queue and account as given."""
    from unittest import mock

    from granchain.campaigns import cluster as cl

    s = cl.check(
        cl.ClusterSettings(kind=kind, queue="workq", account="proj", cores_per_job=4, memory="8GB", interface="lo"),
        ranks=2,
    )
    jc = cl.JobCluster(s, 2, None)
    with (
        mock.patch.object(cl.shutil, "which", return_value="/usr/bin/true"),
        mock.patch.object(cl.JobCluster, "_submit", return_value=None),  # the script only: nothing submitted
    ):
        client = jc.start()
    try:
        script = jc.job_script()
    finally:
        client.close()
        jc.cluster.close()
    cores = "#SBATCH --cpus-per-task=4" if kind == "slurm" else "#PBS -l select=1:ncpus=4:mem=8GB"
    for line in (cores, "--nworkers 2", "--nthreads 1", "export HYDRA_BOOTSTRAP=fork", "--interface lo", "workq"):
        assert line in script, (line, script)
    assert "--lifetime 3300s" in script  # an hour's walltime less 5 min
    if kind == "slurm":
        assert "#SBATCH --mem=8G" in script


def test_without_memory_the_job_asks_for_none_and_takes_the_queues_default():
    from unittest import mock

    from granchain.campaigns import cluster as cl

    jc = cl.JobCluster(cl.check(cl.ClusterSettings(kind="slurm", interface="lo")), 1, None)
    with (
        mock.patch.object(cl.shutil, "which", return_value="/usr/bin/true"),
        mock.patch.object(cl.JobCluster, "_submit", return_value=None),
    ):
        client = jc.start()
    try:
        script = jc.job_script()
    finally:
        client.close()
        jc.cluster.close()
    assert "#SBATCH --mem" not in script
    assert "--memory-limit" in script


def test_ranks_auto_follows_the_np_auto_rule_within_a_workers_cores():
    from granchain.campaigns.execute import point_ranks
    from granchain.schedule import auto_ranks

    c = parse_campaign(
        campaign_text('[vary]\n"chain.beads" = [2000, 12000, 40000]\n', campaign='backend = "lammps"\nranks = "auto"')
    )
    for p in c.points():
        for cores in (1, 2, 4, 16):
            n = point_ranks(c, p.scene, cores)
            assert n == auto_ranks(p.scene.chain.beads, cores)
            assert 1 <= n <= cores
    assert [point_ranks(c, p.scene, 16) for p in c.points()] == [1, 2, 8]


def test_a_task_run_again_finds_its_own_finished_point_and_does_not_run_it(tmp_path):
    """A point whose worker (or worker job) ended after the run directory was complete but before the
    scheduler heard of it is submitted again by Dask: the task finds its own token in task.json and
    returns done without running (the scene here would fail if it ran)."""
    from granchain.campaigns import workspace as wsp
    from granchain.campaigns.execute import run_point
    from granchain.campaigns.run import run_campaign

    c = parse_campaign(campaign_text('[vary]\n"loading.amplitude" = [1.0]\n'))
    tables, _ = run_campaign(c, tmp_path / "ws", workers=1)
    job = tmp_path / "ws" / "workspace" / tables["table"]["job"][0]
    task = json.loads((job / "task.json").read_text())
    summary = (job / "run" / "summary.json").stat().st_mtime_ns
    payload = {"job_dir": str(job), "token": task["token"], "rerun": True, "scene": {}, "backend": "reference"}
    r = run_point(payload)
    assert r["status"] == "done"
    assert r["repeated"]
    assert r["wall_time"] == task["wall_time"]
    assert (job / "run" / "summary.json").stat().st_mtime_ns == summary  # not run again
    # another campaign run's token with rerun: it runs (and this payload's empty scene fails, recorded)
    other = {"token": "other", "source": "x", "method": None, "rtol": None, "error_estimate": False}
    r2 = run_point({**payload, **other, "code": wsp.code_version("reference")})
    assert r2["status"] == "failed"
    assert (job / "failure.json").is_file()


# -------------------------------------------------------------------------- on a real SLURM


@pytest.mark.slow
@pytest.mark.slurm
def test_a_12_point_campaign_through_slurm_gives_the_local_table(tmp_path, no_job_left):
    """`campaign run --cluster slurm --jobs 2`: 12 LAMMPS points on two worker jobs, the table the
    local cluster gives (but for the wall times); both jobs ran points; none is left."""
    import granchain
    from granchain.campaigns.run import run_campaign
    from granchain.cli import main

    text = campaign_text(REFERENCE_GRID, campaign='backend = "lammps"\nerror_estimate = false')
    path = write(tmp_path, "c.toml", text)
    ws = tmp_path / "slurm"
    assert main(["campaign", "run", str(path), "--out", str(ws), "--jobs", "2", *SLURM_ARGS, "-q"]) == 0
    remote = granchain.load_campaign(ws)
    assert len(remote) == 12
    assert set(remote["status"]) == {"done"}
    tasks = [json.loads((ws / "workspace" / j / "task.json").read_text()) for j in remote["job"]]
    assert len({t["pid"] for t in tasks}) == 2, "both worker jobs ran points"
    assert any(p.name.endswith(".err") for p in (ws / "jobs").iterdir()), "the jobs' output is in WS/jobs"
    local, _ = run_campaign(path, tmp_path / "local", workers=2)
    assert without_timing(remote).equals(without_timing(local["table"]))


@pytest.mark.slow
@pytest.mark.slurm
def test_an_mpi_point_with_ranks_2_gives_the_peaks_of_np_2(tmp_path, no_job_left):
    """[campaign] ranks = 2 on SLURM: the point runs on 2 MPI ranks inside its 2-core job, and its
    peaks.csv is the one `granchain run --np 2` writes for the same scene, to the bit."""
    from granchain.campaigns.run import run_campaign
    from granchain.rundir import read_summary
    from granchain.scene import scene_from_dict
    from granchain.workflows.run import run_scene

    body = '[vary]\n"loading.amplitude" = [100.0]\n'
    c = parse_campaign(campaign_text(body, scene=BIG, campaign='backend = "lammps"\nerror_estimate = false\nranks = 2'))
    ws = tmp_path / "ws"
    tables, report = run_campaign(c, ws, cluster={"kind": "slurm", "interface": "lo", "walltime": "00:20:00"})
    assert (report.done, report.failed) == (1, 0)
    job = ws / "workspace" / tables["table"]["job"][0]
    assert json.loads((job / "task.json").read_text())["ranks"] == 2
    assert read_summary(job / "run")["provenance"]["lammps"]["ranks"] == 2
    scene = scene_from_dict(json.loads((job / "signac_statepoint.json").read_text())["scene"])
    direct = tmp_path / "np2"
    run_scene(scene, backend="lammps", np_=2, out=direct)
    assert (job / "run" / "peaks.csv").read_text() == (direct / "peaks.csv").read_text()


def _same_run_files(a: Path, b: Path) -> None:
    from granchain.rundir import read_summary

    for name in ("peaks.csv", "energy.csv", "histories.csv", "snapshots.csv", "scene.toml", "deck.lmp", "chain.data"):
        assert (a / name).read_text() == (b / name).read_text(), name
    sa, sb = read_summary(a), read_summary(b)
    for k in ("backend", "method", "timestep", "steps", "end_time", "beads", "peaks", "observables", "conservation"):
        assert sa[k] == sb[k], k
    assert sa["provenance"]["lammps"]["ranks"] == sb["provenance"]["lammps"]["ranks"] == 2


@pytest.mark.slow
@pytest.mark.slurm
def test_submit_ranks_2_wait_gives_the_run_directory_of_granchain_run_np_2(tmp_path, no_job_left, capsys):
    """`granchain submit SCENE --ranks 2 --wait`: plain lmp under mpirun in a 2-task job, collected;
    its peaks, energies, histories, snapshots, deck and summary are those of `granchain run --np 2`
    (one run: --error-estimate off)."""
    from granchain.cli import main

    scene = write(tmp_path, "big.toml", BIG)
    out = tmp_path / "submitted"
    assert main(["submit", str(scene), "--out", str(out), "--ranks", "2", "--wait", "--walltime", "00:10:00"]) == 0
    printed = capsys.readouterr().out
    job_id = json.loads((out / "job.json").read_text())["job_id"]
    assert f"submitted job {job_id}" in printed
    assert "run directory:" in printed
    assert "mpirun -np 2" in (out / "job.sh").read_text()
    assert "python" not in (out / "job.sh").read_text()
    ref = tmp_path / "run"
    argv = ["run", str(scene), "--backend", "lammps", "--np", "2", "--error-estimate", "off", "--out", str(ref), "-q"]
    assert main(argv) == 0
    _same_run_files(out, ref)


@pytest.mark.slow
@pytest.mark.slurm
def test_a_cancelled_submit_job_is_one_clear_message(tmp_path, no_job_left):
    from granchain.scene import parse_scene
    from granchain.workflows.submit import SubmitError, submit, wait

    sub = submit(parse_scene(BIG.replace("end_time = 1e-4", "end_time = 1e-1"), source="long.toml"), tmp_path / "j")
    deadline = time.time() + 60
    while "RUNNING" not in " ".join(our_jobs()) and time.time() < deadline:
        time.sleep(0.2)
    subprocess.run(["scancel", sub.job_id], check=True, timeout=30)
    with pytest.raises(SubmitError, match=rf"job {sub.job_id} ended CANCELLED .* without finishing its run"):
        wait(sub)


def _campaign_process(path: Path, ws: Path, *extra: str) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "granchain", "campaign", "run", str(path), "--out", str(ws), *SLURM_ARGS, *extra]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)


def _worker_jobs() -> list[str]:
    return [line.split()[0] for line in our_jobs() if "granchain-worker" in line and "RUNNING" in line]


def _wait_for(cond, timeout=240.0, what="") -> None:
    deadline = time.time() + timeout
    while not cond():
        assert time.time() < deadline, f"timed out waiting for {what}"
        time.sleep(0.1)


@pytest.mark.slow
@pytest.mark.slurm
def test_scancel_of_a_worker_job_mid_campaign_loses_and_redoes_nothing(tmp_path, no_job_left):
    """16 LAMMPS points on two worker jobs; one job is cancelled (scancel) once 4 points are complete:
    the campaign finishes on the other job and a replacement, every point complete, none of the points
    complete at the cancel written again, the table the local run gives."""
    from granchain.campaigns.run import run_campaign

    path = write(tmp_path, "c.toml", campaign_text(SIXTEEN, campaign='backend = "lammps"'))
    ws = tmp_path / "ws"
    p = _campaign_process(path, ws, "--jobs", "2", "-q")
    try:
        _wait_for(lambda: (ws / "workspace").is_dir() and len(complete_jobs(ws)) >= 4, what="4 points")
        jobs = _worker_jobs()
        assert len(jobs) == 2, our_jobs()
        subprocess.run(["scancel", jobs[0]], check=True, timeout=30)
        before = complete_jobs(ws)
        mtimes = {j: (ws / "workspace" / j / "run" / "summary.json").stat().st_mtime_ns for j in before}
        out, err = p.communicate(timeout=600)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGINT)
            p.wait(timeout=60)
    assert p.returncode == 0, err[-3000:]
    assert "16 points: 0 complete before, 16 run now, 0 failed" in out
    assert len(complete_jobs(ws)) == 16
    assert all((ws / "workspace" / j / "run" / "summary.json").stat().st_mtime_ns == t for j, t in mtimes.items())
    local, _ = run_campaign(path, tmp_path / "local", workers=2)
    import granchain

    assert without_timing(granchain.load_campaign(ws)).equals(without_timing(local["table"]))


@pytest.mark.slow
@pytest.mark.slurm
def test_past_the_replacement_limit_the_campaign_stops_clearly_and_a_rerun_finishes_it(tmp_path, no_job_left):
    """One worker job, no replacement: cancelling it stops the campaign with one message naming the
    job and the limit (exit 2); the rerun runs only the missing points."""
    from granchain.campaigns.run import run_campaign

    path = write(tmp_path, "c.toml", campaign_text(SIXTEEN, campaign='backend = "lammps"\nerror_estimate = false'))
    ws = tmp_path / "ws"
    p = _campaign_process(path, ws, "--jobs", "1", "--replacements", "0", "-q")
    try:
        _wait_for(lambda: (ws / "workspace").is_dir() and len(complete_jobs(ws)) >= 2, what="2 points")
        jobs = _worker_jobs()
        subprocess.run(["scancel", *jobs], check=True, timeout=30)
        out, err = p.communicate(timeout=300)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGINT)
            p.wait(timeout=60)
    assert p.returncode == 2, err[-3000:]
    assert f"every worker job ended ({jobs[0]} CANCELLED" in err, err[-2000:]
    assert "replacements 0" in err, err[-2000:]
    done = complete_jobs(ws)
    assert 2 <= len(done) < 16
    _, report = run_campaign(path, ws, cluster={"kind": "slurm", "interface": "lo", "walltime": "00:20:00"})
    assert (report.cached, report.ran, report.done) == (len(done), 16 - len(done), 16 - len(done))


@pytest.mark.slow
@pytest.mark.slurm
def test_ctrl_c_cancels_the_campaigns_jobs_and_only_those(tmp_path, no_job_left):
    """Ctrl-C (SIGINT) to `campaign run --cluster slurm` mid-campaign: exit 130, its worker jobs leave the
    queue; a job of the same user's that the campaign did not submit stays."""
    path = write(tmp_path, "c.toml", campaign_text(SIXTEEN, campaign='backend = "lammps"'))
    ws = tmp_path / "ws"
    foreign = subprocess.run(
        ["sbatch", "--parsable", "-J", "granchain-foreign", "-o", "/dev/null", "--wrap", "sleep 600"],
        capture_output=True,
        text=True,
        check=True,
        timeout=30,
    ).stdout.strip()
    try:
        p = _campaign_process(path, ws, "--jobs", "2")
        _wait_for(lambda: (ws / "workspace").is_dir() and len(complete_jobs(ws)) >= 2, what="2 points")
        mine = _worker_jobs()
        assert mine
        assert foreign not in mine
        os.killpg(p.pid, signal.SIGINT)
        out, err = p.communicate(timeout=120)
        assert p.returncode == 130, err[-2000:]
        _wait_for(lambda: not any(line.split()[0] in mine for line in our_jobs()), 60, "the worker jobs to go")
        assert any(line.split()[0] == foreign for line in our_jobs()), "the foreign job was cancelled"
    finally:
        subprocess.run(["scancel", foreign], timeout=30)


#: 64 LAMMPS points of about a second each (300 beads, 8e4 steps; 1-2 s on this machine): longer on one
#: core than a 1-minute job's worker lives (40 s), on any machine this project runs on
LONGER = """
[vary]
"loading.amplitude" = { log = [1.0, 100.0], num = 8 }
"loading.duration" = { linear = [1e-6, 5e-6], num = 8 }
"""


@pytest.mark.slow
@pytest.mark.slurm
def test_a_worker_job_at_its_walltime_is_replaced_and_the_campaign_finishes(tmp_path, no_job_left):
    """One worker job of 1 minute: its worker leaves before the limit (--lifetime 40 s), the job ends,
    a replacement (with a name of its own: distributed cancels the job under a lost worker's name) takes
    over, and every point completes once. The points take several minutes of one worker on an idle
    machine (at a quarter of this, 64 points finished inside 40 s on CI's idle cores: no job ended)."""
    scene = BIG.replace("beads = 2000", "beads = 300").replace("end_time = 1e-4", "end_time = 6.4e-3")
    scene = scene.replace("timestep = 1e-8", "timestep = 2e-8")
    path = write(tmp_path, "c.toml", campaign_text(LONGER, scene=scene, campaign='backend = "lammps"'))
    ws = tmp_path / "ws"
    cmd = [sys.executable, "-m", "granchain", "campaign", "run", str(path), "--out", str(ws), "--jobs", "1"]
    cmd += ["--cluster", "slurm", "--interface", "lo", "--walltime", "00:01:00", "-q"]
    # the replacement limit is not what this test checks (test_past_the_replacement_limit_...): on a
    # machine loaded by other work each point is slower and more jobs end (CI on 2 cores shared with four
    # other processes: 3 replacements were used up with points left, 2026-11-27)
    cmd += ["--replacements", "12"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr[-3000:]
    assert "64 points: 0 complete before, 64 run now, 0 failed" in p.stdout
    assert len(complete_jobs(ws)) == 64
    jobs = {f.stem for f in (ws / "jobs").glob("*.err")}
    assert len(jobs) >= 2, f"no job was replaced: {jobs}"
