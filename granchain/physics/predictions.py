"""Every analytic prediction of the paper for a scene, with its domain of validity and whether the
scene is inside it (:func:`applicability`, the one place that rule lives: `granchain predict`,
`compare` and the plots all ask it)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import NamedTuple

from granchain.physics import models
from granchain.physics.laws import LAWS
from granchain.physics.regimes import loading_regime


@dataclass(frozen=True)
class Prediction:
    name: str
    value: float
    unit: str
    equation: str
    valid: str  # the model's domain of validity, in words
    nondim: float | None = None  # F/(E* R*^2) for forces, I/(E* R*^2 tau) for impulses
    applies: bool = True  # the scene is inside the model's domain (see applicability)
    applies_reason: str = ""  # why it does or does not apply, with the scene's numbers

    def as_dict(self) -> dict:
        return asdict(self)


# ------------------------------------------------------------------------- applicability


class Applicability(NamedTuple):
    applies: bool
    reason: str


#: Quantities of the scene itself (not models): they always apply.
SCENE_QUANTITIES = frozenset({"tau", "impulse", "loading_time_over_tau", "amplitude"})

_HERTZ_SHORT = ("short_load_peak_force", "short_load_wave_speed")
_HERTZ_LONG = (
    "front_speed_lower",
    "front_speed_upper",
    "long_load_peak_force_lower",
    "long_load_peak_force_upper",
    "bead_velocity_at_lower_speed",
    "bead_velocity_at_upper_speed",
)
#: peak_force_envelope: min(Eq. 8, Eq. 15 bound), an upper estimate for any loading time;
#: nesterenko_wave_speed: a solitary wave's speed from its peak force (ref. 9), used by `compare`.
_HERTZ_ANY = ("peak_force_envelope", "nesterenko_wave_speed")
_BILINEAR_SHORT = (
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
)
_BILINEAR_LONG = tuple(f"long_load_{k}" for k in ("c", "c_u", "F_1", "v_1", "v_t", "x_t", "T_t", "F_2", "v_2"))

#: Every model: (contact law, loading regime it needs: "short", "long" or "any").
MODEL_DOMAINS: dict[str, tuple[str, str]] = {
    **{n: ("hertz", "short") for n in _HERTZ_SHORT},
    **{n: ("hertz", "long") for n in _HERTZ_LONG},
    **{n: ("hertz", "any") for n in _HERTZ_ANY},
    **{n: ("bilinear", "short") for n in _BILINEAR_SHORT},
    **{n: ("bilinear", "long") for n in _BILINEAR_LONG},
    # the effects' own regimes: a precompressed chain, two-body impacts of a striker or on the wall
    "precompressed_sound_speed": ("hertz", "precompressed"),
    # Nesterenko's V_s(f_r) at a measured leading peak (compare, like nesterenko_wave_speed)
    "precompressed_solitary_wave_speed": ("hertz", "precompressed"),
    "striker_impact_peak_force": ("hertz", "striker_impact"),
    "striker_impact_duration": ("hertz", "striker_impact"),
    "wall_impact_peak_force": ("hertz", "wall_impact"),
    "wall_impact_duration": ("hertz", "wall_impact"),
    # a law's own models (granchain.physics.laws: ContactLaw.model_domains)
    **{n: (name, needs) for name, cls in LAWS.items() for n, needs in cls.model_domains.items()},
}

#: (model, measured quantity) pairs where the run measures something other than what the model
#: predicts, whatever the scene. A run's wave_speed follows the times of peak force along the window.
MEASURES_OTHER = {
    # Table I scene: 979 m/s measured from the times of peak, c = 757 m/s
    ("long_load_c", "wave_speed"): (
        "c is the plastic loading front's speed (where the force first rises), while wave_speed is measured "
        "from the times of peak force, which lag the dispersing pulse of a short load and fall anywhere on the "
        "flat plateau behind a long load's front"
    ),
}

#: A striker within this fraction of a bead's mass hands bead 1 its velocity (equal elastic masses
#: exchange velocities): the velocity load, Eq. 8's zero-duration limit (measured: Eq. 8 within 0.3%;
#: 0.3 m: 65% above it, the striker rebounds; 2 m: 35% below, it pushes on).
EQUAL_STRIKER_MASS = 0.05


def applicability(name: str, scene, quantity: str | None = None) -> Applicability:
    """Whether the model `name` (a prediction's name, see MODEL_DOMAINS) applies to `scene`, and why.

    The paper's models are for a semi-infinite monodisperse chain with no dissipation but the contact
    law's, no precompression, loaded by f(t) = A on 0 < t <= T (Eq. 4) or its zero-duration limit, a
    velocity of bead 1. A model applies when the scene has its contact law, uniform beads, no dashpot,
    no precompression, the paper's loading (a striker only as an equal-mass one, which hands bead 1
    its velocity) and the loading regime the model is for
    (granchain.physics.regimes.loading_regime). A far-end wall leaves every model in force for
    the incident wave, before the reflection reaches a contact. Given the measured `quantity` it is
    compared with, also whether the run measures what the model predicts (MEASURES_OTHER).
    """
    if name in SCENE_QUANTITIES:
        return Applicability(True, "a quantity of the scene itself, not a model")
    if name not in MODEL_DOMAINS:
        raise ValueError(f"{name!r}: no such model; known: {', '.join([*SCENE_QUANTITIES, *MODEL_DOMAINS])}")
    law, needs = MODEL_DOMAINS[name]
    if needs in EFFECT_DOMAINS:
        return _effect_model_applies(law, needs, scene)
    why_not: list[str] = []
    if scene.contact.law != law:
        why_not.append(f"a {law} model; this chain's contact law is {scene.contact.law}")
    why_not += _outside_the_papers_chain(scene)
    ld = scene.loading
    if needs == "collision":
        if ld.kind != "velocity" or scene.chain.beads != 2 or scene.effects.far_end != "free":
            why_not.append(
                "a two-body impact model: it needs two beads, bead 1 given a velocity and a free far end "
                f"(this scene: {scene.chain.beads} beads, a {ld.kind} load, far end {scene.effects.far_end})"
            )
        needs = "any"
    wall = (
        "; with the far-end wall: for the incident wave, at contacts the wall's reflection has not yet reached"
        if scene.effects.far_end == "wall"
        else ""
    )
    regime = loading_regime(scene) if scene.contact.law == law else None
    if regime is not None and needs != "any" and regime.regime != needs:
        why_not.append(f"{regime.text}; the model is for a {needs} load")
    if why_not:
        return Applicability(False, "; ".join(why_not))
    if quantity is not None and (name, quantity) in MEASURES_OTHER:
        return Applicability(False, MEASURES_OTHER[(name, quantity)])
    chain = f"uniform {'Hertz' if law == 'hertz' else law} chain, no dashpot, no precompression"
    if needs == "any":
        return Applicability(True, f"{chain}, any loading time{wall}")
    return Applicability(True, f"{regime.text}; {chain}{wall}")


#: the domains of the effects' models: what the scene must be, in words
EFFECT_DOMAINS = {
    "precompressed": "a uniform Hertz chain under static precompression, no dashpot",
    "striker_impact": "a striker on one free bead, Hertz contact, no dashpot or precompression (two bodies)",
    "wall_impact": "one bead given a velocity against the wall, Hertz contact, no dashpot or precompression",
}


def _effect_model_applies(law: str, needs: str, scene) -> Applicability:
    """Applicability of the effects' models (EFFECT_DOMAINS), which hold where the paper's do not."""
    why_not = []
    if scene.contact.law != law:
        why_not.append(f"a {law} model; this chain's contact law is {scene.contact.law}")
    if scene.effects.dashpot:
        why_not.append(f"viscous dashpot (gamma = {scene.effects.dashpot:g} N s/m)")
    if needs == "precompressed":
        if not scene.effects.precompression:
            why_not.append("no static precompression")
        if scene.per_bead:
            why_not.append("the beads differ: c0 is for a uniform chain")
    else:
        if scene.effects.precompression:
            why_not.append(f"static precompression F0 = {scene.effects.precompression:g} N")
        if scene.chain.beads != 1:
            why_not.append(f"{scene.chain.beads} beads: a two-body impact needs one bead (its neighbours push back)")
        ld, wall = scene.loading, scene.effects.far_end == "wall"
        if needs == "striker_impact" and (ld.kind != "striker" or wall):
            why_not.append(f"a {ld.kind} load, far end {scene.effects.far_end}: needs a striker and a free bead")
        if needs == "wall_impact" and (ld.kind != "velocity" or not wall):
            why_not.append(f"a {ld.kind} load, far end {scene.effects.far_end}: needs a velocity load and the wall")
    if why_not:
        return Applicability(False, "; ".join(why_not))
    return Applicability(True, "the scene is inside the model's domain")


#: The paper's models are for a long chain: the solitary wave forms over the first few beads and is
#: measured over the middle half of the chain; below this many beads they do not apply (a two-bead
#: chain is a two-body impact: Eq. 8 gives 159.6 N where the exact impact gives 187.8 N)
MIN_CHAIN_BEADS = 10


def _outside_the_papers_chain(scene) -> list[str]:
    """Why the scene is not the paper's chain (uniform beads, no dashpot or precompression, the
    paper's loading), one reason each; empty when it is."""
    why_not: list[str] = []
    if scene.chain.beads is not None and scene.chain.beads < MIN_CHAIN_BEADS:
        why_not.append(
            f"a chain of {scene.chain.beads} bead{'s' if scene.chain.beads > 1 else ''}: the paper's models are "
            f"for a long chain, where the wave forms over the first beads (at least {MIN_CHAIN_BEADS})"
        )
    if scene.per_bead:
        r = scene.chain.radii or (scene.chain.radius,)
        differ = [f"radii {min(r) * 1e3:.3g} to {max(r) * 1e3:.3g} mm: tapered or decorated"] if len(set(r)) > 1 else []
        if scene.chain.materials is not None and len(set(scene.chain.materials)) > 1:
            differ.append(f"materials {', '.join(sorted(set(scene.chain.materials)))}")
        why_not.append(f"the beads differ ({'; '.join(differ)}): the paper's models are for a monodisperse chain")
    if scene.effects.dashpot:
        why_not.append(
            f"viscous dashpot (gamma = {scene.effects.dashpot:g} N s/m): the paper's models have no viscous dissipation"
        )
    if scene.effects.precompression:
        why_not.append(
            f"static precompression F0 = {scene.effects.precompression:g} N: the paper's models are for an "
            "uncompressed chain (a precompressed chain carries other waves, ref. 9)"
        )
    ld = scene.loading
    if ld.kind == "striker":
        ratio = scene.striker_mass / scene.mass
        if scene.contact.law != "hertz" or abs(ratio - 1.0) > EQUAL_STRIKER_MASS:
            why_not.append(
                f"a striker (M = {ratio:.3g} m at {ld.velocity:g} m/s) is not the paper's loading (a force "
                "f(t), Eq. 4, or bead 1's velocity): a lighter one rebounds, a heavier one pushes on"
                + ("" if scene.contact.law == "hertz" else f", and its {scene.contact.law} contact dissipates")
            )
    return why_not


