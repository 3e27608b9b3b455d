"""The shaker ([loading] kind = "shaker") against an independent solver (issue 46 item 1).

The yardstick is written here, not granchain's: the chain's equations of motion from the material's
constants (Hertz's k = 4/3 E* sqrt(R*), a bead on a rigid flat E* = E / (1 - nu^2), R* = R) or the power
law's own k and n, with the driver's flat at the prescribed x_d(t) = x_d0 + A sin(2 pi f t) r(t)
(r = sin^2(pi t / (2 t_r)) until t_r, then 1; the driver stops at T and holds) touching bead 1 through
the same law, a dashpot max(F + gamma d(alpha)/dt, 0) on every contact while it overlaps, integrated by
scipy's DOP853 at rtol 1e-12. Every recorded contact's force history (the driver's contact included) must
be the run's within the run's rtol of the largest dynamic force, on the planned step.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from granchain.scene import parse_scene
from granchain.workflows.run import calculate_scene

#: the run's relative tolerance (the planner's default rtol, which sets the planned step)
RTOL = 1e-3

BASE = """[chain]
beads = {beads}
radius = 4.76e-3
material = "brass"
[contact]
{contact}
[loading]
kind = "shaker"
amplitude = {amplitude!r}
frequency = {frequency!r}
cycles = {cycles!r}
ramp = {ramp!r}
[run]
end_time = "auto"
timestep = "auto"
"""

CASES = {
    # Hertz, uncompressed, on a wall, damped: the driver pushes for part of each period and leaves bead 1
    "hertz-dashpot-wall": dict(
        beads=6,
        contact='law = "hertz"',
        amplitude=3e-7,
        frequency=4000.0,
        cycles=3.0,
        ramp=1.0,
        extra='[boundary]\nfar_end = "wall"\n[damping]\ndashpot = 3.0\n',
    ),
    # a power law (n = 1.3), precompressed, free far end (held by the pull F0), no ramp: the driver
    # starts at A 2 pi f
    "power-precompressed-free": dict(
        beads=5,
        contact='law = "power"\nexponent = 1.3\nstiffness = 2e9',
        amplitude=2e-7,
        frequency=6000.0,
        cycles=2.5,
        ramp=0.0,
        extra="[precompression]\nforce = 5.0\n",
    ),
    # Hertz, precompressed on a wall, damped: the driver holds F0 and shakes about it
    "hertz-precompressed-dashpot": dict(
        beads=6,
        contact='law = "hertz"',
        amplitude=5e-8,
        frequency=5000.0,
        cycles=3.0,
        ramp=2.0,
        extra='[precompression]\nforce = 8.0\n[boundary]\nfar_end = "wall"\n[damping]\ndashpot = 2.0\n',
    ),
}


def case_scene(name: str):
    c = CASES[name]
    return parse_scene(BASE.format(**c) + c["extra"], source=f"{name}.toml")


def driver_position(t: float, a: float, f: float, t_r: float, t_end: float) -> tuple[float, float]:
    """x_d(t) - x_d0 and x_d'(t), written out (the driver holds at T)."""
    t = min(t, t_end)
    w = 2.0 * math.pi * f
    if t_r > 0.0 and t < t_r:
        h = 0.5 * math.pi / t_r
        r, r1 = math.sin(h * t) ** 2, h * math.sin(2.0 * h * t)
    else:
        r, r1 = 1.0, 0.0
    x = a * math.sin(w * t) * r
    v = a * (w * math.cos(w * t) * r + math.sin(w * t) * r1) if t < t_end else 0.0
    return x, v


