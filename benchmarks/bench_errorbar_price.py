"""The error bar's price per contact law and backend: the companions' wall time over the run's.

    python benchmarks/bench_errorbar_price.py [--reps 3] [--cases hertz,bilinear,thornton] [--long]

Each law's bundled short impulse runs as ``granchain run SCENE --rtol 1e-3`` runs it on every backend
(LAMMPS, reference RK4, reference Verlet), with its error bars; the price is summary.json's
``price.error_estimate`` (the companions' wall time) over ``price.wall_time`` (the run's: for LAMMPS its
start-up, setup, integration and output; for the reference its integration). Both come from the same
run, side by side, so the ratio holds under load where the absolute times do not. Each cell gives the
median ratio over the repetitions and its range, and what the companions were (Richardson at 2 dt and
4 dt; bounds from 2 dt and 4 dt for Verlet on a kinked law, or RK4 at multiples of the run's dt with
error_estimate="checked").

On a loaded machine wall times swing with the other processes; the CPU column is the same ratio in
CPU time (this process and its LAMMPS children, ended or alive: the kept LAMMPS child outlives the
run): the companions' (inside estimate_errors) over everything else of the run (planning and writing
included, so slightly more than the run's own).

--long adds the long loads (elastic-step-40N, plastic-long-load-table1 on LAMMPS) and two spheres
(classic-two-spheres: LAMMPS's start-up is all of the run).
"""

from __future__ import annotations

import argparse
import os
import statistics
import warnings
from contextlib import contextmanager

import psutil

os.environ.setdefault("GRANCHAIN_QUIET", "1")

from granchain.cli import resolve_scene  # noqa: E402
from granchain.workflows import error_estimates as errors  # noqa: E402
from granchain.workflows.run import run_scene  # noqa: E402

#: law -> its bundled short impulse
SCENES = {"hertz": "default", "bilinear": "plastic-short-impulse", "thornton": "thornton-short-impulse"}
#: (label, backend, method)
BACKENDS = (
    ("lammps", "lammps", None),
    ("reference rk4", "reference", "rk4"),
    ("reference verlet", "reference", "verlet"),
)
LONG = (
    ("hertz", "elastic-step-40N", "lammps", None),
    ("bilinear", "plastic-long-load-table1", "lammps", None),
    ("hertz", "classic-two-spheres", "lammps", None),
)


def cpu() -> float:
    """CPU seconds of this process and its children (LAMMPS runs) so far: the reaped ones (os.times) and
    the live ones (psutil: the kept LAMMPS child a run and its companions share lives on)."""
    t = os.times()
    live = 0.0
    for child in psutil.Process().children(recursive=True):
        try:
            c = child.cpu_times()
        except psutil.Error:  # (ended in between: reaped, in os.times next time)
            continue
        live += c.user + c.system
    return t.user + t.system + t.children_user + t.children_system + live


@contextmanager
def companions_cpu(spent: list):
    """While inside, the CPU time of every estimate_errors call (the companions) is added to spent."""
    real = errors.estimate_errors

    def timed(*args, **kwargs):
        t0 = cpu()
        try:
            return real(*args, **kwargs)
        finally:
            spent.append(cpu() - t0)

    errors.estimate_errors = timed
    try:
        yield
    finally:
        errors.estimate_errors = real


def price_of(scene_name: str, backend: str, method: str | None) -> tuple[float, float, float, str]:
    """(run wall time, companions' wall time, companions' CPU over the rest's, the companions' steps as
    multiples of dt) of one run."""
    spent: list[float] = []
    t0 = cpu()
    with companions_cpu(spent):
        r = run_scene(resolve_scene(scene_name), backend=backend, method=method, rtol=1e-3, error_estimate=True)
    total = cpu() - t0
    price = r.price()
    dt = r.scene.run.timestep
    kind = "RK4 " if r.errors.against == "rk4" else "bounds, " if r.errors.bound else ""
    steps = kind + ", ".join(f"{t / dt:.3g}" for t in r.errors.timesteps) + " dt"
    comp = sum(spent)
    return float(price["wall_time"]), float(price["error_estimate"] or 0.0), comp / (total - comp), steps


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--cases", default=",".join(SCENES), help="laws, comma-separated")
    ap.add_argument("--long", action="store_true", help="also the long loads and two spheres")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    cases = [(law, SCENES[law], b, m, label) for law in args.cases.split(",") for label, b, m in BACKENDS]
    if args.long:
        cases += [(law, name, b, m, b) for law, name, b, m in LONG]
    print("| law | scene | backend | run (s) | companions (s) | price: median (min - max) | CPU | companions at |")
    print("|---|---|---|---|---|---|---|---|")
    for law, name, backend, method, label in cases:
        got = [price_of(name, backend, method) for _ in range(args.reps)]
        ratios = [c / r for r, c, _, _ in got]
        run = statistics.median(g[0] for g in got)
        comp = statistics.median(g[1] for g in got)
        cpu_ratio = statistics.median(g[2] for g in got)
        print(
            f"| {law} | {name} | {label} | {run:.3g} | {comp:.3g} | {statistics.median(ratios):.2f} "
            f"({min(ratios):.2f} - {max(ratios):.2f}) | {cpu_ratio:.2f} | {got[0][3]} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
