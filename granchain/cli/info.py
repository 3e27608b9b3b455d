"""granchain plan, predict, scenes, materials and doctor: what granchain knows, without a run."""

from __future__ import annotations

import math

from granchain.backends import METHODS
from granchain.exceptions import UsageError
from granchain.results import printable
from granchain.scene import SceneError, bundled_scenes, parse_scene

from .terminal import SCENE_HELP, print_json, resolve_scene, scene_name, shown


def add_predict_parser(sub) -> None:
    """granchain predict SCENE [--json]."""
    q = sub.add_parser("predict", help="print the paper's analytic predictions for a scene")
    q.add_argument("scene", nargs="?", help=SCENE_HELP)
    q.add_argument("--json", action="store_true", help="JSON output (NaN as null)")
    q.set_defaults(func=cmd_predict)


def cmd_predict(args) -> int:
    """Every analytic prediction for a scene, whether it applies and why."""
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


def add_plan_parser(sub) -> None:
    """granchain plan SCENE [--rtol X] [--method M] [--json]."""
    pp = sub.add_parser("plan", help="print the planner's choices (time step, beads, end time) with reasons")
    pp.add_argument("scene", nargs="?", help=SCENE_HELP)
    pp.add_argument("--rtol", type=float, default=None, help="relative tolerance (default 1e-3; sets the time step)")
    pp.add_argument(
        "--method",
        default=None,
        choices=list(METHODS),
        help="integrator the plan is for (default: the one `granchain run` uses on the reference: rk4, or verlet on "
        "a scene with a dashpot)",
    )
    pp.add_argument("--json", action="store_true", help="the plan as JSON on stdout")
    pp.set_defaults(func=cmd_plan)


def cmd_plan(args) -> int:
    """The planner's choices for a scene, each with its reason, and the run's cost."""
    from granchain.backends import REFERENCE
    from granchain.workflows.plan import plan_scene
    from granchain.workflows.run import method_choice

    scene = resolve_scene(args.scene)
    method, why = method_choice(REFERENCE, args.method, scene)
    plan = plan_scene(scene, rtol=args.rtol, method=method)
    s = plan.scene
    steps = math.ceil(s.run.end_time / s.run.timestep)
    kept = [("beads", s.chain.beads), ("end_time", s.run.end_time), ("timestep", s.run.timestep)]
    chosen = {c.name for c in plan.choices}
    if args.json:
        print_json(
            {
                "scene": {"title": scene.title, "source": scene.source},
                "method": plan.method,
                "method_reason": why,
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
    print(f"scene       {scene_name(scene)}")
    print(
        f"method      {plan.method}, rtol {plan.rtol:g}; stability limit {plan.stable_timestep:.4g} s "
        f"(omega_max = {plan.omega_max:.4g} rad/s)"
    )
    if why is not None:
        print(f"            ({shown(why)})")
    for c in plan.choices:
        print(f"{c.name:11s} {c.value:.6g}  because {shown(c.reason)}")
    for name, v in kept:
        if name not in chosen:
            print(f"{name:11s} {v:.6g}  as given in the scene")
    print(f"cost        about {steps} steps x {s.chain.beads} beads = {steps * s.chain.beads:.3g} bead-steps")
    return 0


def add_doctor_parser(sub) -> None:
    """granchain doctor."""
    doc = sub.add_parser("doctor", help="report LAMMPS, MPI and plugin status")
    doc.set_defaults(func=cmd_doctor)


def cmd_doctor(args) -> int:
    """LAMMPS, MPI and the plugin's status, one line each; exit 1 if one is bad."""
    from granchain.lammps.doctor import doctor

    ok = True
    for name, good, text in doctor():
        ok &= good
        print(f"{'ok ' if good else 'BAD'} {name:16s} {text}")
    return 0 if ok else 1


def add_scenes_parser(sub) -> None:
    """granchain scenes [NAME]."""
    s = sub.add_parser("scenes", help="list the bundled example scenes, or print one")
    s.add_argument("name", nargs="?", help="print this scene's TOML")
    s.set_defaults(func=cmd_scenes)


def cmd_scenes(args) -> int:
    """The bundled scenes with their titles, or one scene's text."""
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


def add_materials_parser(sub) -> None:
    """granchain materials [NAME]."""
    mt = sub.add_parser("materials", help="list the built-in bead materials with their sources")
    mt.add_argument("name", nargs="?", help="show one material")
    mt.set_defaults(func=cmd_materials)


def cmd_materials(args) -> int:
    """The built-in bead materials (density, E, nu, yield) with their sources."""
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
