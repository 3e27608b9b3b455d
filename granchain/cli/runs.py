"""granchain run, compare, compare-laws and accuracy: the subcommands that run scenes."""

from __future__ import annotations

import sys

from granchain.backends import BACKENDS, LAMMPS, METHODS, REFERENCE, backend_named
from granchain.exceptions import UsageError

from .terminal import (
    DEFAULT_SCENE,
    SCENE_HELP,
    add_quiet,
    auto_np,
    ended_too_soon,
    np_arg,
    planned,
    print_json,
    print_result,
    resolve_scene,
    scene_name,
    scene_stem,
    shown,
)

#: --error-estimate's choices as the API's error_estimate (granchain.workflows.error_estimates)
ERROR_ESTIMATE = {"on": True, "off": False, "checked": "checked"}


def add_run_parser(sub) -> None:
    """granchain run SCENE [--backend B] [--method M] [--np N|auto] [--rtol X] [--out DIR] ..."""
    r = sub.add_parser("run", help="run a scene and write a run directory")
    r.add_argument("scene", nargs="?", help=f"{SCENE_HELP} (default: {DEFAULT_SCENE})")
    r.add_argument("--backend", default=REFERENCE.name, choices=list(BACKENDS), help="solver backend")
    r.add_argument(
        "--method",
        default=None,
        choices=list(METHODS),
        help="integrator: reference rk4 (default; verlet on a scene with velocity-dependent damping, where rk4's peak "
        "is the elastic "
        "force where the overlap turns and it gives no error bars) or verlet; LAMMPS is always verlet",
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
        choices=["on", "off", "checked"],
        help="give every number an error from companion runs (default on): at 2 dt and 4 dt (3/4 of the run's "
        "steps more); on a kinked law (bilinear, Thornton) bounds from those on LAMMPS, one run at 2 dt on reference "
        "RK4 (half), RK4 runs at their own larger steps on reference Verlet where they cost at most the run; "
        "`granchain plan --error-estimate` counts them; checked: RK4's estimates also checked by a run at dt / 2 "
        "(2x a run more), one it contradicts withheld, and Verlet's on a kinked law measured against RK4 runs "
        "instead of bounded",
    )
    r.add_argument("--json", action="store_true", help="print the summary (summary.json and run_dir) as JSON on stdout")
    add_quiet(r)
    r.set_defaults(func=cmd_run)


def cmd_run(args) -> int:
    """Run a scene on a backend, write its run directory and print its numbers."""
    from granchain.workflows.run import integrator, ranks_refused, run_scene

    backend = backend_named(args.backend)
    scene = resolve_scene(args.scene)
    method = integrator(backend, args.method, scene)  # (run_scene says why where the scene chose it)
    np_ = 1 if args.np is None else args.np
    if args.np not in (None, "auto") and not backend.mpi:  # refused, not ignored
        raise UsageError(ranks_refused(args.np, backend))
    concrete, _ = planned(scene, args.rtol, backend, method)  # the plan's notes (run_scene plans it)
    if np_ == "auto":
        np_ = auto_np(concrete, backend)
    # one integrator: the backend's name says it; several: the run's directory names its own
    out = args.out or f"runs/{scene_stem(args)}-{backend.name}" + ("" if len(backend.methods) == 1 else f"-{method}")
    result = run_scene(
        scene,
        backend=backend,
        method=args.method,
        out=out,
        overwrite=args.overwrite,
        np_=np_,
        force=args.force,
        oversubscribe=args.oversubscribe,
        rtol=args.rtol,
        error_estimate=ERROR_ESTIMATE[args.error_estimate],
    )
    planned_end = scene.run.end_time is None  # "auto": the planner promised to cover the outputs
    if args.json:
        print_json({"run_dir": str(out), **result.summary})
        return ended_too_soon(result, planned_end)
    print_result(result, out)
    return ended_too_soon(result, planned_end)


