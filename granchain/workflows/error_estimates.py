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

Orders: each integrator's (granchain.integrators: IntegratorFacts.order, damping_order): RK4 4,
velocity Verlet (reference and LAMMPS) 2, but 1 for Verlet with velocity-dependent damping (a damping
part's velocity_dependent: the dashpot, Kuwabara-Kono): the damping force sees half-step velocities and
is first order (Verlet.damping_error). Measured on effect-dashpot (LAMMPS, planned step,
against dt / 16): with order 2 every estimate was 0.37-0.43 of the true error, an underestimate by the
factor (2^2 - 1) / (2^1 - 1) = 3 the first order predicts. No function here asks which integrator a run
has: each reads the integrator's facts (integrator(method)).

The 4 dt companion is skipped where 4 dt is above the stability limit the planner predicts (then
the order is not checked and the status says so); the 2 dt one where 2 dt is (then nothing is
estimated, and the report says why).

The strategies: one class each in granchain.workflows.errorbars.strategies, tried in the order of
STRATEGIES (the first that applies gives the run's bars: AgainstRK4, Withheld, Bounded, OneCompanion,
Checked, Richardson); why each applies in errorbars.reasons (the *_because predicates), the bars in
errorbars.bars, the companion runs in errorbars.runs, the orders and steps in errorbars.facts. This
module asks the registry (estimate_errors, planned_companions) and keeps the names others import.
"""

from __future__ import annotations

from granchain.integrators import RK4
from granchain.workflows.errorbars.bars import (
    END_PEAK_COMPANION_INCOMPLETE,
    END_PEAK_INCOMPLETE,
    END_PEAKS,
    _end_peaks,
    _largest,
    measured_contacts,
    per_contact,
)
from granchain.workflows.errorbars.cover import Covering, continued_status, unmeasured_status
from granchain.workflows.errorbars.facts import (
    RK4_COMPANION_SHARE,
    RK4_STEP_COST,
    SHARED_BELOW,
    against_rk4_factors,
    companion_scene,
    companion_steps,
    expected_orders,
    integrator_order,
    kinked_law,
    onset_order,
    rk4_companions_cost,
)
from granchain.workflows.errorbars.observables import (
    FIT_DOMINATES,
    _observable_error,
    _observable_floor,
    _withheld_step_bound,
    roundoff_floor,
)
from granchain.workflows.errorbars.reasons import (
    BOUNDED_BY_DEFAULT,
    ONE_COMPANION_BY_DEFAULT,
    UNCHECKED_BY_DEFAULT,
    against_rk4_because,
    bounded_because,
    check_because,
    one_companion_because,
    unchecked_because,
    withheld_because,
)
from granchain.workflows.errorbars.report import Companion, ErrorReport
from granchain.workflows.errorbars.runs import kept_lammps
from granchain.workflows.errorbars.strategies import STRATEGIES, ErrorBarStrategy, Request, strategy

__all__ = [
    "BOUNDED_BY_DEFAULT",
    "END_PEAKS",
    "END_PEAK_COMPANION_INCOMPLETE",
    "END_PEAK_INCOMPLETE",
    "FIT_DOMINATES",
    "ONE_COMPANION_BY_DEFAULT",
    "RK4_COMPANION_SHARE",
    "RK4_STEP_COST",
    "SHARED_BELOW",
    "STRATEGIES",
    "UNCHECKED_BY_DEFAULT",
    "Companion",
    "ErrorBarStrategy",
    "ErrorReport",
    "Request",
    "_end_peaks",
    "_largest",
    "_observable_error",
    "_observable_floor",
    "_withheld_step_bound",
    "against_rk4_because",
    "against_rk4_factors",
    "bounded_because",
    "check_because",
    "companion_scene",
    "companion_steps",
    "estimate_errors",
    "expected_orders",
    "integrator_order",
    "kept_lammps",
    "kinked_law",
    "measured_contacts",
    "one_companion_because",
    "onset_order",
    "per_contact",
    "planned_companions",
    "richardson_factors",
    "rk4_companions",
    "rk4_companions_cost",
    "roundoff_floor",
    "strategy",
    "unchecked_because",
    "withheld_because",
]


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


def planned_companions(
    scene, method: str, stable_timestep: float, checked: bool = False, numpy_speed: bool = False
) -> list[Companion]:
    """The runs the error estimate of a run of this concrete scene with `method` makes when none fails
    (estimate_errors with run_rk4 given, as granchain run and the API give it): the companions of the
    first strategy in STRATEGIES that applies (ErrorBarStrategy.companions): RK4 runs at
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
    req = Request(method, scene, checked, numpy_speed)
    return strategy(req).companions(req, stable_timestep)


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
    the backend integrates at numpy's speed (Backend.numpy_speed; against_rk4_because). The bars are
    the first strategy's in STRATEGIES that applies (ErrorBarStrategy.estimate).
    """
    req = Request(method, result.scene, checked, numpy_speed, rk4_runs=run_rk4 is not None)
    # a companion that ends inside its own event is continued to its end (errorbars.cover)
    own, rk4 = Covering(run_one, result.solution), Covering(run_rk4, result.solution)
    rk4_one = rk4 if run_rk4 is not None else None
    report = strategy(req).estimate(req, result, own, rk4_one, stable_timestep, absolute_positions)
    unmeasured_status(report, result.scene, result.solution, own.companions + rk4.companions)
    continued_status(report, own.continued + rk4.continued)
    return report
