"""The optimize campaign kind (issue 45): its [optimize] table's validation, an optimum a dense grid of
the same runs confirms, a categorical optimum an enumeration confirms, resumption that replays the
cached trials and runs no point twice, and the best design's verdict against its error bars.

Real reference runs on the cheapest chains that still have an interior optimum (6 beads, a struck
chain, auto end time)."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.campaigns.model import CampaignError
from granchain.campaigns.optimize import best_design
from granchain.campaigns.run import load_campaign, run_campaign
from granchain.campaigns.spec import campaign_from_dict

BEADS = 6


@pytest.fixture(scope="module")
def sched():
    """One Dask worker for the module's campaigns (a local cluster's start costs seconds per campaign;
    the points run the same way on it: granchain campaign run --scheduler)."""
    import logging

    from distributed import LocalCluster

    with LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},  # the default 8787 may be taken
        silence_logs=logging.ERROR,
    ) as cluster:
        yield cluster.scheduler_address


def scene(material: str = "chrome-steel-52100") -> dict:
    """A 6-bead chain struck at bead 1 by a bead of its own size; the window ends at its last contact."""
    return {
        "chain": {"beads": BEADS, "radius": 4.76e-3, "taper": 1.0, "material": material},
        "contact": {"law": "hertz"},
        "loading": {"kind": "striker", "velocity": 1.0},
        "run": {"end_time": "auto", "timestep": "auto"},
        "outputs": {"peak_force": True, "window": [1, BEADS - 1]},
    }


def optimize_campaign(optimize: dict, error_estimate: bool = False, confirm: bool = False, **scene_args) -> dict:
    """The search without the winner's re-runs unless confirm (test_the_winner_is_re_run tests them)."""
    return {
        "campaign": {"backend": "reference", "rtol": 1e-3, "error_estimate": error_estimate},
        "scene": scene(**scene_args),
        "optimize": {"confirm": confirm, **optimize},
    }


TAPER = {
    "objective": "leading_peak_force",
    "direction": "maximize",
    "variables": {"chain.taper": {"low": 1.0, "high": 1.4}},
}


@pytest.mark.parametrize(
    ("change", "field", "fix"),
    [
        ({"bogus": 1}, "'bogus'", "allowed keys"),
        ({"direction": "down"}, "direction", "'minimize' or 'maximize'"),
        ({"trials": 0}, "trials", "whole number from 1"),
        ({"variables": {"chain.taper": {"low": 1.2, "high": 1.0}}}, "'chain.taper'", "give low < high"),
        ({"variables": {"chain.material": {"choices": []}}}, "'chain.material'", "non-empty list"),
        ({"variables": {"chain.taper": {"low": 1.0, "hgh": 1.4}}}, "'hgh'", "did you mean 'high'"),
        ({"variables": {"chian.taper": {"low": 1.0, "high": 1.4}}}, "'chian.taper'", "did you mean 'chain'"),
        ({"objective": "leading_peak_forse"}, "objective", "did you mean 'leading_peak_force'"),
        ({"objective": "chain.taper * 2"}, "objective", "reads no observable"),
        ({"constraints": ["chain.taper"]}, "constraint", "one comparison"),
        ({"variables": {"chain.taper": {"low": 0.0, "high": 1.0, "log": True}}}, "log = true", "low > 0"),
    ],
)
def test_bad_optimize_tables_name_the_field_and_the_fix(change, field, fix):
    with pytest.raises(CampaignError) as e:
        campaign_from_dict(optimize_campaign({**TAPER, **change}))
    assert field in str(e.value), str(e.value)
    assert fix in str(e.value), str(e.value)


def test_an_invalid_design_at_a_range_end_is_refused_before_anything_runs(tmp_path, sched):
    ws = tmp_path / "ws"
    bad = {**TAPER, "variables": {"chain.taper": {"low": -0.5, "high": 1.0}}}  # a taper must be > 0
    with pytest.raises(CampaignError, match="taper"):
        run_campaign(optimize_campaign(bad), ws, scheduler=sched)
    assert not ws.exists()


def _grid(tmp_path, name: str, vary: dict, sched):
    c = {"campaign": {"backend": "reference", "rtol": 1e-3, "error_estimate": False}, "scene": scene(), "vary": vary}
    df, _ = run_campaign(c, tmp_path / name, scheduler=sched)
    return df["table"]


