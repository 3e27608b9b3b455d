"""Campaigns as data (issue 43 item 5): the table's units in attrs, a point whose value could not be
measured says so with the reason, the campaign records the libraries it ran on, and signac's own
to_dataframe() shows each point's results."""

from __future__ import annotations

import json

import pytest

from granchain.campaigns import workspace as wsp
from granchain.campaigns.run import load_campaign, run_campaign
from granchain.campaigns.spec import parse_campaign
from granchain.postprocess.observables import units
from granchain.results import CAMPAIGN_PACKAGES, RUN_PACKAGES, package_versions

from .test_campaign_values import campaign_text


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    """Two points of a 20-bead chain: one run long enough for its window, one stopped before the
    leading pulse reached the window's last contact (its leading_peak_force cannot be measured)."""
    ws = tmp_path_factory.mktemp("camp") / "ws"
    text = campaign_text('[vary]\n"run.end_time" = [4e-4, 1e-4]\n"loading.amplitude" = [1000.0]\n')
    run_campaign(parse_campaign(text), ws, workers=1)
    return ws


def test_every_column_has_its_unit_and_the_campaign_its_libraries(workspace):
    """attrs["units"] names every column's unit: a scene key's, an observable's and its error's the
    registry's; attrs["provenance"] and campaign.json record dask, distributed and signac too."""
    from granchain.scene import KEY_UNITS

    df = load_campaign(workspace)
    u = df.attrs["units"]
    assert set(u) == set(df.columns)
    assert u["run.end_time"] == KEY_UNITS["run.end_time"] == "s"
    assert u["loading.amplitude"] == "N"
    for name, unit in units().items():
        if name in df.columns:
            assert u[name] == unit, name
    assert u["timestep"] == "s"
    assert "-" not in u.values()
    packages = json.loads((workspace / wsp.RECORD).read_text())["provenance"]["packages"]
    assert packages == package_versions(RUN_PACKAGES + CAMPAIGN_PACKAGES)
    assert {"dask", "distributed", "signac"} <= {k for k, v in packages.items() if v}
    assert df.attrs["provenance"]["packages"] == packages


def test_a_point_whose_value_is_missing_says_which_and_why(workspace):
    """The short run's row names the observables it could not measure, with summary.json's reasons
    (its status stays 'done': the run is complete; the long run's column is blank)."""
    df = load_campaign(workspace).set_index("run.end_time")
    assert df.loc[4e-4, "status"] == "done"
    assert not isinstance(df.loc[4e-4, "unmeasured"], str)
    short = df.loc[1e-4]
    summary = json.loads((workspace / "workspace" / short["job"] / wsp.RUN_DIR / "summary.json").read_text())
    missing = summary["observables_missing"]
    assert missing
    assert short["status"] == "done"
    never = set(summary["observables_inapplicable"])  # a wall's on this free chain: never measurable
    assert never
    assert never < set(missing)
    for name, why in missing.items():
        assert (f"{name}: {why}" in short["unmeasured"]) == (name not in never), name


def test_signac_to_dataframe_shows_each_points_results(workspace):
    """signac's own to_dataframe() has the observables beside the state points."""
    import signac

    frame = signac.get_project(str(workspace)).to_dataframe()
    table = load_campaign(workspace).set_index("job")
    assert "doc.leading_peak_force" in frame.columns
    for job, row in frame.iterrows():
        assert row["doc.max_peak_force"] == table.loc[job, "max_peak_force"]
    assert frame["doc.unmeasured"].notna().sum() == 1
