"""Issue 41: the error bars of the new parts against their true error, and their price, per backend.

    python benchmarks/bench_parts.py [--parts power-n1,...] [--backends lammps,rk4,verlet] [--finer 16]

Each part's chains (PARTS: the power law at n = 1, 2 and 3 and with a per-contact list of n, a
dashpot, Kuwabara-Kono damping, a PTFE and a steel wall) run as ``granchain run SCENE --rtol 1e-3``
runs them on each backend (LAMMPS, reference RK4, reference Verlet), with their default error bars.
The true error of every observable with a bar (each contact's peak force and leading pulse, the
wall's peak force) is its distance to the same run, same backend and integrator, at dt / FINER (a
much smaller step: its own error is FINER^-p of the run's at order p; 1/16 with a damping part's
first-order Verlet error, 1/256 at order 2), counted where it is above that run's round-off (1e3 ulps
of the value, and workflows.error_estimates.roundoff_floor where the run has one). The effectivity is
the bar over the true error; a bar without a number counts by its status. The price is
summary.json's ``price.error_estimate`` (the companions' wall time) over ``price.wall_time`` (the
run's), both from the same run, so the ratio holds under load.

Prints one row per chain and backend (counts, the effectivity's range, the statuses of the peaks
without a number, the price) and each peak outside [1/3, 3] with its status.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import warnings
from collections import Counter
from dataclasses import replace

import numpy as np

os.environ.setdefault("GRANCHAIN_QUIET", "1")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # (bench_errorbar_price beside it)

from bench_errorbar_price import companions_cpu, cpu  # noqa: E402

from granchain.scene.reader import scene_from_dict  # noqa: E402
from granchain.workflows.error_estimates import roundoff_floor  # noqa: E402
from granchain.workflows.run import plan_for, run_scene  # noqa: E402

RADIUS = 4.76e-3
#: (label, backend, method)
BACKENDS = {"lammps": ("lammps", None), "rk4": ("reference", "rk4"), "verlet": ("reference", "verlet")}


def stiffness_for(n: float) -> float:
    """A K (N/m^n) that gives a brass-like contact: the Hertz force at an overlap of 1e-5 R (as
    tests/test_power_law.py)."""
    a = 1e-5 * RADIUS
    return 1.3e10 * math.sqrt(RADIUS / 2) * a**1.5 / a**n


def chain(beads: int, contact: dict, *, velocity=0.3, end_time=4e-4, material="brass", **tables) -> dict:
    """A chain given `velocity` at bead 1, planned for rtol 1e-3 (timestep "auto")."""
    d = {
        "chain": {"beads": beads, "radius": RADIUS, "material": material},
        "contact": contact,
        "loading": {"kind": "velocity", "velocity": velocity},
        "run": {"end_time": end_time, "timestep": "auto"},
        "outputs": {"peak_force": True},
    }
    return d | tables


def power(n) -> dict:
    ns = n if isinstance(n, list) else None
    k = [stiffness_for(x) for x in ns] if ns else stiffness_for(n)
    return {"law": "power", "exponent": n, "stiffness": k}


def walled(wall: str, end_time: float) -> dict:
    """A stainless chain of 8 beads on a wall of `wall` (tests/test_wall_material.py's chains), until the
    wall's force has fallen past half its peak."""
    return chain(
        8, {"law": "hertz"}, material="stainless-steel-316", end_time=end_time, velocity=0.3,
        boundary={"far_end": "wall", "wall_material": wall},
    )  # fmt: skip


#: part -> its chains (name, scene dict)
PARTS = {
    # (a linear chain's wave is slow and dispersive: 3 ms to cross 12 beads)
    "power-n1": [("power n = 1, 12 beads", chain(12, power(1.0), end_time=3e-3))],
    "power-n2": [("power n = 2, 12 beads", chain(12, power(2.0)))],
    "power-n3": [("power n = 3, 12 beads", chain(12, power(3.0)))],
    "power-list": [
        ("power n = 1.5 / 2.5 (interface), 11 beads", chain(11, power([1.5] * 5 + [2.5] * 5))),
        ("power n = 1.2 .. 2.6 (disorder), 9 beads", chain(9, power([1.2, 2.6, 1.8, 1.4, 2.2, 1.6, 2.0, 1.3]))),
    ],
    "dashpot": [
        (
            "hertz + dashpot 5 N s/m, 20 beads, 1 m/s",
            chain(20, {"law": "hertz"}, velocity=1.0, damping={"dashpot": 5.0}),
        )
    ],
    "kuwabara-kono": [
        (
            "hertz + kuwabara_kono 1 us, 20 beads, 1 m/s",
            chain(20, {"law": "hertz"}, velocity=1.0, damping={"kuwabara_kono": 1e-6}),
        ),
        (
            "power n = 2 + kuwabara_kono 1 us, 12 beads",
            chain(12, power(2.0), damping={"kuwabara_kono": 1e-6}),
        ),
    ],
    "wall-ptfe": [("stainless on a PTFE wall, 8 beads", walled("ptfe", 6e-4))],
    "wall-steel": [("stainless on a stainless wall, 8 beads", walled("stainless-steel-316", 3e-4))],
}


def observables(got, fine):
    """(name, value at dt, value at dt / FINER, bar, status, round-off floor) of every observable with a bar."""
    a, b, e = got.solution, fine.solution, got.errors
    floor = roundoff_floor(fine.scene, b)
    floor = np.zeros(len(a.peak_force)) if floor is None else np.nan_to_num(floor)
    out = []
    for name, bars in (("peak_force", e.peak_force), ("leading_pulse_force", e.leading_pulse_force)):
        if bars is None:
            continue
        va, vb = np.asarray(getattr(a, name), float), np.asarray(getattr(b, name), float)
        ok = (a.complete & b.complete) if name == "peak_force" else (va > 0) & (vb > 0)
        for i in np.flatnonzero(ok):
            out.append((f"{name}[{i + 1}]", va[i], vb[i], bars.error[i], str(bars.status[i]), floor[i]))
    for name, bar in e.end_peaks.items():
        if not name.endswith("_peak_force"):
            continue  # (the end peaks' times: not this benchmark's observables)
        va, vb = getattr(a, name, None), getattr(b, name, None)
        if va is not None and vb is not None and np.isfinite(va) and np.isfinite(vb):
            err = bar.get("error")
            out.append((name, float(va), float(vb), np.nan if err is None else float(err), str(bar.get("status")), 0.0))
    return out


def priced_runs(planned, backend: str, method: str | None, reps: int):
    """The run with its error bars, repeated: the last result and each repetition's price (wall: the
    companions' wall time over the run's, summary.json's; CPU: bench_errorbar_price's, the companions'
    CPU time over the rest of the run's, LAMMPS children included)."""
    prices = []
    for _ in range(reps):
        spent: list[float] = []
        t0 = cpu()
        with companions_cpu(spent):
            got = run_scene(planned, backend=backend, method=method, error_estimate=True)
        total, comp = cpu() - t0, sum(spent)
        price = got.price()
        prices.append(((price["error_estimate"] or 0.0) / price["wall_time"], comp / (total - comp)))
    return got, prices


def measure(label: str, sd: dict, b: str, finer: int, reps: int, out: list) -> None:
    backend, method = BACKENDS[b]
    sc = scene_from_dict(sd, source=f"{label}.toml")
    planned, _ = plan_for(sc, backend, method, 1e-3)
    got, prices = priced_runs(planned, backend, method, reps)
    truth = replace(planned, run=replace(planned.run, timestep=planned.run.timestep / finer))
    fine = run_scene(truth, backend=backend, method=method)
    p = " / ".join(f"{statistics.median(x):.2f}" for x in zip(*prices, strict=True))
    p += f" / {sum(got.errors.steps) / max(got.solution.steps, 1):.2f}"
    if got.errors.peak_force is None and not got.errors.end_peaks:
        out.append(f"| {label} | {b} | no bars: {got.errors.why_none} | | | | {p} |")
        return
    ratios, why, outside, wall = [], Counter(), [], ""
    for name, va, vb, bar, status, floor in observables(got, fine):
        true = abs(va - vb)
        if not true > max(1e3 * np.spacing(abs(va)), floor):
            continue  # the truth is round-off: nothing to compare
        if not np.isfinite(bar):
            why[status.split(":")[0]] += 1
            continue
        q = bar / true
        ratios.append(q)
        if name == "wall_peak_force":
            wall = f"; wall peak {q:.2f}"
        if not 1 / 3 <= q <= 3:
            outside.append(f"    {label}, {b}, {name}: {q:.3g} (status {status}; true {true:.2e} of {va:.4g})")
    r = np.asarray(ratios)
    inside = int(np.sum((r >= 1 / 3) & (r <= 3)))
    rng = f"{r.min():.2f} - {np.median(r):.2f} - {r.max():.2f}" if r.size else "-"
    kind = "bounds" if got.errors.peak_bounds else got.errors.against or "Richardson"
    out.append(f"| {label} | {b} | {kind} | {inside} / {r.size} | {rng}{wall} | {dict(why) or ''} | {p} |")
    out.extend(outside)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--parts", default=",".join(PARTS))
    ap.add_argument("--backends", default=",".join(BACKENDS))
    ap.add_argument("--reps", type=int, default=3, help="runs per chain and backend for the price (median)")
    ap.add_argument("--finer", type=int, default=16, help="the truth's step: dt / FINER")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    print(f"truth: the same run at dt / {args.finer}; load {os.getloadavg()[0]:.1f}")
    head = (
        "chain",
        "integrator",
        "bars",
        "within 1/3 - 3",
        "bar / true: min - median - max",
        "no number",
        "price: wall / CPU / steps",
    )
    print("| " + " | ".join(head) + " |\n" + "|---" * len(head) + "|")
    for part in args.parts.split(","):
        for label, sd in PARTS[part]:
            for b in args.backends.split(","):
                rows: list[str] = []
                measure(label, sd, b, args.finer, args.reps, rows)
                print("\n".join(rows), flush=True)
    print(f"load at the end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
