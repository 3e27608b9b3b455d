"""The front's speed along the measurement window, and the note on what it is where the window's
contacts or beads differ.

wave_speed: 1 / (d t_arrival / d x), a least-squares line through the arrival times of the window's
contacts that have one (wave_speed_contacts of them) against their positions, with the slope's standard
error propagated to the speed. The arrival is the leading pulse's time; on a precompressed chain the
half-amplitude arrival (fit.front_arrivals). Where the window's contacts are not all alike
(windows.contact_kinds: a contact's law constants and its two beads' masses, whichever comes first; an
interface between two sections, an impurity, a taper) the front's speed differs along the window and
the fit is an average over it: the note says so, and wave_speed_sections gives the speed fitted over
each uniform stretch of the window that has FIT_CONTACTS arrivals (fit.section_speeds). A periodic
window (windows.periodic_cell: a dimer, a trimer, a cell of beads repeated PERIODIC_CELLS times or
more) has one speed at the scale of its cell: the note says the fit is that cell-averaged speed, and
there are no sections. A window whose contacts are all of one kind but whose beads differ (a dimer
window of fewer than PERIODIC_CELLS cells) is noted as an average too, with no sections.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from granchain.postprocess.observables.base import Measurement, Observable
from granchain.postprocess.observables.fit import (
    _ARRIVAL,
    FIT_CONTACTS,
    _under_front_resolution,
    fit_wave_speed,
    front_arrivals,
    section_speeds,
    wave_speed_unmeasurable,
)
from granchain.postprocess.observables.windows import (
    PERIODIC_CELLS,
    _window_beads,
    _window_beads_alike,
    _window_contacts,
    periodic_cell,
    uniform_sections,
)
from granchain.problem import contact_positions, scene_static_forces


def _arrivals(scene, solution) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The window's contacts, the front's arrival at every contact (s; nan where none) and which of
    the window's have one."""
    a, b = scene.window
    contacts = np.arange(a, b + 1)
    arrival = front_arrivals(solution, float(scene.effects.precompression))
    return contacts, arrival, np.isfinite(arrival[contacts - 1])


def _average_note(scene, sections: list, fields: dict) -> str | None:
    """What a measured speed is where the window's contacts or beads differ (an average; over a periodic
    window the cell-averaged speed), None over a uniform window; sections: uniform_sections(scene), and
    fields gets wave_speed_sections where the fit averages over stretches of several kinds."""
    a, b = scene.window
    if periodic_cell(scene):  # one speed at the scale of the cell, none per contact kind
        return (
            f"the cell-averaged speed of a periodic chain over contacts {a}-{b} ({_window_beads(scene)}): "
            "one number at the scale of the cell, the speed dimer and trimer chains are measured by (none "
            "per contact kind: the front's hops from contact to contact differ within the cell)"
        )
    if len(sections) > 1:  # the fit averages the speed over stretches of several contact kinds
        each = (
            f"wave_speed_sections: the speed over each uniform stretch with {FIT_CONTACTS} arrivals or more"
            if fields["wave_speed_sections"]
            else f"no uniform stretch of the window has {FIT_CONTACTS} arrivals to fit on its own"
        )
        return (
            f"an average over contacts {a}-{b}, whose contacts differ (law constants or bead masses: "
            f"{_window_contacts(scene)}; {_window_beads(scene)}): the front's speed is not one number along this "
            f"window; {each}"
        )
    if not _window_beads_alike(scene):  # one contact kind between beads that alternate: a dimer window
        # of fewer than PERIODIC_CELLS cells, no periodic chain (periodic_cell) and no stretches
        return (
            f"an average over contacts {a}-{b}, whose contacts are of one kind but join beads that differ "
            f"({_window_beads(scene)}): the front's speed is not one number along this window; its "
            f"{b - a + 2} beads repeat a cell fewer than {PERIODIC_CELLS} times, too few to count as a periodic "
            "chain with a cell-averaged speed, and its one contact kind makes no stretch to fit on its own"
        )
    return None


