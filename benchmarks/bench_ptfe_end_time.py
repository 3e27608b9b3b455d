"""The auto end time on random material sequences with PTFE (tests/test_varied_chains.py's "materials"
draw): for each drawn chain, the planned run (with its stop check, and once more, longer, when it ended
before measuring its window: plan.extended_plan, as run_scene does; --no-extend without it) against the
property's criteria: the window's last contact's leading pulse measured ("miss" if not), and the run
ending within 1.5x the crossing ("too long" if not). Two crossings: "old", the leading pulse's arrival
(the first maximum), or where the stop check ended the run the later peak it waited for; "new", the
later of the arrival and the last maximum at that contact, before the end, above half the largest
before it, stopped or not (a main wave behind a small precursor, a train of pulses: the test's).

    python benchmarks/bench_ptfe_end_time.py N [--seed S] [--precompressed always|mixed] [--out FILE]

The draw is numpy's (uniform), not hypothesis's: beads 20-40, each bead's material uniform over the
built-in Hertz materials, kick 0.1-2 m/s, wall or not; precompressed (always, or with probability 1/2)
at 10^U(-3, 3) x the kick's force scale, within the test's static-strain limit. Only chains with a PTFE
bead are run.
"""

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from granchain.peaks import still_rising  # noqa: E402
from granchain.postprocess.observables import unmeasured_outputs  # noqa: E402
from granchain.scene import parse_scene  # noqa: E402
from granchain.workflows.plan import plan_scene  # noqa: E402
from granchain.workflows.run import run_reference  # noqa: E402
from tests.test_varied_chains import (  # noqa: E402
    HERTZ_MATERIALS,
    _auto_run,
    _last_maximum_above_half,
    chain_text,
    precompression_range,
)

#: whether a run that ended before measuring its window runs again, longer (plan.extended_plan)
EXTEND = True


def draw(rng, precompressed: str):
    n = int(rng.integers(20, 41))
    names = [HERTZ_MATERIALS[i] for i in rng.integers(0, len(HERTZ_MATERIALS), n)]
    chain = f"radius = 4.76e-3\nmaterial = {names!r}\n"
    velocity = float(rng.uniform(0.1, 2.0))
    wall = bool(rng.integers(0, 2))
    bare = parse_scene(chain_text(chain, n, velocity, wall=wall), source="varied.toml")
    pre = precompressed == "always" or bool(rng.integers(0, 2))
    ratio = 10.0 ** rng.uniform(-3.0, 3.0)
    if not pre:
        return bare, names, velocity, wall, 0.0, 0.0
    f_kick, f_max = precompression_range(bare)
    f0 = min(ratio * f_kick, f_max)
    sc = parse_scene(chain_text(chain, n, velocity, f0, wall), source="varied.toml")
    return sc, names, velocity, wall, f0, f0 / f_kick


def measure(sc):
    if EXTEND:  # as run_scene does (without its refinement of the time step)
        planned, res = _auto_run(sc)
    else:
        plan = plan_scene(sc, method="verlet")
        sc = plan.scene
        outputs = replace(sc.outputs, histories=(sc.window[1],), history_interval=sc.run.timestep)
        planned = replace(sc, outputs=outputs)
        res = run_reference(planned, "verlet")
    b = planned.window[1]
    s = res.solution
    arrival = float(s.leading_pulse_time[b - 1])
    stopped = s.end_time < planned.run.end_time
    crossing_old = max(arrival, float(s.time_of_peak[b - 1])) if stopped else arrival
    crossing = max(arrival, _last_maximum_above_half(s, planned.effects.precompression))
    covered = bool(np.isfinite(arrival)) and res.observables()["leading_peak_force"] is not None
    f = s.history_force[:, 0] - planned.effects.precompression
    rising = bool(f.size > 1 and f[-1] > f[-2] and f[-1] > 0.5 * np.max(f))
    first_end = plan_scene(sc, method="verlet").scene.run.end_time
    return {
        "planned_end": planned.run.end_time,
        "first_planned_end": first_end,
        "extended": bool(EXTEND and planned.run.end_time > first_end),
        "end": float(s.end_time),
        "stopped": bool(stopped),
        "arrival": arrival,
        "crossing_old": crossing_old,
        "crossing": crossing,
        "covered": covered,
        "ratio_old": float(s.end_time / crossing_old) if covered else None,
        "ratio": float(s.end_time / crossing) if covered else None,
        "window_end": b,
        "rising": rising,
        "flagged": bool(still_rising(s.complete, s.time_of_peak, s.velocity)[b - 1]),
        "unmeasured": unmeasured_outputs(planned, s),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("n", type=int)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--precompressed", choices=["always", "mixed"], default="mixed")
    ap.add_argument("--out", default=None)
    ap.add_argument("--no-extend", action="store_true", help="without plan.extended_plan's second run")
    a = ap.parse_args()
    global EXTEND
    EXTEND = not a.no_extend
    rng = np.random.default_rng(a.seed)
    rows = []
    t0 = time.time()
    for i in range(a.n):
        sc, names, v, wall, f0, fr = draw(rng, a.precompressed)
        if "ptfe" not in names:
            continue
        row = {"i": i, "materials": names, "velocity": v, "wall": wall, "f0": f0, "f0_over_kick": fr}
        row.update(measure(sc))
        for key, crossing in (("verdict_old", "crossing_old"), ("verdict", "crossing")):
            row[key] = "miss" if not row["covered"] else ("too long" if row["end"] > 1.5 * row[crossing] else "ok")
        rows.append(row)
        print(
            f"{i:3d} {row['verdict_old']:8s} {row['verdict']:8s} beads {len(names)} wall {wall:d} F0/kick {fr:8.3g} "
            f"end/crossing {row['ratio_old'] if row['ratio_old'] is None else round(row['ratio_old'], 3)} "
            f"{row['ratio'] if row['ratio'] is None else round(row['ratio'], 3)} extended {row['extended']:d} "
            f"stopped {row['stopped']:d} rising {row['rising']:d} flagged {row['flagged']:d}",
            flush=True,
        )
    for key in ("verdict_old", "verdict"):
        counts = {v: sum(r[key] == v for r in rows) for v in ("ok", "miss", "too long")}
        print(f"{len(rows)} PTFE chains, {key}: {counts} ({time.time() - t0:.0f} s)")
    count = {k: sum(r[k] for r in rows) for k in ("extended", "stopped", "rising", "flagged")}
    print(
        f"extended {count['extended']}, stopped {count['stopped']}, ending with the window's last contact rising "
        f"{count['rising']}, of them flagged {sum(r['rising'] and r['flagged'] for r in rows)}; flagged "
        f"{count['flagged']}; still not measured {sum(bool(r['unmeasured']) for r in rows)}"
    )
    longer = [r["end"] / r["first_planned_end"] for r in rows if r["extended"]]
    if longer:
        print(f"extended runs end at {min(longer):.3g}-{max(longer):.3g}x the first run's planned end")
    print(
        "rising at the end:", [r["i"] for r in rows if r["rising"]], "flagged:", [r["i"] for r in rows if r["flagged"]]
    )
    if a.out:
        Path(a.out).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
