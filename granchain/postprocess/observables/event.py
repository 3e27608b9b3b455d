"""The far-end wall's event quantities ([outputs] event = true; granchain.physics.event defines the
event and what both backends sum over it at every step): the largest dynamic force on the wall and
its time, the impulse it takes (total and dynamic) and the energy that reaches it."""

from __future__ import annotations

from typing import ClassVar

from granchain.postprocess.observables.base import Measurement, Observable

#: the event quantities' error bar (every one of them)
_BAR = (
    "the time step's error from the companion runs at 2 dt and 4 dt, each summed over its own event (their ends "
    "at the stop check's steps: after it the sums stand still)"
)


def _not_asked(scene) -> str | None:
    """Why a scene has no event quantities, or None."""
    if scene.effects.far_end != "wall":
        return 'a chain without a far-end wall: the event quantities are the wall\'s ([boundary] far_end = "wall")'
    if not scene.outputs.event:
        return "not asked for: [outputs] event = true tracks the wall's event"
    return None


def _why_unended(scene, solution) -> str:
    """Why a run's event quantities are not the event's: it was not tracked, or had not ended."""
    if solution.wall_impulse is None:
        return "the run did not track the wall's event (a run made without [outputs] event = true)"
    held = scene.effects.precompression or scene.effects.gravity
    how = (
        "the wall's dynamic force back at its static value with bead N and the chain's momentum moving away"
        if held
        else "proved to have left the wall for good (no body can reach it again: granchain.physics.event)"
    )
    return (
        f"the event had not ended when the run did (t = {solution.end_time:g} s): not yet {how}; its sums so far "
        "are a part of the event. Run longer: a longer [run] end_time"
    )


class _EventObservable(Observable):
    """What every event quantity shares: where it applies, and its value read off the solution (its
    field of the same name, granchain.physics.event.EVENT_FIELDS) once the event has ended."""

    needs = frozenset({"event"})
    asked = True
    error_bar = _BAR
    applies_where = "a chain on a far-end wall, with [outputs] event = true"

    def applies(self, scene) -> str | None:
        """None on a walled chain asking for the event, else why not."""
        return _not_asked(scene) or super().applies(scene)

    def measure(self, scene, solution) -> Measurement:
        """The event's value, or None and why (not tracked, or not ended by the end of the run)."""
        fields = {k: getattr(solution, k) for k in self.companions}
        if solution.event_end_time is None:
            return Measurement(None, dict.fromkeys(fields), _why_unended(scene, solution))
        return Measurement(float(getattr(solution, self.name)), fields)

    def unmeasured(self, scene, solution, reason: str) -> Measurement:
        """None for it and every companion."""
        return Measurement(None, dict.fromkeys(self.companions), reason)


class WallMaxForce(_EventObservable):
    """The largest dynamic force on the wall over the event, its time and the event's end."""

    name = "wall_max_force"
    unit = "N"
    definition = (
        "the largest force on the far-end wall over the event, above its static force (every step, parabola-refined)"
    )
    companions: ClassVar[dict[str, str]] = {"wall_time_of_max": "s", "event_end_time": "s"}
    shares_reason = ("wall_time_of_max", "event_end_time")
    table_fields = ("wall_time_of_max",)
    shown = True


class WallImpulse(_EventObservable):
    """The impulse delivered to the wall over the event: total (the momentum it takes) and dynamic."""

    name = "wall_impulse"
    unit = "N s"
    definition = (
        "the impulse delivered to the wall over the event, the integral of its total contact force (the momentum "
        "it takes); wall_dynamic_impulse: of the force above its static force"
    )
    companions: ClassVar[dict[str, str]] = {"wall_dynamic_impulse": "N s"}
    shares_reason = ("wall_dynamic_impulse",)
    table_fields = ("wall_dynamic_impulse",)
    shown = True


class WallEnergy(_EventObservable):
    """The energy that reaches the far end: the work bead N does pressing into the wall's contact."""

    name = "wall_energy"
    unit = "J"
    definition = (
        "the energy that reaches the far end over the event: the integral of (F_w - F_s) max(v_N, 0) dt, the work "
        "bead N does pressing into the wall's contact"
    )
