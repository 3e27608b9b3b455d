"""What a campaign's points hold and its table stores: "auto" beside numbers in one column, a derived
integer key, a varied taper, each run's own points when two campaigns share a workspace."""

from __future__ import annotations

import json
import math
import re
import textwrap
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.campaigns import workspace as wsp
from granchain.campaigns.spec import CampaignError, parse_campaign
from granchain.cli import main

from .conftest import CAMPAIGN_SCENE

QUICK = 'backend = "reference"\nmethod = "verlet"\nerror_estimate = false'


def campaign_text(body: str, scene: str = CAMPAIGN_SCENE, campaign: str = QUICK) -> str:
    return f"[campaign]\n{campaign}\n\n{textwrap.dedent(body)}\n[scene]\n" + scene.replace("\n[", "\n[scene.")


# ------------------------------------------------------------ two campaigns, one workspace


def test_two_campaigns_on_one_workspace_each_return_and_print_their_own_points(tmp_path, monkeypatch, capsys):
    """Campaign B runs into A's workspace while A's points run (B rewrites campaign.json): A's table
    is A's 3 points, B's is B's 1."""
    from granchain.campaigns import run as run_module

    a = parse_campaign(campaign_text('[vary]\n"loading.amplitude" = [10.0, 20.0, 30.0]\n'))
    b = parse_campaign(campaign_text('[vary]\n"loading.amplitude" = [40.0]\n'))
    ws = tmp_path / "ws"
    grid, tables_of_b = run_module.run_grid, []

    def and_another_campaign_meanwhile(campaign, runner, points):
        grid(campaign, runner, points)
        if campaign is a:
            tables_of_b.append(run_module.run_campaign(b, ws, workers=1)[0]["table"])

    monkeypatch.setattr(run_module, "run_grid", and_another_campaign_meanwhile)
    table_of_a = run_module.run_campaign(a, ws, workers=1)[0]["table"]
    assert table_of_a["loading.amplitude"].tolist() == [10.0, 20.0, 30.0]
    assert tables_of_b[0]["loading.amplitude"].tolist() == [40.0]
    assert set(table_of_a["status"]) == {"done"}


# ------------------------------------------------------------ "auto" beside numbers

#: the scene keys that take "auto" (the planner's choice) and a strategy of their other values
AUTO_KEYS = {
    "chain.beads": st.integers(1, 10**6),
    "run.end_time": st.floats(1e-9, 1.0),
    "run.timestep": st.floats(1e-15, 1e-6),
    "outputs.history_interval": st.floats(1e-12, 1e-3),
    "outputs.dump_interval": st.floats(1e-12, 1e-3),
}


def _workspace_of(tmp_path: Path, params: list[dict]) -> Path:
    """A workspace whose record has these points (none run yet: every row 'missing')."""
    import signac

    ws = tmp_path / "ws"
    ws.mkdir(exist_ok=True)
    signac.init_project(str(ws))
    points = [{"params": p, "job": f"{k:032x}", "key": None} for k, p in enumerate(params)]
    wsp.write_json(ws / wsp.RECORD, {"kind": "grid", "code": {}, "points": points})
    return ws


def _stored_as_given(df, params: list[dict]) -> None:
    """Each point's value in the stored table: a number as that number, "auto" as NaN with
    <key>_auto True, in a column of mixed kinds (true, [5, 10]) the value as JSON writes it."""
    import pandas as pd

    for i, p in enumerate(params):
        for key, v in p.items():
            cell = df[key].iloc[i]
            if f"{key}_auto" in df.columns:
                assert bool(df[f"{key}_auto"].iloc[i]) == (v == "auto")
                assert math.isnan(cell) if v == "auto" else cell == float(v)
            elif isinstance(v, list) or pd.api.types.is_string_dtype(df[key]):
                assert cell == (v if isinstance(v, str) else json.dumps(v))
            else:
                assert cell == v


@settings(max_examples=25, deadline=None)
@given(
    data=st.data(),
    keys=st.lists(st.sampled_from(sorted(AUTO_KEYS)), min_size=1, max_size=3, unique=True),
    points=st.integers(1, 5),
)
def test_a_key_that_is_auto_at_some_points_and_a_number_at_others_is_stored_and_read(
    tmp_path_factory, data, keys, points
):
    """Every mix of "auto" and numbers of every auto-able key (and peak_force true / a list of
    contacts): table.csv and table.parquet are written, read back with each point's value, and
    `campaign table --csv` prints them."""
    import pandas as pd

    from granchain.campaigns.table import write_tables

    params = []
    for _ in range(points):
        p = {k: data.draw(st.one_of(st.just("auto"), AUTO_KEYS[k])) for k in keys}
        p["outputs.peak_force"] = data.draw(st.one_of(st.booleans(), st.lists(st.integers(1, 99), max_size=3)))
        params.append(p)
    ws = _workspace_of(tmp_path_factory.mktemp("auto"), params)
    write_tables(ws)
    _stored_as_given(pd.read_parquet(ws / "table.parquet"), params)
    csv = pd.read_csv(ws / "table.csv")
    for key in keys:
        assert csv[key].tolist() == pytest.approx(pd.read_parquet(ws / "table.parquet")[key].tolist(), nan_ok=True)
    assert main(["campaign", "table", str(ws), "--csv"]) == 0


