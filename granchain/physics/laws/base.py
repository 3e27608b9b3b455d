"""The base class of a contact law, and the rules for writing a new one.

A contact law is one module of this package plus one C++ header in granchain/lammps (law_<name>.h).
The overlap of contact i (between bead i and bead i+1) is alpha = u_i - u_{i+1} (Eq. 2); alpha <= 0
means the beads are apart and the force is zero. A law instance holds its per-contact parameters
(dataclass fields, each a float or one value per contact) and every method is vectorised over
contacts.

Rules for writing a new law (the reference solver, the LAMMPS deck, the planner and the checks rely
on them; tests/test_laws.py and tests/test_kernels.py check them for every registered law):

1. Subclass ContactLaw as a frozen dataclass whose fields are the per-contact parameters, the first
   one ``k`` (the stiffness the planner and the deck's watch scale by). Set the class attributes:
   ``name`` (the scene's ``[contact] law``), ``pair_style`` (the C++ style, ``chain/<name>``),
   ``history`` (True when the force depends on alpha_max, the largest overlap so far: the only
   history a law may keep; the backends store it per contact, d_amax in LAMMPS, and update it as
   alpha_max = max(alpha_max, alpha) after every step), ``Coefficients`` (a frozen dataclass
   subclassing LawCoefficients, one field per ``[contact]`` key the law reads besides ``law``: a
   scene's Contact holds one, and ``scene_keys`` lists its fields), ``key_units`` (each key's unit: a
   law that leaves one out cannot be declared), ``parameter_ranges`` (valid values of each parameter,
   for the tests).
2. ``force(alpha, alpha_max)`` with alpha_max the history *before* this step: the law takes
   max(alpha_max, alpha) itself, so a stale history below alpha gives the loading curve. The force
   is never negative. ``force_into`` is the same into preallocated arrays (the solver's inner loop;
   alpha already clipped at 0). ``energy`` is the stored (recoverable) energy and ``dissipated``
   what the contact has dissipated once it reached alpha_max; energy + dissipated = the work done
   on the contact, whatever path led there (the energy balance checks it).
3. ``loading_force(alpha)``: the virgin curve, the force at a contact's largest overlap (its peak
   force); ``static_overlap(force)``: its inverse (precompression, on the virgin curve: a law with
   history starts with alpha_max = that overlap); ``tangent_stiffness(force)``: the stiffest dF/dalpha
   a contact loaded to that force can show (the planner's omega_max and the stability check);
   ``loading_stiffness(force)``: the virgin curve's own dF/dalpha where it carries that force, the
   stiffness a further compression meets from a static force (a precompressed chain's linearised
   fronts). Each law defines both: a plastic law's virgin curve is softer than its unloading.
   ``overlap_tangent(alpha, alpha_max)``: dF/dalpha of the branch in force at overlap alpha (the
   loading branch where alpha >= the history, else the unloading one), the damping parts' tangent
   (granchain.physics.damping: Kuwabara-Kono's A dF/dalpha d(alpha)/dt, through
   ``damping_tangent(alpha, alpha_max, force)``, which may derive it from the force there); its C++
   twin is the kernel's ``tangent(alpha, am, d, f)``, the same expression.
4. ``kinks(alpha_max)``: where dF/dalpha (or a higher derivative) jumps, for RK4's event location:
   overlaps (one per contact) with where they apply; ``turn_level(alpha_max)``: a contact whose
   overlap turns (from rising to falling) above this level starts unloading on another curve (None:
   the law has no such kink).
5. ``pair_coefficients()``: the numbers of ``pair_coeff I J k d0 [extras]`` after d0, k first and
   d0 inserted by the deck: the C++ kernel reads them in this order.
6. ``read_contact(section, chain)`` reads and validates its scene keys (section: scene's Section) and
   returns its Coefficients; ``for_pair(coefficients, e_star, r_star, nominal_r_star)`` the law of one
   pair of bodies (bead-bead, bead-wall with the flat's E* and R* = R, striker-bead);
   ``contact_to_dict(contact)`` the ``[contact]`` table a scene file writes back. A key may hold one
   value per bead-bead contact (the power law's lists): its Coefficients then say so (``varies``) and
   give each contact's (``of_contact(i)``), and for_pair gets one contact's values (the striker's the
   first contact's, the wall's the last's: Scene.pair_law).
7. Register the class in granchain/physics/laws/__init__.py (LAWS, the only list of laws); the C++
   kernel, struct Law<Name> in granchain/lammps/law_<name>.h, is compiled and registered from LAWS
   (granchain.lammps.build). The planner's estimates (expected_peak_force, wave speeds) are class
   methods over a scene.
9. The facts the rest of the code reads instead of asking which law it is (no module outside this
   package compares a law's name: tests/test_law_facts.py): ``loading_exponent()`` (the onset
   F ~ alpha^n) and ``onset_order()`` (1 + n unless the law measured better), ``closing_limits_order``,
   ``constant_tangent``, ``builtin_granular_normal``; ``loading_time_scale(scene, A, T)`` (the loading
   regime's T against the law's time scale), from ``two_body_contact_time(scene, A)``, which a law
   gives unless it overrides loading_time_scale (Hertz's crossover T_c). A model of the law that a
   module measures (the bilinear chain's long-load fronts, postprocess.fronts) is one of its
   ``model_domains``: the module asks for the model, not the law.
8. The law's analytic models (optional: a law without any has empty tables), which `granchain
   predict`, `compare` and the peak plot take from the law and nowhere else:
   ``model_domains`` names every model the law predicts and what it needs (a loading regime, "any",
   "collision" or an effect's regime: MODEL_NEEDS); ``predictions(scene)`` gives the values of those
   that follow from the scene; ``measured_models(scene, values, observables)`` those that need a
   run's measured observables (a wave speed at the measured peak); ``compare_models`` the models
   each compared quantity is checked against; ``model_curves(scene, contacts, applies)`` the peak
   force along the chain of the models that apply. Whether a model applies to a scene is decided in
   one place, granchain.physics.predictions.applicability, from ``model_domains``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np

ArrayLike = np.ndarray | float


class Kink(NamedTuple):
    """An overlap level per contact where a law's force has a kink (RK4 event location)."""

    level: np.ndarray  # one per contact
    kind: str  # what happens there, in words (the event-location error message names it)
    where: np.ndarray | None = None  # contacts the kink applies to (bool per contact); None: all
    from_below: bool = False  # only a crossing from below counts (the overlap rising through it)


