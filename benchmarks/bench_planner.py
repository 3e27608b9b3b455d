"""The paper's own setup vs the planner, at the same measured accuracy (issue 5's benchmark).

Paper setup: RK4 at dt = 5e-9 s on a fixed 1000-bead chain for a fixed end time, the force of the
measured contacts stored every step (peaks taken from the stored samples). Planner: beads, end time
and time step chosen by granchain for the rtol that the paper setup achieves (and, as the practical
case, for rtol = 1e-3, with RK4 and with LAMMPS's Verlet), early stop. Errors of the measured
contacts' peak forces are measured against a converged RK4 run (dt = 2.5e-9 s) on the planner's
chain. Run by hand:

    python benchmarks/bench_planner.py [SUBSTRING]   # only the cases whose name contains SUBSTRING
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from granchain.reference.solver import ChainProblem, solve_chain
from granchain.scene import parse_scene
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import run_scene

BASE = """
[chain]
beads = "auto"
radius = 4.76e-3
material = "brass"
[contact]
{contact}
[loading]
{loading}
[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = [{contacts}]
"""
CASES = {
    "elastic short pulse (Sec. II B)": (
        'law = "hertz"',
        'kind = "impulse"\nimpulse = 0.4\nduration = 1e-6',
        "20, 40, 60",
    ),
    "elastic long load (Sec. II C, A = 40 N)": (
        'law = "hertz"',
        'kind = "step"\namplitude = 40.0\nduration = 1e-2',
        "20, 60, 100",
    ),
    "Table I (Sec. III B)": (
        'law = "bilinear"\nunloading_coeff = 0.8\nplastic_stiffness = 2.43e7',
        'kind = "step"\namplitude = 8000.0\nduration = 2.5e-3',
        "50, 150, 300",
    ),
}
PAPER_DT, PAPER_BEADS = 5e-9, 1000


def main(only: str = "") -> None:
    rows = []
    for name, (contact, loading, contacts) in CASES.items():
        if only not in name:
            continue
        auto = parse_scene(BASE.format(contact=contact, loading=loading, contacts=contacts), source=name)
        planned = plan_scene(auto, rtol=1e-3).scene
        idx = np.asarray(planned.peak_contacts) - 1
        end = planned.run.end_time
        # the paper's setup: fixed long chain, dt = 5e-9, every step stored for the measured contacts
        paper_sc = replace(
            planned,
            chain=replace(planned.chain, beads=PAPER_BEADS),
            run=replace(planned.run, timestep=PAPER_DT, stop_after_contact=None),
        )
        t0 = time.perf_counter()
        paper = solve_chain(ChainProblem.from_scene(paper_sc), end, PAPER_DT, "rk4", histories=tuple(idx))
        paper_wall = time.perf_counter() - t0
        paper_peaks = paper.history_force.max(axis=0)  # peak = largest stored sample, as from output files
        conv = solve_chain(ChainProblem.from_scene(paper_sc), end, PAPER_DT / 2, "rk4")
        exact = conv.peak_force[idx]
        paper_err = float(np.max(np.abs(paper_peaks - exact) / exact))
        for label, rtol, backend in (
            ("same accuracy", max(paper_err, 1e-12), "reference"),
            ("rtol 1e-3", 1e-3, "reference"),
            ("rtol 1e-3, LAMMPS", 1e-3, "lammps"),
        ):
            method = "verlet" if backend == "lammps" else "rk4"
            sc = plan_scene(auto, rtol=rtol, method=method).scene
            if backend == "lammps":
                run_scene(sc, backend=backend)  # plugin build and file caches warm
            t0 = time.perf_counter()
            got = run_scene(sc, backend=backend).solution  # LAMMPS: wall includes its start-up
            wall = time.perf_counter() - t0
            err = float(np.max(np.abs(got.peak_force[idx] - exact) / exact))
            rows.append(
                (
                    name,
                    label,
                    paper.steps * PAPER_BEADS,
                    paper_wall,
                    paper_err,
                    (got.steps + got.extra_steps) * sc.chain.beads,
                    wall,
                    err,
                )
            )
            r = rows[-1]
            print(
                f"{name} | {label}: paper {r[2]:.3g} bead-steps {r[3]:.3g} s err {r[4]:.1e} | planner "
                f"{r[5]:.3g} bead-steps {r[6]:.3g} s err {r[7]:.1e} | ratio bead-steps {r[2] / r[5]:.0f}x, "
                f"wall {r[3] / r[6]:.0f}x",
                flush=True,
            )


if __name__ == "__main__":
    import sys

    main(sys.argv[1] if len(sys.argv) > 1 else "")