def add_compare_parser(sub) -> None:
    """granchain compare SCENE [--rtol X] [--method M] [--np N|auto] [--out DIR] ..."""
    c = sub.add_parser("compare", help="run LAMMPS and the reference on a scene and compare them")
    c.add_argument("scene", nargs="?", help=SCENE_HELP)
    c.add_argument("--rtol", type=float, default=1e-3, help="tolerance between the two solvers (default 1e-3)")
    c.add_argument(
        "--method",
        default=None,
        choices=list(REFERENCE.methods),
        help="reference integrator (default rk4; verlet on a scene with velocity-dependent damping, where rk4's peak "
        "is the elastic "
        "force where the overlap turns, not the total force's maximum that LAMMPS reports)",
    )
    c.add_argument("--np", type=np_arg, default=1, help="MPI ranks for LAMMPS (default 1; auto: as many as pay)")
    c.add_argument("--out", help="output directory (default runs/<scene>-compare-<method>)")
    c.add_argument("--overwrite", action="store_true", help="replace an existing output directory")
    c.add_argument(
        "--error-estimate",
        default="on",
        choices=["on", "off", "checked"],
        help="give both runs error bars from companion runs (as `granchain run --error-estimate`); a "
        "difference fails only beyond rtol plus both errors (default on); checked: RK4's also checked by a "
        "run at dt / 2, and "
        "Verlet's on a kinked law measured against RK4 runs",
    )
    c.add_argument(
        "--json", action="store_true", help="the table as JSON on stdout (exit 1 still means a disagreement)"
    )
    add_quiet(c)
    c.set_defaults(func=cmd_compare)


def cmd_compare(args) -> int:
    """LAMMPS and the reference on one scene, one table; exit 1 when they differ beyond their errors."""
    from granchain.postprocess.comparison_table import format_table
    from granchain.workflows.compare_backends import compare_scene, reference_method

    scene = resolve_scene(args.scene)
    from granchain.progress import is_quiet

    ref_method, why_method = reference_method(scene, args.method)  # (a dashpot: verlet, like LAMMPS)
    if why_method and not is_quiet():  # (with the plan's lines; the header says it too)
        print(f"granchain: the reference runs {why_method}", file=sys.stderr)
    plan_rtol = args.rtol / 2 if scene.run.timestep is None else None  # as compare_scene plans
    np_ = args.np
    for backend, method in ((LAMMPS, None), (REFERENCE, ref_method)):
        concrete, _ = planned(scene, plan_rtol, backend, method)  # print each backend's plan (stderr)
        if backend.mpi and np_ == "auto":
            np_ = auto_np(concrete, backend)
    out = args.out or f"runs/{scene_stem(args)}-compare-{ref_method}"
    rows, lam, ref = compare_scene(
        scene,
        rtol=args.rtol,
        out=out,
        overwrite=args.overwrite,
        method=ref_method,
        np_=np_,
        error_estimate=ERROR_ESTIMATE[args.error_estimate],
    )
    bad = [r.quantity for r in rows if not r.ok]
    if args.json:
        _print_compare_json(args, scene, rows, lam, ref, out, bad, ref_method, why_method)
        return 1 if bad else 0
    print(f"scene      {scene_name(scene)}")
    print(f"lammps     verlet, dt = {lam.solution.timestep:g} s, {lam.solution.wall_time:.3g} s wall")
    print(f"reference  {ref_method}, dt = {ref.solution.timestep:g} s, {ref.solution.wall_time:.3g} s wall")
    if why_method:
        print(f"           ({why_method})")
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


def _print_compare_json(args, scene, rows, lam, ref, out, bad, method, why_method) -> None:
    from granchain.workflows.comparison_frame import compare_frame

    table = compare_frame(rows).reset_index()
    print_json(
        {
            "scene": {"title": scene.title, "source": scene.source},
            "rtol": args.rtol,
            "ok": not bad,
            "differ": bad,
            LAMMPS.name: {
                "method": LAMMPS.integrator(None, scene),
                "timestep": lam.solution.timestep,
                "wall_time": lam.solution.wall_time,
            },
            REFERENCE.name: {
                "method": method,
                "method_reason": why_method,
                "timestep": ref.solution.timestep,
                "wall_time": ref.solution.wall_time,
            },
            "rows": table.to_dict(orient="records"),
            "compare_dir": str(out),
        }
    )


def add_compare_laws_parser(sub) -> None:
    """granchain compare-laws SCENE [--laws L1,L2] [--backend B] [--rtol X] [--out DIR] ..."""
    cl = sub.add_parser("compare-laws", help="run a scene under two contact laws and compare their peak-force decay")
    cl.add_argument("scene", nargs="?", help=SCENE_HELP)
    cl.add_argument(
        "--laws", default="thornton,bilinear", help="comma-separated contact laws (default thornton,bilinear)"
    )
    choices = [LAMMPS.name, *(b for b in BACKENDS if b != LAMMPS.name)]  # the default first
    cl.add_argument("--backend", default=LAMMPS.name, choices=choices, help=f"backend (default {LAMMPS.name})")
    cl.add_argument("--rtol", type=float, default=None, help="plan every run for this tolerance")
    cl.add_argument("--out", help="output directory (default runs/<scene>-laws)")
    cl.add_argument("--overwrite", action="store_true", help="replace an existing output directory")
    cl.add_argument("--error-estimate", default="on", choices=["on", "off"], help="error bars (default on)")
    add_quiet(cl)
    cl.set_defaults(func=cmd_compare_laws)


