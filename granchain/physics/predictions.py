"""Every analytic prediction of the paper for a scene, with its domain of validity and whether the
scene is inside it (:func:`applicability`, the one place that rule lives: `granchain predict`,
`compare` and the plots all ask it)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import NamedTuple

from granchain.physics import bands as band_structure
from granchain.physics import materials as mat
from granchain.physics import models
from granchain.physics.damping import DAMPING
from granchain.physics.effects.gravity import scene_static_forces
from granchain.physics.laws import LAWS
from granchain.physics.laws.base import EFFECT_DOMAINS, two_bodies
from granchain.physics.loading_regime import loading_regime
from granchain.physics.models import leading_peaks_exponential, transition_contact

__all__ = [
    "DAMPING_MODEL_DOMAINS",
    "EFFECT_DOMAINS",
    "MODEL_DOMAINS",
    "SCENE_QUANTITIES",
    "BAND_ROWS",
    "Applicability",
    "Prediction",
    "applicability",
    "leading_peaks_exponential",
    "predict",
    "transition_contact",
]


@dataclass(frozen=True)
class Prediction:
    """One value of a model of the paper (or a quantity of the scene itself) for a scene, with its
    equation, the model's domain of validity and whether the scene is inside it (``applicability``).
    What `granchain predict` prints and `compare` and the plots check runs against."""

    name: str
    value: float
    unit: str
    equation: str
    valid: str  # the model's domain of validity, in words
    nondim: float | None = None  # F/(E* R*^2) for forces, I/(E* R*^2 tau) for impulses
    applies: bool = True  # the scene is inside the model's domain (see applicability)
    applies_reason: str = ""  # why it does or does not apply, with the scene's numbers

    def as_dict(self) -> dict:
        """Its fields as a dict (`granchain predict --json`)."""
        return asdict(self)


# ------------------------------------------------------------------------- applicability


class Applicability(NamedTuple):
    """Whether a model applies to a scene (its domain of validity holds there) and why, in words with
    the scene's numbers: ``applicability``'s answer."""

    applies: bool
    reason: str


#: Quantities of the scene itself (not models): they always apply.
SCENE_QUANTITIES = frozenset({"tau", "impulse", "loading_time_over_tau", "amplitude"})

#: A vertical chain's local sound speed c0(i) at its top and bottom contacts ([gravity]): each
#: contact's static force differs, so the linearised chain's speed does (local_sound_speeds)
LOCAL_SPEEDS = {"local_sound_speed_top": 0, "local_sound_speed_bottom": -1}

#: The linear band structure of a precompressed periodic chain (granchain.physics.bands): the top of
#: its highest pass band and the edges of its first gap (a cell of two beads or more), Hz
BAND_ROWS = ("band_cutoff", "band_gap_lower", "band_gap_upper")

#: Every model: (contact law, what it needs: ContactLaw.model_domains, from the law registry).
MODEL_DOMAINS: dict[str, tuple[str, str]] = {
    n: (name, needs) for name, cls in LAWS.items() for n, needs in cls.model_domains.items()
}

#: Every damping part's two-body model: (damping part, its two-body setup: DampingPart.model_domains)
DAMPING_MODEL_DOMAINS: dict[str, tuple[str, str]] = {
    n: (name, needs) for name, cls in DAMPING.items() for n, needs in cls.model_domains.items()
}

#: Models whose value is a contact within the chain, so needs its length: on a chain of beads = "auto"
#: (the planner's) they give NaN and do not apply (applicability says why).
NEEDS_THE_LENGTH = frozenset({"transition_contact"})

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
    (granchain.physics.loading_regime.loading_regime). A far-end wall leaves every model in force for
    the incident wave, before the reflection reaches a contact. Given the measured `quantity` it is
    compared with, also whether the run measures what the model predicts (MEASURES_OTHER).
    """
    beyond_the_laws = _beyond_the_laws(name, scene)
    if beyond_the_laws is not None:
        return beyond_the_laws
    if name not in MODEL_DOMAINS:
        known = [*SCENE_QUANTITIES, *MODEL_DOMAINS, *DAMPING_MODEL_DOMAINS]
        raise ValueError(f"{name!r}: no such model; known: {', '.join(known)}")
    law, needs = MODEL_DOMAINS[name]
    if name in NEEDS_THE_LENGTH and scene.chain.beads is None:
        return Applicability(
            False,
            'a contact of the chain, within its length or not, and [chain] beads = "auto": the length is the '
            "planner's (granchain plan gives it; give [chain] beads = N to predict this for N beads)",
        )
    if needs in EFFECT_DOMAINS:
        return _effect_model_applies(law, needs, scene)
    why_not: list[str] = []
    if scene.contact.law != law:
        why_not.append(f"a {law} model; this chain's contact law is {scene.contact.law}")
    outside = _outside_the_papers_chain(scene)
    if needs == "collision":  # two beads by definition: not the paper's long chain, and need not be
        outside = [w for w in outside if not w.startswith(SHORT_CHAIN)]
    why_not += outside
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
    chain = f"uniform {LAWS[law].label or law} chain, no dashpot, no precompression"
    if needs == "any":
        return Applicability(True, f"{chain}, any loading time{wall}")
    return Applicability(True, f"{regime.text}; {chain}{wall}")


