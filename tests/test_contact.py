"""Contact laws: properties that must hold for every overlap and history (hypothesis)."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from granchain.physics.laws.bilinear import bilinear_dissipated, bilinear_energy, bilinear_force, unloading_stiffness
from granchain.physics.laws.hertz import hertz_energy, hertz_force
from granchain.physics.models import dissipation_per_cycle

overlap = st.floats(-1e-3, 1e-3, allow_nan=False)
positive_overlap = st.floats(1e-9, 1e-3)
stiffness = st.floats(1e3, 1e10)
beta = st.floats(0.0, 0.99)


@given(overlap, st.floats(0, 1e-3), stiffness, beta)
def test_forces_nonnegative(a, amax, k, b):
    assert hertz_force(a, k) >= 0
    assert bilinear_force(a, amax, k, b) >= 0


@given(st.floats(-1e-3, 0.0), st.floats(0, 1e-3), stiffness, beta)
def test_no_force_without_overlap(a, amax, k, b):
    assert hertz_force(a, k) == 0 and bilinear_force(a, amax, k, b) == 0
    assert hertz_energy(a, k) == 0 and bilinear_energy(a, amax, k, b) == 0


@given(positive_overlap, stiffness, beta, st.floats(0.0, 1.0))
def test_bilinear_continuity(amax, k, b, frac):
    # at alpha_max the unloading line meets the loading line; at beta alpha_max it reaches zero
    eps = amax * 1e-9
    left = bilinear_force(amax - eps, amax, k, b)
    right = bilinear_force(amax + eps, amax, k, b)
    assert abs(right - left) <= 1e-6 * k * amax + unloading_stiffness(k, b) * 2 * eps
    assert bilinear_force(b * amax, amax, k, b) <= unloading_stiffness(k, b) * 1e-12 * amax + 1e-300
    # never above the loading line, never below zero
    a = frac * amax
    assert 0 <= bilinear_force(a, amax, k, b) <= k * amax * (1 + 1e-12)


@given(positive_overlap, stiffness, beta)
def test_load_unload_cycle_dissipates_eq20(amax, k, b):
    # load 0 -> alpha_max on F = k alpha, unload to zero force: the loop's area is Eq. 20
    a_load = np.linspace(0, amax, 2001)
    w_in = np.trapezoid(bilinear_force(a_load, 0.0, k, b), a_load)
    # the law is piecewise linear: with its kink (beta alpha_max) as a node the trapezoid is exact
    a_unload = np.unique(np.append(np.linspace(0, amax, 2001), b * amax))[::-1]
    w_out = -np.trapezoid(bilinear_force(a_unload, amax, k, b), a_unload)
    eq20 = dissipation_per_cycle(k * amax, k, b)
    assert np.isclose(w_in - w_out, eq20, rtol=1e-9, atol=1e-12 * w_in)  # atol: round-off at beta = 0
    assert np.isclose(bilinear_dissipated(amax, k, b), eq20, rtol=1e-12)
    # stored + dissipated = work done, at the top of the cycle
    assert np.isclose(bilinear_energy(amax, amax, k, b) + bilinear_dissipated(amax, k, b), w_in, rtol=1e-5)


@given(positive_overlap, stiffness, beta, st.floats(0.0, 1.0))
def test_energies_are_integrals_of_force(amax, k, b, frac):
    a = max(frac * amax, 1e-12)
    h = a * 1e-6
    dh = (hertz_energy(a + h, k) - hertz_energy(a - h, k)) / (2 * h)
    assert np.isclose(dh, hertz_force(a, k), rtol=1e-5)
    if a < amax * (1 - 1e-5) and abs(a - b * amax) > 2 * h:  # not across a kink of the law
        db = (bilinear_energy(a + h, amax, k, b) - bilinear_energy(a - h, amax, k, b)) / (2 * h)
        assert np.isclose(db, bilinear_force(a, amax, k, b), rtol=1e-4, atol=1e-9 * k * amax)


@given(overlap, st.floats(0, 1e-3), stiffness)
def test_beta_zero_is_a_linear_elastic_spring(a, amax, k):
    assert bilinear_force(a, amax, k, 0.0) == k * max(a, 0.0)
    assert bilinear_dissipated(amax, k, 0.0) == 0.0
    assert np.isclose(bilinear_energy(a, max(a, amax), k, 0.0), 0.5 * k * max(a, 0.0) ** 2)


def test_vectorized_per_contact_stiffness():
    a = np.array([1e-6, -1e-6, 2e-6])
    k = np.array([1e9, 2e9, 3e9])
    assert np.allclose(hertz_force(a, k), [k[0] * 1e-9, 0.0, k[2] * 2e-6**1.5])
    am = np.array([2e-6, 0.0, 2e-6])
    f = bilinear_force(a, am, k, 0.5)
    assert np.allclose(f, [k[0] * 2 * (1e-6 - 1e-6), 0.0, k[2] * 2e-6])
