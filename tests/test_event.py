"""The far-end wall's event ([outputs] event = true; issue 42 item 4): its largest force, impulse and
energy, tracked at every step on both backends (granchain.physics.event), and end_time = "auto"
planned to the event's end.

On generated walled chains (heavy strikers, kicks, tapers, precompression) the reported largest wall
force is the maximum of a dense wall-force history of a run continued to the event's end, and the
impulse its integral; the planned run covers the event; LAMMPS agrees with the reference's Verlet to
1e-9; a run that ends before the event says so; bad input is refused with one message.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.backends.builtin import ReferenceBackend
from granchain.postprocess.observables import unmeasured_outputs
from granchain.problem import ChainProblem, scene_static_forces
from granchain.reference.solver import solve_chain
from granchain.scene import SceneError, parse_scene
from granchain.workflows.plan import extended_plan, plan_scene

#: the run's rtol (the planner's default): the tracked values against a dense history at dt / 2
RTOL = 1e-3
#: how much longer than the event the dense run lasts (an unloaded chain: the wall is not touched again)
AFTER = 2.0


@st.composite
def walled_event_scenes(draw, max_beads: int = 10):
    """Small Hertz chains on a rigid wall asking for the event: a striker up to 8x a bead's mass (a
    heavy one pushes several times) or a kick, a taper or not, held on the wall by precompression or
    gravity or not."""
    beads = draw(st.integers(4, max_beads))
    radius = draw(st.floats(3e-3, 6e-3))
    chain = f'beads = {beads}\nradius = {radius!r}\nmaterial = "stainless-steel-316"\n'
    if draw(st.booleans()):
        chain += f"taper = {draw(st.floats(0.9, 0.99))!r}\n"
    v = draw(st.floats(0.05, 1.0))
    if draw(st.booleans()):
        mass = draw(st.floats(0.5, 8.0)) * 8000.0 * 4.18879 * radius**3
        loading = f'kind = "striker"\nvelocity = {v!r}\nmass = {mass!r}\n'
    else:
        loading = f'kind = "velocity"\nvelocity = {v!r}\n'
    text = (
        f'[chain]\n{chain}[contact]\nlaw = "hertz"\n[loading]\n{loading}'
        '[run]\nend_time = "auto"\ntimestep = "auto"\n[boundary]\nfar_end = "wall"\n'
        "[outputs]\npeak_force = true\nevent = true\n"
    )
    held = draw(st.sampled_from(["", "precompression", "gravity"]))
    if held == "precompression":
        text += f"[precompression]\nforce = {draw(st.floats(0.1, 5.0))!r}\n"
    elif held == "gravity":  # a vertical chain standing on the wall
        text += "[gravity]\ng = 9.81\n"
    return parse_scene(text, source="generated.toml")


def planned_run(scene, method: str = "verlet"):
    """The planned run (extended once where it ended before something asked for, as granchain run does)."""
    plan = plan_scene(scene, method=method)
    sol = ReferenceBackend().calculate(plan.scene, method).result.solution
    longer = extended_plan(scene, plan, sol)
    if longer is not None:
        plan = longer
        sol = ReferenceBackend().calculate(plan.scene, method).result.solution
    return plan.scene, sol


def dense_wall_history(scene, end: float, timestep: float):
    """The wall's contact force at every step of a run without a stop check to `end`: (time, force)."""
    n = scene.chain.beads
    sol = solve_chain(
        ChainProblem.from_scene(scene), end, timestep, "verlet", histories=(n - 1,), history_stride=1, progress=None
    )
    return sol.history_time, sol.history_force[:, 0]


