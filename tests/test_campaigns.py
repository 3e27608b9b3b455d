"""Campaigns: campaign files, the safe expression language, the signac workspace, runs on a local
Dask cluster, the table, the search kind (end to end on Dask, slow: test_campaign_execution.py)."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import pytest

from granchain.campaigns import expr
from granchain.campaigns import workspace as wsp
from granchain.campaigns.spec import CampaignError, parse_campaign

from .conftest import CAMPAIGN_SCENE
from .scenegen import brass_impulse_text

SMALL_SCENE = CAMPAIGN_SCENE


def campaign_text(
    body: str, scene: str = SMALL_SCENE, campaign: str = 'backend = "reference"\nmethod = "verlet"'
) -> str:
    return f"[campaign]\n{campaign}\n\n{textwrap.dedent(body)}\n[scene]\n" + scene.replace("\n[", "\n[scene.")


# ------------------------------------------------------------------------------- expressions


@pytest.mark.parametrize(
    ("text", "values", "expected"),
    [
        ("impulse / amplitude", {"impulse": 0.4, "amplitude": 100.0}, 0.004),
        ("2 ** 3 ** 2", {}, 512.0),  # right-associative
        ("-2 ** 2", {}, -4.0),  # ** binds tighter than a unary minus
        ("(1 + 2) * 3 - 4 / 2", {}, 7.0),
        ("loading.amplitude * 1e-3", {"loading.amplitude": 5.0}, 5e-3),
        ("a ** -0.5", {"a": 4.0}, 0.5),
        (".5e1 + 1.", {}, 6.0),
    ],
)
def test_expression_values(text, values, expected):
    assert expr.evaluate(expr.parse(text), values, text) == pytest.approx(expected, rel=1e-15)


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("__import__('os').system('true')", "is not allowed"),  # no calls, no strings, no attributes
        ("a[0]", "is not allowed"),
        ("lambda: 1", "':' at position 7 is not allowed"),
        ("1 +", "ends too early"),
        ("(1 + 2", "never closed"),
        ("1 2", "unexpected"),
        ("", "non-empty"),
        ("a; b", "is not allowed"),
    ],
)
def test_expressions_refuse_anything_else(text, fragment):
    with pytest.raises(expr.ExpressionError, match=fragment):
        expr.parse(text)


def test_expression_errors_at_evaluation():
    with pytest.raises(expr.ExpressionError, match="division by zero"):
        expr.evaluate(expr.parse("1 / a"), {"a": 0.0}, "1 / a")
    with pytest.raises(expr.ExpressionError, match="not a finite real number"):
        expr.evaluate(expr.parse("(-1) ** 0.5"), {}, "(-1) ** 0.5")
    with pytest.raises(expr.ExpressionError, match="overflows"):
        expr.evaluate(expr.parse("10.0 ** 400"), {}, "10.0 ** 400")


# ----------------------------------------------------------------------------- campaign files


def test_grid_vary_zip_derive():
    c = parse_campaign(
        campaign_text(
            """
            [vary]
            "loading.amplitude" = { log = [1.0, 100.0], num = 3 }
            impulse = [1e-5, 2e-5]
            [zip]
            "chain.beads" = [20, 24]
            "run.end_time" = [1e-4, 1.2e-4]
            [derive]
            "loading.duration" = "impulse / amplitude"
            """
        )
    )
    points = c.points()
    assert len(points) == 3 * 2 * 2
    assert c.varied_keys == ("loading.amplitude", "impulse", "chain.beads", "run.end_time", "loading.duration")
    p = points[-1]
    assert p.params["loading.amplitude"] == 100.0
    assert p.params["chain.beads"] == 24
    assert p.scene.loading.duration == pytest.approx(2e-5 / 100.0, rel=1e-15)
    assert p.scene.chain.beads == 24
    assert p.scene.run.end_time == 1.2e-4
    assert [q.params["loading.amplitude"] for q in points[::4]] == [1.0, 10.0, 100.0]


def test_same_scene_same_canonical_dict():
    """A point's state point uses the canonical scene: 100 and 100.0 are one point."""
    a = parse_campaign(campaign_text('[vary]\n"loading.amplitude" = [100]\n')).points()[0]
    b = parse_campaign(campaign_text('[vary]\n"loading.amplitude" = [100.0]\n')).points()[0]
    assert a.scene_dict == b.scene_dict