def _why_no_fit(scene, solution, ok: np.ndarray) -> str:
    """Why the window's arrivals (ok: which of its contacts have one) give no speed."""
    a, b = scene.window
    contacts = np.arange(a, b + 1)
    if np.sum(ok) >= FIT_CONTACTS:
        return f"the arrival times of the window's complete leading pulses (contacts {a}-{b}) do not increase"
    f0 = float(scene.effects.precompression)
    why = f"{int(np.sum(ok))} of the window's contacts {a}-{b} have {_ARRIVAL[bool(f0)]}; the fit needs {FIT_CONTACTS}"
    if f0:
        static = scene_static_forces(scene)[contacts - 1]  # each contact's own (gravity adds the weight above)
        lead_f = np.asarray(solution.leading_pulse_force, dtype=float)[contacts - 1] - static
        done = np.asarray(solution.complete, dtype=bool)[contacts - 1]
        passed = np.where(done, np.asarray(solution.peak_force, dtype=float)[contacts - 1] - static, np.nan)
        why += _under_front_resolution(lead_f, passed, f0)
    return why


class WaveSpeed(Observable):
    """The front's speed over the measurement window (see the module docstring)."""

    name = "wave_speed"
    unit = "m/s"
    definition = (
        "1 / slope of a least-squares line of the window's arrival times (leading pulses; precompressed: "
        "half-amplitude arrivals) against the contacts' positions"
    )
    needs = frozenset({"leading_pulses", "fronts", "peaks"})
    companions = {
        "wave_speed_stderr": "m/s",
        "wave_speed_contacts": "contacts fitted",
        # a window whose contacts differ: the speed over each uniform stretch, {contacts, speed, stderr, arrivals}
        "wave_speed_sections": "m/s per stretch",
    }
    shares_reason = ("wave_speed_stderr",)
    field_kinds: ClassVar[dict[str, str]] = {"wave_speed_contacts": "integer", "wave_speed_sections": "sections"}
    table_fields = ("wave_speed_stderr", "wave_speed_contacts")
    shown = True
    asked = True
    error_bar = "the time step's error from the companion runs and the fit's standard error, in quadrature"
    fit_stderr = "wave_speed_stderr"
    applies_where = f"a measurement window of {FIT_CONTACTS} contacts or more"

    def applies(self, scene) -> str | None:
        """None where the window has FIT_CONTACTS contacts or more (fit.wave_speed_unmeasurable)."""
        return super().applies(scene) or wave_speed_unmeasurable(scene)

    def unmeasured(self, scene, solution, reason: str) -> Measurement:
        """None, and the arrivals a window too short to fit still counts."""
        m = super().unmeasured(scene, solution, reason)
        if scene.n_contacts:  # one bead: the count is the context's (registry.measure)
            m.fields["wave_speed_contacts"] = int(np.sum(_arrivals(scene, solution)[2]))
        return m

    def measure(self, scene, solution) -> Measurement:
        """The fitted speed, its standard error, the arrivals fitted and, over unlike contacts, the
        speed of each uniform stretch; or None and why."""
        contacts, arrival, ok = _arrivals(scene, solution)
        positions = contact_positions(scene)
        fit = fit_wave_speed(contacts[ok], arrival[contacts - 1][ok], scene.diameter, positions)
        fields = {"wave_speed_stderr": fit[1] if fit else None, "wave_speed_contacts": int(np.sum(ok))}
        if fit is None:
            return Measurement(None, fields, _why_no_fit(scene, solution, ok))
        sections = uniform_sections(scene)
        if not periodic_cell(scene) and len(sections) > 1:
            fields["wave_speed_sections"] = section_speeds(scene, arrival, positions)
        return Measurement(fit[0], fields, None, _average_note(scene, sections, fields))
