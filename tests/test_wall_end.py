"""end_time = "auto" on a chain with a wall whose peak forces are asked for measures the wall's peak:
the stop check also waits for the wall's contact ([run] stop_after_wall: bead N on the flat) and the
planned end covers it (granchain.workflows.plan.wall_peak_planned). A chain without a wall, or without peak_force,
is planned as before: its stop check at the last measured contact.
"""

import os
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, assume, event, example, given, settings
from hypothesis import strategies as st

from granchain.backends.builtin import ReferenceBackend
from granchain.peaks import end_contact_reached
from granchain.scene import SceneError, parse_scene
from granchain.workflows.plan import (
    REFLECTION_CROSSINGS,
    WALL_PULSE_CONTACTS,
    _front_end_time,
    extended_plan,
    extension_budget,
    front_travel_time,
    last_measured_contact,
    plan_scene,
    wall_peak_planned,
    wave_speeds,
)
from tests.scenegen import (
    AUTO_RUN,
    PEAKS,
    WALL,
    brass_text,
    overlap_fraction,
    scene_texts,
    scenes,
    stainless_on_wall_text,
)

#: bead-steps one example may cost (the planned run and the longer one)
MAX_BEAD_STEPS = 3e6
#: how much longer than the planned run's own end the comparison run lasts, without a stop check: a
#: second arrival at the wall needs a round trip through the chain, far later
LONGER = 1.5

WALLED = stainless_on_wall_text("striker", 0.44, 20000, histories=[1, 10, 19])

#: a CI draw: a Thornton chain precompressed 450x beyond its yield force (F0 = 5.6 N, F_y = 0.0125 N),
#: whose fronts move on the plastic line, 0.36x as fast as Hertz's tangent at F0 made the planner expect;
#: the wall's peak (8.525 N at 1.94e-4 s) was not complete at the extended end 2.29e-4 s
THORNTON_BEYOND_YIELD = """
[chain]
beads = 12
radius = 0.002
material = "stainless-steel-316"
[contact]
law = "thornton"
yield_pressure = 300000000.0
[loading]
kind = "velocity"
velocity = 1.1
[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
histories = [1, 6]
[boundary]
far_end = "wall"
[damping]
dashpot = 5.607951089738603
[precompression]
force = 5.607951089738603
"""


def reference(scene, method="rk4"):
    return ReferenceBackend().calculate(scene, method).result.solution


@pytest.mark.slow
@settings(max_examples=40, deadline=None, derandomize=True, phases=[Phase.explicit, Phase.reuse, Phase.generate])
@given(scene=scenes(max_beads=30, wall=True))
@example(scene=parse_scene(THORNTON_BEYOND_YIELD, source="generated.toml"))
def test_auto_end_measures_the_wall_peak(scene):
    """On generated walled chains (laws, materials, radii, tapers, precompression, striker, velocity and
    force loads, dashpots): the planned run ends with the wall's peak complete, and a run LONGER x as long
    without a stop check finds the same wall peak, or a larger one after the run's end (a precompressed
    chain's main wave behind its precursors: the run's is the wall's first complete maximum). Where the wall's force
    stays up past the planned end (a plastic, damped chain that settles on the wall) the run is
    extended once (extended_plan), as granchain run does. Fails before the wall's stop: the stop
    check at contact N-1 ended the run before the wall's force fell back."""
    # a load lasting longer than any run (plan.extension_budget) is a lasting one: the wall's peak not planned
    assume(wall_peak_planned(scene))
    plan = plan_scene(scene, method="rk4")
    planned = plan.scene
    cost = planned.run.end_time / planned.run.timestep * planned.chain.beads
    assume(cost * (1 + LONGER) <= MAX_BEAD_STEPS)
    sol = reference(planned)
    longer_plan = extended_plan(scene, plan, sol)  # once, as granchain run does (workflows.run)
    extended = longer_plan is not None
    if extended:
        planned = longer_plan.scene
        sol = reference(planned)
    log = os.environ.get("GRANCHAIN_WALL_LOG")
    if log:
        with open(log, "a") as f:
            f.write(
                f"{scene.contact.law} {scene.loading.kind} pre={float(scene.effects.precompression):g} "
                f"planned/ran {planned.run.end_time / sol.end_time:.3f} complete {sol.wall_peak_complete} "
                f"extended {extended} first {plan.scene.run.end_time:.4g} ran {sol.end_time:.4g}\n"
            )
    assert planned.run.stop_after_wall, "the stop check waits for the wall's contact"
    assert sol.wall_peak_complete, f"the wall's peak was not complete at {sol.end_time:.4g} s\n{scene.to_toml()}"
    longer = replace(
        planned,
        run=replace(planned.run, end_time=LONGER * sol.end_time, stop_after_contact=None, stop_after_wall=False),
    )
    ref = reference(longer)
    if ref.wall_time_of_peak > sol.end_time:
        # a later, larger maximum (a precompressed chain's main wave behind its precursors): the run's
        # peak is the wall's first complete one, not a running maximum cut short
        assert ref.wall_peak_force > sol.wall_peak_force
    else:
        assert np.isclose(sol.wall_peak_force, ref.wall_peak_force, rtol=1e-9, atol=0.0), (
            f"{sol.wall_peak_force!r} vs {ref.wall_peak_force!r} to {longer.run.end_time:.4g} s\n{scene.to_toml()}"
        )


