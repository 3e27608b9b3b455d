"""The error-bar companions cover the wall's event wherever the run does (errorbars.cover).

A companion at 2 dt or 4 dt ends its own event a little elsewhere than the run (its stop checks are
2x or 4x as far apart in time, its dynamics coarser): on a user's scene whose end time falls just after
the run's event end, a companion ran to that end inside its event and the event quantities' bars were
missing under a peak's status ("not complete in the run or its 2 dt companion"). Now such a companion
is continued to its event's end; where it cannot be, the status names the companion and its reason.
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from granchain.backends.builtin import ReferenceBackend
from granchain.physics.materials import MATERIALS
from granchain.postprocess.observables import OBSERVABLES
from granchain.scene import parse_scene
from granchain.workflows.errorbars import cover
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import run_scene

#: the event quantities whose bars come from the companions (Observable.needs "event", with a bar)
EVENT_QUANTITIES = tuple(n for n, o in OBSERVABLES.items() if "event" in o.needs and o.error_bar)
#: the old status of an event quantity a companion had not ended: a peak's, which says nothing of the event
PEAK_STATUS = "not complete in the run or its"


def walled_text(beads: int, material: str, taper: float | None, ratio: float, v: float, held: str) -> str:
    """A Hertz chain of 4 mm beads on a rigid wall asking for the event and the largest force at
    contact 1 and sensor bead 3 over it: a striker of `ratio` beads' mass at v (a heavy one pushes
    several times), a taper or not, precompressed (1 N) or standing under gravity or neither; end
    time and step "auto"."""
    radius = 4e-3
    mass = ratio * MATERIALS[material].density * 4.18879 * radius**3
    chain = f'beads = {beads}\nradius = {radius!r}\nmaterial = "{material}"\n'
    chain += f"taper = {taper!r}\n" if taper else ""
    text = (
        f'[chain]\n{chain}[contact]\nlaw = "hertz"\n[loading]\nkind = "striker"\nvelocity = {v!r}\n'
        f'mass = {mass!r}\n[run]\nend_time = "auto"\ntimestep = "auto"\n[boundary]\nfar_end = "wall"\n'
        "[outputs]\npeak_force = true\nevent = true\nevent_max_contacts = [1]\nsensors = [3]\nevent_max_sensors = [3]\n"
    )
    return text + {"": "", "pre": "[precompression]\nforce = 1.0\n", "g": "[gravity]\ng = 9.81\n"}[held]


def user_scene(text: str, after: float):
    """The scene a user writes after a planned run: end_time given, `after` (a fraction) past the end of
    the planned run's event; None where that run's event did not end."""
    planned = plan_scene(parse_scene(text, source="generated.toml"), method="verlet").scene
    sol = ReferenceBackend().calculate(planned, "verlet").result.solution
    if sol.event_end_time is None:
        return None
    end = sol.event_end_time * (1.0 + after)
    return parse_scene(text.replace('end_time = "auto"', f"end_time = {end!r}"), source="user.toml")


def assert_covered(scene) -> None:
    """The run's event quantities each have a bar, or a status that says why (a companion's own reason,
    or the extrapolation's verdict), never a peak's status."""
    result = run_scene(scene, backend="reference", method="verlet", error_estimate=True)
    assert result.solution.event_end_time is not None, scene.to_toml()
    for name in EVENT_QUANTITIES:
        entry = result.errors.observables[name]
        assert result.observables()[name] is not None, name
        assert PEAK_STATUS not in entry["status"], (name, entry, scene.to_toml())
        if entry["error"] is None and entry["status"].startswith("not measured"):
            assert entry["status"].startswith("not measured in the companion at"), (name, entry)


#: PTFE under a striker of 8 beads' mass: the run's event ends at 4.8838e-3 s, both companions' at
#: 4.8888e-3 s (their stop checks 2x and 4x as far apart): an end of 4.8862e-3 s cuts them short
PTFE = walled_text(8, "ptfe", None, 8.0, 0.3, "")


def test_a_companion_cut_short_by_the_users_end_time_is_continued_to_its_events_end():
    """Fails before: every event quantity's bar was missing, its status a peak's."""
    assert_covered(user_scene(PTFE, 5e-4))


def test_a_companion_that_cannot_cover_its_event_says_which_and_why(monkeypatch):
    """Continued no further than its end, the companion stays inside its event: the status names it and
    the event's reason, not a peak's."""
    monkeypatch.setattr(cover, "CONTINUED", 1.0)
    result = run_scene(user_scene(PTFE, 5e-4), backend="reference", method="verlet", error_estimate=True)
    for name in EVENT_QUANTITIES:
        status = result.errors.observables[name]["status"]
        assert status.startswith("not measured in the companion at 2 dt: the event had not ended"), (name, status)


@pytest.mark.slow
@settings(max_examples=10, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(
    beads=st.integers(5, 10),
    material=st.sampled_from(["ptfe", "stainless-steel-316", "brass"]),
    taper=st.one_of(st.none(), st.floats(0.88, 0.97)),
    ratio=st.floats(0.5, 20.0),
    v=st.floats(0.05, 0.8),
    held=st.sampled_from(["", "pre", "g"]),
    after=st.floats(1e-5, 0.03),
)
@example(beads=8, material="ptfe", taper=None, ratio=8.0, v=0.3, held="", after=5e-4)
def test_generated_walled_chains_companions_cover_their_event(beads, material, taper, ratio, v, held, after):
    """Heavy strikers on walled tapers, PTFE and steel beads, precompression and gravity, each with an
    end time a user gives just past the planned run's event: every event quantity has a bar or a
    status that says why."""
    scene = user_scene(walled_text(beads, material, taper, ratio, v, held), after)
    if scene is not None:  # (the planned run's own coverage is tests/test_event.py's)
        assert_covered(scene)


def test_a_continued_companion_keeps_its_own_peaks():
    """Only the event's fields come from the continued run: the companion's peaks and end are its own."""
    scene = user_scene(PTFE, 5e-4)
    planned = plan_scene(scene, method="verlet").scene
    main = ReferenceBackend().calculate(planned, "verlet").result.solution
    run_one = lambda s: ReferenceBackend().calculate(s, "verlet").result  # noqa: E731
    covering = cover.Covering(run_one, main)
    companion = replace(planned, run=replace(planned.run, timestep=2 * planned.run.timestep))
    own = run_one(companion).solution
    got = covering(companion).solution
    assert own.event_end_time is None
    assert got.event_end_time is not None
    assert got.end_time == own.end_time
    assert list(got.peak_force) == list(own.peak_force)
    assert got.wall_impulse >= own.wall_impulse


#: stainless beads tapered by 0.93 to a wall under a striker of 8 beads' mass: "auto" planned 1.626e-3 s,
#: and the chain was proved gone from the wall for good only at 1.855e-3 s
TAPERED_HEAVY = walled_text(8, "stainless-steel-316", 0.93, 8.0, 0.3, "")


@pytest.mark.slow  # 42 s on a loaded machine: two runs of 3e4 steps
def test_an_auto_run_that_ends_inside_its_event_is_run_again_to_its_end():
    """The planned end is a cap the event can outlast: the run is extended (extended_plan, as granchain run
    does) to EVENT_EXTENSION x its end, its stop check ending it at the event's end. Fails before: the
    extension's budget, 3 crossings of the chain, was below the planned end, so nothing ran again and
    the event quantities were unmeasured."""
    from granchain.workflows.plan import EVENT_EXTENSION, extended_plan

    scene = parse_scene(TAPERED_HEAVY, source="tapered.toml")
    plan = plan_scene(scene, method="verlet")
    first = ReferenceBackend().calculate(plan.scene, "verlet").result.solution
    assert first.event_end_time is None  # (the scene's point: the planned end falls inside the event)
    longer = extended_plan(scene, plan, first)
    assert longer is not None
    assert longer.scene.run.end_time == pytest.approx(EVENT_EXTENSION * plan.scene.run.end_time)
    sol = ReferenceBackend().calculate(longer.scene, "verlet").result.solution
    assert sol.event_end_time is not None
    assert sol.end_time < longer.scene.run.end_time  # the stop check ended it at the event's end
