"""Contact laws as vectorized numpy functions with explicit history.

The overlap of contact i (between bead i and bead i+1) is alpha = u_i - u_{i+1} (Eq. 2); a
negative alpha means the beads are apart and the force is zero. Every function takes arrays
(or scalars) and the stiffness may be a scalar or one value per contact.

Hertz (Sec. II A):           F = k alpha^(3/2),  stored energy 2/5 k alpha^(5/2).
Bilinear, Walton-Braun (Sec. III, Fig. 4), with alpha_max the largest overlap so far:
    loading     (alpha >= alpha_max):  F = k alpha
    un/reloading (alpha <  alpha_max):  F = k_u (alpha - beta alpha_max), never negative,
    k_u = k / (1 - beta).  The residual overlap after full unloading is beta alpha_max.
    Stored (recoverable) energy:  k_u/2 (alpha - beta alpha_max)^2 where positive.
    Dissipated energy:            beta k alpha_max^2 / 2 = F^2/2 (1/k - 1/k_u)   (Eq. 20, first form).
    These two add up to the work done on the contact, whatever path led to (alpha, alpha_max).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

ArrayLike = np.ndarray | float


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


def dissipation_per_cycle(peak_force: ArrayLike, k: ArrayLike, beta: ArrayLike) -> np.ndarray:
    """Eq. 20: energy dissipated at a contact loaded to peak force F, F^2/2 (1/k - 1/k_u) = beta F^2 / (2k).

    The paper prints the last form of Eq. 20 as beta F^2 / (2k (1 - beta)), which does not follow
    from its own first form (1/k - 1/k_u = beta/k) and disagrees with the area of the
    load-unload loop; we use the first form (checked against the loop's area in the tests).
    """
    k = np.asarray(k)
    ku = unloading_stiffness(k, beta)
    return 0.5 * np.asarray(peak_force) ** 2 * (1.0 / k - 1.0 / ku)


@dataclass(frozen=True)
class HertzLaw:
    """Elastic Hertz contacts; k is one value or one per contact."""

    k: np.ndarray | float
    name: str = "hertz"

    def force(self, alpha, alpha_max=None):
        return hertz_force(alpha, self.k)

    def energy(self, alpha, alpha_max=None):
        return hertz_energy(alpha, self.k)

    def dissipated(self, alpha_max):
        return np.zeros_like(np.asarray(alpha_max, dtype=float))

    def force_at_peak_overlap(self, alpha_peak):
        """The largest force of a contact is reached at its largest overlap (F is monotone)."""
        return hertz_force(alpha_peak, self.k)

    def max_stiffness(self, force):
        """Stiffness dF/dalpha at the given force: what limits the stable time step."""
        return hertz_tangent_stiffness(force, self.k)


@dataclass(frozen=True)
class BilinearLaw:
    """Walton-Braun bilinear elastoplastic contacts (plastic stiffness k, unloading coefficient beta)."""

    k: np.ndarray | float
    beta: np.ndarray | float
    name: str = "bilinear"

    @property
    def k_unloading(self):
        return unloading_stiffness(self.k, self.beta)

    def force(self, alpha, alpha_max):
        return bilinear_force(alpha, alpha_max, self.k, self.beta)

    def energy(self, alpha, alpha_max):
        return bilinear_energy(alpha, alpha_max, self.k, self.beta)

    def dissipated(self, alpha_max):
        return bilinear_dissipated(alpha_max, self.k, self.beta)

    def force_at_peak_overlap(self, alpha_peak):
        """The force never exceeds the loading line: the peak is k alpha_max."""
        return np.asarray(self.k) * np.maximum(alpha_peak, 0.0)

    def max_stiffness(self, force=None):
        return np.asarray(self.k_unloading)
