"""Complete peaks and the end-of-run state in the summary.

A contact's peak is complete once its force has fallen to PEAK_PASSED_FRACTION of the peak (both
above the static force) at some sample after the peak (granchain.peaks.complete_peaks). A peak
that is not complete is marked so in the solution, peaks.csv and summary.json and never feeds an
observable. The summary's energies are those of the end of the run, not of the last periodic
energy sample.
"""

import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.cli import resolve_scene
from granchain.peaks import PEAK_PASSED_FRACTION, complete_peaks, still_rising
from granchain.postprocess.comparison_table import compare_runs
from granchain.postprocess.dumps import complete_from_samples
from granchain.postprocess.observables import fit_wave_speed, measure_observables
from granchain.reference.solver import ChainProblem, solve_chain
from granchain.rundir import read_peaks, read_summary
from granchain.scene import parse_scene
from granchain.workflows.run import run_reference, run_scene

from .conftest import LAW_NAMES, make_scene, make_scene_text

SHORT = 'kind = "impulse"\nimpulse = 0.1\nduration = 1e-6'


def _with_end_time(scene, end_time):
    return dataclasses.replace(scene, run=dataclasses.replace(scene.run, end_time=end_time))


# ---- the bundled default scene: the wave is at contacts 96-99 when the run ends


@pytest.fixture(scope="module")
def default_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("default") / "run"
    res = run_scene(resolve_scene("default"), out=out)
    return res, out


def test_default_scene_peaks_at_the_end_are_incomplete(default_run):
    res, out = default_run
    s = res.solution
    assert s.complete.dtype == bool
    assert s.complete.shape == s.peak_force.shape
    # the contacts 97-99: "peaks" of 24643 N, 957 N and 1 N at time_of_peak = end_time
    at_end = np.flatnonzero(s.time_of_peak >= s.end_time)
    assert {96, 97, 98} <= set(at_end.tolist())
    assert not s.complete[at_end].any()
    # contact 96 peaked 3 us before the end (its force is still at 82% of the peak): not complete either
    assert not s.complete[95]
    # the wave still arrives at 97-99 (their overlaps still close at the end); 96 has its maximum behind it
    rising = still_rising(s.complete, s.time_of_peak, s.velocity)
    assert set(np.flatnonzero(rising).tolist()) == {96, 97, 98}
    # every contact the wave has passed is complete
    assert s.complete[:90].all()
    assert s.complete.sum() == 95
    # peaks.csv and summary.json say so
    p = read_peaks(out)
    assert p["complete"].dtype == bool
    assert np.array_equal(p["complete"], s.complete[p["contact"].astype(int) - 1])
    summ = read_summary(out)
    st_ = summ["peaks"]
    assert st_["complete"] + st_["incomplete"] + st_["unreached"] == len(p["contact"])
    assert st_["incomplete"] == 4
    assert st_["unreached"] == 0
    assert st_["complete"] == int(np.sum(s.complete))
    # everything measured but the leading pulse's decay, which a uniform chain's solitary wave does not
    # show, and what a free chain never measures (the wall's event: observables_inapplicable)
    missing = summ["observables_missing"]
    never = set(summ["observables_inapplicable"])
    assert {k for k, why in missing.items() if k not in never and not why.startswith("no decay:")} == set()
    assert "leading_pulse_decay_length" in missing


def test_default_scene_cut_short_leading_peak_missing_with_reason(default_run, tmp_path):
    """End the default run while the wave is at contact 74 (the window's last): no leading peak."""
    res, _ = default_run
    t74 = float(res.solution.time_of_peak[73])
    sc = _with_end_time(resolve_scene("default"), t74 - 1e-6)
    short = run_scene(sc, out=tmp_path / "r")
    s = short.solution
    assert np.isfinite(s.time_of_peak[73])
    assert not s.complete[73]
    obs = short.observables()
    assert obs["leading_peak_force"] is None
    assert obs["leading_peak_force_nondim"] is None
    missing = read_summary(tmp_path / "r")["observables_missing"]
    assert "no leading pulse yet" in missing["leading_peak_force"]
    assert "74" in missing["leading_peak_force"]
    # the wave speed is fitted through the arrival times of the window's passed leading pulses only
    a, b = sc.window
    c = np.arange(a, b + 1)
    ok = np.isfinite(s.leading_pulse_time[c - 1])
    assert np.array_equal(ok, s.complete[c - 1])  # a single pulse: its leading pulse passed when complete
    assert 3 <= ok.sum() < len(c)
    fit = fit_wave_speed(c[ok], s.leading_pulse_time[c - 1][ok], sc.diameter)
    assert obs["wave_speed"] == pytest.approx(fit[0], rel=1e-12)
    assert obs["wave_speed_contacts"] == int(ok.sum())
    assert s.complete[obs["max_peak_contact"] - 1]


