"""granchain command line: run, compare, plan, predict, plot, render, collect, scenes, materials, doctor, campaign."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import warnings
from pathlib import Path

from granchain._version import __version__
from granchain.errors import GranchainError, UsageError
from granchain.results import OBSERVABLE_UNITS, printable
from granchain.scene import Scene, SceneError, bundled_scenes, load_scene, parse_scene

DEFAULT_SCENE = "default"


def shown(text) -> str:
    """Text from a scene, a file or a path as printed on a terminal: control characters escaped
    (a title's ESC sequences cannot retitle the window or clear the screen); newlines and tabs kept."""
    return printable(str(text), keep="\n\t")


def _scene_name(scene: Scene) -> str:
    return printable(scene.title or scene.source or "")


def json_safe(o):
    """o with every non-finite float as None (null) and numpy numbers as Python's: strict JSON for
    scripts (json.dumps refuses NaN with allow_nan=False)."""
    if isinstance(o, dict):
        return {str(k): json_safe(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [json_safe(v) for v in o]
    if hasattr(o, "tolist") and not isinstance(o, (str, bytes)):  # numpy scalars and arrays
        return json_safe(o.tolist())
    if isinstance(o, float) and not math.isfinite(o):
        return None
    if isinstance(o, Path):
        return str(o)
    return o


def print_json(data) -> None:
    """data as strict JSON on stdout (one document; NaN and infinities as null)."""
    print(json.dumps(json_safe(data), indent=2, allow_nan=False))


def resolve_scene(arg: str | None) -> Scene:
    """A scene from a path, or from the name of a bundled scene (the default scene if None)."""
    return load_scene(arg or DEFAULT_SCENE)


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def planned(scene: Scene, rtol: float | None, backend: str, method: str | None):
    """The scene with its "auto" values (and, given rtol, its time step) chosen by the planner for
    the integrator this backend runs; the plan's notes go to stderr (stdout may be a deck)."""
    from granchain.progress import is_quiet
    from granchain.workflows.run import integrator, plan_for

    scene, plan = plan_for(scene, backend, method, rtol)
    if plan is not None and not is_quiet():  # (--quiet: no plan lines either)
        for c in plan.choices:
            print(
                f"plan ({integrator(backend, method)}): {c.name} = {c.value:.6g}  ({shown(c.reason)})", file=sys.stderr
            )
    return scene, plan


def np_arg(text: str) -> int | str:
    """--np: a whole number of MPI ranks, or "auto"."""
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of MPI ranks or 'auto', got {text!r}") from None


def auto_np(scene: Scene, backend: str) -> int:
    """--np auto: one rank where MPI does not pay (the reference backend, a chain shorter than the
    measured crossover, one idle core), else granchain.schedule.auto_ranks over the idle cores; said
    on stderr."""
    from granchain.schedule import MPI_CROSSOVER_BEADS, auto_ranks, idle_cores
    from granchain.workflows.run import available_cores

    if backend != "lammps":
        return 1
    cores = available_cores()
    idle = idle_cores(cores)
    n = auto_ranks(scene.chain.beads, idle)
    print(
        f"--np auto: {n} rank{'s' if n > 1 else ''} for {scene.chain.beads} beads on {idle} idle of {cores} cores "
        f"(two ranks pay from {MPI_CROSSOVER_BEADS} beads on idle cores)",
        file=sys.stderr,
    )
    return n


def cmd_plan(args) -> int:
    from granchain.workflows.plan import plan_scene

    scene = resolve_scene(args.scene)
    plan = plan_scene(scene, rtol=args.rtol, method=args.method)
    s = plan.scene
    steps = math.ceil(s.run.end_time / s.run.timestep)
    if args.json:
        chosen = {c.name for c in plan.choices}
        kept = [("beads", s.chain.beads), ("end_time", s.run.end_time), ("timestep", s.run.timestep)]
        print_json(
            {
                "scene": {"title": scene.title, "source": scene.source},
                "method": plan.method,
                "rtol": plan.rtol,
                "stable_timestep": plan.stable_timestep,
                "omega_max": plan.omega_max,
                "choices": [{"name": c.name, "value": c.value, "reason": c.reason} for c in plan.choices],
                "given": [{"name": n, "value": v} for n, v in kept if n not in chosen],
                "beads": s.chain.beads,
                "end_time": s.run.end_time,
                "timestep": s.run.timestep,
                "steps": steps,
                "bead_steps": steps * s.chain.beads,
                "units": {"end_time": "s", "timestep": "s", "stable_timestep": "s", "omega_max": "rad/s"},
            }
        )
        return 0
    print(f"scene       {_scene_name(scene)}")
    print(
        f"method      {plan.method}, rtol {plan.rtol:g}; stability limit {plan.stable_timestep:.4g} s "
        f"(omega_max = {plan.omega_max:.4g} rad/s)"
    )
    for c in plan.choices:
        print(f"{c.name:11s} {c.value:.6g}  because {shown(c.reason)}")
    kept = [("beads", s.chain.beads), ("end_time", s.run.end_time), ("timestep", s.run.timestep)]
    for name, v in kept:
        if name not in {c.name for c in plan.choices}:
            print(f"{name:11s} {v:.6g}  as given in the scene")
    print(f"cost        about {steps} steps x {s.chain.beads} beads = {steps * s.chain.beads:.3g} bead-steps")
    return 0


def cmd_run(args) -> int:
    from granchain.workflows.run import integrator, run_scene

    method = integrator(args.backend, args.method)
    scene = resolve_scene(args.scene)
    np_ = 1 if args.np is None else args.np
    if args.np not in (None, "auto") and args.backend != "lammps":  # refused, not ignored
        raise UsageError(
            f"--np = {args.np}: the {args.backend} backend runs in one process; MPI ranks are for "
            "--backend lammps (drop --np)"
        )
    concrete, _ = planned(scene, args.rtol, args.backend, method)  # the plan's notes (run_scene plans it)
    if np_ == "auto":
        np_ = auto_np(concrete, args.backend)
    name = Path(args.scene).stem if args.scene else DEFAULT_SCENE
    out = args.out or f"runs/{name}-{args.backend}" + ("" if args.backend == "lammps" else f"-{method}")
    result = run_scene(
        scene,
        backend=args.backend,
        method=method,
        out=out,
        overwrite=args.overwrite,
        np_=np_,
        force=args.force,
        oversubscribe=args.oversubscribe,
        rtol=args.rtol,
        error_estimate=args.error_estimate == "on",
    )
    planned_end = scene.run.end_time is None  # "auto": the planner promised to cover the outputs
    if args.json:
        print_json({"run_dir": str(out), **result.summary})
        return _ended_too_soon(result, planned_end)
    print_result(result, out)
    return _ended_too_soon(result, planned_end)


def _ended_too_soon(result, planned_end: bool) -> int:
    """Say on stderr what the scene asked for that the run ended before measuring (a wave that had
    not passed the window's end), with why; 1 when the end time was the planner's ("auto", which
    promised to cover it), else 0 (a fixed end_time the user chose, now told what it missed)."""
    from granchain.postprocess.observables import unmeasured_outputs

    unmeasured = unmeasured_outputs(result.scene, result.solution)
    for line in unmeasured:
        print(f"granchain: not measured: {shown(line)}", file=sys.stderr)
    return 1 if unmeasured and planned_end else 0


def print_result(result, out) -> None:
    """What `granchain run` (and `granchain collect`) prints about a finished run."""
    scene = result.scene
    s = result.summary()
    print(f"scene      {_scene_name(scene)}")
    print(
        f"backend    {s['backend']} ({s['method']}), dt = {s['timestep']:g} s, {s['steps']} steps, "
        f"{s['wall_time']:.3g} s wall"
    )
    missing = s.get("observables_missing", {})
    errors = (s.get("errors") or {}).get("observables", {})
    for k, v in s["observables"].items():
        label = f"{k} ({OBSERVABLE_UNITS.get(k, '?')})"
        why = f"   not measured: {shown(missing[k])}" if v is None and k in missing else ""
        bar = ""
        if v is not None and k in errors:  # the measured error bar, or why there is none
            e = errors[k]
            bar = f" +- {e['error']:.2g}   ({e['status']})" if e["error"] is not None else f"   ({e['status']})"
        print(f"  {label:38s} {_fmt(v)}{bar}{why}")
    end_errors = (s.get("errors") or {}).get("end_peaks", {})
    for name, label in (("striker_peak_force", "striker's contact"), ("wall_peak_force", "wall's contact")):
        value = s.get(name)
        if value is None:
            continue
        e = end_errors.get(name)
        bar = (
            ""
            if e is None
            else (f" +- {e['error']:.2g}   ({e['status']})" if e["error"] is not None else f"   ({e['status']})")
        )
        print(f"  {name + ' (N)':38s} {_fmt(value)}{bar}   (the {label} peak)")
    c = s["conservation"]
    ld = scene.loading
    if ld.is_force:
        print(f"  {'impulse of the load (N s)':38s} {_fmt(c['impulse_delivered'])}   (A T delivered by the force)")
    else:
        who = "the striker's M V" if ld.kind == "striker" else "bead 1's m v0"
        print(f"  {'momentum put in at t = 0 (N s)':38s} {_fmt(scene.initial_momentum)}   ({who}; no force load)")
    free = scene.effects.far_end == "free" and not scene.effects.precompression
    print(
        f"  {'momentum at the end (N s)':38s} {_fmt(c['momentum'])}"
        + ("   (a free chain keeps what was put in)" if free else "   (the wall or the static load takes some)")
    )
    err = _fmt(c["energy_balance_error_relative"])
    print(f"  {'energy balance error (1)':38s} {err}   (relative to the energy put in)")
    e = s.get("errors")
    if e is not None:
        if e["why_none"]:
            print(f"  {'error estimate':38s} none: {shown(e['why_none'])}")
        else:
            worst = e["error_estimate"]
            where = f" at contact {e['error_estimate_contact']}" if worst is not None else ""
            n_bad = len(e["unreliable_contacts"])
            print(
                f"  {'largest peak-force error (1)':38s} {_fmt(worst)}{where}   (measured: "
                + ("reference RK4 " if e.get("companion_method") == "rk4" else "")
                + "runs at "
                + ", ".join(f"{t:g}" for t in e["companion_timesteps"])
                + f" s, {e['companion_wall_time']:.3g} s more)"
            )
            if n_bad:
                print(f"  {'peaks without an estimate':38s} {n_bad}   (peaks.csv error_status says why)")
    print(f"run directory: {shown(out)}")


def cmd_predict(args) -> int:
    from granchain.physics.predictions import predict

    scene = resolve_scene(args.scene)
    preds = predict(scene)
    if args.json:
        print_json([p.as_dict() for p in preds])
        return 0
    print(f"{'quantity':34s} {'value':>12s} {'unit':8s} {'nondim':>10s}  {'applies':7s}  source; valid when; why")
    for p in preds:
        nd = f"{p.nondim:.4g}" if p.nondim is not None else ""
        applies = "yes" if p.applies else "no"
        print(
            f"{p.name:34s} {p.value:12.5g} {p.unit:8s} {nd:>10s}  {applies:7s}  "
            + shown(f"{p.equation}; {p.valid}; {p.applies_reason}")
        )
    return 0


def cmd_compare_laws(args) -> int:
    from granchain.rundir import check_output_dir
    from granchain.workflows.laws import compare_laws, write_law_comparison

    scene = resolve_scene(args.scene)
    name = Path(args.scene).stem if args.scene else DEFAULT_SCENE
    out = args.out or f"runs/{name}-laws"
    check_output_dir(out, args.overwrite)  # before any run
    laws = tuple(x.strip() for x in args.laws.split(",") if x.strip())
    cmp = compare_laws(scene, laws, backend=args.backend, rtol=args.rtol, error_estimate=args.error_estimate == "on")
    write_law_comparison(cmp, out, overwrite=args.overwrite)
    print(f"scene      {_scene_name(scene)}")
    print(
        f"{'law':10} {'contact':44} {'F_1 (N)':>10} {'F_last (N)':>10} {'transition':>10} "
        f"{'lambda (1/contact)':>18} {'p':>14}"
    )
    for row in cmp.table():
        contact = ", ".join(f"{k}={v:.4g}" for k, v in row["contact"].items() if k != "law")
        if row["transition_contact"]:
            lo, hi = row["transition_contact_range"]
            trans = f"{row['transition_contact']} ({lo}-{hi})"
            lam = f"{row['decay_per_contact']:.3g} +- {row['decay_per_contact_stderr']:.2g}"
            pw = f"{row['inverse_power']:.3g} +- {row['inverse_power_stderr']:.2g}"
            fit = f"{trans:>10} {lam:>18} {pw:>14}"
        else:
            fit = f"  no fit: {shown(row['why_no_fit'])}"
        first = row["first_peak_force"] or float("nan")
        last = row["last_peak_force"] or float("nan")
        print(f"{row['law']:10} {contact:44} {first:>10.4g} {last:>10.4g} {fit}")
    print(f"laws directory: {shown(out)}")
    return 0


def cmd_compare(args) -> int:
    from granchain.postprocess.compare import format_table
    from granchain.workflows.compare import compare_scene

    scene = resolve_scene(args.scene)
    plan_rtol = args.rtol / 2 if scene.run.timestep is None else None  # as compare_scene plans
    np_ = args.np
    for backend, method in (("lammps", None), ("reference", args.method)):
        concrete, _ = planned(scene, plan_rtol, backend, method)  # print each backend's plan (stderr)
        if backend == "lammps" and np_ == "auto":
            np_ = auto_np(concrete, backend)
    name = Path(args.scene).stem if args.scene else DEFAULT_SCENE
    out = args.out or f"runs/{name}-compare-{args.method}"
    rows, lam, ref = compare_scene(
        scene,
        rtol=args.rtol,
        out=out,
        overwrite=args.overwrite,
        method=args.method,
        np_=np_,
        error_estimate=args.error_estimate == "on",
    )
    bad = [r.quantity for r in rows if not r.ok]
    if args.json:
        from granchain.workflows.api import compare_frame

        table = compare_frame(rows).reset_index()
        print_json(
            {
                "scene": {"title": scene.title, "source": scene.source},
                "rtol": args.rtol,
                "ok": not bad,
                "differ": bad,
                "lammps": {"method": "verlet", "timestep": lam.solution.timestep, "wall_time": lam.solution.wall_time},
                "reference": {
                    "method": args.method,
                    "timestep": ref.solution.timestep,
                    "wall_time": ref.solution.wall_time,
                },
                "rows": table.to_dict(orient="records"),
                "compare_dir": str(out),
            }
        )
        return 1 if bad else 0
    print(f"scene      {_scene_name(scene)}")
    print(f"lammps     verlet, dt = {lam.solution.timestep:g} s, {lam.solution.wall_time:.3g} s wall")
    print(f"reference  {args.method}, dt = {ref.solution.timestep:g} s, {ref.solution.wall_time:.3g} s wall")
    print(f"rtol       {args.rtol:g}")
    print(shown(format_table(rows)))
    unmeasured = [r.quantity for r in rows if not r.measured]
    if unmeasured:
        print(f"granchain: not measured (the table says why): {', '.join(unmeasured)}", file=sys.stderr)
    print(f"compare directory: {shown(out)}")
    if bad:
        print(
            f"granchain: {len(bad)} quantities differ by more than rtol = {args.rtol:g}: {', '.join(bad)}",
            file=sys.stderr,
        )
        return 1
    return 0


def cmd_plot(args) -> int:
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


def cmd_accuracy(args) -> int:
    from granchain.workflows.accuracy import accuracy_study, check_study_dir, summary_text, write_study

    scene, _ = planned(resolve_scene(args.scene), None, "reference", "rk4")
    name = Path(args.scene).stem if args.scene else DEFAULT_SCENE
    out = args.out or f"runs/{name}-accuracy"
    check_study_dir(out, args.overwrite)  # before the study runs
    study = accuracy_study(scene, methods=tuple(args.methods.split(",")), levels=args.levels, repeats=args.repeats)
    for p in write_study(study, out, overwrite=args.overwrite):
        print(p)
    print(summary_text(study))
    return 0


def cmd_render(args) -> int:
    from granchain.templates import render_deck

    if args.out and args.data:
        raise UsageError("--data prints chain.data; --out writes it (with the deck and the scene): give one of them")
    given = resolve_scene(args.scene)
    scene, plan = planned(given, None, "lammps", None)
    if args.out:
        from granchain.workflows.collect import render_dir

        out = render_dir(scene, args.out, plan, given)
        print(f"deck directory: {out} ({', '.join(sorted(p.name for p in out.iterdir()))})")
        print(f"run it with plain LAMMPS:   cd {out} && lmp -in deck.lmp   (or: mpirun -np N lmp -in deck.lmp)")
        print(f"then make it a run directory: granchain collect {out}")
        return 0
    deck = render_deck(scene)
    print(deck.data if args.data else deck.deck, end="")
    return 0


def cmd_collect(args) -> int:
    from granchain.workflows.collect import collect

    result = collect(args.run_dir, out=args.out, overwrite=args.overwrite)
    print_result(result, args.out or args.run_dir)
    return 0


def cmd_doctor(args) -> int:
    from granchain.lammps.doctor import doctor

    ok = True
    for name, good, text in doctor():
        ok &= good
        print(f"{'ok ' if good else 'BAD'} {name:16s} {text}")
    return 0 if ok else 1


def cmd_scenes(args) -> int:
    scenes = bundled_scenes()
    if args.name:
        if args.name not in scenes:
            raise SceneError(f"{args.name}: no bundled scene of that name; bundled: {', '.join(scenes)}")
        print(scenes[args.name], end="")
        return 0
    for name, text in scenes.items():
        title = parse_scene(text, source=name).title
        print(f"{name:28s} {printable(title)}")
    return 0


def cmd_materials(args) -> int:
    from granchain.physics.materials import material_table

    rows = material_table()
    if args.name:
        names = [n for n, _, _ in rows]
        if args.name not in names:
            raise UsageError(f"{args.name}: no built-in material of that name; built-in: {', '.join(names)}")
        rows = [r for r in rows if r[0] == args.name]
    print(f"{'name':20s} {'rho kg/m^3':>10s} {'E GPa':>7s} {'nu':>5s} {'yield MPa':>9s}  source")
    for name, m, source in rows:
        ys = "-" if m.yield_strength is None else f"{m.yield_strength / 1e6:.0f}"
        print(f"{name:20s} {m.density:10.0f} {m.youngs_modulus / 1e9:7.4g} {m.poisson_ratio:5.2f} {ys:>9s}  {source}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="granchain", description="Stress waves in 1D granular chains.")
    p.add_argument("--version", action="version", version=f"granchain {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="run a scene and write a run directory")
    r.add_argument("scene", nargs="?", help=f"scene file or bundled scene name (default: {DEFAULT_SCENE})")
    r.add_argument("--backend", default="reference", choices=["reference", "lammps"], help="solver backend")
    r.add_argument(
        "--method",
        default=None,
        choices=["rk4", "verlet"],
        help="integrator: reference rk4 (default) or verlet; LAMMPS is always verlet",
    )
    r.add_argument(
        "--np",
        type=np_arg,
        default=None,
        help="MPI ranks for the LAMMPS backend (default 1); auto: as many as pay for the planned chain length",
    )
    r.add_argument("--oversubscribe", action="store_true", help="allow more MPI ranks than cores (slower; for testing)")
    r.add_argument("--force", action="store_true", help="run even above the predicted stability limit")
    r.add_argument(
        "--rtol",
        type=float,
        default=None,
        help="let the planner choose the cheapest time step for this relative tolerance",
    )
    r.add_argument("--out", help="run directory (default runs/<scene>-lammps or runs/<scene>-reference-<method>)")
    r.add_argument("--overwrite", action="store_true", help="replace an existing run directory")
    r.add_argument(
        "--error-estimate",
        default="on",
        choices=["on", "off"],
        help="also run at 2 dt and 4 dt and give every number a measured error (default on; about 0.75x a run more)",
    )
    r.add_argument("--json", action="store_true", help="print the summary (summary.json and run_dir) as JSON on stdout")
    r.set_defaults(func=cmd_run)

    q = sub.add_parser("predict", help="print the paper's analytic predictions for a scene")
    q.add_argument("scene", nargs="?", help="scene file or bundled scene name")
    q.add_argument("--json", action="store_true", help="JSON output (NaN as null)")
    q.set_defaults(func=cmd_predict)

    pp = sub.add_parser("plan", help="print the planner's choices (time step, beads, end time) with reasons")
    pp.add_argument("scene", nargs="?", help="scene file or bundled scene name")
    pp.add_argument("--rtol", type=float, default=None, help="relative tolerance (default 1e-3; sets the time step)")
    pp.add_argument("--method", default="rk4", choices=["rk4", "verlet"], help="integrator the plan is for")
    pp.add_argument("--json", action="store_true", help="the plan as JSON on stdout")
    pp.set_defaults(func=cmd_plan)

    c = sub.add_parser("compare", help="run LAMMPS and the reference on a scene and compare them")
    c.add_argument("scene", nargs="?", help="scene file or bundled scene name")
    c.add_argument("--rtol", type=float, default=1e-3, help="tolerance between the two solvers (default 1e-3)")
    c.add_argument("--method", default="rk4", choices=["rk4", "verlet"], help="reference integrator")
    c.add_argument("--np", type=np_arg, default=1, help="MPI ranks for LAMMPS (default 1; auto: as many as pay)")
    c.add_argument("--out", help="output directory (default runs/<scene>-compare-<method>)")
    c.add_argument("--overwrite", action="store_true", help="replace an existing output directory")
    c.add_argument(
        "--error-estimate",
        default="on",
        choices=["on", "off"],
        help="give both runs measured error bars (companions at 2 dt and 4 dt); a difference fails only "
        "beyond rtol plus both errors (default on)",
    )
    c.add_argument(
        "--json", action="store_true", help="the table as JSON on stdout (exit 1 still means a disagreement)"
    )
    c.set_defaults(func=cmd_compare)

    cl = sub.add_parser("compare-laws", help="run a scene under two contact laws and compare their peak-force decay")
    cl.add_argument("scene", nargs="?", help="scene file or bundled scene name")
    cl.add_argument(
        "--laws", default="thornton,bilinear", help="comma-separated contact laws (default thornton,bilinear)"
    )
    cl.add_argument("--backend", default="lammps", choices=["lammps", "reference"], help="backend (default lammps)")
    cl.add_argument("--rtol", type=float, default=None, help="plan every run for this tolerance")
    cl.add_argument("--out", help="output directory (default runs/<scene>-laws)")
    cl.add_argument("--overwrite", action="store_true", help="replace an existing output directory")
    cl.add_argument("--error-estimate", default="on", choices=["on", "off"], help="error bars (default on)")
    cl.set_defaults(func=cmd_compare_laws)

    pl = sub.add_parser("plot", help="make the figures of a run directory or of a compare directory")
    pl.add_argument("run_dir", help="a run directory (granchain run) or a compare directory (granchain compare)")
    pl.add_argument("--linear", action="store_true", help="linear axes for the peak-force plot")
    pl.add_argument("--format", default="png", help="figure formats, comma-separated: png, pdf, svg (default png)")
    pl.set_defaults(func=cmd_plot)

    acc = sub.add_parser("accuracy", help="work-precision study: error vs wall time per method")
    acc.add_argument("scene", nargs="?", help="scene file or bundled scene name")
    acc.add_argument("--methods", default="lammps,rk4,verlet,dop853", help="comma-separated methods")
    acc.add_argument("--levels", type=int, default=7, help="time steps (tolerances) per method")
    acc.add_argument("--repeats", type=int, default=3, help="repeats per run (median wall time)")
    acc.add_argument("--out", help="output directory (default runs/<scene>-accuracy)")
    acc.add_argument("--overwrite", action="store_true", help="replace --out if granchain wrote it")
    acc.set_defaults(func=cmd_accuracy)

    d = sub.add_parser("render", help="print the LAMMPS deck of a scene, or write a directory plain LAMMPS runs")
    d.add_argument("scene", nargs="?", help="scene file or bundled scene name")
    d.add_argument("--data", action="store_true", help="print the data file (chain.data) instead")
    d.add_argument(
        "--out",
        help="write a new directory with deck.lmp, chain.data, scene.toml (and plan.json): run it with "
        "'lmp -in deck.lmp' there, then 'granchain collect DIR'",
    )
    d.set_defaults(func=cmd_render)

    co = sub.add_parser(
        "collect", help="make a directory that plain LAMMPS ran (granchain render --out) a run directory"
    )
    co.add_argument("run_dir", help="the directory of 'granchain render --out' after 'lmp -in deck.lmp' ran in it")
    co.add_argument("--out", help="write a new run directory here instead of adding the files to RUN_DIR")
    co.add_argument("--overwrite", action="store_true", help="replace an existing --out directory")
    co.set_defaults(func=cmd_collect)

    doc = sub.add_parser("doctor", help="report LAMMPS, MPI and plugin status")
    doc.set_defaults(func=cmd_doctor)

    rp = sub.add_parser(
        "reproduce",
        help="regenerate the paper's figures and printed numbers, with verdicts (granchain reproduce --help)",
        add_help=False,
    )
    rp.add_argument("rest", nargs=argparse.REMAINDER)  # main() hands these to granchain.reproduce.main

    s = sub.add_parser("scenes", help="list the bundled example scenes, or print one")
    s.add_argument("name", nargs="?", help="print this scene's TOML")
    s.set_defaults(func=cmd_scenes)

    for sp in (r, c, acc, cl):
        sp.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")

    mt = sub.add_parser("materials", help="list the built-in bead materials with their sources")
    mt.add_argument("name", nargs="?", help="show one material")
    mt.set_defaults(func=cmd_materials)
    from granchain.cli.campaign import add_campaign_parser
    from granchain.cli.submit import add_submit_parser

    add_campaign_parser(sub)
    add_submit_parser(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    from granchain import progress

    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["reproduce"]:  # its own parser (argparse's REMAINDER drops leading options)
        from granchain import reproduce

        return reproduce.main(argv[1:])
    args = build_parser().parse_args(argv)

    def one_line(message, category, filename, lineno, file=None, line=None):
        print(f"granchain: warning: {shown(message)}", file=sys.stderr)

    try:
        with warnings.catch_warnings(), progress.quiet(getattr(args, "quiet", False)):
            warnings.showwarning = one_line
            warnings.simplefilter("always", UserWarning)
            return args.func(args)
    except GranchainError as e:  # a user's error: one line; anything else is a bug and keeps its traceback
        print(f"granchain: error: {shown(e)}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # `granchain predict | head`: the reader has what it wanted
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - no flush error at exit
        return 0
    except KeyboardInterrupt:
        print("granchain: interrupted; no run directory was written", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