def cmd_compare_laws(args) -> int:
    """One chain and load under several contact laws: each one's peak-force decay and its fits."""
    from granchain.rundir import check_output_dir
    from granchain.workflows.law_comparison import compare_laws, write_law_comparison

    scene = resolve_scene(args.scene)
    out = args.out or f"runs/{scene_stem(args)}-laws"
    check_output_dir(out, args.overwrite)  # before any run
    laws = tuple(x.strip() for x in args.laws.split(",") if x.strip())
    cmp = compare_laws(scene, laws, backend=args.backend, rtol=args.rtol, error_estimate=args.error_estimate == "on")
    write_law_comparison(cmp, out, overwrite=args.overwrite)
    print(f"scene      {scene_name(scene)}")
    print(
        f"{'law':10} {'contact':44} {'F_1 (N)':>10} {'F_last (N)':>10} {'transition':>10} "
        f"{'lambda (1/contact)':>18} {'p':>14}"
    )
    rows = cmp.table()
    for row in rows:
        contact = ", ".join(f"{k}={c['value']:.4g}" for k, c in row["coefficients"].items())
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
    print("coefficients (nominal bead-bead contact):")
    for row in rows:
        for k, c in row["coefficients"].items():
            print(f"  {row['law']:10} {k:18} {c['value']:<10.4g} from {shown(c['source'])}")
    for row in rows:
        if row["contacts_not_complete"]:
            print(
                f"  {row['law']}: {len(row['contacts_not_complete'])} contacts' peaks not complete by the end "
                "of the run: not fitted (drawn open, as lower bounds, only where no peak is complete)"
            )
    print(f"laws directory: {shown(out)}")
    return 0


def add_accuracy_parser(sub) -> None:
    """granchain accuracy SCENE [--methods M1,M2] [--levels N] [--repeats N] [--out DIR]."""
    acc = sub.add_parser("accuracy", help="work-precision study: error vs wall time per method")
    acc.add_argument("scene", nargs="?", help=SCENE_HELP)
    acc.add_argument(
        "--methods",
        default="lammps,rk4,verlet,dop853",
        help="comma-separated methods among lammps, rk4, verlet, dop853 (default all four; dop853 runs on a free "
        "elastic Hertz chain only: no dashpot, wall, striker or precompression). Each is measured against a "
        "converged run whose peak is the same quantity: RK4, but Verlet for lammps and verlet on a scene with a "
        "dashpot (RK4's peak there is the elastic force where the overlap turns)",
    )
    acc.add_argument("--levels", type=int, default=7, help="time steps (tolerances) per method, at least 1")
    acc.add_argument("--repeats", type=int, default=3, help="repeats per run (median wall time), at least 1")
    acc.add_argument("--out", help="output directory (default runs/<scene>-accuracy)")
    acc.add_argument("--overwrite", action="store_true", help="replace --out if granchain wrote it")
    add_quiet(acc)
    acc.set_defaults(func=cmd_accuracy)


def cmd_accuracy(args) -> int:
    """Error against wall time per method, the plan's point marked."""
    from granchain.progress import is_quiet
    from granchain.workflows.accuracy import (
        accuracy_study,
        check_study_dir,
        check_study_options,
        study_method,
        summary_text,
        write_study,
    )

    methods = check_study_options(args.methods, args.levels, args.repeats)  # before any run
    scene = resolve_scene(args.scene)
    # planned for the integrator the study measures (a dashpot: Verlet, like LAMMPS; study_method)
    method, why_method = study_method(scene, methods)
    if why_method and scene.needs_plan and not is_quiet():
        print(f"granchain: the study plans with {why_method}", file=sys.stderr)
    scene, _ = planned(scene, None, REFERENCE, method)
    out = args.out or f"runs/{scene_stem(args)}-accuracy"
    check_study_dir(out, args.overwrite)  # before the study runs
    study = accuracy_study(scene, methods=methods, levels=args.levels, repeats=args.repeats)
    for p in write_study(study, out, overwrite=args.overwrite):
        print(p)
    print(summary_text(study))
    return 0
