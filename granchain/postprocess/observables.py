"""Scalar observables of a run, measured the same way for every backend.

leading_peak_force: the peak force at the last contact of the measurement window (the wave has
    formed there and has not yet met the far end), in N and as F / (E* R*^2) (Eq. 5).
wave_speed: D / (d time_of_peak / d contact), a least-squares line through the times of peak of
    the window's contacts, with the slope's standard error propagated to the speed.
Both are None where they cannot be measured (the wave has not reached the window before the end
of the run, or fewer than three contacts were reached).
"""

from __future__ import annotations

import numpy as np


def fit_wave_speed(contacts: np.ndarray, times: np.ndarray, diameter: float) -> tuple[float, float] | None:
    """Least-squares speed (m/s) and its standard error from times of peak at 1-based contacts."""
    ok = np.isfinite(times)
    x, t = np.asarray(contacts, dtype=float)[ok], np.asarray(times)[ok]
    if x.size < 3:
        return None
    xm, tm = x.mean(), t.mean()
    sxx = np.sum((x - xm) ** 2)
    slope = np.sum((x - xm) * (t - tm)) / sxx  # s per contact
    if slope <= 0:
        return None
    resid = t - (tm + slope * (x - xm))
    stderr_slope = np.sqrt(np.sum(resid**2) / (x.size - 2) / sxx)
    speed = diameter / slope
    return float(speed), float(speed * stderr_slope / slope)


def measure_observables(scene, solution) -> dict:
    a, b = scene.window
    contacts = np.arange(a, b + 1)
    times = solution.time_of_peak[contacts - 1]
    out: dict = {"window": [int(a), int(b)]}
    last = b - 1
    reached = np.isfinite(solution.time_of_peak[last])
    out["leading_peak_contact"] = int(b)
    out["leading_peak_force"] = float(solution.peak_force[last]) if reached else None
    out["leading_peak_force_nondim"] = float(solution.peak_force[last] / scene.force_scale) if reached else None
    fit = fit_wave_speed(contacts, times, scene.diameter) if reached else None
    out["wave_speed"] = fit[0] if fit else None
    out["wave_speed_stderr"] = fit[1] if fit else None
    i = int(np.argmax(solution.peak_force))
    out["max_peak_force"] = float(solution.peak_force[i])
    out["max_peak_contact"] = i + 1
    return out
