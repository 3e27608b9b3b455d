"""Every run carries a measured error estimate (companion runs at 2 dt and 4 dt, or RK4 on a kinked law when asked)."""

import json
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from granchain.cli import main, resolve_scene
from granchain.rundir import read_peaks
from granchain.scene import parse_scene
from granchain.workflows.error_estimates import against_rk4_factors, companion_scene, rk4_companions_cost
from granchain.workflows.load import load_run
from granchain.workflows.run import plan_for, run_scene

from .scenegen import scenes

WALL_CHAIN = """
title = "invented: 40 aluminium beads, a short pulse, a far-end wall"
[chain]
beads = 40
radius = 3e-3
material = "aluminium-6061-t6"
[contact]
law = "hertz"
[loading]
kind = "impulse"
impulse = 0.02
duration = 2e-6
[boundary]
far_end = "wall"
[run]
timestep = "auto"
end_time = "auto"
[outputs]
peak_force = true
histories = [1, 20]
"""


@pytest.mark.parametrize("backend", ["lammps", "reference"])
def test_granchain_run_gives_every_peak_an_error_by_default(tmp_path, backend, capsys):
    p = tmp_path / "wall.toml"
    p.write_text(WALL_CHAIN)
    out = tmp_path / "run"
    assert main(["run", str(p), "--backend", backend, "--out", str(out), "--quiet"]) == 0
    peaks = read_peaks(out)
    assert {"peak_force_error", "time_of_peak_error", "error_status"} <= set(peaks)
    s = json.loads((out / "summary.json").read_text())
    e = s["errors"]
    assert e["order"] == (2 if backend == "lammps" else 4)
    assert len(e["companion_timesteps"]) == 2
    assert e["companion_timesteps"][0] == pytest.approx(2 * s["timestep"])
    assert s["error_estimate"] is not None
    assert 0 < s["error_estimate"] < 1e-2
    # every complete peak has an estimate or a status that says why not; never a silent blank
    done = peaks["complete"]
    has = np.isfinite(peaks["peak_force_error"][done])
    statuses = peaks["error_status"][done]
    assert all(st.startswith(("nominal", "observed", "round-off")) for st in statuses[has])
    assert all(st.startswith(("unreliable", "not measured", "order not checked")) for st in statuses[~has])
    assert s["errors"]["observables"]["leading_peak_force"]["status"]
    printed = capsys.readouterr().out
    assert "largest peak-force error" in printed
    assert "+-" in printed


BILINEAR_CHAIN = """
title = "invented: 25 steel beads, bilinear beta 0.6, a short pulse"
[chain]
beads = 25
radius = 2.5e-3
material = "stainless-steel-316"
[contact]
law = "bilinear"
unloading_coeff = 0.6
plastic_stiffness = 3e7
[loading]
kind = "impulse"
impulse = 0.02
duration = 2e-6
[run]
timestep = "auto"
end_time = "auto"
[outputs]
peak_force = true
"""


THORNTON_CONTACT = """[contact]
law = "thornton"
yield_pressure = 1.2e9
"""


@pytest.mark.parametrize("backend", ["lammps", "reference"])
@pytest.mark.parametrize("dashpot", [0.0, 5.0])
@pytest.mark.parametrize("law", ["bilinear", "thornton"])
def test_a_plastic_verlet_run_is_bounded_by_its_own_companions_unless_it_has_a_dashpot(tmp_path, backend, dashpot, law):
    """Plastic laws' slopes jump at kinks the contacts cross: Verlet's error is erratic in sign. By
    default a LAMMPS run's bars are bounds from its own runs at 2 dt and 4 dt, which the summary and each
    status name (RK4 runs only with --error-estimate checked, or for a reference Verlet run where they
    cost at most the run); with a dashpot Verlet is first order and Richardson stays."""
    text = BILINEAR_CHAIN
    if law == "thornton":
        start = text.index("[contact]")
        text = text[:start] + THORNTON_CONTACT + text[text.index("[loading]") :]
    p = tmp_path / "plastic.toml"
    p.write_text(text.replace("[run]", f"[damping]\ndashpot = {dashpot}\n[run]") if dashpot else text)
    out = tmp_path / "run"
    args = ["run", str(p), "--backend", backend, "--out", str(out), "--quiet"]
    assert main(args + ([] if backend == "lammps" else ["--method", "verlet"])) == 0
    s = json.loads((out / "summary.json").read_text())
    e = s["errors"]
    statuses = read_peaks(out)["error_status"]
    # the reference's Verlet is measured against RK4 where that costs at most the run (test_kinked_error_bars)
    if backend == "reference" and not dashpot and rk4_companions_cost(load_run(out).scene) <= 1.0:
        assert e["companion_method"] == "rk4"
        assert e["bound"] is None
        assert any(st.startswith("against RK4") for st in statuses)
        assert not any(st.startswith("bound:") for st in statuses)
        return
    assert e["companion_method"] is None
    assert not any(st.startswith("against RK4") for st in statuses)
    assert e["companion_timesteps"] == pytest.approx([2 * s["timestep"], 4 * s["timestep"]])
    if dashpot:
        assert e["order"] == 1
        assert e["bound"] is None
        assert not any(st.startswith("bound:") for st in statuses)
    else:
        assert e["bound"] is not None
        assert "may overstate" in e["method"]
        assert "--error-estimate checked" in e["why_unchecked"]
        assert e["error_estimate"] is not None
        assert any(st.startswith("bound: kinked law") for st in statuses)
        assert not any(st.startswith(("nominal", "observed")) for st in statuses)


