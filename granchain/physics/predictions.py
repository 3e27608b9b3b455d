"""Every analytic prediction of the paper for a scene, with its domain of validity and whether the
scene is inside it (:func:`applicability`, the one place that rule lives: `granchain predict`,
`compare` and the plots all ask it)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import NamedTuple

from granchain.physics import materials as mat
from granchain.physics import models
from granchain.physics.laws import LAWS
from granchain.physics.laws.base import EFFECT_DOMAINS
from granchain.physics.loading_regime import loading_regime
from granchain.physics.models import leading_peaks_exponential, transition_contact

__all__ = [
    "EFFECT_DOMAINS",
    "MODEL_DOMAINS",
    "SCENE_QUANTITIES",
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

#: Every model: (contact law, what it needs: ContactLaw.model_domains, from the law registry).
MODEL_DOMAINS: dict[str, tuple[str, str]] = {
    n: (name, needs) for name, cls in LAWS.items() for n, needs in cls.model_domains.items()
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
    if name in SCENE_QUANTITIES:
        return Applicability(True, "a quantity of the scene itself, not a model")
    if name not in MODEL_DOMAINS:
        raise ValueError(f"{name!r}: no such model; known: {', '.join([*SCENE_QUANTITIES, *MODEL_DOMAINS])}")
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


def _contact_model_applies(law: str, scene) -> Applicability:
    """Applicability of a closed form of the nominal bead pair's contact (a yield force): the scene's
    law, every contact the nominal one (uniform beads), and nothing else on it (no dashpot's force, no
    static load from the start); the chain's length and loading aside."""
    why_not = []
    if scene.contact.law != law:
        why_not.append(f"a {law} model; this chain's contact law is {scene.contact.law}")
    if scene.per_bead:
        why_not.append("the beads differ: a closed form of the nominal bead pair (bead 1's radius and material)")
    if scene.effects.dashpot:
        why_not.append(f"viscous dashpot (gamma = {scene.effects.dashpot:g} N s/m)")
    if scene.effects.precompression:
        why_not.append(f"static precompression F0 = {scene.effects.precompression:g} N")
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
    if scene.effects.dashpot:
        why_not.append(f"viscous dashpot (gamma = {scene.effects.dashpot:g} N s/m)")
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
        # equal masses exchange velocities only in an elastic impact: a law with history dissipates
        dissipates = scene.contact.law_class.history
        if dissipates or abs(ratio - 1.0) > EQUAL_STRIKER_MASS:
            why_not.append(
                f"a striker (M = {ratio:.3g} m at {ld.velocity:g} m/s) is not the paper's loading (a force "
                "f(t), Eq. 4, or bead 1's velocity): a lighter one rebounds, a heavier one pushes on"
                + (f", and its {scene.contact.law} contact dissipates" if dissipates else "")
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
    """The scene's own quantities (Eqs. 4, 7), then the models of its contact law (ContactLaw.predictions)."""
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
    if ld.is_force:
        out.append(Prediction("loading_time_over_tau", ld.duration / scene.tau, "-", "T / tau (Eq. 7)", "always"))
        out.append(
            Prediction("amplitude", ld.amplitude, "N", "Eq. 4", "always", nondim=ld.amplitude / scene.force_scale)
        )
    return out + [Prediction(**fields) for fields in scene.contact.law_class.predictions(scene)]
