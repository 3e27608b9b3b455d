"""RK4 event location (granchain.reference.solver, first_kink_crossing) always gets past a kink.

A bilinear chain precompressed to F0 starts with every contact at its kink alpha_max (the
precompression loaded it plastically): the overlap u_i - u_i+1 of the static displacements (a
cumulative sum) lies a few units of round-off of u below alpha_max = F0 / k. Once the wave's
leading tail reaches a contact (d alpha/dt ~ 1e-11 m/s), "reloading meets alpha_max" was found
1e-21 m ahead; the split step to it moved u by v h ~ 1e-21 m, below half a unit of round-off of
u ~ 2e-5 m, so u did not change and the same crossing was found again, 1e-10 s further on, about
2400 times per step and more at every step: the run never ended (scenes 34 and 85 of a generated
set). A crossing now counts only beyond the overlap's round-off, and a step split more often than
the solver's cap raises EventLocationError instead of looping.
"""

import signal
from contextlib import contextmanager
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from granchain.reference import solver
from granchain.scene import parse_scene
from granchain.workflows.run import run_scene
from tests.scenegen import scenes

RTOL = 1e-3
# scene 34 of a generated set (tests.scenegen) that hung, and scene 85, which hung the same way
KICKED = {
    "ptfe": """[chain]
beads = 24
radius = 0.005502895962431
material = "ptfe"

[contact]
law = "bilinear"
unloading_coeff = 0.8289440635198787
plastic_stiffness = 36784690.965194084

[loading]
kind = "velocity"
velocity = 1.2913702605498514

[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
histories = [1, 15]
[precompression]
force = 41.68653045782795""",
    "glass": """[chain]
beads = 35
radius = 0.0042038707774578465
material = "soda-lime-glass"

[contact]
law = "bilinear"
unloading_coeff = 0.4570449829306096
plastic_stiffness = 91743461.71754174

[loading]
kind = "velocity"
velocity = 0.8486616009963589

[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
histories = [1, 11, 32]
[precompression]
force = 35.668819020217825""",
}


@contextmanager
def time_limit(seconds: float):
    """Fail (TimeoutError) instead of hanging: the run is interrupted after `seconds`."""

    def fail(signum, frame):
        raise TimeoutError(f"the run did not end within {seconds} s")

    previous = signal.signal(signal.SIGALRM, fail)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def kicked(case: str):
    return parse_scene(KICKED[case], source=f"kicked-{case}.toml")


@pytest.mark.parametrize("case", list(KICKED))
def test_precompressed_bilinear_kick_ends_and_agrees_with_fine_verlet(case):
    with time_limit(60):
        result = run_scene(kicked(case), backend="reference", method="rk4", rtol=RTOL)
    sol, planned = result.solution, result.plan.scene
    # it ran to its end, or to the planned stop once the wave had passed contact stop_after_contact
    stop = planned.run.stop_after_contact
    assert sol.end_time == pytest.approx(planned.run.end_time) or sol.complete[stop - 1]
    # events are still located (the wave loads, unloads and opens contacts), and few: measured
    # 364 extra steps for 990 steps (ptfe) and 452 for 1590 (glass); it hung before
    assert 0 < sol.extra_steps <= 2 * sol.steps
    fine_scene = replace(planned, run=replace(planned.run, timestep=planned.run.timestep / 32))
    with time_limit(120):
        fine = run_scene(fine_scene, backend="reference", method="verlet").solution
    both = sol.complete & fine.complete
    assert both.sum() >= 2 * stop // 3  # the contacts up to the stop (measured: 14 of 17, 30 of 32)
    rel = np.abs(sol.peak_force[both] / fine.peak_force[both] - 1.0)
    assert rel.max() <= RTOL, f"RK4 vs Verlet at dt/32: {rel.max():.3g}"  # measured 9e-7 and 2e-7


def test_split_cap_raises_a_clear_error(monkeypatch):
    # the last line of defence: with no splits allowed the first located kink stops the run
    monkeypatch.setattr(solver, "MAX_SPLITS_BASE", 0)
    monkeypatch.setattr(solver, "MAX_SPLITS_PER_CONTACT", 0)
    with time_limit(60), pytest.raises(solver.EventLocationError, match=r"split step \d+ .* contact \d+ \("):
        run_scene(kicked("ptfe"), backend="reference", method="rk4", rtol=RTOL)