def test_auto_end_measures_the_wall_peak_on_both_backends():
    """Daraio's precompressed striker chain (F0 = 2e4 N: the linear, dispersed chain whose wall
    completes latest against the planned end for contact N-1): both backends end with the wall's peak
    complete and agree on it (20052.2 N); before, the stop at contact 19 ended the run at 5.3e-5 s,
    the wall's force completing at 5.7e-5 s."""
    from granchain.workflows.run import run_scene

    sc = parse_scene(WALLED, source="walled.toml")
    planned = plan_scene(sc, method="verlet").scene
    assert planned.run.stop_after_wall
    lmp = run_scene(planned, backend="lammps").solution
    ref = reference(planned, "verlet")
    assert lmp.wall_peak_complete
    assert ref.wall_peak_complete
    assert np.isclose(lmp.wall_peak_force, ref.wall_peak_force, rtol=1e-7)
    assert lmp.end_time < planned.run.end_time  # the stop check ended it


def test_without_peak_force_or_wall_the_stop_stays_at_the_last_measured_contact():
    """Simulate only what the scene calls for: no peak forces asked (histories only), or no wall, and the
    stop check is the last measured contact's, the end the one planned for it."""
    no_peaks = parse_scene(WALLED.replace("peak_force = true", "peak_force = false"), source="s.toml")
    free = parse_scene(WALLED.replace('far_end = "wall"', 'far_end = "free"'), source="s.toml")
    walled = parse_scene(WALLED, source="s.toml")
    for sc in (no_peaks, free):
        plan = plan_scene(sc)
        assert plan.scene.run.stop_after_contact == 19
        assert not plan.scene.run.stop_after_wall
        assert "wall's contact" not in dict((c.name, c.reason) for c in plan.choices)["end_time"]
    assert plan_scene(no_peaks).scene.run.end_time < plan_scene(walled).scene.run.end_time


def test_stop_after_wall_needs_a_wall_and_a_stop_contact():
    text = WALLED.replace('end_time = "auto"', "end_time = 1e-4\nstop_after_contact = 19\nstop_after_wall = true")
    assert parse_scene(text, source="s.toml").run.stop_after_wall
    assert parse_scene(parse_scene(text, source="s.toml").to_toml(), source="again.toml").run.stop_after_wall
    with pytest.raises(SceneError, match='needs a wall: \\[boundary\\] far_end = "wall"'):
        parse_scene(text.replace('far_end = "wall"', 'far_end = "free"'), source="s.toml")
    with pytest.raises(SceneError, match="needs \\[run\\] stop_after_contact"):
        parse_scene(text.replace("stop_after_contact = 19\n", ""), source="s.toml")
    with pytest.raises(SceneError, match="stop_after_wall = 1 is invalid: true or false"):
        parse_scene(text.replace("stop_after_wall = true", "stop_after_wall = 1"), source="s.toml")


#: 30 brass beads, Hertz, a 40 N step on bead 1 (its duration DURATION), a wall, every "auto"
BRASS_STEP_ON_A_WALL = brass_text(30, 'kind = "step"\namplitude = 40.0\nduration = DURATION\n', WALL + PEAKS)


def _with_stop(text: str, stop: int) -> str:
    assert AUTO_RUN in text
    return text.replace(AUTO_RUN, f"{AUTO_RUN}stop_after_contact = {stop}\n")


#: 20 brass beads, Hertz, kicked at 0.5 m/s, a wall, every "auto"; the stop check the scene's own:
#: contact 5, not the wall's
BRASS_KICK_STOPPED_AT_5 = _with_stop(brass_text(20, 'kind = "velocity"\nvelocity = 0.5\n', WALL + PEAKS), 5)

PLAN_SETTINGS = settings(
    max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.filter_too_much]
)


@st.composite
def walled_steps(draw):
    """A generated walled chain (tests.scenegen: laws, materials, tapers, precompression, dashpots) under
    a step force lasting 1e-6 to 100 s (below the 1e3 s of plan._front_end_time's own lasting load)."""
    text = draw(scene_texts(max_beads=30, wall=True))
    assume('kind = "step"' in text)
    lines = text.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("duration = "))
    lines[i] = f"duration = {10.0 ** draw(st.floats(-6.0, 2.0), label='log10 T')!r}"
    sc = parse_scene("\n".join(lines) + "\n", source="generated.toml")
    assume(overlap_fraction(sc) < 0.05)
    return sc


