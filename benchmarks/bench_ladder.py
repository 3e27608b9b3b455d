"""The price of the crossing-time ladder in the reference solver (Verlet), side by side in one run: the
300-bead brass chain at F0 = 100 N with a 0.1 N step of 1 s (docs/observables.md), planned for Verlet,
solved with the ladder and without it (the leading pulse alone), alternating, in a fresh process each.

    python benchmarks/bench_ladder.py [--reps 5] [--tree DIR]

--tree runs another granchain checkout's solver instead of this one (a worktree of an older commit), for
a before/after. Prints the best and the median CPU time of the solve of each (the process's CPU time:
on a shared machine wall times moved by 1.5x between repetitions; noise is one-sided, the best is the
figure to compare), their ratio, the leading pulse's floor and the rungs crossed.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
from pathlib import Path

SCENE = """
[chain]
beads = 300
radius = 0.00476
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "step"
amplitude = 0.1
duration = 1.0
[run]
end_time = "auto"
timestep = "auto"
[precompression]
force = 100.0
[outputs]
peak_force = true
"""

CHILD = r"""
import sys, time
sys.path.insert(0, sys.argv[1])
from granchain.scene import parse_scene
from granchain.workflows.run import plan_for
from granchain.reference.solver import ChainProblem, solve_chain
from granchain.peaks import lead_floor, stop_force_floor
import granchain.reference.observers as observers
sc, _ = plan_for(parse_scene(sys.argv[2]), "reference", "verlet")
if sys.argv[3] == "without":
    observers.CrossingLadder = lambda *a, **k: None  # LeadingPulse then runs without a ladder
p = ChainProblem.from_scene(sc)
kw = dict(lead_floor=lead_floor(sc), stop_after=sc.run.stop_after_contact - 1, stop_floor=stop_force_floor(sc))
t = time.process_time()
sol = solve_chain(p, sc.run.end_time, sc.run.timestep, "verlet", **kw)
wall = time.process_time() - t
ladder = getattr(sol, "front_ladder", None)
rungs = int(ladder[:, 0].sum()) if ladder is not None and ladder.size else 0
print(wall, kw["lead_floor"], sol.steps, rungs)
"""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--tree", default=str(Path(__file__).resolve().parents[1]))
    args = ap.parse_args()
    walls: dict[str, list[float]] = {"with": [], "without": []}
    info: dict[str, tuple[str, str, str]] = {}
    for _ in range(args.reps):
        for mode in walls:
            out = subprocess.run(
                [sys.executable, "-c", CHILD, args.tree, SCENE, mode],
                capture_output=True,
                text=True,
                check=True,
                env={"GRANCHAIN_QUIET": "1", "PATH": ""},
            )
            wall, floor, steps, rungs = out.stdout.split()[-4:]
            walls[mode].append(float(wall))
            info[mode] = (floor, steps, rungs)
    floor, steps, rungs = info["with"]
    print(f"tree {args.tree}: floor {float(floor):.3g} N, {steps} steps, {rungs} rungs crossed")
    print("| reference Verlet | best CPU (s) | median CPU (s) |")
    print("|---|---|---|")
    for mode, w in walls.items():
        print(f"| {mode} ladder | {min(w):.3f} | {statistics.median(w):.3f} |")
    print(f"ratio with / without (best): {min(walls['with']) / min(walls['without']):.2f}")


if __name__ == "__main__":
    main()
