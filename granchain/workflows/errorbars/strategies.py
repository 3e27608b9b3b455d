"""The error-bar strategies, one class each, and the registry that picks a run's (STRATEGIES).

A run's bars come from the first strategy in STRATEGIES whose ``because`` gives a reason: the RK4
runs a Verlet run is measured against (AgainstRK4), none (Withheld), bounds from 2 dt and 4 dt
(Bounded), bounds from 2 dt alone (OneCompanion), Richardson checked at dt / 2 (Checked), Richardson
(Richardson, which always applies). Each says what it costs before a run (``companions``) and makes
its report (``estimate``); granchain.workflows.error_estimates asks the registry for both.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from granchain.integrators import RK4, integrator
from granchain.richardson import BOUND_ORDER, CHECK_FACTOR, erratic_bounds, one_companion, richardson
from granchain.workflows.errorbars import reasons
from granchain.workflows.errorbars.bars import against_rk4_bars, extrapolated_bars
from granchain.workflows.errorbars.facts import against_rk4_factors, integrator_order
from granchain.workflows.errorbars.report import Companion, ErrorReport
from granchain.workflows.errorbars.runs import _check_run, _richardson_runs, kept_lammps, rk4_runs


@dataclass(frozen=True)
class Request:
    """What a strategy is asked about: a run of this concrete scene with this integrator.

    Attributes
    ----------
    method : str
        The run's integrator.
    scene : granchain.scene.Scene
        The concrete scene the run runs (its time step and end time set).
    checked : bool
        Checked bars asked for (error_estimate="checked").
    numpy_speed : bool
        The run's backend integrates at numpy's speed (Backend.numpy_speed).
    rk4_runs : bool
        RK4 runs of the reference can be made for it (estimate_errors' run_rk4 given; the plan assumes so).
    """

    method: str
    scene: object
    checked: bool = False
    numpy_speed: bool = False
    rk4_runs: bool = True


class ErrorBarStrategy:
    """One way of giving a run's error bars.

    Rules for writing a new strategy:

    * ``because(req)`` returns why it applies to this run (a sentence the report keeps, naming the
      measurement that chose it, docs/error-bars.md) or None; it reads only the integrator's and the
      law's declared facts (IntegratorFacts, ContactLaw), never an integrator's or a law's name.
    * ``companions(req, stable_timestep)`` lists every run its estimate makes when none fails, in the
      order ``estimate`` makes them: it is the price the planner shows (granchain info --plan,
      planned_companions) and must agree with ``estimate`` (tests/test_plan_cost.py checks the steps).
    * ``estimate(...)`` makes those runs and fills an ErrorReport; a companion that fails leaves the run
      standing, the report saying why (why_none, why_none_4dt, why_unchecked), never an exception.
    * Put it in STRATEGIES where it is to be tried: the first whose ``because`` gives a reason is the
      run's, so a narrower strategy comes before a broader one, and Richardson, which always applies,
      stays last.
    """

    name: ClassVar[str]

    def because(self, req: Request) -> str | None:
        """Why this strategy gives the run's bars, or None."""
        raise NotImplementedError

    def companions(self, req: Request, stable_timestep: float) -> list[Companion]:
        """The runs its estimate makes when none fails (stable_timestep: the planner's limit, s)."""
        raise NotImplementedError

    def estimate(self, req: Request, result, run_one, run_rk4, stable_timestep: float, absolute_positions: bool):
        """The run's ErrorReport (run_one, run_rk4: as estimate_errors')."""
        raise NotImplementedError


class AgainstRK4(ErrorBarStrategy):
    """A Verlet run on a kinked law measured against RK4 runs (against_rk4_because)."""

    name = "against rk4"

    def because(self, req: Request) -> str | None:
        """against_rk4_because, where RK4 runs can be made."""
        if not req.rk4_runs:
            return None
        return reasons.against_rk4_because(req.method, req.scene, req.checked, req.numpy_speed)

    def companions(self, req: Request, stable_timestep: float) -> list[Companion]:
        """RK4 runs at against_rk4_factors; none where RK4 gives no bar or 2 dt is above its limit."""
        from granchain.workflows.plan import plan_scene

        scene = req.scene
        if (
            reasons.withheld_because("rk4", scene)
            or 2 * scene.run.timestep > plan_scene(scene, method="rk4").stable_timestep
        ):
            return []
        return [Companion("rk4", f, "rk4 reference") for f in against_rk4_factors(scene)]

    def estimate(self, req: Request, result, run_one, run_rk4, stable_timestep: float, absolute_positions: bool):
        """The distance to the RK4 runs (richardson.against_reference), the check's absence said."""
        from granchain.workflows.plan import plan_scene

        scene = result.scene
        dt = scene.run.timestep
        report = ErrorReport(order=integrator(req.method).order, timesteps=[], wall_times=[], against=RK4.name)
        report.why_none = reasons.withheld_because(RK4.name, scene)
        if not report.why_none:
            if 2 * dt > plan_scene(scene, method="rk4").stable_timestep:
                report.why_none = f"2 dt = {2 * dt:.3g} s is above RK4's stability limit: no RK4 companion, no estimate"
            else:
                # RK4 at its own step for a small share of Verlet's error (against_rk4_factors; at least
                # 2 dt and 4 dt): 4th order with its kinks located, its error there is far below
                # Verlet's at dt, and against_reference checks that it is
                runs = rk4_runs(report, scene, run_rk4, against_rk4_factors(scene))
                if runs is not None:
                    against_rk4_bars(report, result, runs)
        report.why_unchecked = reasons.unchecked_because(req.method, scene)
        return report


class Withheld(ErrorBarStrategy):
    """No bars: the integrator's error follows no order on this scene (withheld_because)."""

    name = "withheld"

    def because(self, req: Request) -> str | None:
        """reasons.withheld_because."""
        return reasons.withheld_because(req.method, req.scene)

    def companions(self, req: Request, stable_timestep: float) -> list[Companion]:
        """None: no companion runs."""
        return []

    def estimate(self, req: Request, result, run_one, run_rk4, stable_timestep: float, absolute_positions: bool):
        """A report without bars, saying why (why_none)."""
        report = ErrorReport(order=integrator_order(req.method, req.scene), timesteps=[], wall_times=[])
        report.bound = reasons.bounded_because(req.method, req.scene)
        report.why_none = self.because(req)
        return report


class Richardson(ErrorBarStrategy):
    """Richardson extrapolation over the runs at dt, 2 dt and 4 dt (richardson.richardson).

    The base of the strategies that extrapolate from the run's own companions: each sets its
    companions' steps (factors), whether a run at dt / 2 checks them (check), the order it assumes
    (order), its rule (extrapolate), the report's fields that say so (mark) and what its bars leave
    unchecked (why_unchecked).
    """

    name = "richardson"
    factors: ClassVar[tuple[float, ...]] = (2.0, 4.0)
    check: ClassVar[bool] = False

    def because(self, req: Request) -> str | None:
        """Always: the last in STRATEGIES."""
        return "Richardson extrapolation over runs at dt, 2 dt and 4 dt"

    def companions(self, req: Request, stable_timestep: float) -> list[Companion]:
        """Its own runs at factors within stable_timestep (none where 2 dt is above it), and the check."""
        dt = req.scene.run.timestep
        if 2.0 * dt > stable_timestep:
            return []
        runs = [Companion(req.method, f, "companion") for f in self.factors if f * dt <= stable_timestep]
        if self.check:
            runs.append(Companion(req.method, CHECK_FACTOR, "check"))
        return runs

    def order(self, req: Request) -> float:
        """The order its extrapolation assumes (integrator_order)."""
        return integrator_order(req.method, req.scene)

    def mark(self, report: ErrorReport, req: Request) -> None:
        """Set the report's fields that say which bars these are."""

    #: the bars of the values at dt, 2 dt and 4 dt (richardson.richardson's arguments)
    extrapolate = staticmethod(richardson)

    def why_unchecked(self, req: Request) -> str | None:
        """What its bars leave unchecked below dt (ErrorReport.why_unchecked), or None."""
        if req.checked:
            return reasons.unchecked_because(req.method, req.scene)
        if reasons.check_because(req.method, req.scene, True):
            return reasons.UNCHECKED_BY_DEFAULT
        return None

    def estimate(self, req: Request, result, run_one, run_rk4, stable_timestep: float, absolute_positions: bool):
        """The companions, then the bars (extrapolated_bars)."""
        scene = result.scene
        report = ErrorReport(order=integrator_order(req.method, scene), timesteps=[], wall_times=[])
        self.mark(report, req)
        report.order = self.order(req)
        with kept_lammps():
            runs = _richardson_runs(report, scene, run_one, stable_timestep, self.factors)
            if runs is None:
                return report
            finer = _check_run(report, scene, run_one) if self.check else None
        why = self.why_unchecked(req)
        if why is not None:
            report.why_unchecked = why
        extrapolated_bars(report, result, runs, req.method, self.extrapolate, finer, absolute_positions)
        return report


class Checked(Richardson):
    """Richardson's bars checked against a run at dt / 2 (check_because, richardson.checked)."""

    name = "checked"
    check = True

    def because(self, req: Request) -> str | None:
        """reasons.check_because."""
        return reasons.check_because(req.method, req.scene, req.checked)

    def why_unchecked(self, req: Request) -> str | None:
        """None: the run at dt / 2 checks them (_check_run says when it failed)."""
        return None


class Bounded(Richardson):
    """Bounds from the runs at 2 dt and 4 dt on a kinked law (bounded_because, richardson.erratic_bounds)."""

    name = "bounded"

    def because(self, req: Request) -> str | None:
        """reasons.bounded_because."""
        return reasons.bounded_because(req.method, req.scene)

    def mark(self, report: ErrorReport, req: Request) -> None:
        """ErrorReport.bound: the reason."""
        report.bound = self.because(req)

    extrapolate = staticmethod(erratic_bounds)

    def why_unchecked(self, req: Request) -> str | None:
        """Asked for checked bars, but no RK4 runs to measure them against; else what the bounds leave."""
        if req.checked:  # (asked for, but no RK4 run to measure against: run_rk4 None)
            return f"no RK4 runs to measure it against here. {reasons.BOUNDED_BY_DEFAULT}"
        if reasons.check_because(req.method, req.scene, True):
            return reasons.UNCHECKED_BY_DEFAULT
        return reasons.BOUNDED_BY_DEFAULT


class OneCompanion(Richardson):
    """Bounds from one companion at 2 dt, |Q(dt) - Q(2 dt)| (one_companion_because, richardson.one_companion)."""

    name = "one companion"
    factors = (2.0,)

    def because(self, req: Request) -> str | None:
        """reasons.one_companion_because."""
        return reasons.one_companion_because(req.method, req.scene, req.checked)

    def order(self, req: Request) -> float:
        """BOUND_ORDER: the bound |Q(dt) - Q(2 dt)|."""
        return BOUND_ORDER

    def mark(self, report: ErrorReport, req: Request) -> None:
        """ErrorReport.bound (None) and one_companion: the reason."""
        report.bound = reasons.bounded_because(req.method, req.scene)
        report.one_companion = self.because(req)

    @staticmethod
    def extrapolate(fine, coarse, coarser, order, times=None, jump_time=None, orders=None, floor=None):
        """richardson.one_companion of the values at dt and 2 dt (coarser, orders: unused)."""
        return one_companion(
            fine, coarse, order, times=None if times is None else times[:2], jump_time=jump_time, floor=floor
        )

    def why_unchecked(self, req: Request) -> str | None:
        """reasons.ONE_COMPANION_BY_DEFAULT."""
        return reasons.ONE_COMPANION_BY_DEFAULT


#: the strategies in the order they are tried: the first whose ``because`` gives a reason is the run's
STRATEGIES: tuple[ErrorBarStrategy, ...] = (
    AgainstRK4(),
    Withheld(),
    Bounded(),
    OneCompanion(),
    Checked(),
    Richardson(),
)


def strategy(req: Request) -> ErrorBarStrategy:
    """The strategy that gives this run's bars: the first in STRATEGIES that applies."""
    return next(s for s in STRATEGIES if s.because(req))
