"""A per-bead [chain] material list: per bead, what `material` takes, a built-in name or an inline
table of values read as a [chain.material] table is; any other entry is refused naming its bead;
the writer round-trips it; both backends run it with each contact's law from the pair's values."""

import datetime
import math
import tomllib
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.physics import materials as mat
from granchain.scene import SceneError, parse_scene, scene_from_dict
from granchain.scene.writer import scene_to_dict

from .conftest import make_scene_text

STEEL = "stainless-steel-316"
RUBBER = {"density": 1100.0, "youngs_modulus": 5e6, "poisson_ratio": 0.49}


def chain_scene(
    materials: list, law: str = "hertz", contact: str = "", beads: int | None = None, end_time: float = 6e-5
) -> dict:
    """A scene dict of len(materials) beads with this [chain] material list."""
    text = make_scene_text(
        beads=beads or len(materials),
        law=law,
        contact_extra=contact,
        loading='kind = "velocity"\nvelocity = 1.0',
        end_time=end_time,
        timestep=1e-8,
    )
    data = tomllib.loads(text)
    data["chain"]["material"] = materials
    return data


def test_the_explorers_rubber_bead_is_read_as_a_chain_material_table():
    sc = scene_from_dict(chain_scene([STEEL, RUBBER] + [STEEL] * 8), source="x.toml")
    assert sc.chain.materials[1] == mat.Material(**RUBBER)
    assert sc.bead_materials[1] == mat.Material(**RUBBER)
    assert sc.bead_materials[0] == mat.MATERIALS[STEEL]


# ---- any entry but a built-in name or a valid table: one SceneError naming the bead's entry

#: what TOML can hold that is no material: every type but a table, and strings that name none
not_a_material = st.one_of(
    st.integers(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.text(max_size=20).filter(lambda s: s not in mat.MATERIALS),
    st.datetimes(),
    st.dates(),
    st.times(),
    st.recursive(st.lists(st.integers() | st.text(max_size=3), max_size=3), lambda c: st.lists(c, max_size=3)),
)


@st.composite
def bad_tables(draw):
    """A table that is not a valid material: a valid one with a key removed, an unknown key added,
    or a value replaced by garbage or by a value outside any real solid's range."""
    table = {**RUBBER, "yield_strength": 2e5}
    how = draw(st.sampled_from(["drop", "add", "garbage", "implausible"]))
    key = draw(st.sampled_from(sorted(table)))
    if how == "drop":
        del table[key if key != "yield_strength" else "density"]  # (yield_strength is optional)
    elif how == "add":
        table[draw(st.text(min_size=1, max_size=8).filter(lambda k: k not in table))] = 1.0
    elif how == "implausible":
        table[key] = {"density": 1.1, "youngs_modulus": 5.0, "poisson_ratio": 0.7, "yield_strength": 1e12}[key]
    else:
        table[key] = draw(not_a_material.filter(lambda v: isinstance(v, bool) or not isinstance(v, (int, float))))
    return table


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    beads=st.integers(2, 12),
    data=st.data(),
    entry=st.one_of(not_a_material, bad_tables()),
    law=st.sampled_from(["hertz", "bilinear", "thornton"]),
)
def test_an_entry_that_is_no_material_is_refused_naming_its_bead(beads, data, entry, law):
    """Never another exception (a table or list entry raised TypeError: unhashable): a SceneError
    naming material[i], i the bead's number from 1, and what an entry may be."""
    i = data.draw(st.integers(1, beads), label="bead")
    materials = [STEEL] * beads
    materials[i - 1] = entry
    contact = "unloading_coeff = 0.8\n" if law == "bilinear" else ""
    with pytest.raises(SceneError) as err:
        scene_from_dict(chain_scene(materials, law, contact), source="x.toml")
    msg = str(err.value)
    assert msg.startswith("x.toml: "), msg
    assert f"material[{i}]" in msg, msg
    if not isinstance(entry, dict):
        assert f"bead {i}'s material: " in msg, msg
        assert "inline table" in msg, msg
        assert STEEL in msg, msg


def test_a_list_of_the_wrong_length_is_refused_whatever_it_holds():
    with pytest.raises(SceneError, match=r"\[chain\] material = .* a list of 4 materials, one per bead"):
        scene_from_dict(chain_scene([STEEL, RUBBER, [1]], beads=4), source="x.toml")


