"""granchain accuracy: a work-precision study of one scene — what each level of accuracy costs.

Methods: LAMMPS velocity Verlet (granchain's pair styles), reference RK4, reference Verlet, and
SciPy's DOP853 (a free elastic Hertz chain only) as an outside yardstick. For each, a range of time
steps (tolerances for DOP853); for each run, the error of the scene's observables (peak force of the
measured contacts, wave speed) against a converged run whose peak is the same quantity (RK4; Verlet
for Verlet and LAMMPS on a scene with a dashpot, where RK4's peak is another: reference_method),
whose own error is estimated by Richardson extrapolation, and the wall time (median of repeats;
LAMMPS's start-up and the plugin build are one-time costs, reported apart). Also the error of
dump-derived peaks against the dump interval.
"""

from __future__ import annotations

import csv
import os
import statistics
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from granchain import safe_files
from granchain.exceptions import UsageError
from granchain.integrators import INTEGRATORS, RK4, IntegratorFacts, Verlet, integrator
from granchain.postprocess.comparison_table import peak_definition
from granchain.postprocess.observables import fit_wave_speed
from granchain.problem import ChainProblem, contact_positions
from granchain.reference.scipy_solver import solve_chain_dop853
from granchain.reference.solver import solve_chain
from granchain.rundir import RunDirError, check_output_dir, owned_by_granchain
from granchain.workflows.plan import plan_scene

TARGETS = (1e-2, 1e-3, 1e-4)


@dataclass(frozen=True)
class StudyMethod:
    """A method the study can compare (``--methods``): its name, its label on the diagram, and the
    integrator it runs (granchain.integrators), which plans its scene and defines its peak
    (peak_definition); DOP853's is RK4's: it is planned as RK4 and its peaks are located alike, where the
    overlap turns, by the cubic Hermite interpolant (reference.scipy_solver)."""

    name: str
    label: str
    integrator: IntegratorFacts


#: the methods a study can compare, by name
STUDY_METHODS = {
    m.name: m
    for m in (
        StudyMethod("lammps", f"LAMMPS {Verlet.label} (chain pair styles)", Verlet()),
        StudyMethod(RK4.name, f"reference {RK4.label}", RK4()),
        StudyMethod(Verlet.name, f"reference {Verlet.label}", Verlet()),
        StudyMethod("dop853", "SciPy DOP853 (rtol ladder)", RK4()),
    )
}
#: the methods a study can compare (``--methods``)
METHODS = tuple(STUDY_METHODS)
#: SciPy's solve_ivp raises any rtol below 100 machine epsilons to that floor with a warning; the
#: DOP853 ladder stops there rather than repeat the floor's run under a smaller label
DOP853_MIN_RTOL = 100 * np.finfo(float).eps
#: the tolerance whose planned time step is marked on the diagram (the planner's default)
PLAN_RTOL = 1e-3


@dataclass
class Point:
    """One point of the work-precision diagram: an integrator at one setting, its cost and errors."""

    method: str
    setting: float  # time step (s) or, for dop853, rtol
    steps: int
    wall_time: float  # s, median of repeats
    error_peak: float  # max relative error of the measured contacts' peak forces
    error_speed: float | None
    wall_time_min: float | None = None  # s, the fastest of the repeats (the least disturbed by other load)
    reference: str = "rk4"  # the integrator of the converged run it is measured against (AccuracyStudy.references)


@dataclass
class Reference:
    """A converged run the study measures against: the integrator, its finest step, its own error
    (Richardson), the peak it measures (peak_definition) and the study's methods measured against it."""

    method: str  # "rk4" or "verlet"
    timestep: float  # s, its finest run
    error: float  # estimate of its own peak-force error
    peak: str  # what its peak force is on the scene (postprocess.comparison_table.peak_definition)
    measures: tuple[str, ...]  # the study's methods measured against it
    how: str = ""  # how it was made and its error estimated, in words


