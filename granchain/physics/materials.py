"""Materials and the derived quantities of a monodisperse sphere chain (paper Sec. II A).

Everything is SI. The nondimensional forms of Eqs. (5)-(7) are defined here and nowhere else.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: Plastic loading stiffness of the bilinear law: k = 18.5 sigma_y R* (paper, Sec. III).
PLASTIC_STIFFNESS_FACTOR = 18.5


@dataclass(frozen=True)
class Material:
    """An isotropic bead material."""

    density: float  # kg/m^3
    youngs_modulus: float  # Pa
    poisson_ratio: float  # -
    yield_strength: float | None = None  # Pa, only needed for the bilinear law's k


#: Built-in materials. Brass is the paper's (Sec. II A): rho = 8500, E = 115 GPa, nu = 0.30.
MATERIALS: dict[str, Material] = {
    "brass": Material(density=8500.0, youngs_modulus=115e9, poisson_ratio=0.30),
}


def effective_modulus(m: Material) -> float:
    """E* = E / (2 (1 - nu^2)) for two identical spheres (Sec. II A)."""
    return m.youngs_modulus / (2.0 * (1.0 - m.poisson_ratio**2))


def effective_radius(radius: float) -> float:
    """R* = R / 2 for two identical spheres (Sec. II A)."""
    return radius / 2.0


def bead_mass(m: Material, radius: float) -> float:
    """m = rho 4/3 pi R^3."""
    return m.density * 4.0 / 3.0 * math.pi * radius**3


def hertz_contact_stiffness(e_star: float, r_star: float) -> float:
    """k = 4 E* sqrt(R*) / 3, so that F = k alpha^(3/2) (text after Eq. 14; Johnson for any pair)."""
    return 4.0 * e_star * math.sqrt(r_star) / 3.0


def hertz_stiffness(m: Material, radius: float) -> float:
    """k of two identical beads (the paper's chain)."""
    return hertz_contact_stiffness(effective_modulus(m), effective_radius(radius))


def flat_effective_modulus(m: Material) -> float:
    """E* of a sphere on a rigid flat: E / (1 - nu^2) (the flat's compliance is zero)."""
    return m.youngs_modulus / (1.0 - m.poisson_ratio**2)


def plastic_stiffness_from_yield(yield_strength: float, radius: float) -> float:
    """Bilinear plastic loading stiffness k = 18.5 sigma_y R* (Sec. III)."""
    return PLASTIC_STIFFNESS_FACTOR * yield_strength * effective_radius(radius)


def time_scale(m: Material, radius: float) -> float:
    """tau = sqrt(pi rho R*^2 / (4 E*)), the chain's intrinsic time scale (Eq. 7)."""
    rs = effective_radius(radius)
    return math.sqrt(math.pi * m.density * rs**2 / (4.0 * effective_modulus(m)))


def force_scale(m: Material, radius: float) -> float:
    """E* R*^2: F~ = F / (E* R*^2) (Eq. 5)."""
    return effective_modulus(m) * effective_radius(radius) ** 2


def impulse_scale(m: Material, radius: float) -> float:
    """E* R*^2 tau: I~ = I / (E* R*^2 tau) (Eq. 6)."""
    return force_scale(m, radius) * time_scale(m, radius)


def pair_effective_modulus(a: Material, b: Material) -> float:
    """E* of two spheres of different materials: 1/E* = (1-nu_a^2)/E_a + (1-nu_b^2)/E_b (Johnson);
    for identical spheres it is E/(2(1-nu^2)), the paper's E*."""
    return 1.0 / ((1.0 - a.poisson_ratio**2) / a.youngs_modulus + (1.0 - b.poisson_ratio**2) / b.youngs_modulus)


def pair_effective_radius(r1: float, r2: float) -> float:
    """R* = R1 R2 / (R1 + R2); R/2 for identical spheres."""
    return r1 * r2 / (r1 + r2)
