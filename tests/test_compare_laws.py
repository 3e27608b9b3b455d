"""granchain compare-laws: one scene under two contact laws, side by side."""

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from granchain.cli import main, resolve_scene
from granchain.exceptions import UsageError
from granchain.physics.laws import LAWS
from granchain.safe_files import MARKER
from granchain.scene import parse_scene
from granchain.workflows.law_comparison import (
    MissingCoefficientError,
    compare_laws,
    contact_and_sources,
    equivalent_contact,
    scene_with_law,
    write_law_comparison,
)

from .conftest import make_scene, make_scene_text


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


def _hertz_scene(material="stainless-steel-316", radius=4.76e-3, beads=12, loading=None):
    text = make_scene_text(beads=beads, law="hertz", loading=loading, end_time=5e-5, timestep=5e-8)
    text = text.replace('material = "brass"', f"material = {material!r}").replace(
        "radius = 4.76e-3", f"radius = {radius!r}"
    )
    return parse_scene(text, source="test.toml")


@pytest.mark.parametrize("law", ["thornton", "bilinear"])
def test_a_plastic_law_on_a_hertz_scene_takes_the_chain_materials_coefficient(law):
    """A Hertz scene of stainless steel (sigma_y = 290 MPa) under compare-laws gets the coefficients
    `granchain run` derives from the material, p_y = 1.61 sigma_y and k = 18.5 sigma_y R* (the paper's
    brass values, p_y = 3.25e9 Pa and k = 2.43e7 N/m, are 7x and 1.9x off), and says so."""
    sc = _hertz_scene()
    contact, sources = contact_and_sources(sc, law)
    twin = scene_with_law(sc, contact)
    # the scene `granchain run` reads with the law and no coefficient of its own
    text = make_scene_text(beads=12, law=law, contact_extra="unloading_coeff = 0.8\n" if law == "bilinear" else "")
    run_scene_ = parse_scene(text.replace('material = "brass"', 'material = "stainless-steel-316"'), source="t.toml")
    ys, r_star = 290e6, 4.76e-3 / 2
    if law == "thornton":
        assert math.isclose(sources["yield_pressure"][0], 1.61 * ys, rel_tol=1e-12)
        assert "1.61 sigma_y" in sources["yield_pressure"][1]
        assert math.isclose(float(twin.law.yield_overlap), float(run_scene_.law.yield_overlap), rel_tol=1e-12)
    else:
        assert math.isclose(sources["plastic_stiffness"][0], 18.5 * ys * r_star, rel_tol=1e-12)
        assert "18.5 sigma_y R*" in sources["plastic_stiffness"][1]
        assert math.isclose(float(twin.law.k), float(run_scene_.law.k), rel_tol=1e-12)
        assert math.isclose(float(twin.law.k), 18.5 * ys * r_star, rel_tol=1e-12)


def test_the_papers_brass_values_only_on_the_papers_brass_chain(tmp_path, capsys, monkeypatch):
    """Brass has no yield strength: its 4.76 mm chain takes the paper's k = 2.43e7 N/m (and p_y by equal
    slopes); a brass chain of other beads, or glass, is refused before any run, naming the coefficient."""
    import granchain.workflows.law_comparison as lc

    contact, sources = contact_and_sources(_hertz_scene("brass"), "bilinear")
    assert contact["plastic_stiffness"] == 2.43e7
    assert "paper" in sources["plastic_stiffness"][1]
    for material, radius in [("brass", 3e-3), ("soda-lime-glass", 4.76e-3)]:
        for law, key in [("thornton", "yield_pressure"), ("bilinear", "plastic_stiffness")]:
            with pytest.raises(MissingCoefficientError, match=f"needs {key}.*yield_strength"):
                contact_and_sources(_hertz_scene(material, radius), law)

    def no_run(*a, **k):
        raise AssertionError("ran")

    monkeypatch.setattr(lc, "run_scene", no_run)
    p = tmp_path / "glass.toml"
    p.write_text(_hertz_scene("soda-lime-glass").to_toml())
    assert main(["compare-laws", str(p), "--backend", "reference", "--out", str(tmp_path / "o")]) == 2
    assert "needs yield_pressure" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_compare_laws_under_a_step_load_writes_its_figure(tmp_path, capsys):
    """Under a step load no contact unloads, so no peak is complete and there is no decay curve: the
    figure (log axes) draws the positive not-complete peaks open and says so, and fits nothing (it
    raised in savefig on an empty log axis). 12 beads, reference backend."""
    step = 'kind = "step"\namplitude = 2000.0\nduration = 1e-3'
    p = tmp_path / "step.toml"
    p.write_text(
        _hertz_scene(loading=step).to_toml().replace('law = "hertz"', 'law = "bilinear"\nunloading_coeff = 0.8')
    )
    out = tmp_path / "o"
    assert main(["compare-laws", str(p), "--backend", "reference", "--error-estimate", "off", "--out", str(out)]) == 0
    table = json.loads((out / "laws.json").read_text())["laws"]
    for row in table:
        assert row["first_peak_force"] is None
        assert row["transition_contact"] is None
        assert row["contacts_not_complete"]
        assert all(f > 0 for f in row["peak_force_not_complete"])
        assert "peaks complete" in row["why_no_fit"]
    assert (out / "laws.png").stat().st_size > 0
    assert "not complete" in capsys.readouterr().out