@PLAN_SETTINGS
@example(sc=parse_scene(BRASS_STEP_ON_A_WALL.replace("DURATION", "1.0"), source="st_1.0.toml"))
@example(sc=parse_scene(BRASS_STEP_ON_A_WALL.replace("DURATION", "1e-2"), source="st_1e-2.toml"))
@given(sc=walled_steps())
def test_a_step_longer_than_the_budget_is_a_lasting_load_for_the_wall(sc):
    """A step lasting longer than the longest end a run is ever run to (plan.extension_budget: 3x the
    slowest front's crossing of the whole chain) keeps pressing the wall past any run: the wall's peak is
    not planned for, and the planned end is at most the end for contact N-1 or the load's end crossing
    the chain within that budget, with the wall's pulse (WALL_PULSE_CONTACTS contacts' time) after it. A
    shorter step is planned until its end has crossed the chain, the stop check waiting for the wall.
    Fails before: the wall's end was the load's whole duration after the crossing, for any step under
    1e3 s (30 brass beads, 40 N for 1 s: 1.001 s and 8.8e5 steps, for a budget of 2.7e-3 s)."""
    plan = plan_scene(sc)
    slow = wave_speeds(sc)[0]
    nc = sc.n_contacts
    crossing = front_travel_time(sc, nc, slow)
    hop = crossing - front_travel_time(sc, nc - 1, slow)
    budget = extension_budget(sc, slow)
    load = sc.loading.duration
    end_n1 = _front_end_time(sc, nc, slow, plan.omega_max).value
    end = plan.scene.run.end_time
    bound = max(end_n1, crossing + budget) + WALL_PULSE_CONTACTS * hop
    if plan.scene.run.stop_after_reflection:  # the cap for the wall's reflection back to contact 1 (peaks)
        bound += REFLECTION_CROSSINGS * crossing
    assert end <= bound * (1 + 1e-12), f"planned end {end:.4g} s beyond {bound:.4g} s (a {load:.3g} s step)"
    event("beyond the budget" if load > budget else "within it")
    event(f"stop_after_wall {plan.scene.run.stop_after_wall}")
    if load > budget:
        assert not wall_peak_planned(sc)
        assert not plan.scene.run.stop_after_wall
        assert "the wall's contact" not in dict((c.name, c.reason) for c in plan.choices)["end_time"]
    if plan.scene.run.stop_after_wall:  # the wall's peak planned for: the load's end crosses the chain first
        assert end >= crossing + load


@st.composite
def walled_with_a_stop(draw):
    """A generated walled chain (every law, load and effect) whose [run] gives stop_after_contact (any of
    its contacts), without stop_after_wall; and its text."""
    text = draw(scene_texts(max_beads=30, wall=True))
    beads = int(next(line for line in text.splitlines() if line.startswith("beads = ")).split("=")[1])
    text = _with_stop(text, draw(st.integers(1, beads - 1)))
    sc = parse_scene(text, source="generated.toml")
    assume(overlap_fraction(sc) < 0.05)
    return sc, text


@PLAN_SETTINGS
@example(case=(parse_scene(BRASS_KICK_STOPPED_AT_5, source="w1.toml"), BRASS_KICK_STOPPED_AT_5))
@given(case=walled_with_a_stop())
def test_a_given_stop_without_the_walls_keeps_the_end_for_the_measured_contacts(case):
    """A scene that gives its own stop check without stop_after_wall ends before the wall's peak: its auto
    end is the one for its measured contacts (plan._front_end_time), whose reason does not say the wall's
    contact is measured; the same scene with stop_after_wall = true keeps the wall's end. Fails before:
    20 brass beads kicked, stop_after_contact = 5: the end extended for the wall (7.8e-4 s against 4.4e-4 s)
    and its reason said 'the wall's contact 20 ... measured'; the run stopped at 1.34e-4 s and printed
    wall_peak_force not reached."""
    sc, text = case
    plan = plan_scene(sc)
    end = dict((c.name, c) for c in plan.choices)["end_time"]
    alone = _front_end_time(sc, last_measured_contact(sc), wave_speeds(sc)[0], plan.omega_max)
    assert "the wall's contact" not in end.reason
    assert end.value == alone.value
    assert not plan.scene.run.stop_after_wall
    waits = parse_scene(text.replace("[run]\n", "[run]\nstop_after_wall = true\n", 1), source="waits.toml")
    waiting = plan_scene(waits)
    assert waiting.scene.run.stop_after_wall
    if wall_peak_planned(waits):
        assert waiting.scene.run.end_time >= end.value
        assert "the wall's contact" in dict((c.name, c.reason) for c in waiting.choices)["end_time"]


@settings(max_examples=200, deadline=None, derandomize=True)
@given(
    force=st.floats(0.0, 1e6),
    rises=st.lists(st.floats(0.0, 1e6), max_size=8),
    gaps=st.lists(st.integers(0, 8), min_size=1, max_size=4),
)
def test_end_contact_reached_leaves_out_the_contacts_without_a_peak(force, rises, gaps):
    """A nan among the other contacts' rises (a peak_force list's other contacts) is left out: the wall's
    or striker's contact is reached or not as without it. Fails before: np.max gave nan, and every end
    contact read 'not reached' (end_contact_reached(5.0, 0.0, [1.0, nan]) was False)."""
    with_nan = list(rises)
    for g in gaps:
        with_nan.insert(min(g, len(with_nan)), float("nan"))
    assert end_contact_reached(force, 0.0, with_nan) == end_contact_reached(force, 0.0, rises)
    assert end_contact_reached(5.0, 0.0, [1.0, float("nan")])