def _beyond_the_laws(name: str, scene) -> Applicability | None:
    """Applicability of what is not a contact law's model (the scene's own quantities, a damping part's
    two-body model, gravity's local speeds, the band structure), or None for a law's model."""
    if name in SCENE_QUANTITIES:
        return Applicability(True, "a quantity of the scene itself, not a model")
    if name in DAMPING_MODEL_DOMAINS:
        return _damping_model_applies(name, scene)
    if name in LOCAL_SPEEDS:
        return _local_speed_applies(scene, LOCAL_SPEEDS[name])
    if name in BAND_ROWS:
        return _band_applies(scene)
    return None


def _contact_model_applies(law: str, scene) -> Applicability:
    """Applicability of a closed form of the nominal bead pair's contact (a yield force): the scene's
    law, every contact the nominal one (uniform beads), and nothing else on it (no dashpot's force, no
    static load from the start); the chain's length and loading aside."""
    why_not = []
    if scene.contact.law != law:
        why_not.append(f"a {law} model; this chain's contact law is {scene.contact.law}")
    if scene.per_bead:
        why_not.append("the beads differ: a closed form of the nominal bead pair (bead 1's radius and material)")
    if scene.damping.velocity_dependent:
        why_not.append(scene.damping.words(scene.damping_coefficient))
    if scene.effects.precompression:
        why_not.append(f"static precompression F0 = {scene.effects.precompression:g} N")
    why_not += _under_gravity(scene)
    if why_not:
        return Applicability(False, "; ".join(why_not))
    return Applicability(True, "the nominal bead pair's contact")


def _effect_model_applies(law: str, needs: str, scene) -> Applicability:
    """Applicability of the effects' models (EFFECT_DOMAINS), which hold where the paper's do not."""
    if needs == "contact":  # the nominal pair's own closed form: nothing of the chain's dynamics
        return _contact_model_applies(law, scene)
    why_not = []
    if scene.contact.law != law:
        why_not.append(f"a {law} model; this chain's contact law is {scene.contact.law}")
    if scene.damping.velocity_dependent:
        why_not.append(scene.damping.words(scene.damping_coefficient))
    why_not += _under_gravity(scene)
    if needs in ("precompressed", "weakly_nonlinear"):
        inside = _precompressed_chain(law, needs, scene, why_not)
        if inside and not why_not:
            return Applicability(True, inside)
    else:
        if scene.effects.precompression:
            why_not.append(f"static precompression F0 = {scene.effects.precompression:g} N")
        why_not += _two_body_setup(needs, scene)
    if why_not:
        return Applicability(False, "; ".join(why_not))
    return Applicability(True, "the scene is inside the model's domain")


def _damping_model_applies(name: str, scene) -> Applicability:
    """Applicability of a damping part's two-body model (DAMPING_MODEL_DOMAINS): the scene has that part,
    the model's two-body setup and no precompression, and the impact is inside the model's own domain
    (DampingPart.model_domain, with its numbers: Kuwabara-Kono's small damping)."""
    part, needs = DAMPING_MODEL_DOMAINS[name]
    why_not = []
    if scene.damping.name != part:
        has = scene.damping.words(scene.damping_coefficient)
        why_not.append(f"a model of {DAMPING[part].description}; this scene has {has}")
    if scene.effects.precompression:
        why_not.append(f"static precompression F0 = {scene.effects.precompression:g} N")
    why_not += _two_body_setup(needs, scene)
    if why_not:
        return Applicability(False, "; ".join(why_not))
    impact = two_bodies(scene)
    applies, reason = scene.damping.model_domain(name, scene.damping_coefficient, impact, scene.loading.velocity)
    return Applicability(applies, reason or "the scene is inside the model's domain")


