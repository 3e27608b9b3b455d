"""Sensor beads ([outputs] sensors): what a piezo embedded in a bead reads, in one place for both
backends, and how the outputs report it: per sensor bead, its peak and its time, named by the
registry's sensor observables (observables.SENSOR_OBSERVABLES) and the bead (sensor_key), in
summary.json's ``sensors``, ``granchain compare``'s rows, the campaign table's columns, the error
bars, the plots and docs/observables.md ("Sensor beads"; tests/test_sensors.py checks that every one
of those places has every quantity).

A sensor bead's force is its average force (F_{i-1,i} + F_{i,i+1}) / 2; its peak is its largest
complete peak (the force has fallen to half of it since: granchain.peaks.complete_peaks) above its own
static force (its two contacts' static forces' average: precompression's F0, gravity's weight above
it), as a contact's peak is measured above its own, and its time that peak's, the sensor's arrival.

Experiments read a bead's average force with a piezo embedded in it (Daraio et al., PRE 72, 016603,
2005 and PRE 73, 026610, 2006; Job et al., PRL 94, 178002, 2005). A sensor bead's two contacts are
its contacts with its neighbours; bead 1's left one is a striker's contact (under a velocity loading
nothing touches bead 1 after t = 0: 0), bead N's right one the wall's (a free end: 0). An applied
force is not a contact: a force loading's on bead 1 is refused (granchain.scene.reader), and the
static forces of a precompression (the push on bead 1, a free end's pull on bead N) are constant, so
the sensor's dynamic force, its rise above its own static force, is the same either way. Both
backends track each sensor's running peak at every step as they track a contact's (the parabola
through three samples, the smallest force since the peak): LAMMPS in the pair styles (pair_style ...
sensors), the reference in reference.sensors.
"""

from __future__ import annotations

import numpy as np

from granchain.peaks import REACHED_FRACTION, complete_peaks
from granchain.physics.effects.gravity import scene_static_forces
from granchain.postprocess.observables.registry import SENSOR_OBSERVABLES
from granchain.postprocess.observables.sensor import sensor_static_forces

#: the note summary.json's ``sensors`` carries: what a sensor reads at the chain's ends
SENSOR_NOTE = (
    "a sensor bead reads (F_left + F_right) / 2 of its two contacts: bead 1's left one is a striker's "
    "contact (a velocity loading: nothing, 0), bead N's right one the wall's (a free end: 0); forces are "
    "dynamic, above the sensor's static average force"
)


def sensor_key(quantity: str, bead: int) -> str:
    """The name of one sensor bead's quantity (a registered sensor observable's, SENSOR_OBSERVABLES), as
    a compare row and a column."""
    return SENSOR_OBSERVABLES[quantity].key(bead)


def sensor_keys(scene) -> tuple[str, ...]:
    """Every sensor quantity's key of the scene's sensor beads, bead by bead."""
    return tuple(sensor_key(q, b) for b in scene.outputs.sensors for q in SENSOR_OBSERVABLES)


def sensor_values(scene, solution) -> tuple[dict, dict]:
    """Each sensor bead's quantities (sensor_key -> value; None where its peak is not complete) and
    why each None is (key -> reason)."""
    values: dict = {}
    missing: dict = {}
    if not scene.outputs.sensors or not np.size(solution.sensor_peak_force):
        why = "not tracked by this run's backend" if scene.outputs.sensors else None
        for key in sensor_keys(scene):
            values[key], missing[key] = None, why
        return values, missing
    dynamic = np.asarray(solution.sensor_peak_force, dtype=float) - sensor_static_forces(scene)
    ended = f"before the run ended at t = {solution.end_time:g} s"
    for k, bead in enumerate(scene.outputs.sensors):
        force, time = sensor_key("sensor_peak_force", bead), sensor_key("sensor_time_of_peak", bead)
        if bool(solution.sensor_complete[k]):
            values[force], values[time] = float(dynamic[k]), float(solution.sensor_time_of_peak[k])
            continue
        reached = np.isfinite(solution.sensor_time_of_peak[k])
        why = (
            f"the peak at sensor bead {bead} is not complete (its force had not fallen to half of it, or the "
            f"wall's reflection may still exceed it) {ended}"
            if reached
            else f"the wave did not reach sensor bead {bead} {ended}"
        )
        values[force] = values[time] = None
        missing[force] = missing[time] = why
    return values, missing