def test_a_failed_figure_leaves_no_directory(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    sc = make_scene(beads=12, law="thornton", end_time=5e-5, timestep=5e-8)
    cmp = compare_laws(sc, ("thornton", "bilinear"), backend="reference", error_estimate=False)

    def fail(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(Figure, "savefig", fail)
    with pytest.raises(OSError, match="disk full"):
        write_law_comparison(cmp, tmp_path / "laws")
    assert list(tmp_path.iterdir()) == []


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(velocity=st.floats(1e-3, 3.0))
@example(velocity=0.05)
@example(velocity=3.0)
def test_the_decay_law_is_fitted_only_where_a_contact_yielded(velocity):
    """A 12-bead brass Thornton chain (p_y = 3.25e9 Pa: F_y = 251 N) kicked at `velocity`: its decay
    fit is refused, naming why, exactly when no contact's peak passed F_y (below about 1.3 m/s), and the
    Hertz law's always (it never yields); the fit was printed with uncertainties before."""
    loading = f'kind = "velocity"\nvelocity = {velocity!r}'
    sc = make_scene(beads=12, law="thornton", loading=loading, end_time=1e-4, timestep=2e-8)
    cmp = compare_laws(sc, ("thornton", "hertz"), backend="reference", error_estimate=False)
    thornton, hertz = cmp.runs
    f_y = float(thornton.result.scene.law.yield_force)
    yielded = float(np.max(thornton.result.solution.peak_force)) > f_y
    assert (thornton.fit is not None or "no contact yielded" not in thornton.why_no_fit) == yielded
    if not yielded:
        assert thornton.fit is None
        assert thornton.why_no_fit.startswith("no contact yielded: the plastic decay model does not apply")
        assert f"yield force {f_y:.4g} N" in thornton.why_no_fit
    assert hertz.fit is None
    assert hertz.why_no_fit == "no contact yielded: the hertz law is elastic, so the plastic decay model does not apply"
    row = cmp.table()[1]
    assert row["decay_per_contact"] is None
    assert row["decay_per_contact_stderr"] is None


def test_the_figure_keeps_its_axis_label_and_signs_its_fits_once(tmp_path, monkeypatch):
    """Three brass beads struck at 1 m/s: peak forces 107-172 N, less than a decade, whose log axis
    labelled its minor ticks "1.7 x 10^2", pushing "peak force (N)" off the figure; a growing fit's
    legend read "i^--0.0499"."""
    from matplotlib.figure import Figure

    from granchain.postprocess.response_regimes import DecayFit
    from granchain.workflows.law_comparison import fit_labels

    growing = DecayFit(transition_contact=4, decay_per_contact=-0.012, power=-0.0499, rms_log_residual=0.0)
    expo, inv = fit_labels("hertz", growing)
    assert "--" not in expo + inv
    assert inv == "hertz: i^+0.0499 from 4"
    assert expo == "hertz: exp(+0.012 i)"
    decaying = DecayFit(transition_contact=4, decay_per_contact=0.012, power=0.5, rms_log_residual=0.0)
    assert fit_labels("hertz", decaying) == ("hertz: exp(-0.012 i)", "hertz: i^-0.5 from 4")

    sc = parse_scene(
        make_scene_text(beads=3, loading='kind = "striker"\nvelocity = 1.0', end_time=1e-4), source="t.toml"
    )
    cmp = compare_laws(sc, ("thornton", "bilinear"), backend="reference", error_estimate=False)
    figures = []
    save = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: (figures.append(fig), save(fig, *a, **k))[1])
    write_law_comparison(cmp, tmp_path / "laws")
    fig = figures[0]
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    ax = fig.axes[0]
    label = ax.yaxis.label.get_window_extent(renderer)
    assert label.x0 >= 0.0, label
    for tick in ax.yaxis.get_ticklabels(minor=True) + ax.yaxis.get_ticklabels():
        assert "times" not in tick.get_text(), tick.get_text()
