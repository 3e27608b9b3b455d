"""Sensor beads against an independent solver (issue 42's acceptance: "within the run's rtol on
contact, sensor and wall forces").

The yardstick is written here, not granchain's: a Hertz chain struck by a bead-sized striker on a rigid
flat wall, its equations of motion from the material's constants alone (Hertz's k = 4/3 E* sqrt(R*)),
each bead's weight m g toward the wall under gravity, integrated by scipy's DOP853 at rtol 1e-12 and read
on a fine grid of its dense output. A sensor bead reads (F_{i-1,i} + F_{i,i+1}) / 2 (bead 1: the striker's
contact is its left one; bead N: the wall's its right one); its dynamic peak (above its static force, the
average of its contacts' weights above) must be the planned run's within the run's rtol, on both
backends, with and without gravity.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from granchain.scene import parse_scene
from granchain.workflows.run import calculate_scene

#: the run's relative tolerance (the planner's default rtol, which sets the planned step)
RTOL = 1e-3
#: the sensor beads read: bead 1 (the striker's contact), two inside, bead N (the wall's contact)
SENSORS = (1, 4, 7, 10)


def scene_text(g: float) -> str:
    """Ten stainless beads on a wall struck by a bead-sized striker at 0.44 m/s (Daraio et al.'s
    setup, shortened), standing vertically under g (0: horizontal)."""
    text = f"""[chain]
beads = 10
radius = 2.38e-3
material = "stainless-steel-316"
[contact]
law = "hertz"
[loading]
kind = "striker"
velocity = 0.44
[run]
end_time = "auto"
timestep = "auto"
[boundary]
far_end = "wall"
[outputs]
peak_force = true
sensors = {list(SENSORS)}
"""
    return text + (f"[gravity]\ng = {g!r}\n" if g else "")


def dop853_sensor_peaks(scene, g: float, end: float) -> tuple[np.ndarray, np.ndarray]:
    """The sensor beads' dynamic peaks to `end` and their static forces, from DOP853."""
    mat = scene.chain.material
    r = float(scene.chain.radius)
    n = scene.chain.beads
    e_star = mat.youngs_modulus / (2.0 * (1.0 - mat.poisson_ratio**2))  # two like spheres
    k = 4.0 / 3.0 * e_star * np.sqrt(r / 2.0)  # R* = R / 2
    k_wall = 4.0 / 3.0 * (2.0 * e_star) * np.sqrt(r)  # a sphere on a rigid flat: E* = E / (1 - nu^2), R* = R
    m = np.full(n + 1, mat.density * 4.0 / 3.0 * np.pi * r**3)  # the striker (index 0), then beads 1..N
    weight = m * g  # the striker falls too: it touches bead 1 unloaded at t = 0, its weight not yet carried
    static = np.cumsum(weight[1:])  # bead i's right contact carries the weight of beads 1..i
    # the static state: each bead-bead overlap (static / k)^(2/3), the wall's (static_N / k_wall)^(2/3)
    overlap = np.append((static[:-1] / k) ** (2.0 / 3.0), (static[-1] / k_wall) ** (2.0 / 3.0))
    u0 = np.cumsum(overlap[::-1])[::-1]  # u_i toward the wall, the wall at 0

    def contacts(u):
        fc = k * np.clip(u[:-1] - u[1:], 0.0, None) ** 1.5  # striker-bead 1, bead 1-2, ..., N-1-N
        return np.concatenate([fc, k_wall * np.clip(u[-1:], 0.0, None) ** 1.5])  # the wall's last

    def rhs(_, y):
        u, v = y[: n + 1], y[n + 1 :]
        f = contacts(u)
        net = weight - f + np.concatenate([[0.0], f[:-1]])
        return np.concatenate([v, net / m])

    y0 = np.concatenate(([u0[0]], u0, [scene.loading.velocity], np.zeros(n)))
    sol = solve_ivp(lambda t, y: rhs(t, y), (0.0, end), y0, method="DOP853", rtol=1e-12, atol=1e-20, dense_output=True)
    t = np.linspace(0.0, end, 400_001)
    f = contacts(sol.sol(t)[: n + 1])  # (N + 1, T): contact j between body j and j + 1
    beads = np.asarray(SENSORS)
    sensor = 0.5 * f[beads - 1] + 0.5 * f[beads]  # bead i's contacts: j = i - 1 (left) and i (right)
    f_static = np.concatenate([[0.0], static])
    rest = 0.5 * f_static[beads - 1] + 0.5 * f_static[beads]
    return sensor.max(axis=1) - rest, rest


@pytest.mark.parametrize("backend", ["reference", "lammps"])
@pytest.mark.parametrize("g", [0.0, 9.81])
def test_sensor_peaks_are_dop853_s_within_the_run_s_rtol(backend, g):
    """Every sensor bead's dynamic peak (bead 1 and bead N with the striker's and the wall's contact)
    within the run's rtol of DOP853's, on the planned step, with and without gravity; the static
    forces are the oracle's too. Measured: the runs are within 1.5e-6 (bead 1) to 1.1e-5 (bead N) of
    DOP853 with or without gravity; gravity moves the oracle's peaks at beads 1, 4, 7 by 0.27%, 0.52%,
    0.70% (above the rtol), bead N's by 0.02%. An oracle whose striker had no weight was 2.5e-4 off."""
    scene = parse_scene(scene_text(g), source="sensors.toml")
    result = calculate_scene(scene, backend=backend, method="verlet", error_estimate=False).result
    sol = result.solution
    assert tuple(sol.sensor_beads) == SENSORS
    want, rest = dop853_sensor_peaks(result.scene, g, sol.end_time)
    got = np.asarray(sol.sensor_peak_force) - rest
    assert np.asarray(sol.sensor_complete).all(), sol.sensor_complete
    np.testing.assert_allclose(got, want, rtol=RTOL)
    # summary.json's sensor peaks are the same dynamic numbers (above the same static forces)
    sensors = result.summary["sensors"]
    np.testing.assert_allclose(sensors["static_force"], rest, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(sensors["sensor_peak_force"], want, rtol=RTOL)