BAD_CAMPAIGNS = [
    (
        '[vary]\n"loading.amplitud" = [1.0]\n',
        r"point 1 of 1 \(loading.amplitud = 1\) is not a valid scene: \[loading\] has unknown key 'amplitud'",
    ),
    ('[vary]\n"lodaing.amplitude" = [1.0]\n', "'lodaing' is not a scene section; did you mean 'loading'"),
    ('[vary]\n"loading.amplitude" = []\n', "empty list makes an empty grid"),
    ('[vary]\n"loading.amplitude" = { log = [1.0, 10.0], num = 0 }\n', "num = 0 is invalid"),
    ('[vary]\n"loading.amplitude" = { log = [0.0, 10.0], num = 3 }\n', "both ends must be > 0"),
    ("[vary]\n", r"\[vary\] is empty"),
    ("", "nothing varies"),
    (
        '[vary]\n"loading.amplitude" = [1.0, -5.0]\n',
        r"point 2 of 2 \(loading.amplitude = -5\).*amplitude = -5.0 is invalid",
    ),
    ('[vary]\n"chain.beads" = [20, 1]\n', r"point 2 of 2 \(chain.beads = 1\)"),
    ('[vary]\n"loading.amplitude" = [1.0]\n[derive]\n"loading.duration" = "impulse / amplitude"\n', "reads 'impulse'"),
    ('[vary]\n"loading.amplitude" = [1.0]\n[derive]\n"loading.duration" = "exec(1)"\n', "calls are not allowed"),
    ('[vary]\na = [0.0]\n[derive]\n"loading.duration" = "1 / a"\n', r"point 1 of 1 \(a = 0\).*division by zero"),
    ('[zip]\n"chain.beads" = [20, 21]\n"run.end_time" = [1e-4]\n', "need equal lengths"),
    ('[vary]\n"loading.amplitude" = [1.0]\n[extra]\nx = 1\n', "unknown table or key 'extra'"),
]


@pytest.mark.parametrize(("body", "message"), BAD_CAMPAIGNS)
def test_bad_campaign_files_get_one_clear_message(body, message):
    with pytest.raises(CampaignError, match=message):
        parse_campaign(campaign_text(body)).points()


def test_bad_campaign_keys():
    with pytest.raises(CampaignError, match="unknown key 'backnd'; did you mean 'backend'"):
        parse_campaign(campaign_text('[vary]\n"loading.amplitude" = [1.0]\n', campaign='backnd = "lammps"'))
    with pytest.raises(CampaignError, match="LAMMPS backend integrates with velocity Verlet only"):
        parse_campaign(
            campaign_text('[vary]\n"loading.amplitude" = [1.0]\n', campaign='backend = "lammps"\nmethod = "rk4"')
        )
    with pytest.raises(CampaignError, match="no base scene"):
        parse_campaign('[campaign]\n[vary]\n"loading.amplitude" = [1.0]\n')
    with pytest.raises(CampaignError, match="neither a scene file nor a bundled scene"):
        parse_campaign('[campaign]\nbase = "no-such-scene"\n[vary]\n"loading.amplitude" = [1.0]\n')