@pytest.mark.slow
@settings(max_examples=12, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(scene=walled_event_scenes())
def test_the_event_is_covered_and_its_quantities_are_the_dense_history_s(scene):
    """The planned run ends with the event ended (the stop check waited for it), and its largest wall
    force and impulse are the maximum and the integral of the wall's force at every step of a run at
    dt / 2 continued to the event's end, within rtol. Fails before: no event was tracked (no fields),
    and end_time = "auto" ended at the wall's first complete peak."""
    planned, sol = planned_run(scene)
    assert sol.event_end_time is not None, f"the event had not ended at {sol.end_time:.4g} s\n{scene.to_toml()}"
    t, f = dense_wall_history(planned, AFTER * sol.event_end_time, planned.run.timestep / 2)
    if not (planned.effects.precompression or planned.effects.gravity):  # left the wall for good: untouched after
        assert not (f[t > sol.event_end_time] > 0.0).any(), f"the wall is touched again\n{scene.to_toml()}"
    f, t = f[t <= sol.event_end_time], t[t <= sol.event_end_time]
    static = float(scene_static_forces(planned)[-1])
    dyn = f - static
    scale = float(np.max(dyn))
    assert sol.wall_max_force == pytest.approx(scale, rel=RTOL)
    assert sol.wall_time_of_max == pytest.approx(float(t[np.argmax(dyn)]), abs=4 * planned.run.timestep)
    impulse = float(np.trapezoid(f, t))
    assert sol.wall_impulse == pytest.approx(impulse, rel=RTOL)
    assert sol.wall_dynamic_impulse == pytest.approx(float(np.trapezoid(dyn, t)), rel=RTOL, abs=RTOL * impulse)
    assert sol.wall_energy > 0.0


def test_an_unloaded_chains_impulse_is_the_momentum_it_lost():
    """On a chain free of external forces the wall is the only one: velocity Verlet's momentum changes by
    exactly the trapezoid of the wall's force, so the impulse is p(0) - p(t_end) to round-off, and the
    chain's last contact with the wall is inside the event (a heavy striker's second push)."""
    scene = parse_scene(HEAVY_STRIKER)
    _, sol = planned_run(scene)
    p0 = scene.initial_momentum
    assert sol.event_end_time is not None
    assert sol.wall_impulse == pytest.approx(p0 - sol.momentum, rel=1e-9)
    # the event outlasts the wall's first peak: the heavy striker pushes the chain into the wall again
    assert sol.wall_impulse > 1.5 * p0


#: a striker of 4 beads' mass on 8 stainless beads on a wall: it pushes more than once
HEAVY_STRIKER = """
[chain]
beads = 8
radius = 0.004
material = "stainless-steel-316"
[contact]
law = "hertz"
[loading]
kind = "striker"
velocity = 0.3
mass = 0.0085
[run]
end_time = "auto"
timestep = "auto"
[boundary]
far_end = "wall"
[outputs]
peak_force = true
event = true
"""


def test_a_run_that_ends_before_the_event_says_so():
    """A given end time before the event's end: the event's quantities are None with the reason, and the
    command line's unmeasured outputs name them (exit 1)."""
    scene = parse_scene(HEAVY_STRIKER.replace('end_time = "auto"', "end_time = 2e-4"))
    result = ReferenceBackend().calculate(plan_scene(scene, method="verlet").scene, "verlet").result
    obs, missing = result.observables(), result.observables_missing()
    for name in ("wall_max_force", "wall_impulse", "wall_energy"):
        assert obs[name] is None, name
    assert "the event had not ended when the run did" in missing["wall_impulse"]
    lines = unmeasured_outputs(result.scene, result.solution)
    assert any(x.startswith("wall_max_force:") for x in lines), lines


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (HEAVY_STRIKER.replace("event = true", 'event = "yes"'), r"event.*true or false"),
    ],
)
def test_bad_event_input_is_refused_with_one_message(text, match):
    with pytest.raises(SceneError, match=match):
        parse_scene(text)


#: the event's quantities LAMMPS and the reference's Verlet must agree on
QUANTITIES = ("wall_max_force", "wall_time_of_max", "wall_impulse", "wall_dynamic_impulse", "wall_energy")


@pytest.mark.parametrize(
    "text",
    [
        HEAVY_STRIKER,
        HEAVY_STRIKER.replace("radius = 0.004\n", "radius = 0.004\ntaper = 0.93\n").replace(
            'kind = "striker"\nvelocity = 0.3\nmass = 0.0085', 'kind = "velocity"\nvelocity = 0.5'
        ),
        HEAVY_STRIKER + "[precompression]\nforce = 2.0\n",
        HEAVY_STRIKER + "[gravity]\ng = 9.81\n",
    ],
    ids=["heavy-striker", "taper-kick", "precompressed", "gravity"],
)
def test_lammps_is_the_reference_verlet_on_the_event(text):
    """Both backends track the event at every step alike: the same end, and every quantity to 1e-9."""
    from granchain.backends.builtin import LammpsBackend

    planned = plan_scene(parse_scene(text), method="verlet").scene
    ref = ReferenceBackend().calculate(planned, "verlet").result.solution
    backend = LammpsBackend()
    backend.prepare()
    lam = backend.calculate(planned, "verlet").result.solution
    assert ref.event_end_time is not None
    assert lam.event_end_time == pytest.approx(ref.event_end_time, rel=1e-12)
    for name in QUANTITIES:
        assert getattr(lam, name) == pytest.approx(getattr(ref, name), rel=1e-9), name


@pytest.mark.parametrize(
    "text",
    [
        pytest.param(HEAVY_STRIKER, marks=pytest.mark.slow, id="striker"),  # 11 s: its companions and dt / 8
        pytest.param(HEAVY_STRIKER + "[precompression]\nforce = 2.0\n", id="held"),
    ],
)
def test_the_event_quantities_error_bars_are_within_a_factor_3_of_the_true_error(text):
    """The companions' bars (2 dt, 4 dt, extrapolated) against the error measured from a run at dt / 8:
    within [1/3, 3], or a status that says why there is none."""
    from dataclasses import replace

    from granchain.workflows.run import run_scene

    result = run_scene(parse_scene(text), backend="reference", method="verlet", error_estimate=True)
    planned = result.scene
    fine = replace(planned, run=replace(planned.run, timestep=planned.run.timestep / 8))
    truth = ReferenceBackend().calculate(fine, "verlet").result.observables()
    for name in ("wall_max_force", "wall_impulse", "wall_energy"):
        bar = result.errors.observables[name]
        true = abs(result.observables()[name] - truth[name])
        if bar.get("error") is None:
            assert bar.get("status"), (name, bar)
            continue
        assert true / 3 <= bar["error"] <= 3 * true, (name, bar, true)
