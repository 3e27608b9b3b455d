"""The leading pulse (peaks.leading_pulse): tracked in the run by both backends, the same way."""

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
    from tests.test_plan_and_user_errors import STEEL

    sc, _ = plan_for(parse_scene(STEEL.format(beads=120), source="steel.toml"), "lammps", None, 1e-3)
    sol = run_scene(sc, backend="lammps").solution
    fine = run_scene(replace(sc, run=replace(sc.run, timestep=sc.run.timestep / 4)), backend="lammps").solution
    c = np.flatnonzero(np.isfinite(sol.leading_pulse_time) & np.isfinite(fine.leading_pulse_time))
    assert c.size > 50
    assert np.any(sol.leading_pulse_time[c] < sol.time_of_peak[c])  # a later pulse is larger somewhere
    assert np.max(np.abs(sol.leading_pulse_force[c] / fine.leading_pulse_force[c] - 1)) < 1e-3
    assert np.max(np.abs(sol.leading_pulse_time[c] / fine.leading_pulse_time[c] - 1)) < 1e-3


def first_maximum(t, f, f0, floor):
    """The first maximum of sampled forces rising more than floor above f0: the first sample above
    its left neighbour (or equal) and strictly above its right one, its value the running peak there
    refined by the parabola through the three samples (what the backends track); (nan, nan) if none."""
    peak, tpeak = f[0], t[0]
    for i in range(1, len(f)):
        if f[i] > peak:
            peak, tpeak = f[i], t[i]
        if i < 2 or not (f[i - 1] > f[i] and f[i - 1] >= f[i - 2] and f[i - 1] > 0):
            continue
        a, b = t[i - 2] - t[i - 1], t[i] - t[i - 1]
        fa, fb = f[i - 2] - f[i - 1], f[i] - f[i - 1]
        det = a * b * (b - a)
        c1, c2 = (fa * b * b - fb * a * a) / det, (a * fb - b * fa) / det
        if c2 < 0:
            s = min(max(-c1 / (2 * c2), a), b)
            v = f[i - 1] + (c1 + c2 * s) * s
            if v > peak:
                peak, tpeak = v, t[i - 1] + s
        if peak - f0 > floor:
            return peak, tpeak
    return np.nan, np.nan


@settings(max_examples=12, deadline=None)
@given(scene=scenes(max_beads=25))
def test_leading_pulse_is_the_first_maximum_of_the_force_history(scene):
    """On any scene (Verlet, every step sampled at every contact): the tracked leading pulse is the
    first maximum of the contact's sampled force above the floor, not a later or larger one."""
    from granchain.peaks import lead_floor

    sc, _ = plan_for(scene, "reference", "verlet", 1e-2)
    n = sc.chain.beads
    sc = replace(sc, outputs=replace(sc.outputs, histories=tuple(range(1, n)), history_interval=None))
    sol = run_scene(sc, method="verlet").solution
    f0 = float(sc.effects.precompression)
    t = np.concatenate([[0.0], sol.history_time]) if sol.history_time[0] > 0 else sol.history_time
    for j, c in enumerate(range(1, n)):
        f = sol.history_force[:, j]
        if t.size == f.size + 1:
            f = np.concatenate([[f0 if f0 else 0.0], f])
        want, when = first_maximum(t, f, f0, lead_floor(sc))
        got, got_t = sol.leading_pulse_force[c - 1], sol.leading_pulse_time[c - 1]
        if np.isnan(got):
            assert np.isnan(want) or not np.isfinite(sol.time_of_peak[c - 1]), c
            continue
        assert got == pytest.approx(want, rel=1e-12), c
        assert got_t == pytest.approx(when, rel=1e-12), c


def test_a_plateau_front_leads_with_its_first_overshoot():
    """A steel bilinear chain under a 2 kN step: at contact 100 the front rises to a plateau whose
    later oscillations are larger than its first overshoot (the old definition took the largest before
    the force fell to half: 21% higher at contact 186 of a 250-bead chain). The leading pulse is the
    first maximum of the history."""
    from granchain.peaks import lead_floor
    from tests.test_plan_and_user_errors import STEEL

    sc, _ = plan_for(parse_scene(STEEL.format(beads=150), source="steel.toml"), "lammps", None, 1e-3)
    sc = replace(sc, outputs=replace(sc.outputs, histories=(60, 100), history_interval=None))
    sol = run_scene(sc, backend="lammps").solution
    for j, c in enumerate((60, 100)):
        want, when = first_maximum(sol.history_time, sol.history_force[:, j], 0.0, lead_floor(sc))
        assert sol.leading_pulse_force[c - 1] == pytest.approx(want, rel=1e-9)
        assert sol.leading_pulse_time[c - 1] == pytest.approx(when, rel=1e-9)
    assert np.any(sol.leading_pulse_force < sol.peak_force * (1 - 1e-3))  # later, larger pulses exist
