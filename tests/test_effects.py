"""Opt-in effects (far-end wall, dashpot): both backends agree, energy balances, and an undeclared
effect leaves no trace in the deck or in the solver. The second half: properties of every effect of
the registry (granchain.physics.effects), drawn over it."""

import dataclasses
import itertools
import tomllib
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.lammps.runner import run_lammps
from granchain.physics.effects import EFFECTS as REGISTRY
from granchain.physics.effects import active_effects, effect_fields, refusal
from granchain.physics.estimates import damping_rate, highest_frequency
from granchain.reference.solver import ChainProblem
from granchain.scene import SECTIONS, Effects, SceneError, scene_from_dict
from granchain.templates import DECK_SLOTS, AtomLayout, effect_blocks, render_deck
from granchain.workflows.run import run_reference

from .conftest import LAW_NAMES, make_scene, make_scene_text

SHORT = 'kind = "impulse"\nimpulse = 0.1\nduration = 1e-6'
EFFECTS = {
    "wall": '[boundary]\nfar_end = "wall"\n',
    "dashpot": "[damping]\ndashpot = 3.0\n",
    "wall+dashpot": '[boundary]\nfar_end = "wall"\n[damping]\ndashpot = 3.0\n',
    "precompression": "[precompression]\nforce = 50.0\n",
    "precompression+wall+dashpot": (
        '[precompression]\nforce = 50.0\n[boundary]\nfar_end = "wall"\n[damping]\ndashpot = 2.0\n'
    ),
}


def rel(a, b):
    return np.nanmax(np.abs(a - b)) / np.nanmax(np.abs(b))


def scene(law, effect, **kw):
    return make_scene(
        beads=30,
        law=law,
        loading=SHORT,
        outputs="histories = [1, 29]\nsnapshots = [2e-4]\n" + EFFECTS[effect],
        **kw,
    )


@pytest.mark.parametrize("effect", list(EFFECTS))
@pytest.mark.parametrize("law", LAW_NAMES)
def test_effect_lammps_equals_reference_verlet(law, effect):
    # step for step: the agreement is the arithmetic's, not the step's; 2e-8 s is well inside Verlet's bound
    sc = scene(law, effect, end_time=4e-4, timestep=2e-8)
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution
    print(
        f"{law} {effect}: peaks {rel(lam.peak_force, ref.peak_force):.1e}, velocities "
        f"{rel(lam.velocity, ref.velocity):.1e}, wall peak {lam.wall_peak_force}, dissipated {lam.dissipated[-1]:.4g} J"
    )
    assert rel(lam.peak_force, ref.peak_force) < 1e-9
    assert rel(lam.velocity, ref.velocity) < 1e-8
    assert rel(lam.snapshot_velocity, ref.snapshot_velocity) < 1e-8
    if "wall" in effect:
        assert lam.wall_peak_force == pytest.approx(ref.wall_peak_force, rel=1e-9)
        assert lam.wall_peak_force > 0
        assert ref.momentum < 0.1  # the wall took momentum
    if "dashpot" in effect:
        assert lam.dissipated[-1] == pytest.approx(ref.dissipated[-1], rel=1e-9)
    if "precompression" in effect:
        assert np.all(lam.peak_force >= 50.0 * (1 - 1e-12))  # every contact starts at F0
        assert rel(lam.displacement, ref.displacement) < 1e-9


@pytest.mark.parametrize("effect", list(EFFECTS))
@pytest.mark.parametrize("law", LAW_NAMES)
def test_effect_energy_balance_rk4(law, effect):
    # at 4e-8 s RK4's own balance error is about 5e-10 of the work (1.8e-11 at 1e-8 s): a missing work or
    # dissipation term (1e-3 and more) still fails the 1e-6 bound by orders of magnitude
    sc = scene(law, effect, end_time=4e-4, timestep=4e-8)
    sol = run_reference(sc, "rk4").solution
    err = np.max(np.abs(sol.energy_balance_error)) / sol.work[-1]
    assert err < 1e-6
    if "dashpot" in effect:
        assert sol.dissipated[-1] > 0


def test_undeclared_effects_leave_no_trace():
    plain = make_scene()
    deck = render_deck(plain).deck
    for word in ("dashpot", "comm_modify", "wall", "type 2", "edash"):
        assert word not in deck, word
    assert set(atom_types(render_deck(plain).data)) == {1}
    p = ChainProblem.from_scene(plain)
    assert p.wall_law is None
    assert p.damping == "none"
    sol = run_reference(plain, "rk4").solution
    assert sol.wall_peak_force is None
    assert sol.dissipated[-1] == 0.0
    walled_scene = scene("hertz", "wall", end_time=4e-4, timestep=1e-8)
    walled = render_deck(walled_scene)
    # the wall is one atom of a type of its own, the last; the beads keep theirs
    types = atom_types(walled.data)
    assert types[-1] == AtomLayout.of(walled_scene).types["wall"] != 1
    assert set(types[:-1]) == {1}
    assert "dashpot" not in walled.deck


