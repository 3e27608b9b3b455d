"""The atoms of a deck: their IDs and types (AtomLayout), the data file that places them
(chain.data), and the pair coefficients between their types."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from granchain.physics.effects import active_effects
from granchain.physics.laws import ContactLaw
from granchain.problem import precompressed_displacements, scene_static_load
from granchain.scene import SceneError
from granchain.templates.filters import float_repr


def largest_radius(scene) -> float:
    """The largest radius of the deck's moving bodies: the beads' and a striker's (a striker larger than
    the beads must not see its own periodic image across y and z, and its cutoff sets the bins)."""
    r = float(max(scene.bead_radii)) if scene.per_bead else float(scene.chain.radius)
    if scene.loading.kind == "striker":
        r = max(r, float(scene.loading.striker_radius))
    return r


@dataclass(frozen=True)
class AtomLayout:
    """Atom IDs and types: the atoms of effects with beads in front (a striker, ID 1), the beads, the
    other effects' atoms (a wall, last); each effect's atom a type of its own (Effect.atom_type), in
    registry order after the beads'.

    Contact i (beads i and i+1) lives on the atom of bead i, ID i + offset.

    Attributes
    ----------
    beads : int
        N, the chain's beads.
    extra_types : tuple of str
        The effects' atom types ("striker", "wall"), in registry order.
    offset : int
        Atoms in front of bead 1 (Effect.beads_in_front): 1 with a striker, else 0.
    skin : float
        The neighbour skin in m: 0.2 x the smallest bead diameter.
    rmax : float
        The largest radius of a body that moves (beads, a striker), m.
    bead_types : int
        The bead kinds (Scene.bead_kinds): atom types 1..bead_types.
    last_bead_type : int
        Bead N's atom type.
    """

    beads: int
    extra_types: tuple[str, ...]  # the effects' atom types, in registry order
    offset: int  # atoms in front of bead 1 (Effect.beads_in_front)
    skin: float  # neighbor skin: 0.2 x the smallest bead diameter
    rmax: float  # the largest radius of a body that moves (beads, a striker)
    bead_types: int = 1  # bead kinds (Scene.bead_kinds): types 1..bead_types
    last_bead_type: int = 1  # bead N's type

    @classmethod
    def of(cls, scene) -> AtomLayout:
        """The layout of a scene's deck: its beads, bead kinds and the atoms of the effects it declares."""
        skin = 0.2 * 2.0 * float(min(scene.bead_radii)) if scene.per_bead else 0.2 * scene.diameter
        rmax = largest_radius(scene)
        active = active_effects(scene)
        extra = tuple(e.atom_type for e in active if e.atom_type)
        kinds, kind_of = bead_kinds(scene) if scene.per_bead else ([None], [0])
        front = sum(e.beads_in_front for e in active)
        return cls(scene.chain.beads, extra, front, skin, rmax, len(kinds), kind_of[-1] + 1)

    @property
    def binsize(self) -> float:
        """Bins for neighbour builds and atom sorting: 2 x (the contact distance + skin), wider than
        LAMMPS's default half of it. A chain along x needs few bins across; at LAMMPS's default,
        1e6 beads take 83 million bins (a third of a GB)."""
        return 2.0 * (2.0 * self.rmax + self.skin)

    @property
    def striker(self) -> bool:
        """A striker atom: ID 1, in front of bead 1."""
        return "striker" in self.extra_types

    @property
    def wall(self) -> bool:
        """A wall atom: the deck integrates the group mobile (all but the wall) instead of all."""
        return "wall" in self.extra_types

    @property
    def types(self) -> dict[str, int]:
        """Atom types: the bead kinds first (1..bead_types; "bead" names the first), then each
        effect's atom, in registry order."""
        first = self.bead_types + 1
        return {"bead": 1, **{name: first + i for i, name in enumerate(self.extra_types)}}

    @property
    def atom_types(self) -> int:
        """The deck's atom types: the bead kinds and one per effect atom (chain.data's "atom types")."""
        return self.bead_types + len(self.extra_types)

    @property
    def natoms(self) -> int:
        """The deck's atoms: the beads and the effects' atoms."""
        return self.beads + len(self.extra_types)

    @property
    def first_id(self) -> int:
        """Bead 1's atom."""
        return 1 + self.offset

    @property
    def last_id(self) -> int:
        """Bead N's atom."""
        return self.beads + self.offset

    @property
    def wall_id(self) -> int:
        """The wall's atom: the last, after bead N."""
        return self.last_id + 1

    def ids(self, contacts) -> list[int]:
        """The atoms contacts live on (bead i's)."""
        return [i + self.offset for i in contacts]


def atom_layout(scene) -> dict:
    """AtomLayout as a dict: offset, striker, wall, types, natoms."""
    lay = AtomLayout.of(scene)
    return {"offset": lay.offset, "striker": lay.striker, "wall": lay.wall, "types": lay.types, "natoms": lay.natoms}


MAX_BEAD_KINDS = 200  # pair_coeff lines grow as kinds^2 / 2


def bead_kinds(scene) -> tuple[list[tuple[float, object]], list[int]]:
    """Scene.bead_kinds, at most MAX_BEAD_KINDS of them (one atom type each); atom type = kind + 1."""
    kinds, kind_of = scene.bead_kinds
    if len(kinds) > MAX_BEAD_KINDS:
        raise SceneError(
            f"{scene.source}: the chain has {len(kinds)} distinct bead kinds (radius, material"
            + (", and the [contact] values of the bead's contacts" if scene.contact.coefficients.varies else "")
            + f"); the LAMMPS backend takes at most {MAX_BEAD_KINDS} (one atom type each); use the reference backend"
        )
    return kinds, kind_of


