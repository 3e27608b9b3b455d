"""Issue 45's acceptance on both backends (slow set): a two-variable continuous search whose optimum a
dense grid of the same runs locates, the one-variable taper and the enumerated categorical problem on
LAMMPS (test_optimize.py runs them on the reference), and a search through a real SLURM queue that
gives the local search's trials.

The two-variable problem: maximise F - c v^2 over the taper t of R_i = R t^(i-1) and the striker's
speed v, where F is the last window contact's leading pulse (test_optimize.scene). F = a(t) v^(6/5)
for a Hertz chain (the equations of motion scale: every force by v^(6/5) when every speed is
multiplied by v), so the optimum is interior in both: a(t) has its interior maximum (the
one-variable problem), and d/dv (a v^(6/5) - c v^2) = 0 at v* = (0.6 a / c)^(5/4). c is chosen so that
v* is near the middle of the speed range for the best taper; nothing else depends on it: the grid,
not a formula, is the truth the search is judged against.
"""

from __future__ import annotations

import numpy as np
import pytest

from granchain.campaigns.run import load_campaign, run_campaign
from granchain.campaigns.table import TIMING_COLUMNS

from .test_optimize import TAPER, scene, sched  # noqa: F401  (sched: a fixture)
from .test_slurm import no_job_left, slurm  # noqa: F401  (fixtures: a SLURM that answers, no job left)

#: the price of impact energy in the objective (N s^2/m^2): v* near 1 m/s at the best taper, where
#: F is about 240 N at 1 m/s (0.6 * 240 = 144)
C = 144.0
TAPERS = (1.0, 1.4)
SPEEDS = (0.4, 2.0)
NUM = 9
TWO = {
    "objective": f"leading_peak_force - {C} * loading.velocity ** 2",
    "direction": "maximize",
    "variables": {
        "chain.taper": {"low": TAPERS[0], "high": TAPERS[1]},
        "loading.velocity": {"low": SPEEDS[0], "high": SPEEDS[1]},
    },
}


def _campaign(backend: str, **parts) -> dict:
    return {"campaign": {"backend": backend, "rtol": 1e-3, "error_estimate": False}, "scene": scene(), **parts}


def _no_timing(df):
    """The table without the columns that differ between two runs of the same points (wall times)."""
    return df.drop(columns=[c for c in TIMING_COLUMNS if c in df.columns])


def _grid(tmp_path, backend: str, vary: dict, sched):  # noqa: F811
    df, _ = run_campaign(_campaign(backend, vary=vary), tmp_path / f"grid-{backend}", scheduler=sched)
    return df["table"]


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["reference", "lammps"])
def test_a_two_variable_optimum_the_dense_grid_confirms(tmp_path, sched, backend):  # noqa: F811
    """A 9 x 9 grid has its best inside both ranges; within 30 trials the search's best is at least as
    good as the worst of the grid best's eight neighbours (the grid's resolution) and within two grid
    steps of it in each variable."""
    vary = {
        "chain.taper": {"linear": list(TAPERS), "num": NUM},
        "loading.velocity": {"linear": list(SPEEDS), "num": NUM},
    }
    grid = _grid(tmp_path, backend, vary, sched)
    assert len(grid) == NUM * NUM
    t = np.round((grid["chain.taper"].to_numpy() - TAPERS[0]) / ((TAPERS[1] - TAPERS[0]) / (NUM - 1))).astype(int)
    v = np.round((grid["loading.velocity"].to_numpy() - SPEEDS[0]) / ((SPEEDS[1] - SPEEDS[0]) / (NUM - 1))).astype(int)
    f = np.full((NUM, NUM), np.nan)
    f[t, v] = grid["leading_peak_force"].to_numpy() - C * grid["loading.velocity"].to_numpy() ** 2
    assert not np.isnan(f).any()
    i, j = np.unravel_index(int(np.argmax(f)), f.shape)
    assert 0 < i < NUM - 1, "the grid's best taper is at an end: no interior optimum to find"
    assert 0 < j < NUM - 1, "the grid's best speed is at an end: no interior optimum to find"
    neighbours = min(f[i + di, j + dj] for di in (-1, 0, 1) for dj in (-1, 0, 1) if (di, dj) != (0, 0))
    opt = {**TWO, "trials": 30, "seed": 4}
    run_campaign(_campaign(backend, optimize={"confirm": False, **opt}), tmp_path / f"opt-{backend}", scheduler=sched)
    best = load_campaign(tmp_path / f"opt-{backend}", "best").iloc[0]
    assert best["objective"] >= neighbours, (best["objective"], f[i, j], neighbours)
    steps = ((TAPERS[1] - TAPERS[0]) / (NUM - 1), (SPEEDS[1] - SPEEDS[0]) / (NUM - 1))
    grid_best = (TAPERS[0] + i * steps[0], SPEEDS[0] + j * steps[1])
    assert abs(best["chain.taper"] - grid_best[0]) <= 2 * steps[0]
    assert abs(best["loading.velocity"] - grid_best[1]) <= 2 * steps[1]
    # the objective is the one the point's own run measured, evaluated as the grid's is
    trials = load_campaign(tmp_path / f"opt-{backend}", "trials")
    done = trials[trials["state"] == "complete"]
    assert len(done) >= 20, "most trials of an unconstrained search complete"


