"""A linear dashpot ([damping] dashpot = gamma, N s/m): the force max(F(alpha) + gamma d(alpha)/dt, 0)."""

from __future__ import annotations

import numpy as np
from typing_extensions import override

from granchain.physics.damping.base import DampingPart


class Dashpot(DampingPart):
    """A viscous dashpot between overlapping beads: dissipation proportional to the relative velocity.

    While two beads overlap, their contact force is max(F(alpha) + gamma d(alpha)/dt, 0): the law's
    force plus a dashpot of coefficient gamma, never pulling. The paper's chains lose energy only
    by plasticity; its introduction cites dissipation tied to the beads' relative motion (its
    Refs. 15 and 16), of which this is the linear form. Its restitution does not depend on the impact
    speed for a linear law, and falls with it for Hertz (unlike Kuwabara-Kono's 1 - e ~ v^(1/5)).

    Scene key: ``[damping] dashpot`` = gamma in N s/m (positive and finite). Pair style:
    ``dashpot gamma`` (granchain/lammps/damping_dashpot.h); the energy it dissipates is the pair
    style's per-atom ``d_edash``. LAMMPS's built-in granular pair style has no such damping, so a
    dashpot scene has no yardstick.
    """

    name = "dashpot"
    key = "dashpot"
    label = "[damping] dashpot"
    unit = "N s/m"
    noun = "dashpot"
    phrase = "a dashpot"
    description = "viscous dashpot"
    symbol = "gamma"
    what = "gamma in N s/m: force gamma x relative velocity while beads overlap"
    example = 3.0
    invalid = (0.0, -1.0, "strong", float("inf"))
    velocity_dependent = True
    dissipated_vectors = ("d_edash",)
    yardstick = "a dashpot (the yardstick has no damping)"

    @classmethod
    @override
    def damped_force(cls, coefficient: float, law, alpha, alpha_max, rate, elastic) -> np.ndarray:
        # dashpot gamma * d(alpha)/dt while the beads overlap; the total never pulls
        return np.maximum(elastic + coefficient * rate, 0.0)

    @classmethod
    @override
    def contact_damping(cls, coefficient: float, tangent):
        return coefficient

    @classmethod
    @override
    def scale_refusal(cls, coefficient: float, lightest_mass: float, min_time: float) -> str | None:
        gamma, m_min = coefficient, lightest_mass
        if m_min / gamma >= min_time:
            return None
        return (
            f"[damping] dashpot = {gamma:g} N s/m is invalid: it damps the lightest body "
            f"({m_min:.3g} kg) in m/gamma = {m_min / gamma:.3g} s, under {min_time:g} s; a dashpot of at most "
            f"{m_min / min_time:.3g} N s/m (a viscous contact is damped over microseconds: gamma of "
            "about 1 to 100 N s/m for millimetre beads)"
        )
