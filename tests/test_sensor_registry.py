"""The sensor beads' quantities are registered observables (registry.SENSOR_OBSERVABLES: name, unit,
definition, needs, where they apply), and the places that report them read the registry: the compare
rows, ``granchain run``'s lines, the campaign table's columns and summary.json's check follow a
registered quantity's declarations (a unit changed in the registry shows there), not a table of their
own (postprocess.sensors' SENSOR_QUANTITIES, read by three modules before)."""

from __future__ import annotations

import pytest

from granchain.postprocess.observables import NEEDS, SENSOR_OBSERVABLES
from granchain.postprocess.observables.sensor import SensorObservable
from granchain.postprocess.sensors import sensor_key
from granchain.scene import parse_scene
from granchain.workflows.run import run_reference

from .test_sensors import scene_text


@pytest.fixture(scope="module")
def run():
    """A free 6-bead chain with sensor beads 2 and 5 (the reference's Verlet)."""
    scene = parse_scene(scene_text(6, wall=False, sensors=(2, 5), end=6e-5), source="registry.toml")
    return run_reference(scene, "verlet")


def test_each_sensor_quantity_declares_what_an_observable_does():
    free = parse_scene(scene_text(6, wall=False, sensors=(), end=6e-5), source="none.toml")
    with_sensors = parse_scene(scene_text(6, wall=False, sensors=(2,), end=6e-5), source="some.toml")
    assert list(SENSOR_OBSERVABLES) == ["sensor_peak_force", "sensor_time_of_peak"]  # summary.json's order
    for name, obs in SENSOR_OBSERVABLES.items():
        assert isinstance(obs, SensorObservable)
        assert obs.name == name
        assert obs.unit
        assert obs.definition
        assert obs.needs <= NEEDS
        assert "sensors" in obs.applies(free)
        assert obs.applies(with_sensors) is None
        assert obs.key(3) == sensor_key(name, 3) == f"{name}_bead_3"


def test_the_places_that_report_sensors_read_the_registrys_declarations(run, monkeypatch, capsys):
    """A unit changed in the registry is the compare row's and the printed line's unit, and a quantity
    left out of it leaves the campaign columns."""
    from granchain.campaigns.table import _sensor_columns
    from granchain.cli.terminal import print_sensors
    from granchain.postprocess.comparison_table import compare_runs

    monkeypatch.setattr(SENSOR_OBSERVABLES["sensor_time_of_peak"], "unit", "fortnights")
    rows = {row.quantity: row for row in compare_runs(run, run)}
    assert rows["sensor_time_of_peak_bead_2"].unit == "fortnights"
    assert rows["sensor_peak_force_bead_5"].unit == "N"
    print_sensors(run.summary)
    assert "sensor_time_of_peak_bead_5 (fortnights)" in capsys.readouterr().out
    summary = run.summary
    monkeypatch.delitem(SENSOR_OBSERVABLES, "sensor_time_of_peak")
    columns = _sensor_columns(summary)
    assert "sensor_peak_force_bead_2" in columns
    assert not any(k.startswith("sensor_time_of_peak") for k in columns)