@dataclass(frozen=True)
class LawCoefficients:
    """A law's ``[contact]`` values as a scene gives them (ContactLaw.Coefficients): one field per key,
    None where the scene leaves the value to the materials. This base has none (the Hertz law's)."""

    @property
    def varies(self) -> bool:
        """Whether a key holds one value per bead-bead contact (the power law's lists): the scene's
        contacts then differ by more than their beads (Scene.per_bead, Scene.bead_kinds)."""
        return False

    def of_contact(self, i: int) -> LawCoefficients:
        """The values of bead-bead contact i (0-based; -1 the last), each one number: these, where
        no key varies."""
        return self


@dataclass(frozen=True)
class ContactLaw:
    """A normal contact law of a bead pair: per-contact parameters and vectorised functions."""

    name: ClassVar[str] = ""
    pair_style: ClassVar[str] = ""
    history: ClassVar[bool] = False
    #: the law's [contact] values (rule 1): one field per key
    Coefficients: ClassVar[type[LawCoefficients]] = LawCoefficients
    #: the [contact] keys the law reads besides law: its Coefficients' fields, in their order
    scene_keys: ClassVar[tuple[str, ...]] = ()
    #: each of scene_keys -> its unit (SI; "1": dimensionless): what a campaign's axes and columns print
    #: beside ``contact.<key>`` (granchain.scene.limits.SCENE_KEY_UNITS is made of them)
    key_units: ClassVar[dict[str, str]] = {}
    #: the [contact] key read_contact derives from a [chain.material] table's yield_strength when the
    #: scene gives none (the bilinear plastic_stiffness = 18.5 sigma_y R*), or None: a scene written
    #: back keeps the yield strength in the table and leaves the key to it (a table's yield strength
    #: and the key together are refused)
    yield_strength_key: ClassVar[str | None] = None
    #: tangent_stiffness is the same at every force (the bilinear law's unloading slope k_u): the
    #: planner's step then names no force it was taken at (workflows.plan)
    constant_tangent: ClassVar[bool] = False
    #: an integrator's error where a contact closes from zero overlap is limited to onset_order (a
    #: striker's or a wall's contact, one impact: workflows.errorbars); False where the closing is a
    #: kink RK4 locates and the force is smooth after it (the bilinear loading line)
    closing_limits_order: ClassVar[bool] = True
    #: the normal model of LAMMPS's built-in pair_style granular that gives this law
    #: (``hertz/material``; templates/builtin_granular.lmp.j2), or None: the built-in yardstick cannot
    #: run it (templates.deck.builtin_granular_refusal)
    builtin_granular_normal: ClassVar[str | None] = None
    #: dF/dalpha jumps at a kink that a contact's overlap crosses while it moves (bilinear: closing at
    #: alpha = 0 and reaching zero force; Thornton: reloading past d_max): fixed-step Verlet's error
    #: then depends on where in a step that happens and follows no order in dt, so its error bars come
    #: from RK4 runs, which locate the kinks (granchain.richardson.against_reference)
    slope_kinks: ClassVar[bool] = False
    #: force_into takes any overlap and gives the force of max(alpha, 0), bit for bit (a negative one
    #: gives +0.0): the reference solver's force evaluation then skips clipping alpha first
    force_into_any_sign: ClassVar[bool] = False
    #: a range of valid values of each parameter (SI), from which the registry's tests draw laws
    parameter_ranges: ClassVar[dict[str, tuple[float, float]]] = {}
    #: the [contact] keys (besides law) of an example: brass beads of R = 4.76 mm (docs and tests)
    example_contact: ClassVar[dict[str, float]] = {}
    #: a range of sensible values of each [contact] key for such beads (generated test scenes)
    scene_key_ranges: ClassVar[dict[str, tuple[float, float]]] = {}

    k: ArrayLike

    def __init_subclass__(cls, **kwargs) -> None:
        """Derive a subclass's ``scene_keys`` from its Coefficients' fields (rule 1), so the two never differ."""
        super().__init_subclass__(**kwargs)
        cls.scene_keys = tuple(f.name for f in dataclasses.fields(cls.Coefficients))
        if set(cls.key_units) != set(cls.scene_keys):
            raise TypeError(f"{cls.__name__}.key_units must give the unit of each of its keys {cls.scene_keys}")

    # ---- the law itself
    def force(self, alpha: ArrayLike, alpha_max: ArrayLike | None = None) -> np.ndarray:
        """The contact force F(alpha) of Eq. 1, never negative and zero where alpha <= 0 (rule 2).

        Parameters
        ----------
        alpha : array_like
            The overlap of each contact, alpha = u_i - u_{i+1} (Eq. 2; may be negative: apart).
        alpha_max : array_like, optional
            The largest overlap so far before this step (laws with history; None: a virgin contact).
            The law takes max(alpha_max, alpha) itself.

        Returns
        -------
        numpy.ndarray
            The force of each contact (N).
        """
        raise NotImplementedError

    def force_into(self, alpha: np.ndarray, alpha_max: np.ndarray, out: np.ndarray, tmp: np.ndarray) -> None:
        """force() into out (alpha >= 0; tmp a scratch array of the same shape)."""
        out[:] = self.force(alpha, alpha_max)

    def energy(self, alpha: ArrayLike, alpha_max: ArrayLike | None = None) -> np.ndarray:
        """The recoverable energy stored in each contact at overlap alpha with history alpha_max (J):
        with ``dissipated(max(alpha_max, alpha))`` it adds up to the work done on the contact (rule 2)."""
        raise NotImplementedError

    def dissipated(self, alpha_max: ArrayLike) -> np.ndarray:
        """The energy a contact has dissipated once its largest overlap reached alpha_max (J; the
        bilinear law's is Eq. 20). Zero here: an elastic law dissipates nothing."""
        return np.zeros_like(np.asarray(alpha_max, dtype=float))

    def update_history(self, alpha_max: np.ndarray, alpha: np.ndarray) -> None:
        """alpha_max = max(alpha_max, alpha), in place (laws with history)."""
        np.maximum(alpha_max, alpha, out=alpha_max)

    def loading_force(self, alpha: ArrayLike) -> np.ndarray:
        """The virgin loading curve: the force at a contact's largest overlap."""
        raise NotImplementedError

    def force_at_peak_overlap(self, alpha_peak: ArrayLike) -> np.ndarray:
        """The peak force of a contact whose largest overlap was alpha_peak (the virgin curve)."""
        return self.loading_force(alpha_peak)

    def static_overlap(self, force: ArrayLike) -> np.ndarray:
        """The overlap at which the virgin curve carries `force` (precompression)."""
        raise NotImplementedError

    def tangent_stiffness(self, force: ArrayLike) -> np.ndarray:
        """The stiffest dF/dalpha of a contact loaded up to `force` (planner, stability)."""
        raise NotImplementedError

    def loading_stiffness(self, force: ArrayLike) -> np.ndarray:
        """dF/dalpha of the virgin curve where it carries `force`: the stiffness a further compression
        meets from a static force on it (precompression's linearised chain; the unloading slope,
        ``tangent_stiffness``, may be stiffer)."""
        raise NotImplementedError

    def overlap_tangent(self, alpha: ArrayLike, alpha_max: ArrayLike | None = None) -> np.ndarray:
        """dF/dalpha of the branch in force at overlap alpha >= 0 (rule 3): the loading branch where
        alpha >= alpha_max (before this step, as force takes it), else the unloading one; 0 apart."""
        raise NotImplementedError

    def damping_tangent(self, alpha: ArrayLike, alpha_max: ArrayLike | None, force: ArrayLike) -> np.ndarray:
        """``overlap_tangent`` at overlap alpha given ``force``, the law's force there (the damping parts'
        tangent, rule 3; C++ ``tangent(alpha, am, d, f)``): a law may derive it from the force, as the
        power law's n F / alpha does instead of a second power; by default the force is not read."""
        return self.overlap_tangent(alpha, alpha_max)

    def max_stiffness(self, force: ArrayLike) -> np.ndarray:
        """The stiffest dF/dalpha of a contact loaded up to `force`: ``tangent_stiffness`` unless a law
        says otherwise."""
        return self.tangent_stiffness(force)

    def loading_exponent(self) -> np.ndarray:
        """The exponent n of the virgin curve's onset F ~ alpha^n at small overlaps, per contact (0-d for a
        uniform law): 3/2 for Hertz and Thornton's elastic start, 1 for the bilinear loading line, the
        power law's own n. An impact's force then grows as t^n from closing, and a smooth-force method's
        error as dt^(1 + n) there (granchain.richardson, workflows.error_estimates read it)."""
        raise NotImplementedError

    def onset_order(self) -> float:
        """The lowest order of a smooth-force integrator's error where a contact closes: 1 + n of the
        onset F ~ alpha^n (loading_exponent; the smallest over the contacts), unless the law knows
        better (the bilinear loading line's measured order). granchain.richardson and
        workflows.errorbars read it."""
        return 1.0 + float(np.min(self.loading_exponent()))

    def plastic_onset_force(self) -> np.ndarray:
        """The force above which a contact deforms plastically, per contact (N): infinite for a law
        that never yields (Hertz)."""
        return np.full(np.shape(self.k), np.inf)

    def kinks(self, alpha_max: np.ndarray) -> list[Kink]:
        """Where the force or one of its derivatives jumps, for RK4's event location (rule 4).

        Parameters
        ----------
        alpha_max : numpy.ndarray
            The largest overlap so far of each contact.

        Returns
        -------
        list of Kink
            Each kink's overlap level per contact, what happens there and the contacts it applies to.
        """
        raise NotImplementedError

    def turn_level(self, alpha_max: np.ndarray) -> np.ndarray | None:
        """The overlap above which a contact whose overlap turns from rising to falling starts unloading
        on another curve (rule 4), one per contact; None here: the law has no such kink."""
        return None

    def kink_screens(self, alpha_max: np.ndarray, a0: np.ndarray, a1: np.ndarray) -> list:
        """RK4 event location's screens of a piece whose overlaps go from a0 to a1 (one per contact):
        (kink, its level per contact, the contacts whose ends lie strictly on both sides of it) of
        each of kinks(alpha_max), in that order, that some contact straddles. A law may give the same
        with fewer numpy calls (bilinear: its kinks' where only when a contact straddles it)."""
        out = []
        for kink in self.kinks(alpha_max):
            level = kink.level
            if not (isinstance(level, np.ndarray) and level.shape == a0.shape):
                level = np.broadcast_to(level, a0.shape)
            idx = (np.less(a0, level) ^ np.less(a1, level)).nonzero()[0]
            if idx.size:
                out.append((kink, level, idx))
        return out

    def pair_coefficients(self) -> list[float]:
        """pair_coeff numbers after d0 in the C++ kernel's order (k first; the deck inserts d0)."""
        return [float(getattr(self, f.name)) for f in dataclasses.fields(self)]

    # ---- the planner's estimates (rule 7; granchain.physics.estimates and workflows.planning ask the law)
    @classmethod
    def wave_speeds(cls, scene, expected_force: float, step) -> tuple[float, float]:
        """(slowest leading-wave speed, fastest wave speed) the planner expects of the scene, m/s.

        Parameters
        ----------
        scene : granchain.scene.Scene
            A scene whose contact law is this one.
        expected_force : float
            The planner's expected peak force (N: physics.estimates.expected_peak_force).
        step : tuple or None
            The load's step equivalent (amplitude, duration), None for an impulse.

        Returns
        -------
        tuple of float
            The slowest and the fastest speed, m/s.
        """
        raise NotImplementedError

    @classmethod
    def leading_edge_speed(cls, scene, expected_force: float, step) -> float:
        """The fastest a disturbance can enter the undisturbed chain, m/s: the fastest of ``wave_speeds``
        unless a law knows a tighter bound (the bilinear loading line's sound speed)."""
        return cls.wave_speeds(scene, expected_force, step)[1]

    @classmethod
    def loading_time_scale(cls, scene, amplitude: float, duration: float) -> TimeScale:
        """A load of amplitude A (N) and duration T (s) against the law's time scale, from which
        granchain.physics.loading_regime tells short from long loads: here T / t_c with t_c the law's
        two-body contact time (two_body_contact_time) and CONTACT_TIME_SHORT_BELOW/LONG_ABOVE; a law
        whose chain has another time scale says so (Hertz: the crossover time T_c of Fig. 3)."""
        t_c, how = cls.two_body_contact_time(scene, amplitude)
        ratio = duration / t_c
        return TimeScale(
            ratio,
            CONTACT_TIME_SHORT_BELOW,
            CONTACT_TIME_LONG_ABOVE,
            "t_c",
            f"T = {ratio:.3g} t_c",
            f"t_c = {how} = {t_c:.3g} s",
        )

    @classmethod
    def two_body_contact_time(cls, scene, amplitude: float) -> tuple[float, str]:
        """(t_c in s, how it was found in words): the contact time of two of the scene's beads under a
        load of amplitude A (N) behind a long load's front (loading_time_scale reads it)."""
        raise NotImplementedError(f"the {cls.name} law gives no two-body contact time")

    # ---- the law's analytic models (rule 8; granchain.physics.predictions, postprocess.comparison_table and the
    # peak plot ask every law for its own)
    #: the law's name in running text ("a uniform Hertz chain"); empty: its name
    label: ClassVar[str] = ""
    #: model name -> what it needs besides this law: one of MODEL_NEEDS
    model_domains: ClassVar[dict[str, str]] = {}
    #: a quantity `granchain compare` measures -> the models it is checked against, in order of
    #: preference: (model name, label); the first that applies to the scene is used
    compare_models: ClassVar[dict[str, tuple[tuple[str, str], ...]]] = {}

    @classmethod
    def predictions(cls, scene) -> list[dict]:
        """The law's models that follow from the scene alone.

        Parameters
        ----------
        scene : granchain.scene.Scene
            A scene whose contact law is this one.

        Returns
        -------
        list of dict
            Prediction fields (name, value, unit, equation, valid[, nondim]), each name a key of
            ``model_domains``; a model the scene gives no value for (a long-load model under a
            velocity load) is left out.
        """
        return []

    @classmethod
    def measured_models(cls, scene, values: dict[str, float], observables: dict) -> dict[str, float]:
        """The law's models evaluated at what a run measured.

        Parameters
        ----------
        scene : granchain.scene.Scene
            A scene whose contact law is this one.
        values : dict
            The scene's predictions, name -> value (``predictions`` and the scene's own quantities).
        observables : dict
            The run's observables (granchain.postprocess.observables).

        Returns
        -------
        dict
            Model name (a key of ``model_domains``) -> value, for those the observables allow.
        """
        return {}

    @classmethod
    def model_curves(cls, scene, contacts: np.ndarray, applies) -> dict[str, np.ndarray]:
        """The peak force along the chain of the law's models that apply to the scene.

        Parameters
        ----------
        scene : granchain.scene.Scene
            A scene whose contact law is this one.
        contacts : numpy.ndarray
            Contact numbers (1-based, float) to evaluate the curves at.
        applies : callable
            ``applies(model name, label) -> bool``: whether the model applies to the scene (it records
            why not); asked once for every curve the law can draw, before its value is computed.

        Returns
        -------
        dict
            Legend label -> peak force (N) at `contacts` (NaN where the model does not hold).
        """
        return {}

    # ---- building laws
    @classmethod
    def join(cls, parts: list[tuple[ContactLaw, int]]) -> ContactLaw:
        """One law over consecutive groups of contacts: (law, number of contacts) each."""
        fields = [f.name for f in dataclasses.fields(cls)]
        values: dict[str, Any] = {}
        for f in fields:
            values[f] = np.concatenate(
                [np.broadcast_to(np.asarray(getattr(law, f), dtype=float), (n,)) for law, n in parts]
            )
        return cls(**values)

    def per_contact(self, n: int) -> ContactLaw:
        """The same law with every parameter as an array of n contacts."""
        return type(self).join([(self, n)])

    def contacts(self, n: int, start: int, stop: int | None = None) -> ContactLaw:
        """The law of contacts start..stop-1 of this law over n contacts."""
        whole = self.per_contact(n)
        return type(self)(**{f.name: getattr(whole, f.name)[start:stop] for f in dataclasses.fields(self)})

    @classmethod
    def read_contact(cls, section, chain) -> LawCoefficients:
        """Read and validate this law's ``[contact]`` keys.

        Parameters
        ----------
        section : granchain.scene.section.Section
            The ``[contact]`` table.
        chain : granchain.scene.Chain
            The scene's chain (its materials may give a value the table leaves out).

        Returns
        -------
        LawCoefficients
            The law's Coefficients, as the scene's Contact holds them.
        """
        forbid_others(section, cls)
        section.finish(("law", *cls.scene_keys))
        return cls.Coefficients()

    @classmethod
    def unsupported(cls, chain) -> str | None:
        """Why a chain (scene.Chain) cannot have this law, or None."""
        return None

    @classmethod
    def for_pair(
        cls, coefficients: LawCoefficients, e_star: float, r_star: float, nominal_r_star: float, materials=()
    ) -> ContactLaw:
        """The law of one contact: two bodies of effective modulus E* and radius R* (a bead on a flat:
        the flat's E* and R* = R), the scene's [contact] values (the law's Coefficients), the nominal
        pair's R* (bead 1 on bead 2) and the materials of the bodies that touch (the flat has none),
        for laws whose mixing rule reads them (the softer material's yield: docs/effects.md)."""
        raise NotImplementedError

    @classmethod
    def contact_to_dict(cls, contact) -> dict:
        """The [contact] table of a scene file for this law (scene_to_dict): law and the Coefficients
        of `contact` (a scene's Contact) the scene gave."""
        # (None: a value the scene left to the materials, e.g. a yield_pressure from the yield strength)
        values = {k: getattr(contact.coefficients, k) for k in cls.scene_keys}
        return {"law": cls.name, **{k: v for k, v in values.items() if v is not None}}


