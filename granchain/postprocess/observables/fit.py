"""The wave front's arrivals and the least-squares fit of its speed (the wave speed's data)."""

from __future__ import annotations

import numpy as np

from granchain.postprocess.observables.windows import uniform_sections


def fit_wave_speed(
    contacts: np.ndarray, times: np.ndarray, diameter: float, positions: np.ndarray | None = None
) -> tuple[float, float] | None:
    """Least-squares speed (m/s) and the fit's standard error from times at 1-based contacts.

    positions: where each contact sits (m; problem.contact_positions, indexed by contact - 1): the
    distances the front travels. Without it the contacts are one diameter apart (a uniform chain).
    """
    ok = np.isfinite(times)
    c = np.asarray(contacts)[ok]
    t = np.asarray(times)[ok]
    x = c.astype(float) * diameter if positions is None else np.asarray(positions, dtype=float)[c - 1]
    if x.size < 3:
        return None
    xm, tm = x.mean(), t.mean()
    sxx = np.sum((x - xm) ** 2)
    slope = np.sum((x - xm) * (t - tm)) / sxx  # s per m
    if slope <= 0:
        return None
    resid = t - (tm + slope * (x - xm))
    stderr_slope = np.sqrt(np.sum(resid**2) / (x.size - 2) / sxx)
    speed = 1.0 / slope
    return float(speed), float(speed * stderr_slope / slope)


#: what an arrival is, without and with precompression (front_arrivals)
_ARRIVAL = {
    False: "a leading pulse whose maximum has passed",
    True: "a half-amplitude arrival (a leading pulse whose rise the crossing-time ladder holds)",
}


def front_arrivals(solution, static_force: float) -> np.ndarray:
    """The front's arrival time at each contact (s; nan where it has none), the wave speed's data.

    Without precompression: the leading pulse's time, the first maximum (the paper's definition).
    On a precompressed chain: the half-amplitude arrival (postprocess.fronts.front_times), the time
    the dynamic force F - F0 rose through half the leading pulse's rise. A small perturbation of a
    precompressed chain spreads as it travels (dispersion): its first maximum falls behind the
    sonic front by 1.4% over 300 beads, the half-amplitude point by a fraction of that, and the
    half-amplitude arrival does not depend on a maximum's exact sample (docs/observables.md).
    """
    lead_t = np.asarray(solution.leading_pulse_time, dtype=float)
    if not static_force:
        return lead_t
    front = np.asarray(solution.front_time, dtype=float)
    return np.where(np.isfinite(lead_t), front, np.nan)


def _under_front_resolution(rises: np.ndarray, passed: np.ndarray, f0: float) -> str:
    """Why a precompressed window lacks arrivals where some of its leading pulses (rises above F0, N;
    nan where none) are no larger than FRONT_RESOLUTION F0, below which no arrival is read
    (postprocess.fronts), or where it has no leading pulse and the wave that passed its contacts (passed:
    their complete peaks above F0, N; nan where not complete) rose no higher; "" otherwise. A window
    with no leading pulse and no complete peak is one the wave had not passed when the run ended (not
    reached, or still rising there): no size of front would have been read there, and the count of
    arrivals says enough."""
    from granchain.postprocess.fronts import FRONT_RESOLUTION

    r = rises[np.isfinite(rises)]
    limit = FRONT_RESOLUTION * f0
    small = int(np.sum(r <= limit))
    if r.size and not small:
        return ""
    if not r.size:
        done = passed[np.isfinite(passed)]
        if not done.size or float(np.max(done)) > limit:
            return ""
        which = "the window's contacts have no leading pulse"
    elif small == r.size:
        which = f"the window's leading pulses rise at most {float(np.max(r)):.2g} N above F0"
    else:
        which = f"{small} of the window's {r.size} leading pulses rise"
    return (
        f": {which}, not above FRONT_RESOLUTION x F0 = {limit:.2g} N, below which no arrival is read (a "
        "precompressed contact's total force is resolved only to about 1e-9 F0 by LAMMPS); a larger load or "
        "a smaller F0 makes a front that can be read"
    )


#: the least number of contacts with an arrival that the wave-speed fit takes (fit_wave_speed: a line
#: and its standard error, which needs a residual)
FIT_CONTACTS = 3


def window_unfittable(scene, fit: str = "the wave-speed fit") -> str | None:
    """Why the scene can never fit a line over its measurement window, whatever the run, or None.

    The fits (the wave speed's, the leading pulse's decay) take one value per contact of the window and
    need FIT_CONTACTS of them: a window of fewer contacts (a chain of 2 or 4 beads, a short
    ``[outputs] window``) never has them. fit: its name in the reason.
    """
    a, b = scene.window if scene.n_contacts else (1, 0)
    if b - a + 1 >= FIT_CONTACTS:
        return None
    where = f"contacts {a}-{b}" if scene.n_contacts else "no bead-bead contact"
    return (
        f"the scene's measurement window has {max(b - a + 1, 0)} contact(s) ({where}); {fit} needs "
        f"{FIT_CONTACTS}, which this scene can never give"
    )


def wave_speed_unmeasurable(scene) -> str | None:
    """Why the scene can never measure the wave speed, whatever the run, or None (window_unfittable)."""
    return window_unfittable(scene)


def section_speeds(scene, arrival: np.ndarray, positions: np.ndarray) -> list[dict]:
    """The wave speed fitted over each uniform stretch of the window (uniform_sections) that has
    FIT_CONTACTS arrivals (arrival: per contact, nan where none): {contacts: [first, last], speed,
    stderr, arrivals} each, in chain order; the stretches with fewer, or whose times do not increase,
    are left out."""
    out = []
    for f, last in uniform_sections(scene):
        c = np.arange(f, last + 1)
        ok = np.isfinite(arrival[c - 1])
        if np.sum(ok) < FIT_CONTACTS:
            continue
        fit = fit_wave_speed(c[ok], arrival[c - 1][ok], scene.diameter, positions)
        if fit is not None:
            out.append({"contacts": [f, last], "speed": fit[0], "stderr": fit[1], "arrivals": int(np.sum(ok))})
    return out
