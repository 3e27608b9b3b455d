"""The shaker's [loading] keys refused clearly: one message naming the key and the fix (issue 46 item 1)."""

from __future__ import annotations

import pytest

from granchain.exceptions import GranchainError
from granchain.scene import SceneError, parse_scene

SCENE = """[chain]
beads = 6
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "shaker"
{loading}
[precompression]
force = 10.0
[boundary]
far_end = "wall"
[run]
end_time = "auto"
timestep = "auto"
"""

GOOD = {"amplitude": "1e-8", "frequency": "5000.0", "cycles": "6", "ramp": "2"}


def loading(**changes) -> str:
    keys = {**GOOD, **changes}
    return "\n".join(f"{k} = {v}" for k, v in keys.items() if v is not None)


BAD = {
    "negative amplitude": (dict(amplitude="-1e-8"), "amplitude", "displacement amplitude A in m"),
    "amplitude of a force": (dict(amplitude="5.0"), "amplitude", "<= 0.01"),
    "amplitude as text": (dict(amplitude='"1 um"'), "amplitude", "in m"),
    "no frequency": (dict(frequency=None), "frequency", "Hz"),
    "zero frequency": (dict(frequency="0.0"), "frequency", "> 0"),
    "cycles and duration": (dict(duration="1e-3"), "cycles", "exactly one of cycles"),
    "neither cycles nor duration": (dict(cycles=None), "cycles", "neither: add one"),
    "ramp beyond the drive": (dict(ramp="7"), "ramp", "at most the drive's length"),
    "a striker's key": (dict(velocity="1.0"), "velocity", "a shaker is given by amplitude (m)"),
    "a force load's key": (dict(impulse="1e-3"), "impulse", "a shaker is given by amplitude (m)"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_shaker_keys_are_refused_naming_the_key(case):
    changes, key, fix = BAD[case]
    with pytest.raises(SceneError) as err:
        parse_scene(SCENE.format(loading=loading(**changes)), source="shaker.toml")
    message = str(err.value)
    assert isinstance(err.value, GranchainError)
    assert key in message, message
    assert fix in message, message
    assert message.count("\n") == 0, message  # one line


def test_a_good_shaker_reads_back_to_the_same_scene():
    scene = parse_scene(SCENE.format(loading=loading()), source="shaker.toml")
    ld = scene.loading
    assert (ld.kind, ld.is_shaker, ld.is_harmonic, ld.is_force) == ("shaker", True, True, False)
    assert (ld.amplitude, ld.ramp) == (1e-8, 2.0)
    assert ld.cycles == pytest.approx(6.0)
    again = parse_scene(scene.to_toml(), source="again.toml")
    assert again.loading == ld