#: what each two-body impact needs of the scene: (beads, loading kind, a far-end wall), and in words
TWO_BODY_SETUPS = {
    "pair_impact": (2, "velocity", False, "two beads, bead 1 given a velocity, the far end free"),
    "striker_impact": (1, "striker", False, "a striker on one free bead"),
    "wall_impact": (1, "velocity", True, "one bead given a velocity against the wall"),
}


def _two_body_setup(needs: str, scene) -> list[str]:
    """What of a two-body impact's setup (TWO_BODY_SETUPS) the scene lacks, each with what it has."""
    beads, kind, wall, words = TWO_BODY_SETUPS[needs]
    ld, has_wall = scene.loading, scene.effects.far_end == "wall"
    lacks = []
    if scene.chain.beads != beads:
        push = " (its neighbours push back)" if beads == 1 else ""
        lacks.append(f"{scene.chain.beads} beads, not {beads}{push}")
    if ld.kind != kind:
        lacks.append(f"a {ld.kind} load, not a {kind}")
    if has_wall != wall:
        lacks.append("a far-end wall, not a free far end" if has_wall else "a free far end, not the wall")
    return [f"{'; '.join(lacks)}: the model is a two-body impact of {words}"] if lacks else []


def _precompressed_chain(law: str, needs: str, scene, why_not: list[str]) -> str:
    """Add to `why_not` why the scene is not a uniform precompressed chain (needs "precompressed") or
    does not carry a wave small against F0 (needs "weakly_nonlinear", c0's domain); return why it
    does where that has numbers to say (else "")."""
    if not scene.effects.precompression:
        why_not.append("no static precompression")
    if scene.per_bead:
        why_not.append("the beads differ: c0 is for a uniform chain")
    if needs != "weakly_nonlinear" or not scene.effects.precompression or scene.contact.law != law:
        return ""
    small, text = _small_against_static_force(scene)
    if not small:
        why_not.append(text)
    return text if small else ""


def _small_against_static_force(scene) -> tuple[bool, str]:
    """Whether the wave a precompressed chain is expected to carry is small against F0, the sound
    speed c0's domain, and why with the numbers.

    The dynamic force expected is the planner's largest (physics.estimates.expected_peak_force, from
    the paper's models of the uncompressed chain): at f_r = 1 + F / F0 a wave moves at Nesterenko's
    V_s(f_r), within SOUND_SPEED_RTOL of c0 only below F / F0 = models.weakly_nonlinear_ratio (0.0181).
    """
    from granchain.physics.estimates import expected_peak_force

    f0 = float(scene.effects.precompression)
    force = expected_peak_force(scene)
    limit = models.weakly_nonlinear_ratio()
    ratio = force / f0
    above = models.precompressed_solitary_wave_speed(1.0, 1.0 + ratio)
    numbers = f"the expected dynamic force {force:.3g} N is {ratio:.3g} F0 (F0 = {f0:g} N)"
    speed = f"Nesterenko's V_s(f_r = 1 + F/F0) = {above:.4f} c0"
    rule = f"within {models.SOUND_SPEED_RTOL:g} of c0 below F = {limit:.3g} F0"
    if ratio <= limit:
        return True, f"{numbers}: a weakly nonlinear wave, at {speed} ({rule})"
    return False, (
        f"{numbers}, not small against F0: a wave there moves at {speed}, {rule} only (c0 is the speed of "
        "a perturbation small against F0; V_s(f_r) at the measured leading peak is this chain's)"
    )


#: The paper's models are for a long chain: the solitary wave forms over the first few beads and is
#: measured over the middle half of the chain; below this many beads they do not apply (a two-bead
#: chain is a two-body impact: Eq. 8 gives 159.6 N where the exact impact gives 187.8 N)
MIN_CHAIN_BEADS = 10
#: how the reason a chain is shorter than that begins (a two-body model drops it)
SHORT_CHAIN = "a chain of "


