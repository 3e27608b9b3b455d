"""granchain render, collect and plot: a deck directory for plain LAMMPS, back to a run directory,
and the figures of a run or compare directory."""

from __future__ import annotations

import sys

from granchain.backends import LAMMPS
from granchain.exceptions import UsageError

from .terminal import SCENE_HELP, ended_too_soon, planned, print_result, resolve_scene, shown


def add_plot_parser(sub) -> None:
    """granchain plot RUN_DIR|COMPARE_DIR [--linear] [--format png,pdf,svg]."""
    pl = sub.add_parser("plot", help="make the figures of a run directory or of a compare directory")
    pl.add_argument("run_dir", help="a run directory (granchain run) or a compare directory (granchain compare)")
    pl.add_argument("--linear", action="store_true", help="linear axes for the peak-force plot")
    pl.add_argument("--format", default="png", help="figure formats, comma-separated: png, pdf, svg (default png)")
    pl.set_defaults(func=cmd_plot)


def cmd_plot(args) -> int:
    """The figures of a run directory, or of a compare directory (LAMMPS over the reference)."""
    from granchain.workflows.plots import is_compare_dir, plot_compare, plot_run

    skipped: dict[str, str] = {}
    if is_compare_dir(args.run_dir):  # lammps/ and reference/, each with summary.json
        made = plot_compare(args.run_dir, formats=args.format, skipped=skipped)
    else:
        made = plot_run(args.run_dir, log=not args.linear, formats=args.format, skipped=skipped)
    for p in made:
        print(shown(p))
    for figure, why in skipped.items():
        print(f"granchain: {figure} not drawn: {shown(why)}", file=sys.stderr)
    return 0


def add_render_parser(sub) -> None:
    """granchain render SCENE [--data | --out DIR]."""
    d = sub.add_parser("render", help="print the LAMMPS deck of a scene, or write a directory plain LAMMPS runs")
    d.add_argument("scene", nargs="?", help=SCENE_HELP)
    d.add_argument("--data", action="store_true", help="print the data file (chain.data) instead")
    d.add_argument(
        "--out",
        help="write a new directory with deck.lmp, chain.data, scene.toml (and plan.json): run it with "
        "'lmp -in deck.lmp' there, then 'granchain collect DIR'",
    )
    d.set_defaults(func=cmd_render)


def cmd_render(args) -> int:
    """Print a scene's LAMMPS deck or data file, or write a directory plain LAMMPS runs."""
    if args.out and args.data:
        raise UsageError("--data prints chain.data; --out writes it (with the deck and the scene): give one of them")
    given = resolve_scene(args.scene)
    scene, plan = planned(given, None, LAMMPS, None)
    if args.out:
        from granchain.workflows.collect import render_dir

        out = render_dir(scene, args.out, plan, given)
        print(f"deck directory: {out} ({', '.join(sorted(p.name for p in out.iterdir()))})")
        print(f"run it with plain LAMMPS:   cd {out} && lmp -in deck.lmp   (or: mpirun -np N lmp -in deck.lmp)")
        print(f"then make it a run directory: granchain collect {out}")
        return 0
    files = LAMMPS.input_files(scene)
    print(files[LAMMPS.DATA] if args.data else files[LAMMPS.INPUT], end="")
    return 0


def add_collect_parser(sub) -> None:
    """granchain collect DIR [--out RUN_DIR] [--overwrite]."""
    co = sub.add_parser(
        "collect", help="make a directory that plain LAMMPS ran (granchain render --out) a run directory"
    )
    co.add_argument("run_dir", help="the directory of 'granchain render --out' after 'lmp -in deck.lmp' ran in it")
    co.add_argument("--out", help="write a new run directory here instead of adding the files to RUN_DIR")
    co.add_argument("--overwrite", action="store_true", help="replace an existing --out directory")
    co.set_defaults(func=cmd_collect)


def cmd_collect(args) -> int:
    """A directory plain LAMMPS ran, made a run directory; its numbers printed as granchain run's."""
    from granchain.workflows.collect import collect

    result = collect(args.run_dir, out=args.out, overwrite=args.overwrite)
    print_result(result, args.out or args.run_dir)
    # what the scene asked for and the run ended before measuring, as granchain run says it (and exits
    # 1 where the end time was the planner's); granchain run runs a planned end again, longer, and a
    # plain-LAMMPS run is run once
    plan = getattr(result, "plan", None)
    planned_end = plan is not None and any(c.name == "end_time" for c in plan.choices)
    then = (
        "granchain run would have run this planned scene again, longer, to measure it; this plain-LAMMPS run "
        "ran once: run it with 'granchain run SCENE --backend lammps', or set a longer [run] end_time in the "
        "scene, render it again and run that deck"
        if planned_end
        else "a longer [run] end_time in the scene would measure it: render it again and run that deck"
    )
    return ended_too_soon(result, planned_end, then)
