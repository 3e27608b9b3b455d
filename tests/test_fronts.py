"""Table I (Sec. III B): the fronts of a bilinear chain under a long load, measured from a run and
set against the quasi-steady model (Eqs. 35-38, as derived in physics.models; the paper's printed
v_2 and x_t disagree with its own equations, docs/paper-discrepancies.md)."""

from dataclasses import replace

import numpy as np
import pytest

from granchain.cli import resolve_scene
from granchain.physics import models
from granchain.postprocess.fronts import long_load_fronts
from granchain.workflows.run import run_scene

#: the paper's own demonstrated agreement between its numerics and this model: Table I's largest
#: relative difference (x_t, 0.333 vs 0.342 m: 2.7%); the model neglects the fronts' width
MODEL_AGREEMENT = 0.03


def test_table1_fronts_follow_the_quasi_steady_model():
    sc = resolve_scene("plastic-long-load-table1")  # snapshots in each phase: 2, 3 and 5.2 ms
    sol = run_scene(replace(sc, run=replace(sc.run, timestep=1e-7)), method="verlet").solution
    got = long_load_fronts(sc, sol)
    ld = sc.loading
    model = models.long_load_bilinear(
        ld.amplitude, ld.duration, sc.stiffness, sc.contact.unloading_coeff, sc.mass, sc.diameter
    )
    print({k: f"{got[k]:.4g} (model {model[k]:.4g})" for k in got})
    for key in ("F_1", "v_1", "v_t", "F_2", "v_2", "x_t"):
        assert got[key] == pytest.approx(model[key], rel=MODEL_AGREEMENT), key
    # and the paper's printed v_2 = 14.84 m/s and x_t = 0.342 m are not what the chain does
    assert abs(got["v_2"] / 14.84 - 1) > 0.2
    assert abs(got["x_t"] / 0.342 - 1) > 5


def test_fronts_need_their_phases():
    sc = resolve_scene("plastic-long-load-table1")
    short = replace(
        sc, run=replace(sc.run, end_time=2.2e-3, timestep=1e-7), outputs=replace(sc.outputs, snapshots=(2e-3,))
    )
    got = long_load_fronts(short, run_scene(short, method="verlet").solution)
    assert np.isfinite(got["v_1"])
    assert np.isnan(got["v_t"])
    assert np.isnan(got["F_2"])
    assert np.isnan(got["x_t"])
    with pytest.raises(ValueError, match="bilinear"):
        long_load_fronts(resolve_scene("default"), None)
