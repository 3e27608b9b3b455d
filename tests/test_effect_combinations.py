"""Every combination of effects runs, right, on both backends (docs/effects.md): any subset of the
effect registry with every contact law, uniform or per-bead chains of several materials; and the
two-body impacts of a contact law against their closed forms."""

import tomllib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.lammps.runner import run_lammps
from granchain.physics import materials as mat
from granchain.physics.damping import DAMPING
from granchain.physics.effects import EFFECTS, active_effects, external_forces
from granchain.physics.laws import LAWS
from granchain.physics.models import hertz_impact
from granchain.physics.predictions import applicability, predict
from granchain.scene import SceneError, parse_scene, scene_from_dict
from granchain.workflows.run import run_reference, run_scene

from .conftest import LAW_NAMES, make_scene_text

#: metals with a yield strength: the plastic laws' mixing rules read it
YIELDING = [name for name, m in mat.MATERIALS.items() if m.yield_strength is not None]


def rel(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    scale = np.max(np.abs(b)) if b.size else 0.0
    return float(np.max(np.abs(a - b)) / scale) if scale else float(np.max(np.abs(a - b), initial=0.0))


def contact_table(law: str, several_materials: bool) -> str | None:
    """[contact] lines besides law: the law's example on a chain of one material (None), or on one of
    several, the plastic laws' k and p_y from each material's yield strength."""
    if not several_materials:
        return None
    cls = LAWS[law]
    # the key the law derives from each material's yield strength (bilinear's k, Thornton's p_y)
    return "".join(f"{k} = {v!r}\n" for k, v in cls.example_contact.items() if k != cls.yield_strength_key)


@st.composite
def combinations(draw):
    """A scene with a drawn subset of the registered effects (their own declarations, with drawn
    strengths; damping: a part drawn from the damping registry, with its example coefficient), a drawn
    law and, for per-bead chains, a taper or a sequence of materials."""
    names = draw(st.sets(st.sampled_from(sorted(EFFECTS))), label="effects")
    part = draw(st.sampled_from([p for p in DAMPING if DAMPING[p].key]), label="damping part")
    law = draw(st.sampled_from(LAW_NAMES), label="law")
    per_bead = "per_bead" in names
    several = per_bead and draw(st.booleans(), label="several materials")
    # one bead: struck or on the wall; a struck bead with a free far end has no contact precompression
    # compresses (the scene refuses it: reader.py)
    one_bead_ok = ("wall" in names or ("striker" in names and "precompression" not in names)) and not per_bead
    beads = draw(st.integers(1 if one_bead_ok else 2, 10), label="beads")
    material = "stainless-steel-316" if (several or law != "hertz") else "brass"
    text = make_scene_text(
        beads=beads,
        law=law,
        contact_extra=contact_table(law, several),
        loading='kind = "velocity"\nvelocity = 1.0',
        end_time=6e-5,
        timestep=1e-8,
    ).replace('material = "brass"', f'material = "{material}"')
    data = tomllib.loads(text)
    for e in (EFFECTS[n] for n in EFFECTS if n in names):  # registry order
        declaration = e.declaration_of(part) if e.name == "damping" else e.declaration
        for table, keys in declaration.items():
            data[table] = {**data.get(table, {}), **keys}
    if "precompression" in data:
        data["precompression"]["force"] = draw(st.floats(0.5, 100.0), label="F0")
    if data["loading"]["kind"] == "striker":
        data["loading"]["velocity"] = draw(st.floats(0.2, 4.0), label="striker velocity")
        if draw(st.booleans(), label="striker of its own size"):
            data["loading"]["radius"] = draw(st.floats(2e-3, 8e-3), label="striker radius")
    if several:
        data["chain"].pop("taper", None)
        data["chain"]["material"] = [draw(st.sampled_from(YIELDING), label=f"material {i + 1}") for i in range(beads)]
        if len(set(data["chain"]["material"])) == 1:  # a uniform list is the plain chain: make it two
            other = next(m for m in YIELDING if m != data["chain"]["material"][0])
            data["chain"]["material"][-1] = other
    return names, data


@pytest.mark.slow
@settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck))
@given(combo=combinations())
def test_every_subset_of_effects_runs_the_same_on_both_backends(combo):
    names, data = combo
    sc = scene_from_dict(data, source="combination.toml")
    needed = names | {r for n in names for r in EFFECTS[n].requires}  # and what they need (gravity: the wall)
    assert [e.name for e in active_effects(sc)] == [n for n in EFFECTS if n in needed]  # accepted, exactly these
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution
    if sc.n_contacts:
        assert rel(lam.peak_force, ref.peak_force) < 1e-9
    assert rel(lam.velocity, ref.velocity) < 1e-8
    scale = max(np.max(np.abs(ref.peak_force), initial=0.0), ref.striker_peak_force or 0.0, ref.wall_peak_force or 0.0)
    for end in ("striker_peak_force", "wall_peak_force"):
        a, b = getattr(lam, end), getattr(ref, end)
        assert (a is None) == (b is None), end
        if a is not None:
            assert abs(a - b) <= 1e-9 * scale, end
    # the energy balance holds on both, within Verlet's own step error at 1e-8 s steps: 1e-4 of the
    # work, and with damping its first-order booking, up to c v^2 dt with c the contacts' viscous
    # coefficient (a dashpot's gamma: its force jumps by gamma v where a contact closes at v; Kuwabara-
    # Kono's A k_t at the largest peak), for each contact (striker's and wall's included)
    work = max(float(np.max(np.abs(ref.work))), 1e-300)
    v = sc.loading.velocity
    peak = max(np.max(ref.peak_force, initial=0.0), ref.striker_peak_force or 0.0, ref.wall_peak_force or 0.0)
    viscous = float(np.max(sc.damping.contact_damping(sc.damping_coefficient, sc.law.tangent_stiffness(peak))))
    dash = viscous * v * v * sc.run.timestep * (sc.n_contacts + 2)
    for sol in (lam, ref):
        assert np.max(np.abs(sol.energy_balance_error)) < 1e-4 * work + dash
    assert lam.work[-1] == pytest.approx(ref.work[-1], rel=1e-9)
    # nothing external acts: the striker's momentum is the chain's (a striker gives it all there is)
    if sc.loading.kind == "striker" and not external_forces(sc):
        p0 = sc.striker_mass * sc.loading.velocity
        for sol in (lam, ref):
            assert sol.momentum == pytest.approx(p0, rel=1e-9)


