"""The damping parts' declared two-body models (DampingPart.model_domains): Kuwabara-Kono's restitution
(Ramirez et al. 1999's series), shown by `granchain predict` on a two-body scene with its domain, against
two-body runs on both backends at small damping, and marked outside its domain at large A."""

import pytest

from granchain.physics.damping import DAMPING
from granchain.physics.damping.kuwabara_kono import RAMIREZ_C1, restitution_parameter
from granchain.physics.laws.base import two_bodies
from granchain.physics.models import hertz_impact
from granchain.physics.predictions import DAMPING_MODEL_DOMAINS, MODEL_DOMAINS, applicability, predict
from granchain.scene import parse_scene
from granchain.workflows.run import run_reference

from .conftest import make_scene_text

KK = DAMPING["kuwabara_kono"]


def striker_scene(damping: float, velocity: float = 1.0, steps_per_contact: int = 1500):
    """An equal striker on one free brass bead at `velocity`, Kuwabara-Kono damping A = `damping`, run
    to 1.5 contact times (the impact is over by then: the clipped contact ends before the elastic one)."""
    text = make_scene_text(beads=1, loading=f'kind = "striker"\nvelocity = {velocity!r}')
    probe = parse_scene(text, source="kk.toml")
    impact = two_bodies(probe)
    contact = hertz_impact(float(impact.law.k), impact.reduced_mass, velocity)
    run = f"end_time = {1.5 * contact['duration']!r}\ntimestep = {contact['duration'] / steps_per_contact!r}"
    text = text.replace("end_time = 0.0002\ntimestep = 1e-08", run)
    return parse_scene(text + f"[damping]\nkuwabara_kono = {damping!r}\n", source="kk.toml")


def restitution_prediction(sc):
    (p,) = [p for p in predict(sc) if p.name in DAMPING_MODEL_DOMAINS]
    return p


def run_restitution(sc, backend: str) -> float:
    """(v_bead - v_striker) / v0 after the impact."""
    if backend == "lammps":
        from granchain.lammps.runner import run_lammps

        sol = run_lammps(sc)[0].solution
    else:
        sol = run_reference(sc, "verlet").solution
    return (float(sol.velocity[0]) - float(sol.striker_velocity)) / sc.loading.velocity


def test_every_damping_model_is_declared_once_and_apart_from_the_laws():
    """A damping part's model names its part's setup (an EFFECT_DOMAINS two-body key) and shares no
    name with a law's model or another part's."""
    names = [n for cls in DAMPING.values() for n in cls.model_domains]
    assert len(names) == len(set(names))
    assert not set(names) & set(MODEL_DOMAINS)
    for name, (part, needs) in DAMPING_MODEL_DOMAINS.items():
        assert name in DAMPING[part].model_domains
        assert needs in ("striker_impact", "wall_impact", "pair_impact")
    assert {needs for _, needs in DAMPING_MODEL_DOMAINS.values()} >= {"striker_impact"}


@pytest.mark.parametrize("backend", ["reference", "lammps"])
@pytest.mark.parametrize("first_order", [0.01, 0.05])
def test_kuwabara_kono_restitution_predicted_against_a_two_body_run(backend, first_order):
    """`predict`'s restitution of the striker on bead 1 against the run's, within the size of the terms
    beyond the series (the unclipped force's delta^3 and the no-pull clip's change, which raises e):
    0.05 delta^2, a sixteenth of its last term C2 delta^2. Measured (reference Verlet, converged: 1500,
    3000 and 6000 steps a contact within 1.6e-7): e - series = 1.5e-6 = 0.020 delta^2 at C1 delta =
    0.01, 5.5e-5 = 0.029 delta^2 at 0.05, LAMMPS alike."""
    impact = two_bodies(striker_scene(1e-9))
    damping = first_order / RAMIREZ_C1 / restitution_parameter(1.0, float(impact.law.k), impact.reduced_mass, 1.0)
    sc = striker_scene(damping)
    p = restitution_prediction(sc)
    assert p.applies, p.applies_reason
    assert "small damping" in p.applies_reason
    delta = first_order / RAMIREZ_C1
    e = run_restitution(sc, backend)
    print(f"{backend}: C1 delta = {first_order}: run e = {e:.8f}, predicted {p.value:.8f}, diff {e - p.value:.3g}")
    assert e == pytest.approx(p.value, abs=0.05 * delta**2)


def test_kuwabara_kono_restitution_outside_its_domain_at_large_damping():
    """At C1 delta > 0.1 the prediction is shown but marked outside the model's domain, with why."""
    p = restitution_prediction(striker_scene(2e-5))
    assert not p.applies
    assert "outside the model's domain" in p.applies_reason
    assert "C1 delta" in p.applies_reason


def test_kuwabara_kono_restitution_needs_its_part_and_setup():
    """The model does not apply to a scene with another damping part or more than two bodies, and says
    why; a chain gets no value of it at all."""
    (name,) = [p.name for p in predict(striker_scene(2e-7)) if p.name in DAMPING_MODEL_DOMAINS]
    for beads, damping, says in ((1, "dashpot = 3.0", "Kuwabara-Kono"), (5, "kuwabara_kono = 2e-7", "two-body impact")):
        text = make_scene_text(beads=beads, loading='kind = "striker"\nvelocity = 1.0')
        other = parse_scene(text + f"[damping]\n{damping}\n", source="other.toml")
        verdict = applicability(name, other)
        assert not verdict.applies
        assert says in verdict.reason
    assert not [p for p in predict(other) if p.name in DAMPING_MODEL_DOMAINS]
