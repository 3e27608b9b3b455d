"""The base class of an effect, and the rules for writing a new one.

An effect is something beyond the paper's bare chain (a free chain of equal beads with a load on
bead 1) that a scene declares: a far-end wall, damping, a static precompression, a striker, per-bead
radii or materials. Each is one module of this package, a subclass of Effect whose class methods the
rest of granchain calls for every registered effect, in registry order; none of them names an effect.
An effect a scene does not declare leaves no trace: ``active(scene)`` is False and nothing of it runs.

Rules for writing a new effect (tests/test_effects.py checks them for every registered effect):

1. Subclass Effect and set ``name`` (the registry's key) and ``label`` (how a message names it, e.g.
   ``"[boundary]"``). An effect with a section of its own sets ``section`` (the scene's
   ``[section]``), ``scene_keys`` (its keys), ``fields`` (the ``scene.Effects`` attributes it owns,
   name -> the value that means absent: ``scene.Effects`` is built from the registry's fields) and
   ``example`` / ``invalid`` (a valid section, and per key values the scene must refuse, with a
   message naming the key: the tests read them), and ``declaration`` (the scene tables that declare
   it, merged key by key into a scene with a velocity load: tests build every combination of
   effects from them). An effect declared elsewhere in the scene (a striker is a ``[loading]
   kind``, per-bead radii are ``[chain]`` lists) leaves ``section`` None; that section's reader
   validates it.
2. ``read(section)``: read and validate the keys of its section (section: scene._Section, whose
   number/choice/finish raise a SceneError naming the file, the key, the value and what is
   allowed); returns its ``fields``. ``to_dict(effects)``: its section for a scene file (None when
   absent); read back by ``read`` to equal fields. ``active(scene)``: the scene declares it.
3. Compatibility: every effect goes with every other (tests simulate every subset of the registry).
   Where a combination truly cannot be simulated, ``incompatible`` maps the other effect to the
   physical reason this effect's refusal gives, or None where the other effect words it. Both sides list
   the pair (the relation is symmetric) and exactly one side words it.
4. The problem (granchain.problem.ChainProblem): ``problem_fields(scene, fields)`` updates the fields
   the chain is built from (mass, law, wall_law, damping, ...); ``ends(problem, parts, mass)`` adds
   the extra beads a solver integrates (a striker in front, an immovable wall at the end; those in
   front counted by ``beads_in_front``), and ``end_fields`` what the results report of them;
   ``static_forces(problem, fp)`` the constant external forces on the end beads (precompression:
   the push on bead 1 returned, the pull on bead N in fp[-1]);
   ``body_acceleration(problem)`` a body force's acceleration on every moving bead (gravity);
   ``requirement(scene)`` what else the scene must declare for it (gravity: a wall), refused by the
   scene reader; ``reference_accel(...)`` the reference's force evaluation when it changes the contact force law
   (damping: a closure over preallocated buffers, as fast as the plain one).
5. The planner's and the stability check's bounds (granchain.physics.estimates.highest_frequency):
   ``chain_bounds(scene, b)`` changes what holds along the chain (masses, contact laws, the force
   level, the damping part) before the contacts' tangents are taken; ``end_bounds(scene, b)`` the
   nodes at the chain's ends (a wall's contact, a striker's mass and contact).
6. Energy: the work of its forces since t = 0, ``work(problem, dx_first, dx_last, dx_mass)`` (numpy
   arrays or floats: the reference's ledger and the LAMMPS read-back call the same function; dx_mass:
   the moving beads' sum of m_i dx_i, for a body force), the same as a LAMMPS expression for the
   deck's run watch, ``watch_work(problem, x_first, x_last, x_mass)`` (x_first, x_last, x_mass:
   expressions of bead 1's and bead N's displacement since t = 0 and of dx_mass), and the energy columns
   its deck adds (``energy_columns(layout)``: name -> (LAMMPS expression, words);
   granchain.lammps.runner reads them back by name). ``conserves_momentum`` False: its forces are
   external (the run watches skip the momentum check where ``in_problem(problem)``: the problem
   carries the effect). Energy it dissipates is a per-atom vector its pair style fills
   (``dissipated_vectors``), summed into the deck's dissipated energy.
7. The deck: ``deck_blocks`` maps a slot of templates/chain.lmp.j2 ("interactions": after the pair
   style; "ends": after the dissipated-energy sum, for extra atoms' groups; "forces": after the
   load) to its template in granchain/templates; ``pair_style_args`` what it adds to the
   pair_style line; ``pair_coeffs(scene, types)`` the pair_coeff lines of its atom types (i, j,
   law, contact distance); ``yardstick`` why LAMMPS's built-in granular pair style
   cannot run it (None: it can; ``yardstick_refusal(scene)`` where the reason depends on the scene).
8. Register the class in granchain/physics/effects/__init__.py (EFFECTS, the only list of effects).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

#: The run watch stops a run once a contact's overlap exceeds this fraction of the smaller radius of its
#: two bodies (granchain.invariants says why). The planner's bounds hold each contact's force to its
#: law's virgin curve there (watched_force): a run whose contact carried more would not go on.
OVERLAP_WATCH = 0.5


def watched_force(law, smaller_radius) -> np.ndarray:
    """The largest force a contact carries in a run the run watch lets go on, N.

    Parameters
    ----------
    law : ContactLaw
        The contact's law (or one over several contacts).
    smaller_radius : array_like
        The smaller radius of its two bodies (a wall's flat: the bead's), m.

    Returns
    -------
    ndarray
        The law's virgin-curve force at OVERLAP_WATCH x smaller_radius (elementwise); a force on the
        unloading or reloading branches of a history law stays below the virgin curve at its largest
        overlap.
    """
    return np.asarray(law.loading_force(OVERLAP_WATCH * np.asarray(smaller_radius, dtype=float)), dtype=float)


@dataclass
class Bounds:
    """What highest_frequency bounds over: the Gershgorin rows of the linearised chain.

    Set along the chain by the effects' chain_bounds (mass, law, force, static_force, damping), then
    the neighbours of each node (k: contact tangent; m: neighbour mass; g: the damping's viscous
    coefficient, viscous) on the left (l) and right (r), which end_bounds changes at the ends; extra:
    effects' own nodes (the striker).
    """

    force: float  # the largest force a bead-bead contact is expected to carry (N)
    mass: np.ndarray  # (n,) kg
    radius: np.ndarray  # (n,) m: each contact's force is held to watched_force of its smaller bead
    law: Any  # ContactLaw over the n-1 contacts
    static_force: float = 0.0  # the largest static force on a contact (precompression's F0, gravity's weight)
    damping: Any = None  # the damping part (granchain.physics.damping), None: none
    damping_coefficient: float = 0.0
    kl: np.ndarray = field(default_factory=lambda: np.zeros(0))
    ml: np.ndarray = field(default_factory=lambda: np.zeros(0))
    kr: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mr: np.ndarray = field(default_factory=lambda: np.zeros(0))
    gl: np.ndarray = field(default_factory=lambda: np.zeros(0))
    gr: np.ndarray = field(default_factory=lambda: np.zeros(0))
    extra: dict[str, float] = field(default_factory=dict)

    def viscous(self, tangent):
        """The damping's viscous coefficient (N s/m) of a contact of stiffest tangent `tangent`: the
        part's contact_damping (a dashpot's gamma, Kuwabara-Kono's A x tangent), 0 without damping."""
        if self.damping is None:
            return 0.0
        return self.damping.contact_damping(self.damping_coefficient, tangent)


