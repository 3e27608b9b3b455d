"""The largest complete peak of any pulse over the measured contacts, and its contact."""

from __future__ import annotations

import numpy as np

from granchain.postprocess.observables.base import Measurement, Observable
from granchain.problem import scene_static_forces


class MaxPeakForce(Observable):
    """The largest complete peak (granchain.peaks.complete_peaks: the force has fallen to half of it
    since), above the static force, and its contact."""

    name = "max_peak_force"
    unit = "N"
    definition = "the largest complete peak of any pulse (above F0), at max_peak_contact"
    needs = frozenset({"peaks"})
    companions = {"max_peak_contact": "contact"}
    shares_reason = ("max_peak_contact",)
    contact_field = "max_peak_contact"
    shown = True
    error_bar = (
        "the time step's error from the companion runs (the largest over contacts is continuous in them, "
        "even where its contact changes), above the round-off of its contact"
    )

    def measure(self, scene, solution) -> Measurement:
        """The largest complete peak and its contact, or None where no contact has one."""
        complete = np.asarray(solution.complete, dtype=bool)
        if not complete.any():
            why = "no contact has a complete peak before the end of the run"
            return Measurement(None, {"max_peak_contact": None}, why)
        # the largest dynamic force, each contact's own static force taken off (under gravity it
        # grows with depth; under precompression alone it is F0 everywhere)
        static = scene_static_forces(scene)[: complete.size]
        dynamic = np.asarray(solution.peak_force, dtype=float) - static
        i = int(np.argmax(np.where(complete, dynamic, -np.inf)))
        return Measurement(float(dynamic[i]), {"max_peak_contact": i + 1})

    def roundoff_floor(self, measured: dict, floor: np.ndarray, b: int) -> float | None:
        """Its contact's round-off."""
        contact = measured.get("max_peak_contact")
        return None if contact is None else float(floor[int(contact) - 1])
