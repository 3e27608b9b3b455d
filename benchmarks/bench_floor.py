"""Issue 18 item 1: what a LAMMPS step costs without any force, against our pair style's deck, the built-in
granular style and the lean compiled loop (bench_pair.py's), side by side.

    python benchmarks/bench_floor.py [--reps 5] [--sizes 1000,10000,100000]

Per chain length, alternated run by run (LAMMPS's own Loop time, ns per bead-step, medians; ratios as
medians of paired ratios):
    plugin     the plugin deck (bench_pair.py's 'plugin': PLUGIN_DECK_OPTIONS, the full run watch)
    zero       the same deck with `pair_style zero`: every step's force clear, integration, neighbour
               check, run watch and outputs, no force computed. Its ratio to the lean loop is a floor
               under plugin/lean that no pair style can go below; zero/granular the same for
               plugin/granular
    bare       `pair_style zero` and only fix chain/nve: no watch, no outputs, no peak data (the step
               LAMMPS itself makes: force clear incl. torque of atom_style sphere, integration, the
               neighbour check)
    granular   LAMMPS's built-in pair_style granular (the yardstick)
    lean       bench_pair.py's numba velocity-Verlet loop over the same chain (numba: pip install numba)
"""

from __future__ import annotations

import argparse
import re
import statistics

from bench_pair import alternate, deck_for, lean_loop_ns, ns_per_bead_step, paired, steps_for

from granchain.templates import PLUGIN_DECK_OPTIONS


def zero_pair(deck: str) -> str:
    """The deck with pair_style zero (the same cutoff: the same neighbour list) in place of ours."""
    m = re.search(r"^pair_coeff\s+1\s+1\s+\S+\s+(\S+)", deck, re.M)
    if m is None:
        raise SystemExit("no 'pair_coeff 1 1 k d0' in the deck")
    deck, n = re.subn(r"^pair_style\s+.*$", f"pair_style      zero {float(m.group(1))!r}", deck, count=1, flags=re.M)
    deck, k = re.subn(r"^pair_coeff\s+.*$", "pair_coeff      * *", deck, flags=re.M)
    if n != 1 or k < 1:
        raise SystemExit("expected one pair_style and pair_coeff lines in the deck")
    return deck


def bare(deck: str) -> str:
    """zero_pair's deck less every fix but the integrator, every compute, variable, dump and thermo."""
    keep = []
    for line in zero_pair(deck).splitlines():
        word = line.split(maxsplit=1)[0] if line.strip() else ""
        if word in ("compute", "variable", "dump", "dump_modify", "thermo", "thermo_style", "thermo_modify"):
            continue
        if word == "fix" and " chain/nve" not in line and " nve" not in line and "property/atom" not in line:
            continue
        if word in ("unfix", "undump", "uncompute"):
            continue
        keep.append(line)
    return "\n".join(keep) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--sizes", default="1000,10000,100000")
    args = ap.parse_args()
    print(f"reps {args.reps}; ns per bead-step (median); ratios: medians of paired ratios")
    head = ("N", "steps", "plugin", "zero", "bare", "granular", "lean")
    head += ("plugin/gran", "zero/gran", "bare/gran", "plugin/lean", "zero/lean", "bare/lean")
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    for n in (int(s) for s in args.sizes.split(",")):
        steps = steps_for(n)
        d = deck_for(n, steps, options=PLUGIN_DECK_OPTIONS)
        g = deck_for(n, steps, yardstick="builtin")
        variants = {
            "plugin": (d.deck, d.data),
            "zero": (zero_pair(d.deck), d.data),
            "bare": (bare(d.deck), d.data),
            "granular": (g.deck, g.data),
        }
        ns = ns_per_bead_step(alternate(variants, args.reps), n, steps)
        lean = statistics.median(lean_loop_ns(n, steps, args.reps))
        med = {k: statistics.median(v) for k, v in ns.items()}
        cells = [f"{med[k]:.1f}" for k in variants] + [f"{lean:.2f}"]
        cells += [f"{paired(ns[k], ns['granular']):.2f}" for k in ("plugin", "zero", "bare")]
        cells += [f"{med[k] / lean:.1f}" for k in ("plugin", "zero", "bare")]
        print(f"| {n} | {steps} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
