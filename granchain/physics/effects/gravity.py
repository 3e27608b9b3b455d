"""Gravity along a vertical chain ([gravity] g, m/s^2): bead 1 on top, the chain standing on the wall.

Every bead (a striker's too) carries its weight m_i g, a body force along the chain toward the wall,
so contact i (beads i and i+1) starts at the weight of the beads above it, F_i = g sum_(j<=i) m_j
(plus any [precompression] force F0), and the wall at the whole chain's weight (granchain.problem:
static_contact_forces, initial_state). Gravity is external: it does work (g times the moving beads'
mass-weighted displacement) and the chain's momentum is not conserved.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from typing_extensions import override

from granchain.physics.effects.base import Bounds, Effect

#: the largest g a scene takes, m/s^2 (a centrifuge's; beyond it a chain's weight is no longer a detail
#: of a stress wave but its own problem)
MAX_GRAVITY = 1e6


def static_profile(mass, f0: float, g: float) -> np.ndarray:
    """The static force of each contact of a chain of beads `mass` (n,) at rest on its far end, N (n-1,):
    contact i (beads i and i+1) carries F0 and the weight of beads 1..i, F0 + g sum_(j<=i) m_j (the
    last bead may be an immovable wall, mass inf: its contact carries the whole chain's weight)."""
    m = np.asarray(mass, dtype=float)[:-1]
    return float(f0) + float(g) * np.cumsum(m) if g else np.full(m.size, float(f0))


def scene_static_forces(scene) -> np.ndarray:
    """Each contact's static force at t = 0, N: the N-1 bead-bead contacts, then the wall's (with a
    wall): F0 plus the weight of the beads above it (static_profile; a striker's contact, not listed,
    starts unloaded)."""
    mass = np.asarray(scene.bead_masses if scene.per_bead else np.full(scene.chain.beads, scene.mass), dtype=float)
    if scene.effects.far_end == "wall":
        mass = np.append(mass, np.inf)
    return static_profile(mass, float(scene.effects.precompression), float(scene.effects.gravity))


class GravityEffect(Effect):
    """Gravity on a vertical chain: every bead's weight rests on the beads below it and on the wall.

    The chain stands on the far end's wall with bead 1 on top, where the load strikes; each bead
    carries its weight m_i g toward the wall for the whole run, and each contact starts in static
    equilibrium at its own static force, the weight above it (plus a precompression's F0), on its
    law's virgin curve (a law with history was loaded to it). Experiments on vertical chains
    (Daraio et al., PRE 72, 016603, 2005) see the wave speed grow with depth; at low striker speeds
    gravity is not a detail (granchain's notes: +26% in speed at 0.01 m/s on a 40-bead chain).

    Scene keys: ``[gravity] g`` in m/s^2 (positive, below MAX_GRAVITY); only with ``[boundary]
    far_end = "wall"``, the floor the chain stands on. Deck block: ``gravity.lmp.j2`` in the
    "forces" slot (fix gravity on the moving atoms; a law with history's alpha_max set to the
    static overlaps); the beads' positions in the data file are the static equilibrium.
    """

    name = "gravity"
    label = "[gravity]"
    declaration = {"gravity": {"g": 9.81}, "boundary": {"far_end": "wall"}}
    section = "gravity"
    scene_keys = ("g",)
    fields = {"gravity": 0.0}
    example = {"g": 9.81}
    invalid = {"g": (0.0, -9.81, "9.81", float("nan"), 2 * MAX_GRAVITY)}
    requires = ("wall",)  # the floor the chain stands on
    conserves_momentum = False
    deck_blocks = {"forces": "gravity.lmp.j2"}

    @classmethod
    @override
    def active(cls, scene) -> bool:
        return bool(scene.effects.gravity)

    @classmethod
    @override
    def in_problem(cls, problem) -> bool:
        return bool(problem.gravity)

    @classmethod
    @override
    def read(cls, section) -> dict[str, Any]:
        g = section.number(
            "g",
            low=0.0,
            high=MAX_GRAVITY,
            what="the acceleration of gravity in m/s^2 along the chain toward the wall (bead 1 on top; 9.81 on Earth)",
        )
        section.finish(cls.scene_keys)
        return {"gravity": g}

    @classmethod
    @override
    def to_dict(cls, effects) -> dict[str, Any] | None:
        return {"g": effects.gravity} if effects.gravity else None

    @classmethod
    @override
    def requirement(cls, scene) -> str | None:
        if scene.effects.far_end == "wall":
            return None
        return (
            f"[gravity] g = {scene.effects.gravity:g} m/s^2 stands the chain vertically on a floor, but "
            'its far end is free: add [boundary] far_end = "wall" (the wall under bead N carries the '
            "chain's weight), or remove [gravity]"
        )

    @classmethod
    @override
    def problem_fields(cls, scene, fields: dict[str, Any]) -> None:
        fields["gravity"] = scene.effects.gravity

    @classmethod
    @override
    def body_acceleration(cls, problem) -> float:
        return float(problem.gravity)

    @classmethod
    @override
    def chain_bounds(cls, scene, b: Bounds) -> None:
        # the deepest contact (the wall's) carries the whole chain's weight: the bounds hold every
        # contact to the largest static force (on top of any F0 the precompression set)
        weight = float(scene.effects.gravity) * float(np.sum(b.mass))
        b.static_force = b.static_force + weight
        b.force = b.force + weight

    @classmethod
    @override
    def work(cls, problem, dx_first, dx_last, dx_mass=0.0):
        g = problem.gravity
        return g * dx_mass if g else 0.0

    @classmethod
    @override
    def watch_work(cls, problem, x_first: str, x_last: str, x_mass: str = "") -> str:
        g = problem.gravity
        return f" + {float(g)!r}*({x_mass})" if g else ""

    @classmethod
    @override
    def energy_columns(cls, layout) -> dict[str, tuple[str, str]]:
        return {"mx": ("mass(mobile)*xcm(mobile,x)", "the moving atoms' mass times their centre of mass's x")}
