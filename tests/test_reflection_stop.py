"""The stop check's wait for the wall's reflection watches contact 1 (beads 1 and 2) on both backends:
the reference watched its inner contact 0, which with a striker is the striker's contact, so a struck
walled chain stopped at another time on each backend (about 6% apart)."""

import pytest

from granchain.scene import parse_scene
from granchain.schedule import STOP_CHECK_EVERY
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import calculate_scene

STRUCK_ON_WALL = """
[chain]
beads = 12
radius = 2.38e-3
material = "stainless-steel-316"
[contact]
law = "hertz"
[loading]
kind = "striker"
velocity = {velocity}
[boundary]
far_end = "wall"
[run]
end_time = "auto"
timestep = "auto"
"""


@pytest.mark.parametrize("velocity", [0.1, 0.5])
def test_a_struck_walled_chain_stops_at_the_same_check_on_both_backends(velocity):
    sc = parse_scene(STRUCK_ON_WALL.format(velocity=velocity), source="struck.toml")
    planned = plan_scene(sc, method="verlet").scene
    assert planned.run.stop_after_reflection  # the case: the plan waits for the reflection
    ref = calculate_scene(sc, method="verlet", error_estimate=False).result.solution
    lam = calculate_scene(sc, backend="lammps", error_estimate=False).result.solution
    assert ref.timestep == lam.timestep
    # the two backends check the same contacts every STOP_CHECK_EVERY steps: at most one check apart
    assert abs(ref.end_time - lam.end_time) <= 1.5 * STOP_CHECK_EVERY * ref.timestep, (ref.end_time, lam.end_time)