def test_search_file_validation():
    good = """
    [vary]
    "loading.amplitude" = [10.0, 100.0]
    [search]
    key = "loading.duration"
    range = [1e-6, 1e-4]
    tolerance = 0.01
    predicate = { quantity = "pulses", contact = 5, op = ">", value = 1 }
    """
    c = parse_campaign(campaign_text(good))
    assert c.kind == "search"
    assert c.search.scale == "log"
    assert c.search.predicate.text == "pulses at contact 5 > 1"
    assert c.varied_keys == ("loading.amplitude", "loading.duration")
    for bad, message in [
        (good.replace('key = "loading.duration"', 'key = "loading.amplitude"'), "also varied"),
        (good.replace('quantity = "pulses"', 'quantity = "pulse"'), "quantity = 'pulse' is invalid"),
        (good.replace('op = ">"', 'op = "=>"'), "op = '=>' is invalid"),
        (good.replace("range = [1e-6, 1e-4]", "range = [0.0, 1e-4]"), "needs both ends > 0"),
        (good.replace("tolerance = 0.01", "tolerance = 0"), "tolerance = 0 is invalid"),
        (good.replace("contact = 5, ", ""), "contact = None is invalid"),
    ]:
        with pytest.raises(CampaignError, match=message):
            parse_campaign(campaign_text(bad))


def test_log_grid_values_are_readable_and_exact_at_the_ends():
    c = parse_campaign(campaign_text('[vary]\n"loading.amplitude" = { log = [1e2, 1e6], num = 9 }\n'))
    vals = [p["loading.amplitude"] for p in c.grid()]
    assert vals[0] == 100.0
    assert vals[-1] == 1e6
    assert vals[2] == 1000.0
    assert all(math.isclose(b / a, math.sqrt(10), rel_tol=1e-11) for a, b in zip(vals, vals[1:], strict=False))


def test_a_point_above_the_stability_limit_is_refused_before_anything_runs(tmp_path):
    from granchain.campaigns.run import run_campaign

    text = campaign_text('[vary]\n"run.timestep" = [5e-8, 5e-5]\n')
    with pytest.raises(CampaignError, match=r"point 2 \(run.timestep = 5e-05\) cannot run: .*stability limit"):
        run_campaign(parse_campaign(text), tmp_path / "ws", workers=1)
    assert not (tmp_path / "ws").exists()  # nothing started, not even the workspace


# ------------------------------------------------------------------------------ running points


def peaks_text(run_dir) -> str:
    return (run_dir / "peaks.csv").read_text()


def job_dirs(ws):
    return sorted((ws / "workspace").iterdir())


def complete_jobs(ws) -> set[str]:
    return {d.name for d in job_dirs(ws) if (d / "run" / "summary.json").is_file()}


REFERENCE_GRID = """
[vary]
"loading.amplitude" = { log = [1.0, 100.0], num = 3 }
"loading.duration" = [1e-6, 2e-6]
[zip]
"chain.beads" = [16, 20]
"outputs.histories" = [[4], [5]]
"""


PRECOMPRESSED = """
[vary]
"precompression.force" = [2000.0, 20.0]
"""


def test_the_table_counts_pulses_on_the_dynamic_force(tmp_path):
    """A 2-4 N pulse on a 24-bead brass chain under F0 = 2000 N never rises a tenth of the total force:
    counted on F - F0 it is one pulse, small against F0 (a weakly nonlinear wave, at c0 = 1063 m/s);
    under F0 = 20 N a solitary wave (both read 'pulses 0, no wave' at 2000 N when counted on F)."""
    from granchain.campaigns.run import run_campaign
    from granchain.physics.models import weakly_nonlinear_ratio

    scene = brass_impulse_text(24, 1e-4, extra="[outputs]\nhistories = [18]\n")
    campaign = 'backend = "reference"\nmethod = "verlet"\nerror_estimate = false'
    c = parse_campaign(campaign_text(PRECOMPRESSED, scene=scene, campaign=campaign))
    df = run_campaign(c, tmp_path / "ws", workers=1)[0]["table"].set_index("precompression.force")
    print(df[["pulses", "regime", "leading_peak_force", "wave_speed"]])
    assert df["pulses"].tolist() == [1, 1]
    assert df.loc[2000.0, "regime"] == "weakly nonlinear wave"
    assert df.loc[2000.0, "leading_peak_force"] < weakly_nonlinear_ratio() * 2000.0
    assert df.loc[20.0, "regime"] == "single solitary wave"


