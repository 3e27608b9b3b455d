"""The observable registry: every place that names observables is made from it (issue 42 item 1).

An observable registered by a fixture (a dummy, `the_first_pulse_ratio`) must reach summary.json (its
value, its companion, its reason where unmeasured), the units and `granchain run`'s lines, compare's
rows, a campaign table's columns (its error column too) and a search predicate, and the error bars; the
real registry's names must be exactly those each place writes, and docs/observables.md must have the
registry's table as the registry makes it.
"""

from __future__ import annotations

import io
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest

from granchain.postprocess.comparison_table import compare_runs
from granchain.postprocess.observables import (
    END_PEAKS,
    NEEDS,
    OBSERVABLES,
    Measurement,
    Observable,
    end_summary_keys,
    registry_table,
    table_columns,
    units,
    with_error_bars,
)
from granchain.postprocess.observables.registry import DOCS_BEGIN, DOCS_END
from granchain.scene import parse_scene
from granchain.workflows.run import run_scene
from tests.scenegen import PEAKS, brass_text

DOCS = Path(__file__).resolve().parents[1] / "docs" / "observables.md"

#: a short struck chain the reference runs in well under a second
SCENE = brass_text(8, 'kind = "velocity"\nvelocity = 0.5\n', PEAKS)


class FirstPulseRatio(Observable):
    """A dummy: the window's last contact's largest complete peak over contact 1's, and that contact."""

    name = "the_first_pulse_ratio"
    unit = "1"
    definition = "a test's dummy"
    needs = frozenset({"peaks"})
    companions = {"the_first_pulse_contact": "contact"}
    shares_reason = ("the_first_pulse_contact",)
    table_fields = ("the_first_pulse_contact",)
    shown = True
    error_bar = "the companion runs' (a test's dummy)"

    def measure(self, scene, solution) -> Measurement:
        b = scene.window[1]
        done = np.asarray(solution.complete, dtype=bool)
        if not (done[0] and done[b - 1]):
            return Measurement(None, {"the_first_pulse_contact": None}, "a dummy's reason: not complete")
        ratio = float(solution.peak_force[b - 1] / solution.peak_force[0])
        return Measurement(ratio, {"the_first_pulse_contact": b})


@pytest.fixture
def dummy(monkeypatch):
    """The dummy registered after the real observables, as a new observable's row would be."""
    monkeypatch.setitem(OBSERVABLES, FirstPulseRatio.name, FirstPulseRatio())
    return FirstPulseRatio.name


@pytest.fixture(scope="module")
def scene():
    return parse_scene(SCENE)


#: the short chain on a wall with its event asked for: where the wall's event quantities apply
WALLED_EVENT = SCENE.replace(
    "[outputs]",
    '[boundary]\nfar_end = "wall"\n[outputs]\nevent = true\n'
    # the largest force over the event at chosen contacts and sensors (event_max_contact_force, ...)
    "sensors = [3]\nevent_max_contacts = [2, 5]\nevent_max_sensors = [3]",
)
#: a precompressed chain driven at 5 kHz (a third of its cutoff), for the spectral observables
DRIVEN = """[chain]
beads = 8
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "harmonic"
amplitude = 0.01
frequency = 5000.0
cycles = 8
ramp = 1
[precompression]
force = 10.0
[run]
end_time = 1.6e-3
timestep = 5e-7
"""


def test_every_registered_observable_keeps_the_rules(scene):
    """Each declares what the rules ask (base.Observable's docstring), applies to a plain chain (the
    wall's event quantities: to it on a wall, asking for the event; the free end's: to it asking for
    the event; the spectral ones: to a harmonic drive) and measures it there, with a value or a reason."""
    walled = parse_scene(WALLED_EVENT)
    free_event = parse_scene(SCENE.replace("[outputs]", "[outputs]\nevent = true"))  # a free end's event
    driven = parse_scene(DRIVEN)
    results = {s: run_scene(s, backend="reference") for s in (scene, walled, free_event, driven)}
    for name, obs in OBSERVABLES.items():
        where = next(s for s in results if obs.applies(s) is None)
        result = results[where]
        assert name == obs.name
        assert obs.unit, name
        assert obs.definition, name
        assert obs.applies_where, name
        assert obs.needs, name
        assert obs.needs <= NEEDS, name
        assert set(obs.shares_reason) <= set(obs.companions), name
        assert set(obs.table_fields) <= set(obs.companions) | {"leading_peak_contact"}, name
        assert obs.applies(where) is None, name
        m = obs.measure(where, result.solution)
        assert (m.value is None) == (m.reason is not None), name
        assert set(m.fields) <= set(obs.companions), name


