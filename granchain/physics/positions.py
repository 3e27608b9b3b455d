"""Where a chain's beads sit at t = 0 so that LAMMPS sees exactly what the reference solver does.

The reference solver works on displacements: an at-rest contact has overlap exactly 0. LAMMPS works on
positions read from the data file, where round-off made a third or more of the at-rest pairs overlap
by an ulp. contact_quantum puts contact radii and positions on a grid where the sums are exact;
touching_positions places a body whose contact distance is not on the grid (a wall) just clear of
touching. Used by granchain.scene (Scene.bead_positions, Scene.contact_radius) and the wall effect.
"""

from __future__ import annotations

import math

import numpy as np


def contact_quantum(radii) -> float:
    """The grid of a chain's contact radii and positions (Scene.contact_radius, Scene.bead_positions): a
    power of two Q with every position of the chain (beads, a wall) below 2^53 Q, so that sums and
    differences of multiples of Q there are exact doubles.

    Why: LAMMPS evaluates a contact when fl(dx * dx) < fl(d0 * d0) (our pair styles: overlap d0 - |dx|,
    d0 from pair_coeff), dx the difference of the data file's positions (printed with repr: read back
    exactly). On x_i = (i-1) D rounded (or a running sum of R_i + R_(i+1)) 35-44% of the at-rest pairs
    of 1e3-1e5-bead chains overlapped by round-off (up to an ulp of x): LAMMPS evaluated about 0.44
    contacts per bead-step ahead of the wave front, with round-off forces and velocities (2e-19 m/s)
    where the reference solver (on displacements: no overlap at rest) has exactly zero. Radii rounded up
    to multiples of Q give contact distances and positions that are exact, so every at-rest overlap is
    exactly 0 (no contact evaluated, nothing ahead of the front moves) and no pair has a gap either (a
    gap of under an ulp at every contact delays the front systematically: measurable at 1e-9 of the
    peak forces 100 contacts on, where round-off overlaps of both signs cancelled). The loop time of the
    chain/hertz deck fell to 0.76-0.88x on 1e3-1e5 beads (benchmarks/bench_pair.py positions). The
    contact distance changes by under 2 Q (Q = 4.4e-16 m for a 2 m chain), the forces not at all: they
    depend on the overlap only; masses and stiffnesses keep the scene's radii.
    """
    r = np.asarray(radii, dtype=float)
    extent = 2.0 * float(np.sum(r)) + 4.0 * float(np.max(r))  # beads, a wall, precompression: all below
    return math.ldexp(1.0, math.frexp(extent)[1] - 53)


def touching_positions(distances, start: float = 0.0) -> np.ndarray:
    """Centres of bodies meant to touch with zero force where the contact distance cannot be put on a
    grid (a wall's R): x_0 = start, then each x_(i+1) the smallest double at or above x_i + distances[i]
    with fl(x_(i+1) - x_i) >= distances[i] (so fl((x_(i+1) - x_i)^2) >= fl(distances[i]^2): rounding
    is monotonic): no overlap in LAMMPS's arithmetic, a gap under an ulp of x (see contact_quantum)."""
    x = float(start)
    out = [x]
    for d in np.asarray(distances, dtype=float).tolist():
        y = x + d
        while y - x < d:
            y = math.nextafter(y, math.inf)
        out.append(y)
        x = y
    return np.array(out)