#: what a model may need besides its law (ContactLaw.model_domains): the paper's chain in a loading
#: regime (granchain.physics.loading_regime: "short", "long"), at "any" loading time, or a two-body impact
#: ("collision": two beads, bead 1 given a velocity, a free far end)
CHAIN_NEEDS = ("short", "long", "any", "collision")

#: ... or an effect's regime, where the paper's models do not hold: what the scene must be, in words
EFFECT_DOMAINS = {
    "precompressed": "a uniform Hertz chain under static precompression, no dashpot",
    # the sound speed c0: the limit of a wave small against F0 (physics.models.weakly_nonlinear_ratio)
    "weakly_nonlinear": "a uniform Hertz chain under static precompression, no dashpot, its wave's dynamic "
    "force small against F0 (weakly nonlinear)",
    "striker_impact": "a striker on one free bead, Hertz contact, no dashpot or precompression (two bodies)",
    "wall_impact": "one bead given a velocity against the wall, Hertz contact, no dashpot or precompression",
    "pair_impact": "two free beads, bead 1 given a velocity, Hertz contact, no dashpot or precompression (two bodies)",
    # a closed form of the nominal bead pair's contact itself (a yield force): any chain of uniform beads
    "contact": "the nominal bead pair's contact: uniform beads with this law",
}

