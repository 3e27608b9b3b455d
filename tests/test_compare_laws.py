"""granchain compare-laws: one scene under two contact laws, side by side."""

import json
import math

import numpy as np
import pytest

from granchain.cli import main, resolve_scene
from granchain.exceptions import UsageError
from granchain.physics.laws import LAWS
from granchain.safe_files import MARKER
from granchain.workflows.law_comparison import compare_laws, equivalent_contact, scene_with_law, write_law_comparison

from .conftest import make_scene


@pytest.mark.parametrize("start", ["thornton", "bilinear"])
def test_equivalent_laws_have_the_same_plastic_slope(start):
    sc = make_scene(law=start)
    other = "bilinear" if start == "thornton" else "thornton"
    twin = scene_with_law(sc, equivalent_contact(sc, other))
    laws = {s.contact.law: s.law for s in (sc, twin)}
    assert math.isclose(float(laws["thornton"].plastic_slope), float(laws["bilinear"].k), rel_tol=1e-12)
    # and back again: the round trip gives the scene's own contact
    back = scene_with_law(twin, equivalent_contact(twin, start))
    if start == "thornton":
        assert math.isclose(back.contact.yield_pressure, sc.contact.yield_pressure, rel_tol=1e-12)
    else:
        assert math.isclose(back.contact.plastic_stiffness, sc.contact.plastic_stiffness, rel_tol=1e-12)


def test_compare_laws_on_the_reference_writes_one_table_and_one_figure(tmp_path):
    sc = make_scene(beads=30, law="thornton", end_time=2e-4, timestep=2e-8)
    cmp = compare_laws(sc, ("thornton", "bilinear"), backend="reference", error_estimate=False)
    assert [r.law for r in cmp.runs] == ["thornton", "bilinear"]
    for r in cmp.runs:
        assert r.result.scene.contact.law == r.law
        assert r.peak_force.size >= 6
        assert np.all(np.isfinite(r.peak_force))
        # the decay curve: no holes, from contact 1
        assert list(r.contacts) == list(range(1, r.contacts.size + 1))
    out = write_law_comparison(cmp, tmp_path / "laws")
    assert {p.name for p in out.iterdir()} == {"laws.csv", "laws.json", "laws.png", MARKER}  # granchain's own
    table = json.loads((out / "laws.json").read_text())["laws"]
    assert [t["law"] for t in table] == ["thornton", "bilinear"]
    header = (out / "laws.csv").read_text().splitlines()[0].split(",")
    assert header == ["contact", *[f"peak_force{s}_{law}" for law in ("thornton", "bilinear") for s in ("", "_error")]]


def test_bad_laws_fail_before_any_run(tmp_path, capsys):
    assert main(["compare-laws", "plastic-short-impulse", "--laws", "thornton,nope", "--out", str(tmp_path / "x")]) == 2
    assert "nope" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
    with pytest.raises(UsageError, match="two different"):
        compare_laws(resolve_scene("plastic-short-impulse"), ("bilinear", "bilinear"))


def test_every_law_can_be_set_up_from_every_scene():
    sc = resolve_scene("plastic-short-impulse")
    for law in LAWS:
        assert scene_with_law(sc, equivalent_contact(sc, law)).contact.law == law


@pytest.mark.parametrize("quiet", [True, False])
def test_compare_laws_quiet_prints_no_progress(tmp_path, capsys, monkeypatch, quiet):
    from granchain import progress

    monkeypatch.setattr(progress, "DELAY", 0.0)  # show progress even for a short run
    monkeypatch.delenv("GRANCHAIN_QUIET", raising=False)
    p = tmp_path / "s.toml"
    p.write_text(make_scene(beads=12, law="thornton", end_time=5e-5, timestep=5e-8).to_toml())
    args = ["compare-laws", str(p), "--backend", "reference", "--error-estimate", "off", "--out", str(tmp_path / "o")]
    assert main(args + (["--quiet"] if quiet else [])) == 0
    err = capsys.readouterr().err
    assert ("%" in err) is not quiet  # the progress line shows a percentage


@pytest.mark.parametrize(
    ("decay", "power", "transition", "noise"), [(0.3, 1.5, 15, 0.02), (0.15, 0.9, 25, 0.01), (0.5, 2.0, 10, 0.05)]
)
def test_decay_fit_uncertainties_cover_the_truth(decay, power, transition, noise):
    """On peak-force curves exponential then inverse with log-normal scatter (200 fixed draws), the
    fitted decay rate and exponent lie within 2 standard errors of the truth about 95% of the time
    (at least 85%: a standard error 2x too small would cover 68%), and the transition range holds
    the true transition at least 80% of the time."""
    from granchain.postprocess.response_regimes import fit_decay

    n = 60
    i = np.arange(1, n + 1, dtype=float)
    at = 1000.0 * math.exp(-decay * (transition - 1))  # continuous at the transition
    clean = np.where(i < transition, 1000.0 * np.exp(-decay * (i - 1)), at * (i / transition) ** -power)
    rng = np.random.default_rng(20261125)
    fits = [fit_decay(clean * np.exp(noise * rng.standard_normal(n))) for _ in range(200)]
    assert np.mean([abs(f.decay_per_contact - decay) <= 2 * f.decay_per_contact_stderr for f in fits]) >= 0.85
    assert np.mean([abs(f.power - power) <= 2 * f.power_stderr for f in fits]) >= 0.85
    assert np.mean([f.transition_range[0] <= transition <= f.transition_range[1] for f in fits]) >= 0.8
    assert all(f.transition_range[0] <= f.transition_contact <= f.transition_range[1] for f in fits)