def test_reference_grid_equals_run_scene_bit_for_bit(tmp_path):
    """12 points on the reference solver (with error estimates): each run directory's peaks.csv is
    the one run_scene writes for the same scene, to the bit; the table has every row; a second run
    runs nothing; the workspace is a signac project."""
    import signac

    import granchain
    from granchain.campaigns.run import run_campaign
    from granchain.scene import scene_from_dict
    from granchain.workflows.run import run_scene

    c = parse_campaign(campaign_text(REFERENCE_GRID, campaign='backend = "reference"\nmethod = "verlet"\nrtol = 1e-3'))
    ws = tmp_path / "ws"
    tables, report = run_campaign(c, ws, workers=2)
    df = tables["table"]
    assert (report.points, report.ran, report.done, report.failed) == (12, 12, 12, 0)
    assert len(df) == 12
    assert set(df["status"]) == {"done"}
    assert list(df.columns[:4]) == ["loading.amplitude", "loading.duration", "chain.beads", "outputs.histories"]
    assert df["bead_steps"].gt(0).all()
    assert df["wall_time"].gt(0).all()
    assert set(df["regime"]) == {"single solitary wave"}
    assert df["max_peak_force_error"].notna().any()
    project = signac.get_project(str(ws), search=False)
    assert len(project) == 12
    for job in project:
        sp = job.statepoint()
        assert sp["backend"] == "reference"
        assert sp["method"] == "verlet"
        assert sp["code"] == {"granchain": granchain.__version__, "source": wsp.source_hash()}
        scene = scene_from_dict(sp["scene"])
        out = tmp_path / f"direct-{job.id}"
        run_scene(scene, backend="reference", method="verlet", rtol=1e-3, error_estimate=True, out=out)
        assert peaks_text(Path(job.path) / "run") == peaks_text(out), job.id
    again, report2 = run_campaign(c, ws, workers=2)
    assert (report2.cached, report2.ran) == (12, 0)
    assert again["table"].equals(df)
    assert granchain.load_campaign(ws).equals(df)
    assert (ws / "table.csv").is_file()
    assert (ws / "table.parquet").is_file()


def test_failures_are_recorded_and_the_campaign_goes_on(tmp_path):
    """A point that breaks an invariant is recorded with its one-line message; the others complete;
    a rerun does not retry it unless asked; the CLI exits 1 and names it."""
    from granchain.campaigns.run import run_campaign
    from granchain.cli import main

    path = tmp_path / "c.toml"
    path.write_text(
        campaign_text(
            '[vary]\n"loading.amplitude" = [10.0, 1e9]\n',
            campaign='backend = "reference"\nmethod = "verlet"\nerror_estimate = false',
        )
    )
    ws = tmp_path / "ws"
    tables, report = run_campaign(path, ws, workers=1)
    df = tables["table"]
    assert (report.done, report.failed) == (1, 1)
    assert list(df["status"]) == ["done", "failed"]
    assert df["message"][1].startswith("invariant 'overlap far below the radius' broken")
    assert (ws / "workspace" / df["job"][1] / "failure.json").is_file()
    _, again = run_campaign(path, ws, workers=1)
    assert (again.cached, again.failed_before, again.ran) == (1, 1, 0)
    assert main(["campaign", "run", str(path), "--out", str(ws), "--retry-failed", "-q"]) == 1


def test_the_code_of_a_point_changes_with_any_source_change_and_only_then(tmp_path):
    """The state point's code holds the hash of granchain's sources: a copy of the package hashes as
    the package does; an edit to a module or a deck template, or a renamed module, changes it;
    compiled caches and bundled scenes (inputs, in the state point already) do not."""
    import shutil

    import granchain

    pkg = Path(granchain.__file__).resolve().parent
    copy = tmp_path / "granchain"
    shutil.copytree(pkg, copy, ignore=shutil.ignore_patterns("__pycache__"))
    base = wsp.hash_sources(copy)
    assert base == wsp.source_hash() == wsp.code_version("reference")["source"]
    (copy / "__pycache__").mkdir(exist_ok=True)
    (copy / "__pycache__" / "x.cpython-312.pyc").write_bytes(b"compiled")
    (copy / "scenes" / "default.toml").write_text("# another default\n")
    assert wsp.hash_sources(copy) == base
    mod = copy / "physics" / "models.py"
    mod.write_text(mod.read_text() + "\n# an edit\n")
    edited = wsp.hash_sources(copy)
    assert edited != base
    tpl = copy / "templates" / "chain.lmp.j2"
    tpl.write_text(tpl.read_text() + "\n")
    assert wsp.hash_sources(copy) not in (base, edited)
    shutil.rmtree(copy)
    shutil.copytree(pkg, copy, ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "physics" / "models.py").rename(copy / "physics" / "models2.py")
    assert wsp.hash_sources(copy) != base


