"""Where a run itself has no value of an observable, its error entry (summary.json errors.observables)
says the run's own reason (observables_missing), not what its companions lacked."""

import pytest

from granchain.scene import load_scene, parse_scene
from granchain.workflows.run import run_scene

from .test_front_resolution_reason import CHAIN


@pytest.mark.parametrize(
    "scene",
    [
        "classic-two-spheres",  # one bead: no bead-bead contact
        "tiny-wave",  # a precompressed wave below the front resolution: no wave speed
    ],
)
def test_a_missing_observables_error_status_is_the_runs_own_reason(scene, tmp_path):
    if scene == "tiny-wave":
        text = CHAIN.format(radius=3e-3, material="brass", velocity=1e-7, f0=500.0)
        sc = parse_scene(text, source="tiny.toml")
    else:
        sc = load_scene(scene)
    result = run_scene(sc, backend="reference", out=tmp_path / "run", error_estimate=True)
    missing = result.observables_missing()
    errors = result.summary()["errors"]["observables"]
    lacking = [k for k, v in result.observables().items() if v is None and k in errors]
    assert lacking, "the scene should leave an observable unmeasured"
    for k in lacking:
        assert errors[k]["status"] == f"not measured: {missing[k]}", (k, errors[k]["status"])