def atom_types(data: str) -> list[int]:
    """The type of each atom of a LAMMPS data file (atom_style sphere: id type diameter density x y z), by ID."""
    lines = data.split("Atoms # sphere\n\n", 1)[1].split("\n\n", 1)[0].splitlines()  # (a Watch section may follow)
    rows = [line.split() for line in lines if line.strip()]
    return [int(r[1]) for r in sorted(rows, key=lambda r: int(r[0]))]


STRIKERS = {
    "bead-like striker": 'kind = "striker"\nvelocity = 20.0',
    "heavy striker": 'kind = "striker"\nvelocity = 20.0\nradius = 6e-3\nmass = 0.03',
}


@pytest.mark.parametrize("striker", list(STRIKERS))
@pytest.mark.parametrize("law", LAW_NAMES)
def test_striker_both_backends(law, striker):
    sc = make_scene(
        beads=30,
        law=law,
        loading=STRIKERS[striker],
        end_time=4e-4,
        timestep=1e-8,
        outputs="histories = [1, 29]\nsnapshots = [2e-4]\n",
    )
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution
    print(
        f"{law} {striker}: striker peak {lam.striker_peak_force:.6g} N, striker velocity after "
        f"{lam.striker_velocity:.4g} m/s; peaks {rel(lam.peak_force, ref.peak_force):.1e}"
    )
    assert rel(lam.peak_force, ref.peak_force) < 1e-9
    assert rel(lam.velocity, ref.velocity) < 1e-8
    assert rel(lam.history_force, ref.history_force) < 1e-8
    assert lam.striker_peak_force == pytest.approx(ref.striker_peak_force, rel=1e-9)
    assert lam.striker_velocity == pytest.approx(ref.striker_velocity, rel=1e-8, abs=1e-9)
    # the striker's momentum M V went into the chain + striker: conserved to round-off (free far end)
    assert lam.momentum == pytest.approx(sc.input_impulse, rel=1e-12)
    rk4 = run_reference(sc, "rk4").solution
    assert np.max(np.abs(rk4.energy_balance_error)) / rk4.work[-1] < 1e-6


def test_no_striker_no_trace():
    deck = render_deck(make_scene())
    assert "striker" not in deck.deck
    assert set(atom_types(deck.data)) == {1}
    assert ChainProblem.from_scene(make_scene()).striker_mass is None


@pytest.mark.parametrize("far_end", ["free", "wall"])
@pytest.mark.parametrize("law", LAW_NAMES)
def test_precompressed_chain_is_in_static_equilibrium(law, far_end):
    """Without a load nothing moves: the initial overlaps balance F0 in both backends."""
    sc = make_scene(
        beads=20,
        law=law,
        loading='kind = "velocity"\nvelocity = 1e-12',
        end_time=2e-5,
        timestep=1e-8,
        outputs=f'[precompression]\nforce = 80.0\n[boundary]\nfar_end = "{far_end}"\n',
    )
    for sol in (run_lammps(sc)[0].solution, run_reference(sc, "rk4").solution):
        assert np.max(np.abs(sol.velocity)) < 1e-9  # m/s: only round-off moves
        assert np.allclose(sol.peak_force, 80.0, rtol=1e-9)


def _per_bead_scene(kind, law="hertz"):
    base = make_scene(
        beads=30,
        law=law,
        loading=SHORT,
        end_time=4e-4,
        timestep=1e-8,
        outputs="histories = [1, 15]\nsnapshots = [2e-4]",
    ).source_text
    if kind == "taper":
        text = base.replace("radius = 4.76e-3", "radius = 4.76e-3\ntaper = 0.97")
    else:  # a small impurity at bead 15
        text = base.replace(
            "radius = 4.76e-3", "radius = [" + ", ".join("2.5e-3" if i == 14 else "4.76e-3" for i in range(30)) + "]"
        )
    from granchain.scene import parse_scene

    return parse_scene(text, source=f"{kind}.toml")


