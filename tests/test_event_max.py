"""The largest force over the far-end wall's event at chosen contacts and sensor beads ([outputs]
event_max_contacts, event_max_sensors; issue 42 item 4's last part).

Its oracle is a dense history (every step, history_interval = the time step) of the same run to the
event's end: the tracked value is that history's maximum within rtol (the parabola through three
samples only refines it upwards), on a heavy striker whose later pushes exceed the contacts' first
complete peak, and on generated walled chains (hypothesis). LAMMPS agrees with the reference's
Verlet to 1e-9; bad input is refused with one message naming the key.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.backends.builtin import ReferenceBackend
from granchain.problem import ChainProblem, scene_static_forces
from granchain.reference.solver import solve_chain
from granchain.scene import SceneError, parse_scene
from granchain.workflows.plan import plan_scene
from tests.test_event import HEAVY_STRIKER, RTOL, planned_run, walled_event_scenes

#: the heavy striker (4 beads' mass on 8 beads) with every contact and two sensors chosen
CHOSEN = HEAVY_STRIKER.replace(
    "event = true",
    "event = true\nsensors = [3, 8]\nevent_max_contacts = [1, 2, 3, 4, 5, 6, 7]\nevent_max_sensors = [3, 8]",
)


def dense_forces(scene, sol):
    """Every contact's force (the wall's last) at every step of the same run to the event's end:
    (time, force (steps, N)), beside the bead averages of the sensor beads (steps, N)."""
    n = scene.chain.beads
    d = solve_chain(
        ChainProblem.from_scene(scene),
        sol.event_end_time,
        scene.run.timestep,
        "verlet",
        histories=tuple(range(n)),
        history_stride=1,
        progress=None,
    )
    f = d.history_force
    # bead i (1-based) between contact i - 1 and contact i; bead 1's left contact (the striker's) is not
    # in the histories, so only inner beads and bead N (its right contact the wall's) are read here
    beads = 0.5 * np.pad(f, ((0, 0), (1, 0)))[:, :-1] + 0.5 * f
    return d.history_time, f, beads


def check_against_dense(scene, sol, sensors: bool = True) -> None:
    """The tracked maxima against the dense history's over the event, within rtol, and their times."""
    t, f, beads = dense_forces(scene, sol)
    static = scene_static_forces(scene)
    for k, c in enumerate(scene.outputs.event_max_contacts):
        dyn = f[:, c - 1] - static[c - 1]
        got = sol.event_contact_max_force[k] - static[c - 1]
        assert got == pytest.approx(float(dyn.max()), rel=RTOL), (c, scene.to_toml())
        assert got >= float(dyn.max()) - 1e-9 * abs(float(dyn.max()))  # the parabola refines upwards
        assert sol.event_contact_time_of_max[k] == pytest.approx(float(t[np.argmax(dyn)]), abs=2 * scene.run.timestep)
    if sensors:
        for k, b in enumerate(scene.outputs.event_max_sensors):
            got = sol.event_sensor_max_force[k]
            assert got == pytest.approx(float(beads[:, b - 1].max()), rel=RTOL), b


def test_the_largest_force_over_the_event_is_the_dense_history_s_and_outgrows_the_first_peak():
    """On the heavy striker every chosen contact's and sensor's largest force over the event is the
    maximum of its force at every step to the event's end; at contact 6 it is a later push, 1.4x the
    contact's first complete peak (its leading pulse): a first-peak reading misses it. The registered
    observables report the largest of them, which one and each one's, above the static force."""
    planned, sol = planned_run(parse_scene(CHOSEN))
    assert sol.event_end_time is not None
    check_against_dense(planned, sol)
    later = np.asarray(sol.event_contact_max_force) / np.asarray(sol.leading_pulse_force)
    assert later.max() > 1.3, later
    result = ReferenceBackend().calculate(planned, "verlet").result
    obs = result.observables()
    assert obs["event_max_contact_force"] == pytest.approx(float(np.max(sol.event_contact_max_force)), rel=1e-12)
    assert obs["event_max_contact"] == 1 + int(np.argmax(sol.event_contact_max_force))
    assert len(obs["event_contact_max_forces"]) == 7
    assert obs["event_max_sensor"] in (3, 8)
    assert result.summary()["event_maxima"]["event_sensor_max_force"] == list(sol.event_sensor_max_force)


