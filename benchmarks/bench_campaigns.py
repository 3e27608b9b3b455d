"""What campaigns cost (issue 16): the speed-up of 2 local Dask workers over 1, and the machinery's
own time per point.

Run by hand:  python benchmarks/bench_campaigns.py [--points 40] [--trivial 200] [--reps 1] [--skip-lammps]
              [--skip-overhead] [--reuse N] [--reuse-reps 3] [--only-reuse]

1. speed-up: a campaign of --points small LAMMPS points (a 20-bead Hertz chain, 2000 steps, no error
   estimate; about 1 s each, mostly LAMMPS's process start-up), run into a fresh workspace with
   --workers 1 and --workers 2, in turns (--reps times each); the wall time of run_campaign from the
   call to the table written (the local cluster's start included) and the sum of the points' own
   run_scene times (task.json run_time).
2. overhead: a campaign of --trivial trivial points (a 2-bead chain, 10 reference Verlet steps) on one
   worker: the wall time, split into validation (every point made, read as a scene, planned, its
   time step checked), the cluster's start, and per point: the rest minus the runs themselves
   (run_scene, run directory included), i.e. job directory, submission, the task's bookkeeping
   (task.json), result collection, progress and the table; then the same campaign again, all cached
   (no cluster: the check that everything is complete, and the table).
3. reuse (issue 18 item 4): a campaign of --reuse tiny LAMMPS points (TINY: a 10-bead Hertz chain,
   200 steps, the peak table only) on one worker, with each point in a fresh LAMMPS process
   (Executor.reuse_lammps = False, as before) and on the worker's kept LAMMPS child (the default), in
   turns (fresh, reused, fresh, ...; --reuse-reps each). Per point: the overhead outside the
   integration = the point's wall time in its worker (task.json wall_time: run_point, scene made,
   planned, run, results read, run directory written) minus LAMMPS's loop time (log.lammps, summary.json
   extra.loop_time); its median and the ratio reused / fresh. Also per point: the campaign's wall
   time less the local cluster's start, over the points, less the mean loop time (the driver's share
   included).
Prints one markdown table per part (the figures in benchmarks/RESULTS.md come from here).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

from granchain.campaigns import execute
from granchain.campaigns.run import run_campaign, validate
from granchain.campaigns.spec import parse_campaign

SMALL = """
[chain]
beads = 20
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "step"
amplitude = 10.0
duration = 1e-6
[run]
end_time = 1e-4
timestep = 5e-8
[outputs]
peak_force = true
histories = [5]
"""

TRIVIAL = """
[chain]
beads = 2
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "step"
amplitude = 10.0
duration = 1e-7
[run]
end_time = 1e-7
timestep = 1e-8
[outputs]
peak_force = true
"""

TINY = """
[chain]
beads = 10
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "step"
amplitude = 10.0
duration = 1e-6
[run]
end_time = 1e-5
timestep = 5e-8
[outputs]
peak_force = true
"""


def campaign(scene: str, backend: str, n: int):
    inline = scene.replace("\n[", "\n[scene.")
    method = "" if backend == "lammps" else 'method = "verlet"\n'
    text = (
        f'[campaign]\nbackend = "{backend}"\n{method}error_estimate = false\n'
        f'[vary]\n"loading.amplitude" = {{ linear = [1.0, 100.0], num = {n} }}\n[scene]\n{inline}'
    )
    return parse_campaign(text, source=f"<bench {backend} {n}>")


def run_times(ws: Path) -> list[float]:
    out = []
    for d in (ws / "workspace").iterdir():
        rec = json.loads((d / "task.json").read_text())
        out.append(rec["run_time"])
    return out


def timed(c, ws: Path, workers: int) -> tuple[float, object]:
    t = time.perf_counter()
    _, report = run_campaign(c, ws, workers=workers)
    return time.perf_counter() - t, report


def cluster_start(workers: int) -> float:
    ex = execute.Executor(workers=workers)
    t = time.perf_counter()
    ex.start()
    ex.client.wait_for_workers(workers)
    dt = time.perf_counter() - t
    ex.close()
    return dt


def speedup(n: int, reps: int, root: Path) -> None:
    c = campaign(SMALL, "lammps", n)
    rows = []
    for rep in range(reps):
        for workers in (1, 2):
            ws = root / f"lammps-{workers}-{rep}"
            wall, report = timed(c, ws, workers)
            assert report.done == n, report
            rows.append((workers, wall, sum(run_times(ws))))
    print(f"\n### {n} LAMMPS points (20 beads, 2000 steps each), {os.cpu_count()} cores\n")
    print("| workers | wall (s) | sum of runs (s) | points/s |")
    print("|---|---|---|---|")
    for workers, wall, runs in rows:
        print(f"| {workers} | {wall:.1f} | {runs:.1f} | {n / wall:.2f} |")
    best = {w: min(r[1] for r in rows if r[0] == w) for w in (1, 2)}
    print(f"\nspeed-up (best of {reps}): {best[1] / best[2]:.2f}")


def overhead(n: int, root: Path) -> None:
    c = campaign(TRIVIAL, "reference", n)
    t = time.perf_counter()
    validate(c)
    t_validate = time.perf_counter() - t
    t_start = cluster_start(1)
    ws = root / "trivial"
    wall, report = timed(c, ws, 1)
    assert report.done == n, report
    runs = sum(run_times(ws))
    cached, report2 = timed(c, ws, 1)
    assert report2.ran == 0
    per = (wall - t_start - runs) / n
    print(f"\n### {n} trivial points (2 beads, 10 reference Verlet steps), 1 worker\n")
    print("| part | s | per point (ms) |")
    print("|---|---|---|")
    print(f"| campaign run, wall | {wall:.2f} | {1e3 * wall / n:.1f} |")
    print(f"| of which validation (points made, planned, checked) | {t_validate:.2f} | {1e3 * t_validate / n:.2f} |")
    print(f"| of which the local cluster's start (measured apart) | {t_start:.2f} | - |")
    print(f"| of which the runs themselves (run_scene + run directory) | {runs:.2f} | {1e3 * runs / n:.1f} |")
    print(f"| the machinery: wall - cluster start - runs | {wall - t_start - runs:.2f} | {1e3 * per:.1f} |")
    print(f"| the same campaign again, all {n} cached | {cached:.2f} | {1e3 * cached / n:.1f} |")


def point_overheads(ws: Path) -> list[tuple[float, float]]:
    """(wall time of run_point, LAMMPS loop time) of every point of a workspace, s."""
    out = []
    for d in (ws / "workspace").iterdir():
        rec = json.loads((d / "task.json").read_text())
        extra = json.loads((d / "run" / "summary.json").read_text())["extra"]
        out.append((rec["wall_time"], extra["loop_time"]))
    return out


def reuse(n: int, reps: int, root: Path) -> None:
    c = campaign(TINY, "lammps", n)
    validate(c)
    t_start = cluster_start(1)
    rows = []
    for rep in range(reps):
        for reused in (False, True):
            execute.Executor.reuse_lammps = reused
            try:
                ws = root / f"reuse-{int(reused)}-{rep}"
                wall, report = timed(c, ws, 1)
            finally:
                execute.Executor.reuse_lammps = True
            assert report.done == n, report
            pts = point_overheads(ws)
            over = sorted(w - loop for w, loop in pts)
            loops = [loop for _, loop in pts]
            rows.append(
                {
                    "reused": reused,
                    "median": statistics.median(over),
                    "p90": over[int(0.9 * (len(over) - 1))],
                    "loop": statistics.median(loops),
                    "campaign": (wall - t_start) / n - statistics.mean(loops),
                    "wall": wall,
                }
            )
    print(f"\n### {n} tiny LAMMPS points (10 beads, 200 steps, peak table only), 1 worker, in turns\n")
    print(
        "| rep | LAMMPS process | overhead per point, median (ms) | p90 (ms) | loop time per point (ms) "
        "| (campaign wall - cluster start) / points - loop (ms) | campaign wall (s) |"
    )
    print("|---|---|---|---|---|---|---|")
    for k, r in enumerate(rows):
        print(
            f"| {k // 2 + 1} | {'reused' if r['reused'] else 'fresh'} | {1e3 * r['median']:.1f} | {1e3 * r['p90']:.1f} "
            f"| {1e3 * r['loop']:.2f} | {1e3 * r['campaign']:.1f} | {r['wall']:.1f} |"
        )
    ratios = [b["median"] / a["median"] for a, b in zip(rows[::2], rows[1::2], strict=True)]
    print(
        f"\nreused / fresh, median overhead per point: {', '.join(f'{x:.3f}' for x in ratios)} "
        f"(median {statistics.median(ratios):.3f}); local cluster start {t_start:.2f} s (measured apart)"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=40)
    ap.add_argument("--trivial", type=int, default=200)
    ap.add_argument("--reps", type=int, default=1)
    ap.add_argument("--skip-lammps", action="store_true")
    ap.add_argument("--skip-overhead", action="store_true")
    ap.add_argument("--reuse", type=int, default=40, help="points of the reuse comparison (0: skip it)")
    ap.add_argument("--reuse-reps", type=int, default=3)
    ap.add_argument("--only-reuse", action="store_true", help="only the reuse comparison")
    args = ap.parse_args()
    os.environ.setdefault("GRANCHAIN_QUIET", "1")
    with tempfile.TemporaryDirectory(prefix="bench-campaigns-") as tmp:
        root = Path(tmp)
        print(f"load average before: {os.getloadavg()[0]:.2f}")
        if not args.skip_overhead and not args.only_reuse:
            overhead(args.trivial, root)
        if not args.skip_lammps and not args.only_reuse:
            speedup(args.points, args.reps, root)
        if args.reuse:
            reuse(args.reuse, args.reuse_reps, root)
        print(f"\nload average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