@pytest.mark.slow
def test_the_one_variable_taper_and_the_categorical_problem_on_lammps(tmp_path, sched):  # noqa: F811
    """test_optimize's two problems on the LAMMPS backend: the taper's optimum within two steps of a
    13-point grid's and at least as good as the grid best's neighbours; the material the enumeration's
    best (its very point: the same workspace)."""
    num = 13
    grid = _grid(tmp_path, "lammps", {"chain.taper": {"linear": [1.0, 1.4], "num": num}}, sched)
    f = grid["leading_peak_force"].to_numpy()
    k = int(f.argmax())
    assert 0 < k < num - 1
    run_campaign(
        _campaign("lammps", optimize={"confirm": False, **TAPER, "trials": 12, "seed": 3}),
        tmp_path / "taper",
        scheduler=sched,
    )
    best = load_campaign(tmp_path / "taper", "best").iloc[0]
    assert best["objective"] >= min(f[k - 1], f[k + 1])
    assert abs(best["chain.taper"] - grid["chain.taper"][k]) <= 2 * 0.4 / (num - 1)
    materials = ["brass", "stainless-steel-316", "chrome-steel-52100", "aluminium-6061-t6"]
    ws = tmp_path / "enum"
    enum, _ = run_campaign(_campaign("lammps", vary={"chain.material": materials}), ws, scheduler=sched)
    truth = enum["table"].loc[enum["table"]["leading_peak_force"].idxmin()]
    cat = {
        "objective": "leading_peak_force",
        "trials": 8,
        "seed": 0,
        "variables": {"chain.material": {"choices": materials}},
    }
    run_campaign(_campaign("lammps", optimize={"confirm": False, **cat}), ws, scheduler=sched)
    best = load_campaign(ws, "best").iloc[0]
    assert best["chain.material"] == truth["chain.material"]
    assert best["job"] == truth["job"]


@pytest.mark.slow
@pytest.mark.slurm
def test_a_search_through_slurm_gives_the_local_searchs_trials(tmp_path, sched, no_job_left):  # noqa: F811
    """The taper search (reference, 8 trials, seed 5) on one SLURM worker job gives the trials table of
    the same search on the local cluster (but for the wall times) and the same best design; the job
    ran the points (its task records name its worker), and no job is left in the queue."""
    import json

    opt = {"confirm": False, **TAPER, "trials": 8, "seed": 5}
    spec = _campaign("reference", optimize=opt)
    cluster = {"kind": "slurm", "jobs": 1, "interface": "lo", "walltime": "00:20:00"}
    remote, _ = run_campaign(spec, tmp_path / "slurm", cluster=cluster)
    local, _ = run_campaign(spec, tmp_path / "local", scheduler=sched)
    assert _no_timing(remote["trials"]).equals(_no_timing(local["trials"]))
    assert _no_timing(load_campaign(tmp_path / "slurm", "best")).equals(
        _no_timing(load_campaign(tmp_path / "local", "best"))
    )
    jobs = remote["trials"]["job"].dropna()
    tasks = [json.loads((tmp_path / "slurm" / "workspace" / j / "task.json").read_text()) for j in jobs]
    assert tasks, "the search ran its points"
    assert len({t["pid"] for t in tasks}) == 1, "the one worker job ran every point"
    assert any(p.name.endswith(".err") for p in (tmp_path / "slurm" / "jobs").iterdir())
