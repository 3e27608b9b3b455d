"""The tables and displays of a run: peaks.csv's columns and units, the observables' units, printable text."""

from __future__ import annotations

import numpy as np

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

#: units of the observables of summary.json ("1": dimensionless)
OBSERVABLE_UNITS = {
    "window": "contacts",
    "leading_peak_contact": "contact",
    "leading_peak_force": "N",
    "leading_peak_force_nondim": "1",  # F / (E* R*^2), Eq. 5
    "wave_speed": "m/s",
    "wave_speed_stderr": "m/s",
    "wave_speed_contacts": "contacts fitted",
    # a window whose contacts differ: the speed over each uniform stretch, {contacts, speed, stderr, arrivals}
    "wave_speed_sections": "m/s per stretch",
    "max_peak_force": "N",
    "max_peak_contact": "contact",
    "static_force": "N",  # a precompression's F0: the forces above are dynamic, F - F0
}

#: the observables a result's short display shows
_SHOWN = ("leading_peak_force", "leading_peak_contact", "wave_speed", "max_peak_force", "max_peak_contact")


def _key_observables(summary: dict):
    """(name, value, unit, error or None) of the shown observables that the summary has."""
    obs = summary.get("observables") or {}
    errs = (summary.get("errors") or {}).get("observables") or {}
    for name in _SHOWN:
        if name in obs:
            e = errs.get(name) or {}
            err = e.get("error") if obs[name] is not None else None
            yield name, obs[name], OBSERVABLE_UNITS.get(name, ""), err


def _num(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def printable(text: str, limit: int | None = None, keep: str = "") -> str:
    r"""text with its control characters escaped (ESC as \x1b, a newline as \n ...): scene text
    shown on a terminal can neither move the cursor nor retitle the window. Cut to limit characters;
    the characters in keep (e.g. "\n" for a message of several lines) stay as they are."""
    out = "".join(
        ch
        if ch.isprintable() or ch in keep
        else (ch.encode("unicode_escape").decode("ascii") if ord(ch) < 0x10000 else repr(ch)[1:-1])
        for ch in str(text)
    )
    if limit is not None and len(out) > limit:
        out = out[: limit - 3] + "..."
    return out


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
    if f0:  # a precompressed contact carries F0 at rest: the wave is the dynamic force F - F0
        cols["dynamic_peak_force"] = s.peak_force[idx] - f0
        cols["dynamic_leading_pulse_force"] = s.leading_pulse_force[idx] - f0
        # the front's arrival there: the half-amplitude arrival (postprocess.fronts.front_times)
        cols["front_time"] = s.front_time[idx]
    e = result.errors
    if e is not None and e.peak_force is not None:
        cols["peak_force_error"] = e.peak_force.error[idx]
        cols["time_of_peak_error"] = e.time_of_peak.error[idx]
        # one CSV cell each (granchain.rundir writes them so)
        cols["error_status"] = np.asarray([str(x).replace(",", ";") for x in e.peak_force.status[idx]], dtype=object)
    return cols
