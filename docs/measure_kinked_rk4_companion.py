"""How well one RK4 companion at 2 dt, with an assumed order, measures reference RK4's error on the kinked
laws (bilinear, Thornton), against the true error (docs/error-bars.md, "RK4 on the kinked laws: one
companion").

    python docs/measure_kinked_rk4_companion.py run SEED N [LAW ...]   # N generated scenes per law
    python docs/measure_kinked_rk4_companion.py summary FILE.json ...  # the tables of several

Each scene (tests/scenegen.scenes of the law, without a dashpot: RK4 gives no bars with one; up to 40
beads; every material, radius, taper, material sequence, precompression, wall, striker and loading the
generator draws) is planned for reference RK4 at rtol 1e-3 and run with RK4 at dt, 2 dt, 4 dt and dt / 4
(the truth: its own error is 1/32 of the run's at order 2.5, 1/256 at 4). Every quantity the run's bars
cover is read from each run: per contact the peak force and its time (complete in every run), the
leading pulse's force and time (the arrival time), the striker's and the wall's peaks and times, and the
observables (leading_peak_force, max_peak_force, wave_speed). Counted where the true error
|Q(dt) - Q(dt / 4)| is above the truth's own round-off (1e3 ulps, and 2x the run's round-off floor,
workflows.error_estimates.roundoff_floor, for forces). Writes /tmp/kinked_rk4_SEED.json (the values
at every step per item, so the estimators are compared on the same runs); ``summary`` prints, per law
and estimator, the effectivity (estimate / true error) 5-50-95%, min-max, the fractions below 1/3 and
above 3, and the observed orders: the three runs' log2((Q(2dt) - Q(4dt)) / (Q(dt) - Q(2dt))) and the
true local one log2(|E(2 dt)| / |E(dt)|).

Estimators (each on the same per-item values; another pulse in a companion run, and round-off, as
richardson decides them, count as "no bar"):
* default: one companion, |Q(dt) - Q(2 dt)| itself, a bound (order 1; workflows.error_estimates
  .one_companion_because);
* one companion, order p assumed for every quantity: |Q(dt) - Q(2 dt)| / (2^p - 1), p = 3 and p = 2.5
  (richardson.one_companion);
* Richardson over dt, 2 dt, 4 dt with its order checks (richardson.richardson, RK4's orders 2.5-4): the
  previous default.
"""

import json
import math
import sys
import warnings
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, seed, settings

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from dataclasses import replace

from granchain.postprocess.observables import measure_observables
from granchain.richardson import BOUND_ORDER, one_companion, richardson
from granchain.workflows.error_estimates import expected_orders, roundoff_floor
from granchain.workflows.plan import highest_frequency
from granchain.workflows.run import plan_for, run_scene
from tests.scenegen import scenes

warnings.simplefilter("ignore")
FACTORS = (1.0, 2.0, 4.0, 0.25)
TIMES = ("time_of_peak", "arrival_time", "striker_time_of_peak", "wall_time_of_peak")
rows: list[dict] = []


def at(scene, factor):
    return replace(scene, run=replace(scene.run, timestep=scene.run.timestep * factor))


def study(sc):
    planned, _ = plan_for(sc, "reference", "rk4", 1e-3)
    sols = [run_scene(at(planned, f), method="rk4").solution for f in FACTORS]
    jump = math.pi / highest_frequency(planned)[0]
    n = len(sols[0].peak_force)
    items = []  # (quantity, values at dt, 2dt, 4dt, dt/4, times at dt, 2dt, 4dt or None, floor)

    def per(name, complete=False):
        out = []
        for s in sols:
            v = np.asarray(getattr(s, name), dtype=float)[:n].copy()
            if complete:
                v[~np.asarray(s.complete, dtype=bool)[:n]] = np.nan
            out.append(v)
        return out

    floor = roundoff_floor(planned, sols[0])
    floor = np.zeros(n) if floor is None else np.nan_to_num(floor)
    pf, tp = per("peak_force", True), per("time_of_peak", True)
    lf, lt = per("leading_pulse_force"), per("leading_pulse_time")
    for name, vals, times, fl in (
        ("peak_force", pf, tp, floor),
        ("time_of_peak", tp, tp, np.zeros(n)),
        ("leading_pulse_force", lf, lt, floor),
        ("arrival_time", lt, lt, np.zeros(n)),
    ):
        for i in range(n):
            items.append((name, [float(v[i]) for v in vals], [float(t[i]) for t in times[:3]], float(fl[i])))
    for force, when in (("striker_peak_force", "striker_time_of_peak"), ("wall_peak_force", "wall_time_of_peak")):
        vals = [getattr(s, force) for s in sols]
        done = [getattr(s, force.replace("_peak_force", "_peak_complete")) is not False for s in sols]
        if any(v is None for v in vals) or not all(done):
            continue
        times = [float(getattr(s, when)) for s in sols]
        items.append((force, [float(v) for v in vals], times[:3], 0.0))
        items.append((when, times, times[:3], 0.0))
    obs = [measure_observables(planned, s) for s in sols]
    b = max(planned.window[1] - 1, 0)
    for name in ("leading_peak_force", "max_peak_force", "wave_speed"):
        vals = [np.nan if o.get(name) is None else float(o[name]) for o in obs]
        times = [float(s.leading_pulse_time[b]) for s in sols[:3]] if name == "leading_peak_force" else None
        items.append((name, vals, times, 0.0))
    row = {
        "law": planned.contact.law,
        "beads": planned.chain.beads,
        "kind": planned.loading.kind,
        "per_bead": bool(sc.per_bead),
        "pre": float(planned.effects.precompression),
        "wall": str(planned.effects.far_end),
        "steps": int(sols[0].steps),
        "jump": jump,
        "items": items,
    }
    rows.append(row)
    print(row["law"], row["beads"], row["kind"], row["per_bead"], row["pre"], row["wall"], row["steps"], flush=True)


