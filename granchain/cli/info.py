"""granchain plan, predict, scenes, materials and doctor: what granchain knows, without a run."""

from __future__ import annotations

from granchain.backends import METHODS
from granchain.exceptions import UsageError
from granchain.integrators import integrator
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
        "a scene with velocity-dependent damping)",
    )
    pp.add_argument(
        "--error-estimate",
        default="on",
        choices=["on", "off", "checked"],
        help="the error bars the run's cost includes, as `granchain run --error-estimate` (default on: the "
        "companion runs at 2 dt and 4 dt, or those the scene's law asks for)",
    )
    pp.add_argument("--json", action="store_true", help="the plan as JSON on stdout")
    pp.set_defaults(func=cmd_plan)


#: what `granchain plan` costs: a run on this backend (planned_bars); what a LAMMPS run would change
PLAN_BACKEND_NOTE = (
    "the integrator, companion runs and steps here are a reference run's; a LAMMPS run's may differ: it runs "
    "velocity Verlet (planned as --method verlet), and on a bilinear or Thornton chain without a dashpot its "
    "default bars are bounds from its own runs at 2 dt and 4 dt, where the reference's Verlet takes RK4 runs "
    "that cost at most the run"
)


#: the units of `granchain info plan --json`'s numbers
PLAN_JSON_UNITS = {
    "end_time": "s",
    "timestep": "s",
    "stable_timestep": "s",
    "omega_max": "rad/s",
    "steps": "steps",
    "bead_steps": "bead-steps",
    "companions.timestep": "s",
    "companions.factor": "x timestep",
    "companions.steps": "steps",
    "companion_steps": "steps",
    "companion_bead_steps": "bead-steps",
    "total_steps": "steps",
    "total_bead_steps": "bead-steps",
}


def _companions_line(bars: dict, at_most: str, extra: int) -> str:
    """The error bars' companion runs in words (planned_bars' entry), or why there are none."""
    named = "; ".join(
        f"{c['method']} at {c['factor']:.3g} dt ({c['role']}): {c['steps']} steps" for c in bars["companions"]
    )
    if named:
        return f"{named}; together {at_most}{extra} steps"
    return f"no companion runs ({shown(bars['why_none'])})"


def cmd_plan(args) -> int:
    """The planner's choices for a scene, each with its reason, and the run's cost with its error bars'."""
    from granchain.backends import REFERENCE
    from granchain.schedule import scene_step_plan
    from granchain.workflows.plan import plan_scene
    from granchain.workflows.run import method_choice

    scene = resolve_scene(args.scene)
    method, why = method_choice(REFERENCE, args.method, scene)
    plan = plan_scene(scene, rtol=args.rtol, method=method)
    s = plan.scene
    steps = sum(g.steps for g in scene_step_plan(s))
    kept = [("beads", s.chain.beads), ("end_time", s.run.end_time), ("timestep", s.run.timestep)]
    chosen = {c.name for c in plan.choices}
    bars = planned_bars(plan, args.error_estimate)
    extra = sum(c["steps"] for c in bars["companions"])
    again = run_again_conditions(plan)
    at_most = "at most " if s.run.stop_after_contact is not None else ""
    if args.json:
        print_json(
            {
                "scene": {"title": scene.title, "source": scene.source},
                "backend": REFERENCE.name,
                "backend_note": PLAN_BACKEND_NOTE,
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
                "error_estimate": args.error_estimate,
                "companions": bars["companions"],
                "why_no_companions": bars["why_none"],
                "companion_steps": extra,
                "companion_bead_steps": extra * s.chain.beads,
                "total_steps": steps + extra,
                "total_bead_steps": (steps + extra) * s.chain.beads,
                "steps_are_upper_bounds": bool(at_most),
                "not_counted": bars["not_counted"],
                "run_again": again,
                "units": dict(PLAN_JSON_UNITS),
            }
        )
        return 0
    print(f"scene       {scene_name(scene)}")
    print(f"backend     {REFERENCE.name}: {PLAN_BACKEND_NOTE}")
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
    b = s.chain.beads
    print(f"cost        the run: {at_most}{steps} steps x {b} beads = {steps * b:.3g} bead-steps")
    print(f"error bars  --error-estimate {args.error_estimate}: {_companions_line(bars, at_most, extra)}")
    print(
        f"total       {at_most}{steps + extra} steps x {b} beads = {(steps + extra) * b:.3g} bead-steps"
        + (f" ({(steps + extra) / steps:.2f}x the run)" if steps else "")
    )
    for note in bars["not_counted"]:
        print(f"            not counted: {shown(note)}")
    for name, when in again.items():
        print(f"may rerun   {name}: {shown(when)}")
    if not again:
        print("may rerun   no: neither the time step nor the end time can change after the first run")
    return 0


