"""The scene's model: frozen dataclasses for the chain, the contact law, the load, the run, the
outputs and the effects, and the quantities derived from them (definitions live in granchain.physics).

Contact i is the contact between bead i and bead i+1 (the paper's F_{i,i+1}); beads and contacts are
numbered from 1 in scene files and output tables.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from granchain.physics import materials as mat
from granchain.physics.damping import DampingPart, damping_of
from granchain.physics.effects import effect_fields
from granchain.physics.laws import ContactLaw, LawCoefficients, contact_keys, law_class
from granchain.physics.positions import contact_quantum
from granchain.scene.display import html_table, scene_facts, scene_line
from granchain.scene.limits import AUTO
from granchain.scene.loading import Loading
from granchain.scene.run_outputs import Outputs, Run
from granchain.scene.writer import dump_toml, scene_to_dict

#: Scene.replace's default for its value: none given (None is a value a caller may mean)
_NO_VALUE = object()
#: granchain.scene.reader.replaced, set when the reader is imported (the reader is above the model)
_REPLACED = None


class UnplannedChainError(RuntimeError):
    """A quantity that needs the number of beads was asked of a chain of beads = "auto" before the
    planner chose it: a bug of the caller (it must plan the scene, or handle the unknown length), not
    the user's error, so it keeps its traceback."""


@dataclass(frozen=True)
class Chain:
    """The [chain] section: how many beads, their radius and material (one each, or one per bead).

    Attributes
    ----------
    beads : int or None
        N, the number of beads; None where the scene says "auto" (the planner chooses).
    radius : float
        R in m; with per-bead radii, bead 1's (the nominal bead the paper's scales use).
    material : Material
        The beads' material (density, Young's modulus, Poisson's ratio, yield strength); with
        per-bead materials, bead 1's.
    material_name : str or None
        The material's built-in name, or None for an inline ``[chain.material]`` table.
    radii : tuple of float or None
        Every bead's radius in m (a list or the taper rule), or None when all are ``radius``.
    materials : tuple of (str or Material), or None
        Every bead's material, as the ``[chain] material`` list gives it: a built-in name, or the
        Material of an inline table; None when all are ``material``.
    """

    beads: int | None  # None: "auto"
    radius: float  # m; with per-bead radii, bead 1's (the nominal one)
    material: mat.Material  # with per-bead materials, bead 1's
    material_name: str | None = None  # built-in name, or None for an inline [chain.material]
    radii: tuple[float, ...] | None = None  # per-bead radii (a list or the taper rule), or None
    materials: tuple[str | mat.Material, ...] | None = None  # per bead: a built-in name or an inline table


@dataclass(frozen=True)
class Contact:
    """The [contact] section: the law (a name in granchain.physics.laws.LAWS) and its values.

    Attributes
    ----------
    law : str
        The law's name (a key of granchain.physics.laws.LAWS).
    coefficients : granchain.physics.laws.LawCoefficients
        The law's [contact] values (its ``Coefficients``). Each also reads as ``contact.<key>``
        (``contact.unloading_coeff``): None where this contact's law has no such key.
    """

    law: str
    coefficients: LawCoefficients = field(default_factory=LawCoefficients)

    @property
    def law_class(self) -> type[ContactLaw]:
        """The registered ContactLaw subclass of ``law``."""
        return law_class(self.law)

    def __getattr__(self, name: str):
        """A [contact] key of any registered law: this law's value, None where it has no such key."""
        # a [contact] key of any registered law: this law's value, None where it has no such key
        if not name.startswith("_") and name in contact_keys():
            return getattr(self.coefficients, name, None)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")


