"""Thornton's elastic-perfectly-plastic spheres (Thornton 1997, J. Appl. Mech. 64, 383).

Per contact, with k = 4/3 E* sqrt(R*) the Hertz stiffness of the pair and p_y the limiting contact
pressure (not the tensile yield strength):

    yield overlap  d_y = (pi p_y / (2 E*))^2 R*,   F_y = k d_y^(3/2) = (2/3) pi p_y R* d_y
    virgin curve   F = k d^(3/2) up to d_y, then the plastic line F = F_y + S (d - d_y), S = pi p_y R*
                   (= 3/2 k d_y^(1/2), the Hertz slope at d_y: the slope is continuous at yield)
    unloading and reloading below d_max (the largest overlap so far) once d_max > d_y: Hertz with the
                   enlarged radius R_p = R* (F_y/F_max) ((2 F_max + F_y)/(3 F_y))^(3/2), i.e.
                   k_p = k sqrt(R_p/R*), F = k_p (d - d_p)^(3/2) for d > d_p, else 0, with
                   F_max = F_y + S (d_max - d_y) and d_p = max(d_max - (F_max/k_p)^(2/3), 0) (the max only
                   catches round-off just above d_y, where d_p -> 0); beyond d_max the
                   plastic line again. A contact that never passed d_y stays Hertzian.
    stored energy  (2/5) F (d - d_p) on the unloading curve
    dissipated     the area between the loading path and the unloading curve of d_max:
                   W(d_max) - (2/5) F_max (d_max - d_p), W the work along the virgin curve.

The per-contact parameters are k and d_y (F_y, S, F_max, k_p and d_p follow), so a wall contact
(E* of the flat, R* = R) and a striker follow the same law with their own pair's E* and R*. The C++
twin is granchain/lammps/law_thornton.h.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from typing_extensions import override

from granchain.physics import materials as mat
from granchain.physics import models
from granchain.physics.laws.base import ArrayLike, ContactLaw, Kink, LawCoefficients, forbid_others
from granchain.physics.laws.hertz import HertzLaw, hertz_force


def yield_overlap(yield_pressure: float, e_star: float, r_star: float) -> float:
    """d_y = (pi p_y / (2 E*))^2 R*: the overlap at which the peak pressure of a Hertz contact,
    2 E* a / (pi R*) with a = sqrt(R* d), reaches p_y (Thornton 1997)."""
    return (math.pi * yield_pressure / (2.0 * e_star)) ** 2 * r_star


def restitution_coefficient(v0: float, vy: float) -> float:
    """Thornton's (1997) coefficient of restitution of an impact at relative velocity v0, yield
    velocity vy (see ThorntonLaw.predictions); 1 at and below vy."""
    if v0 <= vy:
        return 1.0
    r = vy / v0
    return (
        math.sqrt(6.0 * math.sqrt(3.0) / 5.0)
        * math.sqrt(1.0 - r * r / 6.0)
        * (r / (r + 2.0 * math.sqrt(6.0 / 5.0 - r * r / 5.0))) ** 0.25
    )


@dataclass(frozen=True)
class ThorntonCoefficients(LawCoefficients):
    """The Thornton law's [contact] values."""

    #: p_y in Pa, Thornton's limiting contact pressure; None: 1.6 sigma_y of the softer bead of each
    #: contact (materials.YIELD_PRESSURE_FACTOR)
    yield_pressure: float | None = None