def planned_bars(plan, error_estimate: str) -> dict:
    """The companion runs a reference run of the plan's scene makes for its error bars (error_estimate
    "on", "off" or "checked", as `granchain run --error-estimate`), from the function the run's error
    estimate follows (error_estimates.planned_companions): {"companions": [{method, role, factor,
    timestep, steps}], "why_none": why there are none, or None, "not_counted": what the steps leave out}."""
    from granchain.backends import REFERENCE
    from granchain.physics.laws import law_class
    from granchain.workflows.error_estimates import (
        RK4_STEP_COST,
        companion_steps,
        planned_companions,
        withheld_because,
    )

    s = plan.scene
    runs = []
    if error_estimate != "off":
        runs = planned_companions(
            s, plan.method, plan.stable_timestep, error_estimate == "checked", numpy_speed=REFERENCE.numpy_speed
        )
    not_counted = []
    locating = any(integrator(m).locates_kinks for m in {plan.method, *(c.method for c in runs)})
    if locating and law_class(s.contact.law).slope_kinks:  # (IntegratorFacts.locates_kinks: RK4's event location)
        not_counted.append(
            "RK4's extra tries at every kink crossing (ChainSolution.extra_steps), known only after a run"
        )
    if {c.method for c in runs} - {plan.method}:
        not_counted.append(
            f"an RK4 step costs about {RK4_STEP_COST:g} Verlet steps in numpy (error_estimates.RK4_STEP_COST): "
            "steps of both are summed as steps"
        )
    dt = s.run.timestep
    why = None
    if error_estimate == "off":
        why = "--error-estimate off"
    elif not runs:
        why = withheld_because(plan.method, s) or f"2 dt = {2 * dt:.3g} s is above the stability limit: no estimate"
    return {
        "companions": [
            {
                "method": c.method,
                "role": c.role,
                "factor": c.factor,
                "timestep": c.factor * dt,
                "steps": companion_steps(s, c.factor),
            }
            for c in runs
        ],
        "why_none": why,
        "not_counted": not_counted,
    }


def run_again_conditions(plan) -> dict[str, str]:
    """When a run of this plan is run again after its first run (workflows.run: refined_plan, then
    extended_plan), by the conditions those functions check before they look at the run: name -> when.
    Its companions then run at the new plan's step and end, so its whole cost grows with it."""
    from granchain.workflows.plan import LINEAR_HORIZON, MAX_REFINE_STEP, REFINE_ABOVE

    s = plan.scene
    chosen = {c.name for c in plan.choices}
    out = {}
    if "timestep" in chosen:
        out["refined"] = (
            "run again at a finer step (at most "
            f"{MAX_REFINE_STEP:g}x finer, companions with it) when the first run's smallest measured peak is so far "
            f"below the force scale that the error model's error times their ratio exceeds {REFINE_ABOVE:g} x rtol "
            "(PlanRefinedWarning; plan.refined_plan)"
        )
    if "end_time" in chosen and "beads" not in chosen and s.run.stop_after_contact is not None and s.n_contacts:
        out["extended"] = (
            "run again, longer (to at most "
            f"{LINEAR_HORIZON:g}x the slowest front's crossing of the whole chain, its stop check ending it), when the "
            "first run reached its end before the window's last contact or the wall's peak was measured "
            "(PlanExtendedWarning; plan.extended_plan)"
        )
    return out


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
