"""Walls of a material ([boundary] wall_material, wall_radius): bead N's contact on the wall takes the
pair's E* (1/E* = (1-nu_b^2)/E_b + (1-nu_w^2)/E_w) and R* (1/R* = 1/R + 1/R_w) with the scene's law.

Checked against closed forms and a solver written here (scipy's DOP853), not granchain's models:
the Hertz two-body impact of one bead on the wall, and chains of stainless beads on walls of PTFE,
aluminium and steel. Before wall_material every scene here was refused ("unknown key").
"""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from granchain.lammps.runner import run_lammps
from granchain.physics.laws import LAWS
from granchain.physics.materials import MATERIALS
from granchain.scene import SceneError, parse_scene, scene_to_dict
from granchain.scene.reader import scene_from_dict
from granchain.workflows.run import run_reference

#: the walls of issue 41's motivation, and a hard one
WALLS = ("ptfe", "aluminium-6061-t6", "stainless-steel-316", "tungsten-carbide")


def walled_text(beads, radius, velocity, wall, *, wall_radius=None, end_time, timestep, law='law = "hertz"\n'):
    """A stainless chain given `velocity` at bead 1 against a wall of material `wall` (a name, or
    a TOML inline table as text)."""
    w = wall if wall.startswith("{") else f'"{wall}"'
    curved = "" if wall_radius is None else f"wall_radius = {wall_radius!r}\n"
    return (
        f'[chain]\nbeads = {beads}\nradius = {radius!r}\nmaterial = "stainless-steel-316"\n'
        f'[contact]\n{law}[loading]\nkind = "velocity"\nvelocity = {velocity!r}\n'
        f"[run]\nend_time = {end_time!r}\ntimestep = {timestep!r}\n[outputs]\npeak_force = true\n"
        f'[boundary]\nfar_end = "wall"\nwall_material = {w}\n{curved}'
    )


def pair_e_star(a, b):
    return 1.0 / ((1 - a.poisson_ratio**2) / a.youngs_modulus + (1 - b.poisson_ratio**2) / b.youngs_modulus)


def hertz_k(e_star, r_star):
    return 4.0 / 3.0 * e_star * math.sqrt(r_star)


def impact(k, m, v):
    """Hertz two-body impact (Johnson, Sec. 11.1): peak overlap, force and the time to the peak
    (half the contact time 2.9432 delta_max / v)."""
    d = (5.0 * m * v**2 / (4.0 * k)) ** 0.4
    return k * d**1.5, 1.4716 * d / v


@settings(max_examples=12, deadline=None)
@given(
    wall=st.sampled_from(WALLS),
    radius=st.floats(2e-3, 1e-2),
    velocity=st.floats(0.05, 2.0),
    wall_radius=st.one_of(st.none(), st.floats(5e-3, 0.5)),
)
def test_one_bead_on_a_wall_of_a_material_is_the_hertz_two_body_impact(wall, radius, velocity, wall_radius):
    """Peak force and time of peak of one stainless bead on the wall: Hertz with the pair's E* and
    R* (rigid before: E* = E/(1-nu^2), R* = R; wall_material was an unknown key)."""
    bead, w = MATERIALS["stainless-steel-316"], MATERIALS[wall]
    r_star = radius if wall_radius is None else radius * wall_radius / (radius + wall_radius)
    m = bead.density * 4.0 / 3.0 * math.pi * radius**3
    f_max, t_peak = impact(hertz_k(pair_e_star(bead, w), r_star), m, velocity)
    dt = t_peak / 1500.0
    sc = parse_scene(
        walled_text(1, radius, velocity, wall, wall_radius=wall_radius, end_time=2.4 * t_peak, timestep=dt),
        source="t.toml",
    )
    sol = run_reference(sc, "rk4").solution
    assert sol.wall_peak_force == pytest.approx(f_max, rel=1e-5)
    assert sol.wall_time_of_peak == pytest.approx(t_peak, rel=2e-3)  # the sampled peak: within a step


def test_one_bead_on_a_ptfe_wall_on_lammps_is_the_hertz_two_body_impact():
    bead, w = MATERIALS["stainless-steel-316"], MATERIALS["ptfe"]
    radius, velocity = 4e-3, 0.5
    m = bead.density * 4.0 / 3.0 * math.pi * radius**3
    f_max, t_peak = impact(hertz_k(pair_e_star(bead, w), radius), m, velocity)
    sc = parse_scene(
        walled_text(1, radius, velocity, "ptfe", end_time=2.4 * t_peak, timestep=t_peak / 1500.0), source="t.toml"
    )
    sol = run_lammps(sc)[0].solution
    assert sol.wall_peak_force == pytest.approx(f_max, rel=1e-5)
    assert sol.wall_time_of_peak == pytest.approx(t_peak, rel=2e-3)


