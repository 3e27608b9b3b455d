"""The spectral observables of a harmonic drive ([loading] kind = "harmonic"): the far end's
steady-state force amplitude and phase at the drive's frequency, and the transmission, the far end's
amplitude over the drive's, linear and in dB (issue 46 item 2).

Both read the far end's force history, which a harmonic scene records by itself (the scene reader
adds the last bead-bead contact to [outputs] histories; the planner samples it at least
HISTORY_SAMPLES_PER_PERIOD times a drive period, docs/observables.md, "Spectral observables"). The
far end is the last bead-bead contact, N - 1, on a free chain and on a walled one alike: the wall's
contact keeps no history on either backend, so on a walled chain the force is the one the last bead
receives from the chain, one contact before the wall.

The steady window (postprocess.spectra.steady_window) starts after the drive's ramp and the front's
transit of the chain to the far end (one bead per sqrt(m_i / k_i), the long-wave time: the fastest
signal of a linear chain), and ends at the drive's end or the record's. Its first half is left to the
transients of the switch-on to decay; the lock-in reads the whole periods of its second half, and its
error bar is spectra.lock_in's |Z(window) - Z(window's last half)|: the finite window's share of the
error, a transient not yet decayed or a drift. The time step's share is the error estimate's (a run
with error estimates: its companion runs at 2 dt and 4 dt keep the far end's history,
workflows.errorbars.facts.companion_scene, and lock it in alike); the note says which is which.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from granchain.physics.estimates import linearised_stiffnesses
from granchain.postprocess.observables.base import Measurement, Observable
from granchain.postprocess.spectra import MIN_PERIODS, SpectraError, SteadyWindow, lock_in, steady_window, transmission

#: the fewest history samples a drive period the planner chooses for a harmonic scene's histories
#: ("auto" history_interval): the lock-in is exact on a sinusoid at 4 (spectra.MIN_SAMPLES_PER_PERIOD);
#: 32 also resolves the second to eighth harmonics a Hertz contact makes, which would otherwise alias
HISTORY_SAMPLES_PER_PERIOD = 32

#: why a struck run has no spectral observable
NOT_DRIVEN = (
    'a struck chain has no drive frequency: the spectral observables are those of [loading] kind = "harmonic" '
    "(read a struck run's spectrum with granchain.postprocess.spectra.spectrum on its histories)"
)
#: why an uncompressed driven chain has none
UNCOMPRESSED = (
    "a drive on an uncompressed chain pulls its contacts open every half period: there is no steady linear "
    "response to read; give [precompression] force = F0 (the drive's amplitude well below it)"
)
#: the note every measured value carries: what the error bars hold
STEP_SHARE = (
    "the time step's share is the error estimate's (errors.json, from the companion runs at 2 dt and 4 dt), not in it"
)

#: the fields the far-end amplitude writes beside it (name -> unit)
WINDOW_FIELDS: dict[str, str] = {
    "steady_window_start": "s",
    "steady_window_end": "s",
    "steady_window_periods": "periods",
}


def far_end_contact(scene) -> int:
    """The far end's contact (1-based): the last bead-bead contact, N - 1 (the module docstring says why)."""
    return int(scene.n_contacts)


def front_transit(scene) -> float:
    """The time a linear front takes from bead 1 to the far end's contact, s: sum_i sqrt(m_(i+1) / k_i)
    over the contacts, k_i linearised at F0 (the long-wave speed a sqrt(k / m) per bead distance)."""
    k, _ = linearised_stiffnesses(scene)
    m = np.asarray(scene.bead_masses, dtype=float)
    return float(np.sum(np.sqrt(m[1 : k.size + 1] / k)))


