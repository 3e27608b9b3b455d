"""One choice of the planner and its reason."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PlanChoice:
    """One choice of the planner (time step, end time, beads, an output interval, the stop check): its
    value and the reason, in words with the scene's numbers."""

    name: str
    value: float
    reason: str