def test_a_continuous_optimum_the_grid_confirms(tmp_path, sched):
    """Maximise the last contact's leading pulse over the taper R_i = R t^(i-1), t in [1, 1.4]: a
    dense grid of the same runs (13 points) has its best inside the range; within 12 trials the search's
    best is at least as good as the grid's best's neighbours (the grid's resolution) and within two grid
    steps of it."""
    num = 13
    grid = _grid(tmp_path, "grid", {"chain.taper": {"linear": [1.0, 1.4], "num": num}}, sched)
    f = grid["leading_peak_force"].to_numpy()
    k = int(f.argmax())
    assert 0 < k < num - 1, "the grid's best is at an end of the range: no interior optimum to find"
    step = 0.4 / (num - 1)
    tables, _ = run_campaign(optimize_campaign({**TAPER, "trials": 12, "seed": 3}), tmp_path / "opt", scheduler=sched)
    best = load_campaign(tmp_path / "opt", "best").iloc[0]
    assert best["objective"] >= min(f[k - 1], f[k + 1])
    assert abs(best["chain.taper"] - grid["chain.taper"][k]) <= 2 * step
    trials = tables["trials"]
    assert list(trials["trial"]) == list(range(12))
    assert (trials["best_so_far"].diff().dropna() >= 0).all()  # maximising: the best so far never falls


def test_a_categorical_optimum_the_enumeration_confirms(tmp_path, sched):
    """The chain's material, one of four: 8 trials find the enumeration's best (its very point)."""
    materials = ["brass", "stainless-steel-316", "chrome-steel-52100", "aluminium-6061-t6"]
    enum = _grid(tmp_path, "enum", {"chain.material": materials}, sched)
    truth = enum.loc[enum["leading_peak_force"].idxmin()]
    opt = {
        "objective": "leading_peak_force",
        "trials": 8,
        "seed": 0,
        "variables": {"chain.material": {"choices": materials}},
    }
    run_campaign(optimize_campaign(opt), tmp_path / "enum", scheduler=sched)  # the same workspace: shared points
    best = load_campaign(tmp_path / "enum", "best").iloc[0]
    assert best["chain.material"] == truth["chain.material"]
    assert best["job"] == truth["job"]


def _summary_times(ws: Path) -> dict:
    return {p.parent.parent.name: p.stat().st_mtime_ns for p in ws.glob("workspace/*/run/summary.json")}


def test_a_longer_rerun_continues_the_search_and_runs_no_point_twice(tmp_path, sched):
    """4 trials, then the same campaign with 8: equal to an uninterrupted 8-trial search of the same
    seed, and the second run runs only the designs the first had not."""
    opt = {**TAPER, "seed": 5}
    _, r4 = run_campaign(optimize_campaign({**opt, "trials": 4}), tmp_path / "a", scheduler=sched)
    before = _summary_times(tmp_path / "a")
    assert r4.ran == len(before)
    tables, r8 = run_campaign(optimize_campaign({**opt, "trials": 8}), tmp_path / "a", scheduler=sched)
    after = _summary_times(tmp_path / "a")
    assert all(after[j] == t for j, t in before.items())  # no point of the first run ran again
    assert r8.ran == len(after) - len(before)
    whole, _ = run_campaign(optimize_campaign({**opt, "trials": 8}), tmp_path / "b", scheduler=sched)
    assert tables["trials"].equals(whole["trials"])


def _row(trial, value, error, job=None):
    return {
        "trial": trial,
        "x": float(trial),
        "state": "complete",
        "objective": value,
        "objective_error": error,
        "job": job or f"{trial:032x}",
    }


@settings(max_examples=60, deadline=None)
@given(
    a=st.floats(-1e3, 1e3),
    b=st.floats(-1e3, 1e3),
    ea=st.floats(0, 10),
    eb=st.floats(0, 10),
    direction=st.sampled_from(["minimize", "maximize"]),
)
def test_the_best_and_its_verdict(a, b, ea, eb, direction):
    """The best is the better objective; 'not distinguished' exactly where the two differ by no more
    than the sum of their error bars; a repeated design (the same job) is no runner-up."""
    rows = [_row(0, a, ea), _row(1, b, eb), {**_row(2, a, ea), "job": _row(0, a, ea)["job"]}]
    best = best_design(rows, direction, ("x",))
    better = (a <= b) if direction == "minimize" else (a >= b)
    assert best["objective"] == (a if better else b)
    assert best["runner_up_objective"] == (b if better else a)
    assert ("not distinguished" in best["verdict"]) == (abs(a - b) <= ea + eb)
    assert best["designs_run"] == 2


