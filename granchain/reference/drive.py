"""The energy ledger of a run under a harmonic drive: the drive's work, accumulated step by step
(a shaker's: its driver's, P = F_c0 v_d through its contact with bead 1).

A constant force's work is A times bead 1's displacement (reference.observers.EnergyLedger); a
force that changes in time has no such closed form, so the drive's work W = integral of f(t) v_1 dt
is summed by the trapezoidal rule over the steps' ends, W += (P(t_{k-1}) + P(t_k)) h_k / 2 with
P = f v_1, as the deck sums it (templates/loading_harmonic.lmp.j2): second order in the step, as
velocity Verlet is, and far inside the run watch's bound (granchain.invariants.ENERGY_WATCH).
"""

from __future__ import annotations

from typing_extensions import override

from granchain.physics.harmonic import drive_function
from granchain.reference.observers import EnergyLedger
from granchain.reference.state import ChainState


class DrivenEnergyLedger(EnergyLedger):
    """EnergyLedger with the drive's work summed every step (its rows still every energy_every steps)."""

    def __init__(self, state: ChainState, energy_every: int) -> None:
        super().__init__(state, energy_every)
        p = self.problem
        self.sample_every, self.every = energy_every, 1
        self.force = drive_function(p.amplitude, p.frequency, p.ramp_time)
        self.drive_work = 0.0
        self.power = 0.0  # f v_1 at the last step's end (0 at t = 0: f(0) = 0)
        if p.shaker:  # a shaker's driver: F_c0 v_d, F0 v_d(0) at t = 0
            self.power = float(state.fc[0]) * float(state.v[state.load_bead])
        self.t_last = 0.0

    @override
    def work(self, state: ChainState) -> float:
        return super().work(state) + self.drive_work

    @override
    def after_step(self, state: ChainState, t0: float, t1: float) -> bool:
        # (t0 is the step's last piece's start under RK4 event location: the step began at t_last)
        if t1 <= self.problem.duration:
            # a shaker's driver (bead 0) works through its contact: P = F_c0 v_d, F_c0 of the step's
            # last force evaluation (Verlet's at its end)
            f = float(state.fc[0]) if self.problem.shaker else self.force(t1)
            power = f * float(state.v[state.load_bead])
            self.drive_work += 0.5 * (self.power + power) * (t1 - self.t_last)
            self.power = power
        else:
            self.power = 0.0
        self.t_last = t1
        if state.step % self.sample_every == 0 and t1 < state.seg_end:  # a breakpoint takes its own row
            self.row(state, t1)
        return False


def energy_ledger(state: ChainState, energy_every: int) -> EnergyLedger:
    """The run's energy ledger: DrivenEnergyLedger under a harmonic drive, else EnergyLedger."""
    return (DrivenEnergyLedger if state.problem.driven else EnergyLedger)(state, energy_every)