def test_no_complete_peak_means_no_observables_and_reasons():
    sc = make_scene(beads=20, loading=SHORT, end_time=2e-6, timestep=1e-8)
    res = run_reference(sc, "verlet")
    assert not res.solution.complete.any()
    summ = res.summary()
    obs, missing = summ["observables"], summ["observables_missing"]
    for name in ("leading_peak_force", "wave_speed", "max_peak_force"):
        assert obs[name] is None
        assert missing[name]
    assert summ["peaks"]["complete"] == 0


# ---- property: generated small scenes, both reference integrators


@st.composite
def small_scenes(draw):
    beads = draw(st.integers(6, 18))
    law = draw(st.sampled_from(LAW_NAMES))
    if draw(st.booleans()):
        loading = f'kind = "impulse"\nimpulse = {draw(st.floats(0.005, 0.1))!r}\nduration = 1e-6'
    else:
        amp = draw(st.floats(20.0, 2000.0))
        loading = f'kind = "step"\namplitude = {amp!r}\nduration = {draw(st.floats(1e-6, 2e-4))!r}'
    end_time = draw(st.floats(5e-6, 1.2e-4))
    text = make_scene_text(
        beads=beads,
        law=law,
        loading=loading,
        end_time=end_time,
        timestep=1e-8,
    )
    if law == "hertz" and draw(st.booleans()):
        text += f"[precompression]\nforce = {draw(st.floats(1.0, 200.0))!r}\n"
    return parse_scene(text, source="generated.toml")


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene=small_scenes(), method=st.sampled_from(["verlet", "rk4"]))
def test_complete_means_the_force_fell_and_observables_use_only_complete(scene, method):
    n = scene.chain.beads
    f0 = scene.effects.precompression
    sol = solve_chain(
        ChainProblem.from_scene(scene), scene.run.end_time, scene.run.timestep, method, histories=tuple(range(n - 1))
    )
    c = sol.complete
    assert np.array_equal(c, complete_peaks(sol.peak_force, sol.force_min_after_peak, sol.time_of_peak, f0))
    # complete: reached, peaked before the end, and the force has fallen to the threshold since
    assert np.all(np.isfinite(sol.time_of_peak[c]))
    assert np.all(sol.time_of_peak[c] < sol.end_time)
    rise = sol.peak_force - f0
    assert np.all(sol.force_min_after_peak[c] - f0 <= PEAK_PASSED_FRACTION * rise[c])
    # the same answer from the recorded force histories (every step, every contact); RK4 also samples
    # split steps, which the histories do not record: allow a margin there
    from_hist = complete_from_samples(sol.history_time, sol.history_force, sol.peak_force, sol.time_of_peak, f0)
    if method == "verlet":
        assert np.array_equal(from_hist, c)
    else:
        t = sol.history_time[:, None]
        after = np.where(t >= sol.time_of_peak[None, :], sol.history_force, np.inf).min(axis=0)
        clear = np.abs(after - f0 - PEAK_PASSED_FRACTION * rise) > 0.02 * np.abs(rise)
        assert np.array_equal(from_hist[clear], c[clear])
    # a peak that has not happened yet (time of peak = end of run) is never complete
    assert not c[sol.time_of_peak >= sol.end_time].any()
    # observables never use an incomplete contact: garbage in the incomplete ones changes nothing
    obs = measure_observables(scene, sol)
    junk = dataclasses.replace(
        sol,
        peak_force=np.where(c, sol.peak_force, 1e30),
        time_of_peak=np.where(c, sol.time_of_peak, np.where(np.isfinite(sol.time_of_peak), -1.0, np.nan)),
    )
    assert measure_observables(scene, junk) == obs
    b = scene.window[1]
    assert (obs["leading_peak_force"] is not None) == bool(np.isfinite(sol.leading_pulse_force[b - 1]))
    # a leading pulse has passed only at a reached contact, never after the largest peak
    lead = np.isfinite(sol.leading_pulse_force)
    assert np.all(np.isfinite(sol.time_of_peak[lead]))
    assert np.all(sol.leading_pulse_time[lead] <= sol.time_of_peak[lead])
    assert obs["max_peak_contact"] is None or c[obs["max_peak_contact"] - 1]


