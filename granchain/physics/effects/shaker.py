"""A shaker's driver ([loading] kind = "shaker", granchain.physics.shaker) as the deck and the planner see it.

The driver is a body in front of bead 1, as a striker is: its own atom (ID 1, the ``driver`` atom type) and
its contact with bead 1 (a rigid flat: Scene.driver_law), integrated by the deck's velocity Verlet with its
contact force removed and its prescribed acceleration applied instead (templates/loading_shaker.lmp.j2).
A kind of load, not a scene section: ``[loading]`` declares it, so it is not in the effect registry (whose
every subset goes with every other, and whose load is the tests' velocity kick); active_effects lists it
after the registered effects where a scene declares it. The reference integrates the driver as the extra
bead 0 of ChainProblem.with_ends.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from typing_extensions import override

from granchain.physics import materials as mat
from granchain.physics.effects.base import Bounds, Effect, watched_force

#: the driver atom's mass, in bead 1's: its kinetic energy (LAMMPS's thermo ke counts every atom) stays
#: at round-off; its motion does not depend on it (its force is its mass times the prescribed acceleration)
DRIVER_MASS_FRACTION = 1e-15


class ShakerEffect(Effect):
    """A rigid flat driver against bead 1 whose position is prescribed (granchain.physics.shaker)."""

    name = "shaker"
    label = 'a shaker ([loading] kind = "shaker")'
    beads_in_front = 1
    atom_type = "driver"
    conserves_momentum = False

    @classmethod
    @override
    def active(cls, scene) -> bool:
        return scene.loading.kind == "shaker"

    @classmethod
    @override
    def in_problem(cls, problem) -> bool:
        return bool(problem.shaker)

    @classmethod
    @override
    def end_bounds(cls, scene, b: Bounds) -> None:
        # a neighbour of infinite mass on bead 1 (the wall's bound, mirrored): F0 and the driver's force
        held = float(watched_force(scene.driver_law, b.radius[0]))
        f = min(b.static_force + 2.0 * max(b.force - b.static_force, scene.drive_amplitude), held)
        kd = float(np.asarray(scene.driver_law.tangent_stiffness(f), dtype=float))
        b.kl[0], b.ml[0], b.gl[0] = kd, np.inf, b.viscous(kd)
        b.extra["driver"] = kd

    @classmethod
    @override
    def data_atoms(cls, scene, types: dict[str, int], x: np.ndarray) -> list[tuple[int, float, float, float]]:
        # the flat at bead 1's surface (x: bead 1 where the data file puts it), pressed into it by the
        # driver's static overlap under precompression; else touching with no overlap in LAMMPS's arithmetic
        r1, x1 = float(scene.bead_radii[0]), float(x[0])
        f0 = float(scene.effects.precompression)
        alpha0 = float(np.asarray(scene.driver_law.static_overlap(f0), dtype=float)) if f0 else 0.0
        xd = x1 - (r1 - alpha0)
        while not alpha0 and x1 - xd < r1:
            xd = np.nextafter(xd, -np.inf)
        m1 = float(scene.bead_masses[0]) if scene.per_bead else float(scene.mass)
        rho = DRIVER_MASS_FRACTION * m1 / (np.pi * (2.0 * r1) ** 3 / 6.0)
        return [(types["driver"], 2.0 * r1, rho, float(xd))]

    @classmethod
    @override
    def pair_coeffs(cls, scene, types: dict[str, int]) -> list[tuple[int, int, Any, float]]:
        # contact distance: bead centre to the flat, R; only bead 1's kind meets it, LAMMPS needs every pair
        td = types["driver"]
        kinds, _ = scene.bead_kinds
        pairs = []
        for k, (r, m) in enumerate(kinds):
            e_star, r_star, materials = mat.wall_contact_pair(m, r, None, None)
            pairs.append((k + 1, td, scene.pair_law(e_star, r_star, materials, 0), r))
        r1 = float(scene.bead_radii[0])
        pairs.append((td, td, scene.driver_law, r1))
        if "wall" in types:  # driver and wall never meet, but their coefficients are required
            pairs.append((types["wall"], td, scene.driver_law, r1))
        return pairs


#: the loads that are effects of their own but not registered (see the module docstring)
LOAD_EFFECTS: tuple[type[Effect], ...] = (ShakerEffect,)
