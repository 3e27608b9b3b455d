"""Companions that end before their own event does: continued to it, or said so.

The wall's event quantities (wall_max_force, wall_impulse, wall_energy, event_max_*: Observable.needs
"event") of a companion at 2 dt or 4 dt are its own event's, which ends where that run's chain has
left the wall (granchain.physics.event). A coarser step moves that end: the unloaded chain's end is
proved at the stop check's steps (every STOP_CHECK_EVERY steps, 4x as far apart in time at 4 dt), and
the coarser dynamics shift the last contact with the wall (a PTFE chain under an 8-bead striker, given
end_time = 4.886e-3 s: the run's event ended at 4.8838e-3 s, both companions' at 4.8888e-3 s). A
companion run to the run's own end time can thus end inside its event while the run's has ended,
and its bar was missing under a peak's status ("not complete in the run or its 2 dt companion").

Here such a companion (the run's event ended, its own not, and it ran to its end time) is run again,
to CONTINUED x its end time, with a stop check so that it ends at its event's end, and its event
fields (EVENT_FIELDS, EVENT_MAXIMA_FIELDS) are the continued run's: the same steps from t = 0, its
sums frozen at its own event's end. Everything else (peaks, end state) stays the companion's own,
run to the run's end. A companion still inside its event at the continued end, or any asked
observable a companion did not measure where the run did (a free far end's bead N not yet proved
gone), gets a status that names that companion and its own reason (unmeasured_status).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from granchain.physics.event import EVENT_FIELDS, EVENT_MAXIMA_FIELDS

#: a companion that ended inside its event is continued to this many times its end time (its stop check
#: ends it at its event's end); the ends measured on generated walled chains moved by at most 4% of the
#: run's end between dt and 4 dt (tests/test_companion_event.py)
CONTINUED = 2.0


def cut_short(main, companion, scene) -> bool:
    """Whether a companion (its solution, its scene) ended inside its event while the run (main: its
    solution) had ended its own: it tracked the event and ran to its end time."""
    return (
        scene.n_contacts >= 1
        and main.event_end_time is not None
        and companion.event_end_time is None
        and companion.wall_impulse is not None
        and companion.end_time >= scene.run.end_time * (1.0 - 1e-9)
    )


def continued_scene(scene):
    """The companion's scene run on to CONTINUED x its end time, stopped at its event's end: the stop
    check at contact 1 (passed long before) where the scene has none, which the event tracker holds
    until the event has ended."""
    run = scene.run
    stop = run.stop_after_contact if run.stop_after_contact is not None else 1
    return replace(scene, run=replace(run, end_time=CONTINUED * run.end_time, stop_after_contact=stop))


@dataclass
class Covering:
    """run_one(scene) -> RunResult wrapped (covering): a companion cut short (cut_short) is continued
    (continued_scene) and its event fields are the continued run's. ``companions`` keeps each
    companion's scene and solution, ``continued`` what was continued, in words."""

    run_one: object
    main: object
    companions: list = field(default_factory=list)
    continued: list[str] = field(default_factory=list)

    def __call__(self, scene):
        """The companion's RunResult, its event covered where it can be."""
        result = self.run_one(scene)
        sol = result.solution
        if cut_short(self.main, sol, scene):
            longer = self.run_one(continued_scene(scene)).solution
            sol = replace(sol, **{k: getattr(longer, k) for k in EVENT_FIELDS + EVENT_MAXIMA_FIELDS})
            how = "ended" if sol.event_end_time is not None else "had not ended"
            self.continued.append(
                f"the companion at {scene.run.timestep / self.main.timestep:g} dt ended inside its event at its end "
                f"time ({scene.run.end_time:.4g} s) and was continued to {CONTINUED * scene.run.end_time:.4g} s, "
                f"where its event {how}"
                + (f" (at {sol.event_end_time:.6g} s)" if sol.event_end_time is not None else "")
            )
            result = _with_solution(result, sol)
        self.companions.append((scene, sol))
        return result


def _with_solution(result, solution):
    """The companion's RunResult with its solution replaced (a copy: the caller's is untouched)."""
    from copy import copy

    out = copy(result)
    out.solution = solution
    return out


def unmeasured_status(report, main_scene, main_solution, companions) -> None:
    """Every asked observable with a bar (Observable.asked and error_bar) that the run measured but a
    companion did not: its status names that companion and its reason (why the bar is missing), in
    place of the extrapolation's; companions: (scene, solution) in the order they ran."""
    from granchain.postprocess.observables import OBSERVABLES, measure

    run = measure(main_scene, main_solution).values
    measured = [(s, measure(s, sol)) for s, sol in companions]
    for name, entry in report.observables.items():
        obs = OBSERVABLES.get(name)
        if obs is None or not obs.asked or run.get(name) is None or entry.get("error") is not None:
            continue
        for s, m in measured:
            if m.values.get(name) is None and name in m.missing:
                factor = s.run.timestep / main_scene.run.timestep
                entry["status"] = f"not measured in the companion at {factor:.3g} dt: {m.missing[name]}"
                break


def continued_status(report, continued: list[str]) -> None:
    """The event quantities' statuses (Observable.needs "event") say which companions were continued
    to cover their event (Covering.continued), after what the bar is."""
    from granchain.postprocess.observables import OBSERVABLES

    if not continued:
        return
    for name, entry in report.observables.items():
        if name in OBSERVABLES and "event" in OBSERVABLES[name].needs and entry.get("status"):
            entry["status"] += "; " + "; ".join(continued)
