"""granchain accuracy: a work-precision study of one scene — what each level of accuracy costs.

Methods: LAMMPS velocity Verlet (granchain's pair styles), reference RK4, reference Verlet, and
SciPy's DOP853 (a free elastic Hertz chain only) as an outside yardstick. For each, a range of time
steps (tolerances for DOP853); for each run, the error of the scene's observables (peak force of the
measured contacts, wave speed) against a converged run whose peak is the same quantity (RK4; Verlet
for Verlet and LAMMPS on a scene with velocity-dependent damping, where RK4's peak is another: reference_method),
whose own error is estimated by Richardson extrapolation, and the wall time (median of repeats;
LAMMPS's start-up and the plugin build are one-time costs, reported apart). Also the error of
dump-derived peaks against the dump interval.
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass, replace

import numpy as np

from granchain.exceptions import UsageError
from granchain.integrators import INTEGRATORS, integrator
from granchain.postprocess.comparison_table import peak_definition
from granchain.postprocess.observables import fit_wave_speed
from granchain.problem import ChainProblem, contact_positions
from granchain.reference.scipy_solver import solve_chain_dop853
from granchain.reference.solver import solve_chain
from granchain.workflows.accuracy_model import (
    DOP853_MIN_RTOL,
    METHODS,
    PLAN_RTOL,
    STUDY_METHODS,
    TARGETS,
    AccuracyStudy,
    Point,
    Reference,
    StudyMethod,
)
from granchain.workflows.accuracy_report import check_study_dir, reference_lines, summary_text, write_study
from granchain.workflows.plan import plan_scene


def _errors(scene, sol, ref, idx) -> tuple[float, float | None]:
    e = float(np.max(np.abs(sol.peak_force[idx] - ref.peak_force[idx]) / ref.peak_force[idx]))
    cs = idx + 1
    at = contact_positions(scene)  # the contacts' real positions (a taper's are not a diameter apart)
    a = fit_wave_speed(cs, sol.time_of_peak[idx], scene.diameter, at)
    b = fit_wave_speed(cs, ref.time_of_peak[idx], scene.diameter, at)
    es = abs(a[0] - b[0]) / b[0] if a and b else None
    return e, es


def check_study_options(methods, levels: int, repeats: int) -> tuple[str, ...]:
    """The methods as a tuple, or a UsageError naming the option and the fix (before any run):
    methods known and not empty (METHODS), levels and repeats at least 1."""
    if isinstance(methods, str):
        methods = tuple(m.strip() for m in methods.split(","))
    methods = tuple(methods)
    bad = [m for m in methods if m not in METHODS]
    if not methods or bad:
        what = f"unknown method(s) {', '.join(repr(m) for m in bad)}" if bad else "no method given"
        raise UsageError(f"--methods: {what}; give a comma-separated list of {', '.join(METHODS)}")
    if isinstance(levels, bool) or not isinstance(levels, int) or levels < 1:
        raise UsageError(f"--levels {levels!r}: give a whole number of settings per method, at least 1")
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise UsageError(f"--repeats {repeats!r}: give a whole number of timed runs per setting, at least 1")
    return tuple(dict.fromkeys(methods))


def study_method(scene, methods=METHODS) -> tuple[str, str | None]:
    """The integrator a study of these methods plans the scene's "auto" values with, and why where the
    scene chose it: the reference's default for the scene (workflows.run.method_choice: Verlet on a
    scene with velocity-dependent damping), unless no method the study measures runs it; then the one they run (RK4 for
    rk4 and dop853 alone, Verlet for lammps and verlet alone)."""
    from granchain.backends import REFERENCE
    from granchain.workflows.run import method_choice

    default, why = method_choice(REFERENCE, None, scene)
    runs = {STUDY_METHODS[m].integrator.name for m in check_study_options(methods, 1, 1)}
    if default in runs:
        return default, why
    return runs.pop(), None  # (one integrator: the default is among any two)


def reference_method(m: str, scene) -> str:
    """The integrator of the converged run method m is measured against: the first registered
    (granchain.integrators.INTEGRATORS: RK4, which converges cheapest, then Verlet) whose peak is the
    quantity m's peak is (postprocess.comparison_table.peak_definition). With a dashpot RK4's peak is
    the elastic force where the overlap turns, Verlet's and LAMMPS's the total force's maximum: 4.5e-3
    apart on an 8-bead brass chain at 1 m/s with gamma = 20 N s/m, at every step, which against RK4 read
    as Verlet's step error (order 0.89, the planned step "missing" rtol 1e-3 by 4.7e-3 where Verlet
    against a 16x finer Verlet differs by 1.6e-4)."""
    peak = peak_definition(STUDY_METHODS[m].integrator.name, scene)
    return next(name for name in INTEGRATORS if peak_definition(name, scene) == peak)


def dop853_skipped_because(scene, problem: ChainProblem) -> str | None:
    """Why the DOP853 yardstick cannot measure this scene, or None: it integrates a free elastic Hertz
    chain (reference.scipy_solver), so a law with history, a dashpot, a wall, a striker or
    precompression is another problem to it (a striker scene read 0.61 from RK4 at every rtol,
    precompression 0.03)."""
    if scene.contact.law_class.history:
        return "DOP853 integrates a state without history: not run on a law with history"
    missing = [
        name
        for name, on in (
            (problem.damping_part.words(problem.damping_coefficient), problem.damping_part.velocity_dependent),
            ("a wall", problem.wall_law is not None),
            ("a striker", problem.striker_mass is not None),
            ("precompression", problem.precompression),
        )
        if on
    ]
    if missing:
        return f"DOP853 integrates a free elastic Hertz chain, without {' or '.join(missing)}: not run on this scene"
    return None


@dataclass
class _Converged:
    """The peaks of a converged run (an extrapolation of runs, or the finest run), the two estimates
    whose difference over ``divisor`` is its own error (Richardson), and its finest run."""

    peak_force: np.ndarray
    time_of_peak: np.ndarray
    coarse: np.ndarray  # peak forces of the coarser estimate
    divisor: float
    finest: object  # ChainSolution: its peaks' times say which contacts the wave passed
    reference: Reference  # (its error set by error())

    def error(self, idx) -> float:
        """Its own error: the largest relative difference of the measured contacts' estimates / divisor."""
        fine = self.peak_force[idx]
        return float(np.max(np.abs(self.coarse[idx] - fine) / np.abs(fine))) / self.divisor


