"""[gravity] g: a vertical chain on the wall, bead 1 on top (issue 42, item 2).

Every bead carries its weight m_i g toward the wall; each contact starts at the weight above it (plus
any precompression F0). The yardstick is written here, not granchain's: the equations of motion with
gravity integrated by scipy's DOP853 from the materials' constants alone.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from granchain.lammps.runner import run_lammps
from granchain.physics.predictions import predict
from granchain.problem import ChainProblem
from granchain.reference.state import ChainState
from granchain.scene import SceneError, parse_scene
from granchain.schedule import STOP_CHECK_EVERY
from granchain.workflows.run import calculate_scene, run_reference

from .conftest import LAW_NAMES, make_scene_text

G = 9.81
#: the run's relative tolerance (the planner's default rtol, which sets the planned step)
RTOL = 1e-3


def toml_value(x) -> str:
    """A run key's value: "auto" quoted, a number as repr."""
    return '"auto"' if x == "auto" else repr(x)


def vertical_text(
    beads=10,
    material="stainless-steel-316",
    radius=2.38e-3,
    law="hertz",
    loading='kind = "striker"\nvelocity = 0.44',
    precompression=0.0,
    end_time="auto",
    timestep="auto",
    wall=True,
    extra="",
) -> str:
    """A vertical chain standing on the wall, struck at bead 1 (the top)."""
    text = f"""title = "vertical chain"
[chain]
beads = {beads}
radius = {radius!r}
material = "{material}"
[contact]
law = "{law}"
{extra}
[loading]
{loading}
[run]
end_time = {toml_value(end_time)}
timestep = {toml_value(timestep)}
[outputs]
peak_force = true
histories = [1, {beads - 1}]
[gravity]
g = {G!r}
"""
    if wall:
        text += '[boundary]\nfar_end = "wall"\n'
    if precompression:
        text += f"[precompression]\nforce = {precompression!r}\n"
    return text


def vertical(**kw):
    return parse_scene(vertical_text(**kw), source="vertical.toml")


#: no load to round-off: bead 1 given the smallest velocity a scene takes, 1e-15 m/s (a striker would
#: not do: it touches bead 1 unloaded and its weight would press it in)
AT_REST = 'kind = "velocity"\nvelocity = 1e-15'


# ---- (4) bad input


def test_gravity_without_a_wall_is_refused_with_the_fix():
    with pytest.raises(SceneError) as e:
        vertical(wall=False)
    msg = str(e.value)
    assert "[gravity]" in msg
    assert 'far_end = "wall"' in msg
    assert "remove [gravity]" in msg


@pytest.mark.parametrize("g", ["0.0", "-9.81", '"9.81"', "nan", "1e7"])
def test_bad_g_names_the_key(g):
    text = vertical_text().replace(f"g = {G!r}", f"g = {g}")
    with pytest.raises(SceneError, match=r"\[gravity\].*'?g'?"):
        parse_scene(text, source="vertical.toml")


def test_scene_round_trips_gravity():
    sc = vertical()
    assert parse_scene(sc.to_toml(), source="again.toml").effects.gravity == G


# ---- (1) at rest to round-off


def round_off_bounds(scene):
    """How far round-off may move a chain at rest: LAMMPS keeps absolute positions, each within an ulp
    of its static one (x up to the wall's), and a bead an ulp off its equilibrium oscillates at up to
    the chain's highest frequency omega = 2 sqrt(k_lin / m) (k_lin = 3/2 k^(2/3) F^(1/3) of the wall's
    contact at the whole weight, the stiffest). A chain out of equilibrium by its static overlaps
    (1e-8 m and more) would move at omega times those: 1e-3 m/s."""
    mass, _, k_wall = hertz_constants(scene)
    ulp = float(np.spacing(np.max(np.abs(scene.bead_positions)) + 2.0 * scene.chain.radius))
    k_lin = 1.5 * k_wall ** (2.0 / 3.0) * static_profile(scene)[-1] ** (1.0 / 3.0)
    omega = 2.0 * np.sqrt(k_lin / mass.min())
    return 100.0 * omega * ulp, 4.0 * ulp


