"""An independent oracle for the tests: a linear mass-spring chain with optional dashpots.

Written from the equations of motion only (numpy; no granchain code): beads 0 .. n-1 of masses m_j,
spring j (stiffness k_j) and dashpot j (c_j) between beads j and j+1, optional springs and dashpots
from bead 0 and bead n-1 to fixed walls, or a ring (spring n-1 joins bead n-1 to bead 0). With u_j the
displacements,

    M u'' + C u' + K u = f(t),

K and C the tridiagonal (on a ring, cyclic) matrices of the springs and dashpots (C plus a
diagonal of dashpots to the ground, if any). Driven by
f(t) = Re(F exp(i w t)), the steady state is u(t) = Re(U exp(i w t)) with (K - w^2 M + i w C) U = F
(any vibrations text, e.g. Meirovitch, *Fundamentals of Vibrations*, 2001, sec. 7.12).
"""

from __future__ import annotations

import numpy as np


def matrices(
    masses, springs, dashpots=None, walls=(0.0, 0.0), wall_dashpots=(0.0, 0.0), ground_dashpots=None, ring=False
):
    """(M, K, C) of a chain: `springs` (and `dashpots`) has n - 1 entries for a chain, n for a ring
    (entry j joins bead j and bead (j + 1) mod n); `walls` are springs from bead 0 and from bead n-1
    to fixed walls, `wall_dashpots` their dashpots (chains only); `ground_dashpots` one dashpot per
    bead to the ground (a viscous medium around the beads), or None."""
    m = np.asarray(masses, dtype=float)
    n = m.size
    k = np.asarray(springs, dtype=float)
    c = np.zeros_like(k) if dashpots is None else np.asarray(dashpots, dtype=float)
    if k.size != (n if ring else n - 1) or c.shape != k.shape:
        raise ValueError(f"{k.size} springs for {n} beads ({'ring' if ring else 'chain'})")
    stiffness, damping = np.zeros((n, n)), np.zeros((n, n))
    for j in range(k.size):
        a, b = j, (j + 1) % n
        for mat, value in ((stiffness, k[j]), (damping, c[j])):
            mat[a, a] += value
            mat[b, b] += value
            mat[a, b] -= value
            mat[b, a] -= value
    if not ring:
        stiffness[0, 0] += walls[0]
        stiffness[-1, -1] += walls[1]
        damping[0, 0] += wall_dashpots[0]
        damping[-1, -1] += wall_dashpots[1]
    if ground_dashpots is not None:
        damping += np.diag(np.asarray(ground_dashpots, dtype=float))
    return np.diag(m), stiffness, damping


def steady_state(masses, springs, omega, force, **chain) -> np.ndarray:
    """The complex amplitudes U of the steady response to f(t) = Re(force exp(i omega t)): the solution
    of (K - omega^2 M + i omega C) U = force (force: one complex amplitude per bead); `chain` as in
    matrices (dashpots, walls, wall_dashpots)."""
    mass, stiffness, damping = matrices(masses, springs, **chain)
    dynamic = stiffness - omega**2 * mass + 1j * omega * damping
    return np.linalg.solve(dynamic, np.asarray(force, dtype=complex))


def state_matrix(masses, springs, **chain) -> np.ndarray:
    """The first-order system's matrix A of y = (u, u'): y' = A y + (0, M^-1 f(t))."""
    mass, stiffness, damping = matrices(masses, springs, **chain)
    n = mass.shape[0]
    inv = np.diag(1.0 / np.diag(mass))
    return np.block([[np.zeros((n, n)), np.eye(n)], [-inv @ stiffness, -inv @ damping]])