def predict(scene) -> list[Prediction]:
    """Predictions for this scene (SI), nondimensional forms where the paper gives them, each with
    whether it applies to the scene (applies, applies_reason: see applicability)."""
    out = []
    for p in _predict(scene):
        verdict = applicability(p.name, scene)
        out.append(replace(p, applies=verdict.applies, applies_reason=verdict.reason))
    return out


def _predict(scene) -> list[Prediction]:
    m, d, k = scene.mass, scene.diameter, scene.stiffness
    fs, isc = scene.force_scale, scene.impulse_scale
    ld = scene.loading
    impulse = scene.input_impulse
    out: list[Prediction] = [
        Prediction("tau", scene.tau, "s", "Eq. 7", "intrinsic time scale of the bead pair"),
        Prediction(
            "impulse", impulse, "N s", "Eq. 4 (I = A T; velocity load: I = m v0)", "always", nondim=impulse / isc
        ),
    ]
    if ld.is_force:
        out.append(Prediction("loading_time_over_tau", ld.duration / scene.tau, "-", "T / tau (Eq. 7)", "always"))
        out.append(Prediction("amplitude", ld.amplitude, "N", "Eq. 4", "always", nondim=ld.amplitude / fs))

    out += _effect_predictions(scene)
    if scene.contact.law == "hertz":
        fp = models.short_load_peak_force(impulse, m, scene.e_star, scene.r_star)
        out.append(
            Prediction(
                "short_load_peak_force",
                fp,
                "N",
                "Eq. 8 (constant 0.719 fitted by the authors)",
                "single-solitary-wave regime: load shorter than the wave's own contact time "
                "(Fig. 1; T/tau ~ 1 at I = 0.4 N s); measured far enough down the chain for the wave to form",
                nondim=fp / fs,
            )
        )
        out.append(
            Prediction(
                "short_load_wave_speed",
                models.solitary_wave_speed(fp, k, m, d),
                "m/s",
                "Nesterenko long-wave relation V = (2/sqrt5) D k^(1/3) F^(1/6) / sqrt(m) (ref. 9) at Eq. 8's force",
                "as Eq. 8; the long-wave relation is approximate for a discrete chain",
            )
        )
        if ld.is_force:
            a = ld.amplitude
            cl = models.front_speed_lower(a, k, m, d)
            cu = models.front_speed_upper(a, k, m, d)
            fl = models.solitary_wave_peak_force(cl, k, m, d)
            fu = models.solitary_wave_peak_force(cu, k, m, d)
            long_valid = "wave-train regime: load much longer than the solitary wave's contact time (e.g. T/tau ~ 100)"
            out += [
                Prediction("front_speed_lower", cl, "m/s", "Eq. 19", long_valid),
                Prediction("front_speed_upper", cu, "m/s", "Eq. 15", long_valid),
                Prediction(
                    "long_load_peak_force_lower", fl, "N", "Eq. 19 + Nesterenko (ref. 9)", long_valid, nondim=fl / fs
                ),
                Prediction(
                    "long_load_peak_force_upper", fu, "N", "Eq. 15 + Nesterenko (ref. 9)", long_valid, nondim=fu / fs
                ),
                Prediction(
                    "bead_velocity_at_lower_speed",
                    models.constant_regime_bead_velocity(a, cl, m, d),
                    "m/s",
                    "Eq. 12 with c = c^l",
                    long_valid + "; beads behind the front",
                ),
                Prediction(
                    "bead_velocity_at_upper_speed",
                    models.constant_regime_bead_velocity(a, cu, m, d),
                    "m/s",
                    "Eq. 12 with c = c^u",
                    long_valid + "; beads behind the front",
                ),
                Prediction(
                    "peak_force_envelope",
                    min(fp, fu),
                    "N",
                    "min(Eq. 8, upper long-load bound): the two regimes of Fig. 3",
                    "upper estimate of the leading peak for any loading time",
                    nondim=min(fp, fu) / fs,
                ),
            ]
        return out

    # ---- the law's own models (granchain.physics.laws)
    out += [Prediction(**d) for d in scene.contact.law_class.predictions(scene)]
    if scene.contact.law != "bilinear":
        return out

    # ---- bilinear (Sec. III)
    beta = scene.contact.unloading_coeff
    ku = scene.unloading_stiffness
    lin = models.linear_chain_impulse_response(impulse, k, m, beta)
    short_valid = "short loading (T much shorter than the contact time pi sqrt(m/2k)); first contacts"
    out += [
        Prediction("first_contact_peak_force", lin["F_p"], "N", "Eq. A2", short_valid, nondim=lin["F_p"] / fs),
        Prediction("first_beads_velocity_at_peak", lin["v_m"], "m/s", "Eq. A1", short_valid),
        Prediction("second_contact_force_at_peak", lin["F_2"], "N", "Eq. A3", short_valid, nondim=lin["F_2"] / fs),
        Prediction("trailing_velocity", lin["v_t"], "m/s", "Eq. A4", short_valid),
        Prediction(
            "dissipation_first_contact",
            float(models.dissipation_per_cycle(lin["F_p"], k, beta)),
            "J",
            "Eq. 20",
            "energy dissipated at a contact loaded to the first contact's peak force",
        ),
    ]
    coeffs = models.leading_wave_coefficients(k, m, beta)
    lam = models.exponential_decay_rate(k, m, beta)
    out += [
        Prediction("gamma", coeffs.gamma, "m/(s N)", "Eq. 22 via A1, A2", short_valid),
        Prediction("eta", coeffs.eta, "-", "Eq. 22 via A2, A3", short_valid),
        Prediction("omega", coeffs.omega, "m/(s N)", "Eq. 22 via A1, A2, A4", short_valid),
        Prediction(
            "exponential_decay_per_contact",
            lam,
            "-",
            "Eqs. 26-27 (F_{i+1} = F_i exp(-lambda); Eq. 27 as derived from Eq. 26)",
            "exponential regime: contacts before the transition",
        ),
    ]
    tc = transition_contact(lin["F_p"], lam, ku, m, coeffs.omega, scene.n_contacts)
    if tc is not None:
        out.append(
            Prediction(
                "transition_contact",
                float(tc),
                "-",
                "Eq. 27 meets Eq. 30",
                "first contact where the secondary-wave peak exceeds the leading peak",
            )
        )
    out.append(
        Prediction(
            "inverse_decay_exponent",
            models.inverse_decay_exponent(beta),
            "-",
            "Eq. 34",
            "inverse regime, beyond the transition contact",
        )
    )
    if ld.is_force:
        try:
            r = models.long_load_bilinear(ld.amplitude, ld.duration, k, beta, m, d)
        except ZeroDivisionError:  # beta ~ 0: c_u = c, the fronts never merge (Eq. 36's x_t is infinite)
            r = {}
        long_valid = "long loading (steady fronts, Sec. III B); until the first collision of the fronts"
        units = {
            "c": "m/s",
            "c_u": "m/s",
            "F_1": "N",
            "v_1": "m/s",
            "v_t": "m/s",
            "x_t": "m",
            "T_t": "s",
            "F_2": "N",
            "v_2": "m/s",
        }
        eqs = {
            "c": "c = D sqrt(k/m) (Sec. III B)",
            "c_u": "c_u = D sqrt(k_u/m) (Sec. III B)",
            "F_1": "F_1 = A",
            "v_1": "Eq. 35",
            "v_t": "v_t = v_1 - 2 F_1 R/(m c_u) (Sec. III B)",
            "x_t": "Eq. 36",
            "T_t": "Eq. 36",
            "F_2": "Eq. 38",
            "v_2": "Eq. 38",
        }
        for key, val in r.items():
            nd = val / fs if units[key] == "N" else None
            out.append(Prediction(f"long_load_{key}", val, units[key], eqs[key], long_valid, nondim=nd))
    return out


