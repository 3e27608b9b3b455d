"""granchain.richardson: Richardson error estimates and their failure modes, on synthetic sequences."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from granchain.integrators import INTEGRATORS as REGISTERED
from granchain.richardson import MAX_OVERESTIMATE, NEXT_TERM, ORDER_SLACK, highest_trusted_order, richardson

values = st.floats(min_value=1e-3, max_value=1e6)
rel_errors = st.floats(min_value=1e-9, max_value=1e-2)

#: RK4's lowest order at a Hertzian onset, 1 + 3/2 (ContactLaw.onset_order): the order the rule's own
#: tests pass to against_reference
HERTZ_ONSET = 2.5


@given(
    q_true=values,
    rel=rel_errors,
    p=st.sampled_from(sorted({f.order for f in REGISTERED.values()})),
    sign=st.sampled_from([-1.0, 1.0]),
)
def test_a_clean_order_p_sequence_gives_its_exact_error(q_true, rel, p, sign):
    """Q(h) = Q* + C h^p: the estimate of Q(dt)'s error is exactly C dt^p, with the nominal order."""
    c = sign * rel * q_true
    runs = [q_true + c * k**p for k in (1, 2, 4)]
    bars = richardson([runs[0]], [runs[1]], [runs[2]], p)
    assert bars.status[0] == f"nominal order {p}"
    assert bars.error[0] == pytest.approx(abs(c), rel=1e-6)


#: (nominal order, the orders the integrator can show): workflows.error_estimates.expected_orders's cases
INTEGRATORS = [(2, None), (2, (2.0, 2.0)), (1, (1.0, 2.0)), (4, (2.5, 4.0))]


@given(
    q_true=values,
    rel=rel_errors,
    integ=st.sampled_from(INTEGRATORS),
    q=st.floats(min_value=1.05, max_value=8.0),
)
def test_an_observed_order_is_used_only_within_the_integrators_range(q_true, rel, integ, q):
    """A clean sequence of order q: outside the orders the integrator can show (widened by the
    slack, capped where p would overstate it more than MAX_OVERESTIMATE) no number; inside, a clearly
    lower q is used and gives the exact error, a higher one keeps p and overstates at most 3x."""
    p, orders = integ
    lo, hi = orders or (p, p)
    c = rel * q_true
    runs = [q_true + c * k**q for k in (1, 2, 4)]
    bars = richardson([runs[0]], [runs[1]], [runs[2]], p, orders=orders)
    below, above = max(1.0, lo - ORDER_SLACK), min(hi + NEXT_TERM, highest_trusted_order(p))
    if q < below - 1e-6 or q > above + 1e-6:
        assert bars.status[0].startswith("unreliable: observed order")
        assert math.isnan(bars.error[0])
    elif not (below + 1e-6 < q < above - 1e-6):
        return  # at an edge: either side is right
    elif q < p - ORDER_SLACK - 1e-6:
        assert bars.status[0].startswith("observed order")
        assert bars.order[0] == pytest.approx(q, rel=1e-6)
        assert bars.error[0] == pytest.approx(c, rel=1e-6)
    elif q > p + ORDER_SLACK + 1e-6:
        assert bars.status[0].startswith(f"nominal order {p} (observed")
        assert c * (1 - 1e-9) <= bars.error[0] <= MAX_OVERESTIMATE * c * (1 + 1e-9)
    elif abs(q - p) < ORDER_SLACK - 1e-6:
        assert bars.status[0] == f"nominal order {p}"
        assert 1 / MAX_OVERESTIMATE <= bars.error[0] / c <= MAX_OVERESTIMATE


@given(q_true=values, rel=rel_errors, p=st.sampled_from([2, 4]))
def test_differences_that_change_sign_or_do_not_shrink_are_unreliable(q_true, rel, p):
    c = rel * q_true
    wobble = [q_true + c, q_true - c, q_true + c]  # changes sign
    flat = [q_true + c, q_true + 1.5 * c, q_true + 2.2 * c]  # shrinks at order < 1
    for runs in (wobble, flat):
        bars = richardson([runs[0]], [runs[1]], [runs[2]], p)
        assert bars.status[0].startswith("unreliable")
        assert math.isnan(bars.error[0])


