"""The largest force over the far-end wall's event at chosen contacts and sensor beads ([outputs]
event_max_contacts, event_max_sensors; issue 42 item 4).

A contact's peak (peak_force, max_peak_force) is its largest *complete* peak: a later, larger maximum
(a heavy striker's second push, the wave reflected from the wall, a rebounding chain) is missed by
definition. These are the largest dynamic force over the whole event (granchain.physics.event: from
the start until the chain has left the wall for good, or its first return on a held chain), tracked
at every step on both backends as the wall's largest force is (physics.event.EventMaxima), above each
contact's or sensor's own static force.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from granchain.postprocess.observables.base import Measurement
from granchain.postprocess.observables.event import _BAR, _EventObservable, _why_unended
from granchain.postprocess.observables.sensor import sensor_static_forces
from granchain.problem import scene_static_forces


class _EventMax(_EventObservable):
    """What the contacts' and the sensors' largest force over the event share: the largest of the
    chosen ones (the value), which one and its time, and every chosen one's (lists)."""

    error_bar = _BAR + "; the largest over the chosen ones is continuous in the runs even where which one changes"
    #: its [outputs] key, the ChainSolution fields of the maxima and their times, the companions' stem
    key: ClassVar[str]
    fields: ClassVar[tuple[str, str]]
    which: ClassVar[str]

    def chosen(self, scene) -> tuple[int, ...]:
        """The chosen contacts or beads (1-based)."""
        return getattr(scene.outputs, self.key)

    def static(self, scene) -> np.ndarray:
        """The chosen ones' static forces (N)."""
        raise NotImplementedError

    def applies(self, scene) -> str | None:
        """None on a walled chain asking for the event and for some contacts or sensors, else why not."""
        why = super().applies(scene)
        if why is None and not self.chosen(scene):
            why = f"not asked for: [outputs] {self.key} = [...] chooses where the largest force over the event is read"
        return why

    def measure(self, scene, solution) -> Measurement:
        """The largest dynamic force over the event at the chosen ones, which one, its time, and each one's."""
        if solution.event_end_time is None:
            return Measurement(None, dict.fromkeys(self.companions), _why_unended(scene, solution))
        force = np.asarray(getattr(solution, self.fields[0]), dtype=float)
        time = np.asarray(getattr(solution, self.fields[1]), dtype=float)
        chosen = self.chosen(scene)
        if force.size != len(chosen):
            why = f"the run did not track [outputs] {self.key} (a run made without it, or by an older granchain)"
            return Measurement(None, dict.fromkeys(self.companions), why)
        dynamic = force - self.static(scene)
        i = int(np.argmax(dynamic))
        names = list(self.companions)
        values = (int(chosen[i]), float(time[i]), [float(x) for x in dynamic], [float(x) for x in time])
        return Measurement(float(dynamic[i]), dict(zip(names, values, strict=True)))


class EventMaxContactForce(_EventMax):
    """The largest dynamic force over the event at the chosen contacts, which one and when."""

    name = "event_max_contact_force"
    unit = "N"
    definition = (
        "the largest force over the wall's event (above its static force; every step, parabola-refined) at the "
        "contacts of [outputs] event_max_contacts, at event_max_contact; each one's in event_contact_max_forces"
    )
    applies_where = "a chain on a far-end wall, with [outputs] event = true and event_max_contacts"
    key = "event_max_contacts"
    fields = ("event_contact_max_force", "event_contact_time_of_max")
    companions: ClassVar[dict[str, str]] = {
        "event_max_contact": "contact",
        "event_contact_time_of_max": "s",
        "event_contact_max_forces": "N",
        "event_contact_times_of_max": "s",
    }
    shares_reason = tuple(companions)
    table_fields = ("event_max_contact", "event_contact_time_of_max")
    field_kinds: ClassVar[dict[str, str]] = dict.fromkeys(
        ("event_contact_max_forces", "event_contact_times_of_max"), "numbers"
    )
    shown = True

    def static(self, scene) -> np.ndarray:
        """Each chosen contact's static force (F0 and, under gravity, the weight above it)."""
        return scene_static_forces(scene)[np.asarray(self.chosen(scene), dtype=int) - 1]


class EventMaxSensorForce(_EventMax):
    """The largest dynamic average force over the event at the chosen sensor beads, which one and when."""

    name = "event_max_sensor_force"
    unit = "N"
    definition = (
        "the largest sensor-bead force (F_{i-1,i} + F_{i,i+1}) / 2 over the wall's event (above its static force; "
        "every step, parabola-refined) at the beads of [outputs] event_max_sensors, at event_max_sensor; each "
        "one's in event_sensor_max_forces"
    )
    applies_where = "a chain on a far-end wall, with [outputs] event = true, sensors and event_max_sensors"
    key = "event_max_sensors"
    fields = ("event_sensor_max_force", "event_sensor_time_of_max")
    companions: ClassVar[dict[str, str]] = {
        "event_max_sensor": "bead",
        "event_sensor_time_of_max": "s",
        "event_sensor_max_forces": "N",
        "event_sensor_times_of_max": "s",
    }
    shares_reason = tuple(companions)
    table_fields = ("event_max_sensor", "event_sensor_time_of_max")
    field_kinds: ClassVar[dict[str, str]] = dict.fromkeys(
        ("event_sensor_max_forces", "event_sensor_times_of_max"), "numbers"
    )
    shown = True

    def static(self, scene) -> np.ndarray:
        """Each chosen sensor's static force (the average of its two contacts')."""
        sensors = list(scene.outputs.sensors)
        return sensor_static_forces(scene)[[sensors.index(b) for b in self.chosen(scene)]]
