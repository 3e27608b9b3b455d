"""The registry of observables (OBSERVABLES, the only list of them) and what is made from it: a run's
measured observables with their reasons and notes, their units, the columns of a campaign table, the
keys a short display shows and docs/observables.md's table.

A run's observables are measured the same way for every backend, from complete peaks and passed
leading pulses only (granchain.peaks): a contact the wave is still passing at the end of the run holds
a value that is still rising; it never feeds one. Each observable is None where it cannot be measured,
and the run says why (``observables_missing``).
"""

from __future__ import annotations

from typing import NamedTuple

from granchain.postprocess.observables.base import ONE_BEAD, Observable
from granchain.postprocess.observables.decay import LeadingPulseDecayExponent, LeadingPulseDecayLength
from granchain.postprocess.observables.event import WallEnergy, WallImpulse, WallMaxForce
from granchain.postprocess.observables.event_max import EventMaxContactForce, EventMaxSensorForce
from granchain.postprocess.observables.far_end import FarEndEnergy
from granchain.postprocess.observables.leading import LeadingPeakForce, LeadingPeakForceNondim
from granchain.postprocess.observables.max_peak import MaxPeakForce
from granchain.postprocess.observables.sensor import SensorObservable, SensorPeakForce, SensorTimeOfPeak
from granchain.postprocess.observables.spatial import SpatialDecay
from granchain.postprocess.observables.spectral import FarEndAmplitude, Transmission
from granchain.postprocess.observables.wave_speed import WaveSpeed

#: name -> observable, in the order summary.json writes them (see base for the rules of a new one)
OBSERVABLES: dict[str, Observable] = {
    o.name: o
    for o in (
        LeadingPeakForce(),
        LeadingPeakForceNondim(),
        WaveSpeed(),
        MaxPeakForce(),
        LeadingPulseDecayLength(),
        LeadingPulseDecayExponent(),
        WallMaxForce(),
        WallImpulse(),
        WallEnergy(),
        FarEndEnergy(),
        EventMaxContactForce(),
        EventMaxSensorForce(),
        FarEndAmplitude(),
        Transmission(),
        SpatialDecay(),
    )
}

#: name -> a sensor bead's quantity, in the order summary.json's ``sensors`` writes them: one value per
#: sensor bead each (SensorObservable.key), written under ``sensors``, not in ``observables``
SENSOR_OBSERVABLES: dict[str, SensorObservable] = {o.name: o for o in (SensorPeakForce(), SensorTimeOfPeak())}

#: what a run's observables carry besides the observables, where they are measured: the window (its
#: first and last contact), the contact the leading pulse is read at (the window's last) and, on a
#: precompressed chain, the static force F0 the forces are measured above (key -> unit)
CONTEXT_UNITS = {"window": "contacts", "leading_peak_contact": "contact", "static_force": "N"}
#: the context's JSON kinds (base.FIELD_KINDS): the window's first and last contact, a contact, a force
CONTEXT_KINDS = {"window": "integers", "leading_peak_contact": "integer", "static_force": "number"}

#: a chain of one bead's context, after its observables (as summary.json has always written it): no
#: window, no contact and no arrival to fit
_ONE_BEAD_CONTEXT = {"window": [], "leading_peak_contact": None, "wave_speed_contacts": 0}


class Measured(NamedTuple):
    """A run's observables (summary.json's ``observables``), why each that is None is unmeasured
    (``observables_missing``), what a measured one is where it is not what its name says
    (``observables_notes``), and those of ``missing`` that the scene can never measure, whatever the
    run (``observables_inapplicable``: Observable.applies, e.g. a wall's on a free chain)."""

    values: dict
    missing: dict
    notes: dict
    inapplicable: tuple[str, ...] = ()


def context(scene) -> dict:
    """Where a run's observables are measured (CONTEXT_UNITS), as summary.json writes it before them."""
    a, b = scene.window
    out: dict = {"window": [int(a), int(b)], "leading_peak_contact": int(b)}
    f0 = float(scene.effects.precompression)
    if f0:  # every contact carries F0 at rest: the observables' forces are the dynamic F - F0
        out["static_force"] = f0
    return out


