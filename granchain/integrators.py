"""What each integrator declares of itself: its order, stability limit, the planner's calibration, how
it locates a peak, and how its error behaves with velocity-dependent damping and on a kinked law.

As scipy.integrate's solvers carry their ``order`` and ``error_estimator_order`` on their class, each
integrator granchain runs is one frozen class here (RK4, Verlet), registered in INTEGRATORS by its name
(the ``method`` of a scene's run, ``--method``, ChainSolution.method). The planner
(workflows.plan), the error bars (richardson, workflows.error_estimates), the comparison table's peak
definitions (postprocess.comparison_table), the accuracy study (workflows.accuracy) and the reference
solver read these facts, ``integrator(method).order`` and so on; none of them asks which method it is
where a fact answers the question (tests/test_integrator_facts.py holds this).

The facts are the integrator's alone. What the contact law adds is the law's: the order 1 + 3/2 of
the error where a Hertzian contact closes (ContactLaw.onset_order, 1 + n of its onset) lowers any
integrator's order above it (RK4's 4) and none below it (Verlet's 2).

The implementations are granchain.reference.verlet and granchain.reference.rk4 (the reference
solver's), and LAMMPS's fix nve, which is velocity Verlet (backends.builtin.LammpsBackend.methods).
"""

from __future__ import annotations

from dataclasses import dataclass, fields


@dataclass(frozen=True)
class IntegratorFacts:
    """The facts an integrator declares; one frozen subclass per integrator, each field given there.

    Rules for writing a new integrator (the tests in tests/test_integrator_facts.py check each):

    1. Subclass IntegratorFacts with ``@dataclass(frozen=True)`` and give every field below a value in
       the subclass's own body (the base gives none, so a fact left out is a TypeError at
       registration), with a comment saying why, from a measurement where the value is one
       (the calibration and the stability limit: on which scenes, against what).
    2. Register one instance in INTEGRATORS under its name, and implement it in the reference solver
       (a granchain.reference.stepping.Integrator subclass with the same ``name``, listed in
       granchain.reference.solver.IMPLEMENTATIONS), with its peak tracker as peaks_by_overlap says.
    3. No module outside this one asks for the integrator by name (``method == "..."``, a table keyed
       by it): a question the facts do not answer is a new field here, declared by every integrator.

    Attributes
    ----------
    name : str
        The method's name: a scene's ``[run] method``, ``--method``, ChainSolution.method.
    label : str
        Its name in words, for tables and plots ("RK4").
    order : int
        Its order of accuracy p: the error of a smooth problem goes as dt^p (Richardson's nominal order,
        the planner's error model C (omega_max dt)^p).
    stability : float
        The largest omega_max dt at which it is stable (the planner's stable step is stability /
        omega_max; a companion above it is not run).
    calibration : float
        The planner's error model constant C in  rel. error of peak forces ~ C (omega_max dt)^order.
    damping_error : float
        The coefficient D of the first-order error of a velocity-dependent damping force (a damping
        part with ``velocity_dependent``: the dashpot, Kuwabara-Kono) the planner adds,
        D x rate x dt, rate the damping's decay rate (0: none).
    damping_order : int
        The order its error shows with a velocity-dependent damping force (Richardson's nominal order
        there).
    unordered_with_damping : str or None
        Why its error follows no order with a velocity-dependent damping force, in words: its runs
        there get no error bar (workflows.error_estimates.withheld_because); None: its error keeps
        damping_order.
    peaks_by_overlap : bool
        True: a peak is located where the overlap turns (the maximum of the quartic interpolant of the
        overlap over a step: its value and rate at both ends, its second derivative at the start), so
        its force is the elastic force there; False: the contact force's samples at step ends are
        tracked, so its peak is the total force's maximum. The two are one
        quantity unless the damping part adds a velocity-dependent force (postprocess.comparison_table
        .peak_definition).
    locates_kinks : bool
        Whether it splits a step where a contact crosses a kink of its law (event location): its error
        is then smooth in dt on a kinked law, but every crossing costs it more tries.
    mixes_orders : str or None
        Why its error mixes orders on a chain, so that Richardson's bars are checked below dt by a run
        at dt / 2 when checked bars are asked for (workflows.error_estimates.check_because); None: its
        error is of one order, which the runs at dt, 2 dt and 4 dt check already.
    extrapolated_reference : bool
        Whether the accuracy study's converged run of it is a Richardson extrapolation of its finest
        runs (True: too low an order for its finest run to be converged) or its finest run itself.
    """

    name: str
    label: str
    order: int
    stability: float
    calibration: float
    damping_error: float
    damping_order: int
    unordered_with_damping: str | None
    peaks_by_overlap: bool
    locates_kinks: bool
    mixes_orders: str | None
    extrapolated_reference: bool


