"""granchain plan's cost is the run's whole cost: the run's steps, the steps of the companion runs its
default error bars make (error_estimates.planned_companions, the rule the run's estimate follows), and
their total; summary.json's errors record the steps each companion took (companion_steps, check_steps)."""

import json
from dataclasses import replace

import pytest

from granchain.cli import main
from granchain.scene import parse_scene
from granchain.workflows.run import plan_for

from .test_error_estimate import BILINEAR_CHAIN


def concrete(tmp_path, law: str, method: str, finer: float = 1.0):
    """A 12-bead chain planned for `method`, written with its step (divided by `finer`) and end fixed and
    no stop check: the run is neither refined nor extended and every run goes to its end, so the plan's
    steps are the steps taken."""
    text = BILINEAR_CHAIN.replace("beads = 25", "beads = 12")
    if law == "hertz":
        start = text.index("[contact]")
        text = text[:start] + '[contact]\nlaw = "hertz"\n' + text[text.index("[loading]") :]
    sc = plan_for(parse_scene(text, source=f"{law}.toml"), "reference", method)[0]
    sc = replace(sc, run=replace(sc.run, timestep=sc.run.timestep / finer, stop_after_contact=None))
    p = tmp_path / f"{law}.toml"
    p.write_text(sc.to_toml())
    return p


@pytest.mark.parametrize(
    ("law", "method", "finer", "estimate", "roles"),
    [
        ("hertz", "rk4", 1.0, "on", ["companion", "companion"]),  # 2 dt and 4 dt
        ("hertz", "rk4", 1.0, "checked", ["companion", "companion", "check"]),  # and dt / 2
        ("bilinear", "rk4", 1.0, "on", ["companion"]),  # a kinked law: 2 dt alone
        ("bilinear", "verlet", 1.0, "on", ["companion", "companion"]),  # its own bounds: RK4 would cost more
        ("bilinear", "verlet", 10.0, "on", ["rk4 reference", "rk4 reference"]),  # RK4 cheaper than the run
    ],
)
def test_plan_counts_the_steps_the_run_and_its_companions_take(tmp_path, capsys, law, method, finer, estimate, roles):
    p = concrete(tmp_path, law, method, finer)
    assert main(["plan", str(p), "--method", method, "--error-estimate", estimate, "--json"]) == 0
    plan = json.loads(capsys.readouterr().out)
    assert [c["role"] for c in plan["companions"]] == roles
    out = tmp_path / "run"
    assert main(["run", str(p), "--method", method, "--error-estimate", estimate, "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    e = summary["errors"]
    assert summary["steps"] == plan["steps"]
    own = [c for c in plan["companions"] if c["role"] != "check"]
    assert e["companion_timesteps"] == pytest.approx([c["timestep"] for c in own])
    assert e["companion_steps"] == [c["steps"] for c in own]
    assert e["check_steps"] == next((c["steps"] for c in plan["companions"] if c["role"] == "check"), None)
    taken = sum(e["companion_steps"]) + (e["check_steps"] or 0)
    assert plan["companion_steps"] == taken
    assert plan["total_steps"] == summary["steps"] + taken
    assert plan["total_bead_steps"] == plan["total_steps"] * summary["beads"]


def test_plan_prints_the_total_and_when_a_run_is_run_again(capsys):
    assert main(["plan", "plastic-short-impulse", "--rtol", "1e-3"]) == 0
    out = capsys.readouterr().out
    assert "error bars  --error-estimate on: rk4 at 2 dt (companion)" in out
    assert "total " in out
    assert "refined:" in out
    assert "PlanRefinedWarning" in out
    assert main(["plan", "plastic-short-impulse", "--error-estimate", "off"]) == 0
    assert "no companion runs (--error-estimate off)" in capsys.readouterr().out