def measure(scene, solution) -> Measured:
    """Every registered observable of a run: its value and companions, its reason, its note."""
    values = context(scene) if scene.n_contacts else {}
    missing: dict[str, str] = {}
    notes: dict[str, str] = {}
    inapplicable: list[str] = []
    for obs in OBSERVABLES.values():
        why = obs.applies(scene)
        if why is not None:
            inapplicable += [obs.name, *obs.shares_reason]
        m = obs.measure(scene, solution) if why is None else obs.unmeasured(scene, solution, why)
        values[obs.name] = m.value
        values.update(m.fields)
        if m.value is None:
            missing[obs.name] = m.reason
            missing.update(dict.fromkeys(obs.shares_reason, m.reason))
        elif m.note is not None:
            notes[obs.name] = m.note
    if not scene.n_contacts:
        values.update(_ONE_BEAD_CONTEXT)
    return Measured(values, missing, notes, tuple(inapplicable))


def measure_observables(scene, solution, missing: dict | None = None, notes: dict | None = None) -> dict:
    """The observables of a run (measure's values); `missing`, if given, gets name -> reason for each
    None; `notes`, if given, name -> what a measured value is where it is not what its name says."""
    m = measure(scene, solution)
    if missing is not None:
        missing.update(m.missing)
    if notes is not None:
        notes.update(m.notes)
    return m.values


def units() -> dict[str, str]:
    """Every key of a run's observables -> its unit ("1": dimensionless): the context's, each
    registered observable's and its companions'."""
    out = dict(CONTEXT_UNITS)
    for obs in OBSERVABLES.values():
        out[obs.name] = obs.unit
        out.update(obs.companions)
    return out


def kinds() -> dict[str, str]:
    """Every key of a run's observables -> its JSON kind (base.FIELD_KINDS; each may also be null): the
    context's and each registered observable's (Observable.kinds), which summary.json's check reads
    (workflows.summary_check), so that no observable's field goes unchecked."""
    out = dict(CONTEXT_KINDS)
    for obs in OBSERVABLES.values():
        out.update(obs.kinds())
    return out


def _with_contacts(observables: list[Observable], fields) -> tuple[str, ...]:
    """The observables' names, each followed by fields(obs), and the contact a group of observables
    read at one contact is read at (contact_field) after the last of the group."""
    out: list[str] = []
    for i, obs in enumerate(observables):
        out += [obs.name, *fields(obs)]
        after = observables[i + 1].contact_field if i + 1 < len(observables) else None
        if obs.contact_field and obs.contact_field != after and obs.contact_field not in out:
            out.append(obs.contact_field)
    return tuple(out)


def table_columns() -> tuple[str, ...]:
    """The observables' columns of a campaign table and the quantities a search predicate may test."""
    return _with_contacts(list(OBSERVABLES.values()), lambda o: o.table_fields)


def shown_keys() -> tuple[str, ...]:
    """The keys a result's short display shows (Observable.shown, with their contacts)."""
    return _with_contacts([o for o in OBSERVABLES.values() if o.shown], lambda o: ())


def with_error_bars() -> tuple[str, ...]:
    """The observables that get an error bar (Observable.error_bar)."""
    return tuple(name for name, obs in OBSERVABLES.items() if obs.error_bar is not None)


#: the lines around docs/observables.md's generated table (registry_table)
DOCS_BEGIN = "<!-- registry_table: generated from granchain.postprocess.observables.OBSERVABLES -->"
DOCS_END = "<!-- end of registry_table -->"


def registry_table() -> str:
    """docs/observables.md's table of the registered observables, between DOCS_BEGIN and DOCS_END
    (tests/test_observable_registry.py checks that the page has it as it is, and its failure shows the
    table to paste)."""
    rows = [
        "| observable (unit) | definition | applies to | reads | error bar | also written |",
        "|---|---|---|---|---|---|",
    ]
    for obs in OBSERVABLES.values():
        also = ", ".join(f"`{k}` ({u})" for k, u in obs.companions.items()) or "-"
        rows.append(
            f"| `{obs.name}` ({obs.unit}) | {obs.definition} | {obs.applies_where} | {', '.join(sorted(obs.needs))} | "
            f"{obs.error_bar or 'none'} | {also} |"
        )
    return "\n".join(rows) + "\n"


__all__ = [
    "ONE_BEAD",
    "OBSERVABLES",
    "SENSOR_OBSERVABLES",
    "Measured",
    "kinds",
    "measure",
    "measure_observables",
    "units",
]
