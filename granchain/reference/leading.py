"""The leading pulse in the reference solver (granchain.peaks.leading_pulse; the pair styles' d_flead,
d_tlead): an observer of the peak tracker's maxima (granchain.reference.observers), which also owns the
precompressed chain's crossing-time ladder (granchain.reference.ladder) and stops it at the freeze.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from typing_extensions import override

from granchain.postprocess.fronts import front_times
from granchain.reference.ladder import CrossingLadder
from granchain.reference.observers import Observer, PeakTracker
from granchain.reference.state import ChainState

#: up to this many contacts at a maximum, the leading pulse looks at them on Python values first
_SCALAR_CONTACTS = 16


class LeadingPulse(Observer):
    """The leading pulse (peaks.leading_pulse): the first maximum of each contact's force that rises
    more than lead_floor above F0 and below which the force then falls by lead_fall before it rises
    above it, frozen from then on (the pair styles' d_flead, d_tlead with 'fall R').

    It listens to the peak tracker, which finds the maxima; at a contact's first maximum the running
    peak is that maximum (before it the force only rose; a maximum at a split step's end is the
    running peak already). With lead_fall = 0 that maximum is frozen at once (the force is at most its
    running peak). Else it is the candidate, and the candidate is the running peak from then on (a
    later rise above it moves it on): it is frozen at the first sample (a step's or piece's end, a
    LAMMPS run's setup) whose force is at most the running peak less lead_fall. Round-off on a slow
    rise (LAMMPS's position resolution, peaks.position_resolution) makes maxima that fall by less.
    """

    def __init__(self, state: ChainState, peaks: PeakTracker, lead_floor: float, lead_fall: float = 0.0) -> None:
        self.peaks = peaks
        self.f0 = state.f0
        self.lead_floor = lead_floor
        self.lead_fall = lead_fall
        self.force = np.full(state.n - 1, np.nan)
        self.time = np.full(state.n - 1, np.nan)
        self.done = np.zeros(state.n - 1, dtype=bool)  # a candidate seen (frozen, or waiting for the fall)
        self.waiting = np.empty(0, dtype=np.intp)  # the contacts whose candidate waits for the fall
        # the fall is checked at every sample while a candidate waits (never without a fall to wait for)
        self.every = 1 if lead_fall > 0.0 else 0
        # a precompressed chain's crossing-time ladder (its wave speed reads the fronts' arrivals off
        # it), as the pair styles: its rungs are multiples of the floor, none without one; it climbs
        # until the leading pulse freezes
        self.ladder = CrossingLadder(state, lead_floor) if lead_floor > 0.0 and state.problem.precompression else None
        peaks.ladder = self.ladder
        peaks.listeners.append(self.at_maximum)

    def at_maximum(self, state: ChainState, ix: np.ndarray) -> None:
        """Contacts ix are at a local maximum: the first that rises far enough above F0 is the candidate."""
        done = self.done
        if ix.size <= _SCALAR_CONTACTS and all(done.item(i) for i in ix.tolist()):
            return  # (mostly: a handful of contacts, each past its first maximum long ago)
        first = ~done[ix]
        if not first.any():
            return
        j = ix[first]
        force, time = self.peaks.peak_at(state, j)
        now = force - self.f0 > self.lead_floor
        if now.any():
            k = j[now]
            self.done[k] = True
            if self.lead_fall > 0.0:
                self.waiting = np.concatenate([self.waiting, k])
                self.check_fall(state)
                return
            self.freeze(k, force[now], time[now])

    def freeze(self, k: np.ndarray, force: np.ndarray, time: np.ndarray) -> None:
        """Contacts k's leading pulses are force at time: frozen, their ladders stop."""
        self.force[k], self.time[k] = force, time
        if self.ladder is not None:
            self.ladder.freeze(k)

    def check_fall(self, state: ChainState) -> None:
        """Freeze the waiting candidates the force has fallen lead_fall below (their running peaks)."""
        k = self.waiting
        now, peak, time = self.peaks.now_and_peaks(state, k)
        fell = now <= peak - self.lead_fall
        if fell.any():
            self.freeze(k[fell], peak[fell], time[fell])
            self.waiting = k[~fell]

    @override
    def after_step(self, state: ChainState, t0: float, t1: float) -> bool:
        if self.waiting.size:
            self.check_fall(state)
        return False

    @override
    def after_split(self, state: ChainState, t0: float, t1: float) -> None:
        if self.waiting.size:
            self.check_fall(state)

    @override
    def after_setup(self, state: ChainState) -> None:
        if self.waiting.size:
            self.check_fall(state)

    @override
    def finish(self, state: ChainState) -> dict[str, Any]:
        reached = np.isfinite(self.peaks.time_of_peak)  # the peak tracker finished first
        force = np.where(reached, self.force, np.nan)
        # the chain's own contacts: the solver reports the leading pulse of those only (solve_chain
        # slices the fields it knows; the ladder it does not): behind a striker's contact in front
        # (problem.front) and before a wall's (an immovable last bead)
        chain = slice(state.problem.first_bead, state.n - 1 - (0 if state.free_end else 1))
        out = {"leading_pulse_force": force, "leading_pulse_time": np.where(reached, self.time, np.nan)}
        if self.ladder is not None:
            rows = self.ladder.rows()[chain]
            out["front_ladder"] = rows
            out["front_time"] = front_times(rows, force[chain], self.f0, self.lead_floor)
        return out
