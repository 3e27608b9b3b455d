"""The [sections] table of a campaign: a per-bead scene key built from sections, each a value taken
from a parameter and a bead count (a whole number, or a parameter), in chain order (issue 45: a
protector's chain of two or three materials in sections, a categorical choice per section)::

    [sections."chain.material"]
    values = ["m1", "m2", "m3"]      # each section's value: a varied, searched or derived key's name
    beads = [4, 4, "n3"]             # each section's bead count: a whole number or such a key's name

    [optimize.variables]
    m1 = { choices = ["chrome-steel-52100", "brass", "ptfe"] }   # a free parameter per section
    ...

makes ``chain.material = [m1] * 4 + [m2] * 4 + [m3] * n3`` at every point (after [derive], so a
derived ``chain.beads = "8 + n3"`` keeps the chain's length equal to the sections' sum; the scene
reader refuses a list whose length is not the chain's beads). The list is set on the point's scene,
not among its parameters: the table's columns are the sections' parameters.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from granchain.campaigns.model import CampaignError

SECTION_KEYS = ("values", "beads")
#: the scene keys that take one value per bead (granchain.scene: [chain] lists)
PER_BEAD_KEYS = ("chain.material", "chain.radius")


@dataclass(frozen=True)
class Sections:
    """One [sections] entry: the per-bead key and its sections, in chain order.

    Attributes
    ----------
    key : str
        The per-bead scene key ("chain.material" or "chain.radius").
    values : tuple of str
        Each section's value: the name of a parameter of the point.
    beads : tuple of int or str
        Each section's bead count: a whole number, or the name of a parameter of the point.
    """

    key: str
    values: tuple[str, ...]
    beads: tuple[int | str, ...]

    def build(self, params: dict, where: str) -> list:
        """The per-bead list for a point's parameters (its [derive] keys among them)."""
        out: list = []
        for value, count in zip(self.values, self.beads, strict=True):
            n = params[count] if isinstance(count, str) else count
            if isinstance(n, float) and n.is_integer():
                n = int(n)
            if not isinstance(n, int) or isinstance(n, bool) or n < 0:
                raise CampaignError(
                    f"{where}: [sections.{self.key!r}] beads {count!r} = {n!r} is invalid: a whole number >= 0"
                )
            out.extend([params[value]] * n)
        return out


def read_sections(table: Any, names: set[str], source: str) -> tuple[Sections, ...]:
    """The [sections] table validated: its keys per-bead scene keys, its names among `names` (the
    varied, searched and derived keys); a CampaignError naming the field and the fix otherwise."""
    if not isinstance(table, dict):
        raise CampaignError(f'{source}: [sections] must be a table: [sections."chain.material"] values = [...]')
    out = []
    for key, spec in table.items():
        where = f"{source}: [sections.{key!r}]"
        if key not in PER_BEAD_KEYS:
            raise CampaignError(f"{where}: {key!r} is not a per-bead key; one of {', '.join(PER_BEAD_KEYS)}")
        if not isinstance(spec, dict) or set(spec) != set(SECTION_KEYS):
            raise CampaignError(
                f'{where} needs exactly values and beads, two lists of equal length: values = ["m1", "m2"], '
                "beads = [5, 5]"
            )
        values, beads = spec["values"], spec["beads"]
        if not isinstance(values, list) or not values or not isinstance(beads, list) or len(beads) != len(values):
            raise CampaignError(f"{where}: values and beads are two non-empty lists of equal length")
        for v in values:
            if not isinstance(v, str) or v not in names:
                raise CampaignError(
                    f"{where} values: {v!r} is not a varied or derived key; name one per section (e.g. a free "
                    f"parameter m1 in [optimize.variables]); known: {', '.join(sorted(names)) or 'none'}"
                )
        for b in beads:
            fixed = isinstance(b, int) and not isinstance(b, bool) and b >= 0
            if not fixed and not (isinstance(b, str) and b in names):
                raise CampaignError(
                    f"{where} beads: {b!r} is invalid: a whole number >= 0 or a varied or derived key's name"
                )
        out.append(Sections(key, tuple(values), tuple(beads)))
    return tuple(out)