def test_unmeasured_and_infeasible_trials_are_never_values(tmp_path, sched):
    """A constraint no design of half the range meets: those trials are infeasible (not run, no
    objective), the others complete; an objective the run cannot measure fails its trial."""
    opt = {**TAPER, "trials": 6, "seed": 1, "constraints": ["chain.taper <= 1.2"]}
    tables, report = run_campaign(optimize_campaign(opt), tmp_path / "c", scheduler=sched)
    t = tables["trials"]
    bad = t[t["chain.taper"] > 1.2]
    assert (bad["state"] == "infeasible").all()
    assert bad["objective"].isna().all()
    assert bad["job"].isna().all()
    assert (t[t["chain.taper"] <= 1.2]["state"] == "complete").all()
    unmeasurable = {**TAPER, "objective": "wall_max_force", "trials": 2, "seed": 1}  # no wall in this scene
    t2 = run_campaign(optimize_campaign(unmeasurable), tmp_path / "c", scheduler=sched)[0]["trials"]
    assert (t2["state"] == "failed").all()
    assert t2["objective"].isna().all()
    assert t2["message"].str.contains("unmeasured").all()


KILL_SCRIPT = """
import sys
from granchain.campaigns.run import run_campaign
from tests.test_optimize import TAPER, optimize_campaign
if __name__ == "__main__":
    run_campaign(optimize_campaign({**TAPER, "trials": 14, "seed": 11}), sys.argv[1], workers=1)
"""


@pytest.mark.slow
def test_kill_9_mid_search_then_rerun_equals_an_uninterrupted_search(tmp_path, sched):
    """kill -9 of the driver after a few points are complete; the rerun runs only the rest and gives
    the uninterrupted search's trials (the same seed), best design included."""
    root = Path(__file__).resolve().parent.parent
    script = tmp_path / "drive.py"
    script.write_text(KILL_SCRIPT)
    ws = tmp_path / "killed"
    env = {**os.environ, "PYTHONPATH": str(root), "GRANCHAIN_QUIET": "1"}
    proc = subprocess.Popen([sys.executable, str(script), str(ws)], env=env, cwd=root, start_new_session=True)
    deadline = time.monotonic() + 60
    while len(_summary_times(ws)) < 4 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    before = _summary_times(ws)
    assert 4 <= len(before) < 14, "the driver was not killed mid-search"
    tables, report = run_campaign(optimize_campaign({**TAPER, "trials": 14, "seed": 11}), ws, scheduler=sched)
    after = _summary_times(ws)
    assert all(after[j] == t for j, t in before.items())
    assert report.ran == len(after) - len(before)
    whole, _ = run_campaign(optimize_campaign({**TAPER, "trials": 14, "seed": 11}), tmp_path / "whole", scheduler=sched)
    assert tables["trials"].equals(whole["trials"])
    assert load_campaign(ws, "best").equals(load_campaign(tmp_path / "whole", "best"))


def test_the_winner_is_re_run_at_a_tighter_rtol_and_on_the_other_backend(tmp_path, sched, capsys):
    """After 3 trials the best design runs again at rtol / 10 (reference) and on LAMMPS, as points of
    their own: the tight run's objective is run_scene's at rtol 1e-4 for that design (an independent
    run), both re-runs are the search's value within 1e-3 relative, `--best` reports the tight value
    first with its bar and each run's agreement with it by the bars' rule, and a rerun runs nothing."""
    from granchain.cli import main
    from granchain.scene import scene_from_dict
    from granchain.workflows.run import run_scene

    opt = {**TAPER, "trials": 3, "seed": 2}
    _, report = run_campaign(optimize_campaign(opt, error_estimate=True, confirm=True), tmp_path / "w", scheduler=sched)
    best = load_campaign(tmp_path / "w", "best").iloc[0]
    assert (best["tight_backend"], best["other_backend"]) == ("reference", "lammps")
    assert (best["tight_rtol"], best["other_rtol"]) == pytest.approx((1e-4, 1e-3))
    design = scene()
    design["chain"]["taper"] = float(best["chain.taper"])
    run_scene(scene_from_dict(design), backend="reference", rtol=1e-4, out=tmp_path / "own")
    own = json.loads((tmp_path / "own" / "summary.json").read_text())["observables"]
    assert best["tight_objective"] == own["leading_peak_force"]
    for name in ("tight", "other"):
        assert best[f"{name}_objective"] == pytest.approx(best["objective"], rel=1e-3)
        assert best[f"{name}_objective_error"] > 0
    assert len({best["job"], best["tight_job"], best["other_job"]}) == 3
    assert report.ran == len(_summary_times(tmp_path / "w"))
    _, again = run_campaign(optimize_campaign(opt, error_estimate=True, confirm=True), tmp_path / "w", scheduler=sched)
    assert again.ran == 0
    assert main(["campaign", "table", str(tmp_path / "w"), "--best"]) == 0
    out = capsys.readouterr().out
    assert f"leading_peak_force = {best['tight_objective']:.6g} +- " in out, out
    for name, run in (("search's", "the reference run at rtol 0.001"), ("other", "the lammps run at rtol 0.001")):
        a, ea = (
            (best["objective"], best["objective_error"])
            if name == "search's"
            else (best["other_objective"], best["other_objective_error"])
        )
        verdict = "agree" if abs(a - best["tight_objective"]) <= ea + best["tight_objective_error"] else "disagree"
        assert f"{run} and the reference run at rtol 0.0001 {verdict}: they differ by" in out, out