def test_a_single_bead_needs_a_striker_or_a_wall():
    text = make_scene_text(beads=1, loading='kind = "velocity"\nvelocity = 1.0')
    with pytest.raises(SceneError, match=r"beads = 1 has no contact to load.*striker.*wall"):
        parse_scene(text, source="one.toml")


def one_bead_scene(material: str, radius: float, velocity: float, wall: bool, striker_radius: float | None = None):
    """One bead of a material: struck by a striker (of its size, or striker_radius) or given a
    velocity against the wall; end time and step planned."""
    if wall:
        loading = f'kind = "velocity"\nvelocity = {velocity!r}'
    else:
        loading = f'kind = "striker"\nvelocity = {velocity!r}'
        if striker_radius is not None:
            loading += f"\nradius = {striker_radius!r}"
    text = make_scene_text(beads=1, loading=loading, end_time=1e-3, timestep=1e-9)
    text = text.replace('material = "brass"', f'material = "{material}"')
    text = text.replace("radius = 4.76e-3", f"radius = {radius!r}")
    text = text.replace("end_time = 0.001\ntimestep = 1e-09", 'end_time = "auto"\ntimestep = "auto"')
    return parse_scene(text + ('[boundary]\nfar_end = "wall"\n' if wall else ""), source="impact.toml")


RTOL = 1e-4