def test_a_worker_on_other_source_is_refused(tmp_path):
    """A point sent by a campaign whose granchain differs from the worker's in its source only (the
    same version string): failed with the one message naming the fix, nothing computed."""
    from granchain.campaigns.execute import run_point

    code = dict(wsp.code_version("reference"), source="0" * 16)
    (tmp_path / "job").mkdir()
    out = run_point(
        {"job_dir": str(tmp_path / "job"), "backend": "reference", "code": code, "scene": {}, "source": None}
    )
    assert out["status"] == "failed"
    assert "install the same granchain on every worker" in out["message"]
    assert f"source {wsp.source_hash()}" in out["message"]
    assert "source 0000000000000000" in out["message"]
    assert not (tmp_path / "job" / "run").exists()


def test_stale_points_are_reported_and_run_again(tmp_path):
    """A point computed by another granchain version is not reused: the table says stale, the next
    run says so and computes it anew."""
    import shutil

    import signac

    from granchain.campaigns.run import run_campaign

    c = parse_campaign(
        campaign_text(
            '[vary]\n"loading.amplitude" = [10.0, 20.0]\n',
            campaign='backend = "reference"\nmethod = "verlet"\nerror_estimate = false',
        )
    )
    ws = tmp_path / "ws"
    run_campaign(c, ws, workers=1)
    project = signac.get_project(str(ws), search=False)
    for job in list(project):
        sp = job.statepoint()
        sp["code"] = {"granchain": "0.0.1"}
        old = project.open_job(sp)
        old.init()
        shutil.copytree(Path(job.path) / "run", Path(old.path) / "run")
        job.remove()
    import granchain

    df = granchain.load_campaign(ws)
    assert list(df["status"]) == ["stale", "stale"]
    assert df["message"][0] == "computed by other code: granchain 0.0.1"
    tables, report = run_campaign(c, ws, workers=1)
    assert (report.stale, report.ran, report.done) == (2, 2, 2)
    assert report.stale_codes == [{"granchain": "0.0.1"}]
    assert list(tables["table"]["status"]) == ["done", "done"]


SEARCH = """
[vary]
"loading.amplitude" = {amplitudes}
[search]
key = "loading.duration"
range = {range}
scale = "log"
tolerance = {tolerance}
predicate = {{ quantity = "pulses", contact = 20, op = ">", value = 1 }}
"""

SEARCH_SCENE = """
[chain]
beads = 40
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "step"
amplitude = 10.0
duration = 1e-5
[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
histories = [20]
"""


def test_a_search_whose_predicate_never_flips_says_so(tmp_path, capsys):
    from granchain.campaigns.run import run_campaign
    from granchain.cli import main

    path = tmp_path / "noflip.toml"
    path.write_text(
        campaign_text(
            SEARCH.format(amplitudes="[100.0]", range="[1e-6, 1e-5]", tolerance=0.01),
            scene=SEARCH_SCENE,
            campaign='backend = "reference"\nrtol = 1e-3\nerror_estimate = false',
        )
    )
    tables, report = run_campaign(path, tmp_path / "ws", workers=1)
    row = tables["search"].iloc[0]
    assert row["status"] == "no flip"
    assert row["runs"] == 2
    assert report.ran == 2
    message = (
        "pulses at contact 20 > 1 is false at both ends of loading.duration's range [1e-06, 1e-05] "
        "(pulses = 1 and 1; loading.amplitude = 100): it never flips in the range; widen [search] range"
    )
    assert row["message"] == message
    capsys.readouterr()
    assert main(["campaign", "run", str(path), "--out", str(tmp_path / "ws"), "-q"]) == 1  # cached: no cluster
    assert f"granchain: search: {message}" in capsys.readouterr().err