@dataclass(frozen=True)
class ThorntonLaw(ContactLaw):
    """Thornton's elastic-perfectly-plastic contacts: Hertz stiffness k, yield overlap d_y."""

    name: ClassVar[str] = "thornton"
    pair_style: ClassVar[str] = "chain/thornton"
    history: ClassVar[bool] = True
    # reloading meets the plastic line at d_max with another slope: Verlet's error follows no order
    # there (generated scenes, Richardson: 94 of 125 peaks estimated, one 17x off; against RK4: 172 of
    # 179, 0.97-1.54; docs/error-bars.md)
    slope_kinks: ClassVar[bool] = True
    Coefficients: ClassVar[type[LawCoefficients]] = ThorntonCoefficients
    parameter_ranges: ClassVar[dict[str, tuple[float, float]]] = {"k": (1e3, 1e12), "yield_overlap": (1e-9, 1e-4)}
    #: brass beads of R = 4.76 mm: p_y = k / (pi R*) makes the plastic slope S = pi p_y R* equal the
    #: paper's bilinear plastic stiffness k = 2.43e7 N/m (the bilinear example), so the two laws load alike
    example_contact: ClassVar[dict[str, float]] = {"yield_pressure": 3.25e9}
    scene_key_ranges: ClassVar[dict[str, tuple[float, float]]] = {"yield_pressure": (3e8, 1e10)}

    yield_overlap: ArrayLike

    # ---- derived per-contact constants
    @property
    def yield_force(self) -> np.ndarray:
        """F_y = k d_y^(3/2)."""
        dy = np.asarray(self.yield_overlap, dtype=float)
        return np.asarray(self.k) * dy * np.sqrt(dy)

    @property
    def plastic_slope(self) -> np.ndarray:
        """S = 3/2 k d_y^(1/2) = pi p_y R*."""
        return 1.5 * np.asarray(self.k) * np.sqrt(np.asarray(self.yield_overlap, dtype=float))

    def unloading(self, alpha_max: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(plastic, F_max, k_p, d_p) of contacts whose largest overlap is alpha_max: plastic where
        alpha_max > d_y; elsewhere F_max on the Hertz curve, k_p = k and d_p = 0."""
        am = np.asarray(alpha_max, dtype=float)
        k = np.broadcast_to(np.asarray(self.k, dtype=float), am.shape)
        dy = np.broadcast_to(np.asarray(self.yield_overlap, dtype=float), am.shape)
        plastic = am > dy
        fy = k * dy * np.sqrt(dy)
        ap = np.maximum(am, dy)  # the plastic formulas at d_y where the contact is still elastic
        fmax_p = fy + 1.5 * k * np.sqrt(dy) * (ap - dy)
        # x^(3/2) as x sqrt(x) and y^(2/3) as cbrt(y^2), as the C++ kernel (law_thornton.h)
        x = (2.0 * fmax_p + fy) / (3.0 * fy)
        kp = k * np.sqrt((fy / fmax_p) * (x * np.sqrt(x)))
        y = fmax_p / kp
        dp = np.maximum(ap - np.cbrt(y * y), 0.0)  # >= 0 (round-off just above d_y)
        amc = np.maximum(am, 0.0)
        fmax = np.where(plastic, fmax_p, k * amc * np.sqrt(amc))
        return plastic, fmax, np.where(plastic, kp, k), np.where(plastic, dp, 0.0)

    # ---- the law
    @override
    def force(self, alpha, alpha_max=None):
        a = np.maximum(np.asarray(alpha, dtype=float), 0.0)
        am = a if alpha_max is None else np.maximum(alpha_max, a)
        _, _, kp, dp = self.unloading(am)
        s = np.maximum(a - dp, 0.0)
        return kp * s * np.sqrt(s)

    @override
    def force_into(self, alpha, alpha_max, out, tmp):
        out[:] = self.force(alpha, alpha_max)

    @override
    def energy(self, alpha, alpha_max=None):
        a = np.maximum(np.asarray(alpha, dtype=float), 0.0)
        am = a if alpha_max is None else np.maximum(alpha_max, a)
        _, _, kp, dp = self.unloading(am)
        s = np.maximum(a - dp, 0.0)
        return 0.4 * kp * s * s * np.sqrt(s)

    @override
    def dissipated(self, alpha_max):
        am = np.maximum(np.asarray(alpha_max, dtype=float), 0.0)
        plastic, fmax, _, dp = self.unloading(am)
        k = np.asarray(self.k, dtype=float)
        dy = np.asarray(self.yield_overlap, dtype=float)
        fy, s = self.yield_force, self.plastic_slope
        x = np.maximum(am - dy, 0.0)
        work = 0.4 * k * dy * dy * np.sqrt(dy) + fy * x + 0.5 * s * x * x  # along the virgin curve
        return np.where(plastic, work - 0.4 * fmax * (am - dp), 0.0)

    @override
    def loading_force(self, alpha):
        a = np.maximum(np.asarray(alpha, dtype=float), 0.0)
        dy = np.asarray(self.yield_overlap, dtype=float)
        return np.where(a > dy, self.yield_force + self.plastic_slope * (a - dy), hertz_force(a, self.k))

    @override
    def static_overlap(self, force):
        f = np.asarray(force, dtype=float)
        fy = self.yield_force
        hertz = (f / np.asarray(self.k, dtype=float)) ** (2.0 / 3.0)
        return np.where(f > fy, np.asarray(self.yield_overlap) + (f - fy) / self.plastic_slope, hertz)

    @override
    def tangent_stiffness(self, force):
        """Unloading from F_max = force is the stiffest: 3/2 k_p^(2/3) F^(1/3) (the plastic line's S and
        the Hertz slope below it are smaller: R_p >= R*)."""
        f = np.maximum(np.asarray(force, dtype=float), 0.0)
        am = self.static_overlap(f)
        _, _, kp, _ = self.unloading(am)
        return 1.5 * np.cbrt(kp * kp * f)

    @override
    def kinks(self, alpha_max):
        am = np.asarray(alpha_max, dtype=float)
        dy = np.broadcast_to(np.asarray(self.yield_overlap, dtype=float), am.shape)
        _, _, _, dp = self.unloading(am)
        return [
            # the force reaches zero at d_p (0 for an elastic contact): F'' is infinite there
            Kink(dp, "zero force at d_p"),
            # reloading meets the plastic line again at d_max (slope of the unloading curve -> S)
            Kink(am, "reloading meets d_max", where=am > dy, from_below=True),
            # first yield: Hertz -> the plastic line (F' continuous, F'' jumps)
            Kink(np.array(dy), "yield at d_y", where=am < dy, from_below=True),
        ]

    @override
    def turn_level(self, alpha_max):
        # a turn above d_max and d_y leaves the plastic line for a new unloading curve
        return np.maximum(alpha_max, self.yield_overlap)

    # ---- analytic predictions (granchain.physics.predictions asks every law for its own)
    #: model name -> what it needs: "any" (every Thornton chain) or "collision" (two beads, bead 1 given
    #: a velocity, the far end free: a two-body impact)
    model_domains: ClassVar[dict[str, str]] = {
        "yield_force": "any",
        "yield_overlap": "any",
        "yield_velocity": "any",
        "restitution_coefficient": "collision",
    }

    @classmethod
    @override
    def predictions(cls, scene) -> list[dict]:
        """Thornton's (1997) closed forms for the nominal bead pair: F_y, d_y, the impact velocity at
        which the contact first yields, (1/2) m* v_y^2 = (2/5) F_y d_y (the Hertz energy at d_y; m* = m/2
        for two equal beads), and his coefficient of restitution for an impact at v0 > v_y,
            e = sqrt(6 sqrt(3) / 5) sqrt(1 - (v_y/v0)^2 / 6)
                * [ (v_y/v0) / ((v_y/v0) + 2 sqrt(6/5 - (v_y/v0)^2 / 5)) ]^(1/4),
        Thornton 1997, J. Appl. Mech. 64, 383, Eq. 43 as quoted in Thornton and Ning (1998), Powder
        Technol. 99, 154 (e = 1 up to v_y). He derived it with the unloading curve used here but an
        approximate loading stage, so it is a model, not an identity, for our runs."""
        law = scene.law
        fy, dy = float(law.yield_force), float(law.yield_overlap)
        m_star = scene.mass / 2.0
        vy = math.sqrt(2.0 * 0.4 * fy * dy / m_star)
        fs = scene.force_scale
        out = [
            dict(
                name="yield_force",
                value=fy,
                unit="N",
                equation="F_y = 4/3 E* sqrt(R*) d_y^(3/2) (Thornton 1997)",
                valid="the force at which a contact first yields",
                nondim=fy / fs,
            ),
            dict(name="yield_overlap", value=dy, unit="m", equation="d_y = (pi p_y / (2 E*))^2 R*", valid="always"),
            dict(
                name="yield_velocity",
                value=vy,
                unit="m/s",
                equation="(1/2) m* v_y^2 = (2/5) F_y d_y, m* = m/2",
                valid="two equal beads: the relative impact velocity at which their contact first yields",
            ),
        ]
        ld = scene.loading
        if ld.kind == "velocity":
            out.append(
                dict(
                    name="restitution_coefficient",
                    value=restitution_coefficient(ld.velocity, vy),
                    unit="-",
                    equation="Thornton 1997 (e = 1 below v_y)",
                    valid="a two-body impact of equal beads at the relative velocity v0 of bead 1",
                )
            )
        return out

    # ---- scenes
    @classmethod
    @override
    def read_contact(cls, s, chain) -> ThorntonCoefficients:
        forbid_others(s, cls)
        if not s.has("yield_pressure"):
            lacking = mat.lacking_yield_strength(chain)
            if lacking:
                raise s.error(
                    "[contact] law = 'thornton' needs yield_pressure: Thornton's limiting contact pressure p_y "
                    "in Pa, the largest pressure plastic flow lets the contact hold (without it, p_y = "
                    f"{mat.YIELD_PRESSURE_FACTOR} sigma_y of the softer bead of each contact, and {lacking}). "
                    "It is not the tensile yield strength sigma_y: a Hertz contact starts to yield at a peak "
                    f"pressure of about {mat.YIELD_PRESSURE_FACTOR} sigma_y"
                )
            s.finish(("law", *cls.scene_keys))
            return ThorntonCoefficients(yield_pressure=None)
        p_y = s.number(
            "yield_pressure",
            low=1e3,
            low_open=False,
            high=1e13,
            high_open=False,
            what="Thornton's limiting contact pressure p_y in Pa, 1e3 to 1e13 (not the yield strength)",
        )
        s.finish(("law", *cls.scene_keys))
        return ThorntonCoefficients(yield_pressure=p_y)

    @classmethod
    @override
    def for_pair(cls, coefficients, e_star, r_star, nominal_r_star, materials=()):
        # without a given p_y: the softer body's yield sets it (docs/effects.md, mixing rules)
        p_y = coefficients.yield_pressure
        if p_y is None:
            p_y = mat.YIELD_PRESSURE_FACTOR * min(m.yield_strength for m in materials)
        return cls(k=mat.hertz_contact_stiffness(e_star, r_star), yield_overlap=yield_overlap(p_y, e_star, r_star))

    @classmethod
    @override
    def unsupported(cls, chain) -> str | None:
        return None

    # ---- the planner's estimates: the virgin curve is Hertz up to F_y and softer beyond, and the
    # contacts dissipate, so Hertz's estimates bound the force from above
    @classmethod
    def expected_peak_force(cls, scene, impulse: float, step) -> float:
        """The Hertz law's estimate (Eq. 8, capped by Eq. 15's wave for steps, x1.5): Thornton's virgin curve
        is Hertz up to F_y and softer beyond, and its contacts dissipate, so it bounds the force from above."""
        return HertzLaw.expected_peak_force(scene, impulse, step)

    @classmethod
    def loading_is_linear(cls) -> bool:
        """False: the virgin curve starts Hertzian (k d^(3/2) up to d_y), so the estimates take their
        Hertz forms."""
        return False

    @classmethod
    def wave_speeds(cls, scene, expected_force: float, step) -> tuple[float, float]:
        """Hertz's solitary-wave speeds, widened: a plastic front is slower (plan with 0.6 D sqrt(S/m), S
        the plastic slope, like the bilinear law's 0.6 c) and unloading is faster (D sqrt(k_t/m) at the
        stiffest unloading tangent)."""
        slow, fast = HertzLaw.wave_speeds(scene, expected_force, step)
        law, m, d = scene.law, scene.mass, scene.diameter
        if float(expected_force) > float(law.yield_force):
            slow = min(slow, 0.6 * models.linear_sound_speed(float(law.plastic_slope), m, d))
            fast = max(fast, models.linear_sound_speed(float(law.tangent_stiffness(expected_force)), m, d))
        return slow, fast

    @classmethod
    def leading_edge_speed(cls, scene, expected_force: float, step) -> float:
        """The fastest a disturbance can enter the undisturbed chain: the fastest of ``wave_speeds``."""
        return cls.wave_speeds(scene, expected_force, step)[1]