#: every value a law's model_domains may hold
MODEL_NEEDS = (*CHAIN_NEEDS, *EFFECT_DOMAINS)


#: a load is short below this fraction of a law's two-body contact time t_c and long above this
#: multiple (ContactLaw.loading_time_scale). Measured on bilinear chains, t_c = pi sqrt(m / 2k) of the
#: plastic loading line k (Sec. III): contact 1's peak is within 0.5% of Eq. A2 at T = 0.1 t_c and 5% at
#: 0.36 t_c; the steady fronts of Sec. III B need many contact times.
CONTACT_TIME_SHORT_BELOW = 0.1
CONTACT_TIME_LONG_ABOVE = 10.0


class TimeScale(NamedTuple):
    """A load's duration T against a law's time scale (ContactLaw.loading_time_scale): T over it, the
    ratios below which the load is short and above which long, the scale's name, and in words T
    against it and how the scale was found (the loading regime's text)."""

    ratio: float
    short_below: float
    long_above: float
    unit: str
    ratio_text: str
    definition: str


class TwoBodies(NamedTuple):
    """A scene's two-body impact (two_bodies): the setup's name (a key of EFFECT_DOMAINS), the
    contact's law, the reduced mass m* (kg) and the bodies in words."""

    setup: str
    law: ContactLaw
    reduced_mass: float
    words: str


