"""Scalar observables of a run, measured the same way for every backend, from complete peaks only.

A peak feeds an observable only once it has passed: the largest peak (max_peak_force) once it is
complete (granchain.peaks.complete_peaks: the force has fallen to half of it since), the leading
pulse once its first maximum is behind it (granchain.peaks.leading_pulse). A contact the wave is still
passing at the end of the run holds a value that is still rising; it never feeds one.

leading_peak_force: the leading pulse at the last contact of the measurement window (the wave has
    formed there and has not yet met the far end), in N and as F / (E* R*^2) (Eq. 5). The leading
    pulse is a contact's first maximum, not its largest (granchain.peaks.leading_pulse): in a
    forming wave train or behind a front that rises to a plateau, the largest pulse, and the time it
    passes, jump between oscillations as the time step changes; the first does not
    (docs/observables.md).
wave_speed: the front's speed, 1 / (d t_arrival / d x), a least-squares line through the arrival
    times of the window's contacts that have one (wave_speed_contacts of them) against their
    positions, with the slope's standard error propagated to the speed. The arrival is the leading
    pulse's time; on a precompressed chain the half-amplitude arrival (front_arrivals).
    Where the window's contacts are not all alike (contact_kinds: a contact's law constants and its
    two beads' masses, whichever comes first; an interface between two sections, an impurity, a taper)
    the front's speed differs along the window and the fit is an average over it: measure_observables
    says so in the dict passed as `notes`, and wave_speed_sections gives the speed fitted over each
    uniform stretch of the window that has FIT_CONTACTS arrivals (section_speeds). A periodic window
    (periodic_cell: a dimer, a trimer, a cell of beads repeated PERIODIC_CELLS times or more) has one
    speed at the scale of its cell: the note says the fit is that cell-averaged speed, and there are no
    sections. A window whose contacts are all of one kind but whose beads differ (a dimer window of
    fewer than PERIODIC_CELLS cells) is noted as an average too, with no sections.
max_peak_force: the largest complete peak (of any pulse), and its contact.
Each is None where it cannot be measured (the window's last contact not reached or its peak not
complete before the end of the run; fewer than three complete peaks in the window; no complete
peak at all); measure_observables says why in the dict passed as `missing`.
"""

from __future__ import annotations

import numpy as np

from granchain.peaks import (
    LEAD_FRACTION,
    lead_fall,
    lead_floor,
    position_resolution,
    still_rising,
)
from granchain.physics.materials import MATERIALS
from granchain.problem import contact_positions


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


def wave_speed_unmeasurable(scene) -> str | None:
    """Why the scene can never measure the wave speed, whatever the run, or None.

    The fit takes one arrival per contact of the measurement window and needs FIT_CONTACTS of them:
    a window of fewer contacts (a chain of 2 or 4 beads, a short ``[outputs] window``) never has them.
    """
    a, b = scene.window if scene.n_contacts else (1, 0)
    if b - a + 1 >= FIT_CONTACTS:
        return None
    where = f"contacts {a}-{b}" if scene.n_contacts else "no bead-bead contact"
    return (
        f"the scene's measurement window has {max(b - a + 1, 0)} contact(s) ({where}); the wave-speed fit needs "
        f"{FIT_CONTACTS}, which this scene can never give"
    )


#: relative difference under which two contacts' constants or masses count as alike: the same kind
#: of bead computed twice (round-off), not a different bead
_ALIKE = 1e-9

#: the least number of times a cell of beads repeats over the window for the window to count as a
#: periodic chain (periodic_cell): fewer is a pattern, not a chain with a speed at the cell's scale
PERIODIC_CELLS = 3


def _alike(k: np.ndarray, ref: np.ndarray) -> bool:
    """Two keys (contact constants, masses, radii) agree to _ALIKE."""
    return k.shape == ref.shape and bool(np.allclose(k, ref, rtol=_ALIKE, atol=0.0))


