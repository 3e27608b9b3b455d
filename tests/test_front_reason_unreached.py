"""A precompressed run that ends before its wave has passed the measurement window does not blame the
front's resolution (FRONT_RESOLUTION F0) for its missing wave speed: nothing there was too small to read,
the wave had not got there (or was still rising there). Before, effect-precompression cut to 40 beads and
3e-5 s said "the window's contacts have no leading pulse, not above FRONT_RESOLUTION x F0 ...; a larger
load or a smaller F0 makes a front that can be read". A wave that passed the window too small to make a
leading pulse still gets that reason."""

import warnings

import numpy as np
import pytest

from granchain.postprocess.fronts import FRONT_RESOLUTION
from granchain.scene import parse_scene
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import run_reference
from tests.conftest import make_scene_text
from tests.scenegen import WALL


def short(end: float) -> str:
    """effect-precompression, 40 beads (window 9-29), cut short at `end` (s)."""
    outputs = 'peak_force = true\nhistories = [1, 10]\nhistory_interval = "auto"'
    text = make_scene_text(beads=40, end_time=end, timestep=5e-8, outputs=outputs)
    return text + "[precompression]\nforce = 100.0\n" + WALL


TINY = """
[chain]
beads = 16
radius = 3e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "velocity"
velocity = 1e-10
[precompression]
force = 100.0
[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
"""


def run(text: str):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run_reference(plan_scene(parse_scene(text, source="t.toml"), method="verlet").scene, "verlet")


@pytest.mark.parametrize("end", [3e-5, 5e-5], ids=["not-reached", "still-rising"])
def test_a_wave_that_has_not_passed_the_window_is_not_blamed_on_the_resolution(end):
    result = run(short(end))
    a, b = result.scene.window
    s = result.solution
    # the case: no leading pulse and no complete peak in the window (nothing passed it before the end)
    assert not np.isfinite(s.leading_pulse_force[a - 1 : b]).any()
    assert not np.asarray(s.complete, dtype=bool)[a - 1 : b].any()
    why = result.observables_missing()["wave_speed"]
    assert "FRONT_RESOLUTION" not in why, why
    assert "a larger load" not in why, why


def test_a_wave_too_small_for_a_leading_pulse_is_still_named():
    result = run(TINY)
    a, b = result.scene.window
    s = result.solution
    f0 = result.scene.effects.precompression
    # the case: the wave passed the window (complete peaks) under FRONT_RESOLUTION F0, with no leading pulse
    assert not np.isfinite(s.leading_pulse_force[a - 1 : b]).any()
    done = np.asarray(s.complete, dtype=bool)[a - 1 : b]
    assert done.any()
    assert np.max(s.peak_force[a - 1 : b][done] - f0) <= FRONT_RESOLUTION * f0
    why = result.observables_missing()["wave_speed"]
    assert "FRONT_RESOLUTION x F0" in why, why
