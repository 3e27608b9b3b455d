"""The spatial decay of a harmonic drive's steady amplitude along the chain (issue 46 item 2): every
contact's force locked in at the drive's frequency, ln A fitted against the cell index.

A harmonic scene records every bead-bead contact's force history by itself (the scene reader,
scene.reader._driven_outputs: N - 1 columns at the planner's HISTORY_SAMPLES_PER_PERIOD samples a
period, 8 (N - 1) x 32 bytes a drive period: 0.2 MB for 20 beads and 40 periods). The chain's period
p (physics.bands.periodic_cell of its masses and linearised springs; p = 1 on a uniform chain, and on
a chain that repeats no cell, whose rate is then per contact) makes the unit of the fit: by Bloch's
theorem the contact at the same place of successive cells carries the force multiplied by exp(i q)
(Brillouin, *Wave Propagation in Periodic Structures*, 1946, ch. IV), so

    ln A_c = b_s - mu n,    c = n p + s + 1 (cell n, place s in the cell),

one slope mu (the decay per cell, nepers: Im q in a gap, physics.bands.decay_per_cell) and one
intercept b_s per place in the cell, by least squares. The fit reads the first half of the bead-bead
contacts only: the far end's reflection, growing as exp(+mu n) towards it, is there below exp(-mu L)
of the incident wave (L the chain's length in cells), and it stops before the first contact whose
amplitude is within 3 of its window error bar (a signal lost in the transients left by the switch-on
or in round-off: the note says where). Its error bars: the fit's standard error (residuals over n -
p - 1 degrees of freedom) and the window's |mu(window) - mu(window's last half)|, the lock-ins'
finite window as spectra.lock_in's bar; spatial_decay_error is both in quadrature. The time step's
share is the error estimate's (errors.json): its companion runs at 2 dt and 4 dt keep every contact's
history (workflows.errorbars.facts.companion_scene) and fit the same contacts over the same window.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from granchain.physics.bands import periodic_cell
from granchain.physics.estimates import linearised_stiffnesses
from granchain.postprocess.observables.base import Measurement
from granchain.postprocess.observables.spectral import STEP_SHARE, _Spectral, settled_window
from granchain.postprocess.spectra import MIN_PERIODS, SpectraError, SteadyWindow, lock_in

#: a contact's amplitude within this many of its window error bar ends the fit (its signal is lost)
SIGNAL_TO_BAR = 3.0
#: the fewest cells the fit needs (its standard error has then n - p - 1 >= 1 degrees of freedom)
MIN_CELLS = 3


def chain_period(scene) -> int:
    """The chain's period in beads (physics.bands.periodic_cell of its masses and linearised springs), 1
    where it repeats none (the fit is then per contact)."""
    k, _ = linearised_stiffnesses(scene)
    return periodic_cell(np.asarray(scene.bead_masses, dtype=float), k) or 1


def fit_decay(contacts, amplitudes, period: int) -> tuple[float, float]:
    """(mu, its standard error) of ln A_c = b_s - mu n over contacts c (1-based), n = (c - 1) // period
    the cell, s = (c - 1) % period the place (the module docstring's fit)."""
    c = np.asarray(contacts, dtype=int) - 1
    cell, place = c // period, c % period
    places = np.unique(place)
    basis = np.column_stack([-cell.astype(float)] + [(place == s).astype(float) for s in places])
    y = np.log(np.asarray(amplitudes, dtype=float))
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    dof = y.size - basis.shape[1]
    if dof < 1:
        return float(coef[0]), math.inf
    s2 = float(np.sum((y - basis @ coef) ** 2)) / dof
    cov = s2 * np.linalg.inv(basis.T @ basis)
    return float(coef[0]), math.sqrt(max(float(cov[0, 0]), 0.0))


def _locked(scene, solution, win: SteadyWindow):
    """(contacts 1-based, amplitudes over the window, over its last half, window bars) of the fitted
    half of the chain, or why not."""
    recorded = [int(i) for i in solution.history_contacts]
    half = [c for c in range(1, scene.n_contacts // 2 + 1)]
    absent = [c for c in half if c - 1 not in recorded]
    if absent:
        return (
            f"contact {absent[0]}'s history was not recorded: a harmonic scene records every contact's by "
            f"itself; a scene written without it needs [outputs] histories = [1, ..., {scene.n_contacts}]"
        )
    if win.periods // 2 < MIN_PERIODS:
        return (
            f"the steady window holds {win.periods} whole period(s): the window bar fits its last half again, "
            f"which needs {2 * MIN_PERIODS} periods or more; drive longer ([loading] cycles or duration)"
        )
    t = np.asarray(solution.history_time, dtype=float)
    spacing = float(np.median(np.diff(t)))
    keep = (t >= win.start - 0.5 * spacing) & (t < win.end - 1e-9 * spacing)
    last = SteadyWindow(win.end - (win.periods // 2) / win.frequency, win.end, win.periods // 2, win.frequency)
    force = np.asarray(solution.history_force, dtype=float)[keep] - float(scene.effects.precompression)
    whole, second, bars = [], [], []
    for c in half:
        x = force[:, recorded.index(c - 1)]
        a = lock_in(t[keep], x, win.frequency, window=win)
        whole.append(float(a.amplitude[0]))
        bars.append(float(a.error[0]))
        second.append(float(lock_in(t[keep], x, win.frequency, window=last).amplitude[0]))
    return half, np.array(whole), np.array(second), np.array(bars)


class SpatialDecay(_Spectral):
    """The decay per cell of the steady amplitude along the chain, from every contact's lock-in."""

    name = "spatial_decay"
    unit = "Np/cell"
    definition = (
        "the decay per cell mu of the contacts' steady force amplitudes at the drive's frequency (ln A = b - mu n "
        "over the first half of the chain, one intercept per place in the cell: Im q in a band gap), its dB, "
        "error bars (the fit's, the window's, both) and the cell and contacts fitted"
    )
    companions: ClassVar[dict[str, str]] = {
        "spatial_decay_db": "dB/cell",
        "spatial_decay_error": "Np/cell",
        "spatial_decay_fit_error": "Np/cell",
        "spatial_decay_window_error": "Np/cell",
        "spatial_decay_cell": "beads",
        "spatial_decay_contacts": "contacts",
    }
    shares_reason = tuple(companions)
    table_fields = ("spatial_decay_db", "spatial_decay_error")
    field_kinds: ClassVar[dict[str, str]] = {"spatial_decay_cell": "integer", "spatial_decay_contacts": "integers"}
    error_bar = (
        "the time step's error from the companion runs (each keeps every contact's history and fits the same "
        "window); the fit's and the window's bars are the *_error companions"
    )
    applies_where = (
        'a precompressed chain under [loading] kind = "harmonic" whose first half holds 3 cells of its period '
        "(7 beads or more on a uniform chain, 13 on a dimer)"
    )

    def applies(self, scene) -> str | None:
        """As the other spectral observables, and a chain holding MIN_CELLS cells in its first half."""
        why = super().applies(scene)
        if why is not None:
            return why
        p = chain_period(scene)
        if scene.n_contacts // 2 < MIN_CELLS * p:
            return (
                f"the fit reads the first half of the chain, {scene.n_contacts // 2} contact(s), fewer than "
                f"{MIN_CELLS} cells of {p} bead(s); give [chain] beads >= {2 * MIN_CELLS * p + 1}"
            )
        return None

    def measure(self, scene, solution) -> Measurement:
        """The fit over the window and over its last half, both bars, the cell and contacts fitted."""
        try:
            win = settled_window(scene, np.asarray(solution.history_time, dtype=float))
            got = _locked(scene, solution, win)
        except SpectraError as e:
            return self.unmeasured(scene, solution, f"the contacts' force histories cannot be locked in: {e}")
        if isinstance(got, str):
            return self.unmeasured(scene, solution, got)
        contacts, whole, second, bars = got
        lost = np.flatnonzero(whole <= SIGNAL_TO_BAR * bars)
        used = int(lost[0]) if lost.size else len(contacts)
        p = chain_period(scene)
        if used < MIN_CELLS * p:
            where = contacts[used] if used < len(contacts) else None
            return self.unmeasured(
                scene,
                solution,
                f"contact {where}'s amplitude is within {SIGNAL_TO_BAR:g} of its window error bar, leaving fewer "
                f"than {MIN_CELLS} cells of {p} bead(s) to fit; drive longer (more periods settle the chain) or add "
                "[damping] to quiet the switch-on's ringing",
            )
        mu, fit_err = fit_decay(contacts[:used], whole[:used], p)
        mu_half, _ = fit_decay(contacts[:used], second[:used], p)
        window_err = abs(mu - mu_half)
        fields = {
            "spatial_decay_db": 20 * mu / math.log(10),
            "spatial_decay_error": math.hypot(fit_err, window_err),
            "spatial_decay_fit_error": fit_err,
            "spatial_decay_window_error": window_err,
            "spatial_decay_cell": p,
            "spatial_decay_contacts": [int(contacts[0]), int(contacts[used - 1])],
        }
        lost_note = f"; contact {contacts[used]} on lost in its window bar" if used < len(contacts) else ""
        note = (
            f"ln A fitted over contacts {contacts[0]}..{contacts[used - 1]} in cells of {p} bead(s){lost_note}; "
            f"lock-ins at the drive's frequency over {win.periods} whole periods, t = {win.start:.6g} to "
            f"{win.end:.6g} s; its bars: the fit's standard error and the window's |mu(window) - mu(last half)|; "
            f"{STEP_SHARE}"
        )
        return Measurement(mu, fields, note=note)