@pytest.mark.parametrize("backend", ["reference", "lammps"])
def test_vertical_chain_without_a_load_stays_at_rest(backend):
    """1e5 steps of a 6-bead vertical chain without a load (precompressed too): every bead stays at its
    static equilibrium (the independent one below) to round-off (before: no [gravity] at all; with the
    weight but the positions at zero force, the chain would fall through its static overlaps, 1e-8 m,
    at once)."""
    steps = 100_000
    for f0 in (0.0, 0.5):
        sc = vertical(beads=6, end_time=steps * 2e-9, timestep=2e-9, precompression=f0, loading=AT_REST)
        sol = (run_lammps(sc)[0] if backend == "lammps" else run_reference(sc, "verlet")).solution
        v_bound, u_bound = round_off_bounds(sc)
        kick = sc.loading.velocity  # bead 1's 1e-15 m/s
        assert np.max(np.abs(sol.velocity)) < v_bound + kick
        assert np.max(np.abs(sol.history_velocity)) < v_bound + kick
        assert np.max(np.abs(sol.displacement - static_displacements(sc))) < u_bound


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    law=st.sampled_from(LAW_NAMES),
    beads=st.integers(1, 30),
    g=st.floats(0.1, 1e4),
    f0=st.sampled_from([0.0, 0.01, 50.0]),
    striker=st.booleans(),
)
def test_every_vertical_chain_starts_in_static_equilibrium(law, beads, g, f0, striker):
    """Any law, length, g and F0: at t = 0 every bead's net force (contacts, weight, F0) is round-off
    against its weight, and a law with history starts at each contact's static overlap (before: no
    [gravity]; with the weight on beads placed at zero force, each would accelerate at g)."""
    load = 'kind = "striker"\nvelocity = 0.1' if striker else 'kind = "velocity"\nvelocity = 0.1'
    text = make_scene_text(beads=beads, law=law, loading=load) + f'[gravity]\ng = {g!r}\n[boundary]\nfar_end = "wall"\n'
    if f0:
        text += f"[precompression]\nforce = {f0!r}\n"
    sc = parse_scene(text, source="vertical.toml")
    state = ChainState(ChainProblem.from_scene(sc).with_ends())
    s0 = state.problem.front
    moving = np.isfinite(state.problem.mass)
    moving[:s0] = False  # a striker falls onto bead 1: its weight is not yet carried
    # the largest force on a bead is its contacts' (F0 + the weight above), an ulp of which is round-off
    scale = (f0 + g * float(np.sum(state.problem.mass[moving]))) * state.inv_m[moving]
    a = state.a_int.copy()
    a[s0] += state.static_push * state.inv_m[s0]  # F0 on bead 1 behind a striker joins the load (a_ext)
    assert np.all(np.abs(a[moving]) <= 1e-12 * scale + 1e-12 * g)
    if state.law.history:  # (the overlaps of the positions: an ulp or so off the static ones)
        np.testing.assert_allclose(state.alpha_hist[s0:], state.overlap()[s0:], rtol=1e-12)


# ---- (2) against an independent DOP853 solver


def hertz_constants(scene):
    """Masses, bead-bead k and the rigid flat's k (Hertz: 4/3 E* sqrt(R*)) from the materials."""
    m = scene.chain.material
    r = float(scene.chain.radius)
    n = scene.chain.beads
    mass = np.full(n, m.density * 4.0 / 3.0 * np.pi * r**3)
    k = 4.0 / 3.0 * m.youngs_modulus / (2.0 * (1.0 - m.poisson_ratio**2)) * np.sqrt(r / 2.0)
    k_wall = 4.0 / 3.0 * m.youngs_modulus / (1.0 - m.poisson_ratio**2) * np.sqrt(r)
    return mass, k, k_wall


def static_profile(scene):
    """Each contact's static force (bead-bead, then the wall's): F0 plus the weight above it."""
    mass, _, _ = hertz_constants(scene)
    return float(scene.effects.precompression) + G * np.cumsum(mass)


def static_displacements(scene):
    """The beads' static displacements toward the wall (the wall at 0), from the forces above."""
    _, k, k_wall = hertz_constants(scene)
    f = static_profile(scene)
    overlap = np.append((f[:-1] / k) ** (2.0 / 3.0), (f[-1] / k_wall) ** (2.0 / 3.0))
    return np.cumsum(overlap[::-1])[::-1]  # u_i = sum of the overlaps below bead i


