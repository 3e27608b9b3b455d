"""A precompressed chain whose wave is too small for its arrivals to be read (the leading pulses no
larger than FRONT_RESOLUTION F0, postprocess.fronts) says so where wave_speed is not measured, instead
of only counting the window's contacts without an arrival."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.postprocess.fronts import FRONT_RESOLUTION
from granchain.scene import parse_scene
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import run_reference

CHAIN = """
[chain]
beads = 16
radius = {radius!r}
material = "{material}"
[contact]
law = "hertz"
[loading]
kind = "velocity"
velocity = {velocity!r}
[precompression]
force = {f0!r}
[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
"""


@settings(max_examples=6, deadline=None)
@given(
    radius=st.floats(2e-3, 5e-3),
    material=st.sampled_from(["brass", "stainless-steel-316", "aluminium-6061-t6"]),
    f0=st.floats(50.0, 500.0),
    velocity=st.floats(1e-7, 1e-6),
)
def test_a_wave_below_the_front_resolution_is_named_as_the_reason(radius, material, f0, velocity):
    sc = parse_scene(CHAIN.format(radius=radius, material=material, velocity=velocity, f0=f0), source="tiny.toml")
    result = run_reference(plan_scene(sc, method="verlet").scene, "verlet")
    if result.observables()["wave_speed"] is not None:  # a readable front after all: nothing to explain
        rises = result.solution.leading_pulse_force - f0
        assert np.nanmax(rises) > FRONT_RESOLUTION * f0
        return
    why = result.observables_missing()["wave_speed"]
    assert "FRONT_RESOLUTION x F0" in why, why
    assert f"{FRONT_RESOLUTION * f0:.2g} N" in why


def test_a_readable_front_is_not_blamed_on_the_resolution():
    sc = parse_scene(CHAIN.format(radius=2.38e-3, material="brass", velocity=0.1, f0=10.0), source="ok.toml")
    result = run_reference(plan_scene(sc, method="verlet").scene, "verlet")
    assert result.observables()["wave_speed"] is not None
    assert "wave_speed" not in result.observables_missing()
