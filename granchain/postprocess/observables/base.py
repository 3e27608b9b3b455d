"""The base class of an observable, and the rules for writing a new one.

An observable is one scalar number a run reports in summary.json's ``observables`` (the leading peak,
the wave speed, ...): one small class in this package and one row of the registry
(granchain.postprocess.observables.registry.OBSERVABLES, the only list of observables). Every place
that names observables reads them from the registry: summary.json's ``observables``,
``observables_missing`` and ``observables_notes`` (registry.measure), the units (results.tables
OBSERVABLE_UNITS, which ``granchain run``'s lines and a result's display print), ``compare``'s rows
(postprocess.comparison_table), the campaign table's columns and a search predicate's quantities
(campaigns.table, campaigns.spec), the error bars (workflows.errorbars) and docs/observables.md's
table of registered observables (registry.registry_table; tests/test_observable_registry.py checks
that every one of those places has every registered observable).

Rules for writing a new observable:

1. Subclass Observable and set the class attributes: ``name`` (its key in summary.json, a campaign
   column's name: the paper's words, snake_case), ``unit`` ("N", "m/s", "1" for a dimensionless
   number), ``definition`` (one line in words: docs/observables.md's table shows it), ``needs`` (what
   it reads from a ChainSolution, a subset of NEEDS), ``companions`` (the other keys it writes beside
   its value, name -> unit, in the order summary.json writes them), ``shares_reason`` (those of the
   companions that are None with it, with its reason, where it is unmeasured), ``table_fields`` (the
   companions a campaign table carries as columns after it), ``contact_field`` (the key naming the
   contact it is read at, if any: a context key or a companion), ``shown`` (whether a result's short
   display shows it), ``field_kinds`` (the JSON kind of each companion that is not a number or, for
   a contact or a bead, a whole number: FIELD_KINDS, which summary.json's check reads), ``asked``
   (whether a run that ends before measuring it says so: unmeasured
   outputs, the command line's exit 1), ``compared`` (whether ``granchain compare`` has a row for it).
2. ``applies(scene)``: None where the scene can measure it, else the reason it never can, whatever
   the run (the base class: a chain of one bead has no bead-bead contact); ``applies_where`` says
   where it applies in words. ``measure(scene, solution)``
   returns a Measurement: the value and its companions, or None and the reason it is unmeasured in
   this run (the wave had not passed yet: say what to do), and a note where the value is not quite
   what its name says (a wave speed averaged over unlike contacts). Read only complete peaks and
   passed leading pulses (granchain.peaks): both backends track those alike, step for step. Where it
   does not apply, ``unmeasured(scene, solution, reason)`` gives its entry (the base class: None for
   it and for ``shares_reason``).
3. Forces are dynamic on a precompressed chain: the rise above the static force F0 that every contact
   carries at rest (the registry's context gives F0 as ``static_force``).
4. Its error bar's route (``error_bar``: None for no bar, else in words how the time step's error is
   measured): the companion runs at 2 dt and 4 dt (and dt / 2 where checked) measure it as the run
   does and workflows.errorbars extrapolates it. Say what the extrapolation needs: ``at_leading_pulse``
   (the value is read at the window's last contact's leading pulse: the companions' must be the same
   pulse), ``roundoff_floor(measured, floor, b)`` (the round-off under which its difference between
   runs is noise), ``fit_stderr`` (a companion holding a fit's standard error, added in quadrature).
5. Register an instance in granchain/postprocess/observables/registry.py (OBSERVABLES, in the order
   summary.json writes them) and run tests/test_observable_registry.py, which says which place lacks
   it; docs/observables.md's generated table is registry_table()'s text.
"""

from __future__ import annotations

from typing import Any, ClassVar, NamedTuple

import numpy as np

#: what an observable may read from a solution (Observable.needs): the per-contact peaks (peak_force,
#: time_of_peak, complete), the leading pulses (leading_pulse_force, leading_pulse_time), the fronts'
#: half-amplitude arrivals (front_time), recorded histories, the state at the end of the run, the
#: far-end wall's event (granchain.physics.event: its sums and end, tracked at every step)
NEEDS = frozenset({"peaks", "leading_pulses", "fronts", "histories", "end_state", "event"})

