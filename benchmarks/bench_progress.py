"""The price of progress reporting (issue 12): the same runs with progress shown, quiet, and absent.

Run by hand:  python benchmarks/bench_progress.py [--reps 5] [--scene plastic-long-load-table1] [--rtol 1e-3]
              [--rk4-end 0.25] (RK4 runs only this fraction of the end time: its steps cost 60x Verlet's)
              [--lammps-rtol 1e-5] (LAMMPS's plan: a run of ~15 s on one core)

Reference: solve_chain on the planned scene (RK4 and Verlet), in turns:
  none   progress=None: no Progress object (the step loop keeps its one integer comparison per step)
  quiet  granchain.progress.quiet(): the Progress object exists but is off
  bar    shown from the first step (DELAY = 0) as a tqdm bar on a terminal-like sink (redrawn every 0.5 s)
  lines  shown from the first step as plain lines (every 5 s)
LAMMPS: run_deck on the planned deck, in turns:
  off    the deck without its `fix progress` line, quiet (no file is read while LAMMPS runs)
  on     the deck as rendered, the bar shown from the first step (progress.txt read every 0.5 s)
Times: CPU seconds (reference: this process; LAMMPS: the worker's, from getrusage of the children,
startup included, and the parent's own CPU while it waits and polls) and wall seconds (the solver's
own; LAMMPS's run in the worker); min and median of --reps, and the ratio of the mins to the
baseline. The modes alternate within each repetition. On a shared machine the run-to-run spread can
exceed the price by far, so the price is also counted directly: the time spent inside the progress
calls (reference), and the cost of one `fix print` (LAMMPS: the deck at a stride of 1 step vs none)
times the number of prints the deck makes.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import sys
import time
import timeit
from dataclasses import replace

import granchain
import granchain.progress as gp
from granchain.lammps.runner import cleanup, run_deck
from granchain.reference.solver import ChainProblem, solve_chain
from granchain.templates import render_deck


class _Sink:
    """A terminal that discards what it is shown (tqdm draws as on a real one)."""

    def __init__(self, tty: bool):
        self.tty = tty
        self.f = open(os.devnull, "w")  # noqa: SIM115

    def isatty(self) -> bool:
        return self.tty

    def write(self, s: str) -> int:
        return self.f.write(s)

    def flush(self) -> None:
        self.f.flush()


def _reference(scene, method: str, mode: str) -> tuple[float, float]:
    p = ChainProblem.from_scene(scene)
    args = (p, scene.run.end_time, scene.run.timestep, method)
    c0 = time.process_time()
    if mode == "none":
        sol = solve_chain(*args, progress=None)
    elif mode == "quiet":
        with gp.quiet():
            sol = solve_chain(*args)
    else:
        with gp.Progress(None, f"reference {method}", stream=_Sink(tty=mode == "bar")) as prog:
            sol = solve_chain(*args, progress=prog)
    return time.process_time() - c0, sol.wall_time


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _lammps(deck, mode: str) -> tuple[float, float, float]:
    c0, p0 = _children_cpu(), time.process_time()
    text = deck.deck
    if mode == "off":
        text = _without_progress(text)
        with gp.quiet():
            info, work = run_deck(text, deck.data, total_steps=deck.total_steps)
    else:
        saved = sys.stderr
        sys.stderr = _Sink(tty=True)  # run_deck's Progress draws its bar here
        try:
            info, work = run_deck(text, deck.data, total_steps=deck.total_steps)
        finally:
            sys.stderr = saved
    parent = time.process_time() - p0
    cleanup(work)
    return _children_cpu() - c0, parent, info["wall_time"]


def _row(label: str, cols: dict[str, dict[str, list[float]]], base: str) -> None:
    print(label)
    for mode in next(iter(cols.values())):
        parts = []
        for name, times in cols.items():
            b, ts = min(times[base]), times[mode]
            parts.append(f"{name} min {min(ts):7.3f} s x{min(ts) / b:6.4f}, median {statistics.median(ts):7.3f} s")
        print(f"  {mode:6s} " + "  |  ".join(parts))
    sys.stdout.flush()


class _Clocked:
    """Accumulates the time spent inside Progress.update / finish (the price the step loop pays)."""

    def __init__(self):
        self.seconds, self.calls = 0.0, 0
        self.update, self.finish = gp.Progress.update, gp.Progress.finish

    def __enter__(self):
        def timed(fn):
            def wrapper(prog, n):
                t = time.perf_counter()
                try:
                    return fn(prog, n)
                finally:
                    self.seconds += time.perf_counter() - t
                    self.calls += 1

            return wrapper

        gp.Progress.update, gp.Progress.finish = timed(self.update), timed(self.finish)
        return self

    def __exit__(self, *exc):
        gp.Progress.update, gp.Progress.finish = self.update, self.finish


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="plastic-long-load-table1")
    ap.add_argument("--rtol", type=float, default=1e-3)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--rk4-end", type=float, default=0.25)
    ap.add_argument("--lammps-rtol", type=float, default=1e-5)
    ap.add_argument("--skip-lammps", action="store_true")
    a = ap.parse_args()
    gp_delay = gp.DELAY
    scene = granchain.load_scene(a.scene)

    # the step loop's own price: one integer comparison per step (the rest runs every ~0.1 s)
    cmp = timeit.timeit("if step == at: pass", "step, at = 12345, -1", number=10_000_000) / 1e7
    print(f"per-step comparison in the step loop: {cmp * 1e9:.1f} ns")

    for method in ("rk4", "verlet"):
        sc = granchain.plan(scene, rtol=a.rtol, method=method).scene
        if method == "rk4":
            sc = replace(sc, run=replace(sc.run, end_time=sc.run.end_time * a.rk4_end))
        steps = round(sc.run.end_time / sc.run.timestep)
        label = f"reference {method} ({sc.chain.beads} beads, {steps} steps, dt {sc.run.timestep:.3g} s)"
        cpu: dict[str, list[float]] = {m: [] for m in ("none", "quiet", "bar", "lines")}
        wall: dict[str, list[float]] = {m: [] for m in cpu}
        warm = replace(sc, run=replace(sc.run, end_time=sc.run.end_time / 20))
        for mode in cpu:  # warm-up (caches, allocator, CPU clock), not counted
            _reference(warm, method, mode)
        for _ in range(a.reps):
            for mode in cpu:
                gp.DELAY = 0.0 if mode in ("bar", "lines") else gp_delay
                c, w = _reference(sc, method, mode)
                cpu[mode].append(c)
                wall[mode].append(w)
        gp.DELAY = gp_delay
        _row(label, {"cpu": cpu, "wall": wall}, "none")
        gp.DELAY = 0.0
        with _Clocked() as clock:
            c, _ = _reference(sc, method, "bar")
        gp.DELAY = gp_delay
        per_step = min(cpu["none"]) / steps
        print(
            f"  counted: one step {per_step * 1e6:.1f} us, its comparison {cmp / per_step * 100:.4f}% of it; "
            f"{clock.calls} progress calls took {clock.seconds * 1e3:.2f} ms = {clock.seconds / c * 100:.4f}% "
            f"of the run; total {(clock.seconds + steps * cmp) / c * 100:.4f}%"
        )

    if a.skip_lammps:
        return
    sc = granchain.plan(scene, rtol=a.lammps_rtol, method="verlet").scene
    deck = render_deck(sc)
    label = f"LAMMPS ({sc.chain.beads} beads, {deck.total_steps} steps)"
    cols: dict[str, dict[str, list[float]]] = {k: {"off": [], "on": []} for k in ("worker cpu", "parent cpu", "wall")}
    gp.DELAY = 0.0
    _lammps(deck, "on")  # warm-up, not counted
    for _ in range(a.reps):
        for mode in ("off", "on"):
            for k, v in zip(cols, _lammps(deck, mode), strict=True):
                cols[k][mode].append(v)
    gp.DELAY = gp_delay
    _row(label, cols, "off")

    # one fix print: the deck on a shorter run with a print every step, against no print at all
    stride = int(deck.deck.split("fix             progress all print ")[1].split()[0])
    prints = deck.total_steps // stride
    short = render_deck(replace(sc, run=replace(sc.run, end_time=sc.run.end_time * 40000 / deck.total_steps)))
    every = short.deck.replace(f"fix             progress all print {stride} ", "fix             progress all print 1 ")
    assert every != short.deck
    t: dict[str, list[float]] = {"none": [], "every": []}
    with gp.quiet():
        for _ in range(a.reps):
            for mode, text in (("none", _without_progress(short.deck)), ("every", every)):
                info, work = run_deck(text, short.data, total_steps=short.total_steps)
                cleanup(work)
                t[mode].append(info["wall_time"])
    per_print = (min(t["every"]) - min(t["none"])) / short.total_steps
    run = min(cols["wall"]["off"])
    print(
        f"  counted: one fix print {per_print * 1e6:.2f} us (a run of {short.total_steps} steps with a print every "
        f"step: {min(t['every']):.3f} s, without: {min(t['none']):.3f} s); the deck prints every {stride} steps: "
        f"{prints} prints = {prints * per_print * 1e3:.2f} ms = {prints * per_print / run * 100:.4f}% of the run; "
        f"the parent's polling: {min(cols['parent cpu']['on']) - min(cols['parent cpu']['off']):+.3f} s CPU"
    )


def _without_progress(deck: str) -> str:
    return "\n".join(line for line in deck.splitlines() if not line.startswith("fix             progress "))


if __name__ == "__main__":
    main()
