"""Damping parts of a contact's normal force: one module each, registered here (DAMPING is the only
list of damping parts). See granchain.physics.damping.base for what a part supplies and the rules
for writing a new one.
"""

from __future__ import annotations

from granchain.physics.damping.base import REGISTRY, DampingPart
from granchain.physics.damping.dashpot import Dashpot
from granchain.physics.damping.kuwabara_kono import KuwabaraKono
from granchain.physics.damping.none import NoDamping

#: name -> damping part class ("none" first: the part of a scene without [damping])
DAMPING: dict[str, type[DampingPart]] = REGISTRY
DAMPING.update({cls.name: cls for cls in (NoDamping, Dashpot, KuwabaraKono)})

__all__ = ["DAMPING", "DampingPart", "damping_keys", "damping_of"]


def damping_keys() -> dict[str, type[DampingPart]]:
    """The [damping] keys -> their part (every part but "none" has one)."""
    return {cls.key: cls for cls in DAMPING.values() if cls.key}


def damping_of(effects) -> tuple[type[DampingPart], float]:
    """The damping part a scene's effects (scene.Effects: one attribute per [damping] key, 0 absent)
    declare and its coefficient; ("none", 0.0) without one. The scene reader refuses two."""
    for key, cls in damping_keys().items():
        value = float(getattr(effects, key))
        if value:
            return cls, value
    return DAMPING["none"], 0.0
