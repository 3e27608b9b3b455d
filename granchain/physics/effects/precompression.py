"""Static precompression ([precompression] force = F0, N).

Every contact starts at F0 in static equilibrium (on its law's virgin curve; a law with history was
loaded to it), bead 1 is pushed by F0 for the whole run and the far end is held by the wall or by an
equal pull on bead N. Those static forces are external: they do work (F0 times bead 1's displacement,
minus F0 times a free bead N's) and the chain's momentum is not conserved.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from typing_extensions import override

from granchain.physics.effects.base import OVERLAP_WATCH, Bounds, Effect, watched_force


class PrecompressionEffect(Effect):
    """A static precompression F0: every contact starts loaded, and the wave travels on top of F0.

    Bead 1 is pushed by F0 for the whole run, and the far end is held by the wall or, on a free
    chain, by an equal pull on bead N; every contact starts in static equilibrium at F0 on its law's
    virgin curve (``granchain.problem.initial_state``). The paper's chains are uncompressed; a
    precompressed chain is linear about F0, and its observables are measured on the dynamic force
    (a contact's force less F0). The static forces are external: they do work and the chain's
    momentum is not conserved.

    Scene keys: ``[precompression] force`` = F0 in N (positive and finite). Deck block:
    ``precompression.lmp.j2`` in the "forces" slot (the push on bead 1, the pull on bead N when
    there is no wall, and a law with history's alpha_max set to the static overlaps); the beads'
    positions in the data file are the static equilibrium.
    """

    name = "precompression"
    label = "[precompression]"
    declaration = {"precompression": {"force": 50.0}}
    section = "precompression"
    scene_keys = ("force",)
    fields = {"precompression": 0.0}
    example = {"force": 50.0}
    invalid = {"force": (0.0, -5.0, "50 N", float("nan"))}
    conserves_momentum = False
    deck_blocks = {"forces": "precompression.lmp.j2"}

    @classmethod
    @override
    def active(cls, scene) -> bool:
        return bool(scene.effects.precompression)

    @classmethod
    @override
    def in_problem(cls, problem) -> bool:
        return bool(problem.precompression)

    @classmethod
    @override
    def read(cls, section) -> dict[str, Any]:
        f0 = section.number(
            "force",
            low=0.0,
            what="static force F0 in N on every contact, pushing bead 1 and held at the "
            "far end by the wall or by an equal force on bead N",
        )
        section.finish(cls.scene_keys)
        return {"precompression": f0}

    @classmethod
    @override
    def to_dict(cls, effects) -> dict[str, Any] | None:
        return {"force": effects.precompression} if effects.precompression else None

    @staticmethod
    def held_contacts(scene) -> list[tuple[str, Any, float]]:
        """Every kind of contact F0 compresses: (which, its law, the smaller radius of its two bodies),
        the bead-bead contacts (one per distinct pair of neighbouring bead kinds, the first in chain
        order) and the wall's (bead N on the flat: bead N's radius). The striker touches bead 1
        unloaded (problem.initial_state): its contact carries no F0."""
        if not scene.per_bead:  # also beads = "auto": a uniform chain
            held = [("every bead-bead contact", scene.law, float(scene.chain.radius))] if scene.chain.beads != 1 else []
        else:
            kinds, kind_of = scene.bead_kinds
            first: dict[tuple[int, int], int] = {}
            for i, pair in enumerate(zip(kind_of[:-1], kind_of[1:], strict=True)):
                first.setdefault(pair, i)
            held = []
            for (a, b), i in first.items():
                (ra, ma), (rb, mb) = kinds[a], kinds[b]
                which = f"contact {i + 1} (beads {i + 1} and {i + 2})"
                held.append((which, scene.bead_pair_law(ra, ma, rb, mb, i), min(ra, rb)))
        if scene.effects.far_end == "wall":
            held.append((f"bead {scene.chain.beads} on the wall", scene.wall_law, float(scene.bead_radii[-1])))
        return held

    @classmethod
    def largest_force(cls, scene) -> tuple[float, str, float, Any] | None:
        """The largest F0 the run watch lets a run start with: the smallest, over the contacts F0
        compresses (held_contacts), of the force its law's virgin curve carries at the run watch's
        overlap bound (watched_force: OVERLAP_WATCH x the smaller radius, the planner's rule); with the
        contact that sets it, its overlap bound in m and its law. None where F0 compresses no contact."""
        best = None
        for which, law, r in cls.held_contacts(scene):
            f = float(watched_force(law, r))
            if best is None or f < best[0]:
                best = (f, which, OVERLAP_WATCH * r, law)
        return best

    @classmethod
    @override
    def problem_fields(cls, scene, fields: dict[str, Any]) -> None:
        fields["precompression"] = scene.effects.precompression

    @classmethod
    @override
    def chain_bounds(cls, scene, b: Bounds) -> None:
        b.static_force = float(scene.effects.precompression)
        b.force = b.static_force + b.force  # every contact carries F0 on top of the wave

    @staticmethod
    def _free_end(problem) -> bool:
        """Bead N is free (not held by a wall, as a law or as the immovable bead of with_ends)."""
        return problem.wall_law is None and bool(np.isfinite(problem.mass[-1]))

    @classmethod
    @override
    def static_forces(cls, problem, fp: np.ndarray) -> float:
        f0 = float(problem.precompression)
        if f0 and cls._free_end(problem):
            fp[-1] = f0  # bead N held by an equal pull when there is no wall
        # the static push on bead 1 (the loading device); a shaker's driver holds F0 through its contact
        return 0.0 if problem.shaker else f0

    @classmethod
    @override
    def work(cls, problem, dx_first, dx_last, dx_mass=0.0):
        f0 = problem.precompression
        if not f0:
            return 0.0
        # a shaker's driver holds F0 through its contact (its work is the drive's): no push on bead 1
        push = 0.0 if problem.shaker else f0 * dx_first
        return push - (f0 * dx_last if cls._free_end(problem) else 0.0)

    @classmethod
    @override
    def watch_work(cls, problem, x_first: str, x_last: str, x_mass: str = "") -> str:
        f0 = problem.precompression
        if not f0:
            return ""
        text = "" if problem.shaker else f" + {float(f0)!r}*({x_first})"
        if cls._free_end(problem):
            text += f" - {float(f0)!r}*({x_last})"
        return text

    @classmethod
    @override
    def energy_columns(cls, layout) -> dict[str, tuple[str, str]]:
        return {"xN": (f"x[{layout.last_id}]", "x of bead N")}
