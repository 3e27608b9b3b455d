"""Viscous dissipation between overlapping beads ([damping] dashpot = gamma, N s/m).

The contact force becomes max(F(alpha) + gamma d(alpha)/dt, 0) while the beads overlap (the total
never pulls); the energy it takes out is dissipated (the pair style's d_edash, the reference's
integrated power). Its overdamped modes decay at up to the Gershgorin bound of M^-1/2 C M^-1/2,
which an explicit integrator must resolve like a frequency.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from typing_extensions import override

from granchain.physics.effects.base import Bounds, Effect


class DashpotEffect(Effect):
    """A viscous dashpot between overlapping beads: dissipation proportional to the relative velocity.

    While two beads overlap, their contact force is max(F(alpha) + gamma d(alpha)/dt, 0): the law's
    force plus a dashpot of coefficient gamma, never pulling. The paper's chains lose energy only
    by plasticity; its introduction cites dissipation tied to the beads' relative motion (its
    Refs. 15 and 16), of which this is the linear form.

    Scene keys: ``[damping] dashpot`` = gamma in N s/m (positive and finite). Deck block:
    ``damping.lmp.j2`` in the "interactions" slot (ghost beads' velocities, which the pair style
    needs), with ``dashpot gamma`` on the pair_style line; the energy it dissipates is the pair
    style's per-atom ``d_edash``. LAMMPS's built-in granular pair style has no such damping, so a
    dashpot scene has no yardstick.
    """

    name = "dashpot"
    label = "[damping] dashpot"
    declaration = {"damping": {"dashpot": 3.0}}
    section = "damping"
    scene_keys = ("dashpot",)
    fields = {"dashpot": 0.0}
    example = {"dashpot": 3.0}
    invalid = {"dashpot": (0.0, -1.0, "strong", float("inf"))}
    dissipated_vectors = ("d_edash",)
    deck_blocks = {"interactions": "damping.lmp.j2"}
    yardstick = "a dashpot (the yardstick has no damping)"

    @classmethod
    @override
    def active(cls, scene) -> bool:
        return bool(scene.effects.dashpot)

    @classmethod
    @override
    def in_problem(cls, problem) -> bool:
        return bool(problem.dashpot)

    @classmethod
    @override
    def read(cls, section) -> dict[str, Any]:
        gamma = section.number(
            "dashpot", low=0.0, what="gamma in N s/m: force gamma x relative velocity while beads overlap"
        )
        section.finish(cls.scene_keys)
        return {"dashpot": gamma}

    @classmethod
    @override
    def to_dict(cls, effects) -> dict[str, Any] | None:
        return {"dashpot": effects.dashpot} if effects.dashpot else None

    @classmethod
    @override
    def problem_fields(cls, scene, fields: dict[str, Any]) -> None:
        fields["dashpot"] = scene.effects.dashpot

    @classmethod
    @override
    def chain_bounds(cls, scene, b: Bounds) -> None:
        b.gamma = float(scene.effects.dashpot)

    @classmethod
    @override
    def reference_accel(cls, problem, law, inv_m: np.ndarray, fp: np.ndarray, alpha_hist: np.ndarray):
        gamma = float(problem.dashpot)
        return dashpot_accel(law, inv_m, gamma, fp, alpha_hist) if gamma else None

    @classmethod
    @override
    def pair_style_args(cls, scene) -> str:
        return f" dashpot {float(scene.effects.dashpot)!r}"


def dashpot_accel(
    law, inv_m: np.ndarray, gamma: float, fp: np.ndarray, alpha_hist: np.ndarray, closing_at_touch: bool = False
) -> Callable[[np.ndarray, np.ndarray, np.ndarray | None], float]:
    """The reference's force evaluation with a dashpot (granchain.reference.state.make_accel): the
    accelerations into out, the contact forces into fp[1:-1], returns the dashpot's power.

    The dashpot acts while the beads overlap (alpha > 0), so its force jumps from 0 to gamma alpha'
    where a contact closes. closing_at_touch: a contact at exactly zero overlap that is closing
    (alpha' > 0) counts as closed, the force just after the touch (where it is not closing the
    force is 0 either way). RK4 asks for this: its stages move forward in time, and a stage at zero
    overlap with a closing rate -- bead 1 kicked or struck at t = 0 (the stage positions lag the
    stage velocities: a stage 2 at rest positions) or a piece that starts where event location found
    the touch -- is at the start of the contact; taking the force before it gives each such touch a
    first-order error. Measured (reference RK4 at the step planned for rtol 1e-3, peaks against the
    run at dt / 16): two brass beads kicked at 1 m/s with gamma = 20.6 N s/m 3.3e-3 without it,
    2.1e-5 with it; struck by a striker at 1 m/s 1.5e-3, 7.2e-6. Velocity Verlet keeps the force
    before the touch, as LAMMPS's pair styles (r < 2R), with which it agrees step for step.
    """
    n = fp.size - 1
    fc = fp[1:n]
    alpha = np.empty(n - 1)
    tmp = np.empty(n - 1)
    fe = np.empty(n - 1)
    touching = np.greater_equal if closing_at_touch else np.greater

    def accel_dashpot(uu: np.ndarray, out: np.ndarray, vv: np.ndarray | None = None) -> float:
        np.subtract(uu[:-1], uu[1:], out=alpha)
        np.maximum(alpha, 0.0, out=alpha)
        law.force_into(alpha, alpha_hist, fc, tmp)
        # dashpot gamma * d(alpha)/dt while the beads overlap; the total never pulls
        rate = vv[:-1] - vv[1:]
        fe[:] = fc
        fc[:] = np.where(touching(uu[:-1] - uu[1:], 0.0), np.maximum(fc + gamma * rate, 0.0), fc)
        power = float(np.dot(fc - fe, rate))
        np.subtract(fp[:-1], fp[1:], out=out)
        out *= inv_m
        return power

    return accel_dashpot