def contact_kinds(scene) -> list[int]:
    """Each bead-bead contact's kind (0, 1, ...; in chain order): two contacts are of one kind where
    their laws' constants (ContactLaw.pair_coefficients: stiffness and any yield or plastic constants) and their
    two beads' masses agree to _ALIKE, whichever bead comes first: a large-small contact and a small-large
    one are one law between one pair of masses (the laws' mixing rules are symmetric), so a chain and its
    mirror image have the same kinds. A wave crosses contacts of one kind at one speed; where the kind
    changes, the speed does (stiffer contacts or lighter beads: faster)."""
    if not scene.per_bead:  # one bead kind: every contact alike (precompressed or not)
        return [0] * scene.n_contacts
    m = np.asarray(scene.bead_masses, dtype=float)
    keys = [
        np.array([*law.pair_coefficients(), *sorted((m[i], m[i + 1]))], dtype=float)
        for i, law in enumerate(scene.contact_laws)
    ]
    kinds: list[int] = []
    seen: list[np.ndarray] = []
    for k in keys:
        for j, ref in enumerate(seen):
            if _alike(k, ref):
                kinds.append(j)
                break
        else:
            seen.append(k)
            kinds.append(len(seen) - 1)
    return kinds


def periodic_cell(scene) -> int | None:
    """The number of beads p >= 2 of the cell that the measurement window's beads repeat (a dimer: 2,
    a trimer: 3), or None: bead i + p is bead i's radius and mass and contact i + p has contact i's law
    constants (to _ALIKE) all over the window's beads, which hold at least PERIODIC_CELLS cells; p is
    the shortest such cell. A window of one bead kind (p = 1) is uniform, not periodic (None).

    A periodic chain has one wave speed at the scale of its cell, the cell-averaged speed that dimer
    and trimer chains are measured by (Jayaprakash, Starosvetsky & Vakakis, "New family of solitary
    waves in granular dimer chains with no precompression", Phys. Rev. E 83, 036606, 2011; Porter, Daraio,
    Szelengowicz, Herbold & Kevrekidis, "Highly nonlinear solitary waves in heterogeneous periodic
    granular media", arXiv:0712.3552, dimer and trimer cells and the speed of their long-wavelength
    solitary wave; Potekin, Jayaprakash, McFarland, Remick, Bergman & Vakakis, "Experimental study of
    strongly nonlinear resonances and anti-resonances in granular dimer chains", Exp. Mech. 2013:
    reference not verified), though within a cell the front's hops from contact to contact (their
    lengths, the masses they move) differ."""
    if not scene.per_bead or not scene.n_contacts:
        return None
    a, b = scene.window  # the window's contacts a..b join beads a..b+1
    laws = scene.contact_laws
    contacts = [np.array(laws[c - 1].pair_coefficients(), dtype=float) for c in range(a, b + 1)]
    p = _shortest_cell(_window_bead_keys(scene), contacts)
    return p if p is not None and p >= 2 else None