@pytest.mark.parametrize(("kind", "law"), [("taper", "hertz"), ("impurity", "hertz"), ("taper", "bilinear")])
def test_per_bead_radius_both_backends(kind, law):
    sc = _per_bead_scene(kind, law)
    assert sc.per_bead
    p = ChainProblem.from_scene(sc)
    assert np.ptp(p.mass) > 0
    assert np.ptp(np.asarray(p.law.k)) > 0
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution
    assert rel(lam.peak_force, ref.peak_force) < 1e-9
    assert rel(lam.velocity, ref.velocity) < 1e-8
    assert rel(lam.history_force, ref.history_force) < 1e-8
    assert lam.momentum == pytest.approx(0.1, rel=1e-12)
    rk4 = run_reference(sc, "rk4").solution
    assert np.max(np.abs(rk4.energy_balance_error)) / rk4.work[-1] < 1e-6
    if kind == "impurity":
        # the light impurity's contacts are softer and its neighbours see a lower peak than the plain chain's
        plain = run_reference(make_scene(beads=30, loading=SHORT, end_time=4e-4, timestep=1e-8), "rk4").solution
        assert rk4.peak_force[14] < plain.peak_force[14]


def test_per_bead_material_list_and_uniform_lists():
    from granchain.scene import parse_scene

    base = make_scene(beads=4).source_text
    sc = parse_scene(base.replace('material = "brass"', 'material = ["brass", "brass", "brass", "brass"]'))
    assert not sc.per_bead  # a uniform list is the plain chain
    deck = render_deck(make_scene())
    assert "taper" not in deck.deck
    assert set(atom_types(deck.data)) == {1}


# ---- the effect registry (granchain.physics.effects): properties every registered
# effect has, drawn over the registry (a new effect is tested by registering it)


TEMPLATES = Path(str(resources.files("granchain") / "templates"))
SECTIONED = [e for e in REGISTRY.values() if e.section]
PROPERTY = settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))


def base_data(beads=12):
    """A plain chain with a velocity load, as scene tables (effects are merged into it)."""
    text = make_scene_text(beads=beads, loading='kind = "velocity"\nvelocity = 1.0', end_time=1e-4, timestep=1e-8)
    return tomllib.loads(text)


def with_effects(effects, beads=12):
    data = base_data(beads)
    for e in effects:
        for table, keys in e.declaration.items():
            data[table] = {**data.get(table, {}), **keys}
    return data


def test_the_registry_is_the_only_list():
    assert len({e.name for e in REGISTRY.values()}) == len(REGISTRY)
    assert all(e.label for e in REGISTRY.values())
    assert [e.section for e in SECTIONED] == [s for s in SECTIONS if s in {e.section for e in SECTIONED}]
    assert set(SECTIONS) >= {e.section for e in SECTIONED}
    assert [f.name for f in dataclasses.fields(Effects)] == list(effect_fields())
    assert Effects() == Effects(**effect_fields())  # every field at its absent value by default
    for e in REGISTRY.values():
        assert e.declaration, e.name
        for slot, template in e.deck_blocks.items():
            assert slot in DECK_SLOTS, (e.name, slot, template)
            assert (TEMPLATES / template).is_file(), (e.name, slot, template)


@PROPERTY
@given(data=st.data())
def test_every_declared_key_is_validated_with_a_message_naming_it(data):
    e = data.draw(st.sampled_from(SECTIONED), label="effect")
    # (an example holds every key, or one of alternatives: [damping]'s keys are one part each)
    assert set(e.example) <= set(e.scene_keys)
    assert e.example
    assert set(e.invalid) <= set(e.scene_keys)
    key = data.draw(st.sampled_from(sorted(e.invalid)), label="key")
    bad = data.draw(st.sampled_from(e.invalid[key]), label="value")
    scene_data = base_data()
    scene_data[e.section] = {**e.example, key: bad}
    with pytest.raises(SceneError, match=rf"\[{e.section}\] {key} = "):
        scene_from_dict(scene_data, source="fx.toml")
    # an unknown key in its section is named too
    unknown = data.draw(st.from_regex(r"[a-z]{3,10}", fullmatch=True).filter(lambda k: k not in e.scene_keys))
    scene_data[e.section] = {**e.example, unknown: 1.0}
    with pytest.raises(SceneError, match=rf"\[{e.section}\] has unknown key '{unknown}'"):
        scene_from_dict(scene_data, source="fx.toml")
    # a missing key is named; an optional one may be left out
    assert set(e.optional_keys) < set(e.scene_keys)
    key = data.draw(st.sampled_from(sorted(e.example)), label="missing key")
    scene_data[e.section] = {k: v for k, v in e.example.items() if k != key}
    if key in e.optional_keys:
        scene_from_dict(scene_data, source="fx.toml")
        return
    with pytest.raises(SceneError, match=rf"\[{e.section}\] is missing '{key}'"):
        scene_from_dict(scene_data, source="fx.toml")