def two_bodies(scene) -> TwoBodies | None:
    """The scene's two-body impact (bead 1 on bead 2, a striker on one bead, one bead on the wall),
    or None where it is not one (the laws' and the damping parts' two-body models)."""
    if scene.chain.beads not in (1, 2):
        return None
    ld, m1 = scene.loading, float(scene.bead_masses[0])
    if scene.chain.beads == 2 and ld.kind == "velocity" and scene.effects.far_end == "free":
        m2 = float(scene.bead_masses[1])
        return TwoBodies("pair_impact", scene.contact_laws[0], m1 * m2 / (m1 + m2), "bead 1 on bead 2")
    if scene.chain.beads != 1:
        return None
    if ld.kind == "striker":
        ms = scene.striker_mass
        return TwoBodies("striker_impact", scene.striker_law, ms * m1 / (ms + m1), "the striker on bead 1")
    if ld.kind == "velocity" and scene.effects.far_end == "wall":
        return TwoBodies("wall_impact", scene.wall_law, m1, "the bead on the flat")
    return None


#: the registered laws, name -> class (granchain.physics.laws.LAWS fills it: the only list of laws)
REGISTRY: dict[str, type[ContactLaw]] = {}


def forbid_others(section, cls: type[ContactLaw]) -> None:
    """Reject [contact] keys of other laws, naming the law that has them."""
    for key in sorted({k for c in REGISTRY.values() for k in c.scene_keys}):
        if key in cls.scene_keys:
            continue
        owners = [name for name, c in REGISTRY.items() if key in c.scene_keys]
        section.forbid((key,), f'only the {" or ".join(owners)} law has it; set law = "{owners[0]}" or remove it')