def leading_peaks_exponential(first_peak: float, decay: float, n: int):
    """Leading peak force at contacts 1..n in the exponential regime (Eq. 27)."""
    return [first_peak * math.exp(-decay * i) for i in range(n)]


def transition_contact(
    first_peak: float, decay: float, k_u: float, mass: float, omega: float, n_contacts: int
) -> int | None:
    """First contact (1-based) where Eq. 30's secondary peak exceeds Eq. 27's leading peak."""
    lead = leading_peaks_exponential(first_peak, decay, n_contacts)
    for i in range(1, n_contacts):
        fs = models.secondary_wave_peak_force(lead[0] - lead[i], k_u, mass, omega)
        if fs > lead[i]:
            return i + 1
    return None


def _effect_predictions(scene) -> list[Prediction]:
    """The effects' models (EFFECT_DOMAINS): the precompressed chain's sound speed, two-body impacts."""
    if scene.contact.law != "hertz":
        return []
    out = []
    f0 = scene.effects.precompression
    if f0:
        k, m = float(scene.law.k), scene.mass
        spacing = scene.diameter - float(scene.law.static_overlap(f0))
        out.append(
            Prediction(
                "precompressed_sound_speed",
                models.precompressed_sound_speed(k, f0, m, spacing),
                "m/s",
                "c0 = a sqrt(k_lin/m), k_lin = 3/2 K^(2/3) F0^(1/3) (Nesterenko 2001, Sec. 1.1)",
                EFFECT_DOMAINS["precompressed"] + "; the speed of a small perturbation's front",
            )
        )
    if scene.chain.beads == 1:
        ld, m1 = scene.loading, float(scene.bead_masses[0])
        if ld.kind == "striker":
            ms = scene.striker_mass
            hit = models.hertz_impact(float(scene.striker_law.k), ms * m1 / (ms + m1), ld.velocity)
            name, law_text = "striker_impact", "striker on bead 1, m* = M m / (M + m)"
        elif ld.kind == "velocity" and scene.effects.far_end == "wall":
            hit = models.hertz_impact(float(scene.wall_law.k), m1, ld.velocity)
            name, law_text = "wall_impact", "bead on the flat, E* = E/(1-nu^2), R* = R, m* = m"
        else:
            return out
        nd = EFFECT_DOMAINS[name]
        out += [
            Prediction(
                f"{name}_peak_force",
                hit["peak_force"],
                "N",
                f"Hertz impact: K^(2/5) (5/4 m* v^2)^(3/5), {law_text} (Johnson 1985, Sec. 11.1)",
                nd,
                nondim=hit["peak_force"] / scene.force_scale,
            ),
            Prediction(
                f"{name}_duration",
                hit["duration"],
                "s",
                "Hertz impact: 2.943 delta_max / v (Johnson 1985, Sec. 11.1)",
                nd,
            ),
        ]
    return out
