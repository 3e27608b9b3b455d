"""Per-bead radii and materials ([chain] radius = [...] or taper = q, material = [...]): tapered,
decorated and impurity chains. The [chain] section reads them (scene._read_chain).

Masses follow the beads and every contact has its own pair's law (Johnson's E* and R* of the two
beads: scene.contact_laws); the planner bounds the highest frequency over those masses and laws.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from typing_extensions import override

from granchain.physics.effects.base import Bounds, Effect


class PerBeadEffect(Effect):
    """Beads of different radii or materials along the chain: tapered, decorated and impurity chains.

    The paper's chain is monodisperse; with this effect each bead has its own mass and each contact
    the law of its own pair of beads (Johnson's E* and R* of the two: ``scene.contact_laws``).

    Scene keys: none of its own; ``[chain]`` declares it with a ``radius`` or ``material`` list or a
    ``taper`` ratio, and the [chain] reader validates them (``section`` is None). Deck block: none;
    the beads' kinds become LAMMPS atom types (``Scene.bead_kinds``) and their pair_coeff lines.
    """

    name = "per_bead"
    label = "per-bead radius or material"
    declaration = {"chain": {"taper": 0.97}}

    @classmethod
    @override
    def active(cls, scene) -> bool:
        return scene.per_bead

    @classmethod
    @override
    def problem_fields(cls, scene, fields: dict[str, Any]) -> None:
        law = fields["law"]
        fields.update(mass=scene.bead_masses, law=type(law).join([(c, 1) for c in scene.contact_laws]))

    @classmethod
    @override
    def chain_bounds(cls, scene, b: Bounds) -> None:
        b.mass = scene.bead_masses
        b.radius = np.asarray(scene.bead_radii, dtype=float)
        b.law = type(scene.law).join([(c, 1) for c in scene.contact_laws])