def test_compatibility_is_symmetric_and_worded_once():
    for a, b in itertools.permutations(REGISTRY.values(), 2):
        assert (b.name in a.incompatible) == (a.name in b.incompatible), (a.name, b.name)
        if b.name in a.incompatible:
            worded = [x for x, y in ((a, b), (b, a)) if x.incompatible[y.name] is not None]
            assert len(worded) == 1, (a.name, b.name)
        assert set(a.incompatible) <= set(REGISTRY), a.name


@PROPERTY
@given(chosen=st.sets(st.sampled_from(sorted(REGISTRY))))
def test_any_combination_is_refused_or_gives_exactly_its_effects(chosen):
    effects = [REGISTRY[n] for n in REGISTRY if n in chosen]  # registry order
    clash = [(a, b) for a, b in itertools.combinations(effects, 2) if b.name in a.incompatible]
    if clash:
        with pytest.raises(SceneError, match="is not available yet") as err:
            scene_from_dict(with_effects(effects), source="fx.toml")
        assert any(a.label in str(err.value) and b.label in str(err.value) for a, b in clash)
        assert refusal(effects) is not None
        return
    assert refusal(effects) is None
    sc = scene_from_dict(with_effects(effects), source="fx.toml")
    # ... and the effects they need (Effect.requires: gravity's wall), which their declarations declare
    needed = chosen | {r for e in effects for r in e.requires}
    effects = [REGISTRY[n] for n in REGISTRY if n in needed]
    assert [e.name for e in active_effects(sc)] == [e.name for e in effects]
    again = scene_from_dict(tomllib.loads(sc.to_toml()), source="again.toml")
    assert again.effects == sc.effects
    assert [e.name for e in active_effects(again)] == [e.name for e in effects]
    # every active effect's deck blocks are in the deck, no inactive effect's
    deck = render_deck(sc).deck
    blocks = effect_blocks(sc)
    for e in REGISTRY.values():
        for slot, template in e.deck_blocks.items():
            assert (template in blocks[slot]) == (e in effects), (e.name, slot)
            if e in effects:
                assert block_heading(template) in deck, (e.name, template)
    omega, _ = highest_frequency(sc)
    assert np.isfinite(omega)
    assert omega > 0


def block_heading(template: str) -> str:
    """The fixed start of a block's first '# ----' comment line (up to its first template value)."""
    line = next(x for x in (TEMPLATES / template).read_text().splitlines() if x.startswith("# ----"))
    return line.split("{{")[0].split("{%")[0]


@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_every_effect_changes_the_planner_bounds_or_says_why_not(name):
    """Alone, an effect the planner must see (masses, stiffness, force level, damping) moves the
    highest frequency or the damping rate away from the plain chain's."""
    e = REGISTRY[name]
    plain = scene_from_dict(base_data(), source="plain.toml")
    sc = scene_from_dict(with_effects([e]), source="fx.toml")
    assert (highest_frequency(sc), damping_rate(sc)) != (highest_frequency(plain), damping_rate(plain)), name


@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_every_effect_closes_the_energy_balance_on_both_backends(name):
    """Kinetic + stored + dissipated = the energy put in (initial energy, the load's and the
    effects' work) on the reference (RK4, to 1e-6) and LAMMPS (Verlet, to its own step error),
    and both backends book the same work and dissipation."""
    e = REGISTRY[name]
    sc = scene_from_dict(with_effects([e], beads=16), source="fx.toml")
    sc = dataclasses.replace(sc, run=dataclasses.replace(sc.run, end_time=6e-5))
    rk4 = run_reference(sc, "rk4").solution
    scale = np.max(np.abs(rk4.work))
    assert np.max(np.abs(rk4.energy_balance_error)) / scale < 1e-6, name
    verlet = run_reference(sc, "verlet").solution
    lam = run_lammps(sc)[0].solution
    for sol in (verlet, lam):
        assert np.max(np.abs(sol.energy_balance_error)) / scale < 1e-4, name
    assert lam.work[-1] == pytest.approx(verlet.work[-1], rel=1e-9), name
    assert lam.dissipated[-1] == pytest.approx(verlet.dissipated[-1], rel=1e-9, abs=1e-12 * scale), name
    assert rel(lam.peak_force, verlet.peak_force) < 1e-9, name


def test_effects_hold_every_registered_field(monkeypatch):
    """Scene.effects has an attribute for each registered effect's field, at its absent value; a
    registered field without one is refused when granchain.scene is imported, naming the field."""
    import granchain.scene.model as model

    assert {f.name: f.default for f in dataclasses.fields(Effects)} == effect_fields()
    model._check_effects_match_the_registry()
    monkeypatch.setattr(model, "effect_fields", lambda: {**effect_fields(), "new_field": 0.0})
    with pytest.raises(RuntimeError, match="new_field"):
        model._check_effects_match_the_registry()