@dataclass
class AccuracyStudy:
    """A work-precision study of a scene: every point against a converged run of an integrator with
    its own peak definition (references; Point.reference)."""

    scene: object
    contacts: np.ndarray  # 1-based measured contacts
    reference_timestep: float  # the finest step of the converged runs
    reference_error: float  # the largest of the converged runs' own peak errors (Richardson)
    points: list[Point] = field(default_factory=list)
    one_time: dict = field(default_factory=dict)
    dump_errors: list[tuple[int, float, float]] = field(default_factory=list)  # (stride, raw, refined)
    plan_points: list[Point] = field(default_factory=list)  # each method at the step planned for PLAN_RTOL
    #: the converged runs by integrator (without any: one RK4 run, reference_timestep and reference_error)
    references: dict[str, Reference] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)  # methods asked for but not run, and why
    #: with two references (a dashpot): the largest relative difference of their peaks, the peak
    #: definitions' difference (no step error of either)
    definition_gap: float | None = None

    def reference_error_of(self, p: Point) -> float:
        """The own error of the converged run p is measured against."""
        r = self.references.get(p.reference)
        return self.reference_error if r is None else r.error

    def orders(self) -> dict[str, float]:
        """Each integrator's observed order: the slope of log error over log step (errors above its
        reference's own)."""
        out = {}
        for m in sorted({p.method for p in self.points} - {"dop853"}):
            pts = [p for p in self.points if p.method == m and p.error_peak > 10 * self.reference_error_of(p)]
            if len(pts) >= 2:
                out[m] = float(np.polyfit(np.log([p.setting for p in pts]), np.log([p.error_peak for p in pts]), 1)[0])
        return out

    def cheapest(self, target: float) -> Point | None:
        """The cheapest point whose peak-force error is at most target, or None.

        Within a method a run's cost grows with its steps, so each method's candidate is its point
        with the fewest steps that meets target (timings of runs a few milliseconds long swing by 2x
        with the machine's load: a median could rank 960 steps under 120). Across methods, whose
        steps cost differently, the candidates are ranked by the fastest of their repeats (the least
        disturbed timing), fewer steps breaking a tie.
        """
        ok = [p for p in self.points if p.error_peak <= target]
        if not ok:
            return None
        best = {}
        for p in ok:
            q = best.get(p.method)
            if q is None or (p.steps, _cost(p)) < (q.steps, _cost(q)):
                best[p.method] = p
        return min(best.values(), key=lambda p: (_cost(p), p.steps))


