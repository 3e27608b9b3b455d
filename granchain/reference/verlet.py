"""Velocity Verlet as LAMMPS's fix nve runs it (granchain.reference.integrators has the overview)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from granchain.reference.state import ChainState
from granchain.reference.stepping import Integrator, SplitHook, _add, _multiply, _subtract


class VerletIntegrator(Integrator):
    """Velocity Verlet as LAMMPS's fix nve runs it: half kick, drift, force, half kick."""

    name = "verlet"

    def __init__(self, state: ChainState) -> None:
        self.history = state.law.history
        self.load_bead = state.load_bead  # where the external load acts (a_ext): bead 1
        self.kick = np.empty(state.n)  # h/2 a and h v, into a preallocated buffer
        self.alpha = np.empty(state.n - 1)  # the overlaps at the step's end (the history)
        self.u_left, self.u_right = state.u[:-1], state.u[1:]
        self.consts: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def start_segment(self, state: ChainState, seg_start: float) -> bool:
        """Start a LAMMPS run at seg_start (the damping's forces again at full-step velocities, as LAMMPS)."""
        if state.damped and seg_start > 0.0:
            # LAMMPS starts each run by recomputing forces with the full-step velocities; damping
            # is the only force that notices, and the reference does the same to stay step for step
            state.accel(state.u, state.a_int, state.v)
            return True
        return False

    def step(
        self, state: ChainState, t0: float, t1: float, h: float, a_ext: float, on_split: Sequence[SplitHook]
    ) -> float:
        """Advance the state from t0 by one velocity Verlet step h (to t1); returns t0."""
        u, v, a_int, kick = state.u, state.v, state.a_int, self.kick
        half = 0.5 * h
        consts = self.consts.get(h)
        if consts is None:  # the plan's step and a segment's last: 0-d arrays, cheaper operands than floats
            consts = self.consts[h] = (np.array(half), np.array(h))
        half_h, h_ = consts
        add, mul = _add, _multiply  # outputs by position (RK4Integrator.rk4)
        mul(a_int, half_h, kick)
        add(v, kick, v)
        drive = self.drive  # a harmonic drive: the force at each half-kick's time, as LAMMPS's addforce
        if drive is not None:
            v[self.load_bead] += half * (a_ext + drive(t0))
        elif a_ext:  # (x + 0.0 is x: an unloaded segment skips it)
            v[self.load_bead] += half * a_ext
        mul(v, h_, kick)
        add(u, kick, u)
        power = state.accel(u, a_int, v)  # damping sees the half-step velocity, as in LAMMPS
        if power:
            state.damping_energy += h * power
        mul(a_int, half_h, kick)
        add(v, kick, v)
        if drive is not None:
            v[self.load_bead] += half * (a_ext + drive(t1))
        elif a_ext:
            v[self.load_bead] += half * a_ext
        if self.history:
            _subtract(self.u_left, self.u_right, self.alpha)
            state.law.update_history(state.alpha_hist, self.alpha)
        return t0

    def contact_forces(self, state: ChainState) -> np.ndarray:
        """Each contact's force from the last force evaluation (at this step's end, what LAMMPS dumps)."""
        return state.fc.copy()  # the last force evaluation, at this step's end: what LAMMPS dumps