def _shortest_cell(beads: list[np.ndarray], contacts: list[np.ndarray]) -> int | None:
    """The shortest p >= 1, up to len(beads) // PERIODIC_CELLS, for which each bead's key is alike
    (_alike) the key of the bead p before it and each contact's that of the contact p before it, or
    None (periodic_cell). Each p is one array comparison over all the keys (_rows_alike), not one
    per key: a window of 3000 beads takes milliseconds, not seconds."""
    bead_rows, bead_sizes = _key_rows(beads)
    contact_rows, contact_sizes = _key_rows(contacts)
    for p in range(1, len(beads) // PERIODIC_CELLS + 1):
        if _rows_alike(bead_rows, bead_sizes, p) and _rows_alike(contact_rows, contact_sizes, p):
            return p
    return None


def _key_rows(keys: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """1-D keys as the rows of one array, each padded with zeros to the longest, and each key's length:
    the padding of two keys of one length compares alike, and keys of two lengths never are (_alike)."""
    sizes = np.array([k.size for k in keys], dtype=int)
    rows = np.zeros((len(keys), int(sizes.max(initial=0))), dtype=float)
    for i, k in enumerate(keys):
        rows[i, : k.size] = k
    return rows, sizes


def _rows_alike(rows: np.ndarray, sizes: np.ndarray, p: int) -> bool:
    """Whether every key (a row of _key_rows) is alike (_alike) the key p rows before it: the same
    elementwise test as _alike(rows[i + p], rows[i]) for every i, in one array comparison."""
    return bool(np.all(sizes[p:] == sizes[:-p])) and bool(np.allclose(rows[p:], rows[:-p], rtol=_ALIKE, atol=0.0))


def _window_beads_alike(scene) -> bool:
    """Whether the measurement window's beads (a..b+1) all have one radius and mass (to _ALIKE)."""
    if not scene.per_bead or not scene.n_contacts:
        return True
    beads = _window_bead_keys(scene)
    return all(_alike(x, beads[0]) for x in beads)


def _window_bead_keys(scene) -> list[np.ndarray]:
    """The measurement window's beads a..b+1 as (radius, mass) keys to compare with _alike."""
    a, b = scene.window
    r, m = np.asarray(scene.bead_radii, dtype=float), np.asarray(scene.bead_masses, dtype=float)
    return [np.array([r[i], m[i]]) for i in range(a - 1, b + 1)]


def uniform_sections(scene) -> list[tuple[int, int]]:
    """The measurement window split into runs of consecutive contacts of one kind (contact_kinds):
    (first, last) 1-based contacts each; one run where the window's contacts are all alike, and one
    where the window is a periodic chain (periodic_cell), uniform at the scale of its cell: a single
    contact kind of it is no stretch the wave crosses at a speed of its own."""
    if not scene.n_contacts:
        return []
    a, b = scene.window
    if periodic_cell(scene):
        return [(int(a), int(b))]
    kind = contact_kinds(scene)
    runs = [[a, a]]
    for c in range(a + 1, b + 1):
        if kind[c - 1] == kind[runs[-1][1] - 1]:
            runs[-1][1] = c
        else:
            runs.append([c, c])
    return [(int(f), int(last)) for f, last in runs]


#: at most this many stretches of like beads are named one by one in the wave speed's note
_NAMED_STRETCHES = 6


def _bead_label(radius: float, material, named: bool) -> str:
    """A bead kind as the wave speed's note names it: its radius, and its material where the chain has several."""
    text = f"R = {radius * 1e3:.4g} mm"
    if named:
        name = next((k for k, v in MATERIALS.items() if v == material), None)
        text += f" {name}" if name else f" (rho {material.density:.4g} kg/m^3, E {material.youngs_modulus:.4g} Pa)"
    return text


def _stretches(runs) -> str:
    """1-based (first, last) stretches as a list: "4-9, 10, 11-19"."""
    return ", ".join(f"{f}-{last}" if f != last else f"{f}" for f, last in runs)


def _span(lo: str, hi: str, unit: str) -> str:
    """A range of formatted values ("2.1 to 2.4 mm"), or the one value where they agree ("2.38 mm")."""
    return f"{lo} {unit}" if lo == hi else f"{lo} to {hi} {unit}"


def _window_contacts(scene) -> str:
    """The window's contacts by stretches of one kind (uniform_sections), counted and, up to
    _NAMED_STRETCHES, listed ("contacts in 3 stretches of one kind: 4-9, 10, 11-19")."""
    sections = uniform_sections(scene)
    a, b = scene.window
    if len(sections) > _NAMED_STRETCHES:
        return f"contacts {a}-{b} in {len(sections)} stretches of one kind"
    return f"contacts in {len(sections)} stretches of one kind: {_stretches(sections)}"


def _window_beads(scene) -> str:
    """The window's beads by stretches of one radius and material ("beads in 2 stretches of one radius
    and material: 1-20 of R = 1 mm, 21-40 of R = 2 mm"; one stretch: "beads 1-40 of R = 1 mm"); a chain
    whose beads change every few beads (a taper) counted, with the range of its radii; a periodic window
    (periodic_cell) by its cell ("beads 7-22 repeat a cell of 2 beads (R = 4.76 mm, R = 2.38 mm): 8
    cells"). The count is that of the stretches listed."""
    a, b = scene.window
    r, mats = scene.bead_radii, scene.bead_materials
    named = any(m != mats[0] for m in mats)
    p = periodic_cell(scene)
    if p:
        cell = ", ".join(_bead_label(float(r[i]), mats[i], named) for i in range(a - 1, a - 1 + p))
        whole, rest = divmod(b - a + 2, p)
        more = f" and {rest} bead{'s' if rest > 1 else ''}" if rest else ""
        return f"beads {a}-{b + 1} repeat a cell of {p} beads ({cell}): {whole} cells{more}"
    runs: list[list] = []
    for i in range(a - 1, b + 1):  # the window's contacts a..b join beads a..b+1
        label = _bead_label(float(r[i]), mats[i], named)
        if runs and runs[-1][2] == label:
            runs[-1][1] = i + 1
        else:
            runs.append([i + 1, i + 1, label])
    if len(runs) > _NAMED_STRETCHES:
        w = r[a - 1 : b + 1] * 1e3
        radii = _span(f"{w.min():.4g}", f"{w.max():.4g}", "mm")
        return (
            f"beads {a}-{b + 1} in {len(runs)} stretches of one radius and material ("
            + ("radii " if radii.count(" to ") else "radius ")
            + radii
            + (", several materials" if named else "")
            + ")"
        )
    listed = ", ".join(f"{f}-{last} of {lab}" if f != last else f"{f} of {lab}" for f, last, lab in runs)
    if len(runs) == 1:
        return f"beads {listed}"
    return f"beads in {len(runs)} stretches of one radius and material: {listed}"


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


def measure_observables(scene, solution, missing: dict | None = None, notes: dict | None = None) -> dict:
    """The observables of a run (complete peaks only); `missing`, if given, gets name -> reason for each
    None; `notes`, if given, name -> what a measured value is where it is not what its name says
    (wave_speed over a window whose contacts differ: an average over it; over a periodic window: the
    cell-averaged speed).

    Forces are dynamic on a precompressed chain: the rise above the static force F0 (static_force),
    which every contact carries at rest; the leading pulse and its arrival are measured on it too.
    """
    why: dict[str, str] = {}
    if scene.n_contacts == 0:  # one bead: its contacts are the striker's and the wall's (end_fields)
        names = ("leading_peak_force", "leading_peak_force_nondim", "wave_speed", "wave_speed_stderr")
        out = dict.fromkeys((*names, "max_peak_force", "max_peak_contact"))
        out.update(window=[], leading_peak_contact=None, wave_speed_contacts=0)
        for name in (*names, "max_peak_force", "max_peak_contact"):
            why[name] = "one bead has no bead-bead contact: its contact's peak is the striker's or the wall's"
        if missing is not None:
            missing.update(why)
        return out
    complete = np.asarray(solution.complete, dtype=bool)
    a, b = scene.window
    contacts = np.arange(a, b + 1)
    out: dict = {"window": [int(a), int(b)]}
    last = b - 1
    out["leading_peak_contact"] = int(b)
    # under precompression every contact carries F0 at rest: the wave is the dynamic force F - F0,
    # which the peak forces below measure (the total is F0 more: peaks.csv keeps it)
    f0 = float(scene.effects.precompression)
    if f0:
        out["static_force"] = f0
    lead_f = np.asarray(solution.leading_pulse_force, dtype=float) - f0
    if np.isfinite(lead_f[last]):
        out["leading_peak_force"] = float(lead_f[last])
        # F / (E* R*^2) of that contact's own pair (Eq. 5): on a chain whose beads differ, not bead 1's
        out["leading_peak_force_nondim"] = float(lead_f[last] / scene.contact_force_scales[last])
    else:
        out["leading_peak_force"] = out["leading_peak_force_nondim"] = None
        why["leading_peak_force"] = why["leading_peak_force_nondim"] = _why_no_leading_pulse(scene, solution, b)
    arrival = front_arrivals(solution, f0)
    ok = np.isfinite(arrival[contacts - 1])
    positions = contact_positions(scene)
    fit = fit_wave_speed(contacts[ok], arrival[contacts - 1][ok], scene.diameter, positions)
    out["wave_speed"] = fit[0] if fit else None
    out["wave_speed_stderr"] = fit[1] if fit else None
    out["wave_speed_contacts"] = int(np.sum(ok))
    sections = uniform_sections(scene)
    average = None
    if fit and periodic_cell(scene):  # one speed at the scale of the cell, none per contact kind
        average = (
            f"the cell-averaged speed of a periodic chain over contacts {a}-{b} ({_window_beads(scene)}): "
            "one number at the scale of the cell, the speed dimer and trimer chains are measured by (none "
            "per contact kind: the front's hops from contact to contact differ within the cell)"
        )
    elif fit and len(sections) > 1:  # the fit averages the speed over stretches of several contact kinds
        out["wave_speed_sections"] = section_speeds(scene, arrival, positions)
        each = (
            f"wave_speed_sections: the speed over each uniform stretch with {FIT_CONTACTS} arrivals or more"
            if out["wave_speed_sections"]
            else f"no uniform stretch of the window has {FIT_CONTACTS} arrivals to fit on its own"
        )
        average = (
            f"an average over contacts {a}-{b}, whose contacts differ (law constants or bead masses: "
            f"{_window_contacts(scene)}; {_window_beads(scene)}): the front's speed is not one number along this "
            f"window; {each}"
        )
    elif fit and not _window_beads_alike(scene):  # one contact kind between beads that alternate: a dimer
        # window of fewer than PERIODIC_CELLS cells, no periodic chain (periodic_cell) and no stretches
        average = (
            f"an average over contacts {a}-{b}, whose contacts are of one kind but join beads that differ "
            f"({_window_beads(scene)}): the front's speed is not one number along this window; its "
            f"{b - a + 2} beads repeat a cell fewer than {PERIODIC_CELLS} times, too few to count as a periodic "
            "chain with a cell-averaged speed, and its one contact kind makes no stretch to fit on its own"
        )
    if fit is None:
        done = complete[contacts - 1]
        passed = np.where(done, np.asarray(solution.peak_force, dtype=float)[contacts - 1] - f0, np.nan)
        why["wave_speed"] = why["wave_speed_stderr"] = (
            wave_speed_unmeasurable(scene)
            or (
                f"{int(np.sum(ok))} of the window's contacts {a}-{b} have {_ARRIVAL[bool(f0)]}; the fit needs "
                f"{FIT_CONTACTS}" + (_under_front_resolution(lead_f[contacts - 1], passed, f0) if f0 else "")
            )
            if np.sum(ok) < FIT_CONTACTS
            else f"the arrival times of the window's complete leading pulses (contacts {a}-{b}) do not increase"
        )
    if complete.any():
        i = int(np.argmax(np.where(complete, solution.peak_force, -np.inf)))
        out["max_peak_force"] = float(solution.peak_force[i]) - f0
        out["max_peak_contact"] = i + 1
    else:
        out["max_peak_force"] = out["max_peak_contact"] = None
        why["max_peak_force"] = why["max_peak_contact"] = "no contact has a complete peak before the end of the run"
    if average is not None and notes is not None:
        notes["wave_speed"] = average
    if missing is not None:
        missing.update(why)
    return out


def _why_still_rising(scene, solution, contact: int) -> str:
    """Why a 1-based contact's peak so far is not its peak: the wave is still arriving there."""
    i, f0 = contact - 1, float(scene.effects.precompression)
    lead = float(solution.leading_pulse_force[i]) - f0
    first = (
        f"; its leading pulse (its first maximum, {lead:.6g} N above the static force at "
        f"t = {float(solution.leading_pulse_time[i]):g} s) stands"
        if np.isfinite(lead)
        else ""
    )
    return (
        f"the force at contact {contact} still rises at the end of the run (t = {solution.end_time:g} s): the wave "
        f"has not passed it, and its peak so far ({float(solution.peak_force[i]) - f0:.6g} N above the static force "
        f"at t = {float(solution.time_of_peak[i]):g} s) is not complete and may not be its peak{first}; run longer"
    )


def unmeasured_outputs(scene, solution) -> list[str]:
    """What the scene asked for that the run ended before measuring: its window's leading peak and
    wave speed (a peak-force table), each with the reason, the window's last contact's peak while
    the force there still rises at the end (peaks.still_rising: a main wave behind a smaller
    precursor; not while a force load still acts, whose plateau the force rises to), and the wall's
    peak where the stop check waits for the wall's contact (stop_after_wall) and it is not complete; [] when everything
    asked for is there. A run that ends too soon says so (the command
    line exits 1), not only in summary.json. The wave speed of a scene that can never measure it
    (wave_speed_unmeasurable: a window of fewer than FIT_CONTACTS contacts) is not missed by the run:
    it is left out here, and the run's observables say why it is None."""
    if not scene.outputs.peak_force or scene.n_contacts == 0:
        return []
    missing: dict[str, str] = {}
    out = measure_observables(scene, solution, missing)
    asked = ("leading_peak_force",) + (("wave_speed",) if wave_speed_unmeasurable(scene) is None else ())
    lines = [f"{name}: {missing[name]}" for name in asked if out.get(name) is None]
    b = scene.window[1]
    # behind a load still acting at the end the force rises toward the load's level: a running maximum
    # that no longer run completes while the load acts, not a main wave still to come
    ld = scene.loading
    lasting = ld.is_force and ld.duration > solution.end_time
    if not lasting and still_rising(solution.complete, solution.time_of_peak, solution.velocity)[b - 1]:
        lines.append(f"peak_force_contact_{b}: {_why_still_rising(scene, solution, b)}")
    # a stop check that waits for the wall's contact ([run] stop_after_wall: the planner's, where the
    # wall's peak is asked for); a run that ended before its force fell back to half its peak missed it
    if scene.run.stop_after_wall and not lasting and solution.wall_peak_complete is False:
        lines.append(
            "wall_peak_force: the wave did not reach or pass the wall (its force falling to half its peak) "
            f"before the run ended at t = {solution.end_time:g} s"
        )
    return lines
