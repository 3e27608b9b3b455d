"""Error bars on the kinked laws (bilinear, Thornton) with Verlet (reference and LAMMPS).

By default a Verlet run on a law whose slope jumps at kinks gets bounds (richardson.erratic_bounds)
from its own runs at 2 dt and 4 dt (3/4 of the run's steps): its error is erratic in sign
(workflows.error_estimates.bounded_because). A bound may overstate the error many times and says so;
here, on generated scenes, every bar given is at least 1/3 of the true error.

Asked for (error_estimate="checked"), such a run is measured against RK4 runs (event location) at RK4's
own step for a share of Verlet's predicted error (workflows.error_estimates.against_rk4_factors), far
coarser than the run's. Whether that step is fine enough is checked run by run
(richardson.against_reference: no estimate where RK4's own error is not small beside the distance);
here, on generated scenes, the estimates given are within [1/3, 3] of the true error.

The truth is RK4 at the run's own dt: its error is below the companions' by (companion step / dt)^4
and below Verlet's by about (omega dt)^2.
"""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.integrators import RK4
from granchain.lammps import server
from granchain.workflows import error_estimates as errors
from granchain.workflows.error_estimates import rk4_companions_cost
from granchain.workflows.plan import highest_frequency, predicted_error
from granchain.workflows.run import plan_for, run_scene

from .conftest import make_scene
from .scenegen import scenes

KINKED = ("bilinear", "thornton")


def kinked_scenes(max_beads: int):
    """Generated scenes of a kinked law without a dashpot (with one, Richardson stays: RK4 cannot locate
    the dashpot's clip, errors.withheld_because)."""
    return st.sampled_from(KINKED).flatmap(
        lambda law: scenes(law=law, max_beads=max_beads).filter(lambda s: not s.effects.dashpot)
    )


