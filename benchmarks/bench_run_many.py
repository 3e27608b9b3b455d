"""granchain.run_many against a loop of granchain.run (issue 44 item 3): core time per point of the
same ensemble, each way in its own child process, in turns.

Run by hand:  python benchmarks/bench_run_many.py [--points 30] [--beads 20] [--backends lammps,reference]
              [--reps 2] [--no-bars]

The ensemble: --points brass Hertz chains of --beads beads, the impulse swept log-evenly over two
decades, end time and step "auto", error bars unless --no-bars, no run directories. Core time: the
child's CPU and its children's (LAMMPS), RUSAGE_CHILDREN, less the same child's imports and scene
building (measured by a child that stops there). The two ways' results are compared (summaries
without their clock keys) before the figures are printed.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
from pathlib import Path

CHILD = r"""
import json, sys, warnings
import granchain
from granchain import progress
way, backend, beads, points, bars = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5] == "1"
sys.path.append({root!r})
from tests.scenegen import brass_impulse_text
impulses = [0.004 * 100 ** (i / max(points - 1, 1)) for i in range(points)]
scenes = [granchain.parse_scene(brass_impulse_text(beads, j), source=f"p{{i}}.toml") for i, j in enumerate(impulses)]
if way == "none":
    sys.exit(0)
with progress.quiet(), warnings.catch_warnings():
    warnings.simplefilter("ignore")
    if way == "many":
        results = granchain.run_many(scenes, backend=backend, error_estimate=bars)
    else:
        results = [granchain.run(s, backend=backend, error_estimate=bars) for s in scenes]
clock = {{"wall_time", "price", "provenance", "companion_wall_time", "check_wall_time", "overhead", "extra"}}
def strip(d):
    if isinstance(d, dict):
        return {{k: strip(v) for k, v in d.items() if k not in clock}}
    return [strip(v) for v in d] if isinstance(d, list) else d
print(json.dumps([strip(dict(r.summary)) for r in results], sort_keys=True, default=str))
"""


def child(way: str, backend: str, beads: int, points: int, bars: bool) -> tuple[float, str]:
    """(core time of a child running the ensemble `way`, its printed summaries)."""
    root = Path(__file__).resolve().parent.parent
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            CHILD.format(root=str(root)),
            way,
            backend,
            str(beads),
            str(points),
            "1" if bars else "0",
        ],
        capture_output=True,
        text=True,
        env=dict(os.environ, GRANCHAIN_QUIET="1"),
        check=True,
    )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), done.stdout


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=30)
    ap.add_argument("--beads", type=int, default=20)
    ap.add_argument("--backends", default="lammps,reference")
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--no-bars", action="store_true")
    args = ap.parse_args()
    bars = not args.no_bars
    print(f"load average before: {os.getloadavg()[0]:.2f}", flush=True)
    rows = []
    for backend in args.backends.split(","):
        for rep in range(args.reps):
            base, _ = child("none", backend, args.beads, args.points, bars)
            single, out_single = child("single", backend, args.beads, args.points, bars)
            many, out_many = child("many", backend, args.beads, args.points, bars)
            assert out_single == out_many, "run_many's summaries differ from the single runs'"
            rows.append((backend, rep, base, single, many))
            print(f"  {backend} rep {rep + 1}: imports {base:.2f} s, single {single:.2f}, many {many:.2f}", flush=True)
    print(f"load average after: {os.getloadavg()[0]:.2f}\n")
    print(f"| backend | rep | points x beads | single (ms/point) | run_many (ms/point) | many / single | (bars {bars})")
    print("|---|---|---|---|---|---|")
    for backend, rep, base, single, many in rows:
        s, m = 1e3 * (single - base) / args.points, 1e3 * (many - base) / args.points
        print(f"| {backend} | {rep + 1} | {args.points} x {args.beads} | {s:.0f} | {m:.0f} | {m / s:.2f} |")


if __name__ == "__main__":
    main()