def render_data(scene) -> str:
    """The text of chain.data, the LAMMPS data file (atom_style sphere) the deck reads.

    One line per atom, "ID type diameter density x 0 0", in ID order: the effects' atoms in front
    (a striker), the beads, the others (a wall; Effect.data_atoms). The beads touch with zero force
    on the contact grid (Scene.bead_positions: every at-rest overlap exactly 0 in LAMMPS's
    arithmetic), displaced by the static displacements of a precompression. The box spans the atoms
    with 2 rmax to spare along x, and +-4 rmax across, wider than cutoff + skin, so that no body
    sees its own periodic image.
    """
    n, d = scene.chain.beads, scene.diameter
    lay = atom_layout(scene)
    rmax = largest_radius(scene)
    w = 4.0 * rmax  # periodic y/z sides wider than cutoff + skin, so no body sees its own image
    rho = scene.chain.material.density
    u0 = np.zeros(n)
    if scene_static_load(scene):
        u0 = precompressed_displacements(scene)[0]
    # touching with zero force, overlaps exactly 0 in LAMMPS's arithmetic; displaced by a precompression
    x = scene.bead_positions + u0
    front: list[tuple[int, float, float, float]] = []  # the effects' atoms (Effect.data_atoms)
    back: list[tuple[int, float, float, float]] = []
    for effect in active_effects(scene):
        (front if effect.beads_in_front else back).extend(effect.data_atoms(scene, lay["types"], x))
    atoms = list(front)
    if scene.per_bead:  # one atom type per distinct (radius, material): see bead_kinds
        kinds, kind_of = bead_kinds(scene)
        atoms += [(kind_of[i] + 1, 2.0 * kinds[kind_of[i]][0], kinds[kind_of[i]][1].density, x[i]) for i in range(n)]
    else:
        atoms += [(1, d, rho, x[i]) for i in range(n)]
    atoms += back
    xlo = min(a[3] for a in atoms) - 2.0 * rmax
    xhi = max(a[3] for a in atoms) + 2.0 * rmax
    lines = [
        "granchain chain: beads in contact with zero force, on an exact grid (granchain.physics.positions)",
        "",
        f"{len(atoms)} atoms",
        f"{max(a[0] for a in atoms)} atom types",
        "",
        f"{float_repr(xlo)} {float_repr(xhi)} xlo xhi",
        f"{float_repr(-w)} {float_repr(w)} ylo yhi",
        f"{float_repr(-w)} {float_repr(w)} zlo zhi",
        "",
        "Atoms # sphere",
        "",
    ]
    lines += [
        f"{i + 1} {t} {float_repr(dd)} {float_repr(rr)} {float_repr(x)} 0.0 0.0"
        for i, (t, dd, rr, x) in enumerate(atoms)
    ]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class PairCoeff:
    """One pair_coeff line: atom types I and J, their contact's law and contact distance d0.

    Attributes
    ----------
    i, j : int
        The two atom types.
    law : ContactLaw
        The law of a contact between them (Scene.bead_pair_law, or an effect's: the wall's flat_law,
        the striker's).
    d0 : float
        The contact distance in m, at which the overlap is 0: R_i + R_j on the contact grid
        (Scene.contact_radius), R for a bead on the wall.
    """

    i: int
    j: int
    law: ContactLaw
    d0: float

    @property
    def args(self) -> list[float]:
        """pair_coeff I J k d0 [the law's other coefficients] (granchain.physics.laws.base, rule 5)."""
        k, *extra = self.law.pair_coefficients()
        return [k, self.d0, *extra]


def pair_coeffs(scene, layout: AtomLayout) -> list[PairCoeff]:
    """Every type pair's contact: beads (one type per bead kind of a per-bead chain), the wall's
    (distance from the bead's centre to the flat, R) and the striker's (R_s + R; striker and wall
    never meet, but their coefficients are required)."""
    rc = scene.contact_radius  # contact distances on the positions' grid: at-rest overlaps exactly 0
    pairs = [PairCoeff(1, 1, scene.law, 2.0 * rc(scene.chain.radius))]
    if scene.per_bead:
        kinds, kind_of = bead_kinds(scene)
        met = _contacts_of_kind_pairs(scene, kind_of)
        pairs = [
            PairCoeff(
                a + 1,
                b + 1,
                scene.bead_pair_law(*kinds[a], *kinds[b], met.get((a, b), 0)),
                rc(kinds[a][0]) + rc(kinds[b][0]),
            )
            for a in range(len(kinds))
            for b in range(a, len(kinds))
        ]
    for effect in active_effects(scene):  # the effects' atom types (Effect.pair_coeffs)
        pairs += [PairCoeff(*c) for c in effect.pair_coeffs(scene, layout.types)]
    return pairs


def _contacts_of_kind_pairs(scene, kind_of: list[int]) -> dict[tuple[int, int], int]:
    """(kind a, kind b), a <= b -> the first bead-bead contact between beads of those kinds, whose
    [contact] values the pair's line carries; {} where the values do not vary per contact (every
    pair then has one law: Scene.bead_kinds says why a pair of kinds meets at one contact's values)."""
    if not scene.contact.coefficients.varies:
        return {}
    first: dict[tuple[int, int], int] = {}
    for i in range(len(kind_of) - 1):
        a, b = sorted((kind_of[i], kind_of[i + 1]))
        first.setdefault((a, b), i)
    return first
