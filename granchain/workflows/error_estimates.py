"""The per-run error estimate: the run repeated at 2 dt and 4 dt and Richardson on every number, or,
on the kinked laws, bounds or RK4 runs (below).

estimate_errors(result, ...) runs the companions of a finished run (the same scene and plan, the
time step doubled and quadrupled; no histories, snapshots or dumps, which no estimate needs) and
returns an ErrorReport: for every contact its peak force, time of peak and leading pulse with an
error estimate and a status (granchain.richardson), the same for every scalar observable, the
largest relative error over the measured contacts, and what the companions cost.

Verlet on a law with slope kinks (bilinear, Thornton) without a dashpot: its error is erratic in sign.
A LAMMPS run's bars are bounds from the same companions (bounded_because, richardson.erratic_bounds),
which may overstate it; a reference Verlet run's are measured against RK4 runs where those cost at most
the run (against_rk4_because, rk4_companions_cost), and LAMMPS's too on request (error_estimate="checked",
at several times a LAMMPS run's price).

On request (error_estimate="checked"), RK4's bars are checked against one more run, at dt / 2
(check_because, richardson.checked): its error mixes orders (2.5 at Hertzian onsets, 4 and beyond),
and the order the runs at dt, 2 dt and 4 dt show need not hold below dt; an estimate the run at dt / 2
contradicts is not given. Not by default: that run costs twice the run, and the bars' price is held
to at most the run's (the companions at 2 dt and 4 dt: 3/4 of its steps).

RK4 on a law with slope kinks (bilinear, Thornton): every kink crossing costs RK4 two more tries in
every run, so companions at 2 dt and 4 dt cost more than the run (1.0-1.6x); by default its bars are
bounds from the companion at 2 dt alone (one_companion_because, richardson.one_companion), which may
overstate the error many times, and error_estimate="checked" gives the checked estimate (2 dt, 4 dt,
dt / 2).

Orders: each integrator's (granchain.integrators: IntegratorFacts.order, dashpot_order): RK4 4,
velocity Verlet (reference and LAMMPS) 2, but 1 for Verlet with a dashpot: the dashpot sees half-step
velocities and is first order (Verlet.dashpot_error). Measured on effect-dashpot (LAMMPS, planned step,
against dt / 16): with order 2 every estimate was 0.37-0.43 of the true error, an underestimate by the
factor (2^2 - 1) / (2^1 - 1) = 3 the first order predicts. No function here asks which integrator a run
has: each reads the integrator's facts (integrator(method)).

The 4 dt companion is skipped where 4 dt is above the stability limit the planner predicts (then
the order is not checked and the status says so); the 2 dt one where 2 dt is (then nothing is
estimated, and the report says why).
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field, replace

import numpy as np

from granchain.exceptions import GranchainError
from granchain.integrators import RK4, integrator
from granchain.postprocess.observables import measure_observables
from granchain.progress import labelled
from granchain.richardson import (
    BOUND_ORDER,
    CHECK_FACTOR,
    ErrorBars,
    against_reference,
    checked,
    erratic_bounds,
    one_companion,
    richardson,
)

#: scalar observables that get an error estimate, and the time each is measured at (for the check
#: that a companion measured the same pulse)
ESTIMATED_OBSERVABLES = ("leading_peak_force", "leading_peak_force_nondim", "wave_speed", "max_peak_force")


@dataclass
class ErrorReport:
    """Measured error estimates of a run (see the module docstring)."""

    order: int
    timesteps: list[float]  # the companions' steps (2 dt, and 4 dt where stable; 2 dt alone for one_companion; RK4's)
    wall_times: list[float]  # their wall times, s
    peak_force: ErrorBars | None = None
    time_of_peak: ErrorBars | None = None
    leading_pulse_force: ErrorBars | None = None
    arrival_time: ErrorBars | None = None
    observables: dict[str, dict] = field(default_factory=dict)  # name -> value, error, status
    error_estimate: float | None = None  # largest relative peak-force error over the measured contacts
    error_estimate_contact: int | None = None
    why_none: str | None = None  # why nothing was estimated (2 dt unstable, or its run failed)
    why_none_4dt: str | None = None  # why the order was not checked (the 4 dt run failed)
    unreliable_contacts: list[int] = field(default_factory=list)  # measured contacts without an estimate
    against: str | None = None  # "rk4": measured against RK4 runs at 2 dt and 4 dt (or dt, 2 dt), not by Richardson
    #: why the bars are bounds from the runs at 2 dt and 4 dt, not Richardson's estimates (bounded_because)
    bound: str | None = None
    #: the effects' own contacts (a striker's, a wall's): name -> value, error, status
    end_peaks: dict[str, dict] = field(default_factory=dict)
    check_timestep: float | None = None  # the step of the run that checks the bars (check_because), s
    check_wall_time: float | None = None  # its wall time, s (in wall_times too: it is part of the bars' price)
    #: why the bars are not checked at dt / 2: asked for, its run failed or the check is not this
    #: integrator's (unchecked_because); not asked for, RK4's bars say what that leaves (UNCHECKED_BY_DEFAULT)
    why_unchecked: str | None = None
    #: why the bars come from one companion at 2 dt with an assumed order (one_companion_because)
    one_companion: str | None = None
    #: the steps each companion took (its ChainSolution.steps, in the order of timesteps)
    steps: list[int] = field(default_factory=list)
    check_steps: int | None = None  # the steps the run that checks the bars took

    @property
    def peak_bounds(self) -> bool:
        """Whether the peak forces' bars are bounds that may overstate the error (bounded_because,
        one_companion_because), not estimates."""
        return self.bound is not None or self.one_companion is not None

    def summary(self, main_wall_time: float) -> dict:
        """The summary.json entry."""
        counts: dict[str, int] = {}
        if self.peak_force is not None:
            for s in self.peak_force.status:
                key = s.split(":")[0].split(" (")[0]  # the kind, without its numbers
                counts[key] = counts.get(key, 0) + 1
        if self.against is not None:
            method = (
                "the distance to RK4 (reference, event location) at 2 dt, plus its own error from RK4 at 4 dt "
                "(granchain.richardson.against_reference)"
            )
        elif self.bound is not None:
            method = (
                f"bounds from runs at dt, 2 dt and 4 dt, max(|Q(dt) - Q(2 dt)|, |Q(2 dt) - Q(4 dt)| / {2**BOUND_ORDER})"
                f", which may overstate the error many times (granchain.richardson.erratic_bounds): {self.bound}"
            )
        elif self.one_companion is not None:
            method = (
                "bounds from one companion at 2 dt, |Q(dt) - Q(2 dt)|, which may overstate the error many times "
                f"(granchain.richardson.one_companion): {self.one_companion}"
            )
        else:
            method = "Richardson extrapolation over runs at dt, 2 dt and 4 dt (granchain.richardson)"
        return {
            "method": method,
            "companion_method": self.against,
            "bound": self.bound,
            "one_companion": self.one_companion,
            "order": self.order,
            "companion_timesteps": self.timesteps,
            "companion_steps": self.steps,
            "check_steps": self.check_steps,
            "companion_wall_time": sum(self.wall_times),
            "overhead": (sum(self.wall_times) / main_wall_time) if main_wall_time > 0 else None,
            "error_estimate": self.error_estimate,
            "error_estimate_contact": self.error_estimate_contact,
            "unreliable_contacts": self.unreliable_contacts,
            "peak_status_counts": counts,
            "observables": self.observables,
            "end_peaks": self.end_peaks,
            "why_none": self.why_none,
            "why_no_order_check": self.why_none_4dt,
            "check_timestep": self.check_timestep,
            "check_wall_time": self.check_wall_time,
            "why_unchecked": self.why_unchecked,
        }


def withheld_because(method: str, scene) -> str | None:
    """Why no error bar is given for this integrator on this scene, or None.

    An integrator whose error follows no order with a dashpot (IntegratorFacts.unordered_with_dashpot;
    RK4: the dashpot force is clipped where it would pull, a kink in time RK4 does not locate, so its
    runs converge at no definite order). Measured on 14 generated Hertz chains planned for rtol 1e-3
    (/tmp experiment recorded in docs/error-bars.md): on the 9 with a dashpot 14 of 55 estimates were
    outside 1/3-3 of the true error (0.013-12x), although the three runs' differences looked like orders
    1-5; on the 5 without, none of 51 (another sample of 12 chains had 4 of about 100 outside, 0.21-3.5:
    RK4's Hertz onsets, docs/error-bars.md).
    """
    if scene.effects.dashpot:
        return integrator(method).unordered_with_dashpot
    return None


#: The lowest order of an integrator's error on a chain of a Hertzian onset: 1 + 3/2 where a contact
#: closes (F ~ t^(3/2) is not smooth at the onset; docs/laws.md), the bilinear peaks at the turn measured
#: 2.5-3.2 alike; it lowers an integrator of higher order (RK4's 4), not one below it (Verlet's 2). Of
#: any other law it is 1 + its declared loading exponent (onset_order).
ONSET_ORDER = 2.5


def onset_order(scene) -> float:
    """The order of an integrator's error where a contact of the scene closes: 1 + n of its onset F ~
    alpha^n (ContactLaw.loading_exponent, the smallest over the nominal law's contacts: 2.5 for Hertz and
    Thornton, 1 + n for the power law); ONSET_ORDER on a loading line (the bilinear law's measured 2.5-3.2)."""
    if scene.contact.law_class.loading_is_linear():
        return ONSET_ORDER
    return 1.0 + float(np.min(scene.law.loading_exponent()))


def expected_orders(method: str, scene) -> tuple[float, float]:
    """The lowest and highest order the integrator's error can show on this scene (richardson): from
    the lower of its order on the scene (integrator_order: Verlet's 1 with a dashpot, its first-order
    term mixing with Verlet's second) and the onset's (onset_order), to its order."""
    return float(min(onset_order(scene), integrator_order(method, scene))), float(integrator(method).order)


def check_because(method: str, scene, checked: bool = False) -> str | None:
    """Why Richardson's bars of this run are checked against a run at dt / 2, or None (always None
    unless the check was asked for: ``checked``, error_estimate="checked").

    RK4 on a chain: its error mixes orders (1 + 3/2 at every Hertzian onset, with a coefficient that
    depends on where in a step the contact closes, 4 and the terms beyond), so the order the runs at
    dt, 2 dt and 4 dt show need not hold below dt. Measured on generated varied Hertz chains (reference
    RK4, planned for rtol 1e-3, true error against dt / 8; docs/error-bars.md): 8 of 243 estimates
    outside 1/3-3 of the true error (0.21-3.8), each where the order between dt and 2 dt (seen with the
    true value) was 2.1-2.3 or 5.6-5.8 while the three runs showed 3.9-4.8, or the error changed sign
    just below dt. The run at dt / 2 costs twice the run (richardson.checked).
    """
    if checked:
        return integrator(method).mixes_orders  # (IntegratorFacts.mixes_orders: RK4's, why)
    return None


#: what RK4's default bars (no run at dt / 2) say of themselves: measured on generated varied chains
#: (docs/error-bars.md, docs/measure_varied_error_ratios.py)
UNCHECKED_BY_DEFAULT = (
    "RK4's bars are not checked below dt by default: about 5% of them fell outside 1/3-3 of the true error "
    "on generated chains, where contacts open and close (docs/error-bars.md); --error-estimate checked "
    '(error_estimate="checked") checks each at dt / 2 and withholds one it contradicts, at twice the run'
)


def unchecked_because(method: str, scene) -> str:
    """Why a run's bars get no check at dt / 2 although it was asked for (error_estimate="checked").

    The check is RK4's (check_because): Verlet's error on a chain is of one order (2; 1 with a
    dashpot, expected_orders), which the runs at dt, 2 dt and 4 dt check already; a Verlet run whose
    law has kinks is then measured against RK4 runs, not extrapolated, so no order is assumed.
    """
    if against_rk4_because(method, scene, checked=True):
        return "its error is measured against RK4 runs (event location), not extrapolated: no check at dt / 2 needed"
    return (
        f"the check at dt / 2 is RK4's: {method}'s error is of one order, which the runs at dt, 2 dt and 4 dt "
        "check already"
    )


def integrator_order(method: str, scene) -> int:
    """The order the error estimate assumes (see the module docstring): the integrator's, or its order
    with a dashpot (IntegratorFacts.dashpot_order)."""
    facts = integrator(method)
    return facts.dashpot_order if scene.effects.dashpot else facts.order


def companion_scene(scene, factor: float):
    """The scene at factor x its time step, with no outputs that no estimate needs."""
    o = scene.outputs
    return replace(
        scene,
        run=replace(scene.run, timestep=scene.run.timestep * factor),
        outputs=replace(o, histories=(), snapshots=(), history_interval=None, dump_interval=None),
    )


def measured_contacts(scene, solution) -> np.ndarray:
    """0-based contacts whose peaks are measured outputs: complete, up to the last measured contact."""
    from granchain.workflows.plan import last_measured_contact

    last = last_measured_contact(scene) or len(solution.peak_force)
    c = np.asarray(solution.complete, dtype=bool)[:last]
    return np.flatnonzero(c)


def per_contact(solutions, name: str, n: int, complete_only: bool = False) -> list:
    """One per-contact quantity (the first n contacts) of each solution (None stays None: no such
    companion); complete_only: nan where that run's peak is not complete."""
    out = []
    for s in solutions:
        if s is None:
            out.append(None)
            continue
        v = np.asarray(getattr(s, name), dtype=float)[:n].copy()
        if complete_only:
            v[~np.asarray(s.complete, dtype=bool)[:n]] = np.nan
        out.append(v)
    return out


def kinked_law(method: str, scene) -> bool:
    """Whether this is a run of an integrator that does not locate kinks (IntegratorFacts.locates_kinks:
    Verlet) on a law whose slope jumps at kinks the contacts cross (ContactLaw.slope_kinks: bilinear,
    Thornton), without a dashpot: its error in dt is erratic in sign."""
    from granchain.physics.laws import law_class

    locates = integrator(method).locates_kinks
    return not locates and not scene.effects.dashpot and bool(law_class(scene.contact.law).slope_kinks)


def bounded_because(method: str, scene) -> str | None:
    """Why this run's bars are bounds (richardson.erratic_bounds), not Richardson's estimates, or None.

    A law whose slope jumps at kinks a moving contact crosses gives fixed-step Verlet an error that
    depends on where in a step each contact crosses them: erratic in sign in dt (generated bilinear
    and Thornton chains without a dashpot, reference Verlet: the runs at dt, 2 dt, 4 dt changed sign
    on 14-22% of the peaks, Richardson's checks failed on 26-36%, and where they passed its estimate
    was below 1/3 of the true error on 6 of 1781, down to 0.07; docs/error-bars.md, "Verlet on the
    kinked laws" and "Bounds from dt, 2 dt, 4 dt"). The default bars are bounds from the same
    companions at 2 dt and 4 dt (3/4 of the run's steps), which may overstate the error many times and
    say so. With a dashpot Verlet is first order and Richardson stays (expected_orders).
    """
    if not kinked_law(method, scene):
        return None
    law = scene.contact.law
    return f"the {law} law's slope jumps at kinks the contacts cross, so Verlet's error is erratic in sign"


def one_companion_because(method: str, scene, checked: bool = False) -> str | None:
    """Why this run's bars are bounds from one companion at 2 dt (richardson.one_companion with
    BOUND_ORDER: |Q(dt) - Q(2 dt)|), or None (always None when checked bars were asked for, ``checked``).

    RK4 (event location) on a law whose slope jumps at kinks the contacts cross (ContactLaw.slope_kinks:
    bilinear, Thornton): each crossing costs a rejected try and the split piece in every run, so
    companions at 2 dt and 4 dt, 3/4 of the run's steps but its crossings twice, cost about 1.0-1.6 times
    the run (bench_errorbar_price.py); the one at 2 dt alone costs less than the run. An estimate from it
    needs an order assumed, and order 3 (0.43-2.14 of a clean order-2-4 error) did not hold: measured on
    generated chains against RK4 at dt / 4 (docs/error-bars.md, "RK4 on the kinked laws: one companion";
    docs/measure_kinked_rk4_companion.py), below 1/3 of the true error on 112 of 1 983 Thornton numbers
    (mostly times, whose error stalls or changes sign between 2 dt and dt) and, for forces, on 41 of 606
    Thornton peaks of a second sample and 3 of 59 on plastic-short-impulse. The bound |Q(dt) - Q(2 dt)|
    (below E(dt) / 3 only where E(2 dt) is within 2/3 - 4/3 of E(dt) with its sign) was below 1/3 of the
    true error on 0.2-1.3% of the numbers of each sample, and overstates the error about 10-15 times at
    the median, as Verlet's kinked bounds (bounded_because) about 6 times.
    """
    if checked or not integrator(method).locates_kinks or scene.effects.dashpot:
        return None
    from granchain.physics.laws import law_class

    if not law_class(scene.contact.law).slope_kinks:
        return None
    return (
        f"the {scene.contact.law} law's kinks cost RK4 two more tries at every crossing, so runs at 2 dt and 4 dt "
        "would cost more than the run: bounds from the one at 2 dt alone"
    )


#: what RK4's default bars on a kinked law (one_companion_because) say of themselves
ONE_COMPANION_BY_DEFAULT = (
    "RK4's bars on a kinked law are bounds from one companion at 2 dt, |Q(dt) - Q(2 dt)|, about 10-15 times the "
    "error (at times 50 times or more; docs/error-bars.md); --error-estimate checked "
    '(error_estimate="checked") estimates it from runs at 2 dt and 4 dt with their order checks and a run at '
    "dt / 2, at about three times the run"
)


#: what a kinked law's default Verlet bars (bounded_because) say of themselves: what they leave and what
#: measures them instead
BOUNDED_BY_DEFAULT = (
    "Verlet's bars on a kinked law are bounds from the runs at 2 dt and 4 dt, about 6 times the error (at times "
    "30 times or more; docs/error-bars.md); --error-estimate checked "
    '(error_estimate="checked") measures it against RK4 runs (event location) instead, at several times a '
    "LAMMPS run's price"
)


def against_rk4_because(method: str, scene, checked: bool = False, numpy_speed: bool = False) -> str | None:
    """Why this Verlet run's error is measured against RK4 runs rather than by Richardson, or None
    (always None unless checked bars were asked for, ``checked``: error_estimate="checked", or the run's
    backend integrates at numpy's speed, ``numpy_speed``: Backend.numpy_speed).

    A law whose slope jumps at kinks a moving contact crosses (ContactLaw.slope_kinks: bilinear,
    Thornton) gives fixed-step Verlet an error that depends on where in a step each contact crosses
    them and follows no order in dt (plastic-short-impulse, reference Verlet: Richardson's three runs
    changed sign on 47 of 59 peaks; docs/error-bars.md). RK4 locates those kinks; it cannot with a dashpot
    (withheld_because), where Richardson stays. By default (bounded_because) a LAMMPS run's bars come
    from its own companions instead: RK4 runs in numpy cost some ten times a LAMMPS run. A reference
    Verlet run's RK4 companions give truthful bars, not bounds, and are its default where they cost at
    most the run (rk4_companions_cost; on the bundled plastic scenes 0.6-0.7 of it, against 0.9-1.1 for
    its own companions at 2 dt and 4 dt: bench_errorbar_price.py).
    """
    if not kinked_law(method, scene):
        return None
    if not checked and not (numpy_speed and rk4_companions_cost(scene) <= 1.0):
        return None
    return (
        f"the {scene.contact.law} law's slope jumps at kinks the contacts cross, so Verlet's error follows no order "
        "in dt: "
        "measured against RK4 (event location) at 2 dt, its own error from RK4 at 4 dt"
    )


def rk4_companions(scene, method: str, checked: bool = False, numpy_speed: bool = False) -> list:
    """The RK4 companion scenes the error estimate of a run of this concrete scene with `method` will
    ask for (the reference's own at 2 dt and 4 dt, or those a Verlet run is measured against), as far
    as they are known before the run (planned_companions): compare starts them early (a run the planner
    refines after it asks for others)."""
    from granchain.workflows.plan import plan_scene

    stable = plan_scene(scene, method=method).stable_timestep
    return [
        companion_scene(scene, c.factor)
        for c in planned_companions(scene, method, stable, checked, numpy_speed)
        if c.method == RK4.name
    ]


def richardson_factors(method: str, scene, checked: bool = False) -> tuple[float, ...]:
    """The steps, as multiples of the run's dt, of a run's own companions before the stability limit
    drops any: 2 dt alone where the bars are bounds from one companion (one_companion_because), else
    2 dt and 4 dt."""
    return (2.0,) if one_companion_because(method, scene, checked) else (2.0, 4.0)


@dataclass(frozen=True)
class Companion:
    """One run a run's error estimate makes (planned_companions).

    Attributes
    ----------
    method : str
        Its integrator (the run's own, or rk4 for the RK4 runs a Verlet run is measured against).
    factor : float
        Its time step as a multiple of the run's.
    role : str
        "companion" (Richardson's or the bounds' runs at 2 dt and 4 dt), "check" (the run at dt / 2
        that checks RK4's bars, check_because) or "rk4 reference" (against_rk4_because).
    """

    method: str
    factor: float
    role: str


def planned_companions(
    scene, method: str, stable_timestep: float, checked: bool = False, numpy_speed: bool = False
) -> list[Companion]:
    """The runs the error estimate of a run of this concrete scene with `method` makes when none fails
    (estimate_errors with run_rk4 given, as granchain run and the API give it): RK4 runs at
    against_rk4_factors where a Verlet run is measured against RK4 (against_rk4_because); else its own
    runs at richardson_factors within stable_timestep (none where 2 dt is above it or no bar is given,
    withheld_because), and the run at dt / 2 where check_because. An empty list: no companion runs.

    Parameters
    ----------
    scene : granchain.scene.Scene
        The concrete scene the run runs (its time step and end time set).
    method : str
        The run's integrator.
    stable_timestep : float
        The planner's stability limit for this scene and integrator, s.
    checked : bool
        Checked bars asked for (error_estimate="checked").
    numpy_speed : bool
        The run's backend integrates at numpy's speed (Backend.numpy_speed).

    Returns
    -------
    list of Companion
        In the order the estimate runs them.
    """
    from granchain.workflows.plan import plan_scene

    dt = scene.run.timestep
    if against_rk4_because(method, scene, checked, numpy_speed):
        if withheld_because("rk4", scene) or 2 * dt > plan_scene(scene, method="rk4").stable_timestep:
            return []
        return [Companion("rk4", f, "rk4 reference") for f in against_rk4_factors(scene)]
    if withheld_because(method, scene) or 2.0 * dt > stable_timestep:
        return []
    runs = [Companion(method, f, "companion") for f in richardson_factors(method, scene, checked)]
    runs = [c for c in runs if c.factor * dt <= stable_timestep]
    if check_because(method, scene, checked):
        runs.append(Companion(method, CHECK_FACTOR, "check"))
    return runs


def companion_steps(scene, factor: float) -> int:
    """The steps a companion of this concrete scene at factor x its time step takes to its end time
    (schedule.scene_step_plan; fewer where a stop check ends it earlier)."""
    from granchain.schedule import scene_step_plan

    return sum(g.steps for g in scene_step_plan(companion_scene(scene, factor)))


#: the RK4 companions a Verlet run is measured against aim at this fraction of the Verlet run's
#: predicted error (the planner's error model): small beside the distance they measure
#: (richardson.REFERENCE_SHARE checks it run by run: where it is not, no estimate), at the largest
#: step that reaches it. RK4's error goes as h^4, so this share sets the step only weakly (0.02 -> 0.1:
#: 1.5x the step). Measured on the bundled bilinear and Thornton short impulses (LAMMPS, planned for
#: rtol 1e-3, true error against dt / 8): at 0.02, 59 of 59 and 39 of 39 peaks estimated; at 0.1, 58
#: and 36, every one within 0.65-1.7 of the true error, for about two thirds of the RK4 steps; at 0.25,
#: 58 and 33 (docs/error-bars.md)
RK4_COMPANION_SHARE = 0.1
#: below this many dt the RK4 companions stay at 2 dt and 4 dt: the reference's own companions there
#: (granchain compare makes each run once for both backends) cost less than slightly coarser new ones
SHARED_BELOW = 3.0


#: what an RK4 step of the reference costs in numpy, in steps of its Verlet (four force evaluations to
#: one, but both pay the same per-step bookkeeping, and a kink crossing costs RK4 two more tries):
#: measured 3.3 on plastic-short-impulse and 2.5 on thornton-short-impulse (bench_errorbar_price.py,
#: 2026-11-27: the RK4 companions' time over the Verlet run's, times their steps' share)
RK4_STEP_COST = 3.3


def rk4_companions_cost(scene) -> float:
    """What the RK4 runs a numpy Verlet run of this scene is measured against cost, as a share of that
    run: their two steps' shares of its steps (against_rk4_factors) times RK4_STEP_COST."""
    return RK4_STEP_COST * sum(1.0 / f for f in against_rk4_factors(scene))


def against_rk4_factors(scene) -> tuple[float, float]:
    """The steps (as multiples of the run's dt) of the RK4 runs a Verlet run is measured against: RK4's
    planned step for RK4_COMPANION_SHARE of the Verlet run's predicted error, and twice it (its own
    error), within RK4's stability, where that is at least SHARED_BELOW dt; else 2 dt and 4 dt, or dt
    and 2 dt where 4 dt is unstable."""
    from granchain.workflows.plan import accurate_timestep, highest_frequency, predicted_error

    omega = highest_frequency(scene)[0]
    dt = scene.run.timestep
    stable = RK4.stability / omega
    h = accurate_timestep("rk4", omega, 0.0, RK4_COMPANION_SHARE * predicted_error("verlet", omega, 0.0, dt))
    h = min(h, 0.5 * stable)
    if h >= SHARED_BELOW * dt:
        return (h / dt, 2.0 * h / dt)
    return (2.0, 4.0) if 4 * dt <= stable else (1.0, 2.0)


def estimate_errors(
    result,
    run_one,
    method: str,
    stable_timestep: float,
    run_rk4=None,
    checked: bool = False,
    absolute_positions: bool = False,
    numpy_speed: bool = False,
) -> ErrorReport:
    """Run a result's companions with run_one(scene) -> RunResult and estimate every error.

    result: the finished run (its scene is concrete, its solution at dt); method: the integrator
    (rk4 or verlet); stable_timestep: the planner's stability limit for this scene and integrator;
    run_rk4(scene) -> RunResult: the reference RK4 run of a scene, for a Verlet run whose law needs it
    (against_rk4_because; None: Richardson always); absolute_positions: the backend integrates
    absolute positions (Backend.absolute_positions; its round-off floor, roundoff_floor); numpy_speed:
    the backend integrates at numpy's speed (Backend.numpy_speed; against_rk4_because).
    """
    scene = result.scene
    if run_rk4 is not None and against_rk4_because(method, scene, checked, numpy_speed):
        report = _against_rk4(result, run_rk4, method)
        report.why_unchecked = unchecked_because(method, scene)
        return report
    report = ErrorReport(order=integrator_order(method, scene), timesteps=[], wall_times=[])
    report.bound = bounded_because(method, scene)
    report.why_none = withheld_because(method, scene)
    if report.why_none:
        return report
    report.one_companion = one_companion_because(method, scene, checked)
    if report.one_companion is not None:
        report.order = BOUND_ORDER
    with kept_lammps():
        factors = richardson_factors(method, scene, checked)
        runs = _richardson_runs(report, scene, run_one, stable_timestep, factors)
        if runs is None:
            return report
        finer = _check_run(report, scene, run_one) if check_because(method, scene, checked) else None
    if checked and report.bound is not None:  # (asked for, but no RK4 run to measure against: run_rk4 None)
        report.why_unchecked = f"no RK4 runs to measure it against here. {BOUNDED_BY_DEFAULT}"
    elif checked and not check_because(method, scene, checked):
        report.why_unchecked = unchecked_because(method, scene)
    elif report.one_companion is not None:
        report.why_unchecked = ONE_COMPANION_BY_DEFAULT
    elif not checked and check_because(method, scene, True):
        report.why_unchecked = UNCHECKED_BY_DEFAULT
    elif not checked and report.bound is not None:
        report.why_unchecked = BOUNDED_BY_DEFAULT
    _richardson_bars(report, result, runs, method, finer, absolute_positions)
    return report


@contextmanager
def kept_lammps():
    """Within, single-rank LAMMPS runs share one kept LAMMPS child (granchain.lammps.server): of two
    LAMMPS companions the second does not pay LAMMPS's start-up again (process, import, plugin load),
    which alone costs more than a short run's integration. Companions of other backends start none."""
    from granchain.lammps import server

    with server.persistent():
        yield


def _richardson_runs(
    report: ErrorReport, scene, run_one, stable_timestep: float, factors: tuple[float, ...] = (2.0, 4.0)
) -> list | None:
    """The companions at 2 dt and (where stable, and in factors) 4 dt, their steps and wall times into
    the report; None when there is no estimate (report.why_none says why)."""
    dt = scene.run.timestep
    runs = []
    for factor in factors:
        if factor * dt > stable_timestep:
            if factor == 2.0:
                report.why_none = (
                    f"2 dt = {2 * dt:.3g} s is above the stability limit {stable_timestep:.3g} s: "
                    "no companion run, no estimate"
                )
                return None
            break
        t0 = time.perf_counter()
        try:
            with labelled(f"error-bar companion at {factor:g} dt"):
                runs.append(run_one(companion_scene(scene, factor)).solution)
            # (a run shared or made ahead by granchain compare returns at once: its own wall time)
            t0 = min(t0, time.perf_counter() - runs[-1].wall_time)
        except GranchainError as e:  # a coarser run broke an invariant: the run itself stands
            first_line = str(e).splitlines()[0] if str(e) else type(e).__name__
            if factor == 2.0:
                report.why_none = f"the 2 dt companion run failed ({first_line}): no estimate"
                return None
            report.why_none_4dt = f"the 4 dt companion run failed ({first_line}): order not checked"
            break
        report.wall_times.append(time.perf_counter() - t0)
        report.timesteps.append(factor * dt)
        report.steps.append(int(runs[-1].steps))
    return runs


def _check_run(report: ErrorReport, scene, run_one):
    """The run at dt / 2 that checks Richardson's bars (check_because), its step and wall time into the
    report (its price counts with the companions'); None if it failed (report.why_unchecked says so)."""
    t0 = time.perf_counter()
    try:
        with labelled(f"error-bar check at {CHECK_FACTOR:g} dt"):
            sol = run_one(companion_scene(scene, CHECK_FACTOR)).solution
        t0 = min(t0, time.perf_counter() - sol.wall_time)
    except GranchainError as e:
        first_line = str(e).splitlines()[0] if str(e) else type(e).__name__
        report.why_unchecked = f"the run at dt / 2 that checks the estimates failed ({first_line}): not checked"
        return None
    report.check_wall_time = time.perf_counter() - t0
    report.wall_times.append(report.check_wall_time)
    report.check_timestep = CHECK_FACTOR * scene.run.timestep
    report.check_steps = int(sol.steps)
    return sol


def _richardson_bars(
    report: ErrorReport, result, runs: list, method: str, finer=None, absolute_positions: bool = False
) -> None:
    """Richardson's error bars of every number of the run from its companions (richardson.richardson),
    checked against the run at dt / 2 where there is one (richardson.checked); absolute_positions:
    the backend's (roundoff_floor)."""
    scene, sol = result.scene, result.solution
    p = report.order
    coarse = runs[0]
    coarser = runs[1] if len(runs) > 1 else None
    from granchain.workflows.plan import highest_frequency

    jump = np.pi / highest_frequency(scene)[0]  # half the shortest period of the chain
    n = len(sol.peak_force)

    def values(name: str, complete_only: bool = False) -> list:
        return per_contact((sol, coarse, coarser, finer), name, n, complete_only)

    orders = expected_orders(method, scene)
    # a kinked law's Verlet bars are bounds (bounded_because); RK4's there are bounds from one companion
    # (one_companion_because: order BOUND_ORDER, the report's)
    extrapolate = erratic_bounds if report.bound is not None else richardson
    if report.one_companion is not None:

        def extrapolate(fine, coarse, coarser, order, times=None, jump_time=None, orders=None, floor=None):
            return one_companion(
                fine, coarse, order, times=None if times is None else times[:2], jump_time=jump_time, floor=floor
            )

    def bars(v, t, order=p, floor=None) -> ErrorBars:
        # Richardson over dt, 2 dt, 4 dt; checked against dt / 2 where that run was made
        b = extrapolate(*v[:3], order, times=tuple(t[:3]), jump_time=jump, orders=orders, floor=floor)
        if finer is None:
            return b
        return checked(b, v[3], v[0], v[1], order, times=(t[3], t[0], t[1]), jump_time=jump, orders=orders, floor=floor)

    pf, tp = values("peak_force", True), values("time_of_peak", True)
    lf, lt = values("leading_pulse_force"), values("leading_pulse_time")
    floor = roundoff_floor(scene, sol, absolute_positions)
    report.peak_force = bars(pf, tp, floor=floor)
    report.time_of_peak = bars(tp, tp)
    # a leading pulse rises no higher than its contact's peak, and a contact's slope grows with its
    # force (Hertz; constant on a loading line): the peak's floor bounds the leading pulse's round-off
    report.leading_pulse_force = bars(lf, lt, floor=floor)
    report.arrival_time = bars(lt, lt)

    _largest(report, scene, sol)

    # a striker's or a wall's contact is one impact from zero overlap: an integrator's error there is its
    # onset's, order 1 + n (Hertz: 1 + 3/2), where its own is higher (RK4, two spheres, planned step: with
    # order 4 the bar was 1/2.9 of the true error); not on a loading line, nor for one companion's bounds
    onset = report.one_companion is None and not scene.contact.law_class.loading_is_linear()
    p_end = onset_order(scene) if onset and onset_order(scene) < p else p

    def bars_of(values, times):
        values, times = list(values), None if times is None else list(times)
        if finer is not None:  # the run at dt / 2 comes last (below)
            h, th = float(values.pop()), None if times is None else float(times.pop())
        v = [float(x) for x in values] + ([None] if coarser is None else [])
        t = None if times is None else tuple([float(x)] for x in times) + ((None,) if coarser is None else ())
        c = None if v[2] is None else [v[2]]
        b = extrapolate([v[0]], [v[1]], c, p_end, times=t, jump_time=jump, orders=orders)
        if finer is None:
            return b
        t = None if times is None else ([th], [float(times[0])], [float(times[1])])
        return checked(b, [h], [v[0]], [v[1]], p_end, times=t, jump_time=jump, orders=orders)

    report.end_peaks = _end_peaks((sol, *runs) + (() if finer is None else (finer,)), bars_of)
    _observable_bars(report, scene, (sol, coarse, coarser, finer), extrapolate, (p, jump, orders), floor)


def _observable_bars(report: ErrorReport, scene, sols: tuple, extrapolate, rule: tuple, floor) -> None:
    """The scalar observables' bars (ESTIMATED_OBSERVABLES) for _richardson_bars: measured on each of
    sols = (the run, 2 dt, 4 dt or None, dt / 2 or None), extrapolated with the run's rule (order,
    jump_time, orders) and checked against dt / 2 where that run was made."""
    sol, coarse, coarser, finer = sols
    p, jump, orders = rule
    missing: dict[str, str] = {}  # why the run itself lacks a value: that, not its companions', is said
    obs = [measure_observables(scene, sol, missing)]
    obs += [measure_observables(scene, s) for s in (coarse,) + ((coarser,) if coarser is not None else ())]
    obs_h = None if finer is None else measure_observables(scene, finer)
    b = max(scene.window[1] - 1, 0)
    for name in ESTIMATED_OBSERVABLES:
        vals = [o.get(name) for o in obs]
        v = [np.nan if x is None else float(x) for x in vals] + ([None] if coarser is None else [])
        times = None
        if name.startswith("leading_peak_force") and scene.n_contacts:
            times = tuple(None if s is None else float(s.leading_pulse_time[b]) for s in (sol, coarse, coarser))
        # max_peak_force: the largest over contacts is continuous in the runs even where its contact
        # changes (a steady wave peaks alike everywhere), so no pulse check; wave_speed: a fit
        fl = _observable_floor(name, obs[0], floor, b)
        bars = extrapolate(
            [v[0]], [v[1]], None if v[2] is None else [v[2]], p, times=times, jump_time=jump, orders=orders, floor=fl
        )
        if obs_h is not None:
            h = obs_h.get(name)
            th = None
            if times is not None:
                th = float(finer.leading_pulse_time[b])
                times = ([th], [times[0]], [times[1]])
            bars = checked(
                bars,
                [np.nan if h is None else float(h)],
                [v[0]],
                [v[1]],
                p,
                times=times,
                jump_time=jump,
                orders=orders,
                floor=fl,
            )
        bound = None
        if obs_h is not None:
            bound = _withheld_step_bound(obs_h.get(name), v[0], v[1], float(p if orders is None else orders[0]))
        report.observables[name] = _observable_error(name, vals[0], bars, obs[0], bound)
        if vals[0] is None and name in missing:
            report.observables[name]["status"] = f"not measured: {missing[name]}"


#: a withheld step error the fit's standard error outweighs this many times over is left out of the
#: wave speed's error: in quadrature it would add under 0.5% of the fit's
FIT_DOMINATES = 10.0


def _withheld_step_bound(finer, fine, coarse, lo: float) -> float | None:
    """A bound on the step's error at dt that holds on either reading of a check that failed
    (richardson.checked): MAX_OVERESTIMATE times the larger of the most the difference to dt / 2
    allows (|Q(dt / 2) - Q(dt)| / (1 - 2^-lo), lo the integrator's lowest order) and the change from
    2 dt, |Q(dt) - Q(2 dt)| (above any estimate from 2 dt and 4 dt at an order of 1 or more). None
    where a run did not measure the value."""
    from granchain.richardson import MAX_OVERESTIMATE

    q = [np.nan if x is None else float(x) for x in (finer, fine, coarse)]
    if not all(np.isfinite(q)):
        return None
    return MAX_OVERESTIMATE * max(abs(q[0] - q[1]) / (1.0 - 2.0**-lo), abs(q[1] - q[2]))


def _observable_floor(name: str, measured: dict, floor: np.ndarray | None, b: int) -> float | None:
    """The round-off floor of a scalar observable (N, or its nondimensional form): the leading peak's
    is its contact's (b, 0-based), the largest peak's its contact's; a wave speed, a fit of arrival
    times, has none."""
    if floor is None:
        return None
    if name.startswith("leading_peak_force") and b < floor.size:
        fl = float(floor[b])
        if name.endswith("_nondim"):  # the nondimensional form scales the force
            force, nondim = measured.get("leading_peak_force"), measured.get(name)
            fl = fl * float(nondim) / float(force) if force and nondim is not None else np.nan
    elif name == "max_peak_force" and measured.get("max_peak_contact") is not None:
        fl = float(floor[int(measured["max_peak_contact"]) - 1])
    else:
        return None
    return fl if np.isfinite(fl) else None


def roundoff_floor(scene, sol, absolute_positions: bool = False) -> np.ndarray | None:
    """Each contact's peak force's round-off in a run (N), or None where the run gives no displacements.

    The reference integrates displacements u (from the undeformed chain) and takes overlaps as
    u_i - u_(i+1): every step rounds u at eps |u|, and over the run's n steps those roundings add as a
    random walk, sqrt(n) eps U (U the largest |u|, from the final state: the drift and the static
    compression of a precompressed chain). A contact's force carries it times its slope, at most
    3/2 F / alpha at its peak (Hertz; a linear loading line's F / alpha is below). Where the step is
    far finer than accuracy needs (the stability limit of a chain's smallest beads: a taper to 0.8,
    a precompressed 20-bead chain, docs/error-bars.md) the step's error falls below this, and the
    three runs' differences are round-off that can look like any order: measured there 0.013-0.62 of
    the distance to a run at dt / 16, itself round-off (the runs at dt / 2 to dt / 16 scattered by
    1e-13 - 1e-12 N about one another, 20-150x eps U dF/dalpha).

    A backend that integrates absolute positions (LAMMPS, Backend.absolute_positions) rounds each at
    eps |x|, up to the chain's length: there U is the largest |x|, and, without overlaps in its
    output, the slope is the stiffest of the chain's laws at the contact's peak force
    (ContactLaw.tangent_stiffness). The same random walk as peaks.position_resolution, which bounds
    it at 6 standard deviations for the leading pulse's floor.
    """
    u = np.asarray(getattr(sol, "displacement", ()), dtype=float)
    if u.size == 0 or not sol.steps:
        return None
    f = np.asarray(sol.peak_force, dtype=float)
    if absolute_positions:
        from granchain.peaks import chain_laws

        size = float(np.max(np.abs(scene.bead_positions[: u.size] + u)))
        force = np.nan_to_num(np.abs(f))
        slope = np.max(
            [np.broadcast_to(law.tangent_stiffness(force), force.shape) for law in chain_laws(scene)], axis=0
        )
        slope = np.where(np.isfinite(f), slope, np.nan)
    else:
        overlap = getattr(sol, "peak_overlap", None)
        if overlap is None:
            return None
        size = float(np.max(np.abs(u)))
        a = np.asarray(overlap, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = np.where(a > 0, 1.5 * np.abs(f) / a, np.nan)
    return np.sqrt(float(sol.steps)) * np.finfo(float).eps * size * slope


def _against_rk4(result, run_rk4, method: str) -> ErrorReport:
    """A Verlet run's error report against RK4 runs at 2 dt and 4 dt, or dt and 2 dt (richardson.against_reference)."""
    from granchain.workflows.plan import highest_frequency, plan_scene

    scene, sol = result.scene, result.solution
    dt = scene.run.timestep
    report = ErrorReport(order=integrator(method).order, timesteps=[], wall_times=[], against=RK4.name)
    report.why_none = withheld_because(RK4.name, scene)
    if report.why_none:
        return report
    stable = plan_scene(scene, method="rk4").stable_timestep
    if 2 * dt > stable:
        report.why_none = f"2 dt = {2 * dt:.3g} s is above RK4's stability limit: no RK4 companion, no estimate"
        return report
    # RK4 at its own step for a small share of Verlet's error (against_rk4_factors; at least 2 dt and
    # 4 dt): 4th order with its kinks located, its error there is far below Verlet's at dt, and
    # against_reference checks that it is
    runs = []
    for factor in against_rk4_factors(scene):
        t0 = time.perf_counter()
        try:
            with labelled(f"error-bar companion (RK4) at {factor:.3g} dt"):
                companion = run_rk4(companion_scene(scene, factor))
        except GranchainError as e:
            first_line = str(e).splitlines()[0] if str(e) else type(e).__name__
            report.why_none = f"the RK4 companion run at {factor:g} dt failed ({first_line}): no estimate"
            return report
        runs.append(companion.solution)
        # the companion's own price: a run shared with another (granchain compare's
        # shared_reference_runs) or made ahead in a worker returns at once, but it cost its wall time
        report.wall_times.append(max(time.perf_counter() - t0, companion.solution.wall_time))
        report.timesteps.append(factor * dt)
        report.steps.append(int(companion.solution.steps))
    jump = np.pi / highest_frequency(scene)[0]
    n = len(sol.peak_force)

    def values(name: str, complete_only: bool = False) -> list:
        return per_contact((sol, *runs), name, n, complete_only)

    pf, tp = values("peak_force", True), values("time_of_peak", True)
    lf, lt = values("leading_pulse_force"), values("leading_pulse_time")
    report.peak_force = against_reference(*pf, times=(tp[0], tp[1]), jump_time=jump)
    report.time_of_peak = against_reference(*tp, times=(tp[0], tp[1]), jump_time=jump)
    report.leading_pulse_force = against_reference(*lf, times=(lt[0], lt[1]), jump_time=jump)
    report.arrival_time = against_reference(*lt, times=(lt[0], lt[1]), jump_time=jump)
    _largest(report, scene, sol)

    def bars_of(values, times):
        v = [float(x) for x in values]
        t = None if times is None else ([float(times[0])], [float(times[1])])
        return against_reference([v[0]], [v[1]], [v[2]], times=t, jump_time=jump)

    report.end_peaks = _end_peaks((sol, *runs), bars_of)
    obs = [measure_observables(scene, s) for s in (sol, *runs)]
    b = max(scene.window[1] - 1, 0)
    for name in ESTIMATED_OBSERVABLES:
        vals = [o.get(name) for o in obs]
        v = [np.nan if x is None else float(x) for x in vals]
        times = None
        if name.startswith("leading_peak_force") and scene.n_contacts:
            times = tuple([float(s.leading_pulse_time[b])] for s in (sol, runs[0]))
        bars = against_reference([v[0]], [v[1]], [v[2]], times=times, jump_time=jump)
        report.observables[name] = _observable_error(name, vals[0], bars, obs[0])
    return report


def _observable_error(name: str, value, bars, measured: dict, withheld_bound: float | None = None) -> dict:
    """An observable's entry: its time-step error (bars) and, for the wave speed, the fit's standard
    error too: the reported error is both in quadrature (on a taper or a dimer the fit's spread is
    30x to 20 000x the step's), each kept under its own name.

    Where a check withheld the step's error (the run at dt / 2, or the order checks of 2 dt and 4 dt) but
    withheld_bound (_withheld_step_bound)
    puts it under 1 / FIT_DOMINATES of the fit's standard error, the wave speed's error is the fit's
    alone (the step's stays withheld, its bound given as step_error_bound) and the status says so.
    """
    step = float(bars.error[0])
    out = {"value": value, "error": step if np.isfinite(step) else None, "status": str(bars.status[0])}
    fit = measured.get("wave_speed_stderr") if name == "wave_speed" else None
    if fit is not None and value is not None:
        out["step_error"] = out["error"]
        out["fit_stderr"] = float(fit)
        out["error"] = float(np.hypot(step, fit)) if np.isfinite(step) else None
        if out["error"] is not None:
            out["status"] += "; error: the step's and the fit's standard error in quadrature"
        elif withheld_bound is not None and FIT_DOMINATES * withheld_bound <= float(fit):
            out["error"] = float(fit)
            out["step_error_bound"] = float(withheld_bound)
            out["status"] = (
                f"fit's spread alone: the step's error is withheld ({out['status'].removeprefix('unreliable: ')}); "
                f"the runs at dt / 2, dt and 2 dt bound it at {withheld_bound:.2g} whichever reading of the "
                f"check that withheld it is right, under 1/{FIT_DOMINATES:g} of the fit's standard error "
                f"{float(fit):.2g}"
            )
    return out


#: the effects' own contacts that get error bars: peak force -> its time (ChainSolution fields)
END_PEAKS = {"striker_peak_force": "striker_time_of_peak", "wall_peak_force": "wall_time_of_peak"}
#: why an end peak has no bar: the run's own peak, or a companion's, had not passed when it ended
END_PEAK_INCOMPLETE = (
    "incomplete: the wave had not reached it, or its force had not fallen to half its peak, when the run ended"
)
END_PEAK_COMPANION_INCOMPLETE = "not measured: incomplete in a companion run"


def _end_peaks(solutions, bars_of) -> dict[str, dict]:
    """Error bars of the striker's and the wall's peak forces and times from the run and its
    companions (bars_of(values, times) -> ErrorBars of one number, the estimator of the report)."""
    out: dict[str, dict] = {}
    for force, when in END_PEAKS.items():
        vals = [getattr(s, force) for s in solutions]
        if vals[0] is None or any(v is None for v in vals):
            continue
        times = [getattr(s, when) for s in solutions]
        # a running maximum is not a peak (ChainSolution.wall_peak_complete); None: not tracked
        done = [getattr(s, force.replace("_peak_force", "_peak_complete")) is not False for s in solutions]
        if not all(done):
            why = END_PEAK_INCOMPLETE if not done[0] else END_PEAK_COMPANION_INCOMPLETE
            for name, values in ((force, vals), (when, times)):
                out[name] = {"value": float(values[0]), "error": None, "status": why}
            continue
        for name, values, at in ((force, vals, times), (when, times, None)):
            bars = bars_of(values, at)
            err = float(bars.error[0])
            out[name] = {
                "value": float(values[0]),
                "error": err if np.isfinite(err) else None,
                "status": str(bars.status[0]),
            }
    return out


def _largest(report: ErrorReport, scene, sol) -> None:
    """The largest relative peak-force error over the measured contacts, and the contacts without one."""
    n = len(sol.peak_force)
    measured = measured_contacts(scene, sol)
    rel = np.full(n, np.nan)
    # relative to the wave's force: above the static force F0 a precompressed contact carries at rest
    dynamic = np.abs(np.asarray(sol.peak_force, dtype=float) - float(scene.effects.precompression))
    ok = report.peak_force.reliable & (dynamic > 0)
    rel[ok] = report.peak_force.error[ok] / dynamic[ok]
    m = measured[np.isfinite(rel[measured])]
    if m.size:
        i = int(m[np.argmax(rel[m])])
        report.error_estimate, report.error_estimate_contact = float(rel[i]), i + 1
    report.unreliable_contacts = [int(i) + 1 for i in measured if not np.isfinite(rel[i])]