@dataclass(frozen=True)
class Effects:
    """Effects beyond the paper's bare chain; each is absent unless the scene declares it.

    One attribute per field of a registered effect (``granchain.physics.effects.effect_fields``),
    at its absent value unless the scene declares the effect. A striker is a kind of load and
    per-bead radii and materials are the chain's; they have no field here.

    Attributes
    ----------
    far_end : str
        "free", or "wall": a wall touching bead N ([boundary] far_end).
    wall_material : str, Material or None
        The wall's material: a built-in name or a Material (an inline table); None: rigid
        ([boundary] wall_material).
    wall_radius : float or None
        The wall's radius of curvature, m; None: a flat ([boundary] wall_radius).
    dashpot : float
        gamma in N s/m, a linear dashpot on every closing contact; 0: none ([damping] dashpot).
    kuwabara_kono : float
        A in s, Kuwabara-Kono damping A dF/dalpha d(alpha)/dt; 0: none ([damping] kuwabara_kono). One
        damping key per scene (Scene.damping: the part they declare, granchain.physics.damping).
    precompression : float
        The static force F0 in N holding the chain together; 0: none ([precompression] force).
    gravity : float
        g in m/s^2 along the chain toward the wall (a vertical chain, bead 1 on top); 0: none
        ([gravity] g).
    """

    far_end: str = "free"
    wall_material: str | mat.Material | None = None
    wall_radius: float | None = None
    dashpot: float = 0.0
    kuwabara_kono: float = 0.0
    precompression: float = 0.0
    gravity: float = 0.0


def _check_effects_match_the_registry() -> None:
    """Effects' attributes are the registered effects' fields with their absent values: a new
    effect's field (Effect.fields) needs its attribute above, or scenes could not hold it."""
    declared = {f.name: f.default for f in fields(Effects)}
    if declared != effect_fields():
        raise RuntimeError(
            f"granchain.scene.Effects declares {declared}, the effect registry {effect_fields()}: "
            "give every registered effect's field an attribute of Effects with its absent value"
        )


_check_effects_match_the_registry()


