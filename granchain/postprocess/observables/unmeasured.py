"""What a run ended before measuring that the scene asked for (the command line exits 1)."""

from __future__ import annotations

import numpy as np

from granchain.peaks import still_rising
from granchain.postprocess.observables import registry
from granchain.problem import scene_static_forces


def _why_still_rising(scene, solution, contact: int) -> str:
    """Why a 1-based contact's peak so far is not its peak: the wave is still arriving there."""
    i = contact - 1
    f0 = float(scene_static_forces(scene)[i])  # the contact's own static force
    lead = float(solution.leading_pulse_force[i]) - f0
    first = (
        f"; its leading pulse (its first maximum, {lead:.6g} N above the static force at "
        f"t = {float(solution.leading_pulse_time[i]):g} s) stands"
        if np.isfinite(lead)
        else ""
    )
    return (
        f"the force at contact {contact} still rises at the end of the run (t = {solution.end_time:g} s): the wave "
        f"has not passed it, and its peak so far ({float(solution.peak_force[i]) - f0:.6g} N above the static force "
        f"at t = {float(solution.time_of_peak[i]):g} s) is not complete and may not be its peak{first}; run longer"
    )


def unmeasured_outputs(scene, solution) -> list[str]:
    """What the scene asked for that the run ended before measuring: the observables a run that
    ends before them says it missed (Observable.asked: the window's leading peak and wave speed, of a
    peak-force table), each with the reason, the window's last contact's peak while
    the force there still rises at the end (peaks.still_rising: a main wave behind a smaller
    precursor; not while a force load still acts, whose plateau the force rises to), and the wall's
    peak where the stop check waits for the wall's contact (stop_after_wall) and it is not complete; [] when everything
    asked for is there. A run that ends too soon says so (the command
    line exits 1), not only in summary.json. An observable the scene can never measure
    (Observable.applies: a wave speed over a window of fewer than FIT_CONTACTS contacts) is not missed
    by the run: it is left out here, and the run's observables say why it is None."""
    if not scene.outputs.peak_force or scene.n_contacts == 0:
        return []
    m = registry.measure(scene, solution)
    asked = [name for name, obs in registry.OBSERVABLES.items() if obs.asked and obs.applies(scene) is None]
    lines = [f"{name}: {m.missing[name]}" for name in asked if m.values.get(name) is None]
    b = scene.window[1]
    # behind a load still acting at the end the force rises toward the load's level: a running maximum
    # that no longer run completes while the load acts, not a main wave still to come
    ld = scene.loading
    lasting = ld.is_force and ld.duration > solution.end_time
    if not lasting and still_rising(solution.complete, solution.time_of_peak, solution.velocity)[b - 1]:
        lines.append(f"peak_force_contact_{b}: {_why_still_rising(scene, solution, b)}")
    # a stop check that waits for the wall's contact ([run] stop_after_wall: the planner's, where the
    # wall's peak is asked for); a run that ended before its force fell back to half its peak missed it
    if scene.run.stop_after_wall and not lasting and solution.wall_peak_complete is False:
        lines.append(
            "wall_peak_force: the wave did not reach or pass the wall (its force falling to half its peak) "
            f"before the run ended at t = {solution.end_time:g} s"
        )
    return lines