def dop853_contact_forces(scene, times: np.ndarray) -> np.ndarray:
    """Every contact's force at `times` (rows: the driver's contact, contacts 1 .. N-1, a wall's)."""
    mat, r, n = scene.chain.material, float(scene.chain.radius), scene.chain.beads
    m = mat.density * 4.0 / 3.0 * math.pi * r**3
    if scene.contact.law == "hertz":
        e_pair = mat.youngs_modulus / (2.0 * (1.0 - mat.poisson_ratio**2))
        k_bead, k_flat, p = 4.0 / 3.0 * e_pair * math.sqrt(r / 2.0), 4.0 / 3.0 * 2.0 * e_pair * math.sqrt(r), 1.5
    else:
        k_bead = k_flat = float(scene.contact.coefficients.stiffness)
        p = float(scene.contact.coefficients.exponent)
    wall = scene.effects.far_end == "wall"
    f0 = float(scene.effects.precompression)
    gamma = float(scene.damping_coefficient) if scene.damping.name == "dashpot" else 0.0
    ks = np.array([k_flat] + [k_bead] * (n - 1) + ([k_flat] if wall else []))
    # the static state: every contact at F0 (the wall, or bead N's pull, holds the far end; bead N at 0
    # on a free chain), the driver's flat alpha0 ahead of bead 1
    alpha0 = (f0 / ks) ** (1.0 / p)
    u0 = np.zeros(n)
    u0[-1] = alpha0[-1] if wall else 0.0
    for i in range(n - 2, -1, -1):
        u0[i] = u0[i + 1] + alpha0[i + 1]
    xd0 = u0[0] + alpha0[0]
    ld = scene.loading
    t_r, t_end = ld.ramp_time, ld.duration

    def forces(t, u, v):
        xd, vd = driver_position(t, ld.amplitude, ld.frequency, t_r, t_end)
        left = np.concatenate(([xd0 + xd], u))
        vleft = np.concatenate(([vd], v))
        right, vright = (np.append(u, 0.0), np.append(v, 0.0)) if wall else (u, v)
        alpha = left[: right.size] - right
        rate = vleft[: right.size] - vright
        elastic = ks[: alpha.size] * np.clip(alpha, 0.0, None) ** p
        return np.where(alpha > 0.0, np.maximum(elastic + gamma * rate, 0.0), 0.0)

    def rhs(t, y):
        u, v = y[:n], y[n:]
        fc = forces(t, u, v)
        net = fc[:n] - (fc[1:] if wall else np.append(fc[1:], f0))
        return np.concatenate([v, net / m])

    y0 = np.concatenate([u0, np.zeros(n)])
    # absolute tolerances far below the drive's amplitude and its velocity A 2 pi f, above the round-off
    # of F0's differences (a static chain's accelerations are F0 x 1e-16 / m)
    atol = np.concatenate([np.full(n, 1e-8 * ld.amplitude), np.full(n, 1e-8 * ld.amplitude * ld.frequency)])
    # the drive's end is a kink of x_d: integrate up to it and on
    pieces, t0 = [], 0.0
    for t1 in sorted({min(t_end, float(times[-1])), float(times[-1])}):
        s = solve_ivp(rhs, (t0, t1), y0, method="DOP853", rtol=1e-12, atol=atol, dense_output=True)
        pieces.append((t0, t1, s.sol))
        y0, t0 = s.y[:, -1], t1
    out = []
    for t in times:
        sol = next(p for p in pieces if p[0] <= t <= p[1])[2]
        y = sol(t)
        out.append(forces(t, y[:n], y[n:]))
    return np.array(out).T


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("backend", ["reference", "lammps"])
def test_shaker_force_histories_are_dop853_s_within_the_run_s_rtol(case, backend):
    """Each contact's force history (the driver's, every bead-bead one) within RTOL of the largest
    dynamic force of DOP853's, on the planned step of the default method (Verlet with a dashpot)."""
    scene = case_scene(case)
    result = calculate_scene(scene, backend=backend, error_estimate=False).result
    sol = result.solution
    contacts = [int(c) for c in sol.history_contacts]
    assert contacts[0] == -1, contacts  # the driver's contact first
    assert contacts[1:] == list(range(scene.chain.beads - 1)), contacts
    t = np.asarray(sol.history_time, dtype=float)
    every = max(1, t.size // 1500)  # (DOP853's dense output at 1500 times of the record)
    t = t[::every]
    got = np.asarray(sol.history_force, dtype=float)[::every].T
    want = dop853_contact_forces(result.scene, t)[: len(contacts)]
    dynamic = np.max(np.abs(want - float(scene.effects.precompression)))
    error = float(np.max(np.abs(got - want))) / dynamic
    print(f"{case} {backend}: largest history error {error:.3g} of the largest dynamic force {dynamic:.4g} N")
    assert dynamic > 0.0
    assert error <= RTOL
