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
The law's models: the paper's Sec. III (the linear chain's first contacts, Eqs. A1-A4; the leading
wave's exponential decay, Eqs. 22-27, the transition, Eq. 30, and the inverse decay, Eq. 34; the
steady fronts of a long load, Eqs. 35-38).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np
from typing_extensions import override

from granchain.physics import materials as mat
from granchain.physics import models
from granchain.physics.laws.base import ArrayLike, ContactLaw, Kink, LawCoefficients, forbid_others

_multiply, _subtract, _greater, _less = np.multiply, np.subtract, np.greater, np.less  # (one lookup, not two)
_ZERO_FORCE, _RELOADING = "zero force at beta alpha_max", "reloading meets alpha_max"  # (the kinks' kinds)

#: the long-load models (Sec. III B; models.long_load_bilinear's keys): unit and equation
_LONG_LOAD = {
    "c": ("m/s", "c = D sqrt(k/m) (Sec. III B)"),
    "c_u": ("m/s", "c_u = D sqrt(k_u/m) (Sec. III B)"),
    "F_1": ("N", "F_1 = A"),
    "v_1": ("m/s", "Eq. 35"),
    "v_t": ("m/s", "v_t = v_1 - 2 F_1 R/(m c_u) (Sec. III B)"),
    "x_t": ("m", "Eq. 36"),
    "T_t": ("s", "Eq. 36"),
    "F_2": ("N", "Eq. 38"),
    "v_2": ("m/s", "Eq. 38"),
}


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
class BilinearCoefficients(LawCoefficients):
    """The bilinear law's [contact] values."""

    #: beta, the residual-to-maximum overlap ratio, 0 <= beta < 1
    unloading_coeff: float
    #: k in N/m, given or from the material's yield strength (k = 18.5 sigma_y R*); None on a chain of
    #: several materials, where each contact's k comes from the softer bead's yield strength
    plastic_stiffness: float | None = None


