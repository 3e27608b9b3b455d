"""The reference RK4's lean step gives the plain step's numbers, bit for bit.

RK4Integrator.lean_step (event location, no dashpot) steps between two pairs of (u, v) buffers
instead of saving and restoring the state, hands the first stage the state's overlaps (alpha_now)
and screens the turning contacts once for the event location and end_piece; end_piece, the peak
tracking and the leading pulse treat a handful of turning contacts on Python floats. Switched off
(integrators._LEAN = False and every _SCALAR_CONTACTS = -1) the solver runs the plain step and the
numpy paths, as before these changes: every array of the solution must be the same bits.
"""

from contextlib import contextmanager

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.problem import ChainProblem
from granchain.reference import integrators, observers, solver
from granchain.reference.state import ChainState
from granchain.scene import load_scene, parse_scene
from tests.scenegen import scene_texts


@contextmanager
def plain():
    """The plain step and the numpy paths (the solver before the lean step)."""
    saved = integrators._LEAN, integrators._SCALAR_CONTACTS, observers._SCALAR_CONTACTS
    integrators._LEAN, integrators._SCALAR_CONTACTS, observers._SCALAR_CONTACTS = False, -1, -1
    try:
        yield
    finally:
        integrators._LEAN, integrators._SCALAR_CONTACTS, observers._SCALAR_CONTACTS = saved


def solve(scene, end_time: float, timestep: float):
    n = scene.chain.beads
    return solver.solve_chain(
        ChainProblem.from_scene(scene),
        end_time,
        timestep,
        "rk4",
        histories=(0, n // 2, n - 2),
        history_stride=3,
        snapshots=(round(end_time / timestep / 2) * timestep,),
        energy_samples=50,
        progress=None,
    )


def assert_same_bits(lean, plain_sol):
    assert lean.steps == plain_sol.steps and lean.extra_steps == plain_sol.extra_steps
    fields = {k: v for k, v in vars(plain_sol).items() if isinstance(v, np.ndarray)}
    assert len(fields) > 15
    for name, value in fields.items():
        got = getattr(lean, name)
        assert got.dtype == value.dtype and got.shape == value.shape, name
        assert got.tobytes() == value.tobytes(), name  # (the bits: signed zeros and nans too)


def both(scene, end_time: float, timestep: float):
    lean = solve(scene, end_time, timestep)
    with plain():
        plain_sol = solve(scene, end_time, timestep)
    return lean, plain_sol


@settings(max_examples=12, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(text=scene_texts(max_beads=40, auto=False), steps=st.integers(300, 1500))
def test_lean_step_gives_the_plain_steps_bits(text, steps):
    """Random scenes (every law, loading and effect; a dashpot runs the plain step either way)."""
    scene = parse_scene(text, source="generated.toml")
    lean, plain_sol = both(scene, steps * 1e-8, 1e-8)
    assert_same_bits(lean, plain_sol)


@pytest.mark.parametrize(
    ("name", "end_time", "timestep", "min_extra"),
    [
        ("plastic-short-impulse", 2e-4, 1e-8, 50),
        ("thornton-short-impulse", 2.5e-4, 2.5e-7, 20),
        ("effect-wall", 1e-4, 5e-8, 0),
    ],
)
def test_lean_step_on_bundled_scenes_with_many_splits(name, end_time, timestep, min_extra):
    """Bundled scenes whose steps event location splits often (bilinear, Thornton) and a Hertz
    chain against a wall: the same bits, and the splits did happen."""
    lean, plain_sol = both(load_scene(name), end_time, timestep)
    assert lean.extra_steps >= min_extra
    assert_same_bits(lean, plain_sol)


def test_lean_step_is_on_where_it_applies():
    """The lean step runs with event location and no dashpot; a dashpot keeps the plain step."""
    scene = load_scene("plastic-short-impulse")
    state = ChainState(ChainProblem.from_scene(scene))
    assert integrators.RK4Integrator(state, 1e-8, True, 100).lean
    assert not integrators.RK4Integrator(state, 1e-8, False, 100).lean
    damped = load_scene("effect-dashpot")
    assert not integrators.RK4Integrator(ChainState(ChainProblem.from_scene(damped)), 1e-8, True, 100).lean