def test_a_peak_that_jumps_to_another_pulse_has_no_estimate():
    f = np.array([10.0, 10.0])
    c = np.array([10.003, 10.003])  # Q* + C h^2 with C = 0.001
    cc = np.array([10.015, 10.015])
    t = (np.array([1.0, 1.0]), np.array([1.0, 1.3]), np.array([1.0, 1.3]))
    bars = richardson(f, c, cc, 2, times=t, jump_time=0.1)
    assert bars.status[0].startswith("nominal")
    assert np.isfinite(bars.error[0])
    assert bars.status[1].startswith("unreliable: another pulse")
    assert math.isnan(bars.error[1])


def test_round_off_is_a_bound_not_a_small_number():
    x = 1234.5
    bars = richardson([x], [np.nextafter(x, 2 * x)], [x], 4)
    assert bars.status[0] == "round-off"
    assert bars.error[0] >= np.spacing(x)


def test_without_a_4dt_run_the_order_is_assumed_and_said():
    bars = richardson([1.0], [1.003], None, 2)
    assert bars.status[0] == "order not checked"
    assert bars.error[0] == pytest.approx(0.001)


def test_missing_values_are_not_measured():
    """A value is nan where the peak was not complete (or the pulse had not come) when a run ended: the
    status says so, not "missing", which read as lost data (error_estimates.per_contact)."""
    from granchain.richardson import against_reference, erratic_bounds

    bars = richardson([np.nan, 1.0], [1.0, np.nan], [1.0, 1.0], 2)
    assert all(s.startswith("not measured") for s in bars.status)
    assert np.all(np.isnan(bars.error))
    against = against_reference([np.nan], [1.0], [1.0], order=HERTZ_ONSET)
    bounds = erratic_bounds([np.nan], [1.0], [1.0], 2)
    for status in (*bars.status, *against.status, *bounds.status):
        assert "missing" not in status, status
        assert "not complete in the run or " in status, status
        assert "had not passed when that run ended" in status, status


@given(
    q_true=values,
    rel=rel_errors,
    ref_share=st.floats(min_value=0.0, max_value=10.0),
    q=st.floats(min_value=2.5, max_value=6.0),
    signs=st.tuples(st.sampled_from([-1.0, 1.0]), st.sampled_from([-1.0, 1.0])),
)
def test_against_a_reference_the_estimate_is_within_1_to_3_of_the_true_error_or_none(q_true, rel, ref_share, q, signs):
    """A run with error e and an RK4 reference with a clean order-q error r (2.5 <= q: RK4's lowest
    order on a chain): where the reference's own error is small enough for a number, that number is
    1-3 times |e| (richardson.against_reference); where it is not, no number and the status says why."""
    from granchain.richardson import REFERENCE_SHARE, against_reference

    e = signs[0] * rel * q_true
    r = signs[1] * ref_share * abs(e)
    bars = against_reference([q_true + e], [q_true + r], [q_true + r * 2**q], order=HERTZ_ONSET)
    own = abs(r) * (2**q - 1) / (2**HERTZ_ONSET - 1)
    if math.isnan(bars.error[0]):
        assert bars.status[0].startswith("unreliable: the RK4 run's own error")
        assert own > REFERENCE_SHARE * abs(e - r) * (1 - 1e-9)
    else:
        assert bars.status[0].startswith(("against RK4", "round-off"))
        ulps = 8 * np.spacing(q_true)  # the values themselves are rounded to q_true's last place
        assert abs(e) - ulps <= bars.error[0] <= 3 * abs(e) + ulps


