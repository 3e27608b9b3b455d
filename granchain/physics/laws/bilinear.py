"""Bilinear elastoplastic contacts, Walton-Braun (Sec. III, Fig. 4), with alpha_max the largest
overlap so far:

    loading      (alpha >= alpha_max):  F = k alpha
    un/reloading (alpha <  alpha_max):  F = k_u (alpha - beta alpha_max), never negative,
    k_u = k / (1 - beta).  The residual overlap after full unloading is beta alpha_max.
    Stored (recoverable) energy:  k_u/2 (alpha - beta alpha_max)^2 where positive.
    Dissipated energy:            beta k alpha_max^2 / 2 = F^2/2 (1/k - 1/k_u)   (Eq. 20, first form).
    These two add up to the work done on the contact, whatever path led to (alpha, alpha_max).

k = 18.5 sigma_y R* (Sec. III) for the nominal pair, scaled by R*_pair / R* for other pairs (a bead on
the rigid flat, R* = R, has twice the bead-bead k).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np

from granchain.physics import materials as mat
from granchain.physics import models
from granchain.physics.laws.base import ArrayLike, ContactLaw, Kink, forbid_others

_multiply, _subtract, _greater, _less = np.multiply, np.subtract, np.greater, np.less  # (one lookup, not two)
_ZERO_FORCE, _RELOADING = "zero force at beta alpha_max", "reloading meets alpha_max"  # (the kinks' kinds)


def unloading_stiffness(k: ArrayLike, beta: ArrayLike) -> np.ndarray:
    """k_u = k / (1 - beta): slope of the unloading/reloading line (Sec. III)."""
    return np.asarray(k) / (1.0 - np.asarray(beta))


def bilinear_force(alpha: ArrayLike, alpha_max: ArrayLike, k: ArrayLike, beta: ArrayLike) -> np.ndarray:
    """Walton-Braun force for the current overlap and the largest overlap so far.

    Where alpha exceeds alpha_max the contact is on the loading line F = k alpha (this does not
    depend on alpha_max, so a stale alpha_max below alpha gives the right force).
    """
    alpha = np.asarray(alpha, dtype=float)
    am = np.maximum(alpha_max, alpha)
    ku = unloading_stiffness(k, beta)
    return np.maximum(ku * (alpha - beta * am), 0.0)


def bilinear_energy(alpha: ArrayLike, alpha_max: ArrayLike, k: ArrayLike, beta: ArrayLike) -> np.ndarray:
    """Recoverable energy stored in the contact: k_u/2 (alpha - beta alpha_max)^2, alpha_max >= alpha."""
    alpha = np.asarray(alpha, dtype=float)
    am = np.maximum(alpha_max, alpha)
    ku = unloading_stiffness(k, beta)
    d = np.maximum(alpha - beta * am, 0.0)
    return 0.5 * ku * d * d


def bilinear_dissipated(alpha_max: ArrayLike, k: ArrayLike, beta: ArrayLike) -> np.ndarray:
    """Energy dissipated once the contact has reached alpha_max: beta k alpha_max^2 / 2.

    Equal to Eq. 20, F^2/2 (1/k - 1/k_u), with F = k alpha_max the peak force.
    """
    am = np.maximum(alpha_max, 0.0)
    return 0.5 * np.asarray(beta) * np.asarray(k) * am * am


@dataclass(frozen=True)
class BilinearLaw(ContactLaw):
    """Walton-Braun bilinear elastoplastic contacts (plastic stiffness k, unloading coefficient beta)."""

    name: ClassVar[str] = "bilinear"
    pair_style: ClassVar[str] = "chain/bilinear"
    history: ClassVar[bool] = True
    # F = k alpha from alpha = 0: dF/dalpha jumps 0 -> k as a contact closes, k_u -> 0 at zero force
    slope_kinks: ClassVar[bool] = True
    # a negative overlap: alpha - beta max(alpha_max, alpha) < 0 as for alpha = 0 (alpha_max >= 0), so +0.0
    force_into_any_sign: ClassVar[bool] = True
    scene_keys: ClassVar[tuple[str, ...]] = ("unloading_coeff", "plastic_stiffness")
    parameter_ranges: ClassVar[dict[str, tuple[float, float]]] = {"k": (1e3, 1e12), "beta": (0.0, 0.99)}
    example_contact: ClassVar[dict[str, float]] = {"unloading_coeff": 0.8, "plastic_stiffness": 2.43e7}
    scene_key_ranges: ClassVar[dict[str, tuple[float, float]]] = {
        "unloading_coeff": (0.0, 0.9),
        "plastic_stiffness": (1e6, 1e8),
    }

    beta: ArrayLike

    @cached_property
    def k_unloading(self):
        """k_u = k / (1 - beta), computed once (the solver's inner loop reads it every step)."""
        return unloading_stiffness(self.k, self.beta)

    def force(self, alpha, alpha_max=None):
        return bilinear_force(alpha, 0.0 if alpha_max is None else alpha_max, self.k, self.beta)

    @cached_property
    def _operands(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """beta, k_u and 0 as arrays (0-d for scalars): numpy takes a Python or numpy float operand at
        about half again the cost of a whole call on a short chain (force_into runs four times an RK4 step)."""
        return np.array(self.beta, dtype=float), np.array(self.k_unloading, dtype=float), np.array(0.0)

    def force_into(self, alpha, alpha_max, out, tmp):
        # F = max(k_u (alpha - beta max(alpha_max, alpha)), 0); with alpha_max frozen this is the
        # loading line k alpha wherever alpha >= alpha_max
        beta, ku, zero = self._operands
        np.maximum(alpha_max, alpha, out=tmp)
        _multiply(tmp, beta, tmp)
        _subtract(alpha, tmp, out)
        _multiply(out, ku, out)
        np.maximum(out, zero, out=out)

    def energy(self, alpha, alpha_max=None):
        return bilinear_energy(alpha, 0.0 if alpha_max is None else alpha_max, self.k, self.beta)

    def dissipated(self, alpha_max):
        return bilinear_dissipated(alpha_max, self.k, self.beta)

    def loading_force(self, alpha):
        """The force never exceeds the loading line: the peak is k alpha_max."""
        return np.asarray(self.k) * np.maximum(alpha, 0.0)

    def static_overlap(self, force):
        return np.asarray(force, dtype=float) / np.asarray(self.k, dtype=float)

    def tangent_stiffness(self, force=None):
        """k_u at any force: unloading is the stiffer line."""
        return np.asarray(self.k_unloading)

    def kinks(self, alpha_max):
        beta, _, zero = self._operands  # (0-d operands: the RK4 event location asks at every piece)
        return [
            # the force reaches zero at beta alpha_max (F' jumps from k_u to 0)
            Kink(_multiply(beta, alpha_max), _ZERO_FORCE),
            # reloading meets the loading line again at alpha_max (slope k_u -> k)
            Kink(alpha_max, _RELOADING, where=_greater(alpha_max, zero), from_below=True),
        ]

    def kink_screens(self, alpha_max, a0, a1):
        # ContactLaw.kink_screens over kinks(alpha_max), the same arrays, with the reloading kink's
        # where (a whole-chain comparison) and the Kinks made only for a kink some contact straddles
        # (most pieces none: RK4 screens every piece)
        beta, _, zero = self._operands
        out = []
        level = _multiply(beta, alpha_max)
        idx = (_less(a0, level) ^ _less(a1, level)).nonzero()[0]
        if idx.size:
            out.append((Kink(level, _ZERO_FORCE), level, idx))
        idx = (_less(a0, alpha_max) ^ _less(a1, alpha_max)).nonzero()[0]
        if idx.size:
            out.append((Kink(alpha_max, _RELOADING, where=_greater(alpha_max, zero), from_below=True), alpha_max, idx))
        return out

    def turn_level(self, alpha_max):
        # a turn from loading to unloading at a new alpha_max (slope k -> k_u)
        return alpha_max

    @classmethod
    def read_contact(cls, s, chain) -> dict:
        forbid_others(s, cls)
        beta = s.number(
            "unloading_coeff",
            low=0.0,
            low_open=False,
            high=1.0,
            what="beta, the residual-to-maximum overlap ratio: 0 <= beta < 1",
        )
        k = s.number(
            "plastic_stiffness",
            required=False,
            low=1.0,
            low_open=False,
            high=1e16,
            high_open=False,
            what="plastic loading stiffness k in N/m, 1 to 1e16",
        )
        ys = chain.material.yield_strength
        if chain.materials is not None:  # each contact's k from the softer of its two materials
            if k is not None:
                raise s.error(
                    f"[contact] plastic_stiffness = {k!r} sets one k, but [chain] material is a list: each "
                    "contact's k = 18.5 sigma_y R* comes from the softer bead's yield_strength; remove it"
                )
            lacking = mat.lacking_yield_strength(chain)
            if lacking:
                raise s.error(f"[contact] law = 'bilinear' on a chain of several materials needs {lacking}")
            s.finish(("law", *cls.scene_keys))
            return {"unloading_coeff": beta, "plastic_stiffness": None}
        if k is None and ys is None:
            raise s.error(
                "[contact] law = 'bilinear' needs a stiffness: give plastic_stiffness (N/m) or "
                "the material's yield_strength (Pa) in [chain.material], from which k = 18.5 sigma_y R*"
            )
        if k is not None and ys is not None and chain.material_name is None:  # a built-in's yield gives way
            raise s.error(
                f"[contact] plastic_stiffness = {k!r} and [chain.material] yield_strength = {ys!r} both set k; "
                "give only one"
            )
        if k is None:
            k = mat.plastic_stiffness_from_yield(ys, chain.radius)
        s.finish(("law", *cls.scene_keys))
        return {"unloading_coeff": beta, "plastic_stiffness": k}

    @classmethod
    def for_pair(cls, contact, e_star, r_star, nominal_r_star, materials=()):
        if contact.plastic_stiffness is None:  # several materials: 18.5 sigma_y R* of the pair, the softer's sigma_y
            k = mat.PLASTIC_STIFFNESS_FACTOR * min(m.yield_strength for m in materials) * r_star
            return cls(k=k, beta=contact.unloading_coeff)
        k = float(contact.plastic_stiffness)
        return cls(k=k if r_star == nominal_r_star else k * (r_star / nominal_r_star), beta=contact.unloading_coeff)

    # ---- the planner's estimates
    @classmethod
    def expected_peak_force(cls, scene, impulse: float, step) -> float:
        """Eq. A2 for an impulse; a long load cannot push a linear contact past 2 A; x1.5 margin."""
        k, m = scene.stiffness, scene.mass
        f = models.linear_chain_impulse_response(impulse, k, m, scene.contact.unloading_coeff)["F_p"]  # Eq. A2
        if step is not None:
            f = min(f, 2.0 * step[0])
        return 1.5 * f

    @classmethod
    def loading_is_linear(cls) -> bool:
        return True

    @classmethod
    def wave_speeds(cls, scene, expected_force: float, step) -> tuple[float, float]:
        """c = D sqrt(k/m) is the fastest plastic loading signal; the peak of the dispersing leading
        pulse travels slower (measured 0.8 c for beta = 0.8, Sec. III A scene): plan with 0.6 c.
        The fastest wave is unloading, D sqrt(k_u/m)."""
        m, d = scene.mass, scene.diameter
        return 0.6 * models.linear_sound_speed(scene.stiffness, m, d), models.linear_sound_speed(
            scene.unloading_stiffness, m, d
        )

    @classmethod
    def leading_edge_speed(cls, scene, expected_force: float, step) -> float:
        """The loading line's sound speed D sqrt(k/m), the largest group velocity of a linear chain
        (the faster unloading speed only exists behind the front)."""
        return models.linear_sound_speed(scene.stiffness, scene.mass, scene.diameter)
