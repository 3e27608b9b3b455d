"""A sensor bead's quantities ([outputs] sensors = [i, ...]; issue 42 item 3): its peak and that
peak's time, registered observables read bead by bead (registry.SENSOR_OBSERVABLES).

Unlike a scalar observable (registry.OBSERVABLES) each is one number per chosen sensor bead, named by
key(bead) (``sensor_peak_force_bead_3``): summary.json writes them under ``sensors``, bead by bead
(postprocess.sensors.sensor_summary), not in ``observables``, and the campaign table's columns,
``granchain compare``'s rows, ``granchain run``'s lines and summary.json's check read them from the
registry. What a sensor bead reads, and how its peak is measured on both backends, is
postprocess.sensors'.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from granchain.physics.effects.gravity import scene_static_forces
from granchain.postprocess.observables.base import Observable


class SensorObservable(Observable):
    """One quantity of every sensor bead: its name (the stem of each bead's key), unit, definition, what
    it reads (the sensors' tracked running peaks), where it applies (a scene with sensors) and its bar."""

    needs = frozenset({"peaks"})
    per_bead: ClassVar[bool] = True
    applies_where = "a chain with [outputs] sensors = [i, ...], bead by bead"
    error_bar = "the time step's error from the companion runs at 2 dt and 4 dt, bead by bead, as a contact's peak"

    def applies(self, scene) -> str | None:
        """None on a scene with sensor beads, else why not."""
        if not scene.outputs.sensors:
            return "not asked for: [outputs] sensors = [i, ...] chooses the sensor beads"
        return None

    def key(self, bead: int) -> str:
        """The name of one sensor bead's value: a compare row, a campaign column, an error bar's key."""
        return f"{self.name}_bead_{int(bead)}"


class SensorPeakForce(SensorObservable):
    """A sensor bead's largest complete peak of its average force, above its static average force."""

    name = "sensor_peak_force"
    unit = "N"
    definition = (
        "the sensor bead's largest complete peak of its average force (F_{i-1,i} + F_{i,i+1}) / 2, above "
        "its static average force (a striker's and a wall's contact count; a missing contact is 0)"
    )


class SensorTimeOfPeak(SensorObservable):
    """The time of a sensor bead's peak: the sensor's arrival."""

    name = "sensor_time_of_peak"
    unit = "s"
    definition = "the time of that peak: the sensor's arrival"


def sensor_static_forces(scene) -> np.ndarray:
    """Each sensor bead's force at rest, N: the average of its two contacts' static forces.

    Parameters
    ----------
    scene : Scene
        The scene ([outputs] sensors, 1-based beads).

    Returns
    -------
    ndarray
        (S,): (F_static(left) + F_static(right)) / 2, a striker's contact (unloaded at t = 0) and a
        missing contact counting 0, a wall's its static force (F0 plus the chain's weight).
    """
    n = scene.chain.beads
    static = scene_static_forces(scene)  # the N-1 bead-bead contacts, then the wall's (with a wall)
    padded = np.concatenate(([0.0], static[: n - 1], [static[n - 1] if static.size >= n else 0.0]))
    beads = np.asarray(scene.outputs.sensors, dtype=int)
    return 0.5 * (padded[beads - 1] + padded[beads])