def dop853_peaks(scene, end):
    """The largest force of every bead-bead contact and of the wall to `end`: striker (a bead of the
    chain's, at the load's velocity) + N beads, each with its weight, F0 pushing bead 1."""
    mass, k, k_wall = hertz_constants(scene)
    f0 = float(scene.effects.precompression)
    n = mass.size
    ms = mass[0]
    m_all = np.concatenate(([ms], mass))

    def forces(u):
        fc = k * np.clip(u[:-1] - u[1:], 0.0, None) ** 1.5  # striker-bead 1, then the chain's
        fw = k_wall * max(u[-1], 0.0) ** 1.5
        return fc, fw

    def rhs(_, y):
        u, v = y[: n + 1], y[n + 1 :]
        fc, fw = forces(u)
        f = m_all * G
        f[1] += f0
        f[:-1] -= fc
        f[1:] += fc
        f[-1] -= fw
        return np.concatenate([v, f / m_all])

    u0 = static_displacements(scene)
    y0 = np.concatenate(([u0[0]], u0, [scene.loading.velocity], np.zeros(n)))
    sol = solve_ivp(rhs, (0.0, end), y0, method="DOP853", rtol=1e-12, atol=1e-20, dense_output=True)
    t = np.linspace(0.0, end, 200_001)
    u = sol.sol(t)[: n + 1]
    fc = k * np.clip(u[:-1] - u[1:], 0.0, None) ** 1.5
    fw = k_wall * np.clip(u[-1], 0.0, None) ** 1.5
    return fc[1:].max(axis=1), float(fw.max())


@pytest.mark.parametrize("material", ["stainless-steel-316", "brass"])
@pytest.mark.parametrize("beads", [8, 20])
@pytest.mark.parametrize("f0", [0.0, 0.2])
def test_struck_vertical_chain_against_dop853(material, beads, f0):
    """A striker on a vertical chain, the planned step: every contact's and the wall's dynamic peak
    (peak less the contact's own static force) within the run's rtol of DOP853 from the equations of
    motion with gravity (before: [gravity] refused as an unknown section). Gravity moves these dynamic
    peaks by 0.8% (8 beads) to 3% (20 beads) at 0.44 m/s, the wall's by 1-2%: far above the rtol."""
    sc = vertical(beads=beads, material=material, precompression=f0)  # planned: the stop check ends it
    result = calculate_scene(sc, error_estimate=False).result
    sol = result.solution
    static = static_profile(sc)
    peaks, wall = dop853_peaks(sc, sol.end_time)
    dynamic = peaks - static[:-1]
    measured = sol.peak_force - static[:-1]
    reached = dynamic > 1e-2 * dynamic.max()
    assert reached.sum() >= beads // 2
    np.testing.assert_allclose(measured[reached], dynamic[reached], rtol=RTOL)
    assert sol.wall_peak_force - static[-1] == pytest.approx(wall - static[-1], rel=RTOL)
    # the observables measure each contact's dynamic force, above its own static force
    i = result.summary["observables"]["max_peak_contact"] - 1
    assert result.summary["observables"]["max_peak_force"] == pytest.approx(dynamic[i], rel=RTOL)


# ---- (3) LAMMPS = reference Verlet, step for step


@pytest.mark.parametrize("law", ["hertz", "thornton"])
@pytest.mark.parametrize("f0", [0.0, 0.5])
def test_vertical_chain_lammps_equals_reference_verlet(law, f0):
    """Both backends step a vertical chain (a law with history too: its alpha_max starts at each
    contact's static overlap) to the same forces, velocities and positions (before: no [gravity])."""
    sc = vertical(beads=12, law=law, precompression=f0, end_time=1.2e-4, timestep=1e-8)
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution

    def rel(a, b):
        return np.nanmax(np.abs(a - b)) / np.nanmax(np.abs(b))

    assert rel(lam.peak_force, ref.peak_force) < 1e-9
    assert rel(lam.velocity, ref.velocity) < 1e-9
    assert rel(lam.displacement, ref.displacement) < 1e-9
    assert rel(lam.history_force, ref.history_force) < 1e-9
    # (relative to the chain's largest force, as rel: a wall the wave has not reached carries the weight
    # and a precursor's round-off)
    assert abs(lam.wall_peak_force - ref.wall_peak_force) < 1e-9 * np.max(ref.peak_force)
    # the leading pulse rises above the static forces (the deck's pair style takes the largest, the wall's):
    # the wave's first maximum, not a round-off bump on a contact's weight
    assert rel(lam.leading_pulse_force, ref.leading_pulse_force) < 1e-9
    if f0:  # the half-amplitude arrival off the ladder, which climbs from the largest static force
        assert rel(lam.front_time, ref.front_time) < 1e-9
    static = static_profile(sc)[:-1]
    found = np.isfinite(lam.leading_pulse_force)
    assert found.sum() >= 6
    assert np.all(lam.leading_pulse_force[found] - static[found] > 0.5 * (lam.peak_force[found] - static[found]))
    # gravity's work: LAMMPS's from the moving atoms' m x_cm column, the reference's ledger's sum of m_i dx_i
    assert rel(lam.work, ref.work) < 1e-9


