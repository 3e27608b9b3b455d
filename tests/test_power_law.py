"""The power law F = K alpha^n (issue 41 item 3): the elastic two-body impact on both backends against
its closed form, LAMMPS against the reference's Verlet step for step, and a chain with an interface in
n against an independent solver (scipy's DOP853, not granchain's code)."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from granchain.physics.laws import PowerLaw
from granchain.physics.laws.power import power_impact
from granchain.problem import ChainProblem
from granchain.reference.solver import solve_chain
from granchain.scene import SceneError, scene_from_dict, scene_to_dict
from granchain.workflows.error_estimates import expected_orders
from granchain.workflows.run import run_scene

RTOL = 1e-3
MATERIALS = ["brass", "chrome-steel-52100", "aluminium-6061-t6"]


def two_beads(n, k, v0, material="brass", radius=4.76e-3, run=None):
    return scene_from_dict(
        {
            "chain": {"beads": 2, "radius": radius, "material": material},
            "contact": {"law": "power", "exponent": n, "stiffness": k},
            "loading": {"kind": "velocity", "velocity": v0},
            "run": run or {"end_time": "auto", "timestep": "auto"},
        },
        source="two.toml",
    )


def stiffness_for(n, radius):
    """A K (N/m^n) that gives a brass-like contact: the Hertz force at an overlap of 1e-5 R."""
    a = 1e-5 * radius
    return 1.3e10 * math.sqrt(radius / 2) * a**1.5 / a**n


@st.composite
def impacts(draw):
    n = draw(st.floats(1.0, 3.0), label="n")
    radius = draw(st.floats(2e-3, 1e-2), label="radius")
    v0 = draw(st.floats(0.05, 2.0), label="v0")
    material = draw(st.sampled_from(MATERIALS), label="material")
    k = stiffness_for(n, radius) * draw(st.floats(0.3, 3.0), label="K factor")
    return n, k, v0, material, radius


def check_impact(sol, sc, n, k, v0):
    hit = power_impact(k, n, sc.mass / 2.0, v0)
    assert sol.peak_force[0] == pytest.approx(hit["peak_force"], rel=RTOL)
    # the elastic impact is symmetric in time: the peak at half the contact time
    assert 2.0 * sol.time_of_peak[0] == pytest.approx(hit["duration"], rel=RTOL)


def test_the_impact_model_has_its_known_limits():
    """pi delta_max / v at n = 1 (half a period of the spring), 2.9432 delta_max / v at n = 3/2 (Johnson)."""
    for n, factor in ((1.0, math.pi), (1.5, 2.9432)):
        hit = power_impact(1e8, n, 1e-3, 0.5)
        assert hit["duration"] * 0.5 / hit["max_overlap"] == pytest.approx(factor, rel=1e-4)


@settings(max_examples=25, deadline=None, suppress_health_check=list(HealthCheck))
@given(case=impacts())
def test_two_body_impact_on_the_reference(case):
    n, k, v0, material, radius = case
    sc = two_beads(n, k, v0, material, radius)
    check_impact(run_scene(sc, backend="reference", rtol=RTOL).solution, sc, n, k, v0)


@settings(max_examples=3, deadline=None, suppress_health_check=list(HealthCheck))
@given(case=impacts())
def test_two_body_impact_on_lammps(case):
    n, k, v0, material, radius = case
    sc = two_beads(n, k, v0, material, radius)
    check_impact(run_scene(sc, backend="lammps", rtol=RTOL).solution, sc, n, k, v0)


def interface_problem(beads, exponents, v0=0.3):
    """A brass chain whose contacts have the exponents given, bead 1 kicked at v0."""
    p = ChainProblem.from_scene(
        scene_from_dict(
            {
                "chain": {"beads": beads, "radius": 4.76e-3, "material": "brass"},
                "contact": {"law": "power", "exponent": 1.5, "stiffness": 1.0},
                "loading": {"kind": "velocity", "velocity": v0},
                "run": {"end_time": 1e-4, "timestep": 1e-8},
            },
            source="chain.toml",
        )
    )
    ks = np.array([stiffness_for(n, 4.76e-3) for n in exponents])
    return dataclasses.replace(p, law=PowerLaw(k=ks, exponent=np.asarray(exponents, dtype=float)))


def independent_peaks(mass, ks, ns, v0, end):
    """Each contact's peak force of the same chain by scipy's DOP853 on m u'' = F_(i-1) - F_i."""

    def rhs(_, y):
        n_b = len(ks) + 1
        u, v = y[:n_b], y[n_b:]
        f = ks * np.maximum(u[:-1] - u[1:], 0.0) ** ns
        a = np.zeros(n_b)
        a[:-1] -= f
        a[1:] += f
        return np.concatenate((v, a / mass))

    y0 = np.zeros(2 * (len(ks) + 1))
    y0[len(ks) + 1] = v0
    sol = solve_ivp(rhs, (0.0, end), y0, method="DOP853", rtol=1e-11, atol=1e-16, dense_output=True)
    t = np.linspace(0.0, end, 200001)
    u = sol.sol(t)[: len(ks) + 1]
    return np.max(ks[:, None] * np.maximum(u[:-1] - u[1:], 0.0) ** ns[:, None], axis=1)


def test_an_interface_in_n_against_an_independent_solver():
    exponents = [1.2] * 5 + [2.0] * 5
    p = interface_problem(11, exponents)
    ref = solve_chain(p, 2e-4, 2e-8, "rk4")
    ks, ns = np.asarray(p.law.k), np.asarray(p.law.exponent)
    expected = independent_peaks(float(p.mass[0]), ks, ns, 0.3, 2e-4)
    assert np.allclose(ref.peak_force, expected, rtol=RTOL)


@pytest.mark.parametrize("n", [1.0, 1.3, 2.0, 3.0])
def test_lammps_equals_the_reference_verlet_step_for_step(n):
    """A chain of 6 beads under one exponent n (per-contact lists: test_per_contact_lammps_equals_...)."""
    sc = scene_from_dict(
        {
            "chain": {"beads": 6, "radius": 4.76e-3, "material": "brass"},
            "contact": {"law": "power", "exponent": n, "stiffness": stiffness_for(n, 4.76e-3)},
            "loading": {"kind": "velocity", "velocity": 0.3},
            "run": {"end_time": 2e-4, "timestep": 2e-8},
        },
        source="chain.toml",
    )
    lam = run_scene(sc, backend="lammps").solution
    ver = run_scene(sc, backend="reference", method="verlet").solution
    # to 1e-9 of the largest force (as tests/test_effect_combinations.py): a far contact's overlap is a
    # small difference of LAMMPS's absolute positions
    assert np.max(np.abs(lam.peak_force - ver.peak_force)) <= 1e-9 * np.max(ver.peak_force)
    assert np.allclose(lam.velocity, ver.velocity, rtol=1e-9, atol=1e-9 * 0.3)


@settings(max_examples=20, deadline=None)
@given(n=st.floats(1.0, 3.0))
def test_the_error_bars_onset_order_is_one_plus_the_laws_exponent(n):
    """RK4's lowest order on a chain is its onset's 1 + n (issue 41 item 1), not Hertz's 2.5 for every
    law; the Hertz and Thornton laws keep 2.5, and each law declares its exponent."""
    sc = two_beads(n, stiffness_for(n, 4.76e-3), 0.3)
    assert expected_orders("rk4", sc) == (pytest.approx(1.0 + n), 4.0)
    assert float(sc.law.loading_exponent()) == n
    hertz = scene_from_dict(
        {
            "chain": {"beads": 2, "radius": 4.76e-3, "material": "brass"},
            "contact": {"law": "hertz"},
            "loading": {"kind": "velocity", "velocity": 0.3},
            "run": {"end_time": "auto", "timestep": "auto"},
        },
        source="hertz.toml",
    )
    assert expected_orders("rk4", hertz) == (2.5, 4.0)
    assert float(hertz.law.loading_exponent()) == 1.5


# ---- per-contact n and K in the scene ([contact] exponent, stiffness: lists; issue 41 item 3)
RADIUS = 4.76e-3


def listed_chain(exponents, stiffnesses, v0=0.3, run=None, boundary=None):
    """A brass chain of len(exponents) + 1 beads whose [contact] lists give each contact its n and K."""
    d = {
        "chain": {"beads": len(exponents) + 1, "radius": RADIUS, "material": "brass"},
        "contact": {"law": "power", "exponent": list(exponents), "stiffness": list(stiffnesses)},
        "loading": {"kind": "velocity", "velocity": v0},
        "run": run or {"end_time": 4e-4, "timestep": "auto"},
        "outputs": {"peak_force": True},
    }
    if boundary:
        d["boundary"] = boundary
    return scene_from_dict(d, source="listed.toml")


def check_against_dop853(exponents, backend, v0=0.3, past_half=True):
    ks = [stiffness_for(n, RADIUS) for n in exponents]
    sc = listed_chain(exponents, ks, v0)
    sol = run_scene(sc, backend=backend, rtol=RTOL).solution
    expected = independent_peaks(sc.mass, np.array(ks), np.asarray(exponents, dtype=float), v0, sc.run.end_time)
    # the contacts the wave reached (a far one's force is round-off against the first's)
    reached = expected > 1e-3 * expected[0]
    assert reached[len(exponents) // 2 :].any() or not past_half  # past the interface
    np.testing.assert_allclose(sol.peak_force[reached], expected[reached], rtol=RTOL)


@pytest.mark.parametrize("backend", ["reference", "lammps"])
def test_an_interface_in_n_given_in_the_scene_against_an_independent_solver(backend):
    """n = 1.5 for the first half of the contacts, 2.5 for the rest (Kekic and Van Gorder's interface),
    K of each its own: peak forces within the run's rtol of DOP853 (before: 'exponent = [...]' refused)."""
    check_against_dop853([1.5] * 5 + [2.5] * 5, backend)


@settings(max_examples=6, deadline=None, suppress_health_check=list(HealthCheck))
@given(exponents=st.lists(st.floats(1.0, 3.0), min_size=2, max_size=7))
def test_random_n_per_contact_on_the_reference_against_an_independent_solver(exponents):
    check_against_dop853(exponents, "reference", past_half=False)


@settings(max_examples=2, deadline=None, suppress_health_check=list(HealthCheck))
@given(exponents=st.lists(st.floats(1.0, 3.0), min_size=2, max_size=7))
def test_random_n_per_contact_on_lammps_against_an_independent_solver(exponents):
    check_against_dop853(exponents, "lammps", past_half=False)


@pytest.mark.parametrize("far_end", ["free", "wall"])
@settings(max_examples=3, deadline=None, suppress_health_check=list(HealthCheck))
@given(exponents=st.lists(st.sampled_from([1.0, 1.5, 2.0, 2.5, 3.0]), min_size=3, max_size=8))
def test_per_contact_lammps_equals_the_reference_verlet_step_for_step(far_end, exponents):
    """Per-contact n and K through LAMMPS's atom types (Scene.bead_kinds: a pair of types tells its
    contact) and the reference's per-contact law, with a wall that takes the last contact's n and K: as
    tests/test_effect_combinations.py holds every law, peaks to 1e-9 and velocities to 1e-8 of the
    largest (LAMMPS's absolute positions round a stiff n = 3 contact's overlap: 2e-9 seen)."""
    ks = [stiffness_for(n, RADIUS) * (1.0 + 0.1 * i) for i, n in enumerate(exponents)]
    sc = listed_chain(exponents, ks, run={"end_time": 1e-4, "timestep": 2e-8}, boundary={"far_end": far_end})
    if far_end == "wall":
        assert (float(sc.wall_law.exponent), float(sc.wall_law.k)) == (exponents[-1], ks[-1])
    lam = run_scene(sc, backend="lammps").solution
    ver = run_scene(sc, backend="reference", method="verlet").solution
    assert np.max(np.abs(lam.peak_force - ver.peak_force)) <= 1e-9 * np.max(ver.peak_force)
    assert np.max(np.abs(lam.velocity - ver.velocity)) <= 1e-8 * np.max(np.abs(ver.velocity))
    if far_end == "wall":
        assert abs(lam.wall_peak_force - ver.wall_peak_force) <= 1e-9 * np.max(ver.peak_force)


def test_uniform_lists_are_the_plain_chain_and_lists_round_trip():
    plain = two_beads(2.0, 1e12, 0.3, run={"end_time": 1e-4, "timestep": 1e-8})
    listed = scene_from_dict(
        {**scene_to_dict(plain), "contact": {"law": "power", "exponent": [2.0], "stiffness": [1e12]}}, "x"
    )
    assert listed.contact == plain.contact
    sc = listed_chain([1.5, 2.5, 2.0], [1e10, 2e12, 3e11])
    assert sc.per_bead
    assert [float(law.exponent) for law in sc.contact_laws] == [1.5, 2.5, 2.0]
    assert [float(law.k) for law in sc.contact_laws] == [1e10, 2e12, 3e11]
    assert scene_from_dict(scene_to_dict(sc), "listed.toml") == sc


@pytest.mark.parametrize(
    ("contact", "beads", "match"),
    [
        (
            {"exponent": [1.5, 2.5], "stiffness": 1e10},
            4,
            r"\[contact\] exponent = \[1.5, 2.5\] is invalid: a list of 3 ",
        ),
        ({"exponent": 1.5, "stiffness": [1e10] * 4}, 4, r"\[contact\] stiffness = .* is invalid: a list of 3 values"),
        ({"exponent": [1.5, 3.5, 2.0], "stiffness": 1e10}, 4, r"\[contact\] exponent\[2\] = 3.5 is invalid"),
        ({"exponent": [1.5, "x", 2.0], "stiffness": 1e10}, 4, r"\[contact\] exponent\[2\] = 'x' is invalid"),
        ({"exponent": [1.5, 2.0], "stiffness": 1e10}, "auto", r'needs a given \[chain\] beads = N \(not "auto"\)'),
    ],
)
def test_a_wrong_list_is_one_clear_error_naming_the_key_and_the_length(contact, beads, match):
    d = {
        "chain": {"beads": beads, "radius": RADIUS, "material": "brass"},
        "contact": {"law": "power", **contact},
        "loading": {"kind": "velocity", "velocity": 0.3},
        "run": {"end_time": 1e-4, "timestep": 1e-8},
    }
    with pytest.raises(SceneError, match=match):
        scene_from_dict(d, source="bad.toml")


# ---- the planner's and the regimes' estimates read the law's exponent (issue 41: not Hertz's 3/2)
def power_scene(n, k, loading, beads=20):
    return scene_from_dict(
        {
            "chain": {"beads": beads, "radius": RADIUS, "material": "brass"},
            "contact": {"law": "power", "exponent": n, "stiffness": k},
            "loading": loading,
            "run": {"end_time": 1e-3, "timestep": 1e-8},
        },
        source="power.toml",
    )


@settings(max_examples=30, deadline=None)
@given(n=st.floats(1.0, 3.0), factor=st.floats(0.1, 10.0), v=st.floats(0.05, 2.0))
def test_a_strikers_step_equivalent_is_the_power_chains_piston(n, factor, v):
    """A striker at V pushes like the step A whose front (Eq. 19 on F = K alpha^n: c^2 = D^2 (A / alpha_A)
    / m, alpha_A = (A/K)^(1/n) the static overlap) moves the beads at V (Eq. 12: V = D A / (m c)).
    Before: Hertz's c ~ A^(1/6) K^(1/3) for every n (at n = 2.5 A was off by 10^2-10^4)."""
    from granchain.physics.estimates import step_equivalent

    k = stiffness_for(n, RADIUS) * factor
    sc = power_scene(n, k, {"kind": "striker", "velocity": v, "radius": RADIUS, "material": "brass"})
    a, duration = step_equivalent(sc)
    c = sc.diameter * math.sqrt(a / (a / k) ** (1.0 / n) / sc.mass)
    assert sc.diameter * a / (sc.mass * c) == pytest.approx(v, rel=1e-9)
    assert duration == pytest.approx(sc.striker_mass * v / a, rel=1e-12)


def contact_time_by_dop853(k, n, m_star, v):
    """Two bodies meeting at v under m* delta'' = -K delta^n: the time until they part (delta = 0)."""

    def apart(_, y):
        return y[0]

    apart.terminal, apart.direction = True, -1
    big = 100.0 * (m_star * v**2 / k) ** (1.0 / (n + 1.0)) / v
    sol = solve_ivp(
        lambda _, y: (y[1], -k * max(y[0], 0.0) ** n / m_star),
        (0.0, big),
        (0.0, v),
        method="DOP853",
        rtol=1e-12,
        atol=1e-30,
        events=apart,
        first_step=big * 1e-9,
    )
    return float(sol.t_events[0][-1])


@pytest.mark.parametrize("n", [1.0, 2.5, 3.0])
def test_a_power_chains_loading_regime_is_told_from_its_own_contact_time(n):
    """A step A over T on a power chain is short below 0.1 and long above 10 contact times t_c, t_c the
    two-body impact at the beads' speed behind the front (Eq. 12 with Eq. 19 on F = K alpha^n). Before:
    Eq. 8's Hertz T_c of the brass's E* and R*, whatever K and n (K 100x Hertz's: a short load was 'long')."""
    from granchain.physics.loading_regime import loading_regime

    k, a = 100.0 * stiffness_for(n, RADIUS), 20.0
    base = power_scene(n, k, {"kind": "step", "amplitude": a, "duration": 1e-6})
    c = base.diameter * math.sqrt(a / (a / k) ** (1.0 / n) / base.mass)
    t_c = contact_time_by_dop853(k, n, base.mass / 2.0, base.diameter * a / (base.mass * c))
    for fraction, regime in ((0.05, "short"), (0.5, "transition"), (20.0, "long")):
        sc = power_scene(n, k, {"kind": "step", "amplitude": a, "duration": fraction * t_c})
        got = loading_regime(sc)
        assert got.regime == regime
        assert got.ratio == pytest.approx(fraction, rel=1e-6)


# ---- Nesterenko's wave speed on F = K alpha^n (issue 41 item 3: the power law's speed model)
def kicked_chain(n, v, beads=40):
    return scene_from_dict(
        {
            "chain": {"beads": beads, "radius": RADIUS, "material": "brass"},
            "contact": {"law": "power", "exponent": n, "stiffness": stiffness_for(n, RADIUS)},
            "loading": {"kind": "velocity", "velocity": v},
            "run": {"end_time": "auto", "timestep": "auto"},
        },
        source="long.toml",
    )


@pytest.mark.parametrize("n", [2.0, 2.5])
def test_the_measured_wave_speed_scales_as_nesterenkos_f_to_the_n_minus_1_over_2n(n):
    """A long uniform power chain kicked at two speeds: the measured front speeds' ratio is the ratio of
    the measured leading peaks to the power (n-1)/(2n) (Hertz's 1/6 would be 1.47 where this is 2.15
    at n = 2), and so is the law's model at those peaks (measured_models, `compare`'s wave speed), whose
    long-wave constant sqrt(2/(n+1)) is below the discrete chain's (measured 3.5% at n = 2, 6% at 2.5)."""
    runs = []
    for v in (0.1, 1.0):
        sc = kicked_chain(n, v)
        obs = run_scene(sc, backend="reference", rtol=RTOL).observables()
        runs.append((obs["wave_speed"], obs["leading_peak_force"], PowerLaw.measured_models(sc, {}, obs)))
    (v1, f1, m1), (v2, f2, m2) = runs
    scaling = (f2 / f1) ** ((n - 1.0) / (2.0 * n))
    assert v2 / v1 == pytest.approx(scaling, rel=RTOL)
    assert m2["power_wave_speed"] / m1["power_wave_speed"] == pytest.approx(scaling, rel=1e-12)
    assert 0.9 * v1 < m1["power_wave_speed"] < v1
    assert "power_wave_speed" in PowerLaw.model_domains


def test_predict_gives_the_power_chains_wave_speed_and_at_n_1_the_sound_speed():
    """`granchain predict` on a kicked power chain: Nesterenko's speed at the first contact's impact
    force with its domain (n > 1); at n = 1 the linear chain's sound speed D sqrt(K/m), no division by
    n - 1, and the domain says there is no solitary wave."""
    from granchain.physics import models
    from granchain.physics.predictions import predict

    for n in (1.0, 2.0):
        sc = kicked_chain(n, 0.5)
        (p,) = [p for p in predict(sc) if p.name == "power_wave_speed_at_impact"]
        assert p.applies
        assert "n > 1" in p.valid
        force = power_impact(float(sc.law.k), n, sc.mass / 2.0, 0.5)["peak_force"]
        expected = math.sqrt(2.0 / (n + 1.0)) * sc.diameter * (float(sc.law.k) / sc.mass) ** 0.5
        expected *= (force / float(sc.law.k)) ** ((n - 1.0) / (2.0 * n))
        assert p.value == pytest.approx(expected, rel=1e-12)
        if n == 1.0:
            assert p.value == pytest.approx(models.linear_sound_speed(float(sc.law.k), sc.mass, sc.diameter), rel=1e-12)
            assert "sound speed" in p.equation


@pytest.mark.parametrize("setup", ["precompressed on a wall", "striker"])
def test_per_contact_lists_with_a_precompression_or_a_striker_agree_step_for_step(setup):
    """The static state of a precompressed list chain (each contact's overlap under F0 from its own n
    and K, the wall's from the last contact's) and a striker's contact (contact 1's n and K) are the
    same on both backends (peaks to 1e-9, velocities to 1e-8 of the largest)."""
    exponents = [1.5, 2.0, 2.5, 1.2, 3.0]
    ks = [stiffness_for(n, RADIUS) for n in exponents]
    wall = setup != "striker"
    d = scene_to_dict(
        listed_chain(
            exponents, ks, run={"end_time": 1e-4, "timestep": 2e-8}, boundary={"far_end": "wall"} if wall else None
        )
    )
    if wall:
        d["precompression"] = {"force": 5.0}
    else:
        d["loading"] = {"kind": "striker", "velocity": 0.3, "radius": RADIUS, "material": "brass"}
    sc = scene_from_dict(d, "listed.toml")
    law = sc.wall_law if wall else sc.striker_law
    assert (float(law.exponent), float(law.k)) == ((exponents[-1], ks[-1]) if wall else (exponents[0], ks[0]))
    lam = run_scene(sc, backend="lammps").solution
    ver = run_scene(sc, backend="reference", method="verlet").solution
    assert np.max(np.abs(lam.peak_force - ver.peak_force)) <= 1e-9 * np.max(ver.peak_force)
    assert np.max(np.abs(lam.velocity - ver.velocity)) <= 1e-8 * np.max(np.abs(ver.velocity))
