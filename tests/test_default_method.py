"""The reference's default integrator depends on the scene, in one place (workflows.run.method_choice,
Backend.default_method): RK4, but Verlet on a scene with a dashpot, where RK4's peak is the elastic
force at the overlap's turn (not the total force's maximum that Verlet and LAMMPS read) and it gives
no error bars. Every entry point without a method runs Verlet there and says why once; an explicit
method is kept."""

from __future__ import annotations

import io
import json
import os
from types import SimpleNamespace

from hypothesis import HealthCheck, given, settings

import granchain
from granchain.backends import LAMMPS, REFERENCE
from granchain.cli import main
from granchain.scene import parse_scene
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import method_choice, plan_for

from .conftest import CAMPAIGN_SCENE, make_scene_text
from .scenegen import scene_texts

#: two brass beads kicked at 1 m/s with a dashpot, a fixed step: a run of a few hundred steps
PLAIN_TEXT = make_scene_text(beads=2, loading='kind = "velocity"\nvelocity = 1.0', end_time=3e-5, timestep=4e-8)
DASHPOT_TEXT = PLAIN_TEXT + "[damping]\ndashpot = 20.6\n"
WHY = "verlet, not rk4, on a scene with a dashpot"


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene_texts())
def test_the_reference_default_is_verlet_exactly_on_a_dashpot_scene(text):
    """On generated scenes of every law, load and effect: no method gives the reference Verlet with the
    reason where the scene has a dashpot, else RK4 without one; an asked method is kept with no
    reason; LAMMPS is Verlet; the planner plans for the integrator the run uses. Before, the reference's
    default was RK4 on every scene (Backend.integrator took no scene)."""
    sc = parse_scene(text, source="gen.toml")
    method, why = method_choice(REFERENCE, None, sc)
    if sc.effects.dashpot:
        assert method == "verlet"
        assert why is not None
        assert why.startswith(WHY)
        assert "elastic force where the overlap turns" in why
    else:
        assert (method, why) == ("rk4", None)
    assert REFERENCE.integrator(None, sc) == method
    for asked in REFERENCE.methods:
        assert method_choice(REFERENCE, asked, sc) == (asked, None)
    assert method_choice(LAMMPS, None, sc) == ("verlet", None)
    assert plan_for(sc, REFERENCE, None, 1e-3)[1].method == method
    assert granchain.plan(sc).method == method


