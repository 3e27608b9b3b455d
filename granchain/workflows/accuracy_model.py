"""What a work-precision study is: the methods it compares, its points, its converged references and
the study itself (granchain.workflows.accuracy runs it, accuracy_report writes it)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from granchain.integrators import RK4, IntegratorFacts, Verlet

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
