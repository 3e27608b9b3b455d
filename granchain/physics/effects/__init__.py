"""Effects beyond the paper's bare chain: one module each, registered here (EFFECTS is the only list
of effects; its order is the order every hook runs in and refusals are checked in).

See granchain.physics.effects.base for what an effect supplies and the rules for writing a new one.
"""

from __future__ import annotations

from granchain.physics.effects.base import OVERLAP_WATCH, REGISTRY, Bounds, Effect, watched_force
from granchain.physics.effects.damping import DampingEffect
from granchain.physics.effects.gravity import GravityEffect
from granchain.physics.effects.per_bead import PerBeadEffect
from granchain.physics.effects.precompression import PrecompressionEffect
from granchain.physics.effects.shaker import LOAD_EFFECTS
from granchain.physics.effects.striker import StrikerEffect
from granchain.physics.effects.wall import FAR_ENDS, WallEffect

#: name -> effect class, in the order every hook runs
EFFECTS: dict[str, type[Effect]] = REGISTRY
EFFECTS.update(
    {
        cls.name: cls
        for cls in (WallEffect, DampingEffect, PrecompressionEffect, GravityEffect, StrikerEffect, PerBeadEffect)
    }
)

__all__ = [
    "EFFECTS",
    "FAR_ENDS",
    "OVERLAP_WATCH",
    "Bounds",
    "Effect",
    "active_effects",
    "body_acceleration",
    "effect_fields",
    "momentum_kept",
    "refusal",
    "sections",
    "watched_force",
    "work",
]


def active_effects(scene) -> list[type[Effect]]:
    """The registered effects the scene declares, in registry order, then a load's own body (a shaker's
    driver: effects.shaker.LOAD_EFFECTS)."""
    return [e for e in (*EFFECTS.values(), *LOAD_EFFECTS) if e.active(scene)]


def unbalanced_forces(scene) -> list[type[Effect]]:
    """external_forces whose sum is not zero, so that the chain's momentum changes: not the static
    precompression of a free chain, whose push on bead 1 and pull on bead N are equal and opposite.
    (The run watches keep external_forces: they check no momentum where any external force acts.)"""
    balanced = scene.effects.far_end == "free"
    return [e for e in external_forces(scene) if not (e.name == "precompression" and balanced)]


def external_forces(scene) -> list[type[Effect]]:
    """The scene's effects whose forces come from outside the chain (Effect.conserves_momentum False):
    with any of them the chain's momentum is not the initial momentum plus the impulse delivered."""
    return [e for e in active_effects(scene) if not e.conserves_momentum]


def effect_fields() -> dict[str, object]:
    """Every scene.Effects attribute -> its absent value (the fields of the registered effects)."""
    return {f: v for e in EFFECTS.values() for f, v in e.fields.items()}


def sections() -> dict[str, type[Effect]]:
    """Scene sections of the effects that have one -> the effect."""
    return {e.section: e for e in EFFECTS.values() if e.section}


def momentum_kept(problem) -> bool:
    """No effect the problem carries exerts external forces: its momentum is the initial one plus the
    load's impulse (the run watches check it)."""
    return all(e.momentum_kept(problem) for e in EFFECTS.values())


def work(problem, dx_first, dx_last, dx_mass=0.0):
    """The work of the effects' forces since t = 0 (dx: bead 1's and bead N's displacement since;
    dx_mass: the moving beads' sum of m_i dx_i; floats or arrays)."""
    w = 0.0
    for e in EFFECTS.values():
        w = w + e.work(problem, dx_first, dx_last, dx_mass)
    return w


def body_acceleration(problem) -> float:
    """The effects' body forces' acceleration on every moving bead toward the far end (gravity), m/s^2."""
    return sum(e.body_acceleration(problem) for e in EFFECTS.values())


def refusal(active: list[type[Effect]]) -> str | None:
    """Why these effects cannot be simulated together (the physical reason, as the first effect that
    words a refusal gives it), or None. Every pair of the registered effects goes together today."""
    names = {e.name for e in active}
    for e in active:
        partners = [o for o in active if o.name in names and e.incompatible.get(o.name) is not None]
        if partners:
            fix = e.incompatible[partners[0].name]
            return f"{e.label} with {', '.join(o.label for o in partners)} cannot be simulated: {fix}"
    return None