def test_against_a_reference_another_pulse_or_a_missing_value_has_no_estimate():
    from granchain.richardson import against_reference

    v, r, rc = np.array([10.0, 10.0, np.nan]), np.array([10.01, 10.01, 10.0]), np.array([10.01, 10.01, 10.0])
    t = (np.array([1.0, 1.0, 1.0]), np.array([1.0, 1.3, 1.0]))
    bars = against_reference(v, r, rc, times=t, jump_time=0.1, order=HERTZ_ONSET)
    assert bars.status[0].startswith("against RK4")
    assert bars.error[0] == pytest.approx(0.01)
    assert bars.status[1].startswith("unreliable: another pulse")
    assert math.isnan(bars.error[1])
    assert bars.status[2].startswith("not measured")
    assert math.isnan(bars.error[2])


def test_differences_within_the_runs_round_off_floor_give_its_bound():
    """With the run's round-off floor given: runs at dt and 2 dt within ROUNDOFF_MARGIN floors (whatever
    order the three seem to show, or a sign change), or a Richardson estimate below one floor, are "round-off" with
    the floor as the bound; differences well above it keep Richardson's number."""
    from granchain.richardson import ROUNDOFF_MARGIN

    floor = 1e-12
    q = 10.0
    # noise that looks like order 3.2, a sign change, a clean order 4 whose estimate is below the floor,
    # and a clean order 4 far above the floor
    fine = np.array([q + 1.6e-13, q + 0.9e-12, q + 1e-13 * 15 / 16, q + 1e-6])
    coarse = np.array([q + 1.6e-13 * 9.5, q - 0.9e-12, q + 1e-13 * 15, q + 1.6e-5])
    coarser = np.array([q + 1.6e-13 * 9.5 * 9.5, q + 1.5e-12, q + 1e-13 * 15 * 16, q + 2.56e-4])
    bars = richardson(fine, coarse, coarser, 4, orders=(2.5, 4.0), floor=np.full(4, floor))
    assert list(bars.status[:3]) == ["round-off"] * 3
    assert np.all(bars.error[:3] == floor)
    assert bars.status[3] == "nominal order 4"
    assert bars.error[3] == pytest.approx(1e-6, rel=1e-6)
    assert ROUNDOFF_MARGIN * floor < abs(fine[3] - coarse[3])
    # without a floor the first is Richardson's tiny number (the failure the floor fixes)
    assert richardson(fine[:1], coarse[:1], coarser[:1], 4, orders=(2.5, 4.0)).error[0] < floor


@given(
    q_true=values,
    scale=rel_errors,
    coef=st.lists(st.floats(min_value=-1.0, max_value=1.0), min_size=3, max_size=3),
)
def test_an_erratic_error_is_bounded_unless_it_did_not_halve_from_4dt_to_dt(q_true, scale, coef):
    """erratic_bounds: every measured item gets max(|d1|, |d2| / 2), status a bound; it is below 1/3
    of the error at dt only where the error did not halve from 4 dt to dt (|E(4 dt)| < 2 |E(dt)|)."""
    from granchain.richardson import BOUND_STATUS, erratic_bounds

    errs = [c * scale * q_true * k**2 for c, k in zip(coef, (1, 2, 4), strict=True)]  # E(h), erratic in sign
    runs = [q_true + e for e in errs]
    bars = erratic_bounds([runs[0]], [runs[1]], [runs[2]], 2)
    bound = max(abs(runs[0] - runs[1]), abs(runs[1] - runs[2]) / 2)
    if bars.status[0] == "round-off":
        return
    assert bars.status[0] == BOUND_STATUS
    assert bars.error[0] == pytest.approx(bound, rel=1e-12)
    if bars.error[0] < abs(errs[0]) / 3:
        assert abs(errs[2]) < 2 * abs(errs[0])


def test_an_erratic_bound_needs_the_same_pulse_and_says_a_missing_4dt_run():
    from granchain.richardson import erratic_bounds

    moved = erratic_bounds([1.0], [1.1], [1.3], 2, times=([0.0], [0.0], [5.0]), jump_time=1.0)
    assert not moved.reliable[0]
    assert "another pulse" in moved.status[0]
    alone = erratic_bounds([1.0], [1.1], None, 2)
    assert alone.error[0] == pytest.approx(0.1)
    assert "no 4 dt run" in alone.status[0]
    missing = erratic_bounds([1.0], [np.nan], [1.3], 2)
    assert not missing.reliable[0]
