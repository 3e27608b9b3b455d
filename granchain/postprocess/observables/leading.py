"""The leading pulse at the window's last contact, in N and as F / (E* R*^2) (Eq. 5).

The leading pulse is a contact's first maximum, not its largest (granchain.peaks.leading_pulse): in a
forming wave train or behind a front that rises to a plateau, the largest pulse, and the time it
passes, jump between oscillations as the time step changes; the first does not (docs/observables.md).
"""

from __future__ import annotations

import numpy as np

from granchain.peaks import LEAD_FRACTION, lead_fall, lead_floor, position_resolution
from granchain.postprocess.observables.base import Measurement, Observable
from granchain.problem import scene_static_forces

#: the leading peak's error bar (LeadingPeakForce, LeadingPeakForceNondim)
_BAR = (
    "the time step's error from the companion runs at 2 dt and 4 dt, their leading pulse the run's (its time "
    "checked), above the round-off of its contact"
)


def _leading_pulse(scene, solution) -> float:
    """The window's last contact's leading pulse above its static force (N; nan where it has none):
    under precompression every contact carries F0 at rest, under gravity also the weight above it."""
    i = scene.window[1] - 1
    return float(np.asarray(solution.leading_pulse_force, dtype=float)[i]) - float(scene_static_forces(scene)[i])


def _why_no_leading_pulse(scene, solution, contact: int) -> str:
    """Why a 1-based contact has no leading pulse."""
    t = float(solution.time_of_peak[contact - 1])
    if not np.isfinite(t):
        return f"contact {contact} was not reached by the wave before the end of the run (t = {solution.end_time:g} s)"
    fall = lead_fall(scene)
    then = f" that it then fell {fall:.3g} N below (the same resolution, peaks.lead_fall)" if fall else ""
    return (
        f"contact {contact} has no leading pulse yet: its force has not had a maximum rising more than "
        f"{lead_floor(scene):.3g} N above the static force{then} ({_floor_reason(scene)}; peak so far "
        f"{float(solution.peak_force[contact - 1]):.6g} N at t = {t:g} s, run ends at t = {solution.end_time:g} s); "
        "run longer"
    )


def _floor_reason(scene) -> str:
    """What sets the leading pulse's floor (peaks.lead_floor)."""
    if scene.effects.precompression and position_resolution(scene) >= lead_floor(scene):
        return "the force LAMMPS resolves under precompression, peaks.position_resolution"
    return f"{LEAD_FRACTION:g} of the largest expected force"


class LeadingPeakForce(Observable):
    """The leading pulse at the window's last contact (the wave has formed there and has not yet met
    the far end), above the static force."""

    name = "leading_peak_force"
    unit = "N"
    definition = "the leading pulse (first maximum, above F0) at the window's last contact"
    needs = frozenset({"leading_pulses", "peaks"})
    contact_field = "leading_peak_contact"
    shown = True
    asked = True
    error_bar = _BAR
    at_leading_pulse = True

    def measure(self, scene, solution) -> Measurement:
        """The leading pulse, or None and why the window's last contact has none yet."""
        force = _leading_pulse(scene, solution)
        if np.isfinite(force):
            return Measurement(force, {})
        return Measurement(None, {}, _why_no_leading_pulse(scene, solution, scene.window[1]))

    def roundoff_floor(self, measured: dict, floor: np.ndarray, b: int) -> float | None:
        """Its contact's round-off."""
        return float(floor[b]) if b < floor.size else None


class LeadingPeakForceNondim(LeadingPeakForce):
    """The leading peak force as F / (E* R*^2) of that contact's own pair (Eq. 5): on a chain whose beads
    differ, not bead 1's."""

    name = "leading_peak_force_nondim"
    unit = "1"
    definition = "leading_peak_force / (E* R*^2) of that contact's own two beads (Eq. 5)"
    shown = False
    asked = False

    def measure(self, scene, solution) -> Measurement:
        """The nondimensional leading pulse, or None and the leading pulse's reason."""
        m = super().measure(scene, solution)
        if m.value is None:
            return m
        return Measurement(m.value / float(scene.contact_force_scales[scene.window[1] - 1]), {})

    def roundoff_floor(self, measured: dict, floor: np.ndarray, b: int) -> float | None:
        """Its contact's round-off, scaled as the force is."""
        fl = super().roundoff_floor(measured, floor, b)
        if fl is None:
            return None
        force, nondim = measured.get("leading_peak_force"), measured.get(self.name)
        return fl * float(nondim) / float(force) if force and nondim is not None else np.nan