@pytest.mark.parametrize("f0", [0.0, 0.5])
def test_vertical_chain_energy_balance_includes_gravity_work(f0):
    """RK4's energy ledger on a struck vertical chain: kinetic + stored = the energy put in, gravity's
    work included, to the effects' bound (test_effects: 1e-6); without precompression gravity's work
    is the energy's whole change, over 1e3 times that bound, so a ledger without it would fail."""
    sc = vertical(beads=12, precompression=f0, end_time=2e-4, timestep=1e-8)
    sol = run_reference(sc, "rk4").solution
    e = sol.kinetic + sol.potential + sol.dissipated
    scale = np.max(np.abs(e))
    assert np.max(np.abs(e - sol.work)) < 1e-6 * scale
    if not f0:  # gravity's the only external force: its work is the energy's whole change
        assert np.max(np.abs(e - e[0])) > 1e-3 * scale


# ---- predict: the local sound speed of each contact


def test_predict_gives_each_contact_its_local_sound_speed():
    """c0(i) = a sqrt(k_lin / m) with k_lin = 3/2 k^(2/3) F_i^(1/3) at the top and bottom contacts, from
    the materials' constants (Daraio et al. 2005, Eq. 1, contact by contact); applies only where the
    expected dynamic force is small against the contact's static force; the paper's models (one static
    force on every contact, or none) say why they do not apply (before: no [gravity])."""
    mass, k, _ = hertz_constants(vertical(beads=40))
    for v, applies in ((0.44, (False, False)), (1e-4, (False, True))):
        sc = vertical(beads=40, loading=f'kind = "striker"\nvelocity = {v!r}')
        f = static_profile(sc)[:-1]
        expected = (2 * sc.chain.radius - (f / k) ** (2 / 3)) * np.sqrt(1.5 * k ** (2 / 3) * f ** (1 / 3) / mass[0])
        got = {p.name: p for p in predict(sc)}
        top, bottom = got["local_sound_speed_top"], got["local_sound_speed_bottom"]
        assert top.value == pytest.approx(expected[0], rel=1e-12)
        assert bottom.value == pytest.approx(expected[-1], rel=1e-12)
        assert (top.applies, bottom.applies) == applies
        assert "outside the model's domain" in top.applies_reason
        paper = [p for p in got.values() if p.name.endswith("wave_speed")]
        assert paper
        assert all(not p.applies and "gravity" in p.applies_reason for p in paper)


def test_planned_vertical_chain_waits_for_the_reflection_on_both_backends():
    """The planned stop check waits for the wall's reflection to come back through contact 1 on both
    backends: a floor above every contact's static force (before: LAMMPS stopped at half the time, once
    the top contact opened below its weight after the striker's rebound, and missed the largest peak)."""
    sc = vertical(beads=20)
    ref = calculate_scene(sc, error_estimate=False).result
    lam = calculate_scene(sc, backend="lammps", error_estimate=False).result
    # the same check on both backends, contact 1's reflection past the striker's contact: one check apart
    assert abs(lam.solution.end_time - ref.solution.end_time) <= 1.5 * STOP_CHECK_EVERY * ref.solution.timestep
    a, b = ref.summary["observables"], lam.summary["observables"]
    assert a["max_peak_contact"] == b["max_peak_contact"]
    assert b["max_peak_force"] == pytest.approx(a["max_peak_force"], rel=RTOL)
