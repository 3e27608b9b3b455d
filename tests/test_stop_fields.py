"""The stop check ([run] stop_after_contact and stop_after_wall, Run.stop_check) travels with every
plan a run is rebuilt from: the planner on a scene that gives its stop check, the refined plan (a
finer step), the extended plan (a later end), the error bars' companions (2 dt, 4 dt) and the scene
file written and read back. A walled run that loses stop_after_wall stops once the wave has passed
its last measured contact and reports the wall's peak "incomplete: the wave had not reached it".
"""

import math
from dataclasses import replace

import pytest

from granchain.scene import parse_scene, scene_from_dict, scene_to_dict
from granchain.scene.run_outputs import stop_fields
from granchain.workflows.error_estimates import companion_scene
from granchain.workflows.plan import extended_plan, plan_scene, refined_plan

#: an aluminium bilinear chain struck at 2 m/s on a wall, peak forces asked for: its front decays
#: from 193 N at contact 1 to 13.85 N at contact 21, so the planned Verlet run is refined (1/14 of the
#: force scale: 7.44e-8 s -> 1.99e-8 s) and its wall's peak is 21.89 N
BILINEAR_WALL = """
title = "bilinear aluminium chain, velocity 2 m/s, wall"
[chain]
beads = 30
radius = 5e-3
material = "aluminium-6061-t6"
[contact]
law = "bilinear"
unloading_coeff = 0.8
[loading]
kind = "velocity"
velocity = 2.0
[boundary]
far_end = "wall"
[run]
end_time = "auto"
timestep = "auto"
{stop}
[outputs]
peak_force = true
"""

#: a non-default value of each stop field (a new stop field must be given one here)
STOP_VALUES = {"stop_after_contact": 21, "stop_after_wall": True, "stop_after_reflection": True}
GIVEN_STOP = "\n".join(f"{k} = {str(v).lower() if isinstance(v, bool) else v}" for k, v in STOP_VALUES.items())


def given_stop_scene():
    return parse_scene(BILINEAR_WALL.format(stop=GIVEN_STOP), source="bil-alu-wall.toml")


def _cut_run(sc, plan):
    """A real run of plan cut at 3e-4 s (before the wall's pulse, after contact 21's): its front fell
    to 1/14 of its force scale (refined_plan) and the wall's peak is not complete at its end
    (extended_plan)."""
    from granchain.backends.builtin import ReferenceBackend

    cut = replace(plan, scene=replace(plan.scene, run=replace(plan.scene.run, end_time=3e-4)))
    sol = ReferenceBackend().calculate(cut.scene, "verlet", 1).result.solution
    assert sol.wall_peak_complete is False
    return cut, sol


def test_every_stop_field_is_given_a_value():
    """STOP_VALUES covers Run's stop fields, so the transformations below test each of them."""
    assert set(STOP_VALUES) == {f.name for f in stop_fields()}
    assert given_stop_scene().run.stop_check() == STOP_VALUES


_CACHE = {}


def _transformations():
    if _CACHE:
        return _CACHE
    sc = given_stop_scene()
    planned = plan_scene(sc, method="verlet")
    out = _CACHE
    out["planned"] = planned.scene
    out["planned for --rtol"] = plan_scene(sc, rtol=1e-3, method="verlet").scene
    out["planned for --rtol, a concrete saved scene"] = plan_scene(planned.scene, rtol=1e-3, method="verlet").scene
    cut, sol = _cut_run(sc, planned)
    refined = refined_plan(sc, cut, sol)
    assert refined is not None
    assert refined.scene.run.timestep < planned.scene.run.timestep
    out["refined"] = refined.scene
    extended = extended_plan(sc, cut, sol)
    assert extended is not None
    assert extended.scene.run.end_time > cut.scene.run.end_time
    out["extended"] = extended.scene
    for factor in (2.0, 4.0):
        out[f"companion at {factor:g} dt"] = companion_scene(planned.scene, factor)
    out["written and read"] = scene_from_dict(scene_to_dict(planned.scene), source="saved.toml")
    return out


TRANSFORMATIONS = [
    "planned",
    "planned for --rtol",
    "planned for --rtol, a concrete saved scene",
    "refined",
    "extended",
    "companion at 2 dt",
    "companion at 4 dt",
    "written and read",
]