def test_a_table_entry_keeps_the_plausibility_checks():
    """The unit slips a [chain.material] table is refused for, with the same fix."""
    with pytest.raises(SceneError, match=r"\[chain.material\[2\]\] density = 1.1 kg/m\^3 .* in g/cm\^3\? write 1100"):
        scene_from_dict(chain_scene([STEEL, {**RUBBER, "density": 1.1}, STEEL]), source="x.toml")
    metal_in_mpa = {"density": 8000.0, "youngs_modulus": 2e5, "poisson_ratio": 0.3, "yield_strength": 2.9e8}
    with pytest.raises(SceneError, match=r"\[chain.material\[3\]\] yield_strength .* youngs_modulus in MPa\?"):
        scene_from_dict(chain_scene([STEEL, STEEL, metal_in_mpa]), source="x.toml")


# ---- a plastic law on a list: the message's fix works


def test_a_built_in_without_yield_strength_in_a_bilinear_list_is_told_a_fix_that_works():
    materials = [STEEL, "brass", STEEL, {**RUBBER}]
    contact = "unloading_coeff = 0.8\n"
    with pytest.raises(SceneError) as err:
        scene_from_dict(chain_scene(materials, "bilinear", contact), source="x.toml")
    msg = str(err.value)
    assert "'brass'" in msg, msg
    assert "inline table of bead 4" in msg, msg
    assert "[chain.material] table" not in msg, msg  # cannot go with a list
    # the fix as the message gives it: brass's values as an inline table with a yield strength
    brass = tomllib.loads("x = " + msg.split("(e.g. ")[1].split(" for 'brass')")[0].replace("...", "2e8"))["x"]
    assert mat.Material(**brass) == replace(mat.MATERIALS["brass"], yield_strength=2e8)
    materials[1] = brass
    materials[3] = {**RUBBER, "yield_strength": 3e5}
    sc = scene_from_dict(chain_scene(materials, "bilinear", contact), source="x.toml")
    # each contact's k = 18.5 sigma_y R* from the softer of its two beads: the custom values
    r_star = mat.effective_radius(4.76e-3)
    assert [float(law.k) for law in sc.contact_laws] == [
        pytest.approx(mat.PLASTIC_STIFFNESS_FACTOR * ys * r_star, rel=1e-15) for ys in (2e8, 2e8, 3e5)
    ]


# ---- the writer round-trips lists of names and inline tables


@st.composite
def custom_materials(draw, yielding: bool):
    e = 10 ** draw(st.floats(math.log10(mat.YOUNGS_MODULUS_RANGE.low), math.log10(2e11)))
    ys = None
    if (yielding or draw(st.booleans())) and e >= 1e6:  # a yield strain sigma_y / E of at most 0.1
        ys = draw(st.floats(mat.YIELD_STRENGTH_RANGE.low, min(mat.YIELD_STRENGTH_RANGE.high, 0.1 * e)))
    return mat.Material(
        density=draw(st.floats(mat.DENSITY_RANGE.low, mat.DENSITY_RANGE.high)),
        youngs_modulus=e,
        poisson_ratio=draw(st.floats(-0.5, 0.49)),
        yield_strength=ys,
    )


def _table(m: mat.Material) -> dict:
    return {k: v for k, v in vars(m).items() if v is not None}


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), law=st.sampled_from(["hertz", "bilinear", "thornton"]), beads=st.integers(1, 12))
def test_lists_of_names_and_inline_tables_round_trip(data, law, beads):
    plastic = law != "hertz"
    names = sorted(n for n, m in mat.MATERIALS.items() if m.yield_strength is not None or not plastic)
    custom = custom_materials(plastic).filter(lambda m: m.yield_strength is not None or not plastic)
    entry = st.one_of(st.sampled_from(names), custom.map(_table))
    materials = data.draw(st.lists(entry, min_size=beads, max_size=beads), label="materials")
    contact = "unloading_coeff = 0.8\n" if law == "bilinear" else ""
    d = chain_scene(materials, law, contact)
    d["loading"] = {"kind": "striker", "velocity": 1.0}  # one bead needs something to touch
    sc = scene_from_dict(d, source="x.toml")
    back = parse_scene(sc.to_toml(), source="x.toml")
    assert replace(back, source_text=None) == sc
    assert scene_from_dict(scene_to_dict(sc), source="x.toml") == sc
    assert back.bead_materials == [mat.Material(**m) if isinstance(m, dict) else mat.MATERIALS[m] for m in materials]


