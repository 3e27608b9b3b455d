"""What an error estimate returns: the ErrorReport of a run, and the Companion runs it makes."""

from __future__ import annotations

from dataclasses import dataclass, field

from granchain.richardson import BOUND_ORDER, ErrorBars


@dataclass
class ErrorReport:
    """Measured error estimates of a run (see granchain.workflows.error_estimates' docstring)."""

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
