"""The values a scene may take: the laws and loads it may name, "auto", the bounds on its numbers,
each with the reason it is where it is, and each numeric key's unit (SCENE_KEY_UNITS, scene_key_unit:
what a campaign's axes and columns print beside a key)."""

from __future__ import annotations

from granchain.physics.damping import DAMPING
from granchain.physics.effects import FAR_ENDS as FAR_ENDS  # the [boundary] far_end choices
from granchain.physics.laws import LAWS as LAW_REGISTRY

LAWS = tuple(LAW_REGISTRY)  # the registered laws' names (granchain.physics.laws.LAWS)

LOADING_KINDS = ("step", "impulse", "harmonic", "velocity", "striker", "shaker")

AUTO = "auto"  # a value the planner chooses (granchain.workflows.plan)

#: the most beads a chain may have: the planner and the solvers hold a few numbers per bead and the
#: leading wave needs steps in proportion to the chain's length, so a longer chain cannot finish (the
#: planner alone needs about a second and 130 MB per million beads)
MAX_BEADS = 10**6
#: the most beads a chain whose beads differ (a taper, per-bead lists) may have: every contact gets its
#: own law, and the planner spends about 80 us per contact on them (8 s for the largest)
MAX_VARIED_BEADS = 10**5
#: the largest scene file read: the TOML reader holds it several times over and takes about a second
#: per few MB
MAX_SCENE_BYTES = 16 * 1024**2
#: the longest time a scene may give (end_time, a load's duration, snapshots, intervals): about 3 hours,
#: far beyond any stress wave in a chain of spheres; more is a typo for a shorter time
MAX_TIME = 1e4

#: the shortest contact time scale tau a chain may have: 1 fs (beads of a micrometre of the stiffest
#: material have 0.2 ps); a shorter one comes only from values at the edge of their ranges together
MIN_TAU = 1e-15
#: the largest static force on a contact (as a load's amplitude)
MAX_FORCE = 1e12

#: the shortest loading time T: an attosecond, as the smallest impulse is 1e-18 N s. No mechanical load
#: acts over less; and an impulse's amplitude I / T must stay within what the peak-force models hold in
#: double precision (an impulse of 0.01 N s over 2.2e-308 s overflows them)
MIN_DURATION = 1e-18
DURATION_TEXT = "loading time T in s; no mechanical load acts over less than an attosecond"
#: the shortest time step a scene may give: a million times below the shortest a chain needs (a contact
#: time scale of MIN_TAU = 1 fs, a step of a thousandth of it at the finest tolerance); a shorter one
#: makes step counts that overflow LAMMPS's and granchain's integers (5e-324 s overflows the planner's)
MIN_TIMESTEP = 1e-24
TIME_TEXT = f"at most {MAX_TIME:g} s: about 3 hours, far beyond any stress wave in a chain"


def _part_units() -> tuple[dict[str, str], dict[str, str]]:
    """The units of the keys the registered parts read: each law's [contact] keys (ContactLaw.key_units),
    in the registry's order, and each damping part's [damping] key (DampingPart.unit)."""
    law_keys = {f"contact.{k}": cls.key_units[k] for cls in LAW_REGISTRY.values() for k in cls.scene_keys}
    return law_keys, {f"damping.{cls.key}": cls.unit for cls in DAMPING.values() if cls.key}


_LAW_KEY_UNITS, _DAMPING_KEY_UNITS = _part_units()

#: dotted scene key -> its unit (SI; "1": dimensionless), as the scene reader reads it; the laws' and the
#: damping parts' keys from the parts themselves
SCENE_KEY_UNITS = {
    "chain.beads": "beads",
    "chain.radius": "m",
    "chain.taper": "1",
    "loading.amplitude": "N",
    "loading.duration": "s",
    "loading.impulse": "N s",
    "loading.velocity": "m/s",
    "loading.frequency": "Hz",
    "loading.cycles": "1",
    "loading.ramp": "1",
    "loading.radius": "m",
    "loading.mass": "kg",
    **_LAW_KEY_UNITS,
    "precompression.force": "N",
    "gravity.g": "m/s^2",
    **_DAMPING_KEY_UNITS,
    "boundary.wall_radius": "m",
    "run.end_time": "s",
    "run.timestep": "s",
    "run.stop_after_contact": "contact",
    "outputs.history_interval": "s",
    "outputs.dump_interval": "s",
}

#: a material's properties (``chain.material.density``, ``boundary.wall_material.youngs_modulus``)
MATERIAL_UNITS = {"density": "kg/m^3", "youngs_modulus": "Pa", "poisson_ratio": "1", "yield_strength": "Pa"}


def scene_key_unit(key: str) -> str | None:
    """The unit of a dotted scene key, or None for a key without one (text, a switch, a free parameter)."""
    if key in SCENE_KEY_UNITS:
        return SCENE_KEY_UNITS[key]
    head, _, last = key.rpartition(".")
    if head.endswith(("material", "wall_material")) and last in MATERIAL_UNITS:
        return MATERIAL_UNITS[last]
    return None
