"""Largest stable time step per integrator vs the planner's prediction, and long-run energy drift.

Stability: for each scene and integrator, bisect (geometrically) on dt / predicted limit for the
largest step whose run does not blow up: the state stays finite and no overlap passes half the
radius (the energy watch off: it would stop a run before it can blow up). Beside it, the largest
step the run watch lets through: both backends with the energy balance watched as in a real run
(5% of the running maximum of the energy put in).

Drift: a pulse trapped between the precompression push and a wall (10 beads, dt = 2e-8 s) runs
for 1e7 Verlet steps (reference and LAMMPS) and 1e6 RK4 steps; the energy error |E - W| / W is
reported over the first and the last tenth of the run. Run by hand:

    python benchmarks/bench_stability.py [stability|drift]
"""

from __future__ import annotations

import re
import sys
import time
from dataclasses import replace

import numpy as np

from granchain.cli import resolve_scene
from granchain.invariants import ENERGY_WATCH, InvariantError, contact_overlap_bounds
from granchain.lammps.runner import LammpsError, cleanup, invariant_from_lammps, run_deck
from granchain.reference.solver import ChainProblem, solve_chain
from granchain.scene import parse_scene
from granchain.templates import render_deck
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import run_scene

BETA99 = """
[chain]
beads = 60
radius = 4.76e-3
material = "brass"
[contact]
law = "bilinear"
unloading_coeff = 0.99
plastic_stiffness = 2.43e7
[loading]
kind = "impulse"
impulse = 0.1
duration = 1e-6
[run]
end_time = 6e-4
timestep = 1e-8
[outputs]
peak_force = true
"""


def scenes():
    yield "default (Hertz, I = 0.4 N s)", resolve_scene("default")
    yield "elastic step 40 N (Hertz)", resolve_scene("elastic-step-40N")
    yield "plastic short impulse (beta 0.8)", resolve_scene("plastic-short-impulse")
    yield "beta 0.99 short impulse", parse_scene(BETA99, source="beta99")


def outcome(sc, integrator: str, energy: bool) -> str:
    """'ok', 'energy' (the run watch's energy balance broke) or 'blow-up' (finite state or overlap).

    energy=False runs without the energy watch (it would stop a run before it can blow up)."""
    if integrator == "lammps":
        if energy:
            try:
                run_scene(sc, backend="lammps", force=True)
            except InvariantError as e:
                return "energy" if e.invariant == "energy balance" else "blow-up"
            return "ok"
        deck = render_deck(sc)
        text = re.sub(r"^fix             watch_energy .*$", "", deck.deck, flags=re.M)
        try:
            _, work = run_deck(text, deck.data)
            cleanup(work)
        except LammpsError as e:
            if invariant_from_lammps(e, sc) is None:
                raise
            return "blow-up"
        return "ok"
    with np.errstate(all="ignore"):
        try:
            solve_chain(
                ChainProblem.from_scene(sc),
                sc.run.end_time,
                sc.run.timestep,
                integrator,
                max_overlap=contact_overlap_bounds(sc),  # the run watch's: each contact's own radii
                # the run watch's own criterion: the running maximum of the energy put in
                energy_watch=ENERGY_WATCH if energy else None,
            )
        except InvariantError as e:
            return "energy" if e.invariant == "energy balance" else "blow-up"
    return "ok"


def largest(sc, integrator: str, limit: float, accept, energy: bool) -> float:
    lo, hi = 0.25, 16.0  # factors of the predicted limit
    at = lambda f: replace(sc, run=replace(sc.run, timestep=f * limit))  # noqa: E731
    if not accept(outcome(at(lo), integrator, energy)):
        return float("nan")
    while accept(outcome(at(hi), integrator, energy)):
        if hi >= 64:
            return hi  # (reported as a lower bound)
        hi *= 2
    for _ in range(10):
        mid = (lo * hi) ** 0.5
        if accept(outcome(at(mid), integrator, energy)):
            lo = mid
        else:
            hi = mid
    return lo


def stability() -> None:
    print(
        "| scene | integrator | predicted limit | largest without blow-up | ratio | largest inside the watch | ratio |"
    )
    print("|---|---|---|---|---|---|---|")
    for name, sc in scenes():
        for integrator in ("rk4", "verlet", "lammps"):
            limit = plan_scene(sc, method="rk4" if integrator == "rk4" else "verlet").stable_timestep
            f_blow = largest(sc, integrator, limit, lambda o: o != "blow-up", energy=False)
            f_watch = largest(sc, integrator, limit, lambda o: o == "ok", energy=True)
            print(
                f"| {name} | {integrator} | {limit:.3g} s | {f_blow * limit:.3g} s | {f_blow:.2f} | "
                f"{f_watch * limit:.3g} s | {f_watch:.2f} |",
                flush=True,
            )


TRAPPED = """
[chain]
beads = 10
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "impulse"
impulse = 0.1
duration = 1e-6
[run]
end_time = {end!r}
timestep = 2e-8
[outputs]
peak_force = true
[precompression]
force = 20.0
[boundary]
far_end = "wall"
"""


def drift() -> None:
    print("| integrator | steps | wall | max |E-W|/W, first tenth | last tenth | whole run |")
    print("|---|---|---|---|---|---|")
    for integrator, steps in (("lammps", 10_000_000), ("verlet", 10_000_000), ("rk4", 1_000_000)):
        sc = parse_scene(TRAPPED.format(end=steps * 2e-8), source="trapped")
        t0 = time.perf_counter()
        if integrator == "lammps":
            sol = run_scene(sc, backend="lammps").solution
        else:
            sol = run_scene(sc, method=integrator).solution
        wall = time.perf_counter() - t0
        w = max(float(np.max(np.abs(sol.work))), float(np.max(sol.kinetic + sol.potential)))
        e = np.abs(sol.energy_balance_error) / w
        n = len(e) // 10
        print(
            f"| {integrator} | {sol.steps} | {wall:.1f} s | {e[1 : n + 1].max():.2e} | {e[-n:].max():.2e} | "
            f"{e.max():.2e} |",
            flush=True,
        )


if __name__ == "__main__":
    what = sys.argv[1] if len(sys.argv) > 1 else "both"
    if what in ("stability", "both"):
        stability()
    if what in ("drift", "both"):
        drift()