@pytest.mark.parametrize("law", ["hertz", "bilinear", "thornton"])
@pytest.mark.parametrize("as_list", [True, False])
def test_one_custom_table_with_a_yield_strength_round_trips_under_every_law(law, as_list):
    """A list of one table is the plain chain of that table; its yield strength, from which the
    bilinear k is derived, is kept (it is the beyond-yield check's and compare-laws' sigma_y)."""
    steel = {"density": 8000.0, "youngs_modulus": 2e11, "poisson_ratio": 0.3, "yield_strength": 3e8}
    d = chain_scene([steel] * 3, law, "unloading_coeff = 0.8\n" if law == "bilinear" else "")
    if not as_list:
        d["chain"]["material"] = steel
    sc = scene_from_dict(d, source="x.toml")
    assert sc.chain.materials is None
    assert sc.chain.material.yield_strength == 3e8
    assert replace(parse_scene(sc.to_toml(), source="x.toml"), source_text=None) == sc


def test_a_striker_tables_yield_strength_round_trips():
    """A plastic law's striker contact reads the striker's yield strength (the softer body's)."""
    d = chain_scene([STEEL, "chrome-steel-52100"], "thornton")
    d["loading"] = {"kind": "striker", "velocity": 1.0, "material": {**RUBBER, "yield_strength": 3e5}}
    sc = scene_from_dict(d, source="x.toml")
    assert scene_from_dict(scene_to_dict(sc), source="x.toml") == sc


def test_a_list_with_toml_datetimes_is_refused_from_a_file():
    text = make_scene_text(beads=3).replace('material = "brass"', "material = [1979-05-27, 'brass', 'brass']")
    with pytest.raises(SceneError, match=r"\[chain\] material\[1\] = datetime.date\(1979, 5, 27\) is invalid"):
        parse_scene(text, source="x.toml")
    assert isinstance(tomllib.loads(text)["chain"]["material"][0], datetime.date)


# ---- a real run on both backends


def test_a_steel_chain_with_a_custom_soft_bead_runs_the_same_on_both_backends():
    """10 beads, 316 stainless with bead 5 of a nylon-like custom table, Thornton's law with p_y from
    the softer bead of each contact: each contact's law is the pair's (Johnson's E*, the custom
    sigma_y), and LAMMPS and the reference's Verlet agree step for step."""
    from granchain.lammps.runner import run_lammps
    from granchain.physics.laws.thornton import yield_overlap
    from granchain.workflows.run import run_reference

    soft = {"density": 1150.0, "youngs_modulus": 3e9, "poisson_ratio": 0.4, "yield_strength": 7e7}
    materials = [STEEL] * 4 + [soft] + [STEEL] * 5
    sc = scene_from_dict(chain_scene(materials, "thornton", end_time=2e-4), source="x.toml")
    steel, nylon = mat.MATERIALS[STEEL], mat.Material(**soft)
    r_star = mat.effective_radius(4.76e-3)
    for i, law in enumerate(sc.contact_laws, 1):
        pair = (steel, nylon) if i in (4, 5) else (steel, steel)
        e_star = mat.pair_effective_modulus(*pair)
        assert float(law.k) == pytest.approx(mat.hertz_contact_stiffness(e_star, r_star), rel=1e-14)
        p_y = mat.YIELD_PRESSURE_FACTOR * min(m.yield_strength for m in pair)  # the softer's: the custom 7e7 Pa
        assert float(law.yield_overlap) == pytest.approx(yield_overlap(p_y, e_star, r_star), rel=1e-14)
    assert sc.bead_masses[4] == pytest.approx(mat.bead_mass(nylon, 4.76e-3), rel=1e-15)
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution
    scale = float(np.max(np.abs(ref.peak_force)))
    assert scale > 0.0
    assert ref.peak_force[5] > 0.1 * scale  # the wave has passed the soft bead (80.8 N, 10 N at contact 6)
    assert float(np.max(np.abs(lam.peak_force - ref.peak_force))) < 1e-9 * scale
    assert float(np.max(np.abs(lam.velocity - ref.velocity))) < 1e-8 * float(np.max(np.abs(ref.velocity)))