def _outside_the_papers_chain(scene) -> list[str]:
    """Why the scene is not the paper's chain (uniform beads, no dashpot or precompression, the
    paper's loading), one reason each; empty when it is."""
    why_not: list[str] = []
    if scene.chain.beads is not None and scene.chain.beads < MIN_CHAIN_BEADS:
        why_not.append(
            f"{SHORT_CHAIN}{scene.chain.beads} bead{'s' if scene.chain.beads > 1 else ''}: the paper's models are "
            f"for a long chain, where the wave forms over the first beads (at least {MIN_CHAIN_BEADS})"
        )
    if scene.per_bead:
        r = scene.chain.radii or (scene.chain.radius,)
        differ = [f"radii {min(r) * 1e3:.3g} to {max(r) * 1e3:.3g} mm: tapered or decorated"] if len(set(r)) > 1 else []
        if scene.chain.materials is not None and len(set(scene.chain.materials)) > 1:
            labels = dict.fromkeys(mat.material_label(e) for e in scene.chain.materials)
            differ.append(f"materials {', '.join(sorted(labels))}")
        why_not.append(f"the beads differ ({'; '.join(differ)}): the paper's models are for a monodisperse chain")
    if scene.damping.velocity_dependent:
        why_not.append(
            f"{scene.damping.words(scene.damping_coefficient)}: the paper's models have no viscous dissipation"
        )
    if scene.effects.precompression:
        why_not.append(
            f"static precompression F0 = {scene.effects.precompression:g} N: the paper's models are for an "
            "uncompressed chain (a precompressed chain carries other waves, ref. 9)"
        )
    if scene.loading.is_harmonic:
        why_not.append(
            "a harmonic drive: the paper's models are for a step f(t) = A on 0 < t <= T (Eq. 4), a kick or a "
            "striker, not a driven chain's steady wave train"
        )
    why_not += _under_gravity(scene)
    ld = scene.loading
    if ld.kind == "striker":
        ratio = scene.striker_mass / scene.mass
        # equal masses exchange velocities only in an elastic impact: a law with history dissipates
        dissipates = scene.contact.law_class.history
        if dissipates or abs(ratio - 1.0) > EQUAL_STRIKER_MASS:
            why_not.append(
                f"a striker (M = {ratio:.3g} m at {ld.velocity:g} m/s) is not the paper's loading (a force "
                "f(t), Eq. 4, or bead 1's velocity): a lighter one rebounds, a heavier one pushes on"
                + (f", and its {scene.contact.law} contact dissipates" if dissipates else "")
            )
    return why_not


def _under_gravity(scene) -> list[str]:
    """Why a model of a chain of one static force (none, or F0 on every contact) is outside its domain
    on a vertical chain: each contact carries the weight above it."""
    if not scene.effects.gravity:
        return []
    forces = scene_static_forces(scene)
    return [
        f"gravity g = {scene.effects.gravity:g} m/s^2: each contact carries its own static force, the weight "
        f"above it{' plus F0' if scene.effects.precompression else ''} ({forces[0]:.3g} N at contact 1 to "
        f"{forces[-1]:.3g} N on the wall); the model is for one static force on every contact"
    ]


def local_sound_speeds(scene):
    """c0(i) = a_i sqrt(k_lin(i) / m_i) of each bead-bead contact of a vertical chain: k_lin(i) the
    slope of its law's virgin curve at its static force F_i (Hertz n K^(1/n) F^((n-1)/n), n = 3/2),
    a_i the centres' distance there, m_i the mean of its two beads' masses (Nesterenko 2001, Sec. 1.1,
    contact by contact: the long-wave speed of the chain linearised about each contact's load)."""
    import numpy as np

    forces = scene_static_forces(scene)[:-1]
    law = scene.law.per_contact(scene.n_contacts) if scene.n_contacts else scene.law
    k_lin = np.asarray(law.loading_stiffness(forces), dtype=float)
    r = np.asarray(scene.bead_radii, dtype=float)
    m = np.asarray(scene.bead_masses if scene.per_bead else np.full(r.size, scene.mass), dtype=float)
    spacing = r[:-1] + r[1:] - np.asarray(law.static_overlap(forces), dtype=float)
    return spacing * np.sqrt(k_lin / (0.5 * (m[:-1] + m[1:])))


def _local_speed_applies(scene, contact: int) -> Applicability:
    """c0(i) holds for a perturbation small against the contact's static force (weakly_nonlinear_ratio
    of it, as c0 under precompression): the expected dynamic force against it, with the numbers."""
    from granchain.physics.estimates import expected_peak_force

    if not scene.effects.gravity or not scene.n_contacts:
        return Applicability(False, "no gravity: a chain of one static force (precompressed_sound_speed)")
    f_static = float(scene_static_forces(scene)[:-1][contact])
    force = expected_peak_force(scene)
    ratio, limit = force / f_static, models.weakly_nonlinear_ratio()
    numbers = (
        f"the expected dynamic force {force:.3g} N is {ratio:.3g} times the contact's static force {f_static:.3g} N"
    )
    if ratio <= limit:
        return Applicability(
            True, f"{numbers}: a weakly nonlinear wave (c0 within {models.SOUND_SPEED_RTOL:g} below {limit:.3g})"
        )
    return Applicability(
        False,
        f"outside the model's domain: {numbers}, not small against it (c0(i) is the speed of a perturbation "
        f"small against the contact's static force, within {models.SOUND_SPEED_RTOL:g} below {limit:.3g} of it)",
    )


