"""Measure estimated / true peak-force error over generated scenes (docs/error-bars.md).

    python docs/measure_error_ratios.py LAW INTEGRATOR N     # e.g. hertz lammps 12

Writes /tmp/ratio_LAW_INTEGRATOR.json (every ratio, per scene) and prints the summary row.
"""

import json
import sys
import warnings
from dataclasses import replace

import numpy as np
from hypothesis import HealthCheck, given, settings

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1]))
from granchain.workflows.run import plan_for, run_scene
from tests.scenegen import scenes

warnings.simplefilter("ignore")
law = sys.argv[1]
integ = sys.argv[2]
n = int(sys.argv[3])
rows = []


@settings(max_examples=n, deadline=None, suppress_health_check=list(HealthCheck), database=None)
@given(sc=scenes(law=law, max_beads=30))
def study(sc):
    backend, method = ("lammps", None) if integ == "lammps" else ("reference", integ)
    try:
        sc2, _ = plan_for(sc, backend, method, 1e-3)
        sc2 = replace(
            sc2, outputs=replace(sc2.outputs, histories=(), snapshots=(), history_interval=None, dump_interval=None)
        )
        got = run_scene(sc2, backend=backend, method=method, error_estimate=True)
        fine = run_scene(
            replace(sc2, run=replace(sc2.run, timestep=sc2.run.timestep / 16)), backend=backend, method=method
        )
    except Exception as e:
        rows.append({"error": f"{type(e).__name__}: {str(e)[:200]}"})
        return
    a, b = got.solution, fine.solution
    measured = a.complete & b.complete
    true = np.abs(a.peak_force - b.peak_force)
    above = measured & (true > 1e3 * np.spacing(np.abs(a.peak_force)))
    est = got.errors.peak_force
    if est is None:
        rows.append({"none": got.errors.why_none})
        return
    ok = above & est.reliable
    r = (est.error[ok] / true[ok]).tolist()
    rows.append(
        {
            "ratios": r,
            "statuses": [str(x) for x in est.status[ok]],
            "all_statuses": [str(x) for x in est.status[measured]],
            "relative_true": (true[ok] / np.abs(a.peak_force[ok])).tolist(),
            "above": int(above.sum()),
            "estimated": int(ok.sum()),
            "dashpot": sc.effects.dashpot,
            "wall": sc.effects.far_end,
            "pre": sc.effects.precompression,
            "kind": sc.loading.kind,
        }
    )


study()
json.dump(rows, open(f"/tmp/ratio_{law}_{integ}.json", "w"))
allr = np.concatenate([np.asarray(x["ratios"]) for x in rows if "ratios" in x] or [np.zeros(0)])
scen = [x for x in rows if "ratios" in x]
bad = sum(1 for x in scen if x["ratios"] and (min(x["ratios"]) < 1 / 3 or max(x["ratios"]) > 3))
print(
    law,
    integ,
    "scenes",
    len(rows),
    "errors",
    sum(1 for x in rows if "error" in x),
    "none",
    sum(1 for x in rows if "none" in x),
    "peaks",
    allr.size,
    "quantiles 0/5/50/95/100",
    np.round(np.quantile(allr, [0, 0.05, 0.5, 0.95, 1]), 3) if allr.size else None,
    "outside [1/3,3]",
    int(np.sum((allr < 1 / 3) | (allr > 3))),
    "scenes with any outside",
    bad,
    "estimated/above",
    sum(x["estimated"] for x in scen),
    "/",
    sum(x["above"] for x in scen),
)