#: the lowest order of an integrator's error on a bilinear chain: its peaks at the turn measured 2.5-3.2,
#: as a Hertzian onset's 1 + 3/2 (BilinearLaw.onset_order); it lowers an integrator of higher order (RK4's
#: 4), not one below it (Verlet's 2)
LOADING_LINE_ORDER = 2.5


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
    # the unloading slope k_u = k / (1 - beta) at any force
    constant_tangent: ClassVar[bool] = True
    # RK4 locates the closing kink and the loading line is smooth after it
    closing_limits_order: ClassVar[bool] = False
    Coefficients: ClassVar[type[LawCoefficients]] = BilinearCoefficients
    key_units: ClassVar[dict[str, str]] = {"unloading_coeff": "1", "plastic_stiffness": "N/m"}
    yield_strength_key: ClassVar[str | None] = "plastic_stiffness"
    parameter_ranges: ClassVar[dict[str, tuple[float, float]]] = {"k": (1e3, 1e12), "beta": (0.0, 0.99)}
    example_contact: ClassVar[dict[str, float]] = {"unloading_coeff": 0.8, "plastic_stiffness": 2.43e7}
    scene_key_ranges: ClassVar[dict[str, tuple[float, float]]] = {
        "unloading_coeff": (0.0, 0.9),
        "plastic_stiffness": (1e6, 1e8),
    }
    model_domains: ClassVar[dict[str, str]] = {
        **dict.fromkeys(
            (
                "first_contact_peak_force",
                "first_beads_velocity_at_peak",
                "second_contact_force_at_peak",
                "trailing_velocity",
                "dissipation_first_contact",
                "gamma",
                "eta",
                "omega",
                "exponential_decay_per_contact",
                "transition_contact",
                "inverse_decay_exponent",
            ),
            "short",
        ),
        **dict.fromkeys((f"long_load_{key}" for key in _LONG_LOAD), "long"),
    }
    compare_models: ClassVar[dict[str, tuple[tuple[str, str], ...]]] = {
        "peak_force_contact_1": (("first_contact_peak_force", "Eq. A2 (short loading)"),),
        "wave_speed": (("long_load_c", "c = D sqrt(k/m) (Sec. III B, long loading)"),),
    }

    beta: ArrayLike

    @cached_property
    def k_unloading(self):
        """k_u = k / (1 - beta), computed once (the solver's inner loop reads it every step)."""
        return unloading_stiffness(self.k, self.beta)

    @override
    def force(self, alpha, alpha_max=None):
        return bilinear_force(alpha, 0.0 if alpha_max is None else alpha_max, self.k, self.beta)

    @cached_property
    def _operands(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """beta, k_u and 0 as arrays (0-d for scalars): numpy takes a Python or numpy float operand at
        about half again the cost of a whole call on a short chain (force_into runs four times an RK4 step)."""
        return np.array(self.beta, dtype=float), np.array(self.k_unloading, dtype=float), np.array(0.0)

    @override
    def force_into(self, alpha, alpha_max, out, tmp):
        # F = max(k_u (alpha - beta max(alpha_max, alpha)), 0); with alpha_max frozen this is the
        # loading line k alpha wherever alpha >= alpha_max
        beta, ku, zero = self._operands
        np.maximum(alpha_max, alpha, out=tmp)
        _multiply(tmp, beta, tmp)
        _subtract(alpha, tmp, out)
        _multiply(out, ku, out)
        np.maximum(out, zero, out=out)

    @override
    def energy(self, alpha, alpha_max=None):
        return bilinear_energy(alpha, 0.0 if alpha_max is None else alpha_max, self.k, self.beta)

    @override
    def dissipated(self, alpha_max):
        return bilinear_dissipated(alpha_max, self.k, self.beta)

    @override
    def loading_exponent(self):
        return np.full(np.shape(self.k), 1.0)  # the loading line F = k alpha

    @override
    def onset_order(self) -> float:
        """LOADING_LINE_ORDER: not 1 + n = 2 of the loading line, whose closing is a kink RK4 locates, but
        the order the error of its peaks at the turn was measured to show."""
        return LOADING_LINE_ORDER

    @override
    def loading_force(self, alpha):
        """The force never exceeds the loading line: the peak is k alpha_max."""
        return np.asarray(self.k) * np.maximum(alpha, 0.0)

    @override
    def static_overlap(self, force):
        return np.asarray(force, dtype=float) / np.asarray(self.k, dtype=float)

    @override
    def loading_stiffness(self, force=None):
        """k at any force: the loading line."""
        return np.asarray(self.k, dtype=float)

    @override
    def tangent_stiffness(self, force=None):
        """k_u at any force: unloading is the stiffer line."""
        return np.asarray(self.k_unloading)

    @override
    def overlap_tangent(self, alpha, alpha_max=None):
        """k on the loading line (alpha >= alpha_max), k_u while un/reloading with a force, else 0."""
        a = np.asarray(alpha, dtype=float)
        am = a if alpha_max is None else np.maximum(alpha_max, a)
        k, ku = np.asarray(self.k, dtype=float), np.asarray(self.k_unloading, dtype=float)
        unloading = np.where(a - np.asarray(self.beta, dtype=float) * am > 0.0, ku, 0.0)
        return np.where(a > 0.0, np.where(a >= am, k, unloading), 0.0)

    @override
    def kinks(self, alpha_max):
        beta, _, zero = self._operands  # (0-d operands: the RK4 event location asks at every piece)
        return [
            # the force reaches zero at beta alpha_max (F' jumps from k_u to 0)
            Kink(_multiply(beta, alpha_max), _ZERO_FORCE),
            # reloading meets the loading line again at alpha_max (slope k_u -> k)
            Kink(alpha_max, _RELOADING, where=_greater(alpha_max, zero), from_below=True),
        ]

    @override
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

    @override
    def plastic_onset_force(self) -> np.ndarray:
        """0: the loading line leaves a residual overlap beta alpha_max at any load (Walton-Braun has
        no elastic range)."""
        return np.zeros(np.shape(self.k))

    @override
    def turn_level(self, alpha_max):
        # a turn from loading to unloading at a new alpha_max (slope k -> k_u)
        return alpha_max

    @classmethod
    @override
    def read_contact(cls, s, chain) -> BilinearCoefficients:
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
            return BilinearCoefficients(unloading_coeff=beta, plastic_stiffness=None)
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
        return BilinearCoefficients(unloading_coeff=beta, plastic_stiffness=k)

    @classmethod
    @override
    def for_pair(cls, coefficients, e_star, r_star, nominal_r_star, materials=()):
        beta = coefficients.unloading_coeff
        if coefficients.plastic_stiffness is None:  # several materials: 18.5 sigma_y R* of the pair, the softer's
            k = mat.PLASTIC_STIFFNESS_FACTOR * mat.softer_yield_strength(materials) * r_star
            return cls(k=k, beta=beta)
        k = float(coefficients.plastic_stiffness)
        return cls(k=k if r_star == nominal_r_star else k * (r_star / nominal_r_star), beta=beta)

    # ---- the planner's estimates
    @classmethod
    def expected_peak_force(cls, scene, impulse: float, step) -> float:
        """Eq. A2 for an impulse; a long load cannot push a linear contact past 2 A; x1.5 margin."""
        k, m = scene.stiffness, scene.mass
        beta = scene.contact.coefficients.unloading_coeff
        f = models.linear_chain_impulse_response(impulse, k, m, beta)["F_p"]  # Eq. A2
        if step is not None:
            f = min(f, 2.0 * step[0])
        return 1.5 * f

    @classmethod
    @override
    def two_body_contact_time(cls, scene, amplitude: float) -> tuple[float, str]:
        """t_c = pi sqrt(m / 2k): two beads on the loading line k (the plastic slope), at any amplitude."""
        return math.pi * math.sqrt(scene.mass / (2.0 * scene.stiffness)), "pi sqrt(m/2k)"

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

    # ---- the law's models (ContactLaw rule 8)
    @classmethod
    @override
    def predictions(cls, scene) -> list[dict]:
        """The paper's bilinear-chain models (Sec. III): short loading's first contacts and decay
        regimes (Eqs. A1-A4, 20-34), and under a force load the steady fronts (Eqs. 35-38)."""
        out = _short_load_predictions(scene)
        ld = scene.loading
        if ld.is_step:
            out += _long_load_predictions(scene, ld.amplitude, ld.duration)
        return out

    @classmethod
    @override
    def model_curves(cls, scene, contacts, applies):
        """Eq. 27's exponential decay from Eq. A2's first peak, drawn a little past the transition
        (Eq. 30) to show where the two meet, and Eq. 34's inverse decay from the transition on."""
        m, k = scene.mass, scene.stiffness
        beta = scene.contact.coefficients.unloading_coeff
        curves: dict[str, np.ndarray] = {}
        f1 = models.linear_chain_impulse_response(scene.input_impulse, k, m, beta)["F_p"]
        lam = models.exponential_decay_rate(k, m, beta)
        coeffs = models.leading_wave_coefficients(k, m, beta)
        tc = models.transition_contact(f1, lam, scene.unloading_stiffness, m, coeffs.omega, int(contacts.max()))
        label = "Eq. 27 (exponential regime)"
        if applies("exponential_decay_per_contact", label):
            # Eq. 27 holds before the transition; drawn to twice it to show where the two meet
            last = 2 * tc if tc is not None else contacts.max()
            curves[label] = np.where(contacts <= last, f1 * np.exp(-lam * (contacts - 1)), np.nan)
        label = "Eq. 34 slope (1+beta)/2" + (f" from contact {tc}" if tc is not None else "")
        if applies("inverse_decay_exponent", label) and tc is not None:
            p = models.inverse_decay_exponent(beta)
            anchor = f1 * np.exp(-lam * (tc - 1))
            curves[label] = np.where(contacts >= tc, anchor * (contacts / tc) ** (-p), np.nan)
        return curves


def _short_load_predictions(scene) -> list[dict]:
    """Short loading (Sec. III A): Eqs. A1-A4 of the first contacts, Eq. 20's dissipation, the leading
    wave's coefficients (Eq. 22) and exponential decay (Eqs. 26-27), the transition contact (Eq. 30)
    and the inverse decay's exponent (Eq. 34)."""
    m, k = scene.mass, scene.stiffness
    fs = scene.force_scale
    beta = scene.contact.coefficients.unloading_coeff
    lin = models.linear_chain_impulse_response(scene.input_impulse, k, m, beta)
    short_valid = "short loading (T much shorter than the contact time pi sqrt(m/2k)); first contacts"

    def short(name, value, unit, equation, nondim=None):
        return dict(name=name, value=value, unit=unit, equation=equation, valid=short_valid, nondim=nondim)

    out = [
        short("first_contact_peak_force", lin["F_p"], "N", "Eq. A2", nondim=lin["F_p"] / fs),
        short("first_beads_velocity_at_peak", lin["v_m"], "m/s", "Eq. A1"),
        short("second_contact_force_at_peak", lin["F_2"], "N", "Eq. A3", nondim=lin["F_2"] / fs),
        short("trailing_velocity", lin["v_t"], "m/s", "Eq. A4"),
        dict(
            name="dissipation_first_contact",
            value=float(models.dissipation_per_cycle(lin["F_p"], k, beta)),
            unit="J",
            equation="Eq. 20",
            valid="energy dissipated at a contact loaded to the first contact's peak force",
        ),
    ]
    coeffs = models.leading_wave_coefficients(k, m, beta)
    lam = models.exponential_decay_rate(k, m, beta)
    out += [
        short("gamma", coeffs.gamma, "m/(s N)", "Eq. 22 via A1, A2"),
        short("eta", coeffs.eta, "1", "Eq. 22 via A2, A3"),
        short("omega", coeffs.omega, "m/(s N)", "Eq. 22 via A1, A2, A4"),
        dict(
            name="exponential_decay_per_contact",
            value=lam,
            unit="1",
            equation="Eqs. 26-27 (F_{i+1} = F_i exp(-lambda); Eq. 27 as derived from Eq. 26)",
            valid="exponential regime: contacts before the transition",
        ),
    ]
    if scene.chain.beads is None:  # "auto": whether the chain reaches the transition is its planned length's
        tc = math.nan  # (predictions.applicability: it does not apply, and why)
    else:
        tc = models.transition_contact(lin["F_p"], lam, scene.unloading_stiffness, m, coeffs.omega, scene.n_contacts)
    if tc is not None:
        out.append(
            dict(
                name="transition_contact",
                value=float(tc),
                unit="1",
                equation="Eq. 27 meets Eq. 30",
                valid="first contact where the secondary-wave peak exceeds the leading peak",
            )
        )
    out.append(
        dict(
            name="inverse_decay_exponent",
            value=models.inverse_decay_exponent(beta),
            unit="1",
            equation="Eq. 34",
            valid="inverse regime, beyond the transition contact",
        )
    )
    return out


def _long_load_predictions(scene, amplitude: float, duration: float) -> list[dict]:
    """Long loading (Sec. III B): the steady fronts until they first collide (Eqs. 35-38)."""
    try:
        r = models.long_load_bilinear(
            amplitude, duration, scene.stiffness, scene.contact.coefficients.unloading_coeff, scene.mass, scene.diameter
        )
    except ZeroDivisionError:  # beta ~ 0: c_u = c, the fronts never merge (Eq. 36's x_t is infinite)
        r = {}
    long_valid = "long loading (steady fronts, Sec. III B); until the first collision of the fronts"
    out = []
    for key, val in r.items():
        unit, equation = _LONG_LOAD[key]
        nd = val / scene.force_scale if unit == "N" else None
        out.append(dict(name=f"long_load_{key}", value=val, unit=unit, equation=equation, valid=long_valid, nondim=nd))
    return out
