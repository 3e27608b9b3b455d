"""Hertz contacts (Sec. II A): F = k alpha^(3/2), stored energy 2/5 k alpha^(5/2), no history.

k = 4/3 E* sqrt(R*) of the pair (Johnson); a bead on the rigid flat has R* = R and E* = E/(1-nu^2).
The law's models: the paper's Sec. II (Eq. 8 for short loads, Eqs. 12-19 with Nesterenko's solitary
wave for long ones) and the effects' Hertz models (a precompressed chain's sound speed, two-body
impacts of a striker or on the wall).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np
from typing_extensions import override

from granchain.physics import materials as mat
from granchain.physics import models
from granchain.physics.laws.base import EFFECT_DOMAINS, ArrayLike, ContactLaw, Kink, TimeScale

#: Hertz chains: a load is short below this fraction of the crossover time T_c and long above the
#: multiple (HertzLaw.loading_time_scale). Measured on the reference solver (brass, I = 0.4 N s, peak
#: at contact 80 of 120): the leading peak is within 3% of Eq. 8 up to T = T_c/3, 8% at T_c/2 and 40%
#: at T_c; it lies between the long-load bounds (Eqs. 15, 19 + Nesterenko) from T = 1.7 T_c on.
HERTZ_SHORT_BELOW = 0.5
HERTZ_LONG_ABOVE = 2.0

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
    """dF/dalpha = 3/2 k alpha^(1/2) = 3/2 k^(2/3) F^(1/3) (the paper's Eq. 16 differentiated), the
    stiffness at a given force."""
    return 1.5 * np.cbrt(np.asarray(k) ** 2 * np.maximum(force, 0.0))


@dataclass(frozen=True)
class HertzLaw(ContactLaw):
    """Elastic Hertz contacts; k is one value or one per contact."""

    name: ClassVar[str] = "hertz"
    pair_style: ClassVar[str] = "chain/hertz"
    builtin_granular_normal: ClassVar[str | None] = "hertz/material"
    history: ClassVar[bool] = False
    parameter_ranges: ClassVar[dict[str, tuple[float, float]]] = {"k": (1e3, 1e12)}
    example_contact: ClassVar[dict[str, float]] = {}
    scene_key_ranges: ClassVar[dict[str, tuple[float, float]]] = {}
    label: ClassVar[str] = "Hertz"
    model_domains: ClassVar[dict[str, str]] = {
        **dict.fromkeys(("short_load_peak_force", "short_load_wave_speed"), "short"),
        **dict.fromkeys(
            (
                "front_speed_lower",
                "front_speed_upper",
                "long_load_peak_force_lower",
                "long_load_peak_force_upper",
                "bead_velocity_at_lower_speed",
                "bead_velocity_at_upper_speed",
            ),
            "long",
        ),
        # peak_force_envelope: min(Eq. 8, Eq. 15 bound), an upper estimate for any loading time;
        # nesterenko_wave_speed: a solitary wave's speed from its measured peak force (ref. 9)
        **dict.fromkeys(("peak_force_envelope", "nesterenko_wave_speed"), "any"),
        # the effects' own regimes: a precompressed chain (Nesterenko's V_s(f_r) at a measured leading
        # peak at any f_r; the sound speed c0 only for a wave small against F0), two-body impacts of a
        # striker or on the wall
        "precompressed_solitary_wave_speed": "precompressed",
        "precompressed_sound_speed": "weakly_nonlinear",
        **dict.fromkeys(("striker_impact_peak_force", "striker_impact_duration"), "striker_impact"),
        **dict.fromkeys(("wall_impact_peak_force", "wall_impact_duration"), "wall_impact"),
        **dict.fromkeys(("pair_impact_peak_force", "pair_impact_duration"), "pair_impact"),
    }
    compare_models: ClassVar[dict[str, tuple[tuple[str, str], ...]]] = {
        "leading_peak_force": (
            ("short_load_peak_force", "Eq. 8"),
            ("pair_impact_peak_force", "Hertz impact (two beads)"),
            ("long_load_peak_force_upper", "Eq. 15 + Nesterenko (upper bound)"),
        ),
        "wave_speed": (
            ("nesterenko_wave_speed", "Nesterenko at the reference's leading peak"),
            ("precompressed_solitary_wave_speed", "Nesterenko's V_s(f_r) at the reference's leading peak over F0"),
        ),
        "striker_peak_force": (("striker_impact_peak_force", "Hertz impact (two bodies)"),),
        "wall_peak_force": (("wall_impact_peak_force", "Hertz impact (bead on the flat)"),),
    }

    @override
    def force(self, alpha, alpha_max=None):
        return hertz_force(alpha, self.k)

    @cached_property
    def _k(self) -> np.ndarray:
        """k as an array (0-d for a scalar): a cheaper operand than a float in force_into (four calls an RK4 step)."""
        return np.array(self.k, dtype=float)

    @override
    def force_into(self, alpha, alpha_max, out, tmp):
        np.sqrt(alpha, out=tmp)
        _multiply(alpha, tmp, out)
        _multiply(out, self._k, out)

    @override
    def energy(self, alpha, alpha_max=None):
        return hertz_energy(alpha, self.k)

    @override
    def loading_exponent(self):
        return np.full(np.shape(self.k), 1.5)  # F = k alpha^(3/2)

    @override
    def loading_force(self, alpha):
        return hertz_force(alpha, self.k)

    @override
    def static_overlap(self, force):
        return (np.asarray(force, dtype=float) / np.asarray(self.k, dtype=float)) ** (2.0 / 3.0)

    @override
    def tangent_stiffness(self, force):
        return hertz_tangent_stiffness(force, self.k)

    @override
    def loading_stiffness(self, force):
        return hertz_tangent_stiffness(force, self.k)

    @override
    def overlap_tangent(self, alpha, alpha_max=None):
        return 1.5 * np.asarray(self.k, dtype=float) * np.sqrt(np.maximum(alpha, 0.0))

    @override
    def kinks(self, alpha_max):
        # F'' is infinite at zero overlap: the contact opens or closes
        return [Kink(np.zeros(np.shape(alpha_max)), "zero overlap")]

    @classmethod
    @override
    def for_pair(cls, coefficients, e_star, r_star, nominal_r_star, materials=()):
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
    @override
    def loading_time_scale(cls, scene, amplitude: float, duration: float) -> TimeScale:
        """T against the crossover time T_c, the corner of Fig. 3's master curve: the loading time at
        which Eq. 8's peak (I = A T, F ~ I^(6/5)) equals the long-load upper bound (Eq. 15 +
        Nesterenko, F ~ A); it goes as A^(-1/6), the transition law of Fig. 1. The paper's Hertz-chain
        models (Eqs. 8, 15, 19) hold for k = 4/3 E* sqrt(R*) and an onset k alpha^(3/2)."""
        m, d, k = scene.mass, scene.diameter, scene.stiffness
        f_short = models.short_load_peak_force(amplitude * duration, m, scene.e_star, scene.r_star)
        f_long = models.solitary_wave_peak_force(models.front_speed_upper(amplitude, k, m, d), k, m, d)
        ratio = (f_short / f_long) ** (5.0 / 6.0)  # Eq. 8 grows as T^(6/5) at fixed A
        return TimeScale(
            ratio,
            HERTZ_SHORT_BELOW,
            HERTZ_LONG_ABOVE,
            "T_c",
            f"T = {duration / scene.tau:.3g} tau = {ratio:.3g} T_c",
            f"T_c = {duration / ratio / scene.tau:.3g} tau, where Eq. 8 meets Eq. 15",
        )

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

    # ---- the law's models (ContactLaw rule 8)
    @classmethod
    @override
    def predictions(cls, scene) -> list[dict]:
        """The effects' Hertz models, then the paper's (Sec. II): Eq. 8 and Nesterenko's speed at its
        force for short loads, the long-load fronts (Eqs. 12, 15, 19) under a force load."""
        return _effect_predictions(scene) + _chain_predictions(scene)

    @classmethod
    @override
    def measured_models(cls, scene, values, observables):
        """Nesterenko's solitary-wave speed at the run's leading peak (ref. 9) and, on a precompressed
        chain, his V_s(f_r) with f_r the largest contact force over F0 (Nesterenko 2001)."""
        f = observables.get("leading_peak_force")
        if not f:
            return {}
        out = {"nesterenko_wave_speed": models.solitary_wave_speed(f, scene.stiffness, scene.mass, scene.diameter)}
        f0 = scene.effects.precompression
        if f0 and "precompressed_sound_speed" in values:
            ratio = (f0 + f) / f0
            c0 = values["precompressed_sound_speed"]
            out["precompressed_solitary_wave_speed"] = models.precompressed_solitary_wave_speed(c0, ratio)
        return out

    @classmethod
    @override
    def model_curves(cls, scene, contacts, applies):
        """Eq. 8's peak (short load) and the long-load bounds, Eqs. 15 and 19 with Nesterenko's peak of
        a solitary wave at the front speed (Fig. 3): constant along the chain."""
        m, d, k = scene.mass, scene.diameter, scene.stiffness
        ld = scene.loading
        curves: dict[str, np.ndarray] = {}
        label = "Eq. 8 (short load)"
        if applies("short_load_peak_force", label):
            curves[label] = np.full(
                contacts.shape, models.short_load_peak_force(scene.input_impulse, m, scene.e_star, scene.r_star)
            )
        for name, eq, fn in (
            ("long_load_peak_force_lower", "Eq. 19", models.front_speed_lower),
            ("long_load_peak_force_upper", "Eq. 15", models.front_speed_upper),
        ):
            label = f"{eq} + Nesterenko (long load)"
            if applies(name, label) and ld.is_step:
                curves[label] = np.full(
                    contacts.shape, models.solitary_wave_peak_force(fn(ld.amplitude, k, m, d), k, m, d)
                )
        return curves


def _chain_predictions(scene) -> list[dict]:
    """The paper's Hertz-chain models (Sec. II): Eq. 8, and under a force load Eqs. 12-19."""
    m, d, k = scene.mass, scene.diameter, scene.stiffness
    fs = scene.force_scale
    ld = scene.loading
    fp = models.short_load_peak_force(scene.input_impulse, m, scene.e_star, scene.r_star)
    out = [
        dict(
            name="short_load_peak_force",
            value=fp,
            unit="N",
            equation="Eq. 8 (constant 0.719 fitted by the authors)",
            valid="single-solitary-wave regime: load shorter than the wave's own contact time "
            "(Fig. 1; T/tau ~ 1 at I = 0.4 N s); measured far enough down the chain for the wave to form",
            nondim=fp / fs,
        ),
        dict(
            name="short_load_wave_speed",
            value=models.solitary_wave_speed(fp, k, m, d),
            unit="m/s",
            equation="Nesterenko long-wave relation V = (2/sqrt5) D k^(1/3) F^(1/6) / sqrt(m) (ref. 9) "
            "at Eq. 8's force",
            valid="as Eq. 8; the long-wave relation is approximate for a discrete chain",
        ),
    ]
    if not ld.is_step:
        return out
    a = ld.amplitude
    cl = models.front_speed_lower(a, k, m, d)
    cu = models.front_speed_upper(a, k, m, d)
    fl = models.solitary_wave_peak_force(cl, k, m, d)
    fu = models.solitary_wave_peak_force(cu, k, m, d)
    long_valid = "wave-train regime: load much longer than the solitary wave's contact time (e.g. T/tau ~ 100)"
    behind = long_valid + "; beads behind the front"
    return out + [
        dict(name="front_speed_lower", value=cl, unit="m/s", equation="Eq. 19", valid=long_valid),
        dict(name="front_speed_upper", value=cu, unit="m/s", equation="Eq. 15", valid=long_valid),
        dict(
            name="long_load_peak_force_lower",
            value=fl,
            unit="N",
            equation="Eq. 19 + Nesterenko (ref. 9)",
            valid=long_valid,
            nondim=fl / fs,
        ),
        dict(
            name="long_load_peak_force_upper",
            value=fu,
            unit="N",
            equation="Eq. 15 + Nesterenko (ref. 9)",
            valid=long_valid,
            nondim=fu / fs,
        ),
        dict(
            name="bead_velocity_at_lower_speed",
            value=models.constant_regime_bead_velocity(a, cl, m, d),
            unit="m/s",
            equation="Eq. 12 with c = c^l",
            valid=behind,
        ),
        dict(
            name="bead_velocity_at_upper_speed",
            value=models.constant_regime_bead_velocity(a, cu, m, d),
            unit="m/s",
            equation="Eq. 12 with c = c^u",
            valid=behind,
        ),
        dict(
            name="peak_force_envelope",
            value=min(fp, fu),
            unit="N",
            equation="min(Eq. 8, upper long-load bound): the two regimes of Fig. 3",
            valid="upper estimate of the leading peak for any loading time",
            nondim=min(fp, fu) / fs,
        ),
    ]


