"""The leading pulse (results.leading_pulse): tracked in the run by both backends, the same way."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings

from granchain.cli import resolve_scene
from granchain.scene import parse_scene
from granchain.workflows.run import plan_for, run_scene
from tests.scenegen import scenes


@pytest.mark.parametrize("name", ["default", "plastic-short-impulse", "effect-precompression", "effect-wall"])
def test_lammps_and_reference_verlet_track_the_same_leading_pulse(name):
    sc, _ = plan_for(resolve_scene(name), "lammps", None, 1e-2)
    lam = run_scene(sc, backend="lammps").solution
    ref = run_scene(sc, method="verlet").solution
    assert np.array_equal(np.isfinite(lam.leading_pulse_force), np.isfinite(ref.leading_pulse_force))
    ok = np.isfinite(ref.leading_pulse_force)
    assert ok.sum() >= 3
    scale = np.max(ref.peak_force)
    np.testing.assert_allclose(lam.leading_pulse_force[ok], ref.leading_pulse_force[ok], rtol=1e-7, atol=1e-9 * scale)
    np.testing.assert_allclose(lam.leading_pulse_time[ok], ref.leading_pulse_time[ok], rtol=1e-9)


@settings(max_examples=15, deadline=None)
@given(scene=scenes(max_beads=30))
def test_leading_pulse_comes_first_and_is_a_passed_maximum(scene):
    """On any scene: the leading pulse is never above the largest peak nor later than it, and where
    no later pulse is larger, the two are the same maximum at the same time."""
    sc, _ = plan_for(scene, "reference", "verlet", 1e-2)
    sol = run_scene(sc, method="verlet").solution
    ok = np.isfinite(sol.leading_pulse_force)
    assert np.all(sol.leading_pulse_force[ok] <= sol.peak_force[ok])
    assert np.all(sol.leading_pulse_time[ok] <= sol.time_of_peak[ok])
    same = sol.leading_pulse_force[ok] == sol.peak_force[ok]
    assert np.all(sol.leading_pulse_time[ok][same] == sol.time_of_peak[ok][same])


def test_a_plastic_front_leads_with_its_first_pulse_not_its_largest():
    """Behind a bilinear chain's front under a long step the force oscillates, and at some contacts a
    later oscillation is larger than the front's pulse: the leading pulse is the first, earlier than
    the largest, and it converges with the time step (LAMMPS, planned at rtol 1e-3, against dt / 4)."""
    from tests.test_trust import STEEL

    sc, _ = plan_for(parse_scene(STEEL.format(beads=120), source="steel.toml"), "lammps", None, 1e-3)
    sol = run_scene(sc, backend="lammps").solution
    fine = run_scene(replace(sc, run=replace(sc.run, timestep=sc.run.timestep / 4)), backend="lammps").solution
    c = np.flatnonzero(np.isfinite(sol.leading_pulse_time) & np.isfinite(fine.leading_pulse_time))
    assert c.size > 50
    assert np.any(sol.leading_pulse_time[c] < sol.time_of_peak[c])  # a later pulse is larger somewhere
    assert np.max(np.abs(sol.leading_pulse_force[c] / fine.leading_pulse_force[c] - 1)) < 1e-3
    assert np.max(np.abs(sol.leading_pulse_time[c] / fine.leading_pulse_time[c] - 1)) < 1e-3