@settings(max_examples=20, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(scene=scenes(max_beads=40, law="bilinear", precompressed=True))
def test_precompressed_bilinear_rk4_splits_stay_few(scene):
    with time_limit(60):
        sol = run_scene(scene, backend="reference", method="rk4", rtol=RTOL).solution
    assert sol.extra_steps < 4 * sol.steps, f"{sol.extra_steps} extra steps for {sol.steps}\n{scene.to_toml()}"


def test_hermite_root_is_the_same_on_python_floats_and_arrays():
    """The event location's bisection on Python floats (a few crossings, _root) gives the bits the
    numpy one gives (many): each must split a step at the same place whichever path it takes."""
    from granchain.reference import hermite

    rng = np.random.default_rng(18)
    n = 1200
    a0 = rng.uniform(1e-12, 1e-6, n) * rng.choice([-1.0, 1.0], n)
    a1 = -np.sign(a0) * rng.uniform(1e-12, 1e-6, n)
    d0, d1 = rng.normal(0.0, 1e-6, n), rng.normal(0.0, 1e-6, n)
    a0[:5], d0[5:10] = 0.0, 0.0  # a zero end and zero slopes
    vectorised = hermite.hermite_root(a0, a1, d0, d1)  # above _SCALAR_ROOTS: numpy
    assert n > hermite._SCALAR_ROOTS
    scalar = np.array([hermite._root(*x) for x in zip(a0.tolist(), a1.tolist(), d0.tolist(), d1.tolist(), strict=True)])
    assert np.array_equal(vectorised, scalar)
    assert np.all((vectorised >= 0.0) & (vectorised <= 1.0))


def test_hermite_root_on_python_floats_keeps_the_bits_near_double_roots():
    """_root decides a bisection step by Horner's value of the cubic where that is far from zero, by
    the numpy path's formula near a root: on cubics with a double root next to the crossing (the
    value stays near zero over a stretch), tiny and huge scales and slopes of zero, the same bits."""
    from granchain.reference import hermite

    rng = np.random.default_rng(5)
    n = 3000
    r = rng.uniform(0.0, 1.0, n)  # a double root r, a simple root q: P(s) = c (s - r)^2 (s - q)
    q = np.where(rng.uniform(size=n) < 0.5, rng.uniform(-0.2, 1.2, n), r + rng.normal(0.0, 1e-9, n))
    c = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-14, 2, n)

    def p(s):
        return c * (s - r) ** 2 * (s - q)

    def dp(s):
        return c * (2.0 * (s - r) * (s - q) + (s - r) ** 2)

    a0, a1, d0, d1 = p(0.0), p(1.0), dp(0.0), dp(1.0)
    a0[:50] = 0.0
    d0[50:100] = d1[50:100] = 0.0
    a1[100:150] = -a0[100:150] * 1e-16  # a crossing right at s = 1
    vectorised = hermite.hermite_root(a0, a1, d0, d1)
    scalar = np.array([hermite._root(*x) for x in zip(a0.tolist(), a1.tolist(), d0.tolist(), d1.tolist(), strict=True)])
    assert np.array_equal(vectorised, scalar)


@pytest.mark.parametrize("name", ["default", "plastic-short-impulse", "thornton-short-impulse"])
def test_kink_crossing_on_python_floats_is_the_array_paths(name):
    """first_kink_crossing tests the few contacts its screens leave on Python floats
    (first_crossing_scalar); over many contacts it takes the array path (kink_roots, turns_above,
    earliest). On random pieces with a handful of contacts near each kink and turning (overlaps, rates,
    histories of both signs and scales), both give the same crossing: fraction, contact and kind."""
    from granchain.reference import integrators as ig
    from granchain.scene import load_scene

    law = load_scene(name).law
    rng = np.random.default_rng(25)
    n, agree, crossed = 40, 0, 0
    for _ in range(400):
        hist = rng.uniform(0.0, 2e-6, n - 1) * (rng.uniform(size=n - 1) < 0.7)
        kinks, turn_level = law.kinks(hist), law.turn_level(hist)
        # a base overlap near some kink level for a few contacts, elsewhere far below zero
        a0 = np.full(n - 1, -1e-3)
        near = rng.choice(n - 1, size=rng.integers(1, 6), replace=False)
        levels = [np.broadcast_to(k.level, hist.shape) for k in kinks]
        lv = levels[rng.integers(len(levels))][near]
        a0[near] = lv + rng.normal(0.0, 1e-8, near.size)
        a1 = a0.copy()
        a1[near] = lv + rng.normal(0.0, 1e-8, near.size)
        d0 = rng.normal(0.0, 1e-2, n - 1)
        d1 = rng.normal(0.0, 1e-2, n - 1)
        u1 = np.concatenate((np.cumsum(a1[::-1])[::-1], [0.0]))
        u0 = np.concatenate((np.cumsum(a0[::-1])[::-1], [0.0]))
        piece = ig.Piece(a0, d0, a1, d1, u0, u1, 1e-6)
        scalar = ig.first_kink_crossing(law, hist, piece, 1e-6)
        found = ig.kink_roots(kinks, piece)
        if turn_level is not None:
            found += ig.turns_above(turn_level, piece)
        arrays = ig.earliest(found, piece.h, 1e-6) if found else None
        assert scalar == arrays
        agree += 1
        crossed += scalar is not None
    assert agree == 400, crossed
    assert crossed > 20, crossed  # the pieces do cross kinks
