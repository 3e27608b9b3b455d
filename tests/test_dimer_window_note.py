"""A dimer window of fewer than PERIODIC_CELLS cells (one contact kind, beads that alternate) has a wave
speed note of its own: an average over its contacts, which are of one kind, with no stretch of its own
to fit. Before, it reused the note of a window of several contact kinds: "whose contacts differ (...: one
contact kind, ...) ...; no uniform stretch of the window has 3 arrivals to fit on its own", beside a fit
of 4 arrivals (/tmp/rev40/dimer.toml: 16 beads, window [5, 8])."""

import warnings

import pytest

from granchain.postprocess.observables import FIT_CONTACTS, PERIODIC_CELLS, periodic_cell, uniform_sections
from granchain.scene import parse_scene
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import run_reference

DIMER = """
[chain]
beads = 16
radius = [{radii}]
material = "stainless-steel-316"
[contact]
law = "hertz"
[loading]
kind = "velocity"
velocity = 1.0
[boundary]
far_end = "free"
[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
window = [{a}, {b}]
"""


@pytest.mark.parametrize("window", [(5, 8), (4, 6), (9, 12)])
def test_a_short_dimer_window_is_noted_as_one_contact_kind(window):
    a, b = window
    radii = ", ".join("4.76e-3" if i % 2 == 0 else "2.38e-3" for i in range(16))
    sc = parse_scene(DIMER.format(radii=radii, a=a, b=b), source="dimer.toml")
    # the case: beads that alternate, fewer than PERIODIC_CELLS cells, all contacts of one kind
    assert b - a + 2 < 2 * PERIODIC_CELLS
    assert periodic_cell(sc) is None
    assert uniform_sections(sc) == [(a, b)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = run_reference(plan_scene(sc, method="verlet").scene, "verlet")
    obs, notes = result.observables(), result.observables_notes()
    assert obs["wave_speed"] is not None
    assert obs["wave_speed_contacts"] >= FIT_CONTACTS
    note = notes["wave_speed"]
    assert note.startswith(f"an average over contacts {a}-{b}")
    assert "not one number" in note  # still marked as an average
    # not the note of several contact kinds: neither contacts that differ nor too few arrivals per stretch
    assert "whose contacts differ" not in note, note
    assert f"{FIT_CONTACTS} arrivals" not in note, note
    assert "one kind" in note, note
    assert f"fewer than {PERIODIC_CELLS} times" in note, note
    assert "wave_speed_sections" not in obs