def test_error_estimate_off_runs_no_companion(tmp_path):
    p = tmp_path / "wall.toml"
    p.write_text(WALL_CHAIN)
    out = tmp_path / "run"
    assert main(["run", str(p), "--backend", "lammps", "--out", str(out), "--quiet", "--error-estimate", "off"]) == 0
    assert "peak_force_error" not in read_peaks(out)
    s = json.loads((out / "summary.json").read_text())
    assert s["errors"] is None
    assert s["error_estimate"] is None


def test_companions_change_only_the_step_and_drop_unneeded_outputs():
    sc, _ = plan_for(parse_scene(WALL_CHAIN, source="wall.toml"), "lammps", None, 1e-3)
    c = companion_scene(sc, 4.0)
    assert c.run.timestep == 4 * sc.run.timestep
    assert c.run.end_time == sc.run.end_time
    assert c.run.stop_after_contact == sc.run.stop_after_contact
    assert c.outputs.histories == ()
    assert c.outputs.snapshots == ()
    assert replace(c, run=sc.run, outputs=sc.outputs) == sc


def test_verlet_with_a_dashpot_is_estimated_at_first_order():
    """Velocity Verlet's dashpot sees half-step velocities: order 1 (order 2 underestimated 3x)."""
    sc, _ = plan_for(resolve_scene("effect-dashpot"), "reference", "verlet", 1e-3)
    got = run_scene(sc, method="verlet", error_estimate=True)
    assert got.errors.order == 1
    fine = run_scene(replace(sc, run=replace(sc.run, timestep=sc.run.timestep / 16)), method="verlet").solution
    ok = got.errors.peak_force.reliable & got.solution.complete & fine.complete
    true = np.abs(got.solution.peak_force[ok] - fine.peak_force[ok])
    ratio = got.errors.peak_force.error[ok] / true
    assert ok.sum() > 50
    assert np.all((ratio > 1 / 3) & (ratio < 3))


CASES = (
    [
        (name, integ)
        for name in ("default", "effect-striker", "effect-tapered", "effect-wall", "effect-precompression")
        for integ in ("lammps", "verlet", "rk4")
    ]
    # bilinear with Verlet: bounds (the law's slope jumps at kinks the contacts cross; Richardson's checks pass
    # on 3 of 59 peaks there, errors.bounded_because)
    + [("plastic-short-impulse", "lammps"), ("plastic-short-impulse", "verlet")]
    # RK4 on a kinked law: bounds from one companion at 2 dt by default (errors.one_companion_because), held
    # to at least 1/3 of the true error; its checked estimates below
    + [("plastic-short-impulse", "rk4"), ("thornton-short-impulse", "rk4")]
    + [("thornton-short-impulse", "lammps"), ("thornton-short-impulse", "verlet")]
    + [
        # effect-dashpot with RK4: no estimate by design (test_rk4_with_a_dashpot_runs_no_companion...)
        ("effect-dashpot", "verlet"),
        ("effect-dashpot", "lammps"),
    ]
)


