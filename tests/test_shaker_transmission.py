"""The shaker's spectral observables against the linearised chain's exact steady state (issue 46 item 1).

A precompressed brass chain of N = 5 beads, free far end (held by the pull F0), a dashpot gamma on every
contact, shaken by a rigid flat at 1e-3 F0 / k_d in the pass band (5 kHz, a third of the cutoff). Linearised
about F0 each bead-bead contact is a spring k = (3/2) K^(2/3) F0^(1/3) (K = (4/3) E* sqrt(R*)), the driver's
contact a spring k_d of the same form on a rigid flat (E* = E / (1 - nu^2), R* = R), each in parallel with
the dashpot. The driver's displacement X = A exp(i w t) acts on bead 1 as a wall spring k_d + i w gamma from
bead 1 to ground and a force (k_d + i w gamma) X on bead 1 (tests/linear_chain.py's walls, written out for a
displacement drive here): U solves (K - w^2 M + i w C) U = F; the driver's contact force is
(k_d + i w gamma)(X - U_1), the far end's (k + i w gamma)(U_(N-1) - U_N). The transmission of a displacement
drive is the far end's force amplitude over the driver's contact's (docs/observables.md).

Tolerance 1e-4 (RK4 at dt = 5e-7 s), the force drive's test's (tests/test_spectral_observables.py): the
step's error (omega_max dt)^4 ~ 5e-6, Hertz's nonlinearity O((A k_d / F0)^2) = 1e-6, the transient down by
1e-5 at the window's start.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from granchain.scene import parse_scene
from granchain.workflows.run import run_scene
from tests.linear_chain import state_matrix, steady_state

E, NU, RHO, R = 115e9, 0.3, 8500.0, 4.76e-3  # the scene's "brass"
N, F0, GAMMA, FREQUENCY = 5, 10.0, 100.0, 5000.0


def linear_springs() -> tuple[float, float, float]:
    """(k, k_d, m): the bead-bead and the driver-bead Hertz contacts' tangents at F0, a bead's mass."""
    e_pair = E / (2 * (1 - NU**2))
    hertz, flat = 4 / 3 * e_pair * math.sqrt(R / 2), 4 / 3 * (2 * e_pair) * math.sqrt(R)
    tangent = [1.5 * c ** (2 / 3) * F0 ** (1 / 3) for c in (hertz, flat)]
    return tangent[0], tangent[1], RHO * 4 / 3 * math.pi * R**3


def amplitude() -> float:
    """The shaker's A: a driver contact's dynamic force about 1e-3 F0 (k_d A)."""
    return 1e-3 * F0 / linear_springs()[1]


def chain_args() -> dict:
    k, kd, m = linear_springs()
    return dict(dashpots=[GAMMA] * (N - 1), walls=(kd, 0.0), wall_dashpots=(GAMMA, 0.0))


def drive_cycles() -> int:
    """Cycles enough that the lock-in's window (the second half after the ramp) starts once the slowest
    transient of the linearised chain (the driver's spring to ground included) has decayed by 1e-5."""
    k, kd, m = linear_springs()
    ev = np.linalg.eigvals(state_matrix([m] * N, [k] * (N - 1), **chain_args())).real
    settle = math.log(1e5) / -np.max(ev)
    return math.ceil(2 + 2 * settle * FREQUENCY + 2)


def exact_forces() -> tuple[float, float]:
    """(|driver's contact force|, |far end's force|) of the linearised chain's exact steady state."""
    k, kd, m = linear_springs()
    w = 2 * math.pi * FREQUENCY
    x = amplitude()
    force = np.zeros(N, dtype=complex)
    force[0] = (kd + 1j * w * GAMMA) * x
    u = steady_state([m] * N, [k] * (N - 1), w, force, **chain_args())
    return abs((kd + 1j * w * GAMMA) * (x - u[0])), abs((k + 1j * w * GAMMA) * (u[-2] - u[-1]))


def shaken_text(timestep: float, cycles: int) -> str:
    return f"""[chain]
beads = {N}
radius = {R}
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "shaker"
amplitude = {amplitude()!r}
frequency = {FREQUENCY}
cycles = {cycles}
ramp = 2
[precompression]
force = {F0}
[damping]
dashpot = {GAMMA}
[run]
end_time = {cycles / FREQUENCY}
timestep = {timestep}
"""


@pytest.mark.slow
@pytest.mark.parametrize(
    ("backend", "method", "timestep", "rtol"),
    [("reference", "rk4", 5e-7, 1e-4), ("lammps", None, 5e-8, 1e-3)],
    ids=["reference-rk4", "lammps"],
)
def test_a_shaken_chains_transmission_is_the_linear_chains_exact_steady_state(backend, method, timestep, rtol):
    scene = parse_scene(shaken_text(timestep, drive_cycles()), source="shaken.toml")
    result = run_scene(scene, backend=backend, method=method)
    o = result.observables()
    drive, far = exact_forces()
    print(f"{backend}: drive {o['drive_amplitude']:.8g} vs {drive:.8g}, far {o['far_end_amplitude']:.8g} vs {far:.8g}")
    assert o["drive_amplitude"] == pytest.approx(drive, rel=rtol)
    assert o["far_end_amplitude"] == pytest.approx(far, rel=rtol)
    assert o["transmission"] == pytest.approx(far / drive, rel=rtol)
    assert 0 < o["transmission_error"] < rtol * far / drive
