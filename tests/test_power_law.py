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
from granchain.scene import scene_from_dict
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
    """A chain of 6 beads under one exponent n (per-contact n is the reference's only: see docs/laws.md)."""
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
