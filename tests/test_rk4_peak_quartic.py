"""RK4's peaks from the quartic dense output (reference.hermite.hermite_max_quartic): exact on a
quartic, O(h^5) on a smooth overlap whatever the phase of its maximum in the step, the same bits on
Python floats and arrays, and on a chain a peak error smooth enough in the step for Richardson's
bars to hold where the cubic's phase-dependent error broke them."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.reference import hermite
from granchain.scene import parse_scene
from granchain.workflows.run import plan_for, run_scene


def _ends(coefficients, h):
    """alpha, alpha' at s = 0 and 1 and alpha'' at 0 of the polynomial in t (numpy order, highest
    first) over a step [0, h], as the integrator hands them over (rates per unit time)."""
    p = np.poly1d(coefficients)
    dp, ddp = p.deriv(), p.deriv(2)
    return p(0.0), p(h), dp(0.0), dp(h), ddp(0.0)


@settings(max_examples=200, deadline=None)
@given(
    peak_at=st.floats(0.02, 0.98),
    curvature=st.floats(0.1, 10.0),
    quartic=st.floats(-0.25, 0.25),
    cubic=st.floats(-0.25, 0.25),
    h=st.floats(1e-3, 1.0),
)
def test_the_quartic_maximum_is_exact_on_a_quartic(peak_at, curvature, quartic, cubic, h):
    # alpha(t) = 1 - c (t - t*)^2 + k3 (t - t*)^3 + k4 (t - t*)^4 with t* = peak_at h inside the step:
    # alpha' = c x (-2 + 3 (k3 h / c) x / h + 4 (k4 h^2 / c) x^2 / h^2), x = t - t*, vanishes in the
    # step only at x = 0 while |k3 h / c|, |k4 h^2 / c| <= 1/4, so its maximum there is 1
    x = np.poly1d([1.0, -peak_at * h])
    poly = 1.0 - curvature * x**2 + cubic * curvature / h * x**3 + quartic * curvature / h**2 * x**4
    a0, a1, d0, d1, dd0 = _ends(poly.coeffs, h)
    p, tp = hermite.hermite_max_quartic(0.0, h, *(np.array([x]) for x in (a0, a1, d0, d1, dd0)))
    assert p[0] == pytest.approx(1.0, rel=1e-12)
    assert tp[0] == pytest.approx(peak_at * h, rel=1e-5)


@settings(max_examples=200, deadline=None)
@given(phase=st.floats(0.02, 0.98), h=st.floats(0.05, 0.5))
def test_on_a_cosine_the_error_is_fifth_order_at_any_phase(phase, h):
    # alpha = cos(t - t*), the maximum 1 at t* = phase h: the quartic's error term f^(5)/120
    # s^3 (1 - s)^2 h^5 (at most 0.0346 h^5 / 120); the cubic's, f^(4)/24 s^2 (1 - s)^2 h^4, would
    # be 1.6e-4 at h = 0.5 mid-step
    t_star = phase * h
    a0, a1 = np.cos(-t_star), np.cos(h - t_star)
    d0, d1 = -np.sin(-t_star), -np.sin(h - t_star)
    dd0 = -np.cos(-t_star)
    p, _ = hermite.hermite_max_quartic(0.0, h, *(np.array([x]) for x in (a0, a1, d0, d1, dd0)))
    assert abs(p[0] - 1.0) <= 1.2 * 0.0346 * h**5 / 120 + 4e-16


def test_the_quartic_maximum_is_the_same_on_python_floats_and_arrays():
    """A step where a few contacts turn takes the Python-float path (max1_quartic), many the numpy
    one: a contact's peak must not depend on how many others turned with it."""
    rng = np.random.default_rng(7)
    n = 1500
    h = 1e-7
    a0 = rng.uniform(1e-7, 1e-4, n)
    d0 = rng.uniform(1e-6, 1.0, n)
    d1 = -rng.uniform(0.0, 1.0, n)
    d1[:5] = 0.0
    a1 = a0 + h * rng.uniform(-1.0, 1.0, n) * d0
    dd0 = -rng.uniform(0.0, 1e7, n)
    assert n > hermite._SCALAR_ROOTS
    p, t = hermite.hermite_max_quartic(0.0, h, a0, a1, d0, d1, dd0)
    rows = zip(a0.tolist(), a1.tolist(), d0.tolist(), d1.tolist(), dd0.tolist(), strict=True)
    scalar = [hermite.max1_quartic(h, *x) for x in rows]
    assert np.array_equal(p, [x for x, _ in scalar])
    assert np.array_equal(t, [s * h for _, s in scalar])


#: CI's draw of tests/test_precompressed_error_bars (rk4): a precompressed aluminium taper, bead 1
#: kicked to 10 x F0's linear force; at 2 dt the first contact's peak fell mid-step, at dt near a
#: step's end, and with the cubic's maximum Richardson gave 0.31 of the distance to a run at dt / 16
TAPER = """
[chain]
beads = 15
radius = 4.76e-3
taper = 0.90625
material = "aluminium-6061-t6"
[contact]
law = "hertz"
[loading]
kind = "velocity"
velocity = 0.17191789651870718
[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
[precompression]
force = 1.0
"""


def test_rk4_bars_hold_where_a_companion_peak_falls_mid_step():
    sc, _ = plan_for(parse_scene(TAPER, source="taper.toml"), "reference", "rk4", 1e-3)
    got = run_scene(sc, backend="reference", method="rk4", error_estimate=True)
    fine = run_scene(replace(sc, run=replace(sc.run, timestep=sc.run.timestep / 16)), backend="reference", method="rk4")
    est = got.errors.peak_force
    ok = got.solution.complete & fine.solution.complete & est.reliable
    assert ok.sum() >= 8, list(est.status)
    ratio = est.error[ok] / np.abs(got.solution.peak_force - fine.solution.peak_force)[ok]
    assert np.all((ratio >= 1 / 3) & (ratio <= 3)), ratio