def estimators(row):
    """name -> (estimate, true error, observed order of the three runs, true local order) per counted
    item of one scene's row (estimate nan: no bar)."""
    out = {k: [] for k in ("default", "one p=3", "one p=2.5", "richardson 3 runs")}
    jump = row["jump"]
    orders = (2.5, 4.0)
    for name, v, t, fl in row["items"]:
        f, c, cc, truth = v
        if not all(np.isfinite(v)):
            continue
        true = abs(f - truth)
        if true <= max(1e3 * np.spacing(abs(truth)), 2.0 * fl):
            continue
        times = None if t is None else tuple([x] for x in t)
        e2 = abs(c - truth)
        d1, d2 = f - c, c - cc
        q3 = math.log2(d2 / d1) if d1 != 0 and d2 / d1 > 0 else math.nan
        qt = math.log2(e2 / true) if e2 > 0 else math.nan
        kw = dict(times=None if times is None else times[:2], jump_time=jump, floor=[fl])
        for key, p in (("one p=3", 3.0), ("one p=2.5", 2.5)):
            b = one_companion([f], [c], p, **kw)
            out[key].append((float(b.error[0]), true, q3, qt, name, str(b.status[0])))
        # the default (error_estimates.one_companion_because): the bound |Q(dt) - Q(2 dt)| (order 1)
        b = one_companion([f], [c], BOUND_ORDER, **kw)
        out["default"].append((float(b.error[0]), true, q3, qt, name, str(b.status[0])))
        b = richardson([f], [c], [cc], 4, times=times, jump_time=jump, orders=orders, floor=[fl])
        out["richardson 3 runs"].append((float(b.error[0]), true, q3, qt, name, str(b.status[0])))
    return out


def pct(x):
    if not x.size:
        return "-"
    p = np.percentile(x, [5, 50, 95])
    return f"{p[0]:.2f} - {p[1]:.2f} - {p[2]:.2f} ({x.min():.2f} - {x.max():.2f})"


def summary(rows):
    seen, unique = set(), []
    for r in rows:  # hypothesis may draw a scene twice: once
        key = (r["law"], r["beads"], r["kind"], r["pre"], r["wall"], r["steps"])
        if key not in seen:
            seen.add(key)
            unique.append(r)
    lines = [
        "| law | estimator | items | with a bar | est/true 5-50-95% (min - max) | below 1/3 | above 3 |",
        "|---|---|---|---|---|---|---|",
    ]
    order_lines = []
    for law in ("bilinear", "thornton"):
        sub = [r for r in unique if r["law"] == law]
        if not sub:
            continue
        per = [estimators(r) for r in sub]
        for key in per[0]:
            recs = [x for p in per for x in p[key]]
            e = np.asarray([x[0] for x in recs])
            t = np.asarray([x[1] for x in recs])
            ok = np.isfinite(e)
            r = e[ok] / t[ok]
            lines.append(
                f"| {law} ({len(sub)} scenes) | {key} | {len(recs)} | {int(ok.sum())} | {pct(r)} | "
                f"{int(np.sum(r < 1 / 3))} ({np.mean(r < 1 / 3):.1%}) | {int(np.sum(r > 3))} ({np.mean(r > 3):.1%}) |"
            )
            if key in ("default", "one p=3"):  # (by quantity)
                by = {}
                for x in recs:
                    if np.isfinite(x[0]):
                        by.setdefault(x[4], []).append(x[0] / x[1])
                for name, rr in sorted(by.items()):
                    rr = np.asarray(rr)
                    lines.append(
                        f"|  | ... {name} | | {rr.size} | {pct(rr)} | {int(np.sum(rr < 1 / 3))} | {int(np.sum(rr > 3))} |"
                    )
            if key != "default":
                continue
            for what, sel in (("forces", lambda x: x[4] not in TIMES), ("times", lambda x: x[4] in TIMES)):
                q3 = np.asarray([x[2] for x in recs if sel(x)])
                qt = np.asarray([x[3] for x in recs if sel(x)])
                m = q3.size
                q3, qt = q3[np.isfinite(q3)], qt[np.isfinite(qt)]
                order_lines.append(
                    f"{law} {what}: observed order of the three runs 5-50-95% {pct(q3)} ({q3.size} of {m} items "
                    f"with same-sign differences); true local order log2(E(2dt)/E(dt)) {pct(qt)}, within 2-4: "
                    f"{np.mean((qt >= 2) & (qt <= 4)):.0%}, below 2: {np.mean(qt < 2):.0%}, above 4: {np.mean(qt > 4):.0%}"
                )
    return "\n".join(lines + [""] + order_lines)


if __name__ == "__main__":
    if sys.argv[1] == "summary":
        allrows = [r for f in sys.argv[2:] for r in json.loads(Path(f).read_text())]
        print(summary(allrows))
        sys.exit()
    SEED, N = int(sys.argv[2]), int(sys.argv[3])
    laws = sys.argv[4:] or ["bilinear", "thornton"]
    for law in laws:

        @seed(SEED)
        @settings(max_examples=N, deadline=None, suppress_health_check=list(HealthCheck), database=None)
        @given(sc=scenes(law=law, max_beads=40).filter(lambda s: not s.effects.dashpot))
        def draw(sc):
            study(sc)
            Path(f"/tmp/kinked_rk4_{SEED}.json").write_text(json.dumps(rows))

        draw()
    print(summary(rows))