def test_a_new_observable_reaches_the_summary_its_units_and_the_run_lines(scene, dummy):
    from granchain.cli.terminal import print_result

    result = run_scene(scene, backend="reference")
    summary = result.summary()
    assert dummy in summary["observables"]
    assert "the_first_pulse_contact" in summary["observables"]
    assert units()[dummy] == "1"
    assert dummy in {name for name, *_ in _shown(summary)}
    out = io.StringIO()
    with redirect_stdout(out):
        print_result(result, "run-dir")
    assert f"{dummy} (1)" in out.getvalue()
    assert "the_first_pulse_contact (contact)" in out.getvalue()


def _shown(summary):
    from granchain.results.tables import _key_observables

    return list(_key_observables(summary))


def test_a_new_observable_unmeasured_says_why(scene, dummy):
    """A run too short for its peaks: None, with the observable's own reason for it and its companion."""
    short = parse_scene(SCENE.replace('end_time = "auto"', "end_time = 1e-6"))
    result = run_scene(short, backend="reference")
    obs, missing = result.observables(), result.observables_missing()
    assert obs[dummy] is None
    assert obs["the_first_pulse_contact"] is None
    assert missing[dummy] == missing["the_first_pulse_contact"] == "a dummy's reason: not complete"


def test_a_new_observable_has_a_compare_row_and_an_error_bar(scene, dummy):
    result = run_scene(scene, backend="reference", method="verlet", error_estimate=True)
    rows = {row.quantity: row for row in compare_runs(result, result)}
    assert dummy in rows
    assert rows[dummy].unit == units()[dummy] == "1"  # dimensionless written one way (issue 43 item 7)
    assert dummy in with_error_bars()
    bar = result.errors.observables[dummy]
    assert bar["value"] == result.observables()[dummy]


def test_a_new_observable_is_a_campaign_column_and_a_predicate(tmp_path, dummy):
    import signac

    from granchain.campaigns import workspace as wsp
    from granchain.campaigns.spec import parse_campaign
    from granchain.campaigns.table import point_row

    ws = tmp_path / "ws"
    ws.mkdir()
    signac.init_project(str(ws))
    entry = {"params": {"loading.velocity": 0.5}, "job": f"{0:032x}", "key": None}
    record = {"kind": "grid", "code": {}, "points": [entry]}
    wsp.write_json(ws / wsp.RECORD, record)
    row = point_row(ws, record, entry, {})
    assert {dummy, f"{dummy}_error", "the_first_pulse_contact"} <= set(row)
    text = (
        '[campaign]\nbackend = "reference"\nkind = "search"\n[search]\nkey = "loading.velocity"\n'
        "range = [0.1, 1.0]\ntolerance = 0.1\n"
        f'predicate = {{ quantity = "{dummy}", op = ">", value = 1.0 }}\n[scene]\n' + SCENE.replace("\n[", "\n[scene.")
    )
    assert parse_campaign(text).search.predicate.quantity == dummy


def test_each_place_writes_exactly_the_registered_observables(scene, tmp_path):
    """summary.json's observables (besides the context), the units, compare's observable rows, the
    campaign columns and the error bars: the registry's names, no more and no fewer."""
    result = run_scene(scene, backend="reference")
    context = {"window", "leading_peak_contact", "static_force"}
    written = set(result.summary()["observables"]) - context
    companions = {k for obs in OBSERVABLES.values() for k in obs.companions}
    assert set(OBSERVABLES) <= written <= set(OBSERVABLES) | companions
    assert set(units()) == set(OBSERVABLES) | companions | context
    rows = {row.quantity for row in compare_runs(result, result)}
    assert {n for n, o in OBSERVABLES.items() if o.compared} <= rows
    assert set(table_columns()) - companions - context == set(OBSERVABLES)
    assert set(with_error_bars()) == {n for n, o in OBSERVABLES.items() if o.error_bar}


