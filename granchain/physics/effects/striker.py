"""A striker ([loading] kind = "striker"): a sphere of its own radius, material and mass hits bead 1
at a velocity instead of a force f(t). The [loading] section reads it (scene._read_loading).

For the solvers the striker is an extra first bead moving at the velocity; its contact with bead 1
has the pair's law (scene.striker_law: Johnson's E* and R* of striker and bead).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from typing_extensions import override

from granchain.physics.effects.base import Bounds, Effect, watched_force


class StrikerEffect(Effect):
    """A striker: a sphere of its own radius, material and mass that hits bead 1 at a velocity.

    The solvers integrate it as an extra bead in front of bead 1, moving at the load's velocity,
    whose contact with bead 1 has the law of that pair (``scene.striker_law``). The paper loads its
    chains with a force f(t) (Eq. 4); a striker is the experiments' load (the paper's Sec. II B
    recalls that a heavier striker makes a longer load and a wave train). The results report its
    contact's peak force and time and its final velocity (``striker_peak_force``,
    ``striker_time_of_peak``, ``striker_velocity``).

    Scene keys: none of its own; ``[loading] kind = "striker"`` declares it, with the striker's
    ``velocity`` and optional ``radius``, ``material`` and ``mass`` (default: a bead's radius and
    material, the mass from them); the [loading] reader validates them (``section`` is None).
    Deck block: none of its own; its load is the ``loading_striker.lmp.j2`` block, chosen by
    ``scene.loading.kind``; its atom is the ``striker`` atom type in front of bead 1.
    """

    name = "striker"
    label = "a striker"
    declaration = {"loading": {"kind": "striker", "velocity": 2.0}}
    deck_blocks = {}  # its load is the loading_striker block (scene.loading.kind)
    beads_in_front = 1
    atom_type = "striker"

    @classmethod
    @override
    def active(cls, scene) -> bool:
        return scene.loading.kind == "striker"

    @classmethod
    @override
    def in_problem(cls, problem) -> bool:
        # the problem as built from the scene: with_ends drops striker_mass (the striker is then the
        # chain's first bead), so this is False after it; the striker's forces are internal
        # (conserves_momentum), so no run watch needs it there
        return problem.striker_mass is not None

    @classmethod
    @override
    def problem_fields(cls, scene, fields: dict[str, Any]) -> None:
        fields.update(striker_mass=scene.striker_mass, striker_law=scene.striker_law)

    @classmethod
    @override
    def ends(cls, problem, parts: list, mass: np.ndarray) -> np.ndarray:
        if problem.striker_mass is None:
            return mass
        parts.insert(0, (problem.striker_law, 1))  # an extra bead in front, moving
        return np.concatenate(([problem.striker_mass], mass))

    @classmethod
    @override
    def end_fields(
        cls, force: np.ndarray, time: np.ndarray, velocity: np.ndarray, last: int, complete: np.ndarray
    ) -> dict[str, Any]:
        return {
            "striker_peak_force": float(force[0]),
            "striker_time_of_peak": float(time[0]),
            "striker_peak_complete": bool(complete[0]),
            "striker_velocity": float(velocity[0]),
        }

    @classmethod
    @override
    def end_bounds(cls, scene, b: Bounds) -> None:
        ms = scene.striker_mass
        smaller = min(float(scene.loading.striker_radius), float(b.radius[0]))
        f = min(b.force, float(watched_force(scene.striker_law, smaller)))  # (the run watch's bound)
        ks = float(np.asarray(scene.striker_law.tangent_stiffness(f), dtype=float))
        gamma = b.viscous(ks)
        b.kl[0], b.ml[0], b.gl[0] = ks, ms, gamma
        m0 = b.mass[0]
        b.extra["striker"] = ks / ms + ks / math.sqrt(ms * m0)
        b.extra["striker_damp"] = gamma / ms + gamma / math.sqrt(ms * m0)

    @classmethod
    @override
    def data_atoms(cls, scene, types: dict[str, int], x: np.ndarray) -> list[tuple[int, float, float, float]]:
        # touching bead 1 from the left with no overlap in LAMMPS's arithmetic (bead 1 where the data file
        # puts it: displaced under precompression), of the requested mass exactly
        rs = scene.loading.striker_radius
        ds = 2.0 * rs
        rho_s = scene.striker_mass / (math.pi * ds**3 / 6.0)
        x1, d = float(x[0]), rs + scene.chain.radius
        x = x1 - d
        while x1 - x < d:
            x = math.nextafter(x, -math.inf)
        return [(types["striker"], ds, rho_s, x)]

    @classmethod
    @override
    def pair_coeffs(cls, scene, types: dict[str, int]) -> list[tuple[int, int, Any, float]]:
        # only bead 1's kind meets the striker; LAMMPS needs every other kind's coefficients too
        ld, ts = scene.loading, types["striker"]
        rs, ms = ld.striker_radius, ld.striker_material
        kinds, kind_of = scene.bead_kinds
        pairs = [(k + 1, ts, scene.bead_pair_law(rs, ms, r, m), rs + r) for k, (r, m) in enumerate(kinds)]
        pairs.append((ts, ts, scene.striker_law, 2 * rs))
        if "wall" in types:  # striker and wall never meet, but their coefficients are required
            pairs.append((types["wall"], ts, scene.striker_law, rs))
        return pairs
