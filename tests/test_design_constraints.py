"""A search's constraints on the design's own chain (issue 45: a total length or mass as a bound):
`chain_mass` and `chain_length` are computed from each design's scene and checked before it runs; a
design beyond the bound is infeasible and never run, one within it runs. The truth is computed here by
hand from the materials' densities and the taper's radii (R_i = R t^(i-1))."""

from __future__ import annotations

import math

import pytest

from granchain.campaigns.model import CampaignError
from granchain.campaigns.run import load_campaign, run_campaign
from granchain.campaigns.spec import campaign_from_dict
from granchain.physics.materials import MATERIALS

from .test_optimize import BEADS, TAPER, optimize_campaign, sched  # noqa: F401  (sched: a fixture)

R = 4.76e-3


def _mass(materials: list[str], radii: list[float]) -> float:
    return sum(4.0 / 3.0 * math.pi * r**3 * MATERIALS[m].density for m, r in zip(materials, radii, strict=True))


def test_a_mass_bound_on_sectioned_designs_rules_out_the_heavy_ones_before_they_run(tmp_path, sched):  # noqa: F811
    """Two sections of 3 beads, each brass, PTFE or aluminium; at most the mass of one brass and one
    PTFE section: a brass section beside an aluminium or a brass one is infeasible (not run), every
    other design runs."""
    choices = ["brass", "ptfe", "aluminium-6061-t6"]
    bound = _mass(["brass"] * 3 + ["ptfe"] * 3, [R] * 6) * (1 + 1e-9)
    c = optimize_campaign(
        {
            "objective": "leading_peak_force",
            "trials": 9,
            "seed": 2,
            "variables": {"m1": {"choices": choices}, "m2": {"choices": choices}},
            "constraints": [f"chain_mass <= {bound!r}"],
        }
    )
    c["sections"] = {"chain.material": {"values": ["m1", "m2"], "beads": [3, 3]}}
    tables, _ = run_campaign(c, tmp_path / "w", scheduler=sched)
    t = tables["trials"]
    heavy = [_mass([a] * 3 + [b] * 3, [R] * 6) > bound for a, b in zip(t["m1"], t["m2"], strict=True)]
    assert any(heavy), "the draws never reached the bound: the test checks nothing"
    assert not all(heavy)
    for is_heavy, (_, row) in zip(heavy, t.iterrows(), strict=True):
        if is_heavy:
            assert row["state"] == "infeasible", row.to_dict()
            assert row["job"] != row["job"] or row["job"] is None  # NaN or None: never run
            assert "chain_mass" in row["message"]
        else:
            assert row["state"] == "complete", row.to_dict()


def test_a_length_bound_on_a_taper_is_the_closed_form_length(tmp_path, sched):  # noqa: F811
    """chain_length = 2 R sum t^(i-1) over the beads: a bound at t = 1.2's length makes every taper
    above 1.2 infeasible and every one below complete."""
    length = lambda t: 2.0 * R * sum(t**i for i in range(BEADS))  # noqa: E731
    opt = {**TAPER, "trials": 8, "seed": 1, "constraints": [f"chain_length <= {length(1.2)!r}"]}
    t = run_campaign(optimize_campaign(opt), tmp_path / "w", scheduler=sched)[0]["trials"]
    over = t["chain.taper"].map(length) > length(1.2)
    assert over.any()
    assert (~over).any()
    assert (t[over]["state"] == "infeasible").all()
    assert (t[~over]["state"] == "complete").all()
    assert load_campaign(tmp_path / "w", "best").iloc[0]["chain.taper"] <= 1.2


def test_a_misspelt_design_number_is_one_clear_error():
    opt = {**TAPER, "constraints": ["chain_mas <= 1.0"]}
    with pytest.raises(CampaignError, match="did you mean 'chain_mass'"):
        campaign_from_dict(optimize_campaign(opt))