def test_a_campaign_varying_end_time_between_auto_and_a_number_runs_and_its_table_reads(tmp_path, capsys):
    """end_time "auto" and 1e-4, peak_force true and [5, 10]: 4 points run, the table is written
    (it was an ArrowTypeError after every point had run), and `campaign table` reads it."""
    import pandas as pd

    f = tmp_path / "c.toml"
    f.write_text(campaign_text('[vary]\n"run.end_time" = ["auto", 1e-4]\n"outputs.peak_force" = [true, [5, 10]]\n'))
    assert main(["campaign", "run", str(f), "--out", str(tmp_path / "ws"), "--workers", "1"]) == 0
    df = pd.read_parquet(tmp_path / "ws" / "table.parquet")
    assert df["run.end_time_auto"].tolist() == [True, True, False, False]
    assert df["run.end_time"].tolist()[2:] == [1e-4, 1e-4]
    assert df["outputs.peak_force"].tolist() == ["true", "[5, 10]"] * 2
    assert set(df["status"]) == {"done"}
    capsys.readouterr()
    assert main(["campaign", "table", str(tmp_path / "ws")]) == 0
    lines = capsys.readouterr().out.splitlines()  # the terminal view: "auto" where the point left it "auto"
    assert lines[0].split()[0] == "run.end_time"
    assert [line.split()[0] for line in lines[1:]] == ["auto", "auto", "0.0001", "0.0001"]
    plot = ["campaign", "plot", str(tmp_path / "ws"), "--y", "max_peak_force"]
    assert main([*plot, "--x", "run.end_time", "--hue", "outputs.peak_force"]) == 0
    capsys.readouterr()
    assert main([*plot, "--x", "outputs.peak_force"]) == 2  # text on an axis: one message (a ValueError traceback)
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith("granchain: error: ")
    assert "--x 'outputs.peak_force' is not a column of numbers" in line


# ------------------------------------------------------------ a derived integer key


@settings(max_examples=40, deadline=None)
@given(n=st.integers(0, 4000), offset=st.sampled_from([0.0, 0.5, 0.25]))
def test_a_derived_integral_value_of_an_integer_key_is_that_integer(n, offset):
    """[derive] "chain.beads" = "2 * n + 6": 2 n + 6 beads (a float 20.0 from the expression was
    refused: 'an integer'); 2 n + 6.5 is refused, naming the key and what it takes."""
    text = campaign_text(f'[vary]\nn = [{n}]\n[derive]\n"chain.beads" = "2 * n + 6 + {offset}"\n')
    if offset:
        with pytest.raises(CampaignError, match=rf"\[chain\] beads = {2 * n + 6 + offset!r} is invalid: an integer"):
            parse_campaign(text).points()
        return
    (point,) = parse_campaign(text).points()
    assert point.scene.chain.beads == 2 * n + 6
    assert type(point.params["chain.beads"]) is int


def test_a_spaced_integer_key_takes_whole_numbers():
    """{ linear = [8, 32], num = 4 } for chain.beads: 8, 16, 24, 32 beads (not 8.0, ... refused)."""
    c = parse_campaign(campaign_text('[vary]\n"chain.beads" = { linear = [8, 32], num = 4 }\n'))
    assert [p.scene.chain.beads for p in c.points()] == [8, 16, 24, 32]


# ------------------------------------------------------------ a varied taper

TAPERED = CAMPAIGN_SCENE.replace('material = "brass"\n', 'material = "brass"\ntaper = 0.97\n')


@settings(max_examples=20, deadline=None)
@given(taper=st.floats(0.8, 1.05), beads=st.integers(6, 40), how=st.sampled_from(["inline", "file", "bundled"]))
def test_a_varied_taper_is_the_scene_file_with_that_taper(tmp_path_factory, taper, beads, how):
    """Varying chain.taper (and chain.beads) over a tapered base: each point's scene is the scene that
    the base's file with those values parses to (every value was refused: 'a rule for a single
    nominal radius and a given number of beads', the base's taper having become per-bead radii)."""
    from granchain.scene import SceneError, bundled_scenes, parse_scene, scene_to_dict

    vary = f'[vary]\n"chain.taper" = [{taper!r}]\n"chain.beads" = [{beads}]\n'
    if how == "inline":
        text, base = campaign_text(vary, scene=TAPERED), TAPERED
    else:
        d = tmp_path_factory.mktemp("taper")
        base = TAPERED if how == "file" else bundled_scenes()["classic-struck-taper"]
        (d / "base.toml").write_text(base)
        name = "base.toml" if how == "file" else "classic-struck-taper"
        text = f'[campaign]\nbase = "{name}"\n{QUICK}\n\n{vary}'
    edited = base.replace("taper = 0.97\n", f"taper = {taper!r}\n").replace("taper = 0.9 ", f"taper = {taper!r} ")
    edited = edited.replace("beads = 20\n", f"beads = {beads}\n")
    base_dir = None if how == "inline" else d
    try:
        expected = scene_to_dict(parse_scene(edited))
    except SceneError as e:  # the file refuses it: so does the campaign, for the same reason
        with pytest.raises(CampaignError, match="is not a valid scene: " + re.escape(str(e).split(": ", 1)[1])):
            parse_campaign(text, base_dir=base_dir).points()
        return
    (point,) = parse_campaign(text, base_dir=base_dir).points()
    assert point.scene_dict == expected


def test_a_campaign_varying_the_taper_of_a_tapered_chain_runs(tmp_path):
    import granchain

    f = tmp_path / "c.toml"
    f.write_text(campaign_text('[vary]\n"chain.taper" = [0.95, 1.0]\n', scene=TAPERED))
    df = granchain.campaign(str(f), tmp_path / "ws", workers=1)
    assert set(df["status"]) == {"done"}
    assert df["chain.taper"].tolist() == [0.95, 1.0]