def sensor_summary(scene, solution) -> dict:
    """summary.json's ``sensors``: the beads, their static force, each quantity's values (bead by bead,
    None where unmeasured), why each None is, and the note on what a sensor reads."""
    values, missing = sensor_values(scene, solution)
    beads = list(scene.outputs.sensors)
    return {
        "beads": beads,
        "static_force": [float(x) for x in sensor_static_forces(scene)],
        **{q: [values[sensor_key(q, b)] for b in beads] for q in SENSOR_OBSERVABLES},
        "missing": missing,
        "note": SENSOR_NOTE,
    }


def bead_average(contact_force: np.ndarray) -> np.ndarray:
    """Every bead's average of its two contacts' forces, (F_left + F_right) / 2, a missing contact 0.

    contact_force: (..., N-1) forces of consecutive contacts (along the last axis); returns (..., N).
    """
    f = np.asarray(contact_force, dtype=float)
    pad = [(0, 0)] * (f.ndim - 1) + [(1, 1)]
    padded = np.pad(f, pad)
    # 0.5 F is exact (a power of two), so 0.5 F_l + 0.5 F_r is 0.5 (F_l + F_r) to the bit, as the
    # pair styles sum it
    return 0.5 * padded[..., :-1] + 0.5 * padded[..., 1:]


def finish_sensors(scene, solution) -> None:
    """Judge a backend's sensor peaks by the contacts' rules (granchain.peaks), in place: the time nan
    where a sensor was not reached (its rise above its static force at most REACHED_FRACTION of the
    largest rise of any contact or sensor), complete where its force fell to PEAK_PASSED_FRACTION of
    its rise since its peak (complete_peaks).

    Parameters
    ----------
    scene : Scene
        The scene that ran ([outputs] sensors).
    solution : ChainSolution
        Its result, with the backend's sensor_peak_force, sensor_time_of_peak (the running peak's) and
        sensor_force_min_after_peak (S,); sets sensor_beads, sensor_time_of_peak and sensor_complete.
    """
    static = sensor_static_forces(scene)
    peak = np.asarray(solution.sensor_peak_force, dtype=float)
    rise = peak - static
    contacts = np.asarray(solution.peak_force, dtype=float) - scene_static_forces(scene)[: np.size(solution.peak_force)]
    largest = max(float(np.max(contacts[np.isfinite(contacts)], initial=0.0)), float(np.max(rise, initial=0.0)))
    time = np.where(rise > REACHED_FRACTION * largest, np.asarray(solution.sensor_time_of_peak, dtype=float), np.nan)
    solution.sensor_beads = tuple(int(b) for b in scene.outputs.sensors)
    solution.sensor_time_of_peak = time
    solution.sensor_complete = complete_peaks(peak, solution.sensor_force_min_after_peak, time, static)


def solution_sensor_fields(scene, sensors: dict | None) -> dict:
    """The solution's sensor fields of a run read back from summary.json's ``sensors`` (sensor_summary):
    each measured peak with its static force again (the solution holds the total), complete where it
    was measured; {} without sensors, or where the entry is not the scene's (a damaged file's), and a
    value that is not a number as unmeasured."""
    if (
        not scene.outputs.sensors
        or not isinstance(sensors, dict)
        or sensors.get("beads") != list(scene.outputs.sensors)
    ):
        return {}
    beads = tuple(scene.outputs.sensors)

    def numbers(key: str) -> np.ndarray:
        v = sensors.get(key)
        v = v if isinstance(v, list) and len(v) == len(beads) else [None] * len(beads)
        return np.array([float(x) if isinstance(x, (int, float)) and not isinstance(x, bool) else np.nan for x in v])

    dynamic = numbers("sensor_peak_force")
    return {
        "sensor_beads": beads,
        "sensor_peak_force": dynamic + sensor_static_forces(scene),
        "sensor_time_of_peak": numbers("sensor_time_of_peak"),
        "sensor_force_min_after_peak": np.full(len(beads), np.nan),
        "sensor_complete": np.isfinite(dynamic),
    }
