"""What SLURM costs a campaign and a run (docs/clusters.md): job start latency and per-point overhead.

Run by hand, with a SLURM that answers (.ci/slurm-up; export the SLURM_CONF it prints):

    python benchmarks/bench_slurm.py [--starts 5] [--points 10,60] [--reps 2]

1. start latency: a trivial job (`sbatch --wrap true`) from sbatch's return to the state RUNNING (or
   already ended) in `scontrol show job` (polled every 20 ms), --starts times; and dask-jobqueue's
   scale to connected workers (granchain.campaigns.cluster.JobCluster.start to a worker in
   client.scheduler_info, 1 and 2 jobs).
2. per-point overhead: campaigns of trivial reference points (a 2-bead chain, 10 Verlet steps;
   bench_campaigns.TRIVIAL) on one worker, through one SLURM job (`--cluster slurm --jobs 1`) and on a
   local cluster of one worker, each with the counts in --points into fresh workspaces, --reps times;
   the overhead per point is the slope of the wall time over the point count (the cluster's and job's
   start cancel out), less the points' own run time (task.json run_time).
Prints markdown tables.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

from bench_campaigns import TRIVIAL

from granchain.campaigns.cluster import ClusterSettings, JobCluster
from granchain.campaigns.run import run_campaign
from granchain.campaigns.spec import parse_campaign


def job_start(n: int) -> list[float]:
    out = []
    for _ in range(n):
        jid = subprocess.run(
            ["sbatch", "--parsable", "-J", "granchain-bench", "-o", "/dev/null", "--wrap", "true"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        t_sub = time.perf_counter()
        while True:
            info = subprocess.run(["scontrol", "show", "job", "-o", jid], capture_output=True, text=True).stdout
            if "JobState=PENDING" not in info:
                break
            time.sleep(0.02)
        out.append(time.perf_counter() - t_sub)
    return out


def workers_up(jobs: int) -> float:
    jc = JobCluster(ClusterSettings(kind="slurm", jobs=jobs, interface="lo", walltime="00:10:00"), 1, None)
    t0 = time.perf_counter()
    client = jc.start()
    try:
        while len(client.scheduler_info()["workers"]) < jobs:
            time.sleep(0.02)
        return time.perf_counter() - t0
    finally:
        client.close()
        jc.close()


def campaign_text(points: int) -> str:
    scene = TRIVIAL.replace("\n[", "\n[scene.")
    return (
        '[campaign]\nbackend = "reference"\nmethod = "verlet"\nerror_estimate = false\n'
        f'[vary]\n"loading.amplitude" = {{ linear = [1.0, 100.0], num = {points} }}\n[scene]{scene}'
    )


def one_campaign(points: int, where: str) -> tuple[float, float]:
    """(wall time of run_campaign, the points' own run time in sum)."""
    c = parse_campaign(campaign_text(points))
    with tempfile.TemporaryDirectory() as d:
        ws = Path(d) / "ws"
        t0 = time.perf_counter()
        if where == "slurm":
            tables, _ = run_campaign(c, ws, cluster={"kind": "slurm", "jobs": 1, "interface": "lo"})
        else:
            tables, _ = run_campaign(c, ws, workers=1)
        wall = time.perf_counter() - t0
        runs = sum(
            json.loads((ws / "workspace" / j / "task.json").read_text())["run_time"] for j in tables["table"]["job"]
        )
    return wall, runs


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--starts", type=int, default=5)
    ap.add_argument("--points", default="10,60")
    ap.add_argument("--reps", type=int, default=2)
    a = ap.parse_args()
    os.environ["GRANCHAIN_QUIET"] = "1"
    lat = job_start(a.starts)
    print("| what | median (s) | min | max |\n|---|---|---|---|")
    med = statistics.median(lat)
    print(f"| sbatch to RUNNING (trivial job, {a.starts}x) | {med:.2f} | {min(lat):.2f} | {max(lat):.2f} |")
    for jobs in (1, 2):
        ups = [workers_up(jobs) for _ in range(a.reps)]
        print(
            f"| scheduler + {jobs} job(s) to connected workers ({a.reps}x) | {statistics.median(ups):.2f} | "
            f"{min(ups):.2f} | {max(ups):.2f} |"
        )
    lo, hi = (int(x) for x in a.points.split(","))
    print("\n| where | points | wall (s) | runs (s) |\n|---|---|---|---|")
    slope = {}
    for where in ("local", "slurm"):
        best = {}
        for _ in range(a.reps):
            for n in (lo, hi):
                wall, runs = one_campaign(n, where)
                print(f"| {where} | {n} | {wall:.2f} | {runs:.2f} |")
                if n not in best or wall - runs < best[n]:
                    best[n] = wall - runs
        slope[where] = (best[hi] - best[lo]) / (hi - lo)
    print("\n| where | overhead per point outside its run (ms, best of reps, slope over the counts) |\n|---|---|")
    for where, s in slope.items():
        print(f"| {where} | {1e3 * s:.1f} |")


if __name__ == "__main__":
    main()
