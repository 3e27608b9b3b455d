"""The reference RK4's lean step gives the plain step's numbers, bit for bit.

RK4Integrator.lean_step (event location, no dashpot) steps between two pairs of (u, v) buffers
instead of saving and restoring the state, hands the first stage the state's overlaps (alpha_now)
and screens the turning contacts once for the event location and end_piece; end_piece, the peak
tracking and the leading pulse treat a handful of turning contacts on Python floats. Switched off
(rk4._LEAN = False and every _SCALAR_CONTACTS = -1) the solver runs the plain step and the
numpy paths, as before these changes: every array of the solution must be the same bits.
"""

from contextlib import contextmanager

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.problem import ChainProblem
from granchain.reference import events, integrators, observers, rk4, solver
from granchain.reference.state import ChainState
from granchain.scene import load_scene, parse_scene
from tests.scenegen import scene_texts


@contextmanager
def plain():
    """The plain step and the numpy paths (the solver before the lean step)."""
    saved = rk4._LEAN, events._SCALAR_CONTACTS, observers._SCALAR_CONTACTS
    rk4._LEAN, events._SCALAR_CONTACTS, observers._SCALAR_CONTACTS = False, -1, -1
    try:
        yield
    finally:
        rk4._LEAN, events._SCALAR_CONTACTS, observers._SCALAR_CONTACTS = saved


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
    assert lean.steps == plain_sol.steps
    assert lean.extra_steps == plain_sol.extra_steps
    fields = {k: v for k, v in vars(plain_sol).items() if isinstance(v, np.ndarray)}
    assert len(fields) > 15
    for name, value in fields.items():
        got = getattr(lean, name)
        assert got.dtype == value.dtype, name
        assert got.shape == value.shape, name
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


def test_stages_by_calls_give_the_written_out_stages_bits(monkeypatch):
    """rk4 writes the force evaluations of stages 2-4 out (make_accel's parts); a force evaluation
    without parts takes them by calls: the same bits."""
    scene = load_scene("plastic-short-impulse")
    written = solve(scene, 1e-4, 1e-8)
    init = integrators.RK4Integrator.__init__

    def without_parts(self, *args, **kw):
        init(self, *args, **kw)
        self.parts = None

    monkeypatch.setattr(integrators.RK4Integrator, "__init__", without_parts)
    assert_same_bits(written, solve(scene, 1e-4, 1e-8))


@pytest.mark.parametrize("law_name", ["bilinear", "thornton", "hertz"])
def test_a_laws_kink_screens_are_the_generic_ones(law_name):
    """A law's own kink_screens (bilinear's) give the generic screens over kinks(): the same kinks,
    levels, where and contacts, bit for bit; on overlaps near every kink level, with zero histories."""
    from granchain.physics.laws.base import ContactLaw

    law = load_scene(
        {"bilinear": "plastic-short-impulse", "thornton": "thornton-short-impulse"}.get(law_name, "default")
    ).law
    rng = np.random.default_rng(7)
    n, straddled = 60, 0
    for _ in range(200):
        hist = rng.uniform(0.0, 2e-6, n - 1) * (rng.uniform(size=n - 1) < 0.7)
        levels = [np.broadcast_to(k.level, hist.shape) for k in law.kinks(hist)]
        a0 = levels[rng.integers(len(levels))] + rng.normal(0.0, 1e-8, n - 1)
        a1 = levels[rng.integers(len(levels))] + rng.normal(0.0, 1e-8, n - 1)
        own, generic = law.kink_screens(hist, a0, a1), ContactLaw.kink_screens(law, hist, a0, a1)
        assert len(own) == len(generic)
        for (k1, l1, i1), (k2, l2, i2) in zip(own, generic, strict=True):
            assert (k1.kind, k1.from_below) == (k2.kind, k2.from_below)
            assert np.asarray(k1.level).tobytes() == np.asarray(k2.level).tobytes()
            assert l1.tobytes() == l2.tobytes()
            assert np.array_equal(i1, i2)
            assert (k1.where is None) == (k2.where is None)
            if k1.where is not None:
                assert np.array_equal(k1.where, k2.where)
            straddled += 1
    assert straddled > 100
