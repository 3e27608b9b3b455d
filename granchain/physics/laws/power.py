"""Power-law contacts: F = K alpha^n, stored energy K alpha^(n+1) / (n+1), no history.

``[contact] law = "power"`` with ``exponent = n`` (1 <= n <= 3) and ``stiffness = K`` (N/m^n): a
contact of any elastic exponent (n = 1 a linear spring that opens, n = 3/2 Hertz, n > 3/2 conical or
rough contacts; interfaces and disorder in n: Kekic and Van Gorder, Physica D 2018). K and n are the
scene's and hold for every contact of the scene, bead-bead, bead-wall and striker-bead alike (they are
not derived from the bodies' E* and R*). The law's model is the elastic two-body impact
(power_impact). The C++ twin is granchain/lammps/law_power.h.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np
from typing_extensions import override

from granchain.physics import models
from granchain.physics.laws.base import ArrayLike, ContactLaw, Kink, LawCoefficients, forbid_others

#: the exponents the law takes (1: a linear spring; 3: the stiffest the planner's estimates are made for)
EXPONENT_RANGE = (1.0, 3.0)


def power_impact(k: float, n: float, reduced_mass: float, velocity: float) -> dict[str, float]:
    """Two elastic bodies meeting at relative velocity v under F = K delta^n, m* their reduced mass (a
    wall: the bead's mass). Energy gives delta_max = ((n+1) m* v^2 / (2K))^(1/(n+1)), the peak force
    K delta_max^n; the contact time is 2 (delta_max / v) sqrt(pi) Gamma(1 + 1/(n+1)) / Gamma(1/2 +
    1/(n+1)) (the quarter period of m* delta'' = -K delta^n, doubled: 2.9432 delta_max / v at n = 3/2,
    Johnson 1985 Sec. 11.1; pi delta_max / v at n = 1, half a period of the spring)."""
    q = 1.0 / (n + 1.0)
    delta = ((n + 1.0) * reduced_mass * velocity**2 / (2.0 * k)) ** q
    factor = 2.0 * math.sqrt(math.pi) * math.gamma(1.0 + q) / math.gamma(0.5 + q)
    return {"peak_force": k * delta**n, "duration": factor * delta / velocity, "max_overlap": delta}


@dataclass(frozen=True)
class PowerCoefficients(LawCoefficients):
    """The power law's [contact] values: its exponent n and stiffness K (N/m^n)."""

    exponent: float
    stiffness: float


@dataclass(frozen=True)
class PowerLaw(ContactLaw):
    """Elastic power-law contacts F = k alpha^n; k (N/m^n) and n each one value or one per contact."""

    name: ClassVar[str] = "power"
    pair_style: ClassVar[str] = "chain/power"
    history: ClassVar[bool] = False
    Coefficients: ClassVar[type[LawCoefficients]] = PowerCoefficients
    parameter_ranges: ClassVar[dict[str, tuple[float, float]]] = {"k": (1e3, 1e12), "exponent": EXPONENT_RANGE}
    #: brass beads of R = 4.76 mm: Hertz's own K and n (k = 4/3 E* sqrt(R*))
    example_contact: ClassVar[dict[str, float]] = {"exponent": 1.5, "stiffness": 4.11e9}
    #: (independent draws: K and n that keep a brass-like chain's overlaps small for any n of the range)
    scene_key_ranges: ClassVar[dict[str, tuple[float, float]]] = {"exponent": (1.3, 1.8), "stiffness": (1e10, 1e11)}
    label: ClassVar[str] = "power-law"
    model_domains: ClassVar[dict[str, str]] = {
        **dict.fromkeys(("power_pair_impact_peak_force", "power_pair_impact_duration"), "pair_impact"),
        **dict.fromkeys(("power_striker_impact_peak_force", "power_striker_impact_duration"), "striker_impact"),
        **dict.fromkeys(("power_wall_impact_peak_force", "power_wall_impact_duration"), "wall_impact"),
    }
    compare_models: ClassVar[dict[str, tuple[tuple[str, str], ...]]] = {
        "leading_peak_force": (("power_pair_impact_peak_force", "power-law impact (two beads)"),),
        "striker_peak_force": (("power_striker_impact_peak_force", "power-law impact (two bodies)"),),
        "wall_peak_force": (("power_wall_impact_peak_force", "power-law impact (bead on the flat)"),),
    }

    exponent: ArrayLike = 1.5

    @cached_property
    def _operands(self) -> tuple[np.ndarray, np.ndarray]:
        """k and n as arrays (0-d for scalars), the inner loop's operands."""
        return np.array(self.k, dtype=float), np.array(self.exponent, dtype=float)

    @override
    def loading_exponent(self):
        return np.asarray(self.exponent, dtype=float)

    @override
    def force(self, alpha, alpha_max=None):
        k, n = self._operands
        return k * np.maximum(alpha, 0.0) ** n

    @override
    def force_into(self, alpha, alpha_max, out, tmp):
        k, n = self._operands
        np.power(alpha, n, out=out)
        np.multiply(out, k, out=out)

    @override
    def energy(self, alpha, alpha_max=None):
        k, n = self._operands
        return k / (n + 1.0) * np.maximum(alpha, 0.0) ** (n + 1.0)  # (the C++ kernel's order)

    @override
    def loading_force(self, alpha):
        return self.force(alpha)

    @override
    def static_overlap(self, force):
        k, n = self._operands
        return (np.asarray(force, dtype=float) / k) ** (1.0 / n)

    @override
    def tangent_stiffness(self, force):
        # dF/dalpha = n k alpha^(n-1) = n k^(1/n) F^((n-1)/n)
        k, n = self._operands
        return n * k ** (1.0 / n) * np.maximum(np.asarray(force, dtype=float), 0.0) ** ((n - 1.0) / n)

    @override
    def loading_stiffness(self, force):
        return self.tangent_stiffness(force)

    @override
    def kinks(self, alpha_max):
        # a derivative of F jumps (or is infinite) at zero overlap unless n is an integer: open or close
        return [Kink(np.zeros(np.shape(alpha_max)), "zero overlap")]

    # ---- scenes
    @classmethod
    @override
    def read_contact(cls, s, chain) -> PowerCoefficients:
        forbid_others(s, cls)
        low, high = EXPONENT_RANGE
        n = s.number(
            "exponent", low=low, low_open=False, high=high, high_open=False, what="the exponent n of F = K alpha^n"
        )
        k = s.number(
            "stiffness", low=0.0, high=1e30, what="K of F = K alpha^n in N/m^n (up to 1e30: n = 3 takes ~1e19)"
        )
        s.finish(("law", *cls.scene_keys))
        return PowerCoefficients(exponent=n, stiffness=k)

    @classmethod
    @override
    def for_pair(cls, coefficients, e_star, r_star, nominal_r_star, materials=()):
        return cls(k=float(coefficients.stiffness), exponent=float(coefficients.exponent))

    # ---- the planner's estimates: the two-body impact of bead 1 on bead 2 at the load's momentum
    @classmethod
    def expected_peak_force(cls, scene, impulse: float, step) -> float:
        """The impact of bead 1, given the load's momentum, on bead 2 (m* = m/2): the first contact
        carries at most about that; a long load cannot push it much past 2 A; x1.5 margin."""
        law = scene.law
        f = power_impact(float(law.k), float(law.exponent), scene.mass / 2.0, impulse / scene.mass)["peak_force"]
        if step is not None:
            f = min(f, 2.0 * step[0])
        return 1.5 * f

    @classmethod
    def loading_is_linear(cls) -> bool:
        """False: the estimates that have only a linear and a Hertz form read ``loading_exponent``."""
        return False

    @classmethod
    def wave_speeds(cls, scene, expected_force: float, step) -> tuple[float, float]:
        """(slowest, fastest) wave speeds, m/s: the linearised chain's D sqrt(k_t/m) at the expected force
        bounds every wave from above; a decayed front at a hundredth of it, halved, from below."""
        law, m, d = scene.law, scene.mass, scene.diameter
        fast = models.linear_sound_speed(float(law.tangent_stiffness(expected_force)), m, d)
        slow = 0.5 * models.linear_sound_speed(float(law.tangent_stiffness(0.01 * expected_force)), m, d)
        return min(slow, fast), fast

    @classmethod
    def leading_edge_speed(cls, scene, expected_force: float, step) -> float:
        """The fastest a disturbance can enter the undisturbed chain: the fastest of ``wave_speeds``."""
        return cls.wave_speeds(scene, expected_force, step)[1]

    # ---- the law's models (ContactLaw rule 8)
    @classmethod
    @override
    def predictions(cls, scene) -> list[dict]:
        """The elastic two-body impact (power_impact) of the scene's two bodies, where it is one."""
        hit = _two_bodies(scene)
        if hit is None:
            return []
        name, law, m_star, words = hit
        out = power_impact(float(law.k), float(law.exponent), m_star, scene.loading.velocity)
        valid = f"a two-body impact of {words}, power-law contact, no dashpot or precompression"
        return [
            dict(
                name=f"power_{name}_peak_force",
                value=out["peak_force"],
                unit="N",
                equation="K delta_max^n, delta_max = ((n+1) m* v^2 / (2K))^(1/(n+1))",
                valid=valid,
                nondim=out["peak_force"] / scene.force_scale,
            ),
            dict(
                name=f"power_{name}_duration",
                value=out["duration"],
                unit="s",
                equation="2 (delta_max / v) sqrt(pi) Gamma(1 + 1/(n+1)) / Gamma(1/2 + 1/(n+1))",
                valid=valid,
            ),
        ]


def _two_bodies(scene) -> tuple[str, PowerLaw, float, str] | None:
    """The scene's two-body impact: (its domain's name, the contact's law, m*, in words), or None."""
    if scene.chain.beads not in (1, 2):
        return None
    ld, m1 = scene.loading, float(scene.bead_masses[0])
    if scene.chain.beads == 2 and ld.kind == "velocity" and scene.effects.far_end == "free":
        m2 = float(scene.bead_masses[1])
        return "pair_impact", scene.contact_laws[0], m1 * m2 / (m1 + m2), "bead 1 on bead 2"
    if scene.chain.beads != 1:
        return None
    if ld.kind == "striker":
        ms = scene.striker_mass
        return "striker_impact", scene.striker_law, ms * m1 / (ms + m1), "the striker on bead 1"
    if ld.kind == "velocity" and scene.effects.far_end == "wall":
        return "wall_impact", scene.wall_law, m1, "the bead on the flat"
    return None
