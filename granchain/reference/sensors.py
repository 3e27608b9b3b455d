"""The reference solver's sensor beads (postprocess.sensors): each sensor's average force tracked at
every step as the pair styles track it, and recorded at the contact histories' steps."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from typing_extensions import override

from granchain.postprocess.sensors import bead_average
from granchain.reference.observers import ForceSamplePeaks, Recorder
from granchain.reference.state import ChainState


class SensorPeaks(ForceSamplePeaks):
    """The running peak of each sensor bead's average force (F_left + F_right) / 2 (its contacts' in
    the state's chain: a striker's and a wall's included, a missing one 0), as ForceSamplePeaks tracks
    a contact's: step-end samples refined by the parabola through three (RK4 too, on its step ends)."""

    def __init__(self, state: ChainState, forces: Callable[[ChainState], np.ndarray], beads) -> None:
        self.forces, self.beads = forces, np.asarray(beads, dtype=int)  # 0-based beads of the state's chain
        super().__init__(state)

    @override
    def _samples(self, state: ChainState) -> np.ndarray:
        return bead_average(self.forces(state))[self.beads]

    @override
    def finish(self, state: ChainState) -> dict[str, Any]:
        return {
            "sensor_peak_force": self.fpk.copy(),
            "sensor_time_of_peak": self.tpk.copy(),
            "sensor_force_min_after_peak": self.fmin.copy(),
        }


class SensorHistory(Recorder):
    """Each sensor bead's average force every history_stride steps from t = 0 (the contact histories'
    rows)."""

    def __init__(self, state: ChainState, forces: Callable[[ChainState], np.ndarray], beads, stride: int, total: int):
        super().__init__(state, lambda s: bead_average(forces(s)), beads, stride, (), total)

    @override
    def finish(self, state: ChainState) -> dict[str, Any]:
        return {
            "sensor_history_time": self.h_t[: self.rows].copy(),
            "sensor_history_force": self.h_f[: self.rows].copy(),
        }


def sensor_observers(state: ChainState, forces, beads, stride: int, total: int) -> list:
    """The observers of sensor beads (0-based beads of the state's chain; none without): their peaks,
    and their histories every stride steps (stride 0: none, as a companion run's)."""
    if not len(beads):
        return []
    history = [SensorHistory(state, forces, beads, stride, total)] if stride > 0 else []
    return [SensorPeaks(state, forces, beads), *history]