def _docs_table() -> str:
    text = DOCS.read_text()
    return text[text.index(DOCS_BEGIN) + len(DOCS_BEGIN) + 1 : text.index(DOCS_END)]


def test_docs_have_the_registry_table():
    assert _docs_table() == registry_table(), (
        f"docs/observables.md's table between {DOCS_BEGIN!r} and {DOCS_END!r} is not the registry's; paste:\n"
        + registry_table()
    )
    for name in OBSERVABLES:
        assert f"`{name}`" in _docs_table()


def test_the_docs_check_notices_an_observable_the_page_omits(dummy):
    assert _docs_table() != registry_table()


#: a short chain struck by a striker, on a wall: where both end peaks apply
STRUCK_WALLED = brass_text(
    6, 'kind = "striker"\nvelocity = 0.3\nradius = 4.76e-3\nmaterial = "brass"\n', PEAKS
).replace("[outputs]", '[boundary]\nfar_end = "wall"\n[outputs]')


@pytest.fixture(scope="module")
def struck_walled():
    return parse_scene(STRUCK_WALLED)


def test_every_end_peak_keeps_the_rules(struck_walled):
    """Each end peak (END_PEAKS) declares what base's rules ask, applies to a struck walled chain and
    measures its complete peak and time there, as the solution holds them; a plain chain's say why not."""
    result = run_scene(struck_walled, backend="reference")
    for name, obs in END_PEAKS.items():
        assert name == obs.name, name
        assert obs.unit == "N", name
        assert obs.definition, name
        assert obs.applies_where, name
        assert obs.needs <= NEEDS, name
        assert obs.time_field in obs.companions, name
        assert {name, obs.complete_field} <= set(obs.summary_keys), name
        assert obs.applies(struck_walled) is None, name
        assert obs.applies(parse_scene(SCENE)), name
        m = obs.measure(struck_walled, result.solution)
        assert m.value == getattr(result.solution, name), name
        assert m.fields == {obs.time_field: getattr(result.solution, obs.time_field)}, name


def test_each_place_names_exactly_the_end_peaks(struck_walled, tmp_path):
    """summary.json's top level and its check, a run loaded back, compare's rows and reasons, the
    error bars and the run's lines: the end peaks the registry has, no more and no fewer."""
    from granchain.cli.terminal import print_end_peaks
    from granchain.postprocess.comparison_table import PEAK_ROWS
    from granchain.workflows.errorbars.bars import END_PEAKS as BARS
    from granchain.workflows.load import load_run
    from granchain.workflows.summary_check import SUMMARY

    result = run_scene(struck_walled, backend="reference", out=tmp_path / "r")
    summary = result.summary()
    ends = set(end_summary_keys())
    assert {k for k in summary if k.startswith(("striker_", "wall_peak"))} == ends
    assert ends <= set(SUMMARY.fields)
    loaded = load_run(tmp_path / "r").solution
    for key in ends:
        assert getattr(loaded, key) == summary[key] == getattr(result.solution, key), key
    assert BARS == {n: o.time_field for n, o in END_PEAKS.items()}
    assert set(END_PEAKS) <= set(PEAK_ROWS)
    rows = {row.quantity for row in compare_runs(result, result)}
    assert set(END_PEAKS) <= rows
    out = io.StringIO()
    with redirect_stdout(out):
        print_end_peaks(result, summary, 0.0)
    for name in END_PEAKS:
        assert f"{name} (N)" in out.getvalue()


def test_an_end_peaks_words_come_from_its_registry_row(struck_walled, monkeypatch):
    """The run's lines and a figure's text say an end contact as its row says it (label): read from
    the registry, not named again by hand."""
    from granchain.cli.terminal import print_end_peaks
    from granchain.workflows.plots.figures import _end_peaks_text

    monkeypatch.setattr(type(END_PEAKS["wall_peak_force"]), "label", "the dummy far end's")
    result = run_scene(struck_walled, backend="reference")
    out = io.StringIO()
    with redirect_stdout(out):
        print_end_peaks(result, result.summary(), 0.0)
    assert "the dummy far end's contact peak" in out.getvalue()
    assert "the dummy far end's contact peak" in _end_peaks_text(result.summary(), struck_walled)