def dop853_wall_peak(n, radius, velocity, wall, end_time):
    """The wall's peak force of a uniform stainless Hertz chain, bead 1 at `velocity`, bead N on a
    flat wall of material `wall`: integrated with scipy's DOP853, the peak refined on dense output."""
    bead, w = MATERIALS["stainless-steel-316"], MATERIALS[wall]
    m = bead.density * 4.0 / 3.0 * math.pi * radius**3
    kb = hertz_k(bead.youngs_modulus / (2 * (1 - bead.poisson_ratio**2)), radius / 2)
    kw = hertz_k(pair_e_star(bead, w), radius)

    def rhs(_t, y):
        u, v = y[:n], y[n:]
        f = kb * np.maximum(u[:-1] - u[1:], 0.0) ** 1.5
        fw = kw * max(u[-1], 0.0) ** 1.5
        a = np.zeros(n)
        a[:-1] -= f
        a[1:] += f
        a[-1] -= fw
        return np.concatenate((v, a / m))

    y0 = np.zeros(2 * n)
    y0[n] = velocity
    s = solve_ivp(rhs, (0, end_time), y0, method="DOP853", rtol=1e-12, atol=1e-18, dense_output=True)
    t = np.linspace(0, end_time, 200001)
    force = kw * np.maximum(s.sol(t)[n - 1], 0.0) ** 1.5
    return float(force.max())


@pytest.mark.parametrize("wall", ["ptfe", "aluminium-6061-t6", "stainless-steel-316"])
def test_a_chain_on_a_wall_of_a_material_against_dop853(wall):
    """10 stainless beads on walls of PTFE, aluminium and steel: the wall's peak force within the
    run's own error bar (its rtol) of an independent DOP853 solution."""
    n, radius, velocity, end = 10, 4e-3, 0.5, 4e-4
    sc = parse_scene(walled_text(n, radius, velocity, wall, end_time=end, timestep=2e-8), source="t.toml")
    sol = run_reference(sc, "rk4").solution
    expected = dop853_wall_peak(n, radius, velocity, wall, end)
    assert sol.wall_peak_force == pytest.approx(expected, rel=1e-5)


def test_softer_walls_carry_less_than_the_rigid_one():
    """Issue 41's observable: on the same chain the wall's peak falls with the wall's stiffness."""
    peaks = [dop853_wall_peak(10, 4e-3, 0.5, w, 4e-4) for w in ("tungsten-carbide", "stainless-steel-316", "ptfe")]
    assert peaks[0] > peaks[1] > peaks[2]


@pytest.mark.parametrize(
    "law",
    ['law = "hertz"\n', 'law = "thornton"\n', 'law = "bilinear"\nunloading_coeff = 0.5\n'],
    ids=["hertz", "thornton", "bilinear"],
)
def test_lammps_and_the_references_verlet_agree_step_for_step_on_a_curved_aluminium_wall(law):
    """The wall's contact on both backends (its pair_coeff in the deck, the reference's wall law): the
    peaks and histories as tests/test_effects.py compares them (relative to the largest), the wall's
    peak to 1e-9; the run lasts past the wall's reflection."""
    text = walled_text(8, 3e-3, 1.5, "aluminium-6061-t6", wall_radius=0.02, end_time=2e-4, timestep=1e-8, law=law)
    text = text.replace("peak_force = true\n", "peak_force = true\nhistories = [1, 7]\n")
    sc = parse_scene(text, source="t.toml")
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution
    assert ref.wall_peak_force > 0.1 * np.max(ref.peak_force)  # the wave reached the wall
    assert rel(lam.peak_force, ref.peak_force) < 1e-9
    assert rel(lam.history_force, ref.history_force) < 1e-8
    assert lam.wall_peak_force == pytest.approx(ref.wall_peak_force, rel=1e-9)


def rel(a, b):
    """The largest difference relative to the largest value (tests/test_effects.py's)."""
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b)))


def test_plastic_laws_take_the_softer_materials_yield_on_the_wall():
    """Bilinear: k = 18.5 sigma_y R* of the softer of bead N and the wall; Thornton: p_y = 1.61 sigma_y."""
    al, ss = MATERIALS["aluminium-6061-t6"], MATERIALS["stainless-steel-316"]
    law = 'law = "bilinear"\nunloading_coeff = 0.5\n'
    sc = parse_scene(walled_text(5, 3e-3, 1.0, "aluminium-6061-t6", end_time=1e-4, timestep=1e-8, law=law), "t")
    assert sc.wall_law.k == pytest.approx(18.5 * min(al.yield_strength, ss.yield_strength) * 3e-3, rel=1e-12)
    rigid = parse_scene(walled_text(5, 3e-3, 1.0, "{}", end_time=1e-4, timestep=1e-8, law=law)
                        .replace("wall_material = {}\n", ""), "t")  # fmt: skip
    assert rigid.wall_law.k == pytest.approx(2 * rigid.law.k, rel=1e-12)  # unchanged: twice the beads' k


