"""Scalar observables of a run, measured the same way for every backend, from complete peaks only:
one small class each (base.Observable says how to write one), registered in registry.OBSERVABLES,
the only list of them (docs/observables.md).

A peak feeds an observable only once it has passed: the largest peak (max_peak_force) once it is
complete (granchain.peaks.complete_peaks: the force has fallen to half of it since), the leading
pulse once its first maximum is behind it (granchain.peaks.leading_pulse). Each observable is None
where it cannot be measured; measure says why (``observables_missing``) and, where a measured value
is not quite what its name says, what it is (``observables_notes``).
"""

from __future__ import annotations

from granchain.postprocess.observables.base import FIELD_KINDS, NEEDS, ONE_BEAD, Measurement, Observable
from granchain.postprocess.observables.ends import END_PEAKS, EndPeak, end_summary, end_summary_keys
from granchain.postprocess.observables.fit import (
    FIT_CONTACTS,
    fit_wave_speed,
    front_arrivals,
    section_speeds,
    wave_speed_unmeasurable,
)
from granchain.postprocess.observables.leading import LeadingPeakForce, LeadingPeakForceNondim
from granchain.postprocess.observables.max_peak import MaxPeakForce
from granchain.postprocess.observables.registry import (
    CONTEXT_UNITS,
    OBSERVABLES,
    SENSOR_OBSERVABLES,
    Measured,
    kinds,
    measure,
    measure_observables,
    registry_table,
    shown_keys,
    table_columns,
    units,
    with_error_bars,
)
from granchain.postprocess.observables.unmeasured import unmeasured_outputs
from granchain.postprocess.observables.wave_speed import WaveSpeed
from granchain.postprocess.observables.windows import (
    _ALIKE,
    _NAMED_STRETCHES,
    PERIODIC_CELLS,
    _shortest_cell,
    _window_bead_keys,
    _window_beads,
    _window_contacts,
    contact_kinds,
    periodic_cell,
    uniform_sections,
)

__all__ = [
    "CONTEXT_UNITS",
    "END_PEAKS",
    "EndPeak",
    "end_summary",
    "end_summary_keys",
    "FIELD_KINDS",
    "FIT_CONTACTS",
    "NEEDS",
    "OBSERVABLES",
    "ONE_BEAD",
    "PERIODIC_CELLS",
    "SENSOR_OBSERVABLES",
    "LeadingPeakForce",
    "LeadingPeakForceNondim",
    "MaxPeakForce",
    "Measured",
    "Measurement",
    "Observable",
    "WaveSpeed",
    "_ALIKE",
    "_NAMED_STRETCHES",
    "_shortest_cell",
    "_window_bead_keys",
    "_window_beads",
    "_window_contacts",
    "contact_kinds",
    "fit_wave_speed",
    "kinds",
    "front_arrivals",
    "measure",
    "measure_observables",
    "periodic_cell",
    "registry_table",
    "section_speeds",
    "shown_keys",
    "table_columns",
    "unmeasured_outputs",
    "uniform_sections",
    "units",
    "wave_speed_unmeasurable",
    "with_error_bars",
]
