"""The price of the reference solver's in-run tracking (complete peaks, leading pulse, progress),
side by side against an older granchain tree, in one run, as ratios.

    git worktree add /tmp/wt-old 1b19874      # the tree before the tracking
    python benchmarks/bench_tracking.py /tmp/wt-old [--reps 5]

Each repetition runs the default scene in a fresh process per tree, alternating, Verlet at 5e-8 s
and RK4 at 2e-7 s; the best of the repetitions is compared (noise on a shared machine is one-sided).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

CHILD = r"""
import sys, time
sys.path.insert(0, sys.argv[1])
from granchain.scene import parse_scene
from granchain.reference.solver import ChainProblem, solve_chain
import inspect
from granchain.reference import solver
sc = parse_scene(open(sys.argv[2]).read())
p = ChainProblem.from_scene(sc)
method, dt = sys.argv[3], float(sys.argv[4])
kw = {}
if "lead_floor" in inspect.signature(solver._solve).parameters:  # as a run passes it
    from granchain.templates import lead_floor
    kw["lead_floor"] = lead_floor(sc)
t = time.perf_counter()
solve_chain(p, 7e-4, dt, method, **kw)
print(time.perf_counter() - t)
"""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("old", help="an older granchain checkout (a git worktree)")
    ap.add_argument("--reps", type=int, default=5)
    args = ap.parse_args()
    new = Path(__file__).resolve().parents[1]
    scene = new / "granchain" / "scenes" / "default.toml"
    print("| method | old tree (s) | this tree (s) | ratio |")
    print("|---|---|---|---|")
    for method, dt in (("verlet", "5e-8"), ("rk4", "2e-7")):
        best = {"old": float("inf"), "new": float("inf")}
        for _ in range(args.reps):
            for name, tree in (("old", args.old), ("new", str(new))):
                out = subprocess.run(
                    [sys.executable, "-c", CHILD, tree, str(scene), method, dt],
                    capture_output=True,
                    text=True,
                    check=True,
                    env={"GRANCHAIN_QUIET": "1", "PATH": ""},
                )
                best[name] = min(best[name], float(out.stdout.split()[-1]))
        print(f"| {method} | {best['old']:.3f} | {best['new']:.3f} | {best['new'] / best['old']:.2f} |")


if __name__ == "__main__":
    main()
