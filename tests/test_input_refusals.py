"""Inputs a user can get wrong are refused before any run starts, in one line naming the field and the
fix: beads = "auto" with a wall, a precompression the contacts cannot carry, a precompression that
compresses no contact, a given time step longer than the planned run, an empty --out."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st

from granchain.cli import main
from granchain.invariants import contact_overlap_bounds
from granchain.problem import precompressed_displacements
from granchain.scene import SceneError, load_scene, parse_scene, scene_from_dict, scene_to_dict

from .scenegen import scene_texts

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def without_precompression(text: str) -> str:
    """scene_texts' text with its [precompression] section (always its last) left out."""
    return text.split("[precompression]")[0]


def with_beads(text: str, beads: str) -> str:
    return re.sub(r"(?m)^beads = .*$", f"beads = {beads}", text, count=1)


# ------------------------------------------------------------------- beads = "auto" with a wall


@SETTINGS
@given(text=scene_texts(max_beads=20, wall=True))
def test_auto_beads_with_a_wall_is_refused_naming_both_keys(text):
    """The planner makes an "auto" chain long enough that its far end's reflection never reaches the
    measured contacts: a wall there contradicts it, whatever the rest of the scene."""
    assume("taper" not in text and "material = [" not in text)  # a per-bead chain needs its length
    text = re.sub(r"(?m)^histories = .*$", "", text)  # histories name contacts of the given length
    parse_scene(text)  # the scene with its number of beads is valid
    with pytest.raises(SceneError) as e:
        parse_scene(with_beads(text, '"auto"'), source="s.toml")
    msg = str(e.value)
    assert "\n" not in msg
    assert '[chain] beads = "auto"' in msg
    assert '[boundary] far_end = "wall"' in msg
    assert 'far_end = "free"' in msg


def test_auto_beads_on_the_bundled_wall_scene_and_in_a_campaign(tmp_path):
    from granchain.campaigns.run import run_campaign
    from granchain.campaigns.spec import CampaignError, parse_campaign

    d = scene_to_dict(load_scene("effect-wall"))
    d["chain"]["beads"] = "auto"
    with pytest.raises(SceneError, match=r'beads = "auto" with \[boundary\] far_end = "wall"'):
        scene_from_dict(d)
    text = '[campaign]\nbase = "effect-wall"\nbackend = "reference"\n[vary]\n"chain.beads" = ["auto"]\n'
    with pytest.raises(CampaignError, match=r'point 1 .*\[chain\] beads = "auto" with \[boundary\] far_end') as e:
        run_campaign(parse_campaign(text, base_dir=tmp_path), tmp_path / "ws", workers=1)
    assert "\n" not in str(e.value)
    assert not (tmp_path / "ws").exists()