def _gravity_predictions(scene) -> list[Prediction]:
    """A vertical chain's local sound speed at its top and bottom contacts (local_sound_speeds)."""
    if not scene.effects.gravity or not scene.n_contacts:
        return []
    c0 = local_sound_speeds(scene)
    equation = "c0(i) = a_i sqrt(k_lin(F_i)/m), k_lin = n K^(1/n) F_i^((n-1)/n), F_i = F0 + g sum_(j<=i) m_j"
    valid = "a perturbation small against the contact's static force (the weight above it, plus F0)"
    return [Prediction(name, float(c0[i]), "m/s", equation, valid) for name, i in LOCAL_SPEEDS.items()]


def _band_applies(scene) -> Applicability:
    """The band structure holds for an undamped precompressed periodic chain carrying a motion small
    against F0 (granchain.physics.bands.DOMAIN), checked as c0's: the expected dynamic force against F0."""
    try:
        band_structure.linearised_cell(scene)
    except band_structure.BandError as exc:
        return Applicability(False, str(exc))
    why_not = []
    if scene.damping.velocity_dependent:
        why_not.append(f"{scene.damping.words(scene.damping_coefficient)}: the bands are the undamped chain's")
    small, text = _small_against_static_force(scene)
    if not small:
        why_not.append(text)
    if why_not:
        return Applicability(False, "; ".join(why_not))
    return Applicability(True, f"{text}; {band_structure.DOMAIN}")


def _band_predictions(scene) -> list[Prediction]:
    """A precompressed periodic chain's band edges (granchain.physics.bands): its cutoff, and its first
    gap where the cell has one; none where the chain has no band structure."""
    if not scene.effects.precompression or scene.effects.gravity:
        return []
    try:
        bands = band_structure.band_structure(scene)
    except band_structure.BandError:
        return []
    equation = "Bloch eigenproblem K(q) U = w^2 M U of the cell, k_j = dF/dalpha at F0 (physics/bands.py)"
    p = bands.cell.masses.size
    top = {1: "; monoatomic: (1/pi) sqrt(k/m)", 2: "; dimer: sqrt(2k (1/m1 + 1/m2)) / (2 pi)"}.get(p, "")
    out = [Prediction("band_cutoff", bands.cutoff, "Hz", equation + top, bands.domain)]
    if len(bands.gaps) > 1:
        lower, upper = bands.gaps[0]
        words = f"{equation}; dimer: sqrt(2k/m_heavy) / (2 pi)" if p == 2 else equation
        out.append(Prediction("band_gap_lower", lower, "Hz", words, bands.domain))
        words = f"{equation}; dimer: sqrt(2k/m_light) / (2 pi)" if p == 2 else equation
        out.append(Prediction("band_gap_upper", upper, "Hz", words, bands.domain))
    return out


def predict(scene) -> list[Prediction]:
    """Predictions for this scene (SI), nondimensional forms where the paper gives them, each with
    whether it applies to the scene (applies, applies_reason: see applicability)."""
    out = []
    for p in _predict(scene):
        verdict = applicability(p.name, scene)
        out.append(replace(p, applies=verdict.applies, applies_reason=verdict.reason))
    return out


def _predict(scene) -> list[Prediction]:
    """The scene's own quantities (Eqs. 4, 7), then the models of its contact law (ContactLaw.predictions)
    and of its damping part's two-body impact (DampingPart.predictions)."""
    ld = scene.loading
    impulse = scene.input_impulse
    out: list[Prediction] = [
        Prediction("tau", scene.tau, "s", "Eq. 7", "intrinsic time scale of the bead pair"),
        Prediction(
            "impulse",
            impulse,
            "N s",
            "Eq. 4 (I = A T; velocity load: I = m v0)",
            "always",
            nondim=impulse / scene.impulse_scale,
        ),
    ]
    if ld.is_step:
        out.append(Prediction("loading_time_over_tau", ld.duration / scene.tau, "1", "T / tau (Eq. 7)", "always"))
        out.append(
            Prediction("amplitude", ld.amplitude, "N", "Eq. 4", "always", nondim=ld.amplitude / scene.force_scale)
        )
    out += [Prediction(**fields) for fields in scene.contact.law_class.predictions(scene)]
    out += _gravity_predictions(scene)
    out += _band_predictions(scene)
    impact = two_bodies(scene)
    if impact is None:
        return out
    damping = scene.damping.predictions(scene.damping_coefficient, impact, scene.loading.velocity)
    return out + [Prediction(**fields) for fields in damping]
