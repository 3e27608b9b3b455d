"""Every key a registered part reads has a unit, and the unit is the part's own.

scene.limits.SCENE_KEY_UNITS (what a campaign's axes, columns and the scene display print beside a
key) takes the laws' ``[contact]`` keys from ContactLaw.key_units and the damping parts' ``[damping]``
keys from DampingPart.unit: a new law or damping part brings its units and edits no table.
"""

import dataclasses
from typing import ClassVar

import pytest

from granchain.physics.damping import DAMPING
from granchain.physics.laws import LAWS, ContactLaw, LawCoefficients
from granchain.scene import KEY_UNITS
from granchain.scene.limits import SCENE_KEY_UNITS, scene_key_unit


@pytest.mark.parametrize("law", sorted(LAWS))
def test_every_key_a_law_reads_has_its_unit(law):
    """Each of the law's [contact] keys (its Coefficients' fields, those read_contact reads) and each key
    of its example has the unit the law declares, wherever a unit is looked up."""
    cls = LAWS[law]
    assert set(cls.key_units) == set(cls.scene_keys)
    for key in (*cls.scene_keys, *cls.example_contact):
        unit = cls.key_units[key]
        assert isinstance(unit, str)
        assert unit.strip()
        assert SCENE_KEY_UNITS[f"contact.{key}"] == unit
        assert scene_key_unit(f"contact.{key}") == unit
        assert KEY_UNITS[f"contact.{key}"] == unit


@pytest.mark.parametrize("name", sorted(DAMPING))
def test_every_damping_key_has_its_parts_unit(name):
    """Each part's [damping] key (all but "none" have one) has the part's unit."""
    cls = DAMPING[name]
    if cls.key is None:
        return
    assert cls.unit.strip()
    assert SCENE_KEY_UNITS[f"damping.{cls.key}"] == cls.unit
    assert scene_key_unit(f"damping.{cls.key}") == cls.unit


def test_no_contact_or_damping_unit_without_a_part():
    """The table holds no [contact] or [damping] key that no registered part reads (a stale row)."""
    law_keys = {f"contact.{k}" for cls in LAWS.values() for k in cls.scene_keys}
    damping_keys = {f"damping.{cls.key}" for cls in DAMPING.values() if cls.key}
    rows = {k for k in SCENE_KEY_UNITS if k.startswith(("contact.", "damping."))}
    assert rows == law_keys | damping_keys


def test_a_law_that_leaves_out_a_unit_cannot_be_declared():
    """ContactLaw's subclass hook refuses a law whose key_units miss one of its keys."""

    @dataclasses.dataclass(frozen=True)
    class Keyed(LawCoefficients):
        softness: float = 1.0

    with pytest.raises(TypeError, match="key_units"):

        class Unitless(ContactLaw):
            name: ClassVar[str] = "unitless"
            Coefficients: ClassVar[type[LawCoefficients]] = Keyed

    class United(ContactLaw):
        name: ClassVar[str] = "united"
        Coefficients: ClassVar[type[LawCoefficients]] = Keyed
        key_units: ClassVar[dict[str, str]] = {"softness": "1"}

    assert United.scene_keys == ("softness",)