def _converged(problem, scene, end: float, h: float, method: str) -> _Converged:
    """A converged run of method from runs at steps down to h / 2, and how its own error is estimated.

    An integrator of high order (IntegratorFacts.extrapolated_reference False: RK4): the run at h / 2,
    its error |Q(h) - Q(h / 2)| / (2^p - 1) (RK4: / 15, order 4), or |Q(h) - Q(h / 2)| with a dashpot,
    where RK4's error follows no order (error_estimates.withheld_because). Else (Verlet: first order
    with a dashpot, the dashpot sees half-step velocities, error_estimates.integrator_order) a finest
    run would carry its error into every point it judges (the planned step's 1.6e-4 read as 1.45e-4
    against Verlet at an 8x finer step): the runs at 2h, h and h / 2 are extrapolated in pairs
    (Richardson at the integrator's order) and the finer extrapolation is the reference, its error the
    two extrapolations' difference.
    """
    from granchain.workflows.error_estimates import integrator_order, withheld_because

    peak = peak_definition(method, scene)
    facts = integrator(method)
    if not facts.extrapolated_reference:
        a, b = solve_chain(problem, end, h, method), solve_chain(problem, end, h / 2, method)
        unordered = withheld_because(method, scene) is not None
        how = "the finer of runs at dt and 2 dt, its error " + (
            f"their difference ({facts.label}'s error follows no order with {scene.damping.phrase})"
            if unordered
            else f"their difference / {2**facts.order - 1} (order {facts.order})"
        )
        info = Reference(method, h / 2, float("nan"), peak, (), how)
        divisor = 1.0 if unordered else float(2**facts.order - 1)
        return _Converged(b.peak_force, b.time_of_peak, a.peak_force, divisor, b, info)
    p = integrator_order(method, scene)
    runs = [solve_chain(problem, end, s, method) for s in (2 * h, h, h / 2)]

    def extrapolated(name: str, i: int) -> np.ndarray:
        fine, coarse = getattr(runs[i + 1], name), getattr(runs[i], name)
        return fine + (fine - coarse) / (2**p - 1)

    how = (
        f"Richardson (order {p}) of runs at dt and 2 dt, its error the difference from the same of runs "
        "at 2 dt and 4 dt"
    )
    info = Reference(method, h / 2, float("nan"), peak, (), how)
    return _Converged(
        extrapolated("peak_force", 1),
        extrapolated("time_of_peak", 1),
        extrapolated("peak_force", 0),
        1.0,
        runs[-1],
        info,
    )


