"""The leading pulse's decay along the window (issue 42 item 4): an exponential and a power-law fit.

On synthetic leading pulses that are an exact exponential or power law (above each contact's static
force, on a plain and a precompressed scene) the fits recover the constants with a standard error of
round-off; where the pulses do not decay, or fewer than three contacts have one, the constants are None
with the reason; on a dashpot and a tapered chain the decay is positive; the error bar is the time
step's and the fit's standard error in quadrature.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from granchain.postprocess.observables import OBSERVABLES
from granchain.problem import scene_static_forces
from granchain.scene import bundled_scenes, parse_scene
from granchain.workflows.run import run_scene
from tests.scenegen import PEAKS, brass_text

LENGTH, EXPONENT = "leading_pulse_decay_length", "leading_pulse_decay_exponent"

#: a plain 30-bead chain and a precompressed one (the fits read the force above F0)
SCENES = {
    "plain": parse_scene(brass_text(30, 'kind = "velocity"\nvelocity = 0.5\n', PEAKS)),
    "precompressed": parse_scene(
        brass_text(30, 'kind = "velocity"\nvelocity = 0.5\n', PEAKS + "[precompression]\nforce = 20.0\n")
    ),
}


#: the least synthetic pulse (N) drawn: on F0 = 20 N a total force is rounded at 4e-15 N, and a pulse
#: of 1e-13 N above it is read to a few percent (a real run's leading pulse floor is far above that)
RESOLVED = 1e-3


def _solution(scene, dynamic: np.ndarray) -> SimpleNamespace:
    """A solution whose window's leading pulses rise `dynamic` (N, per window contact) above each
    contact's static force; nan (no leading pulse) elsewhere."""
    a, b = scene.window
    lead = np.full(scene.n_contacts, np.nan)
    lead[a - 1 : b] = scene_static_forces(scene)[a - 1 : b] + dynamic
    return SimpleNamespace(leading_pulse_force=lead)


def _window(scene) -> np.ndarray:
    a, b = scene.window
    return np.arange(a, b + 1, dtype=float)


def _measure(name, scene, sol):
    return OBSERVABLES[name].measure(scene, sol)


#: each fit: its law F(i; A, c), the range its constant c is drawn from, its amplitude's and standard error's names
FITS = {
    LENGTH: (lambda i, a, c: a * np.exp(-i / c), (0.5, 200.0), "leading_pulse_decay_amplitude", "_length_stderr"),
    EXPONENT: (lambda i, a, c: a * i**-c, (0.05, 3.0), "leading_pulse_power_amplitude", "_exponent_stderr"),
}


@settings(max_examples=40)
@given(
    kind=st.sampled_from(sorted(SCENES)),
    name=st.sampled_from(sorted(FITS)),
    amplitude=st.floats(1.0, 1e4),
    where=st.floats(0.0, 1.0),
)
def test_an_exact_exponential_or_power_law_is_recovered(kind, name, amplitude, where):
    scene = SCENES[kind]
    law, (lo, hi), amplitude_name, stderr = FITS[name]
    constant = lo + where * (hi - lo)
    i = _window(scene)
    dynamic = law(i, amplitude, constant)
    assume(dynamic.min() >= RESOLVED)
    m = _measure(name, scene, _solution(scene, dynamic))
    assert m.value == pytest.approx(constant, rel=1e-9)
    assert m.fields[amplitude_name] == pytest.approx(amplitude, rel=1e-8)
    assert m.fields[f"leading_pulse_decay{stderr}"] <= 1e-9 * constant
    if name == LENGTH:
        assert m.fields["leading_pulse_decay_contacts"] == i.size


@settings(max_examples=25)
@given(
    kind=st.sampled_from(sorted(SCENES)),
    amplitude=st.floats(1.0, 1e4),
    # a constant pulse with round-off's scatter, or one that grows along the window
    growth=st.one_of(st.just(0.0), st.floats(1e-3, 0.5)),
    seed=st.integers(0, 2**16),
)
def test_a_pulse_that_does_not_decay_has_no_constant_but_a_reason(kind, amplitude, growth, seed):
    scene = SCENES[kind]
    i = _window(scene)
    scatter = 1.0 + 1e-9 * np.random.default_rng(seed).standard_normal(i.size)
    sol = _solution(scene, amplitude * np.exp(growth * (i - i[0])) * scatter)
    for name in (LENGTH, EXPONENT):
        m = _measure(name, scene, sol)
        assert m.value is None, name
        assert "no decay:" in m.reason
        assert set(m.fields.values()) <= {None, i.size}


def test_fewer_than_three_leading_pulses_say_run_longer():
    scene = SCENES["plain"]
    dynamic = np.full(_window(scene).size, np.nan)
    dynamic[:2] = [100.0, 50.0]
    for name in (LENGTH, EXPONENT):
        m = _measure(name, scene, _solution(scene, dynamic))
        assert m.value is None
        assert "2 of the window's contacts" in m.reason
        assert "run longer" in m.reason


def test_a_window_of_two_contacts_never_applies():
    scene = parse_scene(brass_text(3, 'kind = "velocity"\nvelocity = 0.5\n', PEAKS))
    for name in (LENGTH, EXPONENT):
        assert "decay fit needs 3" in OBSERVABLES[name].applies(scene)


@pytest.mark.parametrize("name", ["effect-dashpot", "effect-tapered"])
def test_a_dissipative_or_tapered_chain_decays(name):
    """A dashpot takes energy from the pulse, a taper of shrinking beads its force: both decay."""
    result = run_scene(parse_scene(bundled_scenes()[name], source=name), backend="reference", method="verlet")
    obs = result.observables()
    assert obs[LENGTH] > 0
    assert obs[EXPONENT] > 0
    assert obs["leading_pulse_decay_length_stderr"] < obs[LENGTH]
    assert obs["leading_pulse_decay_exponent_stderr"] < obs[EXPONENT]


def test_a_uniform_chain_says_its_pulse_does_not_decay():
    result = run_scene(parse_scene(bundled_scenes()["default"], source="default"), backend="reference")
    assert result.observables()[LENGTH] is None
    assert "no decay:" in result.observables_missing()[LENGTH]


def test_the_error_bar_is_the_step_and_the_fit_in_quadrature():
    scene = parse_scene(bundled_scenes()["effect-dashpot"], source="effect-dashpot")
    result = run_scene(scene, backend="reference", method="verlet", error_estimate=True)
    obs = result.observables()
    stderrs = {LENGTH: "leading_pulse_decay_length_stderr", EXPONENT: "leading_pulse_decay_exponent_stderr"}
    for name, stderr in stderrs.items():
        bar = result.errors.observables[name]
        assert bar["value"] == obs[name]
        assert bar["fit_stderr"] == obs[stderr]
        assert bar["error"] == pytest.approx(np.hypot(bar["step_error"], bar["fit_stderr"]), rel=1e-12)
