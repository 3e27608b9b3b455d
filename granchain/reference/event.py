"""The reference's event tracker: the far-end wall's event quantities at every step
(granchain.physics.event defines them; the LAMMPS plugin's fix chain/event does the same arithmetic
in the same order, so that the two agree step for step)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from typing_extensions import override

from granchain.physics.event import EventMaxima, EventSums, left_for_good
from granchain.postprocess.sensors import bead_average
from granchain.reference.observers import EarlyStop, Observer
from granchain.reference.state import ChainState


class EventTracker(Observer):
    """The wall's force and bead N's velocity after every step (the force at the step's end: the
    integrator's contact_forces), summed by physics.event.EventSums; an unloaded chain's end checked
    every `check_every` steps (as LAMMPS's fix halt checks), a held chain's after every step. With an
    early stop (the run's stop check), the run stops once the stop check and the event's end have
    both come: the early stop is asked at its own steps, after the event's check on the same step."""

    every = 1

    def __init__(
        self,
        state: ChainState,
        forces: Callable[[ChainState], np.ndarray],
        floor: float,
        check_every: int,
        early: EarlyStop | None = None,
        maxima: tuple = ((), ()),
    ) -> None:
        self.forces = forces
        # the chosen contacts and sensor beads (0-based, of the state's chain) whose largest force is tracked
        self.contacts, self.sensors = (np.asarray(x, dtype=int) for x in maxima)
        self.maxima = EventMaxima(np.zeros(self.contacts.size + self.sensors.size))
        self.check_every = check_every
        self.early = early
        self.floor = floor
        problem = state.problem
        # an unloaded chain's end is its free flight; a chain pressed on the wall has its first return
        self.held = bool(problem.precompression or problem.gravity)
        self.load_end = problem.duration if problem.amplitude else 0.0
        self.sums = EventSums(float(state.static_force[-1]), floor, 0.0, 0.0)

    @override
    def start(self, state: ChainState) -> None:
        # the t = 0 sample, once the integrator has its forces (the wall's contact is the state's last)
        f0 = float(self.forces(state)[-1])
        self.sums = EventSums(float(state.static_force[-1]), self.floor, f0, float(state.v[-2]))
        self.maxima = EventMaxima(self.chosen(state))

    def chosen(self, state: ChainState) -> np.ndarray:
        """The chosen contacts' forces, then the chosen sensor beads' average forces, now."""
        f = self.forces(state)
        return np.concatenate((f[self.contacts], bead_average(f)[self.sensors]))

    @override
    def after_step(self, state: ChainState, t0: float, t1: float) -> bool:
        sums = self.sums
        if not sums.ended:
            sums.add(t1, float(self.forces(state)[-1]), float(state.v[-2]))
            if self.maxima.fmax.size:
                self.maxima.add(t1, self.chosen(state))
            if self.held:
                sums.cross(float(state.v[-2]), lambda: float(np.dot(state.mass_ke, state.v)))
            elif state.step % self.check_every == 0:
                sums.check(t1, self.free(state, t1))
        if self.early is None or state.step % self.early.every:
            return False
        # as the deck's stop variable: the stop check's test at this step, and the event's end (latched)
        return self.early.after_step(state, t0, t1) and sums.ended

    def free(self, state: ChainState, t: float) -> bool:
        """Whether an unloaded chain has left the wall for good at t (the load over, physics.event's
        left_for_good)."""
        if t < self.load_end:
            return False
        stored = float(np.sum(state.law.energy(state.overlap(), state.alpha_hist)))
        return left_for_good(state.v[:-1], state.mass_ke[:-1], self.forces(state), stored)

    @override
    def finish(self, state: ChainState) -> dict[str, Any]:
        k, m = self.contacts.size, self.maxima
        return {
            **self.sums.fields(),
            "event_contact_max_force": m.fmax[:k].copy(),
            "event_contact_time_of_max": m.tmax[:k].copy(),
            "event_sensor_max_force": m.fmax[k:].copy(),
            "event_sensor_time_of_max": m.tmax[k:].copy(),
        }
