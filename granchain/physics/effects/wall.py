"""The far end: free (the default) or a wall touching bead N at t = 0 ([boundary] far_end = "wall"):
rigid (the default) or of a material (wall_material), flat (the default) or curved (wall_radius).

The wall is an immovable extra bead for the solvers (zero inverse mass) whose contact with bead N has
the wall's law (scene.wall_law: the scene's law with the pair's E* and R*, materials.wall_contact_pair;
on a rigid flat Hertz has R* = R and E* = E/(1-nu^2), bilinear twice the bead-bead k). It takes
momentum: a walled chain does not conserve it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from typing_extensions import override

from granchain.physics import materials as mat
from granchain.physics.effects.base import Bounds, Effect, watched_force

FAR_ENDS = ("free", "wall")

#: what [boundary] wall_material takes, in words
WALL_MATERIAL_TEXT = (
    f"a built-in material name ({', '.join(mat.MATERIALS)}) or an inline table of the values a "
    "[chain.material] table takes, {density = ..., youngs_modulus = ..., poisson_ratio = ...} (SI; "
    "yield_strength optional); leave it out for a rigid wall"
)


class WallEffect(Effect):
    """A rigid wall at the far end: a flat touching bead N at t = 0, on which the wave reflects.

    The paper's chain is semi-infinite (its far end free and never reached); with a wall, bead N
    presses on an immovable wall with the wall's law (``scene.wall_law``: the chain's law for a bead
    on the wall, with the pair's E* and R*; on a rigid flat R* = R and E* = E/(1-nu^2), for the
    bilinear law twice the bead-bead k; the damping, where the scene has one, on it too). The
    solvers integrate it as an extra bead of zero inverse mass after bead N; the results report its
    contact's peak force and time (``wall_peak_force``, ``wall_time_of_peak``). The wall takes
    momentum: a walled chain does not conserve it.

    Scene keys: ``[boundary] far_end`` = "free" (the default: no wall) or "wall";
    ``wall_material`` (a built-in name or an inline table; default: rigid) and ``wall_radius`` (m;
    default: a flat), only with a wall. Deck block:
    ``wall.lmp.j2`` in the "ends" slot (the wall's group, held at rest); its atom is the ``wall``
    atom type after bead N. LAMMPS's built-in granular pair style would see it as a sphere, so a
    walled scene has no yardstick.
    """

    name = "wall"
    label = '[boundary] far_end = "wall"'
    declaration = {"boundary": {"far_end": "wall"}}
    section = "boundary"
    scene_keys = ("far_end", "wall_material", "wall_radius")
    optional_keys = ("wall_material", "wall_radius")  # a rigid flat when left out
    fields = {"far_end": "free", "wall_material": None, "wall_radius": None}
    example = {"far_end": "wall", "wall_material": "aluminium-6061-t6", "wall_radius": 0.05}
    invalid = {"far_end": ("rigid", 1, True)}
    conserves_momentum = False
    deck_blocks = {"ends": "wall.lmp.j2"}
    yardstick = "a wall (the yardstick would see a sphere)"
    atom_type = "wall"

    @classmethod
    @override
    def active(cls, scene) -> bool:
        return scene.effects.far_end == "wall"

    @classmethod
    @override
    def in_problem(cls, problem) -> bool:
        return problem.wall_law is not None or not bool(np.isfinite(problem.mass[-1]))

    @classmethod
    @override
    def read(cls, section) -> dict[str, Any]:
        given = [k for k in ("wall_material", "wall_radius") if section.has(k)]
        # a missing far_end is the section's own message (it names the key and its values)
        if given and section.has("far_end") and section.raw("far_end") != "wall":
            raise section.error(
                f"[boundary] {given[0]} is the far-end wall's, but the chain has no wall: add "
                f'[boundary] far_end = "wall", or remove {" and ".join(given)}'
            )
        far_end = section.choice("far_end", FAR_ENDS)
        material = _read_wall_material(section) if section.has("wall_material") else None
        radius = section.number(
            "wall_radius",
            required=False,
            low=0.0,
            high=1e3,
            what="the wall's radius of curvature in m (no key: a flat)",
        )
        section.finish(cls.scene_keys)
        return {"far_end": far_end, "wall_material": material, "wall_radius": radius}

    @classmethod
    @override
    def to_dict(cls, effects) -> dict[str, Any] | None:
        if effects.far_end == "free":
            return None
        out: dict[str, Any] = {"far_end": effects.far_end}
        w = effects.wall_material
        if w is not None:
            out["wall_material"] = w if isinstance(w, str) else mat.material_values(w)
        if effects.wall_radius is not None:
            out["wall_radius"] = effects.wall_radius
        return out

    @classmethod
    @override
    def problem_fields(cls, scene, fields: dict[str, Any]) -> None:
        fields["wall_law"] = scene.wall_law

    @classmethod
    @override
    def ends(cls, problem, parts: list, mass: np.ndarray) -> np.ndarray:
        if problem.wall_law is None:
            return mass
        parts.append((problem.wall_law, 1))  # an immovable extra bead at the end (zero inverse mass)
        return np.append(mass, np.inf)

    @classmethod
    @override
    def end_fields(
        cls, force: np.ndarray, time: np.ndarray, velocity: np.ndarray, last: int, complete: np.ndarray
    ) -> dict[str, Any]:
        return {
            "wall_peak_force": float(force[last]),
            "wall_time_of_peak": float(time[last]),
            "wall_peak_complete": bool(complete[last]),
        }

    @classmethod
    @override
    def end_bounds(cls, scene, b: Bounds) -> None:
        # a neighbour of infinite mass: only the diagonal term; its contact sees the reflected wave,
        # up to twice the force, and no more than the run watch lets bead N's flat contact carry
        held = float(watched_force(scene.wall_law, b.radius[-1]))
        f = min(b.static_force + 2.0 * b.force, held)
        kw = float(np.asarray(scene.wall_law.tangent_stiffness(f), dtype=float))
        if f == held:
            b.extra["wall_held"] = held
        b.kr[-1], b.mr[-1], b.gr[-1] = kw, np.inf, b.viscous(kw)
        b.extra["wall"] = kw

    @classmethod
    @override
    def data_atoms(cls, scene, types: dict[str, int], x: np.ndarray) -> list[tuple[int, float, float, float]]:
        # the rigid flat: an atom at bead N's surface, never integrated; touching it with zero force and no
        # overlap in LAMMPS's arithmetic (touching_positions), unless precompression or gravity presses bead N into it
        from granchain.physics.positions import touching_positions

        r = float(scene.bead_radii[-1])
        xn = float(scene.bead_positions[-1])
        x = (
            xn + r
            if scene.effects.precompression or scene.effects.gravity
            else float(touching_positions([r], start=xn)[-1])
        )
        return [(types["wall"], 2.0 * r, scene.bead_materials[-1].density, x)]

    @classmethod
    @override
    def pair_coeffs(cls, scene, types: dict[str, int]) -> list[tuple[int, int, Any, float]]:
        # contact distance: bead centre to the flat, R. Only bead N's kind meets the wall; LAMMPS needs
        # every other kind's coefficients too (each kind's own law on the flat)
        tw = types["wall"]
        kinds, _ = scene.bead_kinds
        pairs = [(k + 1, tw, scene.flat_law(r, m), r) for k, (r, m) in enumerate(kinds)]
        rn = float(scene.bead_radii[-1])
        return pairs + [(tw, tw, scene.wall_law, rn)]


def _read_wall_material(section) -> str | mat.Material:
    """[boundary] wall_material: a built-in name (kept as the name, as the scene wrote it) or an
    inline table, read as a [chain.material] table is."""
    w = section.raw("wall_material")
    if isinstance(w, str):
        if w not in mat.MATERIALS:
            raise section.fail("wall_material", w, WALL_MATERIAL_TEXT)
        return w
    if isinstance(w, dict):
        return mat.read_material_table(type(section)(section.file, "boundary.wall_material", w))
    raise section.fail("wall_material", w, WALL_MATERIAL_TEXT)