def _sectioned(sections: dict, variables: dict | None = None) -> dict:
    c = optimize_campaign(
        {
            "objective": "leading_peak_force",
            "variables": variables
            or {"m1": {"choices": ["brass", "ptfe"]}, "n2": {"low": 1, "high": 5, "integer": True}},
        }
    )
    c["derive"] = {"chain.beads": "4 + n2"}  # the window's contacts 1 to 5 need 6 beads or more
    c["sections"] = sections
    return c


@settings(max_examples=10, deadline=None)
@given(m1=st.sampled_from(["brass", "ptfe"]), n2=st.integers(2, 5))
def test_sections_build_a_per_bead_material_list(m1, n2):
    """[sections] makes chain.material from a categorical parameter and a bead count, in chain order,
    with the derived chain length; the list is on the scene, not among the point's parameters."""
    sec = {"chain.material": {"values": ["m1", "fixed"], "beads": [4, "n2"]}}
    c = _sectioned(
        sec,
        {
            "m1": {"choices": ["brass", "ptfe"]},
            "fixed": {"choices": ["brass"]},
            "n2": {"low": 1, "high": 5, "integer": True},
        },
    )
    from granchain.scene import scene_from_dict, scene_to_dict

    p = campaign_from_dict(c).point({"m1": m1, "fixed": "brass", "n2": n2})
    assert p.scene.chain.beads == 4 + n2
    by_hand = scene()
    by_hand["chain"].update(beads=4 + n2, material=[m1] * 4 + ["brass"] * n2)
    assert p.scene_dict == scene_to_dict(scene_from_dict(by_hand))  # (a uniform list reads as one material)
    assert "chain.material" not in p.params


@pytest.mark.parametrize(
    ("sections", "fix"),
    [
        ({"chain.taper": {"values": ["m1"], "beads": [3]}}, "not a per-bead key"),
        ({"chain.material": {"values": ["m1"]}}, "needs exactly values and beads"),
        ({"chain.material": {"values": ["m1", "m1"], "beads": [3]}}, "equal length"),
        ({"chain.material": {"values": ["m9"], "beads": [3]}}, "'m9' is not a varied or derived key"),
        ({"chain.material": {"values": ["m1"], "beads": [-1]}}, "a whole number >= 0"),
    ],
)
def test_bad_sections_name_the_field_and_the_fix(sections, fix):
    with pytest.raises(CampaignError, match="sections") as e:
        campaign_from_dict(_sectioned(sections))
    assert fix in str(e.value), str(e.value)


