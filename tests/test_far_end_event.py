"""A free far end's event (issue 42 item 4): what bead N carries off once it has left the chain for good.

[outputs] event = true on a free far end is no longer refused; far_end_energy and far_end_momentum are
bead N's kinetic energy and momentum once it is proved gone (postprocess.observables.far_end): a run
continued further reports the same numbers (nothing catches bead N again), a run too short says why,
and LAMMPS agrees with the reference's Verlet.
"""

from __future__ import annotations

import pytest

from granchain.scene import parse_scene
from granchain.workflows.run import run_scene
from tests.scenegen import PEAKS, brass_text

#: a six-bead free brass chain struck by a brass striker, the event asked for; bead N leaves before 6e-4 s
STRUCK_FREE = brass_text(6, 'kind = "striker"\nvelocity = 0.3\nradius = 4.76e-3\nmaterial = "brass"\n', PEAKS).replace(
    "[outputs]", "[outputs]\nevent = true"
)


def _free(end_time: float):
    return parse_scene(STRUCK_FREE.replace('end_time = "auto"', f"end_time = {end_time!r}"))


def _measured(result):
    obs = result.observables()
    return obs["far_end_energy"], obs["far_end_momentum"]


def test_a_free_far_ends_event_is_what_bead_n_carries_off():
    """Bead N's kinetic energy and momentum, the same in a run continued further (it left for good),
    and at most what the striker brought in."""
    scene = _free(6e-4)
    first = run_scene(scene, backend="reference", method="verlet")
    later = run_scene(_free(9e-4), backend="reference", method="verlet")
    energy, momentum = _measured(first)
    assert energy is not None
    assert _measured(later) == pytest.approx((energy, momentum), rel=1e-12)
    m_n, v_n = float(scene.bead_masses[-1]), float(first.solution.velocity[-1])
    assert energy == pytest.approx(0.5 * m_n * v_n**2, rel=1e-15)
    assert momentum == pytest.approx(m_n * v_n, rel=1e-15)
    assert 0.0 < energy <= 0.5 * float(scene.striker_mass) * 0.3**2


def test_a_run_ending_before_bead_n_leaves_says_why():
    result = run_scene(_free(5e-5), backend="reference", method="verlet")
    assert _measured(result) == (None, None)
    why = result.observables_missing()
    assert why["far_end_energy"] == why["far_end_momentum"]
    assert "bead N had not left the chain for good" in why["far_end_energy"]
    assert "end_time" in why["far_end_energy"]


def test_a_walled_chain_has_the_walls_event_not_the_free_ends():
    walled = parse_scene(STRUCK_FREE.replace("[outputs]", '[boundary]\nfar_end = "wall"\n[outputs]'))
    result = run_scene(walled, backend="reference")
    assert result.observables()["far_end_energy"] is None
    assert "wall" in result.observables_missing()["far_end_energy"]


def test_lammps_agrees_with_the_reference_verlet():
    scene = _free(6e-4)
    ref = _measured(run_scene(scene, backend="reference", method="verlet"))
    lmp = _measured(run_scene(scene, backend="lammps"))
    assert lmp == pytest.approx(ref, rel=1e-9)
