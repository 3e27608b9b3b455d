"""The price of the per-run error estimate: the companions' wall time over the run's, in one run.

    python benchmarks/bench_error_estimate.py [--reps 3]

For each law on each backend the scene runs as `granchain run` runs it (planned for rtol 1e-3, then
the companions: at 2 dt and 4 dt, or RK4 runs for a Verlet run on a kinked law); the table gives the run's wall time, the companions' and their ratio (best of
the repetitions for each). Expected from the step counts alone: 1/2 + 1/4 = 0.75; LAMMPS pays its
start-up (process, plugin load) once more per companion, which dominates small runs.
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

os.environ.setdefault("GRANCHAIN_QUIET", "1")

from granchain.cli import resolve_scene  # noqa: E402
from granchain.workflows.run import run_scene  # noqa: E402

#: every law on every backend (the short impulse of each law's bundled scene), and the long loads
CASES = [
    ("default", "reference", "rk4"),
    ("default", "reference", "verlet"),
    ("default", "lammps", None),
    ("plastic-short-impulse", "reference", "rk4"),
    ("plastic-short-impulse", "reference", "verlet"),
    ("plastic-short-impulse", "lammps", None),
    ("thornton-short-impulse", "reference", "rk4"),
    ("thornton-short-impulse", "reference", "verlet"),
    ("thornton-short-impulse", "lammps", None),
    ("classic-two-spheres", "reference", "rk4"),
    ("classic-two-spheres", "lammps", None),
    ("elastic-step-40N", "lammps", None),
    ("plastic-long-load-table1", "lammps", None),
]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=3)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    print("| scene | backend | run (s) | companions (s) | ratio |")
    print("|---|---|---|---|---|")
    for name, backend, method in CASES:
        best_run, best_comp = float("inf"), float("inf")
        for _ in range(args.reps):
            t0 = time.perf_counter()
            r = run_scene(resolve_scene(name), backend=backend, method=method, rtol=1e-3, error_estimate=True)
            total = time.perf_counter() - t0
            comp = sum(r.errors.wall_times)
            best_run, best_comp = min(best_run, total - comp), min(best_comp, comp)
        label = backend if method is None else f"{backend} {method}"
        print(f"| {name} | {label} | {best_run:.3g} | {best_comp:.3g} | {best_comp / best_run:.2f} |")


if __name__ == "__main__":
    main()