def test_auto_beads_with_a_wall_on_the_command_line(tmp_path, capsys):
    d = scene_to_dict(load_scene("effect-wall"))
    f = tmp_path / "w.toml"
    f.write_text(load_scene("effect-wall").to_toml().replace(f"beads = {d['chain']['beads']}", 'beads = "auto"'))
    assert main(["plan", str(f)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("granchain: error:")
    assert "\n" not in err
    assert "[chain] beads" in err


# ------------------------------------------------------- a precompression beyond the run watch's bound


def static_overlap_ratio(scene) -> float:
    """The largest static overlap F0 gives a contact it compresses (problem.precompressed_displacements:
    the solvers' own initial state) over the run watch's overlap bound of that contact
    (invariants.contact_overlap_bounds: the run watch's own bound; a striker's contact carries no F0)."""
    _, alpha0 = precompressed_displacements(scene)
    bounds = contact_overlap_bounds(scene)
    if scene.loading.kind == "striker":
        bounds = bounds[1:]
    return float(np.max(np.asarray(alpha0) / bounds))


@SETTINGS
@given(
    text=scene_texts(max_beads=24),
    log_f0=st.floats(0.0, 8.0),
)
def test_a_precompression_is_accepted_exactly_when_its_static_overlaps_stay_within_the_run_watch(text, log_f0):
    """For any scene: F0 is refused at reading exactly when the static overlap it gives some contact it
    compresses exceeds the run watch's bound there; the refusal names [precompression] force and
    quotes a largest F0 that is accepted and within 0.1% of the largest there is."""
    base = parse_scene(without_precompression(text) + "[precompression]\nforce = 1e-6\n")
    f0 = 10.0**log_f0
    ratio = static_overlap_ratio(replace(base, effects=replace(base.effects, precompression=f0)))
    if abs(ratio - 1.0) < 1e-9:
        return  # on the bound itself, to round-off: either answer
    scene_text = without_precompression(text) + f"[precompression]\nforce = {f0!r}\n"
    event("accepted" if ratio < 1.0 else "refused")
    if ratio < 1.0:
        parse_scene(scene_text)
        return
    with pytest.raises(SceneError) as e:
        parse_scene(scene_text, source="s.toml")
    msg = str(e.value)
    assert "\n" not in msg
    assert "[precompression] force" in msg
    quoted = float(re.search(r"a force of at most (\S+) N", msg).group(1))
    parse_scene(without_precompression(text) + f"[precompression]\nforce = {quoted!r}\n")  # accepted
    above = quoted * 1.001
    with pytest.raises(SceneError, match=r"\[precompression\] force"):
        parse_scene(without_precompression(text) + f"[precompression]\nforce = {above!r}\n")


def test_the_testers_thornton_scene_is_refused_at_reading():
    text = (
        '[chain]\nbeads = 20\nradius = 2.38e-3\nmaterial = "stainless-steel-316"\n'
        '[contact]\nlaw = "thornton"\nyield_pressure = 3e8\n[loading]\nkind = "striker"\nvelocity = 0.5\n'
        '[boundary]\nfar_end = "wall"\n[run]\nend_time = "auto"\ntimestep = "auto"\n'
    )
    parse_scene(text + "[precompression]\nforce = 10\n")
    for f0 in ("1e4", "1e6"):
        with pytest.raises(SceneError, match=r"\[precompression\] force = .* static overlap .* at most"):
            parse_scene(text + f"[precompression]\nforce = {f0}\n")


# ------------------------------------------------------ a precompression that compresses no contact


@pytest.mark.parametrize("law", ["hertz", "thornton", "bilinear"])
def test_precompression_of_one_free_bead_is_refused_and_on_a_wall_accepted(law):
    contact = {"hertz": "", "thornton": "yield_pressure = 3e8\n", "bilinear": "unloading_coeff = 0.8\n"}[law]
    text = (
        '[chain]\nbeads = 1\nradius = 2.38e-3\nmaterial = "stainless-steel-316"\n'
        f'[contact]\nlaw = "{law}"\n{contact}[loading]\nkind = "striker"\nvelocity = 0.5\n'
        '[run]\nend_time = "auto"\ntimestep = "auto"\n[precompression]\nforce = 10\n'
    )
    with pytest.raises(SceneError, match=r"\[precompression\] force = 10 N on \[chain\] beads = 1 .*no contact"):
        parse_scene(text)
    scene = parse_scene(text + '[boundary]\nfar_end = "wall"\n')  # the wall's contact carries F0
    assert float(precompressed_displacements(scene)[1][-1]) > 0.0


# ------------------------------------------------------- a given time step longer than the planned run


def test_a_given_step_longer_than_the_planned_end_is_refused_quoting_it(tmp_path, capsys):
    text = (
        '[chain]\nbeads = 20\nradius = 2.38e-3\nmaterial = "stainless-steel-316"\n[contact]\nlaw = "hertz"\n'
        '[loading]\nkind = "velocity"\nvelocity = 0.5\n[run]\nend_time = "auto"\ntimestep = 1e-3\n'
    )
    f = tmp_path / "t.toml"
    f.write_text(text)
    for cmd in ("plan", "run"):
        assert main([cmd, str(f), "--out", str(tmp_path / "r")] if cmd == "run" else [cmd, str(f)]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err
        assert "[run] timestep = 0.001 s" in err
    assert not (tmp_path / "r").exists()


# ------------------------------------------------------------------------------------ --out ""


@pytest.mark.parametrize(
    "argv",
    [["run", "--out", ""], ["compare", "--out", ""], ["accuracy", "--out", ""], ["compare-laws", "--out", ""]],
)
def test_an_empty_out_is_refused_naming_it(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("granchain: error: --out")
    assert "\n" not in err
    assert not any(tmp_path.iterdir())  # nothing written, not even runs/
