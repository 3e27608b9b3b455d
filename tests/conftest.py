import os
import re
import textwrap

import pytest
from hypothesis import settings

from granchain.physics.laws import LAWS
from granchain.scene import parse_scene

# Hypothesis: every property test explores new draws on a developer's machine (and prints the blob
# that reproduces a failure); CI (.ci/run sets GRANCHAIN_HYPOTHESIS=ci) runs the same derandomized
# draws every time, so that a commit lands or not on its own merits, not on the luck of a draw
settings.register_profile("ci", derandomize=True, print_blob=True, deadline=None)  # (a loaded machine)
settings.register_profile("default", print_blob=True)
settings.load_profile(os.environ.get("GRANCHAIN_HYPOTHESIS", "default"))

ISSUE_SCENE = """
[chain]
beads = 200               # number of beads; bead 1 is the loaded end
radius = 4.76e-3          # m
material = "brass"

[contact]
law = "hertz"

[loading]
kind = "step"
amplitude = 40.0          # N
duration = 1e-2           # s

[run]
end_time = 5e-3           # s
timestep = 1e-8           # s

[outputs]
peak_force = true
histories = [1, 2, 3]
snapshots = [2e-3]
"""


def make_scene_text(
    *, beads=30, law="hertz", contact_extra=None, loading=None, end_time=2e-4, timestep=1e-8, outputs=""
) -> str:
    if contact_extra is None:
        contact_extra = law_example(law)
    if contact_extra is None:
        contact_extra = law_example(law)
    loading = loading or 'kind = "impulse"\nimpulse = 0.1\nduration = 1e-6'
    if "histories" in outputs and "history_interval" not in outputs:
        # these tests compare histories sample by sample: every step (the scene's default is "auto")
        outputs = re.sub(r"^(histories = .*)$", rf"\1\nhistory_interval = {timestep!r}", outputs, count=1, flags=re.M)
    return (
        textwrap.dedent(f"""
        [chain]
        beads = {beads}
        radius = 4.76e-3
        material = "brass"
        [contact]
        law = "{law}"
        """)
        + contact_extra
        + "\n[loading]\n"
        + loading
        + f"""
[run]
end_time = {end_time!r}
timestep = {timestep!r}
[outputs]
"""
        + outputs
        + "\n"
    )


def make_scene(**kw):
    return parse_scene(make_scene_text(**kw), source="test.toml")


def law_example(law: str) -> str:
    """The [contact] lines (besides law) of the registered law's example (brass, R = 4.76 mm)."""
    return "".join(f"{k} = {v!r}\n" for k, v in LAWS[law].example_contact.items())


#: every registered contact law (granchain.physics.laws.LAWS): tests that hold for any law run over it
LAW_NAMES = sorted(LAWS)

#: the loadings of the random-scene property tests, scaled by size (impulse, step amplitude, velocity)
RANDOM_LOADINGS = {
    "impulse": 'kind = "impulse"\nimpulse = {s!r}\nduration = 1e-6',
    "step": 'kind = "step"\namplitude = {a!r}\nduration = {step!r}',
    "velocity": 'kind = "velocity"\nvelocity = {v!r}',
}


def random_scene_text(
    *, law, beads, loading, size, wall, precompression, dashpot, end_time, step_duration, outputs
) -> str:
    """A scene of the random-scene property tests (tests/test_peak_tracking.py, tests/test_energy_fix.py):
    a brass chain with one of RANDOM_LOADINGS of the given size, dt = 2e-8 s, and a wall, precompression
    and a dashpot where asked."""
    load = RANDOM_LOADINGS[loading].format(s=0.05 * size, a=100.0 * size, v=4.0 * size, step=step_duration)
    text = make_scene_text(beads=beads, law=law, loading=load, end_time=end_time, timestep=2e-8, outputs=outputs)
    if wall:
        text += '\n[boundary]\nfar_end = "wall"\n'
    if precompression:
        text += f"\n[precompression]\nforce = {precompression!r}\n"
    if dashpot:
        text += f"\n[damping]\ndashpot = {dashpot!r}\n"
    return text


#: the laws with history (alpha_max)
PLASTIC_LAWS = [n for n in LAW_NAMES if LAWS[n].history]

BILINEAR = law_example("bilinear")


@pytest.fixture
def issue_scene_text():
    return ISSUE_SCENE


#: the small scene of the campaign tests (a 20-bead brass chain under a short step)
CAMPAIGN_SCENE = """
[chain]
beads = 20
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "step"
amplitude = 10.0
duration = 1e-6
[run]
end_time = 1e-4
timestep = 5e-8
[outputs]
peak_force = true
histories = [5]
"""
