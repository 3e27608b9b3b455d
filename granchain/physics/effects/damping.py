"""Damping between overlapping beads ([damping]: one registered damping part and its coefficient).

The effect holds the scene's [damping] section and hands everything else to the scene's damping part
(granchain.physics.damping: the dashpot, Kuwabara-Kono): the contact force becomes the part's damped
total while the beads overlap (never pulling), whose extra work is dissipated (the pair style's
d_edash, the reference's integrated power). Its overdamped modes decay at up to the Gershgorin bound
of M^-1/2 C M^-1/2, which an explicit integrator must resolve like a frequency.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from typing_extensions import override

from granchain.physics.damping import DAMPING, damping_keys, damping_of
from granchain.physics.effects.base import Bounds, Effect

#: the scene's damping keys, in the registry's order
_KEYS = tuple(damping_keys())


class DampingEffect(Effect):
    """Dissipation in the contacts while beads overlap: the scene's damping part.

    Scene keys: one of ``[damping]``'s keys, each a registered damping part's coefficient
    (``dashpot`` = gamma in N s/m, ``kuwabara_kono`` = A in s; positive and finite); two together are
    refused (one damping part per scene: a sum of parts is a part of its own). Deck block:
    ``damping.lmp.j2`` in the "interactions" slot (ghost beads' velocities, which the pair style
    needs), with the part's words on the pair_style line; the energy it dissipates is the pair style's
    per-atom ``d_edash``. LAMMPS's built-in granular pair style has no such damping, so a damped
    scene has no yardstick.
    """

    name = "damping"
    label = "[damping]"
    declaration = {"damping": {"dashpot": 3.0}}
    section = "damping"
    scene_keys = _KEYS
    fields = dict.fromkeys(_KEYS, 0.0)
    example = {"dashpot": 3.0}
    invalid = {cls.key: cls.invalid for cls in DAMPING.values() if cls.key}
    # every part books its energy in the pair style's d_edash (the damping's vector: one part at a time)
    dissipated_vectors = ("d_edash",)
    deck_blocks = {"interactions": "damping.lmp.j2"}
    yardstick = "damping (the yardstick has none)"  # (the part's own words: yardstick_refusal)

    @classmethod
    def declaration_of(cls, part: str) -> dict[str, dict[str, Any]]:
        """The scene tables that declare damping part `part` with its example coefficient (tests)."""
        p = DAMPING[part]
        return {"damping": {p.key: p.example}} if p.key else {}

    @classmethod
    @override
    def active(cls, scene) -> bool:
        return damping_of(scene.effects)[0].velocity_dependent

    @classmethod
    @override
    def in_problem(cls, problem) -> bool:
        return problem.damping != "none"

    @classmethod
    @override
    def read(cls, section) -> dict[str, Any]:
        given = [key for key in _KEYS if section.has(key)]
        if not given:
            raise section.missing(
                _KEYS[0], "one damping part: " + "; ".join(f"{k} = {damping_keys()[k].what}" for k in _KEYS)
            )
        out = dict(cls.fields)
        for key in given:
            out[key] = section.number(key, low=0.0, what=damping_keys()[key].what)
        if len(given) > 1:
            section.forbid(
                tuple(given[1:]),
                f"one damping part per scene: {' and '.join(given)} together are not a model granchain has "
                f"(a sum of two dampings is a part of its own); keep one of them in [damping]",
            )
        section.finish(cls.scene_keys)
        return out

    @classmethod
    @override
    def to_dict(cls, effects) -> dict[str, Any] | None:
        part, coefficient = damping_of(effects)
        return {part.key: coefficient} if part.key else None

    @classmethod
    @override
    def problem_fields(cls, scene, fields: dict[str, Any]) -> None:
        part, coefficient = damping_of(scene.effects)
        fields["damping"] = part.name
        fields["damping_coefficient"] = coefficient

    @classmethod
    @override
    def chain_bounds(cls, scene, b: Bounds) -> None:
        b.damping, b.damping_coefficient = damping_of(scene.effects)

    @classmethod
    @override
    def reference_accel(cls, problem, law, inv_m: np.ndarray, fp: np.ndarray, alpha_hist: np.ndarray):
        part = problem.damping_part
        if not part.velocity_dependent:
            return None
        return damped_accel(part, float(problem.damping_coefficient), law, inv_m, fp, alpha_hist)

    @classmethod
    @override
    def yardstick_refusal(cls, scene) -> str | None:
        return damping_of(scene.effects)[0].yardstick

    @classmethod
    @override
    def pair_style_args(cls, scene) -> str:
        part, coefficient = damping_of(scene.effects)
        return part.pair_style_args(coefficient)


def damped_accel(
    part,
    coefficient: float,
    law,
    inv_m: np.ndarray,
    fp: np.ndarray,
    alpha_hist: np.ndarray,
    closing_at_touch: bool = False,
) -> Callable[[np.ndarray, np.ndarray, np.ndarray | None], float]:
    """The reference's force evaluation with a damping part (granchain.reference.state.make_accel): the
    accelerations into out, the contact forces into fp[1:-1], returns the damping's power.

    The damping acts while the beads overlap (alpha > 0), so its force jumps from 0 to the part's
    where a contact closes with a rate (a dashpot's gamma alpha'). closing_at_touch: a contact at
    exactly zero overlap that is closing (alpha' > 0) counts as closed, the force just after the
    touch (where it is not closing the force is 0 either way). RK4 asks for this: its stages move
    forward in time, and a stage at zero overlap with a closing rate -- bead 1 kicked or struck at
    t = 0 (the stage positions lag the stage velocities: a stage 2 at rest positions) or a piece that
    starts where event location found the touch -- is at the start of the contact; taking the force
    before it gives each such touch a first-order error. Measured (reference RK4 at the step planned
    for rtol 1e-3, peaks against the run at dt / 16): two brass beads kicked at 1 m/s with a dashpot
    of gamma = 20.6 N s/m 3.3e-3 without it, 2.1e-5 with it; struck by a striker at 1 m/s 1.5e-3,
    7.2e-6. Velocity Verlet keeps the force before the touch, as LAMMPS's pair styles (r < 2R), with
    which it agrees step for step.
    """
    n = fp.size - 1
    fc = fp[1:n]
    alpha = np.empty(n - 1)
    tmp = np.empty(n - 1)
    fe = np.empty(n - 1)
    touching = np.greater_equal if closing_at_touch else np.greater
    damped_force = part.damped_force

    def accel_damped(uu: np.ndarray, out: np.ndarray, vv: np.ndarray | None = None) -> float:
        np.subtract(uu[:-1], uu[1:], out=alpha)
        np.maximum(alpha, 0.0, out=alpha)
        law.force_into(alpha, alpha_hist, fc, tmp)
        # the part's damped total while the beads overlap; it never pulls
        rate = vv[:-1] - vv[1:]
        fe[:] = fc
        total = damped_force(coefficient, law, alpha, alpha_hist, rate, fc)
        fc[:] = np.where(touching(uu[:-1] - uu[1:], 0.0), total, fc)
        power = float(np.dot(fc - fe, rate))
        np.subtract(fp[:-1], fp[1:], out=out)
        out *= inv_m
        return power

    return accel_damped