# ---- LAMMPS: the same `complete` as the reference's Verlet, step for step


@pytest.mark.parametrize(
    ("law", "extra"),
    [("hertz", ""), ("bilinear", ""), ("hertz", '[precompression]\nforce = 50.0\n[boundary]\nfar_end = "wall"\n')],
)
def test_lammps_and_reference_agree_on_complete(law, extra):
    from granchain.lammps.runner import run_lammps

    text = make_scene_text(
        beads=40,
        law=law,
        loading=SHORT,
        end_time=1.6e-4,
        timestep=1e-8,
    )
    sc = parse_scene(text + extra, source="test.toml")
    lam, _ = run_lammps(sc)
    ref = run_reference(sc, "verlet")
    a, b = lam.solution, ref.solution
    assert np.array_equal(a.complete, b.complete)
    rising = still_rising(b.complete, b.time_of_peak, b.velocity)
    assert rising.any()
    assert np.array_equal(still_rising(a.complete, a.time_of_peak, a.velocity), rising)
    ok = np.isfinite(b.time_of_peak)
    scale = np.max(b.peak_force)
    assert np.max(np.abs(a.force_min_after_peak[ok] - b.force_min_after_peak[ok])) < 1e-9 * scale
    # the run ends with the wave inside the chain: some complete, some not yet, some not reached
    assert b.complete.sum() >= 5
    assert (ok & ~b.complete).sum() >= 2
    assert (~ok).sum() >= 2
    assert lam.summary()["peaks"] == ref.summary()["peaks"]
    oa, ob = lam.observables(), ref.observables()
    assert oa.keys() == ob.keys()
    assert law == "bilinear" or ob["wave_speed"] is not None
    for key, value in ob.items():
        assert oa[key] == (value if value is None or isinstance(value, list) else pytest.approx(value, rel=1e-6)), key


# ---- defect 6: the summary reports the state at the end of the run


def _kinetic(scene, velocity):
    return 0.5 * float(np.sum(scene.mass * velocity**2))


@pytest.mark.parametrize("law", LAW_NAMES)
def test_final_energies_are_the_end_of_run_state(law):
    """12370 steps, energy samples every 61: LAMMPS's last periodic sample is 48 steps before the end."""
    from granchain.lammps.runner import run_lammps

    sc = make_scene(beads=30, law=law, end_time=1.237e-4, timestep=1e-8)
    lam, _ = run_lammps(sc)
    ref = run_reference(sc, "verlet")
    for res in (lam, ref):
        s, summ = res.solution, res.summary()
        cons = summ["conservation"]
        assert s.energy_time[-1] == s.end_time == summ["end_time"]
        assert cons["time"] == s.end_time
        assert cons["kinetic"] == pytest.approx(_kinetic(sc, s.velocity), rel=1e-12)
    la, ra = lam.summary()["conservation"], ref.summary()["conservation"]
    for key in ("kinetic", "potential", "dissipated", "work"):
        assert la[key] == pytest.approx(ra[key], rel=1e-9, abs=1e-12 * ra["work"]), key
    rows = {r.quantity: r for r in compare_runs(lam, ref, rtol=1e-9)}
    assert rows["final_kinetic_energy"].ok


def test_stopped_lammps_run_reports_the_state_it_stopped_in():
    from granchain.lammps.runner import run_lammps

    sc = make_scene(beads=30, end_time=3e-4, timestep=1e-8)
    sc = dataclasses.replace(sc, run=dataclasses.replace(sc.run, stop_after_contact=12))
    lam, _ = run_lammps(sc)
    ref = run_reference(sc, "verlet")
    a, b = lam.solution, ref.solution
    assert a.end_time == b.end_time < sc.run.end_time
    assert a.energy_time[-1] == a.end_time
    assert a.kinetic[-1] == pytest.approx(_kinetic(sc, a.velocity), rel=1e-12)
    assert a.kinetic[-1] == pytest.approx(b.kinetic[-1], rel=1e-9)
    # the contact that stopped the run is complete in both (the same criterion)
    assert a.complete[11]
    assert b.complete[11]