def accuracy_study(
    scene, methods=METHODS, levels: int = 5, repeats: int = 3, dump_intervals: bool = True
) -> AccuracyStudy:
    """Run the scene with each method at `levels` settings (``repeats`` timings each) against a
    converged run of an integrator whose peak is the same quantity (reference_method: RK4, but Verlet
    for Verlet and LAMMPS on a scene with velocity-dependent damping): errors, orders and prices for the work-precision
    diagram.

    The study measures the peak forces of bead-bead contacts (a striker's or a wall's contact is
    not among them); a scene without one (a single bead) is a UsageError, as are the options
    check_study_options refuses and a study left with no method to run (DOP853 alone on a scene it
    does not model: dop853_skipped_because).
    """
    methods = check_study_options(methods, levels, repeats)
    if scene.needs_plan:
        scene = plan_scene(scene, method=study_method(scene, methods)[0]).scene
    contacts = _study_contacts(scene)
    idx = contacts - 1
    problem = ChainProblem.from_scene(scene)
    skipped = {}
    if "dop853" in methods and (why := dop853_skipped_because(scene, problem)):
        skipped["dop853"] = why
    methods = tuple(m for m in methods if m not in skipped)
    if not methods:
        raise UsageError(f"{scene.source}: no method left to measure: {'; '.join(skipped.values())}")
    end = scene.run.end_time
    ladders, planned = _study_steps(scene, methods)
    # the converged references, one per peak definition the methods measure: a quarter of the finest
    # step the study runs (ladders and plans) and half that
    finest = min([*(ladder / 2 ** (levels - 1) for ladder in ladders.values()), *planned.values()]) / 4
    against = {m: reference_method(m, scene) for m in methods}
    refs = {r: _converged(problem, scene, end, finest, r) for r in dict.fromkeys(against.values())}
    passed = np.ones(idx.size, dtype=bool)
    for c in refs.values():
        passed &= c.finest.time_of_peak[idx] < 0.99 * c.finest.end_time  # the leading wave has passed them
    if not passed.any():
        raise UsageError(
            "no measured contact is passed by the leading wave before the end of the run: "
            "lengthen end_time or measure contacts nearer the loaded end"
        )
    contacts, idx = contacts[passed], idx[passed]
    references = {  # their own errors over the contacts measured
        r: replace(c.reference, error=c.error(idx), measures=tuple(m for m in methods if against[m] == r))
        for r, c in refs.items()
    }
    study = AccuracyStudy(
        scene=scene,
        contacts=contacts,
        reference_timestep=finest / 2,
        reference_error=max(r.error for r in references.values()),
        references=references,
        skipped=skipped,
    )
    if len(refs) > 1:
        a, b = (c.peak_force[idx] for c in refs.values())
        study.definition_gap = float(np.max(np.abs(a - b) / np.abs(b)))

    for m in methods:
        if m == "dop853":
            settings = [r for r in (10.0**-e for e in range(4, 4 + 2 * levels, 2)) if r >= DOP853_MIN_RTOL]
        else:
            settings = [ladders[m] / 2**j for j in range(levels)]
        ref = refs[against[m]]
        for s in settings:
            study.points.append(_measure(study, scene, problem, m, s, repeats, ref, idx, against[m]))
        if m != "dop853":
            # the current plan's point: the step the planner chooses for PLAN_RTOL with this integrator
            study.plan_points.append(_measure(study, scene, problem, m, planned[m], repeats, ref, idx, against[m]))
    if dump_intervals and "lammps" in methods:
        study.dump_errors = _dump_interval_errors(scene, ladders["lammps"] / 4)
    return study


