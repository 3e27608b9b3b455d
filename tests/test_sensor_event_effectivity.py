"""Error bars on the sensor beads and the far end's event against their true error (issue 42's
acceptance: "error bars on the new observables within [1/3, 3] of the true error, or a status that
says why"), as tests/test_event.py checks the wall's event quantities.

The bars are the companions' (2 dt and 4 dt, extrapolated); the true error is the distance to a run
of the same planned scene at dt / 8 (Verlet, order 2: that run's own error is 1/64 of the run's).
Checked: each sensor bead's dynamic peak and its time, far_end_energy (a free far end), and the
largest force over the wall's event at chosen contacts and sensors (event_max_contact_force,
event_max_sensor_force).
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from granchain.backends.builtin import ReferenceBackend
from granchain.postprocess.sensors import sensor_key, sensor_values
from granchain.scene import parse_scene
from granchain.workflows.run import run_scene
from tests.test_event_max import CHOSEN
from tests.test_far_end_event import STRUCK_FREE

#: a bar this far from the true error, either way, fails (the issue's [1/3, 3])
FACTOR = 3.0
#: the true error's run: the planned step over this
FINER = 8

#: six brass beads struck by a brass striker, free far end (bead N leaves before 6e-4 s), two sensors
FREE_SENSORS = STRUCK_FREE.replace('end_time = "auto"', "end_time = 6e-4").replace(
    "event = true", "event = true\nsensors = [2, 5]"
)


def run_and_truth(text: str):
    """The run with its companions' bars, and the same planned scene at dt / FINER."""
    result = run_scene(parse_scene(text), backend="reference", method="verlet", error_estimate=True)
    planned = result.scene
    fine = replace(planned, run=replace(planned.run, timestep=planned.run.timestep / FINER))
    return result, ReferenceBackend().calculate(fine, "verlet").result


def check_bar(name: str, bar: dict, value: float, truth: float) -> None:
    """A bar within [1/FACTOR, FACTOR] of |value - truth|, or none with a status that says why."""
    true = abs(value - truth)
    if bar.get("error") is None:
        assert bar.get("status"), (name, bar)
        return
    assert true / FACTOR <= bar["error"] <= FACTOR * true, (name, bar, true)


def check_sensors(result, truth) -> None:
    """Every sensor bead's dynamic peak and its time."""
    run, _ = sensor_values(result.scene, result.solution)
    fine, _ = sensor_values(truth.scene, truth.solution)
    for b in result.scene.outputs.sensors:
        for q in ("sensor_peak_force", "sensor_time_of_peak"):
            key = sensor_key(q, b)
            check_bar(key, result.errors.end_peaks[key], run[key], fine[key])


def test_sensor_and_far_end_energy_bars_are_within_a_factor_3_of_the_true_error():
    """A free struck chain: the sensors' bars (measured 1.07-2.0x the true error) and far_end_energy's
    (1.01x; before: no bar, error_bar None), against a run at dt / 8."""
    result, truth = run_and_truth(FREE_SENSORS)
    check_sensors(result, truth)
    name = "far_end_energy"
    assert result.observables()[name] is not None
    check_bar(name, result.errors.observables[name], result.observables()[name], truth.observables()[name])


@pytest.mark.slow  # 13 s: the heavy striker's event at dt / 8
def test_the_event_maxima_and_sensor_bars_are_within_a_factor_3_of_the_true_error():
    """The heavy striker on a wall with every contact and two sensors chosen: the largest force over
    the event at them (measured 1.02x and 0.51x the true error) and the sensors' peaks (0.51-1.04x)."""
    result, truth = run_and_truth(CHOSEN)
    check_sensors(result, truth)
    for name in ("event_max_contact_force", "event_max_sensor_force"):
        value = result.observables()[name]
        assert value is not None, name
        check_bar(name, result.errors.observables[name], value, truth.observables()[name])
