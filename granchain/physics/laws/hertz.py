"""Hertz contacts (Sec. II A): F = k alpha^(3/2), stored energy 2/5 k alpha^(5/2), no history.

k = 4/3 E* sqrt(R*) of the pair (Johnson); a bead on the rigid flat has R* = R and E* = E/(1-nu^2).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np

from granchain.physics import materials as mat
from granchain.physics import models
from granchain.physics.laws.base import ArrayLike, ContactLaw, Kink

_multiply = np.multiply  # (outputs by position: cheaper than out=)


def hertz_force(alpha: ArrayLike, k: ArrayLike) -> np.ndarray:
    """F = k alpha^(3/2) for alpha > 0, else 0."""
    a = np.maximum(alpha, 0.0)
    return k * a * np.sqrt(a)


def hertz_energy(alpha: ArrayLike, k: ArrayLike) -> np.ndarray:
    """Stored energy 2/5 k alpha^(5/2) (integral of the Hertz force)."""
    a = np.maximum(alpha, 0.0)
    return 0.4 * k * a * a * np.sqrt(a)


def hertz_tangent_stiffness(force: ArrayLike, k: ArrayLike) -> np.ndarray:
    """dF/dalpha = 3/2 k alpha^(1/2) = 3/2 k^(2/3) F^(1/3), the stiffness at a given force."""
    return 1.5 * np.cbrt(np.asarray(k) ** 2 * np.maximum(force, 0.0))


@dataclass(frozen=True)
class HertzLaw(ContactLaw):
    """Elastic Hertz contacts; k is one value or one per contact."""

    name: ClassVar[str] = "hertz"
    pair_style: ClassVar[str] = "chain/hertz"
    history: ClassVar[bool] = False
    scene_keys: ClassVar[tuple[str, ...]] = ()
    parameter_ranges: ClassVar[dict[str, tuple[float, float]]] = {"k": (1e3, 1e12)}
    example_contact: ClassVar[dict[str, float]] = {}
    scene_key_ranges: ClassVar[dict[str, tuple[float, float]]] = {}

    def force(self, alpha, alpha_max=None):
        return hertz_force(alpha, self.k)

    @cached_property
    def _k(self) -> np.ndarray:
        """k as an array (0-d for a scalar): a cheaper operand than a float in force_into (four calls an RK4 step)."""
        return np.array(self.k, dtype=float)

    def force_into(self, alpha, alpha_max, out, tmp):
        np.sqrt(alpha, out=tmp)
        _multiply(alpha, tmp, out)
        _multiply(out, self._k, out)

    def energy(self, alpha, alpha_max=None):
        return hertz_energy(alpha, self.k)

    def loading_force(self, alpha):
        return hertz_force(alpha, self.k)

    def static_overlap(self, force):
        return (np.asarray(force, dtype=float) / np.asarray(self.k, dtype=float)) ** (2.0 / 3.0)

    def tangent_stiffness(self, force):
        return hertz_tangent_stiffness(force, self.k)

    def kinks(self, alpha_max):
        # F'' is infinite at zero overlap: the contact opens or closes
        return [Kink(np.zeros(np.shape(alpha_max)), "zero overlap")]

    @classmethod
    def for_pair(cls, contact, e_star, r_star, nominal_r_star, materials=()):
        return cls(k=mat.hertz_contact_stiffness(e_star, r_star))

    # ---- the planner's estimates (granchain.physics.estimates dispatches here)
    @classmethod
    def expected_peak_force(cls, scene, impulse: float, step) -> float:
        """Eq. 8 for short loads, capped by the long-load wave (Eq. 15) for steps; x1.5 for the first
        contacts, which peak above the formed wave (up to ~1.2x measured)."""
        m, d, k = scene.mass, scene.diameter, scene.stiffness
        f = models.short_load_peak_force(impulse, m, scene.e_star, scene.r_star)  # Eq. 8
        if step is not None:
            amp = step[0]
            fu = models.solitary_wave_peak_force(models.front_speed_upper(amp, k, m, d), k, m, d)
            f = min(f, max(fu, amp))  # Fig. 3: the smaller of the two regimes' peaks
        return 1.5 * f

    @classmethod
    def loading_is_linear(cls) -> bool:
        """The virgin curve is a line (the striker's piston amplitude, Eqs. 12 and 19)."""
        return False

    @classmethod
    def wave_speeds(cls, scene, expected_force: float, step) -> tuple[float, float]:
        """(slowest leading-wave speed, fastest wave speed) expected, m/s: solitary waves (Nesterenko)
        between the expected force and the long load's lower front speed."""
        m, d, k = scene.mass, scene.diameter, scene.stiffness
        fast = models.solitary_wave_speed(expected_force, k, m, d)
        slow = models.solitary_wave_speed(expected_force / 1.5, k, m, d)
        if step is not None:
            slow = min(models.front_speed_lower(step[0], k, m, d), slow)
        # leading waves decay while they form; allow the slower speed of a wave at a tenth the force
        return slow * 0.1 ** (1 / 6), fast

    @classmethod
    def leading_edge_speed(cls, scene, expected_force: float, step) -> float:
        """The fastest a disturbance can enter the undisturbed chain: the fastest solitary wave."""
        return cls.wave_speeds(scene, expected_force, step)[1]
