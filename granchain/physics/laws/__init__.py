"""Contact laws: one module each, registered here (LAWS is the only list of laws).

See granchain.physics.laws.base for what a law supplies and the rules for writing a new one.
"""

from __future__ import annotations

from granchain.physics.laws.base import REGISTRY, ContactLaw, Kink, LawCoefficients
from granchain.physics.laws.bilinear import BilinearCoefficients, BilinearLaw
from granchain.physics.laws.hertz import HertzLaw
from granchain.physics.laws.power import PowerCoefficients, PowerLaw
from granchain.physics.laws.thornton import ThorntonCoefficients, ThorntonLaw

#: name (the scene's [contact] law) -> law class
LAWS: dict[str, type[ContactLaw]] = REGISTRY
LAWS.update({cls.name: cls for cls in (HertzLaw, BilinearLaw, ThorntonLaw, PowerLaw)})

__all__ = [
    "LAWS",
    "BilinearCoefficients",
    "BilinearLaw",
    "ContactLaw",
    "HertzLaw",
    "Kink",
    "LawCoefficients",
    "PowerCoefficients",
    "PowerLaw",
    "ThorntonCoefficients",
    "ThorntonLaw",
    "contact_keys",
    "law_class",
]


def law_class(name: str) -> type[ContactLaw]:
    """The registered law called `name` (a scene's [contact] law, validated when the scene was read)."""
    return LAWS[name]


def contact_keys() -> frozenset[str]:
    """Every registered law's [contact] keys (besides law)."""
    return frozenset(k for cls in LAWS.values() for k in cls.scene_keys)
