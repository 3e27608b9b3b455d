"""The tables of a run: peaks.csv's columns and units, the observables' units."""

from __future__ import annotations

import numpy as np

from granchain.physics.effects.gravity import scene_static_forces
from granchain.postprocess.observables import shown_keys, units

#: units of peaks.csv's columns (RunResult.peaks' attrs["units"]); "1": dimensionless
PEAK_UNITS = {
    "contact": "1",
    "peak_force": "N",
    "time_of_peak": "s",
    # peak_force / (E* R*^2) of the contact's own pair (Scene.contact_force_scales), Eq. 5: the total force, F0
    # included on a precompressed chain (dynamic_peak_force is F - F0)
    "peak_force_nondim": "1",
    "complete": "bool",
    "leading_pulse_force": "N",
    "arrival_time": "s",
    "dynamic_peak_force": "N",  # precompressed chains: peak_force - F0
    "dynamic_leading_pulse_force": "N",
    "front_time": "s",  # precompressed chains: the half-amplitude arrival (postprocess.fronts)
    "peak_force_error": "N",
    "time_of_peak_error": "s",
    "error_status": "text",
}

#: units of the observables of summary.json ("1": dimensionless), the registry's
#: (granchain.postprocess.observables.units) as it was when this module was imported
OBSERVABLE_UNITS = units()


def _key_observables(summary: dict):
    """(name, value, unit, error or None) of the shown observables (the registry's shown_keys) that the
    summary has."""
    obs = summary.get("observables") or {}
    errs = (summary.get("errors") or {}).get("observables") or {}
    unit = units()
    for name in shown_keys():
        if name in obs:
            e = errs.get(name) or {}
            err = e.get("error") if obs[name] is not None else None
            yield name, obs[name], unit.get(name, ""), err


def _num(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def peak_columns(result) -> dict[str, np.ndarray]:
    """peaks.csv's columns of a result: name -> array over the measured contacts (contact 1-based;
    complete bool; with error estimates peak_force_error, time_of_peak_error, error_status)."""
    sc, s = result.scene, result.solution
    contacts = np.asarray(sc.peak_contacts, dtype=int)
    idx = contacts - 1
    cols = {
        "contact": contacts,
        "peak_force": s.peak_force[idx],
        "time_of_peak": s.time_of_peak[idx],
        "peak_force_nondim": s.peak_force[idx] / sc.contact_force_scales[idx],  # each contact's E* R*^2
        "complete": s.complete[idx],
        "leading_pulse_force": s.leading_pulse_force[idx],
        "arrival_time": s.leading_pulse_time[idx],
    }
    f0 = float(sc.effects.precompression)
    if f0 or sc.effects.gravity:  # a contact carries F0 (+ the weight above it) at rest: the wave is F - F_static
        static = scene_static_forces(sc)[idx]
        cols["dynamic_peak_force"] = s.peak_force[idx] - static
        cols["dynamic_leading_pulse_force"] = s.leading_pulse_force[idx] - static
    if f0:  # the front's arrival there: the half-amplitude arrival (postprocess.fronts.front_times)
        cols["front_time"] = s.front_time[idx]
    e = result.errors
    if e is not None and e.peak_force is not None:
        cols["peak_force_error"] = e.peak_force.error[idx]
        cols["time_of_peak_error"] = e.time_of_peak.error[idx]
        # one CSV cell each (granchain.rundir writes them so)
        cols["error_status"] = np.asarray([str(x).replace(",", ";") for x in e.peak_force.status[idx]], dtype=object)
    return cols
