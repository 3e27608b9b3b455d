"""summary.json's schema, checked once when a run directory is read back (granchain.load_run).

A run directory may come from someone else (a shared filesystem, a colleague's tarball): its
summary.json is checked against the fields RunResult and its displays use before anything reads
them, so that a value of the wrong type (``provenance`` a list, ``wall_time`` a string, ``plan: {}``,
a date that is not ISO 8601, nesting 10^5 deep) is one error naming the field, never an exception
further in. Fields granchain does not read are not checked (a newer granchain's summary loads).
"""

from __future__ import annotations

from datetime import datetime

from granchain.postprocess.observables import END_PEAKS, FIELD_KINDS, SENSOR_OBSERVABLES, kinds, with_error_bars

#: the deepest nesting granchain writes is about 5 (errors.observables.<name>.<field>); far deeper is
#: not granchain's and would exhaust the stack of whatever walks it (copy.deepcopy, repr)
MAX_DEPTH = 64


class SummaryFieldError(ValueError):
    """A field of summary.json that is not what granchain writes: ``field`` (dotted) and why."""

    def __init__(self, field: str, why: str):
        super().__init__(f"{field}: {why}")
        self.field = field


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _integer(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _iso_time(v) -> bool:
    if not isinstance(v, str):
        return False
    try:
        datetime.fromisoformat(v)
    except ValueError:
        return False
    return True


NUMBER = (_number, "a number")
INTEGER = (_integer, "a whole number")
TEXT = (lambda v: isinstance(v, str), "text")
FLAG = (lambda v: isinstance(v, bool), "true or false")
TIME = (_iso_time, "an ISO 8601 time (2025-01-31T12:00:00.000+00:00)")
ANY = (lambda v: True, "anything")


class Optional_:
    """A field that may also be null."""

    def __init__(self, spec):
        self.spec = spec


class MapOf:
    """A JSON object whose every value is ``spec``."""

    def __init__(self, spec):
        self.spec = spec


class ListOf:
    """A JSON list whose every item is ``spec``."""

    def __init__(self, spec):
        self.spec = spec


class Record:
    """A JSON object with the named fields (``required`` must be there; others may be absent; fields
    not named are not checked)."""

    def __init__(self, fields: dict, required: tuple[str, ...] = ()):
        self.fields, self.required = fields, required


def opt(spec):
    """spec or null."""
    return Optional_(spec)


_PLAN = Record(
    {
        "method": TEXT,
        "rtol": NUMBER,
        "omega_max": NUMBER,
        "stable_timestep": NUMBER,
        "choices": ListOf(Record({"name": TEXT, "value": NUMBER, "reason": TEXT}, ("name", "value", "reason"))),
    },
    ("method", "rtol", "omega_max", "stable_timestep", "choices"),
)

_PROVENANCE = Record(
    {
        "started_utc": TIME,
        "start_time": TEXT,
        "finished_utc": opt(TIME),
        "command": opt(ListOf(TEXT)),
        "plan": opt(_PLAN),
        "collected": Record({}),
    }
)

#: each JSON kind an observable's field takes (postprocess.observables.FIELD_KINDS) -> its spec here
KIND_SPECS = {
    "number": NUMBER,
    "integer": INTEGER,
    "numbers": ListOf(NUMBER),
    "integers": ListOf(INTEGER),
    "sections": ListOf(
        Record({"contacts": ListOf(INTEGER), "speed": NUMBER, "stderr": opt(NUMBER), "arrivals": INTEGER})
    ),
}
assert set(KIND_SPECS) == set(FIELD_KINDS), "a kind of observable field without its spec here"

#: summary.json's ``observables``: every key the registry declares (the context's and each observable's
#: value and companions, postprocess.observables.kinds), of its kind or null; a key it does not declare is
#: not checked (a newer granchain's observable loads)
_OBSERVABLES = Record({key: opt(KIND_SPECS[kind]) for key, kind in kinds().items()})

#: one number's error bar (errors.observables.<name>, errors.end_peaks.<name>)
_BAR = Record(
    {
        "value": opt(NUMBER),
        "error": opt(NUMBER),
        "status": TEXT,
        "step_error": opt(NUMBER),
        "fit_stderr": opt(NUMBER),
        "step_error_bound": opt(NUMBER),
    }
)

_ERRORS = Record({"observables": Record({name: opt(_BAR) for name in with_error_bars()}), "end_peaks": MapOf(_BAR)})

#: summary.json's ``sensors`` (postprocess.sensors.sensor_summary): the beads, their static forces, each
#: quantity bead by bead (null where unmeasured), why each null is, the note
_SENSORS = Record(
    {
        "beads": ListOf(INTEGER),
        "static_force": ListOf(NUMBER),
        **{q: ListOf(opt(NUMBER)) for q in SENSOR_OBSERVABLES},
        "missing": MapOf(opt(TEXT)),
        "note": TEXT,
    }
)

#: the fields of summary.json that load_run, RunResult and its displays read
SUMMARY = Record(
    {
        "title": opt(TEXT),
        "scene_source": opt(TEXT),
        "backend": TEXT,
        "method": TEXT,
        "method_reason": opt(TEXT),
        "timestep": NUMBER,
        "steps": INTEGER,
        "end_time": NUMBER,
        "beads": INTEGER,
        "contact_law": TEXT,
        "loading": TEXT,
        "wall_time": NUMBER,
        "observables": _OBSERVABLES,
        "observables_missing": MapOf(TEXT),
        "observables_inapplicable": ListOf(TEXT),
        "observables_notes": MapOf(TEXT),
        "peaks": MapOf(INTEGER),
        "conservation": MapOf(opt(NUMBER)),
        # the end contacts' peaks (postprocess.observables.ends): whether each is a peak, and numbers
        **{k: opt(FLAG if k == o.complete_field else NUMBER) for o in END_PEAKS.values() for k in o.summary_keys},
        "event": MapOf(opt(NUMBER)),
        "event_maxima": MapOf(ListOf(NUMBER)),
        "sensors": _SENSORS,
        "extra": Record({}),
        "error_estimate": opt(NUMBER),
        "errors": opt(_ERRORS),
        "price": Record({"steps": INTEGER, "not_timed": MapOf(TEXT)}),
        "provenance": _PROVENANCE,
    },
    ("backend", "method", "timestep", "steps", "end_time", "wall_time"),
)


def _depth_at_most(value, limit: int) -> bool:
    """Whether value nests no deeper than limit (walked without recursion)."""
    stack = [(value, 1)]
    while stack:
        v, depth = stack.pop()
        if isinstance(v, (dict, list)):
            if depth > limit:
                return False
            stack.extend((x, depth + 1) for x in (v.values() if isinstance(v, dict) else v))
    return True


def _describe(v) -> str:
    text = repr(v)
    return text if len(text) <= 60 else text[:57] + "..."


def _check(value, spec, where: str) -> None:
    if isinstance(spec, Optional_):
        if value is not None:
            _check(value, spec.spec, where)
        return
    if isinstance(spec, tuple):
        test, what = spec
        if not test(value):
            raise SummaryFieldError(where, f"{_describe(value)} is not {what}")
        return
    if isinstance(spec, ListOf):
        if not isinstance(value, list):
            raise SummaryFieldError(where, f"{_describe(value)} is not a list")
        for k, item in enumerate(value):
            _check(item, spec.spec, f"{where}[{k}]")
        return
    if not isinstance(value, dict):
        raise SummaryFieldError(where, f"{_describe(value)} is not a JSON object")
    if isinstance(spec, MapOf):
        for k, item in value.items():
            _check(item, spec.spec, f"{where}.{k}")
        return
    for name in spec.required:
        if name not in value:
            raise SummaryFieldError(f"{where}.{name}" if where else name, "missing")
    for name, sub in spec.fields.items():
        if name in value:
            _check(value[name], sub, f"{where}.{name}" if where else name)


def check_summary(summary) -> None:
    """Raise SummaryFieldError (its ``field`` dotted, e.g. ``provenance.plan.rtol``) unless summary
    (summary.json as parsed) has the fields granchain reads, of the types it writes them with."""
    if not isinstance(summary, dict):
        raise SummaryFieldError("(the whole file)", "not a JSON object")
    if not _depth_at_most(summary, MAX_DEPTH):
        raise SummaryFieldError("(the whole file)", f"nested deeper than {MAX_DEPTH} levels")
    _check(summary, SUMMARY, "")