#: (scene, integrator, error_estimate): every case by default, and RK4's checked estimates on the kinked laws
#: (runs at 2 dt and 4 dt with the order-range rule, checked at dt / 2: error_estimates.check_because; by
#: default three runs at 2 dt and 4 dt gave 1 of 34 Thornton estimates 6.3x the true error, contact 6,
#: 'nominal order 4', a true error 4e-9 of the peak, which the check at dt / 2 withholds)
ESTIMATES = [pytest.param(*p.values, True, marks=p.marks) if hasattr(p, "marks") else (*p, True) for p in CASES] + [
    ("plastic-short-impulse", "rk4", "checked"),
    ("thornton-short-impulse", "rk4", "checked"),
]


@pytest.mark.slow
@pytest.mark.parametrize(("name", "integ", "mode"), ESTIMATES)
def test_estimated_error_is_within_a_factor_3_of_the_true_error(name, integ, mode):
    """The validation: estimated / true error (true: a run at dt / 16) in [1/3, 3] wherever
    the true error is above round-off and an estimate is given, and an estimate for most peaks.

    On a law with slope kinks Verlet's error follows no order (errors.bounded_because: there its bars
    are bounds, which may overstate the error and say so in their status: those are held to at least
    1/3 of it; RK4's default bars there are bounds too, errors.one_companion_because), so its run at dt / 16
    need not be converged:
    thornton-short-impulse, contact 34, reference Verlet minus RK4 at dt / 4 was -5.8e-5 N at dt,
    -9.8e-4 at dt / 4, -6.0e-5 at dt / 16, -3.6e-6 at dt / 64, and against dt / 16 the estimate looked
    39x too large (1.5x against dt / 64). There the truth is RK4 (event location) at dt / 4, converged
    far beyond Verlet's error."""
    from granchain.physics.laws import law_class

    backend, method = ("lammps", None) if integ == "lammps" else ("reference", integ)
    sc, _ = plan_for(resolve_scene(name), backend, method, 1e-3)
    sc = replace(sc, outputs=replace(sc.outputs, histories=(), snapshots=(), history_interval=None))
    got = run_scene(sc, backend=backend, method=method, error_estimate=mode)
    if integ != "rk4" and law_class(sc.contact.law).slope_kinks and not sc.effects.dashpot:
        fine = run_scene(replace(sc, run=replace(sc.run, timestep=sc.run.timestep / 4)), method="rk4")
    else:
        fine = run_scene(
            replace(sc, run=replace(sc.run, timestep=sc.run.timestep / 16)), backend=backend, method=method
        )
    a, b = got.solution, fine.solution
    measured = a.complete & b.complete
    true = np.abs(a.peak_force - b.peak_force)
    above = measured & (true > 1e3 * np.spacing(np.abs(a.peak_force)))
    est = got.errors.peak_force
    ok = above & est.reliable
    assert ok.sum() >= 0.5 * above.sum(), f"{ok.sum()} of {above.sum()} peaks have an estimate"
    ratio = est.error[ok] / true[ok]
    # a kinked law's default bars (Verlet: errors.bounded_because; RK4: errors.one_companion_because) are
    # bounds that may overstate the error, and their status says so
    said = np.array([str(st).startswith("bound:") and "may overstate" in str(st) for st in est.status[ok]], dtype=bool)
    assert np.all((ratio >= 1 / 3) & ((ratio <= 3) | said)), f"ratios {np.sort(ratio)[[0, -1]]}"