def test_a_winner_the_other_backend_cannot_run_says_why(tmp_path, sched, monkeypatch):
    """Where the other backend refuses the winner's scene (here its preflight is made to refuse, as it
    does a scene past its limits), --best gives the tight run's value and says why there is no other."""
    import granchain.campaigns.execute as execute
    from granchain.campaigns.optimize import best_text

    real = execute.preflight

    def refuse_lammps(campaign, points):
        if campaign.backend == "lammps":
            raise CampaignError("point 1 cannot run: a made-up limit of this test")
        return real(campaign, points)

    monkeypatch.setattr(execute, "preflight", refuse_lammps)
    opt = {**TAPER, "trials": 2, "seed": 4}
    run_campaign(optimize_campaign(opt, confirm=True), tmp_path / "w", scheduler=sched)
    best = load_campaign(tmp_path / "w", "best").iloc[0]
    assert best["other_objective"] is None or best["other_objective"] != best["other_objective"]  # None or NaN
    assert "the lammps backend cannot run the winner: point 1 cannot run: a made-up limit" in best["other_message"]
    assert best["tight_objective"] == pytest.approx(best["objective"], rel=1e-3)
    from granchain.campaigns.table import read_record

    record = read_record(tmp_path / "w")
    text = best_text(
        best_design(record["optimize_results"], "maximize", ("chain.taper",)),
        "leading_peak_force",
        ("chain.taper",),
        record["optimize_confirm"],
    )
    assert "the other backend: no value: the lammps backend cannot run the winner" in text, text
    assert "not compared" in text, text


def test_the_bundled_protector_example_is_a_small_sectioned_wall_problem():
    """granchain/campaigns/protector-optimize.toml (issue 45 item 5): at most 20 beads in sections of two
    or three materials, a striker heavier than a bead, a wall, the wall's largest force over the event
    minimised; every design at the variables' ends is a valid, planned scene."""
    from importlib import resources

    from granchain.campaigns.run import validate
    from granchain.campaigns.spec import load_campaign_file
    from granchain.physics.materials import MATERIALS

    c = load_campaign_file(resources.files("granchain.campaigns") / "protector-optimize.toml")
    assert (c.optimize.objective, c.optimize.direction) == ("wall_max_force", "minimize")
    assert [s.key for s in c.sections] == ["chain.material"]
    materials = {m for v in c.optimize.variables for m in v.choices}
    assert 2 <= len(materials) <= 3
    validate(c)
    p = c.point({v.key: v.choices[0] for v in c.optimize.variables})
    d = p.scene_dict
    assert d["chain"]["beads"] <= 20
    assert d["boundary"]["far_end"] == "wall"
    assert d["outputs"]["event"] is True
    heaviest = max(MATERIALS[m].density for m in materials) * 4 / 3 * math.pi * d["chain"]["radius"] ** 3
    assert d["loading"]["mass"] > 2 * heaviest  # heavy: more than two of the heaviest beads
    assert d["loading"]["material"] in materials  # the ball's own, not bead 1's (which s1 changes)


def test_two_objectives_give_a_pareto_front_that_is_known(tmp_path, sched, capsys):
    """Two objectives whose front is known: the last contact's pulse minimised and maximised (no design
    dominates another: every distinct design is on the front), then minimised twice (one design
    dominates all: the front is the least value's); --best prints the front, the figure is pareto.png."""
    from granchain.campaigns.plot import plot_convergence
    from granchain.cli import main

    ws = tmp_path / "w"
    two = {**TAPER, "objective": ["leading_peak_force", "leading_peak_force"], "trials": 5, "seed": 3}
    run_campaign(optimize_campaign({**two, "direction": ["minimize", "maximize"]}), ws, scheduler=sched)
    trials = load_campaign(ws, "trials")
    assert (trials["objective_2"] == trials["objective"]).all()
    front = load_campaign(ws, "best")
    assert set(front["job"]) == set(trials["job"])  # every distinct design
    assert list(front["objective"]) == sorted(front["objective"])
    tables, _ = run_campaign(optimize_campaign({**two, "direction": ["minimize", "minimize"]}), ws, scheduler=sched)
    t = tables["trials"]
    front = load_campaign(ws, "best")
    assert list(front["job"]) == [t.loc[t["objective"].idxmin(), "job"]]
    assert main(["campaign", "table", str(ws), "--best"]) == 0
    out = capsys.readouterr().out
    assert "Pareto front of leading_peak_force and leading_peak_force: 1 designs" in out, out
    assert [p.name for p in plot_convergence(ws)] == ["pareto.png"]


def test_a_missing_error_bar_read_back_as_nan_is_no_bar():
    """The trials table reads a blank error bar back as NaN: the verdict says it cannot be judged (it
    said 'their error bars both 0': NaN compares false both ways)."""
    nan = float("nan")
    best = best_design([_row(0, 1.0, nan), _row(1, 2.0, 0.1)], "minimize", ("x",))
    assert best["objective_error"] is None
    assert "cannot be judged" in best["verdict"], best["verdict"]
