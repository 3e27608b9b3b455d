"""Measure estimated / true peak-force error on chains that vary (tapers, radius and material
sequences, dimers up to 1:20, precompression, walls: tests/test_varied_chains.varied_chains).

    python docs/measure_varied_error_ratios.py BACKEND METHOD N     # e.g. reference rk4 8; lammps verlet 8

The true error is the distance to the same run at dt / 8 (its own error is 1/64 of the run's for Verlet, 1/4096 for RK4). Prints one row per scene and a summary:
how many estimates fall within [1/3, 3] of the true error, and the statuses of those without one.
"""

import sys
import warnings
from collections import Counter
from dataclasses import replace

import numpy as np
from hypothesis import HealthCheck, given, settings

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1]))
from granchain.workflows.run import plan_for, run_scene
from tests.test_varied_chains import varied_chains

warnings.simplefilter("ignore")
backend, method, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
method = None if backend == "lammps" else method
ratios, statuses, rows = [], Counter(), []


@settings(max_examples=n, deadline=None, suppress_health_check=list(HealthCheck), database=None)
@given(sc=varied_chains())
def study(sc):
    planned, _ = plan_for(sc, backend, method, 1e-3)
    got = run_scene(planned, backend=backend, method=method, error_estimate=True)
    fine = run_scene(replace(planned, run=replace(planned.run, timestep=planned.run.timestep / 8)), backend=backend, method=method)
    a, b = got.solution, fine.solution
    measured = a.complete & b.complete
    true = np.abs(a.peak_force - b.peak_force)
    above = measured & (true > 1e3 * np.spacing(np.abs(a.peak_force)))
    est = got.errors.peak_force
    if est is None:
        rows.append(f"{sc.chain.beads} beads: no estimate ({got.errors.why_none})")
        return
    ok = above & est.reliable
    r = est.error[ok] / true[ok]
    ratios.extend(r.tolist())
    statuses.update(str(s).split(":")[0].split(" (")[0] for s in est.status[measured & ~est.reliable])
    kind = "per-bead" if sc.per_bead else "uniform"
    extra = (" F0 " if sc.effects.precompression else " ") + ("wall" if sc.effects.far_end == "wall" else "")
    inside = int(np.sum((r >= 1 / 3) & (r <= 3)))
    rows.append(f"{sc.chain.beads:3d} beads {kind}{extra}: {inside}/{r.size} within 1/3-3, range "
                f"{(r.min() if r.size else np.nan):.2g}-{(r.max() if r.size else np.nan):.2g}")


study()
r = np.asarray(ratios)
for row in rows:
    print(row)
inside = int(np.sum((r >= 1 / 3) & (r <= 3)))
print(f"{backend} {method or 'verlet'}: {inside}/{r.size} estimates within [1/3, 3] of the true error "
      f"(min {r.min():.2g}, median {np.median(r):.2g}, max {r.max():.2g}); without an estimate: {dict(statuses)}")
