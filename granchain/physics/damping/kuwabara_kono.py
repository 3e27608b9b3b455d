"""Viscoelastic (Kuwabara-Kono) damping ([damping] kuwabara_kono = A, s): A dF/dalpha d(alpha)/dt.

Brilliantov, Spahn, Hertzsch & Poeschel, PRE 53, 5382 (1996) derive it for viscoelastic spheres: the
dissipative force is the dissipative constant A (a time) times the elastic force's rate,
A (dF_el/dalpha) d(alpha)/dt, for Hertz (3/2) A K sqrt(alpha) d(alpha)/dt. Here it applies to every
normal law through the law's tangent of the branch in force (ContactLaw.damping_tangent, given the
elastic force: loading or unloading), and the total force never pulls (clipped at 0).

Its restitution (restitution; the part's declared two-body model, which `granchain predict` shows
with its domain) is the series of Ramirez, Poeschel, Brilliantov & Schwager, PRE 60,
4465 (1999). The clipping changes it (Schwager & Poeschel, PRE 78, 051304, 2008): the contact ends
where the total force reaches zero, before the overlap returns to 0, and e is larger than the
unclipped series' by a term of higher order in delta (8e-5 of 1 - e at delta = 0.005, 1.7% at 0.2:
docs/damping.md).
"""

from __future__ import annotations

import math

import numpy as np
from typing_extensions import override

from granchain.physics.damping.base import DampingPart

#: Ramirez et al. (1999)'s coefficients of e = 1 - C1 delta + C2 delta^2 - ...: C1 in closed form,
#: sqrt(pi) Gamma(3/5) / (2^(1/5) 5^(2/5) Gamma(21/10)) = 1.1534489 (the paper prints 1.15344, its digits
#: cut, not rounded: with 1.15344 the series misses the impact's e by 9e-9 at delta = 1e-3, ten times
#: its third-order term), and C2 as printed
RAMIREZ_C1 = math.sqrt(math.pi) * math.gamma(0.6) / (2.0**0.2 * 5.0**0.4 * math.gamma(2.1))
RAMIREZ_C2 = 0.79826


def restitution_parameter(damping: float, k: float, reduced_mass: float, velocity: float) -> float:
    """delta, the small parameter of the Kuwabara-Kono restitution series (dimensionless).

    Ramirez et al. (1999) give e = 1 - C1 A beta^(2/5) v^(1/5) + C2 A^2 beta^(4/5) v^(2/5) - ... with
    C1 = 1.15344 (RAMIREZ_C1: its closed form), C2 = 0.79826. The impact's only dimensionless parameter
    is A (K/m_eff)^(2/5) v^(1/5), and for the force of this module,
    F = K alpha^(3/2) + (3/2) A K sqrt(alpha) alpha', the series holds with
    A beta^(2/5) = (3/2) A (K/m_eff)^(2/5), i.e. beta = (3/2)^(5/2) K / m_eff:
    delta = (3/2) A (K/m_eff)^(2/5) v^(1/5), e = 1 - C1 delta + C2 delta^2. Derived and checked against
    the impact's ODE solved by DOP853 (unclipped): (1 - e) / delta -> 1.15345 and
    (e - 1 + C1 delta) / delta^2 -> 0.798 as A -> 0 (tests/test_kuwabara_kono.py).

    Parameters
    ----------
    damping : float
        A, s.
    k : float
        The Hertz constant K of F = K alpha^(3/2), N/m^1.5.
    reduced_mass : float
        m_eff = m1 m2 / (m1 + m2), kg (a body on a rigid wall: its mass).
    velocity : float
        The impact (approach) speed, m/s.
    """
    return 1.5 * damping * (k / reduced_mass) ** 0.4 * velocity**0.2


def restitution(damping: float, k: float, reduced_mass: float, velocity: float) -> dict[str, float | str]:
    """The two-body Hertz impact's coefficient of restitution with Kuwabara-Kono damping, to second order.

    e = 1 - C1 delta + C2 delta^2 (Ramirez et al., PRE 60, 4465, 1999; delta: restitution_parameter),
    so 1 - e ~ v^(1/5) at small damping. Domain: small damping, C1 delta << 1 (the series' third term is
    of order delta^3), for the unclipped force; the clipped force (the total never pulls) ends the
    contact early and raises e by a term of higher order in delta (Schwager & Poeschel 2008), not its
    exponent.

    Returns
    -------
    dict
        ``e`` the coefficient, ``delta`` the small parameter, ``first_order`` C1 delta, ``valid`` the domain.
    """
    d = restitution_parameter(damping, k, reduced_mass, velocity)
    return {
        "e": 1.0 - RAMIREZ_C1 * d + RAMIREZ_C2 * d * d,
        "delta": d,
        "first_order": RAMIREZ_C1 * d,
        "valid": "small damping: C1 A beta^(2/5) v^(1/5) << 1 (Hertz contact, unclipped force)",
    }


