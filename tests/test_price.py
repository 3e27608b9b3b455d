"""Every run states its price: summary.json's "price"."""

import json

import pytest

from granchain.lammps.runner import log_timing
from granchain.rundir import write_run_dir
from granchain.workflows.run import run_scene

from .conftest import make_scene

LOG = """LAMMPS (22 Jul 2025 - Update 4)
Loop time of 0.25 on 2 procs for 100 steps with 30 atoms
Section |  min time  |  avg time  |  max time  |%varavg| %total
---------------------------------------------------------------
Pair    | 0.1        | 0.11       | 0.12       |   0.0 | 44.00
Output  | 0.01       | 0.02       | 0.03       |   0.0 |  8.00
Other   |            | 0.001      |            |       |  0.40
Loop time of 0.5 on 2 procs for 200 steps with 30 atoms
Output  | 0.04       | 0.05       | 0.06       |   0.0 | 10.00
"""


def test_log_timing_adds_every_run():
    t = log_timing(LOG)
    assert t["loop_time"] == pytest.approx(0.75)
    assert t["output_time"] == pytest.approx(0.07)
    assert log_timing("no runs here") == {"loop_time": None, "output_time": None}


@pytest.mark.parametrize("backend", ["reference", "lammps"])
@pytest.mark.parametrize(
    "loading",
    ['kind = "impulse"\nimpulse = 0.1\nduration = 1e-6', 'kind = "striker"\nvelocity = 1.0\nradius = 4.76e-3'],
)
def test_price_parts_add_up(tmp_path, backend, loading):
    sc = make_scene(beads=20, end_time=5e-5, timestep=2e-8, loading=loading, outputs="histories = [1, 2]")
    res = run_scene(sc, backend=backend, error_estimate=True)
    write_run_dir(res, tmp_path / "run")
    price = json.loads((tmp_path / "run" / "summary.json").read_text())["price"]
    parts = [price[k] for k in ("start_up", "plugin_build", "setup", "integration", "output")]
    assert all(p is None or p >= 0.0 for p in parts)
    assert price["wall_time"] == pytest.approx(sum(p for p in parts if p is not None))
    beads = 20 + (loading.startswith('kind = "striker"'))
    steps = res.solution.steps + res.solution.extra_steps
    assert price["steps"] == steps
    assert price["bead_steps"] == steps * beads
    assert price["ns_per_bead_step"] == pytest.approx(1e9 * price["integration"] / price["bead_steps"])
    assert price["error_estimate"] == pytest.approx(sum(res.errors.wall_times))
    if backend == "lammps":
        assert price["start_up"] > 0.0
        assert price["integration"] > 0.0
        assert price["output"] > 0.0
        assert price["integration"] <= res.extra["loop_time"] <= res.solution.wall_time
        assert "not_timed" not in price
    else:
        assert price["integration"] == res.solution.wall_time
        assert price["output"] is None
        assert "output" in price["not_timed"]
