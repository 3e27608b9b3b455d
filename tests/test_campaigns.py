"""Campaigns (issue 16): campaign files, the safe expression language, the signac workspace, Dask
execution (local cluster, an external scheduler), resume after kill -9, the table, the search kind."""

from __future__ import annotations

import math
import textwrap

import pytest

from granchain.campaigns import expr
from granchain.campaigns.spec import CampaignError, parse_campaign

SMALL_SCENE = """
[chain]
beads = 20
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "step"
amplitude = 10.0
duration = 1e-6
[run]
end_time = 1e-4
timestep = 5e-8
[outputs]
peak_force = true
histories = [5]
"""


def campaign_text(
    body: str, scene: str = SMALL_SCENE, campaign: str = 'backend = "reference"\nmethod = "verlet"'
) -> str:
    return f"[campaign]\n{campaign}\n\n{textwrap.dedent(body)}\n[scene]\n" + scene.replace("\n[", "\n[scene.")


# ------------------------------------------------------------------------------- expressions


@pytest.mark.parametrize(
    "text, values, expected",
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
    "text, fragment",
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
    assert p.params["loading.amplitude"] == 100.0 and p.params["chain.beads"] == 24
    assert p.scene.loading.duration == pytest.approx(2e-5 / 100.0, rel=1e-15)
    assert p.scene.chain.beads == 24 and p.scene.run.end_time == 1.2e-4
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


@pytest.mark.parametrize("body, message", BAD_CAMPAIGNS)
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
    assert c.kind == "search" and c.search.scale == "log" and c.search.predicate.text == "pulses at contact 5 > 1"
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
    assert vals[0] == 100.0 and vals[-1] == 1e6 and vals[2] == 1000.0
    assert all(math.isclose(b / a, math.sqrt(10), rel_tol=1e-11) for a, b in zip(vals, vals[1:], strict=False))
