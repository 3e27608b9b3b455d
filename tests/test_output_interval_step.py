"""A given output interval shorter than the planner's step shortens the step, and the plan says so: the
time step choice's value is the run's step and its reason names the interval (and the one that keeps
the planned step); the output-size warning names only files the backend writes (the reference writes no
chain.dump)."""

from dataclasses import replace

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from granchain.workflows.guards import output_sizes
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import OUTPUT_WARN_BYTES, output_size_warning
from tests.scenegen import scenes


def _with_interval(scene, key: str, value: float):
    return replace(scene, outputs=replace(scene.outputs, **{key: value}))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    scene=scenes(max_beads=30),
    key=st.sampled_from(["history_interval", "dump_interval"]),
    shrink=st.floats(1.5, 1e6),
    rtol=st.sampled_from([None, 1e-3, 1e-5]),
)
def test_timestep_choice_is_the_run_step(scene, key, shrink, rtol):
    planned = plan_scene(scene, rtol=rtol).choices
    dt = next(c.value for c in planned if c.name == "timestep")
    interval = dt / shrink
    plan = plan_scene(_with_interval(scene, key, interval), rtol=rtol)
    choice = next(c for c in plan.choices if c.name == "timestep")
    assert choice.value == plan.scene.run.timestep  # what plan prints is what runs
    if interval < plan.scene.run.end_time:
        assert plan.scene.run.timestep <= interval
        assert f"[outputs] {key} = {interval:g} s" in choice.reason
        assert f"{key} >= {dt:.3g} s keeps the planned step" in choice.reason


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene=scenes(max_beads=30), grow=st.floats(1.0, 10.0))
def test_a_larger_interval_keeps_the_planned_step(scene, grow):
    plan = plan_scene(scene)
    dt = plan.scene.run.timestep
    assume(dt * grow <= plan.scene.run.end_time)  # an interval may not exceed the run (the scene's rule)
    again = plan_scene(_with_interval(scene, "dump_interval", dt * grow))
    assert again.scene.run.timestep == dt
    assert [c.reason for c in again.choices if c.name == "timestep"] == [
        c.reason for c in plan.choices if c.name == "timestep"
    ]


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene=scenes(max_beads=30))
def test_output_size_warning_names_only_files_the_backend_writes(scene):
    dt = plan_scene(scene).scene.run.timestep
    planned = plan_scene(_with_interval(scene, "dump_interval", dt)).scene
    # a dump interval that makes chain.dump far larger than the warning's threshold, no other big file
    sizes = output_sizes(planned)
    factor = 10 * OUTPUT_WARN_BYTES / sizes["chain.dump"]
    big = replace(planned, run=replace(planned.run, end_time=planned.run.end_time * max(factor, 1.0)))
    big = replace(big, outputs=replace(big.outputs, histories=()))
    assert output_sizes(big)["chain.dump"] > OUTPUT_WARN_BYTES
    assert output_size_warning(big, "reference") is None
    msg = output_size_warning(big, "lammps")
    assert msg is not None
    assert "chain.dump" in msg
