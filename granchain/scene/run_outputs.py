"""The scene's [run] and [outputs] sections as frozen dataclasses (granchain.scene.model re-exports
them with the rest of the scene's model)."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

__all__ = ["Outputs", "Run", "stop_fields"]


@dataclass(frozen=True)
class Run:
    """The [run] section: end time and time step (None where the planner chooses), and an early stop.

    Attributes
    ----------
    end_time : float or None
        The simulated time in s; None: "auto".
    timestep : float or None
        The time step dt in s; None: "auto".
    stop_after_contact : int or None
        The stop check: stop once the leading wave has passed this contact (1-based), or None.
    stop_after_wall : bool
        The stop check also waits for the wall's contact (bead N on the flat) to pass: its force back
        below half its peak after the reflection (only on a chain with a wall).
    stop_after_reflection : bool
        The stop check also waits for the wall's reflection to pass back through contact 1: after the
        wall's contact has passed, contact 1's force rose above the stop floor and fell back below half
        of its largest since (only with stop_after_wall). Then every contact's peak has seen the
        reflection (peaks.reflection_pending).
    """

    end_time: float | None  # s; None: "auto"
    timestep: float | None  # s; None: "auto"
    stop_after_contact: int | None = None  # stop once the leading wave has passed this contact
    stop_after_wall: bool = False  # ... and the wall's contact (a walled chain)
    stop_after_reflection: bool = False  # ... and the wall's reflection back through contact 1

    def stop_check(self) -> dict:
        """The stop check's fields (every field but end_time and timestep) that differ from "no stop".

        Returns
        -------
        dict
            Field name -> value, as [run] writes them: what a run rebuilt from this one (another
            time step, another end) carries over so that it stops where this one does.
        """
        return {f.name: getattr(self, f.name) for f in stop_fields() if getattr(self, f.name) != f.default}

    def without_stop(self) -> Run:
        """The run without a stop check: it lasts to its end time."""
        return replace(self, **{f.name: f.default for f in stop_fields()})


def stop_fields() -> tuple:
    """The dataclass fields of Run that make up its stop check: all but end_time and timestep."""
    return tuple(f for f in fields(Run) if f.name not in ("end_time", "timestep"))


@dataclass(frozen=True)
class Outputs:
    """The [outputs] section: which contacts' peaks and histories are kept, snapshots, the window.

    Attributes
    ----------
    peak_force : bool or tuple of int
        True: every contact's peak force; False: none; or the contacts (1-based) to tabulate.
    histories : tuple of int
        Contacts whose force (and bead velocity) against time is kept.
    snapshots : tuple of float
        Times in s of force and velocity profiles along the chain.
    window : tuple of int or None
        The first and last contact of the window, or None for the default (``Scene.window``).
    history_interval : float, str or None
        s between history samples, "auto" (the default with histories) or None.
    dump_interval : float, str or None
        s between whole-chain LAMMPS dump frames, "auto", or None (the default: no dump).
    event : bool
        The event quantities of the far-end wall (its largest force, impulse and energy over the
        event, granchain.physics.event) are tracked, and a stop check also waits for the event's end.
    sensors : tuple of int
        Sensor beads (1-based): each reports its average force (F_{i-1,i} + F_{i,i+1}) / 2, the reading
        of a piezo embedded in the bead (docs/observables.md, "Sensor beads").
    event_max_contacts, event_max_sensors : tuple of int
        Contacts (1-based) and sensor beads (of ``sensors``) whose largest dynamic force over the far-end
        wall's event, and its time, is tracked at every step (granchain.physics.event.EventMaxima; the
        observables event_max_contact_force and event_max_sensor_force).
    """

    peak_force: bool | tuple[int, ...] = True  # True: every contact; or a tuple of contacts
    histories: tuple[int, ...] = ()  # contacts whose force (and bead velocity) vs time is kept
    snapshots: tuple[float, ...] = ()  # times of force/velocity profiles along the chain
    window: tuple[int, int] | None = None  # contacts used for leading peak and wave speed
    history_interval: float | str | None = None  # s between history samples ("auto", the default with histories)
    dump_interval: float | str | None = None  # s between whole-chain LAMMPS dump frames (default: none; "auto")
    event: bool = False  # the wall's event quantities tracked; a stop check waits for the event's end
    sensors: tuple[int, ...] = ()  # sensor beads (1-based): their average force (F_{i-1,i} + F_{i,i+1}) / 2
    event_max_contacts: tuple[int, ...] = ()  # contacts (1-based) whose largest force over the event is tracked
    event_max_sensors: tuple[int, ...] = ()  # sensor beads (of sensors) whose largest force over the event is tracked
