"""An elastic law's peaks beyond the force at which the beads yield are marked, not printed as sure:
F_y = pi^3 p_y^3 R*^2 / (6 E*^2) with p_y = 1.61 sigma_y (Johnson, Contact Mechanics, Sec. 6.2)."""

import json
import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from granchain.physics import materials as mat
from granchain.scene import parse_scene
from granchain.workflows.run import run_scene

from .conftest import make_scene_text


def johnson_yield_force(e_star: float, r_star: float, sigma_y: float) -> float:
    """Johnson's F_Y of a Hertz contact, from its own closed form (not granchain's Thornton law)."""
    p_y = 1.61 * sigma_y
    return math.pi**3 * p_y**3 * r_star**2 / (6.0 * e_star**2)


def ratio(note: str) -> float:
    """The largest F / F_y a note gives ("... is 48.6x F_y ...")."""
    return float(re.search(r" is ([0-9.e+-]+)x F_y", note).group(1))


def chain(material: str, law: str, velocity: float, striker: bool = False):
    kind = "striker" if striker else "velocity"
    text = make_scene_text(
        beads=12, law=law, loading=f'kind = "{kind}"\nvelocity = {velocity!r}', end_time=6e-5, timestep=2e-8
    )
    return parse_scene(text.replace('material = "brass"', f"material = {material!r}"), source="y.toml")


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(velocity=st.floats(1e-6, 100.0), striker=st.booleans())
@example(velocity=100.0, striker=True)
@example(velocity=1e-6, striker=False)
def test_a_hertz_chain_beyond_yield_is_marked_exactly_where_a_peak_passes_f_y(velocity, striker):
    """A 12-bead chain of annealed 316 stainless (sigma_y = 290 MPa: F_y = 0.265 N) under the Hertz law:
    the summary marks the contacts whose peak passed Johnson's F_y, and only those (at 100 m/s the
    peak pressure is 27 GPa, 58 times p_y); the run printed its peaks as sure before."""
    sc = chain("stainless-steel-316", "hertz", velocity, striker)
    result = run_scene(sc, backend="reference", method="verlet", error_estimate=False)
    s = result.summary()
    m = mat.MATERIALS["stainless-steel-316"]
    f_y = johnson_yield_force(mat.effective_modulus(m), mat.effective_radius(4.76e-3), m.yield_strength)
    peaks = np.asarray(result.solution.peak_force)
    over = np.flatnonzero(peaks > f_y) + 1
    notes = s.get("outside_domain", [])
    chain_notes = [n for n in notes if "contacts (" in n]
    assert bool(chain_notes) == bool(over.size), (peaks.max(), f_y, notes)
    if over.size:
        note = chain_notes[0]
        assert f"beyond first yield at {over.size} of 11 contacts" in note
        worst = int(np.argmax(peaks))  # one material: the largest F / F_y is the largest peak
        assert f" at contact {worst + 1}, is " in note
        assert ratio(note) == pytest.approx(peaks[worst] / f_y, rel=5e-3)
        assert f"F_y = {f_y:.3g} N" in note
        assert "sigma_y = 290 MPa, the library's for stainless-steel-316" in note
        # first yield is graded, not a verdict on the run's numbers
        assert "outside its domain" not in note
        assert "carry less" not in note
        assert "growing with F/F_y" in note
    striker_notes = [n for n in notes if "striker's contact" in n]
    assert bool(striker_notes) == bool(striker and result.solution.striker_peak_force > f_y)
    json.dumps(s["outside_domain"] if notes else [])  # summary.json can hold it


@pytest.mark.parametrize(("material", "law"), [("brass", "hertz"), ("soda-lime-glass", "hertz")])
def test_no_yield_strength_no_mark(material, law):
    """Brass (the paper's, no yield strength given) and glass (brittle) have no F_y: nothing is said."""
    result = run_scene(chain(material, law, 100.0), backend="reference", method="verlet", error_estimate=False)
    assert "outside_domain" not in result.summary()


def test_a_plastic_law_is_not_marked():
    """Thornton's law yields on its own: its peaks beyond F_y are inside its domain."""
    result = run_scene(chain("stainless-steel-316", "thornton", 10.0), backend="reference", method="verlet")
    assert float(np.max(result.solution.peak_force)) > 1.0
    assert "outside_domain" not in result.summary()


def test_granchain_run_prints_the_mark(tmp_path, capsys):
    from granchain.cli import main

    (tmp_path / "s.toml").write_text(chain("stainless-steel-316", "hertz", 100.0, striker=True).to_toml())
    args = ["run", str(tmp_path / "s.toml"), "--backend", "reference", "--method", "verlet", "--out"]
    assert main([*args, str(tmp_path / "r"), "--error-estimate", "off", "-q"]) == 0
    out = capsys.readouterr().out
    lines = [line for line in out.splitlines() if line.split()[:3] == ["beyond", "first", "yield"]]
    assert len(lines) == 2, out
    assert "hertz law beyond first yield at 11 of 11 contacts (1-11)" in lines[0]
    assert "p_y = 1.61 sigma_y" in lines[0]
    assert "striker's contact" in lines[1]
    assert "thornton" not in lines[1]  # what the law leaves out is said once


@pytest.mark.parametrize("f0", [0.1, 2.0])
def test_a_precompression_beyond_first_yield_is_said(f0):
    """On a precompressed chain the peaks are total forces and F0 alone may pass F_y (the bundled
    Daraio 2005 chain: F0 = 2 N is 30x F_y of its 316 stainless): the note gives F0 / F_y then, and
    only then (F_y = 0.265 N here)."""
    text = chain("stainless-steel-316", "hertz", 1.0).to_toml() + f"[precompression]\nforce = {f0!r}\n"
    sc = parse_scene(text, source="p.toml")
    result = run_scene(sc, backend="reference", method="verlet", error_estimate=False)
    m = mat.MATERIALS["stainless-steel-316"]
    f_y = johnson_yield_force(mat.effective_modulus(m), mat.effective_radius(4.76e-3), m.yield_strength)
    note = result.summary()["outside_domain"][0]
    assert "(total force, F0 included)" in note
    peaks = np.asarray(result.solution.peak_force)
    assert ratio(note) == pytest.approx(peaks.max() / f_y, rel=5e-3)
    assert ("alone is" in note) == (f0 > f_y), note
    if f0 > f_y:
        assert f"F0 = {f0:.3g} N alone is {f0 / f_y:.3g}x F_y" in note