def settled_window(scene, t: np.ndarray) -> SteadyWindow:
    """The lock-in's window: the second half (whole periods, at least MIN_PERIODS) of the steady window
    after the ramp and the front's transit, up to the drive's end or the record's (t: the record's
    times, of which only the first and last count)."""
    ld = scene.loading
    # the record's span on a uniform grid: the step plan ends a step at the drive's end T, so the
    # samples after T are off the grid before it (steady_window only reads the span)
    span = np.linspace(float(t[0]), float(t[-1]), 16)
    whole = steady_window(span, ld.duration, ld.frequency, ld.ramp, front_transit(scene))
    used = max(MIN_PERIODS, whole.periods // 2)
    return SteadyWindow(whole.end - used / ld.frequency, whole.end, used, ld.frequency)


def _far_force(scene, solution, c: int | None = None) -> tuple[np.ndarray, np.ndarray] | str:
    """(times, dynamic force) of contact c (1-based; default the far end's; 0 a shaker's driver's contact
    with bead 1) from the run's histories, or why not."""
    c = far_end_contact(scene) if c is None else c
    contacts = [int(i) for i in solution.history_contacts]
    if (c - 1) not in contacts:
        if c == 0:
            return "the shaker's driver's contact history was not recorded: the backend records it by itself"
        return (
            f"contact {c}'s history was not recorded: a harmonic scene records it by itself; a scene written "
            f"without it needs [outputs] histories = [..., {c}]"
        )
    t = np.asarray(solution.history_time, dtype=float)
    f = np.asarray(solution.history_force, dtype=float)[:, contacts.index(c - 1)]
    return t, f - float(scene.effects.precompression)


def drive_force(scene, solution) -> tuple[np.ndarray, np.ndarray] | str:
    """(times, the drive's dynamic force on bead 1) over the far end's record, or why not: a force drive's
    own f(t) (Loading.force_at), a shaker's its driver's contact force less F0 (its history, contact 0)."""
    if not scene.loading.is_shaker:
        t = np.asarray(solution.history_time, dtype=float)
        return t, scene.loading.force_at(t)
    return _far_force(scene, solution, 0)


def lock_far_end(scene, solution):
    """(far end's LockIn, drive's LockIn) over the settled window, or why they cannot be measured."""
    got = _far_force(scene, solution)
    if isinstance(got, str):
        return got
    t, force = got
    try:
        win = settled_window(scene, t)
        # the samples of the window only: uniform there (the ramp's end is no step boundary, the drive's
        # end T is the window's end at the latest)
        spacing = float(np.median(np.diff(t)))
        keep = (t >= win.start - 0.5 * spacing) & (t < win.end - 1e-9 * spacing)
        t, force = t[keep], force[keep]
        far = lock_in(t, force, scene.loading.frequency, window=win)
        drive = drive_force(scene, solution)
        if isinstance(drive, str):
            return drive
        drive = lock_in(t, drive[1][keep], scene.loading.frequency, window=win)
    except SpectraError as e:
        return f"the far end's force history cannot be locked in: {e}"
    return far, drive


class _Spectral(Observable):
    """What both spectral observables share: where they apply, and the lock-in they read."""

    needs = frozenset({"histories"})
    compared = True
    error_bar = (
        "the time step's error from the companion runs (each keeps the far end's history and locks it in over "
        "the same window); the window's own bar is the *_error companion"
    )
    applies_where = 'a precompressed chain of two beads or more under [loading] kind = "harmonic"'

    def applies(self, scene) -> str | None:
        """None on a precompressed harmonic drive, else why never."""
        if not scene.loading.is_harmonic:
            return NOT_DRIVEN
        if not scene.effects.precompression:
            return UNCOMPRESSED
        return super().applies(scene)

    def note(self, win: SteadyWindow) -> str:
        """What a measured value is: the window it was read over, and the error bar's share."""
        return (
            f"lock-in at the drive's frequency over {win.periods} whole periods, t = {win.start:.6g} to "
            f"{win.end:.6g} s (the second half of the steady part, after the ramp and the front's transit); its "
            f"error bar is the finite window's |Z(window) - Z(last half)|, {STEP_SHARE}"
        )


class FarEndAmplitude(_Spectral):
    """The far end's steady force amplitude and phase at the drive's frequency, with the window's error bar."""

    name = "far_end_amplitude"
    unit = "N"
    definition = (
        "the steady-state amplitude of the far end's dynamic force (the last bead-bead contact's) at the drive's "
        "frequency, a lock-in over whole periods of the steady window; its phase (F = A cos(2 pi f t + phase)), "
        "its window error bar, the drive's amplitude and the window"
    )
    companions: ClassVar[dict[str, str]] = {
        "far_end_phase": "rad",
        "far_end_amplitude_error": "N",
        "drive_amplitude": "N",
        **WINDOW_FIELDS,
        "far_end_contact": "contact",
    }
    shares_reason = tuple(companions)
    table_fields = ("far_end_amplitude_error", "drive_amplitude", "steady_window_start", "steady_window_end")
    contact_field = "far_end_contact"
    field_kinds: ClassVar[dict[str, str]] = {"steady_window_periods": "integer"}
    shown = True

    def measure(self, scene, solution) -> Measurement:
        """The lock-in's amplitude, phase and error bar at the far end, the drive's amplitude, the window."""
        got = lock_far_end(scene, solution)
        if isinstance(got, str):
            return self.unmeasured(scene, solution, got)
        far, drive = got
        w = far.window
        fields = {
            "far_end_phase": float(far.phase[0]),
            "far_end_amplitude_error": float(far.error[0]),
            "drive_amplitude": float(drive.amplitude[0]),
            "steady_window_start": w.start,
            "steady_window_end": w.end,
            "steady_window_periods": w.periods,
            "far_end_contact": far_end_contact(scene),
        }
        return Measurement(float(far.amplitude[0]), fields, note=self.note(w))


class Transmission(_Spectral):
    """The far end's amplitude over the drive's, linear and in dB, with the window's error bars."""

    name = "transmission"
    unit = "1"
    definition = (
        "the far end's steady force amplitude over the drive's (far_end_amplitude / drive_amplitude); "
        "transmission_db = 20 log10 of it, the phase lag and both error bars (the window's)"
    )
    companions: ClassVar[dict[str, str]] = {
        "transmission_db": "dB",
        "transmission_error": "1",
        "transmission_db_error": "dB",
        "transmission_phase": "rad",
    }
    shares_reason = tuple(companions)
    table_fields = ("transmission_db", "transmission_error", "transmission_db_error")

    def measure(self, scene, solution) -> Measurement:
        """spectra.transmission of the far end's lock-in over the drive's."""
        got = lock_far_end(scene, solution)
        if isinstance(got, str):
            return self.unmeasured(scene, solution, got)
        far, drive = got
        tr = transmission(far, drive)
        fields = {
            "transmission_db": tr.db,
            "transmission_error": tr.ratio_error,
            "transmission_db_error": tr.db_error,
            "transmission_phase": tr.phase,
        }
        return Measurement(tr.ratio, fields, note=self.note(far.window))