def test_an_inline_wall_material_and_a_radius_round_trip():
    table = "{density = 1200.0, youngs_modulus = 3.0e9, poisson_ratio = 0.35}"
    sc = parse_scene(walled_text(4, 3e-3, 1.0, table, wall_radius=0.01, end_time=1e-4, timestep=1e-8), "t")
    back = scene_from_dict(scene_to_dict(sc), source="t")
    assert back.effects == sc.effects
    assert parse_scene(sc.to_toml(), "t").effects == sc.effects
    named = parse_scene(walled_text(4, 3e-3, 1.0, "ptfe", end_time=1e-4, timestep=1e-8), "t")
    assert scene_to_dict(named)["boundary"] == {"far_end": "wall", "wall_material": "ptfe"}


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (('wall_material = "ptfe"', 'wall_material = "unobtainium"'), r"\[boundary\] wall_material = 'unobtainium'"),
        (('wall_material = "ptfe"', "wall_material = 3"), r"\[boundary\] wall_material = 3 is invalid"),
        (('wall_material = "ptfe"', 'wall_material = "ptfe"\nwall_radius = -0.01'), r"\[boundary\] wall_radius"),
        (('far_end = "wall"', 'far_end = "free"'), r'wall_material .* no wall: add \[boundary\] far_end = "wall"'),
        (('far_end = "wall"\n', ""), r"\[boundary\] is missing 'far_end'"),
        (
            ('law = "hertz"', 'law = "thornton"'),
            r"\[boundary\] wall_material with \[contact\] law = 'thornton'.*ptfe has no yield_strength",
        ),
        (
            ('wall_material = "ptfe"', "wall_material = {density = 1200.0, youngs_modulus = 3.0, poisson_ratio = 0.3}"),
            r"\[boundary.wall_material\] youngs_modulus",
        ),
    ],
)
def test_bad_wall_input_is_one_clear_error(edit, match):
    text = walled_text(4, 3e-3, 1.0, "ptfe", end_time=1e-4, timestep=1e-8).replace(*edit)
    with pytest.raises(SceneError, match=match):
        parse_scene(text, source="t.toml")


@pytest.mark.parametrize(
    ("law", "given"),
    [("bilinear", "unloading_coeff = 0.5\nplastic_stiffness = 2.43e7\n"), ("thornton", "yield_pressure = 3.25e9\n")],
)
def test_a_given_plastic_value_gives_way_to_the_softer_yield_on_a_wall_of_a_material(law, given):
    """The law's declared yield_strength_key (bilinear's k, Thornton's p_y) is what a wall of a material
    re-derives from the softer material's yield, for every plastic law alike (Thornton named none: its
    wall kept the chain's p_y against a softer aluminium wall)."""
    key = LAWS[law].yield_strength_key
    assert key is not None
    assert key in given
    al, ss = MATERIALS["aluminium-6061-t6"], MATERIALS["stainless-steel-316"]
    text = f'law = "{law}"\n{given}'
    sc = parse_scene(walled_text(5, 3e-3, 1.0, "aluminium-6061-t6", end_time=1e-4, timestep=1e-8, law=text), "t")
    softer = dataclasses.replace(sc.contact.coefficients, **{key: None})
    pair = sc.wall_pair(3e-3, ss)
    assert sc.wall_law == LAWS[law].for_pair(softer, *pair[:2], sc.r_star, (ss, al))
    assert min(al.yield_strength, ss.yield_strength) == al.yield_strength


def test_a_thornton_yield_pressure_and_a_tables_yield_strength_are_one_clear_error():
    table = "{density = 8000.0, youngs_modulus = 2e11, poisson_ratio = 0.3, yield_strength = 3e8}"
    text = walled_text(3, 3e-3, 1.0, "{}", end_time=1e-4, timestep=1e-8, law='law = "thornton"\nyield_pressure = 3e9\n')
    text = text.replace('material = "stainless-steel-316"', f"material = {table}").replace("wall_material = {}\n", "")
    with pytest.raises(SceneError, match=r"yield_pressure = 3000000000.0 and \[chain.material\] yield_strength"):
        parse_scene(text, "t")
