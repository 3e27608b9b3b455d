"""Issue 11's property: on any valid scene with timestep = "auto", for rtol 1e-2 and 1e-3 and for
RK4, reference Verlet and LAMMPS, every complete measured peak is within rtol of a run at a quarter
of the planned step (the step the run ran: planned, or refined when its measured peaks fell far
below its force scale, granchain.workflows.plan.refined_plan).

The achieved error over rtol of every example is appended to the file named by
$GRANCHAIN_PROPERTY_LOG (when set), one line per run, for the note's table.
"""

import os
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import assume, given, settings

from granchain.workflows.run import plan_for, run_scene
from tests.scenegen import scenes

#: the runs this property can afford in CI: the quarter-step run's bead-steps. A generated chain with a
#: strong dashpot plans Verlet's step from its first-order dashpot term (and a refined plan up to 16x
#: finer): 4.8e7 steps were measured for one draw, minutes of numpy for one example. Such draws are
#: outside what CI checks here, not outside what the planner promises (say so: the note of stop 21).
MAX_BEAD_STEPS = 2e7

INTEGRATORS = {"rk4": ("reference", "rk4"), "verlet": ("reference", "verlet"), "lammps": ("lammps", None)}


def achieved_error(scene, backend, method, rtol):
    """The largest relative difference of complete peaks (complete in both runs) between the planned
    run and a run at a quarter of its step; and how many peaks it was taken over."""
    first, _ = plan_for(scene, backend, method, rtol)
    assume(4 * first.run.end_time / first.run.timestep * first.chain.beads <= MAX_BEAD_STEPS)
    result = run_scene(scene, backend=backend, method=method, rtol=rtol)  # planned, refined if its peaks fell
    got, planned = result.solution, result.plan.scene
    assume(4 * planned.run.end_time / planned.run.timestep * planned.chain.beads <= MAX_BEAD_STEPS)
    fine_scene = replace(planned, run=replace(planned.run, timestep=planned.run.timestep / 4))
    fine = run_scene(fine_scene, backend=backend, method=method).solution
    both = got.complete & fine.complete
    if not both.any():
        return 0.0, 0
    rel = np.abs(got.peak_force[both] / fine.peak_force[both] - 1.0)
    return float(rel.max()), int(both.sum())


@pytest.mark.slow
@pytest.mark.parametrize(
    ("integrator", "rtol"), [(i, r) for i in INTEGRATORS for r in (1e-2, 1e-3) if (i, r) != ("verlet", 1e-3)]
)
@settings(max_examples=8, deadline=None, derandomize=True)
@given(scene=scenes(max_beads=40))
def test_planned_step_meets_rtol_on_any_scene(scene, rtol, integrator):
    check_planned_step(scene, rtol, integrator)


# the reference's Verlet at rtol 1e-3 is the slow set's longest case (250 s of CI's 30 minutes at 8
# draws, its steps a tenth of rtol 1e-2's): 4 draws
@pytest.mark.slow
@settings(max_examples=4, deadline=None, derandomize=True)
@given(scene=scenes(max_beads=40))
def test_planned_verlet_step_meets_rtol_1e_3_on_any_scene(scene):
    check_planned_step(scene, 1e-3, "verlet")


def check_planned_step(scene, rtol, integrator):
    """The planned run's complete peaks within rtol of a run at a quarter of its step."""
    backend, method = INTEGRATORS[integrator]
    err, n = achieved_error(scene, backend, method, rtol)
    log = os.environ.get("GRANCHAIN_PROPERTY_LOG")
    if log:
        with open(log, "a") as f:
            f.write(f"{integrator} {rtol:g} {err / rtol:.4g} {n} {scene.contact.law} {scene.loading.kind}\n")
    assert err <= rtol, f"{integrator} at rtol {rtol:g}: {err:.3g} over {n} complete peaks\n{scene.to_toml()}"