def test_run_without_a_method_on_a_dashpot_scene_runs_verlet_and_says_why(tmp_path, capsys, monkeypatch):
    """granchain run: Verlet, its run directory runs/<scene>-reference-verlet, the reason once on
    stderr, in the header and in summary.json; with --method rk4 RK4 is kept, its peaks labelled by
    their definition in the withheld error bars, and no reason. Before, the default ran RK4."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("GRANCHAIN_QUIET", raising=False)
    (tmp_path / "dash.toml").write_text(DASHPOT_TEXT)
    assert main(["run", "dash.toml", "--error-estimate", "off"]) == 0
    out, err = capsys.readouterr()
    run_dir = tmp_path / "runs" / "dash-reference-verlet"
    summary = json.loads((run_dir / "summary.json").read_text())
    assert summary["method"] == "verlet"
    assert summary["method_reason"].startswith(WHY)
    assert err.count(WHY) == 1, err
    assert "backend    reference (verlet)" in out
    assert f"({WHY}" in out
    assert granchain.load_run(run_dir).method_reason == summary["method_reason"]

    assert main(["plan", "dash.toml", "--json"]) == 0  # granchain plan: for the integrator run uses
    plan = json.loads(capsys.readouterr().out)
    assert plan["method"] == "verlet"
    assert plan["method_reason"].startswith(WHY)
    assert main(["plan", "dash.toml", "--method", "rk4"]) == 0
    assert "method      rk4," in capsys.readouterr().out

    assert main(["run", "dash.toml", "--method", "rk4"]) == 0
    out, err = capsys.readouterr()
    summary = json.loads((tmp_path / "runs" / "dash-reference-rk4" / "summary.json").read_text())
    assert summary["method"] == "rk4"
    assert "method_reason" not in summary
    assert WHY not in err + out
    assert "its peaks are the elastic force where the overlap turns" in summary["errors"]["why_none"]


def test_the_python_api_runs_verlet_on_a_dashpot_scene_unless_told(capsys, monkeypatch):
    """granchain.run and run_scene without a method: Verlet and the reason (once, on stderr); an
    explicit "rk4" is kept; a scene without a dashpot still runs RK4."""
    monkeypatch.delenv("GRANCHAIN_QUIET", raising=False)
    sc = parse_scene(DASHPOT_TEXT, source="dash.toml")
    res = granchain.run(sc)
    assert res.solution.method == "verlet"
    assert res.summary["method_reason"].startswith(WHY)
    assert capsys.readouterr().err.count(WHY) == 1
    rk4 = granchain.run(sc, method="rk4")
    assert rk4.solution.method == "rk4"
    assert "method_reason" not in rk4.summary
    plain = granchain.run(parse_scene(PLAIN_TEXT, source="p.toml"))
    assert plain.solution.method == "rk4"
    assert "method_reason" not in plain.summary
    assert WHY not in capsys.readouterr().err
    # planned and given error bars for the integrator it runs (RK4 with a dashpot withholds its bars)
    auto_text = DASHPOT_TEXT.replace("timestep = 4e-08", "timestep = 'auto'")
    assert auto_text != DASHPOT_TEXT
    auto = granchain.run(parse_scene(auto_text, source="auto.toml"), rtol=1e-3, error_estimate=True)
    assert auto.plan.method == "verlet"
    assert auto.summary["provenance"]["plan"]["method"] == "verlet"
    assert auto.errors.error_estimate is not None, auto.errors.why_none


def _campaign_jobs(tmp_path, text: str):
    """A reference campaign's points planned and checked (preflight), their jobs and payloads, and what
    the driver said (no run)."""
    from granchain.campaigns.execute import Runner, preflight
    from granchain.campaigns.spec import parse_campaign

    c = parse_campaign(text, source="c.toml")
    grid = c.grid()
    points = [c.point(p, i, len(grid)) for i, p in enumerate(grid)]
    preflight(c, points)
    stream = io.StringIO()
    old = os.environ.pop("GRANCHAIN_QUIET", None)
    try:
        runner = Runner(c, tmp_path, executor=SimpleNamespace(slot_cores=lambda: 1), stream=stream)
        jobs = [runner.job(p) for p in points]
        payloads = [runner.payload(j, p) for j, p in zip(jobs, points, strict=True)]
    finally:
        if old is not None:
            os.environ["GRANCHAIN_QUIET"] = old
    methods = [j.cached_statepoint["method"] for j in jobs]
    assert [p["method"] for p in payloads] == methods
    return runner, methods, stream.getvalue()


def test_a_campaign_point_with_a_dashpot_runs_verlet_and_its_state_point_says_so(tmp_path):
    """A reference campaign with no method: its points with a dashpot are keyed (state point, payload)
    on verlet, so an existing workspace's rk4 result of such a point is not taken for it, and the
    driver says why once; a campaign without a dashpot stays on rk4; method = "rk4" is kept. Before,
    every point was rk4."""
    scene = CAMPAIGN_SCENE.replace("\n[", "\n[scene.")
    damped = '[campaign]\nbackend = "reference"\n\n[vary]\n"damping.dashpot" = [5.0, 7.0]\n\n[scene]\n' + scene
    runner, methods, said = _campaign_jobs(tmp_path / "a", damped)
    assert methods == ["verlet", "verlet"]
    assert said.count(WHY) == 1, said
    assert runner.record_method[0] == "verlet"
    assert runner.record_method[1].startswith(WHY)
    plain = '[campaign]\nbackend = "reference"\n\n[vary]\n"loading.amplitude" = [5.0, 7.0]\n\n[scene]\n' + scene
    runner, methods, said = _campaign_jobs(tmp_path / "b", plain)
    assert methods == ["rk4", "rk4"]
    assert (said, runner.record_method) == ("", ("rk4", None))
    asked = damped.replace('backend = "reference"', 'backend = "reference"\nmethod = "rk4"')
    runner, methods, said = _campaign_jobs(tmp_path / "c", asked)
    assert methods == ["rk4", "rk4"]
    assert (said, runner.record_method) == ("", ("rk4", None))


def test_compare_and_its_api_resolve_the_reference_method_in_the_same_place():
    """compare's reference_method is method_choice on the reference (one place for the default)."""
    from granchain.workflows.compare_backends import reference_method

    damped = parse_scene(DASHPOT_TEXT, source="dash.toml")
    plain = parse_scene(PLAIN_TEXT, source="p.toml")
    for sc in (damped, plain):
        assert reference_method(sc) == method_choice(REFERENCE, None, sc)
        assert reference_method(sc, "rk4") == ("rk4", None)
    assert plan_scene(damped, method=reference_method(damped)[0]).method == "verlet"