class Effect:
    """One effect beyond the bare chain: every hook does nothing unless an effect overrides it."""

    name: ClassVar[str] = ""
    label: ClassVar[str] = ""
    section: ClassVar[str | None] = None
    scene_keys: ClassVar[tuple[str, ...]] = ()
    #: the scene keys a section may leave out (each has a default: the wall's material and radius)
    optional_keys: ClassVar[tuple[str, ...]] = ()
    #: scene.Effects attributes this effect owns -> the value that means absent
    fields: ClassVar[dict[str, Any]] = {}
    #: a valid section (tests), and per key values the scene refuses
    example: ClassVar[dict[str, Any]] = {}
    #: how a scene declares it: tables merged into a scene's (tests build every combination from them)
    declaration: ClassVar[dict[str, dict[str, Any]]] = {}
    invalid: ClassVar[dict[str, tuple[Any, ...]]] = {}
    #: other effect's name -> the fix this effect's refusal suggests ("" none), None: the other words it
    incompatible: ClassVar[dict[str, str | None]] = {}
    #: other effects it needs (their names; its declaration declares them, requirement() refuses a
    #: scene without them): gravity a wall to stand on
    requires: ClassVar[tuple[str, ...]] = ()
    conserves_momentum: ClassVar[bool] = True
    #: extra beads a solver puts in front of bead 1 (a striker: 1; Effect.ends)
    beads_in_front: ClassVar[int] = 0
    #: the deck's atom type of its extra atom (data_atoms), or None
    atom_type: ClassVar[str | None] = None
    dissipated_vectors: ClassVar[tuple[str, ...]] = ()
    deck_blocks: ClassVar[dict[str, str]] = {}
    yardstick: ClassVar[str | None] = None

    # ---- the scene
    @classmethod
    def active(cls, scene) -> bool:
        """The scene declares this effect."""
        return any(getattr(scene.effects, f) != v for f, v in cls.fields.items())

    @classmethod
    def read(cls, section) -> dict[str, Any]:
        """Read and validate this effect's section: its fields."""
        section.finish(cls.scene_keys)
        return {}

    @classmethod
    def to_dict(cls, effects) -> dict[str, Any] | None:
        """Its section of a scene file, or None when absent."""
        return None

    @classmethod
    def requirement(cls, scene) -> str | None:
        """Why the scene, declaring this effect, lacks what the effect needs (the fix in words), or None
        (gravity: a wall to stand on). The scene reader refuses it with this message."""
        return None

    # ---- the problem
    @classmethod
    def problem_fields(cls, scene, fields: dict[str, Any]) -> None:
        """Update the ChainProblem fields (in place) for this effect."""

    @classmethod
    def ends(cls, problem, parts: list, mass: np.ndarray) -> np.ndarray:
        """Extra beads a solver integrates: insert (law, contacts) into parts, return the masses."""
        return mass

    @classmethod
    def end_fields(
        cls, force: np.ndarray, time: np.ndarray, velocity: np.ndarray, last: int, complete: np.ndarray
    ) -> dict[str, Any]:
        """ChainSolution fields of its extra beads, from the whole chain's contact peak forces, their
        times and which are complete (peaks.every_contact_complete; index 0: a striker's contact;
        `last`: a wall's) and bead velocities (0: a striker's): the reference (inner chain) and the
        LAMMPS read-back (by atom) alike."""
        return {}

    @classmethod
    def static_forces(cls, problem, fp: np.ndarray) -> float:
        """External forces constant over the run: returns the push on bead 1 (N), and writes a pull on
        bead N into the reference's padded force buffer, fp[-1] (pulling when positive)."""
        return 0.0

    @classmethod
    def body_acceleration(cls, problem) -> float:
        """A body force's acceleration on every moving bead toward the far end, m/s^2 (gravity's g;
        0: none): the reference adds it to every force evaluation, the deck has its own fix."""
        return 0.0

    @classmethod
    def reference_accel(cls, problem, law, inv_m: np.ndarray, fp: np.ndarray, alpha_hist: np.ndarray):
        """The reference's force evaluation when this effect changes the contact forces (the
        damping; see granchain.reference.state.make_accel), else None."""
        return None

    # ---- planner bounds
    @classmethod
    def chain_bounds(cls, scene, b: Bounds) -> None:
        """Change masses, laws, force level or damping along the chain (before the tangents)."""

    @classmethod
    def end_bounds(cls, scene, b: Bounds) -> None:
        """Change the nodes at the chain's ends (after the tangents)."""

    # ---- energy
    @classmethod
    def in_problem(cls, problem) -> bool:
        """The problem (a ChainProblem) carries this effect. An effect with external forces must
        answer so after with_ends too: the reference's run watches ask the problem it integrates."""
        return False

    @classmethod
    def momentum_kept(cls, problem) -> bool:
        """The chain's momentum is the initial one plus the load's impulse, as far as this effect goes."""
        return cls.conserves_momentum or not cls.in_problem(problem)

    @classmethod
    def work(cls, problem, dx_first, dx_last, dx_mass=0.0):
        """The work its forces did since t = 0 (dx: bead 1's and bead N's displacement since; dx_mass:
        the moving beads' sum of m_i dx_i, a striker's included, for a body force)."""
        return 0.0

    @classmethod
    def watch_work(cls, problem, x_first: str, x_last: str, x_mass: str = "") -> str:
        """work() as a LAMMPS expression (" + ..." terms; "" none); x_mass: dx_mass's expression."""
        return ""

    @classmethod
    def energy_columns(cls, layout) -> dict[str, tuple[str, str]]:
        """Columns it adds to the deck's energy samples: name -> (LAMMPS expression, what it is)."""
        return {}

    # ---- the deck
    @classmethod
    def yardstick_refusal(cls, scene) -> str | None:
        """Why LAMMPS's built-in granular pair style cannot run the scene's effect (None: it can)."""
        return cls.yardstick

    @classmethod
    def pair_style_args(cls, scene) -> str:
        """Words it adds to the pair_style line ("" none)."""
        return ""

    @classmethod
    def data_atoms(cls, scene, types: dict[str, int], x: np.ndarray) -> list[tuple[int, float, float, float]]:
        """Its atoms in the deck's data file: (type, diameter, density, x); in front of bead 1 when it
        has beads_in_front, after bead N otherwise. types: the layout's atom types (bead kind k is
        type k + 1, Scene.bead_kinds; an effect's by its atom_type); x: the beads' positions in the
        data file (displaced by any precompression)."""
        return []

    @classmethod
    def pair_coeffs(cls, scene, types: dict[str, int]) -> list[tuple[int, int, Any, float]]:
        """(I, J, law, contact distance) of the pair_coeff lines of its atom types: with every bead
        kind (types 1..K, Scene.bead_kinds; LAMMPS needs a line for every pair of types, also those
        that never meet) and with the other effects' types."""
        return []


#: the registered effects, name -> class (granchain.physics.effects fills it: the only list of effects)
REGISTRY: dict[str, type[Effect]] = {}
