"""ns per bead-step: granchain's chain/hertz vs LAMMPS's built-in pair_style granular (hertz/material,
no damping, no tangential force), same chain and deck otherwise, N = 1000 and 10000, serial.

Run by hand:  python benchmarks/bench_lammps.py          (chain/hertz vs granular)
              python benchmarks/bench_lammps.py watch    (the run watch's price)
Times are LAMMPS's own 'Loop time' of the runs (no start-up, no plugin build), median of 3.
"""

from __future__ import annotations

import re
import statistics
import tempfile
from pathlib import Path

from granchain.lammps.runner import run_deck
from granchain.scene import parse_scene
from granchain.templates import render_deck

SCENE = """
[chain]
beads = {n}
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "velocity"
velocity = 20.0
[run]
end_time = {end!r}
timestep = 2e-8
[outputs]
peak_force = true
"""


def loop_time(work: Path) -> float:
    return sum(float(x) for x in re.findall(r"Loop time of ([0-9.eE+-]+)", (work / "log.lammps").read_text()))


def main() -> None:
    print(f"{'N':>6s} {'steps':>6s} {'chain/hertz ns/bead-step':>25s} {'granular ns/bead-step':>22s} {'ratio':>6s}")
    for n, steps in ((1000, 20000), (10000, 2000)):
        sc = parse_scene(SCENE.format(n=n, end=steps * 2e-8))
        deck = render_deck(sc)
        res = {"ours": [], "builtin": []}
        for _ in range(3):
            for name, text in (("ours", deck.deck), ("builtin", render_deck(sc, yardstick="builtin").deck)):
                with tempfile.TemporaryDirectory() as tmp:
                    _, work = run_deck(text, deck.data, work_dir=tmp)
                    res[name].append(loop_time(work) / (n * steps) * 1e9)
        a, b = statistics.median(res["ours"]), statistics.median(res["builtin"])
        print(f"{n:6d} {steps:6d} {a:25.1f} {b:22.1f} {a / b:6.2f}")


def watch_cost(n: int = 1000, steps: int = 20000) -> None:
    """The run watch's price: chain/hertz with the full watch, the overlap watch only, and none."""
    sc = parse_scene(SCENE.format(n=n, end=steps * 2e-8))
    deck = render_deck(sc)
    variants = {
        "full watch": deck.deck,
        "overlap watch only": re.sub(r"^fix             watch_(energy|momentum) .*$", "", deck.deck, flags=re.M),
        "no watch": re.sub(r"^fix             watch\w* .*$", "", deck.deck, flags=re.M),
    }
    res = {k: [] for k in variants}
    for _ in range(3):
        for name, text in variants.items():
            with tempfile.TemporaryDirectory() as tmp:
                _, work = run_deck(text, deck.data, work_dir=tmp)
                res[name].append(loop_time(work) / (n * steps) * 1e9)
    for name, times in res.items():
        print(f"{name:>20s}: {statistics.median(times):.1f} ns/bead-step (median of 3)")


if __name__ == "__main__":
    import sys

    watch_cost() if sys.argv[1:] == ["watch"] else main()