@pytest.mark.parametrize("backend", ["reference", "lammps"])
@settings(max_examples=6, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    material=st.sampled_from(sorted(mat.MATERIALS)),
    radius=st.floats(1e-3, 1e-2),
    velocity=st.floats(0.05, 5.0),
    wall=st.booleans(),
    striker_ratio=st.one_of(st.none(), st.floats(0.5, 2.0)),
)
def test_two_body_hertz_impacts_match_the_closed_form(backend, material, radius, velocity, wall, striker_ratio):
    """A striker on one bead (m* the reduced mass, the pair's E* and R*) and a bead on the wall
    (E* = E/(1-nu^2), R* = R, m* = m): peak force K^(2/5) (5/4 m* v^2)^(3/5) and contact time
    2.943 delta_max / v (the peak at half of it), to within the plan's rtol (LAMMPS's time of peak
    to within its step as well)."""
    sc = one_bead_scene(material, radius, velocity, wall, None if striker_ratio is None else striker_ratio * radius)
    m1 = float(sc.bead_masses[0])
    if wall:
        mat_ = sc.chain.material
        k = 4.0 / 3.0 * mat_.youngs_modulus / (1.0 - mat_.poisson_ratio**2) * np.sqrt(radius)
        exact = hertz_impact(k, m1, velocity)
    else:
        ms, r_s = sc.striker_mass, sc.loading.striker_radius
        compliance = sum(
            (1 - m.poisson_ratio**2) / m.youngs_modulus for m in (sc.loading.striker_material, sc.chain.material)
        )
        k = 4.0 / 3.0 / compliance * np.sqrt(r_s * radius / (r_s + radius))
        exact = hertz_impact(k, ms * m1 / (ms + m1), velocity)
    result = run_scene(sc, backend=backend, rtol=RTOL, error_estimate=True)
    sol = result.solution
    force = sol.wall_peak_force if wall else sol.striker_peak_force
    when = sol.wall_time_of_peak if wall else sol.striker_time_of_peak
    assert force == pytest.approx(exact["peak_force"], rel=RTOL)
    # its error bar tells the truth: within 1/3 - 3 of the distance to the closed form
    bar = result.errors.end_peaks["wall_peak_force" if wall else "striker_peak_force"]
    true = abs(force - exact["peak_force"])
    if bar["error"] is not None and true > 1e-11 * force:  # (above the closed form's own round-off)
        assert 1 / 3 <= bar["error"] / true <= 3, bar
    step = result.scene.run.timestep
    slack = RTOL + (0.0 if backend == "reference" else step / when)  # LAMMPS's peak time is a step's
    assert 2.0 * when == pytest.approx(exact["duration"], rel=2 * slack)


def two_bead_scene(materials: list[str], radii: list[float], velocity: float):
    """Two free beads of their own materials and radii, bead 1 given a velocity towards bead 2; end time
    and step planned."""
    text = make_scene_text(beads=2, loading=f'kind = "velocity"\nvelocity = {velocity!r}', end_time=1e-3, timestep=1e-9)
    text = text.replace('material = "brass"', f"material = {materials!r}".replace("'", '"'))
    text = text.replace("radius = 4.76e-3", f"radius = {radii!r}")
    text = text.replace("end_time = 0.001\ntimestep = 1e-09", 'end_time = "auto"\ntimestep = "auto"')
    return parse_scene(text, source="pair.toml")


@pytest.mark.parametrize("backend", ["reference", "lammps"])
@settings(max_examples=6, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    materials=st.lists(st.sampled_from(sorted(mat.MATERIALS)), min_size=2, max_size=2),
    radii=st.lists(st.floats(1e-3, 1e-2), min_size=2, max_size=2),
    velocity=st.floats(0.05, 5.0),
)
def test_two_free_beads_are_the_two_body_hertz_impact(backend, materials, radii, velocity):
    """Bead 1 of two free beads (any two materials and radii) hits bead 2: the peak is the Hertz impact's
    K^(2/5) (5/4 m* v^2)^(3/5) with m* = m1 m2 / (m1 + m2) and the pair's E* and R*, computed here from the
    materials' E and nu, to within the plan's rtol; compare's model for the leading peak is this one."""
    sc = two_bead_scene(materials, radii, velocity)
    m1, m2 = (float(m) for m in sc.bead_masses)
    a, b = (mat.MATERIALS[name] for name in materials)
    e_star = 1.0 / ((1 - a.poisson_ratio**2) / a.youngs_modulus + (1 - b.poisson_ratio**2) / b.youngs_modulus)
    k = 4.0 / 3.0 * e_star * np.sqrt(radii[0] * radii[1] / (radii[0] + radii[1]))
    exact = hertz_impact(k, m1 * m2 / (m1 + m2), velocity)
    result = run_scene(sc, backend=backend, rtol=RTOL)
    assert result.observables()["leading_peak_force"] == pytest.approx(exact["peak_force"], rel=RTOL)
    model = {p.name: p for p in predict(sc)}["pair_impact_peak_force"]
    assert model.value == pytest.approx(exact["peak_force"], rel=1e-12)
    assert applicability("pair_impact_peak_force", sc, quantity="leading_peak_force").applies
