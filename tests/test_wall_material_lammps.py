"""LAMMPS's chains on walls of a material against a solver written here (scipy's DOP853), issue 41's
acceptance: stainless Hertz chains on walls of PTFE, aluminium and steel, flat or curved, run with the
planner's step for an rtol; every contact's peak force and the wall's within that rtol of DOP853's.

The solver is this file's own: the chain's Hertz constants from the materials' E and nu (the bead-bead
pair's E* and R*, the wall's 1/E* = (1-nu_b^2)/E_b + (1-nu_w^2)/E_w and 1/R* = 1/R + 1/R_w), not
granchain's law or problem; the peaks refined on its dense output. tests/test_wall_material.py holds
the reference backend's and one bead's closed form.
"""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from granchain.physics.materials import MATERIALS
from granchain.scene import parse_scene
from granchain.workflows.run import run_scene

#: the run's rtol: the planner chooses LAMMPS's step for it
RTOL = 1e-4
BEAD = "stainless-steel-316"


def pair_e_star(a, b) -> float:
    return 1.0 / ((1 - a.poisson_ratio**2) / a.youngs_modulus + (1 - b.poisson_ratio**2) / b.youngs_modulus)


def dop853_peaks(n, radius, velocity, wall, wall_radius, end_time):
    """Every contact's and the wall's peak force of a uniform stainless Hertz chain, bead 1 at
    `velocity`, bead N on a wall of material `wall` (flat: wall_radius None), by DOP853 at rtol 1e-12;
    each peak the largest of the dense output on a grid of 400001 times, refined by a parabola
    through its neighbours."""
    bead, w = MATERIALS[BEAD], MATERIALS[wall]
    m = bead.density * 4.0 / 3.0 * math.pi * radius**3
    kb = 4.0 / 3.0 * pair_e_star(bead, bead) * math.sqrt(radius / 2)
    r_wall = radius if wall_radius is None else radius * wall_radius / (radius + wall_radius)
    kw = 4.0 / 3.0 * pair_e_star(bead, w) * math.sqrt(r_wall)

    def rhs(_t, y):
        u, v = y[:n], y[n:]
        f = kb * np.maximum(u[:-1] - u[1:], 0.0) ** 1.5
        a = np.zeros(n)
        a[:-1] -= f
        a[1:] += f
        a[-1] -= kw * max(u[-1], 0.0) ** 1.5
        return np.concatenate((v, a / m))

    y0 = np.zeros(2 * n)
    y0[n] = velocity
    s = solve_ivp(rhs, (0, end_time), y0, method="DOP853", rtol=1e-12, atol=1e-18, dense_output=True)
    u = s.sol(np.linspace(0, end_time, 400001))[:n]
    forces = np.vstack((kb * np.maximum(u[:-1] - u[1:], 0.0) ** 1.5, kw * np.maximum(u[-1], 0.0) ** 1.5))
    return np.array([refined_max(f) for f in forces])


def refined_max(f: np.ndarray) -> float:
    """The largest sample of f refined by the parabola through it and its neighbours."""
    i = int(np.argmax(f))
    if i == 0 or i == f.size - 1:
        return float(f[i])
    a, b, c = f[i - 1], f[i], f[i + 1]
    curvature = a - 2 * b + c
    return float(b - 0.125 * (c - a) ** 2 / curvature) if curvature < 0 else float(b)


def walled_scene(n, radius, velocity, wall, wall_radius, end_time):
    """The chain of dop853_peaks as a scene: LAMMPS's step planned for RTOL ("auto")."""
    curved = "" if wall_radius is None else f"wall_radius = {wall_radius!r}\n"
    text = (
        f'[chain]\nbeads = {n}\nradius = {radius!r}\nmaterial = "{BEAD}"\n[contact]\nlaw = "hertz"\n'
        f'[loading]\nkind = "velocity"\nvelocity = {velocity!r}\n'
        f'[run]\nend_time = {end_time!r}\ntimestep = "auto"\n[outputs]\npeak_force = true\n'
        f'[boundary]\nfar_end = "wall"\nwall_material = "{wall}"\n{curved}'
    )
    return parse_scene(text, source="wall.toml")


@pytest.mark.slow
@pytest.mark.parametrize("wall", ["ptfe", "aluminium-6061-t6", "stainless-steel-316"])
@settings(max_examples=3, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(
    n=st.integers(2, 8),
    velocity=st.floats(0.1, 2.0),
    wall_radius=st.one_of(st.none(), st.floats(0.01, 0.5)),
)
def test_lammps_chains_on_walls_of_a_material_against_dop853(wall, n, velocity, wall_radius):
    """Stainless beads (R = 4 mm) on a wall of PTFE, aluminium or steel, flat or curved: LAMMPS at the
    planner's step for rtol 1e-4; every bead-bead contact's peak force and the wall's within the rtol
    of DOP853's, relative to the largest (a contact's peak in the tail of the wave is small)."""
    radius, end = 4e-3, 4e-4
    sc = walled_scene(n, radius, velocity, wall, wall_radius, end)
    sol = run_scene(sc, backend="lammps", rtol=RTOL).solution
    expected = dop853_peaks(n, radius, velocity, wall, wall_radius, end)
    got = np.append(sol.peak_force, sol.wall_peak_force)
    scale = float(np.max(expected))
    worst = float(np.max(np.abs(got - expected))) / scale
    print(f"{wall} n={n}: wall peak {got[-1]:.6g} vs {expected[-1]:.6g}; worst {worst:.1e} of the largest")
    assert worst <= RTOL
    assert got[-1] == pytest.approx(expected[-1], rel=RTOL)