def _cost(p: Point) -> float:
    """A point's wall time for ranking: the fastest repeat where measured, else the median."""
    return p.wall_time if p.wall_time_min is None else p.wall_time_min


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
    scene with a dashpot), unless no method the study measures runs it; then the one they run (RK4 for
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
            ("a dashpot", problem.dashpot),
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
            f"their difference ({facts.label}'s error follows no order with a dashpot)"
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
    for Verlet and LAMMPS on a scene with a dashpot): errors, orders and prices for the work-precision
    diagram.

    The study measures the peak forces of bead-bead contacts (a striker's or a wall's contact is
    not among them); a scene without one (a single bead) is a UsageError, as are the options
    check_study_options refuses and a study left with no method to run (DOP853 alone on a scene it
    does not model: dop853_skipped_because).
    """
    methods = check_study_options(methods, levels, repeats)
    if scene.needs_plan:
        scene = plan_scene(scene, method=study_method(scene, methods)[0]).scene
    a, b = scene.window
    contacts = np.asarray(
        scene.peak_contacts if isinstance(scene.outputs.peak_force, tuple) else range(a, b + 1), dtype=int
    )
    if contacts.size == 0:
        raise UsageError(
            f"{scene.source}: no bead-bead contact to measure (the chain has {scene.chain.beads} bead(s)); "
            "the accuracy study compares bead-bead contacts' peak forces: use a chain of at least two beads"
        )
    idx = contacts - 1
    problem = ChainProblem.from_scene(scene)
    skipped = {}
    if "dop853" in methods and (why := dop853_skipped_because(scene, problem)):
        skipped["dop853"] = why
    methods = tuple(m for m in methods if m not in skipped)
    if not methods:
        raise UsageError(f"{scene.source}: no method left to measure: {'; '.join(skipped.values())}")
    end = scene.run.end_time
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


def check_study_dir(out: str | Path, overwrite: bool = False) -> Path:
    """Fail early (before the study runs) if out cannot take the study: it exists and is not empty
    (without overwrite), it is not a directory granchain wrote (with overwrite), it is a link, or its
    parent is not writable (a RunDirError naming it and the fix). An empty directory is taken."""
    out = Path(out)
    if _empty_dir(out):
        return out
    return check_output_dir(out, overwrite)


def _empty_dir(d: Path) -> bool:
    if os.path.islink(d) or not d.is_dir():
        return False
    try:
        with os.scandir(d) as it:
            return next(it, None) is None
    except OSError:
        return False


def write_study(study: AccuracyStudy, out: str | Path, overwrite: bool = False) -> list[Path]:
    """accuracy.csv, accuracy.png and accuracy.md in the directory out, written aside and renamed into
    place (granchain's marker in it): out must be new or empty, or, with overwrite, a directory
    granchain wrote (check_study_dir). Returns the three paths."""
    out = check_study_dir(out, overwrite)
    if _empty_dir(out):
        os.rmdir(out)  # taken as new: the directory is renamed into its place
    try:
        with safe_files.atomic_directory(out, "accuracy", overwrite=overwrite, owned=owned_by_granchain) as tmp:
            _write_study_files(study, tmp)
    except OSError as e:
        raise RunDirError(f"{out}: could not write the study ({e}); nothing was left behind") from None
    return [out / "accuracy.csv", out / "accuracy.png", out / "accuracy.md"]


def _write_study_files(study: AccuracyStudy, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with safe_files.create_new(out / "accuracy.csv") as fh:
        w = csv.writer(fh)
        w.writerow(["method", "setting", "steps", "wall_time", "error_peak_force", "error_wave_speed", "reference"])
        for p in [*study.points, *study.plan_points]:
            w.writerow(
                [
                    p.method + (" (planned)" if p in study.plan_points else ""),
                    repr(p.setting),
                    p.steps,
                    repr(p.wall_time),
                    repr(p.error_peak),
                    "" if p.error_speed is None else repr(p.error_speed),
                    p.reference,
                ]
            )
    fig, ax = plt.subplots(figsize=(7, 5))
    for m in dict.fromkeys(p.method for p in study.points):
        pts = [p for p in study.points if p.method == m]
        label = STUDY_METHODS[m].label
        if len(study.references) > 1:
            label += f" vs converged {_name(pts[0].reference)}"
        (line,) = ax.loglog([p.wall_time for p in pts], [max(p.error_peak, 1e-16) for p in pts], "o-", label=label)
        for q in (q for q in study.plan_points if q.method == m):
            ax.loglog(
                [q.wall_time],
                [max(q.error_peak, 1e-16)],
                "*",
                ms=13,
                mec="k",
                color=line.get_color(),
                label=f"{label}: planned for rtol {PLAN_RTOL:g} (dt {q.setting:.3g} s)",
            )
    for (r, ref), ls in zip(study.references.items(), (":", "-."), strict=False):
        ax.axhline(ref.error, color="gray", ls=ls, label=f"converged {_name(r)}'s own error (Richardson)")
    if not study.references:
        ax.axhline(study.reference_error, color="gray", ls=":", label="converged reference's own error (Richardson)")
    ax.axhline(PLAN_RTOL, color="0.5", ls="--", lw=0.8, label=f"rtol {PLAN_RTOL:g}")
    ax.set_xlabel("wall time (s, median of repeats; LAMMPS start-up excluded)")
    ax.set_ylabel("max relative error of peak forces")
    import textwrap

    text = "".join(c if c.isprintable() else c.encode("unicode_escape").decode() for c in str(study.scene.title or ""))
    title = "\n".join(textwrap.wrap(f"Work-precision: {text or study.scene.source}", 80))
    ax.set_title(title, fontsize=9, parse_math=False)  # the scene's own text, not mathtext
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    try:
        safe_files.save_figure(fig, out / "accuracy.png", dpi=120)
    finally:
        plt.close(fig)
    with safe_files.create_new(out / "accuracy.md") as fh:
        fh.write(summary_text(study))


def _name(method: str) -> str:
    facts = INTEGRATORS.get(method)
    return method if facts is None else facts.label


def reference_lines(study: AccuracyStudy) -> list[str]:
    """What each row is measured against, as Markdown lines: each converged run, its own error, its
    peak and the methods measured against it; with two, the definitions' difference; methods not run."""
    if not study.references:
        return [
            f"Converged reference RK4 at dt = {study.reference_timestep:.3g} s, its own error "
            f"(Richardson) {study.reference_error:.1e}.",
        ]
    lines = ["Each method is measured against a converged run whose peak is the same quantity:"]
    for r, ref in study.references.items():
        lines.append(
            f"- converged {_name(r)} at dt = {ref.timestep:.3g} s ({ref.how}), its own error {ref.error:.1e}; "
            f"its peak: {ref.peak}; measures {', '.join(ref.measures)}"
        )
    if study.definition_gap is not None:
        lines.append(
            f"- the two converged runs' peaks differ by {study.definition_gap:.1e}: different quantities (the "
            "dashpot's force), not step error; a method's error is of its own peak, not the other's"
        )
    lines += [f"- not run: {m} ({why})" for m, why in study.skipped.items()]
    return lines


def summary_text(study: AccuracyStudy) -> str:
    """The study as Markdown: the measured contacts, the converged runs each method is measured against
    and their own errors, and a table per method."""
    lines = [
        f"# Work-precision: {study.scene.title or study.scene.source}",
        "",
        f"Measured contacts: {study.contacts.min()}..{study.contacts.max()} ({len(study.contacts)}).",
        "",
        *reference_lines(study),
        "",
    ]
    lines.append("Observed orders (fit of log error vs log dt, points above 10x their reference's own error):")
    orders = study.orders()
    for m, o in orders.items():
        against = next(p.reference for p in study.points if p.method == m)
        lines.append(f"- {m}: {o:.2f} (against converged {_name(against)})")
    lines += [
        "",
        "| target | cheapest method | setting | wall time (s) | error | measured against |",
        "|---|---|---|---|---|---|",
    ]
    for t in TARGETS:
        p = study.cheapest(t)
        if p is None:
            lines.append(f"| {t:g} | none reached it | | | | |")
        else:
            setting = f"rtol {p.setting:g}" if p.method == "dop853" else f"dt {p.setting:.3g} s"
            lines.append(
                f"| {t:g} | {p.method} | {setting} | {p.wall_time:.3g} | {p.error_peak:.1e} | "
                f"converged {_name(p.reference)} |"
            )
    if study.plan_points:
        lines += [
            "",
            f"The planner's choice for rtol {PLAN_RTOL:g} (the stars on the diagram), measured:",
            "",
            "| method | planned dt (s) | wall time (s) | error | meets rtol | measured against |",
            "|---|---|---|---|---|---|",
        ]
        lines += [
            f"| {q.method} | {q.setting:.3g} | {q.wall_time:.3g} | {q.error_peak:.1e} | "
            f"{'yes' if q.error_peak <= PLAN_RTOL else 'no'} | converged {_name(q.reference)} |"
            for q in study.plan_points
        ]
    if study.one_time:
        lines += [
            "",
            "One-time costs (not in the wall times): "
            + ", ".join(f"{k} {v:.3g} s" for k, v in study.one_time.items() if v is not None),
        ]
    if study.dump_errors:
        lines += [
            "",
            "Dump-derived peaks vs in-run peaks (LAMMPS), max relative error:",
            "",
            "| dump every (steps) | raw samples | parabola-refined |",
            "|---|---|---|",
        ]
        lines += [f"| {s} | {r:.1e} | {f:.1e} |" for s, r, f in study.dump_errors]
    return "\n".join(lines) + "\n"


__all__ = [
    "METHODS",
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