@dataclass(frozen=True)
class Scene:
    """A validated scene: its sections as frozen dataclasses and the quantities derived from them.

    Read one with :func:`granchain.scene.load_scene`, :func:`~granchain.scene.parse_scene` or
    :func:`~granchain.scene.scene_from_dict`; :meth:`to_toml` writes it back.

    Attributes
    ----------
    chain, contact, loading, run, outputs, effects
        The sections (``effects`` holds every registered effect's fields, absent ones at their
        absent value).
    title : str
        The scene's title, or "".
    source : str or None
        Where it was read from: a path, ``<bundled scene NAME>``, or None.
    source_text : str or None
        The text it was read from, copied into run directories.
    """

    chain: Chain
    contact: Contact
    loading: Loading
    run: Run
    outputs: Outputs = field(default_factory=Outputs)
    effects: Effects = field(default_factory=Effects)
    title: str = ""
    source: str | None = None  # path of the scene file, if it came from one
    source_text: str | None = None  # the file's text, copied into run directories

    @property
    def needs_plan(self) -> bool:
        """Some value is "auto": run granchain.workflows.plan.plan_scene first."""
        return (
            self.chain.beads is None
            or self.run.end_time is None
            or self.run.timestep is None
            or AUTO in (self.outputs.history_interval, self.outputs.dump_interval)
        )

    # ---- derived quantities (definitions live in granchain.physics) ----
    @property
    def damping(self) -> type[DampingPart]:
        """The scene's damping part (granchain.physics.damping; the part "none" without [damping]): the
        facts the planner, the integrators and the checks ask it."""
        return damping_of(self.effects)[0]

    @property
    def damping_coefficient(self) -> float:
        """The damping part's coefficient (a dashpot's gamma in N s/m, Kuwabara-Kono's A in s), 0: none."""
        return damping_of(self.effects)[1]

    def planned_beads(self, what: str) -> int:
        """N, the number of beads, for a quantity that needs it (`what`, named in the error).

        Raises
        ------
        UnplannedChainError
            The scene says beads = "auto": the count is the planner's, which the caller must ask
            first (granchain.workflows.plan.plan_scene), or handle the chain of unknown length itself.
        """
        if self.chain.beads is None:
            raise UnplannedChainError(
                f'Scene.{what} needs the number of beads, and this scene says [chain] beads = "auto": plan it '
                "first (granchain.workflows.plan.plan_scene), or handle a chain of unknown length explicitly"
            )
        return self.chain.beads

    @property
    def has_contacts(self) -> bool:
        """The chain has a bead-bead contact: N > 1, or beads = "auto" (the planner makes it long)."""
        return self.chain.beads is None or self.chain.beads > 1

    @property
    def n_contacts(self) -> int:
        """The number of bead-bead contacts, N - 1 (a wall's contact not counted); the planned N
        (planned_beads: an "auto" chain is an UnplannedChainError)."""
        return self.planned_beads("n_contacts") - 1

    @property
    def mass(self) -> float:
        """The nominal bead's mass m = rho 4/3 pi R^3 (bead 1's radius and material), kg."""
        return mat.bead_mass(self.chain.material, self.chain.radius)

    @property
    def diameter(self) -> float:
        """The nominal bead's diameter D = 2R, m."""
        return 2.0 * self.chain.radius

    @property
    def e_star(self) -> float:
        """E* = E / (2 (1 - nu^2)) of two nominal beads (Sec. II A), Pa."""
        return mat.effective_modulus(self.chain.material)

    @property
    def r_star(self) -> float:
        """R* = R / 2 of two nominal beads (Sec. II A), m."""
        return mat.effective_radius(self.chain.radius)

    @property
    def tau(self) -> float:
        """The chain's intrinsic time scale tau = sqrt(pi rho R*^2 / (4 E*)) (Eq. 7), s."""
        return mat.time_scale(self.chain.material, self.chain.radius)

    @property
    def force_scale(self) -> float:
        """E* R*^2, the force scale of the nondimensional force F~ (Eq. 5), N."""
        return mat.force_scale(self.chain.material, self.chain.radius)

    @property
    def contact_force_scales(self) -> np.ndarray:
        """E* R*^2 of every bead-bead contact, in chain order (N): Eq. 5's force scale of the contact's
        own two beads (pair_effective_modulus, pair_effective_radius: Johnson's E* and R* of two
        spheres) on a chain whose beads differ (per_bead); force_scale at every contact of a uniform
        chain."""
        if not self.per_bead:
            return np.full(self.n_contacts, self.force_scale)
        r, m = self.bead_radii, self.bead_materials
        return np.array(
            [
                mat.pair_effective_modulus(m[i], m[i + 1]) * mat.pair_effective_radius(r[i], r[i + 1]) ** 2
                for i in range(len(r) - 1)
            ]
        )

    @property
    def impulse_scale(self) -> float:
        """E* R*^2 tau, the impulse scale of the nondimensional impulse I~ (Eq. 6), N s."""
        return mat.impulse_scale(self.chain.material, self.chain.radius)

    def pair_law(self, e_star: float, r_star: float, materials: tuple = (), contact: int = 0) -> ContactLaw:
        """The contact law of two bodies of effective modulus E* and radius R* and their materials (a
        flat has none), with the [contact] values of bead-bead contact `contact` (0-based, -1 the last:
        LawCoefficients.of_contact): the law's for_pair, its mixing rules included."""
        c = self.contact.coefficients.of_contact(contact)
        return self.contact.law_class.for_pair(c, e_star, r_star, self.r_star, materials)

    @property
    def law(self) -> ContactLaw:
        """The nominal bead-bead contact's law (bead 1's material and radius)."""
        return self.pair_law(self.e_star, self.r_star, (self.chain.material, self.chain.material))

    @property
    def stiffness(self) -> float:
        """Contact stiffness k of the nominal pair: Hertz k = 4 E* sqrt(R*)/3, the bilinear plastic slope."""
        return float(self.law.k)

    @property
    def per_bead(self) -> bool:
        """Beads differ in radius or material (tapered, decorated, impurity), or contacts in their
        [contact] values (a power law's per-contact exponent or stiffness): each contact has its own law."""
        return self.chain.radii is not None or self.chain.materials is not None or self.contact.coefficients.varies

    @property
    def bead_radii(self) -> np.ndarray:
        """Every bead's radius, bead 1 first, m (of the planned N: planned_beads)."""
        if self.chain.radii:
            return np.asarray(self.chain.radii)
        return np.full(self.planned_beads("bead_radii"), self.chain.radius)

    @property
    def bead_materials(self) -> list:
        """Every bead's Material, bead 1 first (of the planned N: planned_beads)."""
        if self.chain.materials:
            return [mat.bead_material(entry) for entry in self.chain.materials]
        return [self.chain.material] * self.planned_beads("bead_materials")

    @property
    def bead_masses(self) -> np.ndarray:
        """Every bead's mass, bead 1 first, kg."""
        return np.array([mat.bead_mass(m, r) for m, r in zip(self.bead_materials, self.bead_radii, strict=True)])

    @property
    def contact_quantum(self) -> float:
        """The grid of contact radii and positions (contact_quantum)."""
        return contact_quantum(self.bead_radii)

    def contact_radius(self, r: float) -> float:
        """A bead radius rounded up to the contact grid: contact distances R_i + R_j (pair_coeff d0) and
        positions (bead_positions) are sums of these, exact doubles (contact_quantum says why)."""
        q = self.contact_quantum
        return math.ceil(float(r) / q) * q

    @property
    def bead_positions(self) -> np.ndarray:
        """Centres of the beads at t = 0 before any precompression displacement, as LAMMPS's data file
        has them and everything reading LAMMPS's positions back subtracts (displacements, the run
        watch): in contact with zero force, x_1 = 0, x_(i+1) = x_i + R_i + R_(i+1) with the radii on the
        contact grid (contact_radius): exact, every at-rest overlap in LAMMPS's arithmetic exactly 0."""
        q = self.contact_quantum
        rc = np.ceil(self.bead_radii / q) * q
        return np.concatenate(([0.0], np.cumsum(rc[:-1] + rc[1:])))

    def bead_pair_law(self, r1: float, m1, r2: float, m2, contact: int = 0) -> ContactLaw:
        """The law of two beads (radius, material each) at bead-bead contact `contact` (its [contact]
        values: pair_law): Hertz 4/3 E*_pair sqrt(R*_pair) (Johnson); the plastic laws' mixing rules
        for two materials are the law's (ContactLaw.for_pair)."""
        e_star, r_star = mat.pair_effective_modulus(m1, m2), mat.pair_effective_radius(r1, r2)
        return self.pair_law(e_star, r_star, (m1, m2), contact)

    @property
    def bead_kinds(self) -> tuple[list[tuple[float, object]], list[int]]:
        """Distinct kinds of the chain's beads (one LAMMPS atom type each), each as its (radius,
        material), in order of first appearance, and each bead's kind (one kind for a uniform chain).

        A kind is a distinct (radius, material), unless the [contact] values vary per contact
        (LawCoefficients.varies): then it is (radius, material, i mod 3, the values of bead i's contact
        to its right), so that a pair of kinds tells its contact's values (the pair's two residues
        mod 3 tell which bead is on the left), with at most 3 x the distinct values kinds, not one a
        bead; such kinds may share a (radius, material)."""
        kinds: list[tuple[float, object]] = []
        index: dict = {}
        kind_of = []
        c = self.contact.coefficients
        n = len(self.bead_radii)
        for i, (r, m) in enumerate(zip(self.bead_radii.tolist(), self.bead_materials, strict=True)):
            key: tuple = (float(r), m)
            if c.varies:
                key += (i % 3, c.of_contact(i) if i < n - 1 else None)
            if key not in index:
                index[key] = len(kinds)
                kinds.append(key[:2])
            kind_of.append(index[key])
        return kinds, kind_of

    def pair_stiffness(self, r1: float, m1, r2: float, m2) -> float:
        """k of two beads (bead_pair_law)."""
        return float(self.bead_pair_law(r1, m1, r2, m2).k)

    @property
    def contact_laws(self) -> list[ContactLaw]:
        """The law of every bead-bead contact, in chain order."""
        r, m = self.bead_radii, self.bead_materials
        return [self.bead_pair_law(r[i], m[i], r[i + 1], m[i + 1], i) for i in range(len(r) - 1)]

    @property
    def contact_stiffnesses(self) -> np.ndarray:
        """k of every bead-bead contact's law, in chain order (N/m^(3/2) Hertz and Thornton, N/m bilinear)."""
        return np.array([float(law.k) for law in self.contact_laws])

    @property
    def drive_amplitude(self) -> float:
        """A harmonic drive's force amplitude, N: its A; a shaker's, the dynamic force of its driver's contact
        pressed A beyond its static overlap against a bead 1 held still, F(alpha_0 + A) - F0 (the planner's
        scale of a shaker's forces; the chain gives way, so the force is less); 0 for other loads."""
        ld = self.loading
        if not ld.is_shaker:
            return ld.amplitude if ld.is_harmonic else 0.0
        law, f0 = self.driver_law, float(self.effects.precompression)
        alpha0 = float(np.asarray(law.static_overlap(f0), dtype=float)) if f0 else 0.0
        return float(np.asarray(law.loading_force(alpha0 + ld.amplitude), dtype=float)) - f0

    @property
    def input_impulse(self) -> float:
        """Momentum put into the chain: A T (force loads), m v (bead 1), M V (striker); a shaker's, that of the
        force drive of its drive_amplitude."""
        ld = self.loading
        if ld.is_shaker:
            return replace(ld, kind="harmonic", amplitude=self.drive_amplitude).impulse
        if ld.is_force:
            return ld.impulse
        return (self.striker_mass if ld.kind == "striker" else self.mass) * ld.velocity

    @property
    def initial_momentum(self) -> float:
        """Momentum at t = 0: bead 1's m v (velocity load), the striker's M V, else 0."""
        ld = self.loading
        if ld.kind == "velocity":
            return float(self.bead_masses[0] if self.per_bead else self.mass) * ld.velocity
        if ld.kind == "striker":
            return self.striker_mass * ld.velocity
        return 0.0

    @property
    def striker_mass(self) -> float:
        """The striker's mass M: the scene's, else rho 4/3 pi R^3 of its radius and material, kg."""
        ld = self.loading
        return ld.striker_mass if ld.striker_mass is not None else mat.bead_mass(ld.striker_material, ld.striker_radius)

    @property
    def striker_law(self) -> ContactLaw:
        """Striker on bead 1: the law of the striker and bead 1 (see bead_pair_law), with contact 1's
        [contact] values (a per-contact list's first)."""
        ld = self.loading
        return self.bead_pair_law(ld.striker_radius, ld.striker_material, self.chain.radius, self.chain.material)

    @property
    def striker_stiffness(self) -> float:
        """k of the striker's contact on bead 1 (striker_law)."""
        return float(self.striker_law.k)

    def wall_pair(self, r: float, m) -> tuple[float, float, tuple]:
        """E*, R* and materials of a bead (radius, material) on the far-end wall: the wall's material
        and radius, rigid and flat unless the scene gives them (materials.wall_contact_pair)."""
        w = self.effects.wall_material
        return mat.wall_contact_pair(m, r, None if w is None else mat.bead_material(w), self.effects.wall_radius)

    def flat_law(self, r: float, m) -> ContactLaw:
        """A bead (radius, material) on the wall (wall_pair's E*, R*, materials); on a rigid flat
        R* = R and E* = E/(1-nu^2) (Hertz, Thornton), bilinear k = 18.5 sigma_y R* with R* = R,
        i.e. twice the bead-bead k. On a wall of a material, a plastic law takes the softer's yield
        as between beads: the [contact] value the law derives from the chain's yield strength
        (yield_strength_key: the bilinear k) is left to the pair's mixing rule."""
        e_star, r_star, materials = self.wall_pair(r, m)
        if self.effects.wall_material is None or self.contact.law_class.yield_strength_key is None:
            return self.pair_law(e_star, r_star, materials, -1)  # (a per-contact list: the last contact's)
        c = replace(self.contact.coefficients.of_contact(-1), **{self.contact.law_class.yield_strength_key: None})
        return self.contact.law_class.for_pair(c, e_star, r_star, self.r_star, materials)

    @property
    def driver_law(self) -> ContactLaw:
        """A shaker's driver on bead 1 (granchain.physics.shaker): a rigid flat, R* = R and E* = E/(1-nu^2)
        of bead 1 as on a rigid wall, with the [contact] values of contact 1."""
        e_star, r_star, materials = mat.wall_contact_pair(self.bead_materials[0], float(self.bead_radii[0]), None, None)
        return self.pair_law(e_star, r_star, materials, 0)

    @property
    def wall_law(self) -> ContactLaw:
        """Bead N on the wall (flat_law of bead N's radius and material)."""
        return self.flat_law(float(self.bead_radii[-1]), self.bead_materials[-1])

    @property
    def wall_stiffness(self) -> float:
        """k of bead N's contact on the wall (wall_law)."""
        return float(self.wall_law.k)

    @property
    def unloading_stiffness(self) -> float | None:
        """k_u of the nominal contact (bilinear), else None."""
        ku = getattr(self.law, "k_unloading", None)
        return None if ku is None else float(ku)

    @property
    def wall_event(self) -> bool:
        """Whether the run tracks the far-end wall's event at every step ([outputs] event on a walled
        chain; on a free far end the event's quantities are read from the end state)."""
        return bool(self.outputs.event) and self.effects.far_end == "wall"

    @property
    def peak_contacts(self) -> tuple[int, ...]:
        """Contacts (1-based) in the peak-force table."""
        if self.outputs.peak_force is True:
            return tuple(range(1, self.n_contacts + 1))
        if self.outputs.peak_force is False:
            return ()
        return tuple(self.outputs.peak_force)

    @property
    def window(self) -> tuple[int, int]:
        """Contacts over which the leading peak and wave speed are measured.

        The scene's ``[outputs] window`` if given; else, with a list of peak contacts, its first to
        its last; else the second and third quarters of the chain, away from the loaded end (where
        the wave forms) and from the far end (where it reflects).
        """
        if self.outputs.window is not None:
            return self.outputs.window
        if isinstance(self.outputs.peak_force, tuple) and len(self.outputs.peak_force) >= 2:
            return (min(self.outputs.peak_force), max(self.outputs.peak_force))
        n = self.n_contacts
        a = max(1, n // 4)
        b = max(a + 1, (3 * n) // 4)
        return (a, min(b, n))

    def to_toml(self) -> str:
        """The scene as TOML text; read back by :func:`parse_scene` to an equal scene."""
        return dump_toml(scene_to_dict(self))

    def replace(self, changes: str | dict, value=_NO_VALUE, /) -> Scene:
        """A new scene with scene keys changed, validated as the scene reader validates a file.

        Parameters
        ----------
        changes : str or dict
            A dotted scene key (``"loading.amplitude"``, ``"chain.material.density"``) with `value`,
            or a dict of such keys -> values, set together (keys that only go together, such as a
            loading's kind and its values, are validated at once).
        value
            The new value of the key `changes` names, as a scene file writes it (a number, a string,
            a list, ``"auto"``).

        Returns
        -------
        Scene
            The scene :meth:`to_toml`'s text with those keys changed would read as, with this scene's
            ``source`` and the changed text as ``source_text``; this scene is left as it is.

        Raises
        ------
        SceneError
            A key or value is invalid: the reader's message, naming the key and the fix.
        """
        if isinstance(changes, str):
            if value is _NO_VALUE:
                raise TypeError(f"Scene.replace({changes!r}) needs the key's new value: replace({changes!r}, value)")
            changes = {changes: value}
        elif value is not _NO_VALUE:
            raise TypeError("Scene.replace(dict) takes the keys' values in the dict, not a second argument")
        return _REPLACED(self, dict(changes))

    def __repr__(self) -> str:
        """The scene in one line: source, beads, law, loading, run and effects (scene_line)."""
        return scene_line(self)

    def _repr_html_(self) -> str:
        """A small table for notebooks: the scene's facts with their units (scene_facts)."""
        return html_table(scene_facts(self), "granchain Scene")