def test_search_predicate_contact_must_be_recorded(tmp_path):
    from granchain.campaigns.run import run_campaign

    c = parse_campaign(
        campaign_text(
            SEARCH.format(amplitudes="[100.0]", range="[1e-6, 1e-5]", tolerance=0.01).replace(
                "contact = 20", "contact = 7"
            ),
            scene=SEARCH_SCENE,
        )
    )
    with pytest.raises(
        CampaignError, match=r"predicate contact = 7 is not among the scene's \[outputs\] histories \[20\]"
    ):
        run_campaign(c, tmp_path / "ws", workers=1)


def test_cli_table_and_plot(tmp_path, capsys):
    """granchain campaign run / table / plot on a small grid made through the Python API from a dict."""
    import tomllib

    import granchain
    from granchain.cli import main

    data = tomllib.loads(
        campaign_text(
            '[vary]\n"loading.amplitude" = [10.0, 20.0]\n"loading.duration" = [1e-6, 2e-6]\n',
            campaign='backend = "reference"\nmethod = "verlet"',
        )
    )
    ws = tmp_path / "ws"
    df = granchain.campaign(data, ws, workers=2)
    assert len(df) == 4
    assert set(df["status"]) == {"done"}
    capsys.readouterr()
    assert main(["campaign", "table", str(ws), "--csv"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].startswith("loading.amplitude,loading.duration,status,pulses,regime,")
    assert len(out.splitlines()) == 5
    assert (
        main(
            [
                "campaign",
                "plot",
                str(ws),
                "--x",
                "loading.amplitude",
                "--y",
                "max_peak_force",
                "--hue",
                "loading.duration",
            ]
        )
        == 0
    )
    png = Path(capsys.readouterr().out.strip())
    assert png.name == "max_peak_force-vs-loading.amplitude-by-loading.duration.png"
    assert png.stat().st_size > 1000
    assert main(["campaign", "plot", str(ws), "--x", "loading.amplitude", "--y", "wave_sped"]) == 2
    assert "--y 'wave_sped' is not a column of the table" in capsys.readouterr().err
    assert main(["campaign", "table", str(tmp_path)]) == 2
    assert "is not a campaign workspace" in capsys.readouterr().err


def test_the_bundled_fig1_campaign_reads():
    from importlib import resources

    from granchain.campaigns.run import validate
    from granchain.campaigns.spec import load_campaign_file

    c = load_campaign_file(resources.files("granchain.campaigns") / "fig1-transition.toml")
    assert c.kind == "search"
    assert c.outer_keys == ("loading.amplitude",)
    validate(c)


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (
            '[vary]\n"loading.amplitude" = { log = [1.0, 10.0], num = 1000000000000 }\n',
            r"\[vary\] 'loading.amplitude' makes 1e\+12 values; a campaign has at most 100000 points",
        ),
        (
            '[vary]\n"loading.amplitude" = { linear = [1.0, 10.0], num = 1000 }\n'
            '"loading.duration" = { linear = [1e-6, 1e-5], num = 1000 }\n',
            r"has 1e\+06 points or more; a campaign has at most 100000",
        ),
        (
            '[zip]\n"loading.amplitude" = { linear = [1.0, 10.0], num = 200000 }\n',
            r"\[zip\] 'loading.amplitude' makes 200000 values; a campaign has at most 100000 points",
        ),
        ('[vary]\n"chain.beads" = [20, 1000000000]\n', r"'chain.beads' = 1000000000: a campaign point has at most"),
    ],
)
def test_a_grid_too_big_is_refused_from_its_lengths_before_any_value_is_made(body, message):
    """num = 1e12 is refused from the count (not after making a trillion values: a MemoryError after
    41 s before); a varied chain.beads of 1e9 before its point is planned (which did not end)."""
    with pytest.raises(CampaignError, match=message):
        parse_campaign(campaign_text(body))
