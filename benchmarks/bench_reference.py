"""ns per bead-step of the reference solver (RK4 and velocity Verlet), N = 100, 1000, 10000.

Run by hand:  python benchmarks/bench_reference.py
A short pulse (I = 0.4 N s, T = 1 us) on a Hertz and on a bilinear (beta = 0.8) brass chain,
dt = 2e-8 s; the number of steps is chosen so that each run takes about a second. Median of 3.

Side by side with another version of the solver (a copy of an older granchain/reference/solver.py,
imported from its file; it must run against this tree's granchain):

    git show <commit>:granchain/reference/solver.py > /tmp/solver_old.py
    python benchmarks/bench_reference.py --compare /tmp/solver_old.py --reps 7

N = 100 and 10 000, old and new runs alternating (so that load on the machine hits both alike),
median of --reps each, the ratio of the medians new/old and the median of the ratios of the runs
taken back to back ("paired": the steadier on a shared machine).
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import sys

import numpy as np

from granchain.physics.laws import BilinearLaw, HertzLaw
from granchain.physics.materials import MATERIALS, bead_mass, hertz_stiffness
from granchain.reference.solver import ChainProblem, solve_chain

R = 4.76e-3
M = bead_mass(MATERIALS["brass"], R)
LAWS = {"hertz": HertzLaw(k=hertz_stiffness(MATERIALS["brass"], R)), "bilinear": BilinearLaw(k=2.43e7, beta=0.8)}


def bench(n: int, law: str, method: str, steps: int, dt: float = 2e-8) -> tuple[float, int]:
    p = ChainProblem(mass=np.full(n, M), law=LAWS[law], amplitude=4e5 if law == "hertz" else 1e5, duration=1e-6)
    times, extra = [], 0
    for _ in range(3):
        s = solve_chain(p, steps * dt, dt, method)
        times.append(s.wall_time)
        extra = s.extra_steps
    return statistics.median(times) / (steps * n) * 1e9, extra


def load_solver(path: str):
    """A solver module (solve_chain, ChainProblem) from a file."""
    spec = importlib.util.spec_from_file_location("solver_under_comparison", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def compare(old_path: str, reps: int) -> None:
    """ns per bead-step of the old and this tree's solver, alternating runs, median of reps each."""
    old = load_solver(old_path)
    solvers = {"old": old.solve_chain, "new": solve_chain}
    steps_of = {("rk4", 100): 5000, ("verlet", 100): 20000, ("rk4", 10000): 400, ("verlet", 10000): 2000}
    heads = ("old ns", "new ns", "new/old", "paired")
    print(f"{'law':9s} {'method':7s} {'N':>6s} {'steps':>6s} " + " ".join(f"{h:>8s}" for h in heads))
    for law in LAWS:
        for method in ("rk4", "verlet"):
            for n in (100, 10000):
                steps, dt = steps_of[method, n], 2e-8
                p = ChainProblem(
                    mass=np.full(n, M), law=LAWS[law], amplitude=4e5 if law == "hertz" else 1e5, duration=1e-6
                )
                times: dict[str, list[float]] = {"old": [], "new": []}
                for rep in range(reps):
                    # alternate which goes first, so that a drift in the machine's load hits both alike
                    for name in ("old", "new") if rep % 2 == 0 else ("new", "old"):
                        times[name].append(solvers[name](p, steps * dt, dt, method, progress=None).wall_time)
                ns = {k: statistics.median(v) / (steps * n) * 1e9 for k, v in times.items()}
                # the median of each pair's ratio: a pair ran back to back, under the same load
                paired = statistics.median(b / a for a, b in zip(times["old"], times["new"], strict=True))
                print(
                    f"{law:9s} {method:7s} {n:6d} {steps:6d} {ns['old']:8.1f} {ns['new']:8.1f} "
                    f"{ns['new'] / ns['old']:8.3f} {paired:8.3f}"
                )
                sys.stdout.flush()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--compare", metavar="SOLVER_PY", help="an older solver.py to time side by side")
    parser.add_argument("--reps", type=int, default=5, help="runs of each solver per case (--compare)")
    args = parser.parse_args()
    if args.compare:
        compare(args.compare, args.reps)
        return
    print(f"{'law':9s} {'method':7s} {'N':>6s} {'steps':>6s} {'ns/bead-step':>13s} {'extra steps':>11s}")
    for law in LAWS:
        for method in ("rk4", "verlet"):
            for n in (100, 1000, 10000):
                steps = {100: 20000, 1000: 5000, 10000: 1000}[n]
                ns, extra = bench(n, law, method, steps)
                print(f"{law:9s} {method:7s} {n:6d} {steps:6d} {ns:13.1f} {extra:11d}")
                sys.stdout.flush()


if __name__ == "__main__":
    main()