@dataclass(frozen=True)
class RK4(IntegratorFacts):
    """Classical RK4 with event location at the law's kinks (granchain.reference.rk4)."""

    name: str = "rk4"
    label: str = "RK4"
    order: int = 4
    #: classical RK4's stability region reaches 2.83 on the imaginary axis
    stability: float = 2.8
    #: measured C (planned runs against runs at dt/16, bundled scenes): 0.2-0.54 (elastic long loads);
    #: 1.0 keeps a safety factor of about 2
    calibration: float = 1.0
    #: RK4 integrates a velocity-dependent force with its stage velocities: no first-order term
    damping_error: float = 0.0
    damping_order: int = 4
    #: the damped force is clipped where it would pull, a kink in time RK4 does not locate, so its runs
    #: converge at no definite order (the message keeps the dashpot's words: it was measured on the
    #: dashpot, and summaries quote it). Measured on 14 generated Hertz chains planned for rtol 1e-3
    #: (docs/error-bars.md): on the 9 with a dashpot 14 of 55 estimates were outside 1/3-3 of the true
    #: error (0.013-12x), although the three runs' differences looked like orders 1-5; on the 5 without,
    #: none of 51
    unordered_with_damping: str | None = (
        "RK4 does not locate where the clipped dashpot force reaches zero, so its error follows no "
        "order, and its peaks are the elastic force where the overlap turns, not the total force's "
        "maximum: no companion runs, no estimate (--method verlet gives error bars)"
    )
    #: the running maximum of each overlap refined by its quartic interpolant (reference.observers
    #: .HermitePeaks): with a dashpot the elastic force where the overlap turns, 4.4e-5 of the peak below
    #: Verlet's converged total on effect-dashpot (docs/error-bars.md)
    peaks_by_overlap: bool = True
    locates_kinks: bool = True
    #: 1 + 3/2 at every Hertzian onset, with a coefficient that depends on where in a step the contact
    #: closes, 4 and the terms beyond: on generated varied Hertz chains 8 of 243 estimates fell outside
    #: 1/3-3 of the true error where the local order between dt and 2 dt was 2.1-2.3 or 5.6-5.8 while the
    #: three runs showed 3.9-4.8 (docs/error-bars.md)
    mixes_orders: str | None = (
        "RK4's error mixes orders (2.5 at Hertzian onsets, 4 and beyond): the order seen at dt, 2 dt and "
        "4 dt is checked below dt by a run at dt / 2"
    )
    #: order 4: the finer of two runs at a quarter of the finest step the study runs is converged, its
    #: error their difference / 15
    extrapolated_reference: bool = False


@dataclass(frozen=True)
class Verlet(IntegratorFacts):
    """Velocity Verlet as LAMMPS's fix nve runs it (granchain.reference.verlet; LAMMPS itself)."""

    name: str = "verlet"
    label: str = "Verlet"
    order: int = 2
    #: velocity Verlet is stable up to omega_max dt = 2
    stability: float = 2.0
    #: measured C (planned runs against runs at dt/16, bundled scenes): 0.1-0.6; 1.0 keeps a safety
    #: factor of about 2
    calibration: float = 1.0
    #: Verlet (and LAMMPS) evaluates a velocity-dependent force with the half-step velocities (the
    #: damping parts' force reads d(alpha)/dt at the half step): its force is first-order
    #: accurate, and a peak carries an error of about 1.0 x rate x dt. Measured: a tapered aluminium
    #: chain with gamma = 6 N s/m (rate 8e4 1/s) planned by (omega_max dt)^2 alone missed rtol 1e-3 by
    #: 1.1x (tests/test_planner_property.py)
    damping_error: float = 1.0
    #: the damping force's first-order term: measured on effect-dashpot (LAMMPS, planned step, against
    #: dt / 16), with order 2 every estimate was 0.37-0.43 of the true error, the factor
    #: (2^2 - 1) / (2^1 - 1) = 3 the first order predicts
    damping_order: int = 1
    unordered_with_damping: str | None = None
    #: the force samples at step ends, refined by the parabola through three (reference.observers
    #: .ForceSamplePeaks): the peak tracking of granchain's LAMMPS pair styles, step for step
    peaks_by_overlap: bool = False
    #: fixed steps: on a law with slope kinks its error depends on where in a step each contact crosses
    #: them and is erratic in sign in dt (workflows.error_estimates.bounded_because)
    locates_kinks: bool = False
    mixes_orders: str | None = None
    #: first order with a velocity-dependent damping force, so a finest run would carry its error into
    #: every point it judges (the planned step's 1.6e-4 read as 1.45e-4 against Verlet at an 8x finer
    #: step): the runs at 2h, h and h / 2 are extrapolated in pairs
    extrapolated_reference: bool = True


#: every integrator, by name (in the order --method lists them)
INTEGRATORS: dict[str, IntegratorFacts] = {facts.name: facts for facts in (RK4(), Verlet())}

#: the names of the facts every integrator declares (the fields of IntegratorFacts)
FACTS = tuple(f.name for f in fields(IntegratorFacts))


def integrator(method: str) -> IntegratorFacts:
    """The facts of the integrator named `method` (a ValueError names the known ones)."""
    try:
        return INTEGRATORS[method]
    except KeyError:
        raise ValueError(f"method = {method!r} is not known; choose one of {', '.join(INTEGRATORS)}") from None