def _study_contacts(scene) -> np.ndarray:
    """The 1-based bead-bead contacts the study measures: the scene's peak contacts, or its window; a
    UsageError where there is none (a single bead)."""
    a, b = scene.window
    contacts = np.asarray(
        scene.peak_contacts if isinstance(scene.outputs.peak_force, tuple) else range(a, b + 1), dtype=int
    )
    if contacts.size == 0:
        raise UsageError(
            f"{scene.source}: no bead-bead contact to measure (the chain has {scene.chain.beads} bead(s)); "
            "the accuracy study compares bead-bead contacts' peak forces: use a chain of at least two beads"
        )
    return contacts


def _study_steps(scene, methods) -> tuple[dict[str, float], dict[str, float]]:
    """The top of every integrator's time-step ladder, and each studied one's step planned for PLAN_RTOL."""
    # time-step ladders: from half the stability limit down by factors of 2 (the planner's own
    # choice lies inside; starting coarser shows where each method stops being usable)
    ladders = {
        m: 0.5 * plan_scene(scene, method=STUDY_METHODS[m].integrator.name).stable_timestep
        for m in METHODS
        if m != "dop853"
    }
    # each integrator's step planned for PLAN_RTOL (the stars on the diagram)
    planned = {
        m: plan_scene(scene, rtol=PLAN_RTOL, method=STUDY_METHODS[m].integrator.name).scene.run.timestep
        for m in methods
        if m != "dop853"
    }
    return ladders, planned


def _measure(study: AccuracyStudy, scene, problem, m: str, s: float, repeats: int, ref, idx, against: str) -> Point:
    """One point of the diagram: method m at setting s (time step, or DOP853's rtol), median wall time."""
    walls, sol = [], None
    for _ in range(repeats):
        if m == "lammps":
            from granchain.lammps.runner import cleanup, run_lammps

            res, work = run_lammps(replace(scene, run=replace(scene.run, timestep=s)))
            cleanup(work)
            sol = res.solution
            study.one_time.setdefault("lammps_startup_time", res.extra.get("startup_time"))
            study.one_time.setdefault("plugin_build_time", res.extra.get("plugin_build_time"))
        elif m == "dop853":
            sol = solve_chain_dop853(problem, scene.run.end_time, s)
        else:
            sol = solve_chain(problem, scene.run.end_time, s, m)
        walls.append(sol.wall_time)
    e, es = _errors(scene, sol, ref, idx)
    return Point(m, s, sol.steps, statistics.median(walls), e, es, min(walls), against)


def _dump_interval_errors(scene, dt: float) -> list[tuple[int, float, float]]:
    """Error of dump-derived peaks (raw and parabola-refined) against the in-run peaks, by interval."""
    from granchain.lammps.runner import cleanup, run_lammps
    from granchain.postprocess.dumps import peaks_from_samples, read_dump
    from granchain.schedule import step_plan, step_times
    from granchain.templates.atoms import atom_layout

    sc = replace(
        scene,
        run=replace(scene.run.without_stop(), timestep=dt),
        outputs=replace(scene.outputs, dump_interval=dt, snapshots=()),
    )
    res, work = run_lammps(sc)
    try:
        times = step_times(step_plan(sc.run.end_time, dt, sc.loading.duration if sc.loading.is_force else 0.0), dt)
        dd = read_dump(work / "chain.dump", times)
    finally:
        cleanup(work)
    # the bead-bead contacts: contact i lives on atom i + offset (a striker is atom 1, a wall follows
    # bead N), as in the in-run peaks
    n, o = scene.chain.beads, atom_layout(scene)["offset"]
    force = dd.columns["d_fc"][:, o : o + n - 1]
    inrun = res.solution.peak_force
    out = []
    for stride in (1, 2, 5, 10, 20, 50):
        raw, _ = peaks_from_samples(dd.time[::stride], force[::stride], refine=False)
        fine, _ = peaks_from_samples(dd.time[::stride], force[::stride], refine=True)
        out.append(
            (
                stride,
                float(np.max(np.abs(raw - inrun)) / inrun.max()),
                float(np.max(np.abs(fine - inrun)) / inrun.max()),
            )
        )
    return out


__all__ = [
    "METHODS",
    "PLAN_RTOL",
    "STUDY_METHODS",
    "TARGETS",
    "StudyMethod",
    "reference_lines",
    "accuracy_study",
    "study_method",
    "reference_method",
    "check_study_options",
    "check_study_dir",
    "write_study",
    "summary_text",
    "AccuracyStudy",
    "Point",
    "Reference",
]
