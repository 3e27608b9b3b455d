"""ns per bead-step of the reference solver (RK4 and velocity Verlet), N = 100, 1000, 10000.

Run by hand:  python benchmarks/bench_reference.py
A short pulse (I = 0.4 N s, T = 1 us) on a Hertz and on a bilinear (beta = 0.8) brass chain,
dt = 2e-8 s; the number of steps is chosen so that each run takes about a second. Median of 3.

Side by side with another tree of granchain (an older commit checked out as a worktree):

    git worktree add /tmp/ref_old <commit>
    python benchmarks/bench_reference.py --compare /tmp/ref_old --reps 5

Each tree runs in its own worker process (this script with --worker and PYTHONPATH set to the tree,
so that every module of the solver, not only solver.py, is that tree's), kept for the whole
comparison; the runs alternate between the two (old first in even repetitions, new first in odd
ones), so that load on a shared machine hits both alike. Per case: the median ns per bead-step of
each, the ratio of the medians new/old and the median of the ratios of the runs taken back to back
("paired": the steadier on a shared machine). --scene NAME adds the reference run of a scene as
granchain compare makes it (seconds instead of ns per bead-step), --companions 2,4 also its RK4
error-bar companions at 2 dt and 4 dt (compare runs them on a second core); --methods "" --sizes ""
times the scenes only. --clock cpu times each run by
its process's CPU time instead of the wall clock: steadier when more processes than cores compete
(helpers, CI), and what a single-threaded numpy solver costs when it has a core to itself.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

#: (law, method, N) -> steps: each run about a second (or less) on a quiet machine
STEPS = {100: 20000, 1000: 5000, 10000: 1000}
R = 4.76e-3


def _problem(law: str, n: int):
    import numpy as np

    from granchain.physics.laws import BilinearLaw, HertzLaw
    from granchain.physics.materials import MATERIALS, bead_mass, hertz_stiffness
    from granchain.problem import ChainProblem

    laws = {"hertz": HertzLaw(k=hertz_stiffness(MATERIALS["brass"], R)), "bilinear": BilinearLaw(k=2.43e7, beta=0.8)}
    m = bead_mass(MATERIALS["brass"], R)
    return ChainProblem(mass=np.full(n, m), law=laws[law], amplitude=4e5 if law == "hertz" else 1e5, duration=1e-6)


def run_case(law: str, method: str, n: int, steps: int, dt: float = 2e-8, clock: str = "wall") -> tuple[float, int]:
    """One run: (ns per bead-step, extra steps); clock "wall" (the solution's wall_time) or "cpu"
    (this process's CPU time around the call: steadier when more processes than cores compete)."""
    import time

    from granchain.reference.solver import solve_chain

    problem = _problem(law, n)
    c0 = time.process_time()
    s = solve_chain(problem, steps * dt, dt, method, progress=None)
    seconds = s.wall_time if clock == "wall" else time.process_time() - c0
    return seconds / (steps * n) * 1e9, s.extra_steps


def run_scene(name: str, method: str, clock: str = "wall", factor: int = 1) -> float:
    """Seconds (wall or cpu) of a scene's reference run, as granchain compare makes it (run_reference);
    factor 2 or 4: its RK4 error-bar companion at that multiple of the step (compare runs those too)."""
    import time

    from granchain.scene import load_scene
    from granchain.workflows.error_estimates import companion_scene
    from granchain.workflows.run import plan_for, run_reference

    scene = load_scene(name)
    if factor != 1:
        scene = companion_scene(plan_for(scene, "reference", method, None)[0], float(factor))
    timer = time.perf_counter if clock == "wall" else time.process_time
    t = timer()
    run_reference(scene, method)
    return timer() - t


def worker() -> None:
    """Serve runs read from stdin, one JSON list a line; answer one JSON number a line."""
    import granchain

    print(json.dumps(str(Path(granchain.__file__).parent.parent)), flush=True)  # the tree it imports
    os.environ["GRANCHAIN_QUIET"] = "1"  # no progress lines from scene runs
    for line in sys.stdin:
        job = json.loads(line)
        clock = job.pop()
        if job[0] == "scene":
            out: float = run_scene(job[1], job[2], clock, *job[3:])
        else:
            out = run_case(*job, clock=clock)[0]
        print(json.dumps(out), flush=True)


class Worker:
    """A worker process importing granchain from `tree`."""

    def __init__(self, tree: str) -> None:
        env = dict(os.environ, PYTHONPATH=str(Path(tree).resolve()))
        self.proc = subprocess.Popen(
            [sys.executable, __file__, "--worker"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,  # progress of scene runs
            text=True,
            env=env,
            cwd=tree,
        )
        self.tree = json.loads(self.proc.stdout.readline())

    def run(self, job: list) -> float:
        self.proc.stdin.write(json.dumps(job) + "\n")
        self.proc.stdin.flush()
        return float(json.loads(self.proc.stdout.readline()))

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait()


def compare(
    old_tree: str,
    reps: int,
    sizes: list[int],
    scenes: list[str],
    new_tree: str | None = None,
    methods=("rk4", "verlet"),
    clock: str = "wall",
    companions: tuple[int, ...] = (),
) -> None:
    """The old tree and the new one (default this one) side by side: alternating runs, median of reps
    each, ratios."""
    workers = {"old": Worker(old_tree), "new": Worker(new_tree or str(Path(__file__).resolve().parent.parent))}
    print(f"old: {workers['old'].tree}\nnew: {workers['new'].tree}")
    heads = ("old", "new", "new/old", "paired")
    print(f"{'case':32s} " + " ".join(f"{h:>8s}" for h in heads) + f"   ({clock}: ns per bead-step; scenes: s)")
    cases: list[tuple[str, list]] = []
    for law in ("hertz", "bilinear"):
        for method in methods:
            for n in sizes:
                cases.append((f"{law} {method} N={n}", [law, method, n, STEPS[n]]))
    for name in scenes:
        cases.append((f"scene {name}", ["scene", name, "rk4"]))
        for factor in companions:
            cases.append((f"scene {name} at {factor} dt", ["scene", name, "rk4", factor]))
    try:
        for label, job in cases:
            times: dict[str, list[float]] = {"old": [], "new": []}
            for rep in range(reps):
                for name in ("old", "new") if rep % 2 == 0 else ("new", "old"):
                    times[name].append(workers[name].run([*job, clock]))
            med = {k: statistics.median(v) for k, v in times.items()}
            paired = statistics.median(b / a for a, b in zip(times["old"], times["new"], strict=True))
            print(f"{label:32s} {med['old']:8.1f} {med['new']:8.1f} {med['new'] / med['old']:8.3f} {paired:8.3f}")
            sys.stdout.flush()
    finally:
        for w in workers.values():
            w.close()


def table(clock: str = "wall") -> None:
    """The table of this tree: ns per bead-step, median of 3 runs."""
    print(f"{'law':9s} {'method':7s} {'N':>6s} {'steps':>6s} {'ns/bead-step':>13s} {'extra steps':>11s}")
    for law in ("hertz", "bilinear"):
        for method in ("rk4", "verlet"):
            for n in (100, 1000, 10000):
                steps = STEPS[n]
                runs = [run_case(law, method, n, steps, clock=clock) for _ in range(3)]
                ns = statistics.median(r[0] for r in runs)
                print(f"{law:9s} {method:7s} {n:6d} {steps:6d} {ns:13.1f} {runs[0][1]:11d}")
                sys.stdout.flush()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--compare", metavar="TREE", help="another granchain tree (a worktree) to time side by side")
    parser.add_argument("--reps", type=int, default=5, help="runs of each tree per case (--compare)")
    parser.add_argument("--sizes", default="100,1000,10000", help="chain lengths (--compare)")
    parser.add_argument("--scene", action="append", default=[], help="also a scene's reference run (--compare)")
    parser.add_argument(
        "--companions",
        default="",
        help="also each --scene's RK4 companions at these multiples of its step, e.g. 2,4 (compare runs them)",
    )
    parser.add_argument("--new", metavar="TREE", help="the tree to compare with --compare's (default: this one)")
    parser.add_argument("--methods", default="rk4,verlet", help="integrators (--compare)")
    parser.add_argument(
        "--clock",
        choices=("wall", "cpu"),
        default="wall",
        help="wall time, or the process's CPU time (steadier under load)",
    )
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker()
    elif args.compare:
        sizes = [int(s) for s in args.sizes.split(",") if s]
        companions = tuple(int(f) for f in args.companions.split(",") if f)
        methods = tuple(m for m in args.methods.split(",") if m)
        compare(args.compare, args.reps, sizes, args.scene, args.new, methods, args.clock, companions)
    else:
        table(args.clock)


if __name__ == "__main__":
    main()