@pytest.mark.parametrize("dashpot", [0.0, 0.5, 20.0])
def test_rk4_with_a_dashpot_runs_no_companion_and_says_why(tmp_path, dashpot):
    """RK4 does not locate the dashpot's clip, so its error follows no order: with any dashpot no
    estimate is given (and no companion run paid for), and the summary says why; without one it is."""
    p = tmp_path / "dash.toml"
    p.write_text(WALL_CHAIN.replace("[run]", f"[damping]\ndashpot = {dashpot}\n[run]") if dashpot else WALL_CHAIN)
    out = tmp_path / "run"
    assert main(["run", str(p), "--backend", "reference", "--method", "rk4", "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    if dashpot:
        assert s["error_estimate"] is None
        assert "dashpot" in s["errors"]["why_none"]
        assert s["errors"]["companion_timesteps"] == []
    else:
        assert s["error_estimate"] is not None
        assert len(s["errors"]["companion_timesteps"]) == 2


def test_a_companion_that_breaks_an_invariant_leaves_the_run_standing():
    """A coarser companion may blow up where the run did not: the run keeps its numbers, and the
    report says which companion failed and what that costs (no estimate, or no order check)."""
    from granchain.exceptions import GranchainError
    from granchain.workflows.error_estimates import estimate_errors

    sc, plan = plan_for(parse_scene(WALL_CHAIN, source="wall.toml"), "reference", "verlet", 1e-2)
    got = run_scene(sc, method="verlet")
    calls = []

    def fails_at(factor):
        def run_one(s):
            calls.append(s.run.timestep / sc.run.timestep)
            if calls[-1] == factor:
                raise GranchainError("energy balance broken at step 12")
            return run_scene(s, method="verlet")

        return run_one

    none = estimate_errors(got, fails_at(2.0), "verlet", plan.stable_timestep)
    assert none.peak_force is None
    assert "2 dt companion run failed" in none.why_none
    calls.clear()
    no_order = estimate_errors(got, fails_at(4.0), "verlet", plan.stable_timestep)
    assert "4 dt companion run failed" in no_order.why_none_4dt
    done = got.solution.complete
    assert all(
        s in ("order not checked", "round-off") or s.startswith("not measured")
        for s in no_order.peak_force.status[done]
    )


def test_a_measured_error_above_rtol_is_said_after_the_run():
    """A fixed step far too coarse for rtol: the companions measure the error and the run says so."""
    import warnings

    from granchain.workflows.run import AccuracyWarning

    sc, _ = plan_for(parse_scene(WALL_CHAIN, source="wall.toml"), "reference", "verlet", 1e-3)
    coarse = replace(sc, run=replace(sc.run, timestep=sc.run.timestep * 8), outputs=replace(sc.outputs, histories=()))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = run_scene(coarse, method="verlet", error_estimate=True)
    assert got.errors.error_estimate > 1e-3
    said = [str(w.message) for w in caught if issubclass(w.category, AccuracyWarning) and "measured" in str(w.message)]
    assert len(said) == 1
    assert f"contact {got.errors.error_estimate_contact}" in said[0]


def test_compare_counts_a_difference_only_beyond_rtol_plus_both_errors():
    from granchain.postprocess.comparison_table import CompareRow

    def row(ea, eb):
        return CompareRow("q", "N", 100.0, 100.5, None, "", 1e-3, None, None, ea, eb)

    assert not row(None, None).ok  # 0.5% apart, rtol 0.1%: a disagreement
    assert not row(0.1, 0.1).ok  # 0.5 > 0.1 + 0.1 + 0.1005
    assert row(0.3, 0.2).ok  # within rtol plus both measured errors
    assert row(0.3, 0.2).verdict == "yes"


def test_granchain_compare_shows_both_error_bars(tmp_path, capsys):
    p = tmp_path / "wall.toml"
    p.write_text(WALL_CHAIN)
    assert main(["compare", str(p), "--out", str(tmp_path / "c"), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "lammps_error" in out
    assert "reference_error" in out
    header = (tmp_path / "c" / "compare.csv").read_text().splitlines()[0].split(",")
    rows = [line.split(",") for line in (tmp_path / "c" / "compare.csv").read_text().splitlines()[1:]]
    lead = next(r for r in rows if r[0] == "leading_peak_force")
    assert float(lead[header.index("lammps_error")]) > 0
    assert float(lead[header.index("reference_error")]) > 0


@pytest.mark.slow
@pytest.mark.parametrize("integ", ["verlet", "lammps"])
@settings(max_examples=8, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(sc=scenes(law="hertz", max_beads=30).filter(lambda s: not s.effects.dashpot))
def test_estimates_hold_on_generated_hertz_scenes(integ, sc):
    """The same on generated scenes (walls, strikers, precompression, tapers, materials): the
    bar of the bundled scenes. Measured over 12 generated scenes per case (README, the note): Hertz
    without a dashpot meets it with Verlet and LAMMPS (ratios 0.96-1.6); with a dashpot (Verlet's
    first order), with the plastic laws' kinks and with RK4 (Hertz onsets from touching beads are
    order 2.5, dashpot clips) a few percent of the peaks fall outside, so those are not claimed.
    Derandomized (the same 8 draws every CI run, like the planner property); random draws are
    explored by docs/measure_error_ratios.py (a random draw found the 13x case behind
    highest_trusted_order)."""
    backend, method = ("lammps", None) if integ == "lammps" else ("reference", integ)
    sc, _ = plan_for(sc, backend, method, 1e-3)
    sc = replace(sc, outputs=replace(sc.outputs, histories=(), snapshots=(), history_interval=None, dump_interval=None))
    got = run_scene(sc, backend=backend, method=method, error_estimate=True)
    fine = run_scene(replace(sc, run=replace(sc.run, timestep=sc.run.timestep / 16)), backend=backend, method=method)
    a, b = got.solution, fine.solution
    true = np.abs(a.peak_force - b.peak_force)
    above = a.complete & b.complete & (true > 1e3 * np.spacing(np.abs(a.peak_force)))
    est = got.errors.peak_force
    ok = above & est.reliable
    ratio = est.error[ok] / true[ok]
    assert np.all((ratio >= 1 / 3) & (ratio <= 3)), f"ratios {np.sort(ratio)[[0, -1]]}"


def test_compare_makes_each_rk4_companion_once(tmp_path, monkeypatch):
    """A bilinear scene with a fixed step at which RK4's own step for its share of Verlet's error is
    below SHARED_BELOW dt, compared with checked bars: LAMMPS's RK4 companions
    (errors.against_rk4_because) are the reference's own at 2 dt and 4 dt, so compare makes them once
    (shared_reference_runs); on two cores a worker process makes them, with the same numbers."""
    import granchain.workflows.run as run_module

    sc, _ = plan_for(parse_scene(BILINEAR_CHAIN, source="b.toml"), "lammps", None, 1e-3)
    # RK4's step for a share of Verlet's error goes as dt^(1/2), so h / dt as dt^(-1/2): a step this
    # much larger than the planned one brings h / dt to 2.5
    f1 = against_rk4_factors(sc)[0]
    dt = sc.run.timestep * max(1.0, f1 / 2.5) ** 2
    sc = replace(sc, run=replace(sc.run, timestep=dt))
    assert against_rk4_factors(sc) == (2.0, 4.0)
    p = tmp_path / "b.toml"
    p.write_text(BILINEAR_CHAIN.replace('timestep = "auto"', f"timestep = {dt!r}"))
    made = []
    real = run_module.run_reference

    def counted(scene, method="rk4"):
        made.append((scene.run.timestep, method))
        return real(scene, method)

    monkeypatch.setattr(run_module, "run_reference", counted)
    monkeypatch.setattr(run_module, "available_cores", lambda: 1)  # no worker: every run made here
    checked = ["--error-estimate", "checked"]
    assert main(["compare", str(p), "--out", str(tmp_path / "c"), "--quiet", *checked]) == 0
    dt = sc.run.timestep
    # the reference's run, its check at dt / 2, and its companions at 2 dt and 4 dt, LAMMPS's too
    assert sorted(made) == [(dt / 2, "rk4"), (dt, "rk4"), (2 * dt, "rk4"), (4 * dt, "rk4")]
    errors = [json.loads((tmp_path / "c" / b / "summary.json").read_text())["errors"] for b in ("lammps", "reference")]
    assert errors[0]["companion_method"] == "rk4"
    assert errors[0]["companion_timesteps"] == errors[1]["companion_timesteps"] == [2 * dt, 4 * dt]
    # the shared runs' price is shown on both: LAMMPS's companions cost what the reference's did
    # (the same runs, but for the reference's check at dt / 2), though LAMMPS's report got them at once
    shared = errors[1]["companion_wall_time"] - errors[1]["check_wall_time"]
    assert errors[0]["companion_wall_time"] >= 0.5 * shared > 0

    made.clear()
    monkeypatch.setattr(run_module, "available_cores", lambda: 2)  # the companions made by a worker
    assert main(["compare", str(p), "--out", str(tmp_path / "w"), "--quiet", *checked]) == 0
    assert made == [(dt, "rk4")]  # (the worker's runs are counted in the worker)
    for name in ("compare.csv", "reference/peaks.csv", "lammps/peaks.csv"):
        assert (tmp_path / "w" / name).read_bytes() == (tmp_path / "c" / name).read_bytes()
    errors = [json.loads((tmp_path / "w" / b / "summary.json").read_text())["errors"] for b in ("lammps", "reference")]
    shared = errors[1]["companion_wall_time"] - errors[1]["check_wall_time"]
    assert errors[0]["companion_wall_time"] >= 0.5 * shared > 0