def _effect_predictions(scene) -> list[dict]:
    """The effects' Hertz models (EFFECT_DOMAINS): a precompressed chain's sound speed, and the peak
    force and duration of a two-body impact (a striker on one bead, one bead on the wall)."""
    out = []
    f0 = scene.effects.precompression
    if f0:
        k, m = float(scene.law.k), scene.mass
        spacing = scene.diameter - float(scene.law.static_overlap(f0))
        out.append(
            dict(
                name="precompressed_sound_speed",
                value=models.precompressed_sound_speed(k, f0, m, spacing),
                unit="m/s",
                equation="c0 = a sqrt(k_lin/m), k_lin = 3/2 K^(2/3) F0^(1/3) (Nesterenko 2001, Sec. 1.1)",
                valid=EFFECT_DOMAINS["precompressed"] + "; the speed of a small perturbation's front",
            )
        )
    if scene.chain.beads not in (1, 2):  # the impacts of one or two bodies; an "auto" chain is a long one
        return out
    ld, m1 = scene.loading, float(scene.bead_masses[0])
    if scene.chain.beads == 2 and ld.kind == "velocity" and scene.effects.far_end == "free":
        m2 = float(scene.bead_masses[1])
        hit = models.hertz_impact(float(scene.contact_laws[0].k), m1 * m2 / (m1 + m2), ld.velocity)
        name, law_text = "pair_impact", "bead 1 on bead 2, m* = m1 m2 / (m1 + m2), their E* and R*"
    elif scene.chain.beads != 1:
        return out
    elif ld.kind == "striker":
        ms = scene.striker_mass
        hit = models.hertz_impact(float(scene.striker_law.k), ms * m1 / (ms + m1), ld.velocity)
        name, law_text = "striker_impact", "striker on bead 1, m* = M m / (M + m)"
    elif ld.kind == "velocity" and scene.effects.far_end == "wall":
        hit = models.hertz_impact(float(scene.wall_law.k), m1, ld.velocity)
        name, law_text = "wall_impact", "bead on the flat, E* = E/(1-nu^2), R* = R, m* = m"
        if scene.effects.wall_material is not None or scene.effects.wall_radius is not None:
            law_text = "bead on the wall, E* and R* of the pair (1/E* = (1-nu^2)/E + (1-nu_w^2)/E_w), m* = m"
    else:
        return out
    return out + [
        dict(
            name=f"{name}_peak_force",
            value=hit["peak_force"],
            unit="N",
            equation=f"Hertz impact: K^(2/5) (5/4 m* v^2)^(3/5), {law_text} (Johnson 1985, Sec. 11.1)",
            valid=EFFECT_DOMAINS[name],
            nondim=hit["peak_force"] / scene.force_scale,
        ),
        dict(
            name=f"{name}_duration",
            value=hit["duration"],
            unit="s",
            equation="Hertz impact: 2.943 delta_max / v (Johnson 1985, Sec. 11.1)",
            valid=EFFECT_DOMAINS[name],
        ),
    ]