#: the restitution series' domain, C1 delta << 1, read as C1 delta <= 0.1: there its next term (of order
#: delta^3) is under 1e-3 of e, and the no-pull clip changes 1 - e by under 1% (8e-5 of it at delta =
#: 0.005, 1.7% at 0.2: docs/damping.md)
SMALL_DAMPING = 0.1

#: the two-body setups the restitution model is declared for (EFFECT_DOMAINS' keys)
TWO_BODY_SETUPS = ("striker_impact", "wall_impact", "pair_impact")


def _hertzian(law) -> bool:
    """Whether a contact's law is F = K alpha^(3/2) on loading and unloading alike (the series' force)."""
    return not law.history and bool(np.all(np.asarray(law.loading_exponent()) == 1.5))


class KuwabaraKono(DampingPart):
    """Viscoelastic damping: A dF/dalpha d(alpha)/dt while bodies overlap, the total never pulling.

    Scene key: ``[damping] kuwabara_kono`` = A in s (positive and finite). Pair style:
    ``kuwabara_kono A`` (granchain/lammps/damping_kuwabara_kono.h, through the law's tangent); the
    energy it dissipates is the pair style's per-atom ``d_edash``, as the dashpot's.
    """

    name = "kuwabara_kono"
    key = "kuwabara_kono"
    label = "[damping] kuwabara_kono"
    unit = "s"
    noun = "Kuwabara-Kono damping"
    phrase = "Kuwabara-Kono damping"
    description = "viscoelastic Kuwabara-Kono damping"
    symbol = "A"
    what = "A in s: force A x dF/dalpha x d(alpha)/dt while beads overlap (Kuwabara-Kono)"
    # about a tenth of a percent of brass beads' contact time: 1 - e of a few percent at 1 m/s
    example = 2e-7
    invalid = (0.0, -1e-7, "slow", float("inf"), float("nan"))
    velocity_dependent = True
    dissipated_vectors = ("d_edash",)
    yardstick = "Kuwabara-Kono damping (the yardstick has no damping)"

    @classmethod
    @override
    def damped_force(cls, coefficient: float, law, alpha, alpha_max, rate, elastic) -> np.ndarray:
        # A dF/dalpha (the branch in force) d(alpha)/dt; the total never pulls
        return np.maximum(elastic + coefficient * law.damping_tangent(alpha, alpha_max, elastic) * rate, 0.0)

    @classmethod
    @override
    def contact_damping(cls, coefficient: float, tangent):
        return coefficient * np.asarray(tangent, dtype=float)

    model_domains = {f"kk_{setup}_restitution": setup for setup in TWO_BODY_SETUPS}

    @classmethod
    @override
    def predictions(cls, coefficient: float, impact, velocity: float) -> list[dict]:
        """The impact's coefficient of restitution (restitution: Ramirez et al. 1999's series) on a
        Hertzian contact; none on another law (the series is for F = K alpha^(3/2))."""
        if not _hertzian(impact.law):
            return []
        e = restitution(coefficient, float(impact.law.k), impact.reduced_mass, velocity)["e"]
        return [
            dict(
                name=f"kk_{impact.setup}_restitution",
                value=e,
                unit="1",
                equation=(
                    f"e = 1 - C1 delta + C2 delta^2, delta = (3/2) A (K/m*)^(2/5) v^(1/5), C1 = {RAMIREZ_C1:.5f}, "
                    f"C2 = {RAMIREZ_C2} (Ramirez et al., PRE 60, 4465, 1999), {impact.words}"
                ),
                valid=(
                    f"a two-body impact of {impact.words}, Hertz contact, small damping: C1 delta << 1 "
                    f"(here C1 delta <= {SMALL_DAMPING:g}), no precompression"
                ),
            )
        ]

    @classmethod
    @override
    def model_domain(cls, name: str, coefficient: float, impact, velocity: float) -> tuple[bool, str]:
        """Small damping: C1 delta <= SMALL_DAMPING, with the impact's C1 delta."""
        first = RAMIREZ_C1 * restitution_parameter(coefficient, float(impact.law.k), impact.reduced_mass, velocity)
        if first <= SMALL_DAMPING:
            return True, f"small damping: C1 delta = {first:.3g} <= {SMALL_DAMPING:g}"
        return False, (
            f"outside the model's domain: C1 delta = {first:.3g} > {SMALL_DAMPING:g}, not small damping (the series' "
            "terms beyond C2 delta^2 and the no-pull clip's change of e are no longer small)"
        )


def restitution_exponent() -> float:
    """The exponent of 1 - e in the impact speed at small damping: 1/5 (dimensional analysis of the
    Hertz impact with A dF/dalpha alpha', whose only parameter is A (K/m)^(2/5) v^(1/5))."""
    return 1.0 / 5.0