#: why no observable of a bead-bead contact applies to one bead
ONE_BEAD = "one bead has no bead-bead contact: its contact's peak is the striker's or the wall's"
#: why no observable of the leading pulse (Observable.needs "leading_pulses") applies under a harmonic drive
HARMONIC_DRIVE = (
    "a harmonic drive makes a steady wave train, not a leading pulse: read the contacts' peak forces and "
    "histories (the leading-pulse observables are those of a step, an impulse, a kick or a striker)"
)


#: the JSON kinds an observable's value and companions take in summary.json (Observable.kinds): a
#: number, a whole number, a list of numbers, a list of whole numbers (a range of contacts), a list
#: of fitted stretches ({contacts, speed, stderr, arrivals}: the wave speed's sections)
FIELD_KINDS = ("number", "integer", "numbers", "integers", "sections")


class Measurement(NamedTuple):
    """What an observable measured in one run: its value (None where unmeasured), its companions'
    values (Observable.companions, in order), why the value is None, and a note on what a measured value
    is where it is not what its name says."""

    value: Any
    fields: dict
    reason: str | None = None
    note: str | None = None


class Observable:
    """One scalar observable of a run (see the module docstring for the rules of writing one)."""

    name: ClassVar[str]
    unit: ClassVar[str]
    definition: ClassVar[str]
    needs: ClassVar[frozenset[str]]
    companions: ClassVar[dict[str, str]] = {}
    shares_reason: ClassVar[tuple[str, ...]] = ()
    table_fields: ClassVar[tuple[str, ...]] = ()
    contact_field: ClassVar[str | None] = None
    shown: ClassVar[bool] = False
    asked: ClassVar[bool] = False
    compared: ClassVar[bool] = True
    error_bar: ClassVar[str | None] = None
    #: where applies(scene) is None, in words (docs/observables.md's table)
    applies_where: ClassVar[str] = "a chain of two beads or more (one bead-bead contact at least)"
    at_leading_pulse: ClassVar[bool] = False
    fit_stderr: ClassVar[str | None] = None
    #: the JSON kind of each companion that is not a number (FIELD_KINDS), as summary.json writes it;
    #: a companion of unit "contact" or "bead" is an "integer" unless named here (kinds())
    field_kinds: ClassVar[dict[str, str]] = {}

    def kinds(self) -> dict[str, str]:
        """Its value's and every companion's JSON kind (FIELD_KINDS), in summary.json's order: the value
        a number, a companion per field_kinds, else "integer" for a contact or a bead, else a number.
        workflows.summary_check checks a loaded summary.json's ``observables`` against them (each may
        also be null: unmeasured)."""
        out = {self.name: "number"}
        for key, unit in self.companions.items():
            out[key] = self.field_kinds.get(key, "integer" if unit in ("contact", "bead") else "number")
        return out

    def applies(self, scene) -> str | None:
        """None where the scene can measure the observable, else why it never can (one bead; a
        leading pulse's observable under a harmonic drive)."""
        if not scene.n_contacts:
            return ONE_BEAD
        return HARMONIC_DRIVE if "leading_pulses" in self.needs and scene.loading.is_harmonic else None

    def measure(self, scene, solution) -> Measurement:
        """The value in this run, or None and why (applies(scene) is None here)."""
        raise NotImplementedError

    def unmeasured(self, scene, solution, reason: str) -> Measurement:
        """The entry of a scene it does not apply to (reason: applies'): None, for it and shares_reason."""
        return Measurement(None, dict.fromkeys(self.shares_reason), reason)

    def roundoff_floor(self, measured: dict, floor: np.ndarray, b: int) -> float | None:
        """The round-off of the value in a run (floor: each contact's peak force's, N; b: the window's
        last contact, 0-based; measured: the run's observables), or None where it has none."""
        return None
