"""The base class of a damping part, and the rules for writing a new one.

A damping part is the dissipative half of a contact's normal force (the other half is the contact
law, granchain.physics.laws): a force that acts while two bodies overlap, added to the law's and
clipped so that the total never pulls. Each part is one module of this package plus one C++ header
in granchain/lammps (damping_<name>.h), as LAMMPS GRANULAR's damping sub-models are one class each.
A scene declares at most one, by its key in ``[damping]``; a scene without one has the part "none".
The rest of granchain asks the scene's part (``Scene.damping``, ``ChainProblem.damping_part``) for
the facts below and never which damping it is.

Rules for writing a new damping part (tests/test_damping.py checks them for every registered part):

1. Subclass DampingPart and set ``name`` (the registry's key), ``key`` (its ``[damping]`` key, whose
   value is the part's one coefficient), ``label`` (how a message names it, e.g.
   ``"[damping] dashpot"``), ``unit`` and ``what`` (the coefficient's unit and meaning, for the
   scene's messages), ``words`` (the damping in running text), ``example`` (a valid coefficient for
   brass beads of R = 4.76 mm, the tests' chains) and ``invalid`` (values the scene must refuse).
2. ``velocity_dependent``: its force depends on the overlap rate. Then the backends need the bodies'
   velocities in the force evaluation (LAMMPS: the ghost beads' velocities, ``comm_modify vel
   yes``), the integrators take their ``damping_*`` facts (granchain.integrators: a velocity force
   makes Verlet first order and RK4's clipping an unlocated kink), a peak is the overlap's turn or
   the largest total force (postprocess.comparison_table.peak_definition), and the planner must
   resolve its decay rate like a frequency.
3. ``damped_force(coefficient, law, alpha, alpha_max, rate, elastic)``: the numpy force term, the
   total normal force of contacts at overlap alpha > 0 with history alpha_max (before this step, as
   the law takes it) closing at ``rate`` = d(alpha)/dt, whose law force is ``elastic``: the damped
   total, never negative. The backends apply it only to overlapping contacts. The C++ header's
   ``force`` is the same expression in the same order, bit for bit.
4. ``contact_damping(coefficient, tangent)``: the viscous coefficient (N s/m) a contact of stiffest
   tangent ``tangent`` shows, the entries of the damping matrix C whose Gershgorin bound of
   M^-1/2 C M^-1/2 is the fastest decay rate an explicit integrator must resolve
   (granchain.physics.estimates.highest_frequency).
5. The energy: its force's work is dissipated, booked by both backends into the per-atom vectors
   ``dissipated_vectors`` (the pair style's, summed into the deck's dissipated energy) and the
   reference's damping energy, so the energy balance holds.
6. The deck: ``pair_style_args(coefficient)`` its words on the pair_style line (the C++ part reads
   them: its ``word`` and the coefficient), ``deck_comment(coefficient)`` the deck's comment line;
   ``yardstick`` why LAMMPS's built-in granular pair style cannot run it (None: it can).
7. Its two-body models, where it has one (optional), as a law declares its own: ``model_domains``
   names each model and the two-body setup it is for (a key of
   granchain.physics.laws.base.EFFECT_DOMAINS: "striker_impact", "wall_impact", "pair_impact"),
   ``predictions(coefficient, impact, velocity)`` gives their values for the scene's two-body impact
   (granchain.physics.laws.base.two_bodies) and ``model_domain(name, coefficient, impact, velocity)`` whether
   the impact is inside the model's own domain and why, with its numbers;
   granchain.physics.predictions.applicability adds the rest (the scene's part, its setup) and
   `granchain predict` shows them.
8. Register the class in granchain/physics/damping/__init__.py (DAMPING, the only list of damping
   parts) and its C++ struct in granchain/lammps/damping_<name>.h (granchain.lammps.build compiles
   and registers every part of DAMPING).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np


class DampingPart:
    """One damping part: every fact says "no damping" unless a part overrides it."""

    name: ClassVar[str] = ""
    #: its [damping] key (the coefficient's), None for the part "none"
    key: ClassVar[str | None] = None
    label: ClassVar[str] = ""
    unit: ClassVar[str] = ""
    what: ClassVar[str] = ""
    #: what it is in a phrase ("the dashpot's decay rate"), in running text ("viscous dashpot") and its
    #: coefficient's symbol ("gamma")
    noun: ClassVar[str] = "damping"
    #: what a message says a scene has ("points with a dashpot")
    phrase: ClassVar[str] = "no damping"
    description: ClassVar[str] = "no damping"
    symbol: ClassVar[str] = ""
    #: a valid coefficient for the tests' brass chains, and coefficients the scene must refuse
    example: ClassVar[float] = 0.0
    invalid: ClassVar[tuple[object, ...]] = ()
    velocity_dependent: ClassVar[bool] = False
    dissipated_vectors: ClassVar[tuple[str, ...]] = ()
    yardstick: ClassVar[str | None] = None
    #: its two-body models (rule 7): model name -> the two-body setup it is for
    model_domains: ClassVar[dict[str, str]] = {}

    @classmethod
    def words(cls, coefficient: float) -> str:
        """The damping in running text ("viscous dashpot (gamma = 3 N s/m)")."""
        if not cls.key:
            return cls.description
        return f"{cls.description} ({cls.symbol} = {coefficient:g} {cls.unit})"

    @classmethod
    def damped_force(cls, coefficient: float, law, alpha, alpha_max, rate, elastic) -> np.ndarray:
        """The total normal force of overlapping contacts (rule 3): the law's, undamped here."""
        return elastic

    @classmethod
    def contact_damping(cls, coefficient: float, tangent):
        """The viscous coefficient (N s/m) of a contact of stiffest tangent `tangent` (rule 4)."""
        return 0.0

    @classmethod
    def scale_refusal(cls, coefficient: float, lightest_mass: float, min_time: float) -> str | None:
        """Why the coefficient damps a body of mass lightest_mass (kg) faster than min_time (s), outside any
        mechanics in double precision (the scene's message after the file name), or None."""
        return None

    @classmethod
    def predictions(cls, coefficient: float, impact, velocity: float) -> list[dict]:
        """Its two-body models' values for `impact` (granchain.physics.laws.base.TwoBodies, the scene's
        two-body impact) at the impact speed `velocity` (m/s): Prediction fields (name, value, unit,
        equation, valid), each name a key of ``model_domains``; a model the impact gives no value for
        is left out (rule 7)."""
        return []

    @classmethod
    def model_domain(cls, name: str, coefficient: float, impact, velocity: float) -> tuple[bool, str]:
        """Whether `impact` is inside the model `name`'s own domain and why, with its numbers (rule 7)."""
        return True, ""

    @classmethod
    def pair_style_args(cls, coefficient: float) -> str:
        """Its words on the pair_style line ("" none): its key, the C++ part's word, and the coefficient."""
        return f" {cls.key} {float(coefficient)!r}" if cls.key else ""

    @classmethod
    def deck_comment(cls, coefficient: float) -> str:
        """What the deck's damping block says it is."""
        return f"{cls.key} {float(coefficient)!r} {cls.unit} between overlapping beads" if cls.key else ""


#: the registered damping parts, name -> class (granchain.physics.damping fills it: the only list)
REGISTRY: dict[str, type[DampingPart]] = {}
