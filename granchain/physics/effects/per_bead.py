"""Per-bead radii and materials ([chain] radius = [...] or taper = q, material = [...]): tapered,
decorated and impurity chains. The [chain] section reads them (scene._read_chain).

Masses follow the beads and every contact has its own pair's law (Johnson's E* and R* of the two
beads: scene.contact_laws); the planner bounds the highest frequency over those masses and laws.
"""

from __future__ import annotations

from typing import Any

from granchain.physics.effects.base import Bounds, Effect


class PerBeadEffect(Effect):
    name = "per_bead"
    label = "per-bead radius or material"
    declaration = {"chain": {"taper": 0.97}}

    @classmethod
    def active(cls, scene) -> bool:
        return scene.per_bead

    @classmethod
    def problem_fields(cls, scene, fields: dict[str, Any]) -> None:
        law = fields["law"]
        fields.update(mass=scene.bead_masses, law=type(law).join([(c, 1) for c in scene.contact_laws]))

    @classmethod
    def chain_bounds(cls, scene, b: Bounds) -> None:
        b.mass = scene.bead_masses
        b.law = type(scene.law).join([(c, 1) for c in scene.contact_laws])