@settings(max_examples=4, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(scene=walled_event_scenes(max_beads=7), pick=st.randoms(use_true_random=False))
def test_on_generated_walled_chains_the_largest_force_is_the_dense_history_s(scene, pick):
    """A property on small generated walled chains (strikers, kicks, tapers, precompression, gravity):
    the chosen contacts' and sensor beads' largest force over the event is their dense history's maximum."""
    from dataclasses import replace

    n = scene.chain.beads
    chosen = tuple(sorted(pick.sample(range(1, n), min(3, n - 1))))
    # sensor beads 2..N (bead 1's left contact, a striker's, is not in the dense history's contacts)
    sensors = tuple(sorted(pick.sample(range(2, n + 1), 2)))
    outputs = replace(scene.outputs, event_max_contacts=chosen, sensors=sensors, event_max_sensors=sensors)
    planned, sol = planned_run(replace(scene, outputs=outputs))
    assert sol.event_end_time is not None
    check_against_dense(planned, sol)


@pytest.mark.parametrize("held", ["[gravity]\ng = 9.81\n", "[precompression]\nforce = 2.0\n"], ids=["gravity", "F0"])
def test_lammps_is_the_reference_verlet_on_the_largest_forces_over_the_event(held):
    """Both backends track the chosen contacts and sensors alike on a chain held on the wall (under
    gravity static forces grow with depth; the event ends at its first return, cut in the step): every
    largest force to 1e-9, its time to 1e-12 of the event."""
    from granchain.backends.builtin import LammpsBackend

    planned = plan_scene(parse_scene(CHOSEN + held), method="verlet").scene
    ref = ReferenceBackend().calculate(planned, "verlet").result
    backend = LammpsBackend()
    backend.prepare()
    lam = backend.calculate(planned, "verlet").result
    for name in ("event_contact_max_force", "event_sensor_max_force"):
        np.testing.assert_allclose(getattr(lam.solution, name), getattr(ref.solution, name), rtol=1e-9)
    for name in ("event_contact_time_of_max", "event_sensor_time_of_max"):
        end = ref.solution.event_end_time
        np.testing.assert_allclose(getattr(lam.solution, name), getattr(ref.solution, name), atol=1e-12 * end)
    for name in ("event_max_contact_force", "event_max_sensor_force"):
        assert lam.observables()[name] == pytest.approx(ref.observables()[name], rel=1e-9)


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("event_max_contacts = [1, 2, 3, 4, 5, 6, 7]", "event_max_contacts = 3", r"event_max_contacts.*list"),
        ("event_max_contacts = [1, 2, 3, 4, 5, 6, 7]", "event_max_contacts = [8]", r"event_max_contacts.*out of range"),
        ("event_max_sensors = [3, 8]", "event_max_sensors = [4]", r"event_max_sensors.*add it to \[outputs\] sensors"),
        ("event = true\n", "event = false\n", r"event_max_contacts.*\[outputs\] event = true"),
    ],
    ids=["not-a-list", "out-of-range", "not-a-sensor", "no-event"],
)
def test_bad_event_max_input_is_refused_with_one_message_naming_the_key(old, new, match):
    text = CHOSEN.replace(old, new, 1)
    assert text != CHOSEN
    with pytest.raises(SceneError, match=match):
        parse_scene(text)


def test_the_keys_survive_the_scene_writer():
    """A scene written back to TOML keeps its chosen contacts and sensors."""
    scene = parse_scene(CHOSEN)
    again = parse_scene(scene.to_toml())
    assert again.outputs.event_max_contacts == tuple(range(1, 8))
    assert again.outputs.event_max_sensors == (3, 8)