@pytest.mark.parametrize("name", TRANSFORMATIONS)
def test_each_plan_transformation_keeps_the_stop_check(name):
    """Fails before on "planned", "planned for --rtol" and "refined" (the planner rebuilt [run] from
    end_time, timestep and stop_after_contact: stop_after_wall = false), so the refined run stopped at
    contact 21 (2.26e-4 s) and the wall's peak was not reached."""
    scene = _transformations()[name]
    assert scene.run.stop_check() == STOP_VALUES


def test_the_planned_stop_check_travels_through_every_transformation():
    """On the scene as the user writes it ("auto", no stop check) the planner chooses the stop check
    with the wall's, and refinement, extension and the companions keep it."""
    sc = parse_scene(BILINEAR_WALL.format(stop=""), source="bil-alu-wall.toml")
    planned = plan_scene(sc, method="verlet")
    assert planned.scene.run.stop_check() == STOP_VALUES
    cut, sol = _cut_run(sc, planned)
    refined, extended = refined_plan(sc, cut, sol), extended_plan(sc, cut, sol)
    for scene in (
        refined.scene,
        extended.scene,
        companion_scene(planned.scene, 2.0),
        companion_scene(refined.scene, 4.0),
    ):
        assert scene.run.stop_check() == STOP_VALUES


def test_without_stop_clears_every_stop_field():
    run = given_stop_scene().run.without_stop()
    assert run.stop_check() == {}
    assert run.end_time is None
    assert run.timestep is None


def _wall(result):
    sol = result.solution
    bar = result.errors.end_peaks.get("wall_peak_force") if result.errors is not None else None
    return sol.wall_peak_force, sol.wall_peak_complete, bar


def _check_refined_wall(backend, method, scene, off):
    """The default run (error bars on) of scene is refined, keeps stop_after_wall, and its wall's peak is
    complete, with a bar, and within the bar of the run without error bars."""
    from granchain.workflows.run import PlanRefinedWarning, run_scene

    with pytest.warns(PlanRefinedWarning):
        res = run_scene(scene, backend=backend, method=method, error_estimate=True)
    assert res.plan.scene.run.stop_after_wall
    force, complete, bar = _wall(res)
    assert complete
    assert bar is not None
    assert bar["error"] is not None, bar
    assert math.isfinite(bar["error"]), bar
    assert res.solution.end_time > 4e-4  # the wall's pulse passes at about 5.6e-4 s; contact 21 at 2.3e-4 s
    off_force, off_complete, _ = _wall(off)
    assert off_complete
    assert abs(force - off_force) <= bar["error"]
    return res


def test_reference_run_of_a_scene_giving_the_wall_stop_keeps_it_when_refined():
    """The reference's Verlet run (error bars on) of a walled chain that gives its stop check
    (stop_after_contact = 21, stop_after_wall = true) is refined and measures the wall's peak (21.89 N),
    as its run without error bars does. Fails before: the planner dropped stop_after_wall and the run
    stopped at 2.26e-4 s, the wall's peak not reached."""
    from granchain.workflows.run import PlanRefinedWarning, run_scene

    sc = given_stop_scene()
    with pytest.warns(PlanRefinedWarning):
        off = run_scene(sc, method="verlet", error_estimate=False)
    _check_refined_wall("reference", "verlet", sc, off)


def test_lammps_default_run_of_a_refined_walled_chain_measures_the_wall():
    """LAMMPS, error bars on (the default), on the walled chain as written ("auto", no stop check): the
    run is refined (7.44e-8 s -> 1.99e-8 s), keeps stop_after_wall and measures the wall's peak (21.8918
    N, bar 0.0018 N), equal within its bar to the run without error bars; the saved scene keeps it."""
    from granchain.workflows.run import PlanRefinedWarning, run_scene

    sc = parse_scene(BILINEAR_WALL.format(stop=""), source="bil-alu-wall.toml")
    with pytest.warns(PlanRefinedWarning):
        off = run_scene(sc, backend="lammps", error_estimate=False)
    res = _check_refined_wall("lammps", None, sc, off)
    saved = scene_from_dict(scene_to_dict(res.scene), source="saved.toml")
    assert saved.run.stop_check() == STOP_VALUES
