"""ns per bead-step of the reference solver (RK4 and velocity Verlet), N = 100, 1000, 10000.

Run by hand:  python benchmarks/bench_reference.py
A short pulse (I = 0.4 N s, T = 1 us) on a Hertz and on a bilinear (beta = 0.8) brass chain,
dt = 2e-8 s; the number of steps is chosen so that each run takes about a second. Median of 3.
"""

from __future__ import annotations

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


def main() -> None:
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