def effectivity(sc, backend: str, mode="checked") -> tuple[np.ndarray, np.ndarray]:
    """Estimated / true peak-force error of a Verlet run of sc (planned for rtol 1e-3) on the backend,
    wherever the true error is above round-off and an estimate is given, and those estimates' statuses;
    mode: error_estimate ("checked": against RK4 runs; True: the default bounds)."""
    method = None if backend == "lammps" else "verlet"
    sc, _ = plan_for(sc, backend, method, 1e-3)
    sc = replace(sc, outputs=replace(sc.outputs, histories=(), snapshots=(), history_interval=None, dump_interval=None))
    got = run_scene(sc, backend=backend, method=method, error_estimate=mode)
    if mode == "checked":
        assert got.errors.against == "rk4", got.errors.why_none
    else:
        assert got.errors.against is None, got.errors.why_none
        assert got.errors.bound, got.errors.why_none
    truth = run_scene(sc, method="rk4")
    a, b = got.solution, truth.solution
    true = np.abs(a.peak_force - b.peak_force)
    above = a.complete & b.complete & (true > 1e3 * np.spacing(np.abs(a.peak_force)))
    est = got.errors.peak_force
    ok = above & est.reliable
    return est.error[ok] / true[ok], est.status[ok]


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["reference", "lammps"])
@settings(max_examples=4, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(sc=kinked_scenes(max_beads=24))
def test_kinked_law_estimates_against_rk4_are_within_a_factor_3_of_the_true_error(backend, sc):
    ratio, _ = effectivity(sc, backend)
    assert np.all((ratio >= 1 / 3) & (ratio <= 3)), f"ratios {np.sort(ratio)[[0, -1]]}"


@pytest.mark.slow
@settings(max_examples=12, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(sc=kinked_scenes(max_beads=60))
def test_kinked_law_default_bars_are_at_least_a_third_of_the_true_error(sc):
    """LAMMPS's default bars on a kinked law (bounds) never understate the true error more than 3x, and
    each says it is a bound that may overstate it (the reference's Verlet is measured against RK4 by
    default: the test above)."""
    backend = "lammps"
    ratio, status = effectivity(sc, backend, True)
    assert all(str(st).startswith("bound: kinked law") or st == "round-off" for st in status), set(status)
    assert np.all(ratio >= 1 / 3), f"ratios {np.sort(ratio)[:3]}"


def test_kinked_verlet_bars_come_from_its_own_companions_by_default():
    """A LAMMPS run on a kinked law: by default its bars are bounds from its runs at 2 dt and 4 dt (3/4
    of the run's steps, no RK4 run: RK4 in numpy costs some ten LAMMPS runs), each status and the
    method line saying so; with error_estimate="checked" it is measured against RK4 runs, and the
    default's why_unchecked says what it leaves and how to ask for that. A reference Verlet run (numpy
    itself) is measured against RK4 runs by default where they cost at most the run: at a step a tenth
    of the planned one, not at the planned step (RK4 at about 3 dt there)."""
    from granchain.scene import parse_scene

    from .test_error_estimate import BILINEAR_CHAIN

    sc = parse_scene(BILINEAR_CHAIN.replace("beads = 25", "beads = 12"), source="b.toml")
    plain = run_scene(sc, backend="lammps", error_estimate=True)
    e, dt = plain.errors, plain.scene.run.timestep
    assert e.against is None
    assert e.timesteps == pytest.approx([2 * dt, 4 * dt])
    assert sum(dt / h for h in e.timesteps) < 1  # the companions' steps: 3/4 of the run's
    status = [str(st) for st in e.peak_force.status]
    assert any(st.startswith("bound: kinked law") and "may overstate" in st for st in status), status
    assert not any(st.startswith(("nominal", "observed")) for st in status), status
    assert "may overstate" in e.summary(1.0)["method"]
    assert "--error-estimate checked" in e.why_unchecked
    got = run_scene(sc, backend="lammps", error_estimate="checked").errors
    assert got.against == "rk4"
    assert got.bound is None
    assert "RK4" in got.why_unchecked
    planned = plan_for(sc, "reference", "verlet", None)[0]
    fine = replace(planned, run=replace(planned.run, timestep=planned.run.timestep / 10))
    for scene, rk4 in ((planned, False), (fine, True)):
        assert (rk4_companions_cost(scene) <= 1.0) == rk4
        ref = run_scene(scene, backend="reference", method="verlet", error_estimate=True).errors
        assert (ref.against == "rk4") == rk4
        assert (ref.bound is None) == rk4


@settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(sc=kinked_scenes(max_beads=60))
def test_rk4_companions_aim_at_a_share_of_verlet_error_within_stability(sc):
    """The RK4 companions' step h (and 2 h): RK4's predicted error at h at most RK4_COMPANION_SHARE of
    the Verlet run's predicted error, within half RK4's stability limit; never below 2 dt unless that
    is unstable."""
    sc, _ = plan_for(sc, "lammps", None, 1e-3)
    omega = highest_frequency(sc)[0]
    dt = sc.run.timestep
    f1, f2 = errors.against_rk4_factors(sc)
    assert f2 == pytest.approx(2 * f1)
    h = f1 * dt
    if f1 >= errors.SHARED_BELOW:
        target = errors.RK4_COMPANION_SHARE * predicted_error("verlet", omega, 0.0, dt)
        assert predicted_error("rk4", omega, 0.0, h) <= target * (1 + 1e-9)
        assert h <= 0.5 * RK4.stability / omega * (1 + 1e-12)
    else:
        assert (f1, f2) in ((2.0, 4.0), (1.0, 2.0))


def test_lammps_companions_share_one_kept_lammps_instance():
    """Richardson's LAMMPS companions (2 dt, 4 dt) run on one kept LAMMPS child: the second is that
    child's second run, not a new process paying LAMMPS's start-up again; after them no child is left."""
    sc = make_scene(beads=12, end_time=3e-5, timestep=2e-8)
    got = run_scene(sc, backend="lammps")
    from granchain.lammps.runner import cleanup, run_lammps

    runs = []

    def run_one(scene):
        result, work = run_lammps(scene)
        cleanup(work)
        runs.append(result.extra["instance_run"])
        return result

    report = errors.estimate_errors(got, run_one, "verlet", stable_timestep=1.0)
    assert report.why_none is None
    assert len(report.wall_times) == 2
    assert runs == [1, 2]
    assert not server.enabled()
    assert server.children() == []
