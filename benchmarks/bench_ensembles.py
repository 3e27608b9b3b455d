"""Ensembles at the machine's speed (issue 44 item 4): ns per bead-step of core time of a campaign of
many small chains, beside the same backend's long single chain, measured in one run.

Run by hand:  python benchmarks/bench_ensembles.py [--points 100] [--beads 20,100] [--backends lammps,reference]
              [--workers 2] [--long-beads 10000] [--long-end-time 1e-3] [--tree DIR ...] [--reps 1]

For each backend and each B in --beads: a campaign of --points points of a B-bead brass Hertz chain
struck by an impulse (the impulse swept over two decades, end time and time step "auto", the default
error bars), run by ``granchain campaign run --workers W`` in a fresh workspace, as a child process;
and the same backend's long chain (--long-beads beads, the same impulse, time step "auto", end time
--long-end-time: its cost per bead-step does not depend on how far the wave went), run by
``granchain run``. Core time: the CPU time (user + system) of that child process and all its
descendants (Dask's nanny and worker processes, LAMMPS children), read from RUSAGE_CHILDREN once the
child is reaped. Bead-steps: each run's beads x (its steps + its companions' steps), from its
summary.json. With --tree DIR (repeatable) every measurement runs in turn on each tree (PYTHONPATH =
DIR), so that an old and a new tree are compared side by side under the same load; the table gives
each tree's figures and the ratio to the first tree.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SCENE = """
[chain]
beads = {beads}
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "impulse"
impulse = 0.4
duration = 1e-6
[run]
end_time = {end_time}
timestep = "auto"
[outputs]
peak_force = true
"""


def campaign_text(backend: str, beads: int, points: int) -> str:
    """The campaign file: the impulse swept log-evenly over two decades."""
    inline = SCENE.format(beads=beads, end_time='"auto"').replace("\n[", "\n[scene.")
    return (
        f'[campaign]\nbackend = "{backend}"\n'
        f'[vary]\n"loading.impulse" = {{ log = [0.004, 0.4], num = {points} }}\n[scene]\n{inline}'
    )


def child_cpu(cmd: list[str], tree: Path) -> tuple[float, float, int]:
    """(core time, wall time, exit status) of a child process and all its descendants, s."""
    env = dict(os.environ, PYTHONPATH=str(tree), GRANCHAIN_QUIET="1")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    done = subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, cwd=tree)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if done.returncode and "campaign" not in cmd:  # (a campaign with failed points says so: below)
        sys.exit(f"{' '.join(cmd)} failed:\n{done.stderr}")
    return cpu, wall, done.returncode


def bead_steps(summary: dict) -> tuple[int, float]:
    """(bead-steps of a run with its companions, its integration time in s)."""
    steps = summary["steps"] + sum((summary.get("errors") or {}).get("companion_steps") or [])
    price = summary.get("price") or {}
    loop = (price.get("integration") or 0.0) + (price.get("error_estimate") or 0.0)
    return summary["beads"] * steps, loop


def run_campaign(tree: Path, backend: str, beads: int, points: int, workers: int, root: Path) -> dict:
    f = root / f"c-{backend}-{beads}.toml"
    f.write_text(campaign_text(backend, beads, points))
    ws = root / f"ws-{backend}-{beads}-{tree.name}-{time.monotonic_ns()}"
    cmd = [
        sys.executable,
        "-m",
        "granchain",
        "campaign",
        "run",
        str(f),
        "--out",
        str(ws),
        "--workers",
        str(workers),
        "-q",
    ]
    cpu, wall, _ = child_cpu(cmd, tree)
    total, done = 0, 0
    for s in ws.glob("workspace/*/run/summary.json"):
        bs, _ = bead_steps(json.loads(s.read_text()))
        total += bs
        done += 1
    failed = [json.loads(f.read_text())["message"] for f in ws.glob("workspace/*/failure.json")]
    for m in sorted(set(failed)):
        print(f"  a point failed ({backend}, {beads} beads): {m[:300]}", flush=True)
    assert done + len(failed) == points, f"{done} done, {len(failed)} failed, of {points} points in {ws}"
    # the failed points' core time is in cpu, their bead-steps are not: the figure is an upper bound then
    return {"cpu": cpu, "wall": wall, "bead_steps": total, "failed": len(failed)}


def run_long(tree: Path, backend: str, beads: int, end_time: float, root: Path) -> dict:
    f = root / f"long-{backend}-{beads}.toml"
    f.write_text(SCENE.format(beads=beads, end_time=end_time))
    out = root / f"long-{backend}-{tree.name}-{time.monotonic_ns()}"
    cmd = [sys.executable, "-m", "granchain", "run", str(f), "--backend", backend, "--out", str(out), "-q"]
    cpu, wall, _ = child_cpu(cmd, tree)
    bs, loop = bead_steps(json.loads((out / "summary.json").read_text()))
    return {"cpu": cpu, "wall": wall, "bead_steps": bs, "loop": loop}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=100)
    ap.add_argument("--beads", default="20,100", help="chain lengths of the campaigns, comma-separated")
    ap.add_argument("--backends", default="lammps,reference")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--long-beads", type=int, default=10000)
    ap.add_argument("--long-end-time", type=float, default=1e-3)
    ap.add_argument("--tree", action="append", type=Path, help="a granchain tree (default: this one)")
    ap.add_argument("--reps", type=int, default=1)
    args = ap.parse_args()
    trees = [t.resolve() for t in (args.tree or [Path(__file__).resolve().parent.parent])]
    rows = []
    print(f"load average before: {os.getloadavg()[0]:.2f}", flush=True)
    with tempfile.TemporaryDirectory(prefix="bench-ensembles-") as tmp:
        root = Path(tmp)
        for backend in args.backends.split(","):
            for rep in range(args.reps):
                for tree in trees:
                    r = run_long(tree, backend, args.long_beads, args.long_end_time, root)
                    rows.append((backend, args.long_beads, 1, tree, rep, r))
                    print(f"  {rows[-1][:3]} {tree.name}: {r}", flush=True)
                    for b in (int(x) for x in args.beads.split(",")):
                        r = run_campaign(tree, backend, b, args.points, args.workers, root)
                        rows.append((backend, b, args.points, tree, rep, r))
                        print(f"  {rows[-1][:3]} {tree.name}: {r}", flush=True)
                    print(f"  ({backend}, rep {rep + 1}, {tree} done; load {os.getloadavg()[0]:.2f})", flush=True)
    print(f"load average after: {os.getloadavg()[0]:.2f}\n")
    print_table(rows, trees, args.workers)


def print_table(rows: list, trees: list[Path], workers: int) -> None:
    long = {(b, t, rep): r for b, _, p, t, rep, r in rows if p == 1}
    print(
        f"| backend | tree | beads | points | bead-steps | wall (s) | core (s) | ns/bead-step (core) "
        f"| x long chain | x first tree | failed | (workers {workers})"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    first = {}
    for backend, beads, points, tree, rep, r in rows:
        ns = 1e9 * r["cpu"] / r["bead_steps"]
        key = (backend, beads, points, rep)
        first.setdefault(key, ns)
        ref = long[(backend, tree, rep)]
        x_long = ns / (1e9 * ref["cpu"] / ref["bead_steps"])
        # the run's own clock of its integration and companions (summary.json price): wall time, not core
        extra = f" (integration wall {1e9 * r['loop'] / r['bead_steps']:.1f})" if "loop" in r else ""
        print(
            f"| {backend} | {tree.name} | {beads} | {points} | {r['bead_steps']:.3g} | {r['wall']:.1f} "
            f"| {r['cpu']:.1f} | {ns:.1f}{extra} | {x_long:.1f} | {ns / first[key]:.3f} | {r.get('failed', 0)} |"
        )


if __name__ == "__main__":
    main()
