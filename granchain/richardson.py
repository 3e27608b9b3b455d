"""Measured error bars: Richardson extrapolation over runs at dt, 2 dt and 4 dt.

A run at time step dt is repeated at 2 dt and, where that is stable, at 4 dt (the same plan
otherwise). For a quantity Q measured by all three, with an integrator of order p (its
IntegratorFacts.order, granchain.integrators: RK4 4, velocity Verlet 2):

    Q(dt) = Q* + C dt^p + ...   =>   error of Q(dt) ~ (Q(dt) - Q(2 dt)) / (2^p - 1)

The third run checks the order: the observed order is log2((Q(2dt) - Q(4dt)) / (Q(dt) - Q(2dt))).
Each integrator declares the orders its error can show on a scene, lo-hi (workflows.error_estimates
.expected_orders: Verlet 2-2; Verlet with a dashpot 1-2, a mixture of the dashpot's first-order
term and Verlet's second; RK4 2.5-4, its 4 lowered to 1 + 3/2 near a Hertzian onset). An observed
order is accepted in lo - ORDER_SLACK ... hi + NEXT_TERM (at least MIN_ORDER, at most
highest_trusted_order(p), where the nominal estimate would overstate a clean order-q error more
than MAX_OVERESTIMATE times). Accepted: within ORDER_SLACK of p the nominal order is used; below
it the observed order; above it (a mixture nearer its higher order) the nominal one, at most
MAX_OVERESTIMATE too large. Not accepted: no number, the status says why. Measured on generated
scenes (docs/error-bars.md) before this rule: an observed order outside the range used as such
overstated the error 3-96x (orders 1.1-1.5 with RK4 or Verlet), and the nominal order kept for a
faster one overstated it up to 70x (RK4, observed 4.8-5.5) or understated it 3x (LAMMPS, observed
7.2); with observed 5.1 (elastic-step-40N, LAMMPS) the observed order understated it 11x. Where
the differences do not shrink (observed order below 1, or the differences change sign) the
estimate is unreliable too. Without a 4 dt run (unstable) the nominal order is assumed, and the
status says so.

Other ways an estimate fails, each with its own status (never a small number in their place):
- the peak is another pulse in a companion run: its time moved by more than half the shortest
  period of the chain (pi / omega_max) between two runs;
- round-off: the differences are below ROUNDOFF_ULPS units in the last place of the value, or
  below ROUNDOFF_MARGIN times the run's own round-off floor where the caller gives one (the
  reference: sqrt(steps) eps U dF/dalpha, workflows.error_estimates.roundoff_floor), or Richardson's
  estimate is below that floor (the error is at most the floor, and is reported as that bound). A
  step far finer than accuracy needs (set by a chain's smallest beads) leaves step errors near
  1e-15 of the force, and the three runs' differences are round-off that can look like any order:
  on a brass chain tapered by 0.8 at F0 = 0.3 N Richardson gave 0.013-0.62 of the distance to a
  run at dt / 16, itself round-off (docs/error-bars.md);
- not measured: the quantity is missing (nan) in one of the runs (a peak not complete, a contact
  not reached).

Statuses (the `*_error_status` columns and summary entries):
    "nominal order p"            Richardson with the integrator's order, confirmed by the 4 dt run
    "observed order q"           a clearly lower q within the integrator's range, used instead
    "nominal order p (observed q)"  a higher q within the integrator's range (a mixture of orders)
    "order not checked"          no 4 dt run (it would be unstable): nominal order assumed
    "round-off"                  differences (or the estimate) at round-off: the error is at most
                                 the bound given (a bound, not an estimate)
    "unreliable: ..."            no estimate; the reason follows (an order outside the range:
                                 the status gives the nominal value, not a bound; a check at
                                 dt / 2 that failed, `checked`: the estimate it withheld)
    "not measured: ..."          no estimate; the reason follows
    "against RK4 ..."            against_reference: the distance to an RK4 run at 2 dt (or dt)
                                 (Verlet on a law with slope kinks, when checked bars are asked for)
    "bound: kinked law, ..."     erratic_bounds: a bound from dt, 2 dt, 4 dt (Verlet on a law with
                                 slope kinks, by default); may overstate the error many times
    "bound: one companion ..."   one_companion with BOUND_ORDER: |Q(dt) - Q(2 dt)| (RK4 on a law with
                                 slope kinks, by default); may overstate the error many times
    "estimate: one companion ..."   one_companion with an order assumed: |Q(dt) - Q(2 dt)| / (2^p - 1),
                                 not checked (measured in docs/error-bars.md; no default gives it)

A law whose force slope jumps at kinks a moving contact crosses (ContactLaw.slope_kinks; bilinear:
dF/dalpha = 0 -> k at alpha = 0 and k_u -> 0 at zero force; Thornton: reloading past d_max) makes
fixed-step Verlet's error depend on where in a step each contact crosses them: it does not follow
any order in dt and Richardson fails (plastic-short-impulse, reference
Verlet: the three runs' differences changed sign on 47 of 59 peaks; |Q(dt) - Q(2 dt)| / 3 alone was
0.1-33x the true error). By default erratic_bounds gives such a run bounds from the same three runs,
which may overstate the error many times. RK4 locates those kinks (event location) and is smooth in
dt there, so, asked for, against_reference measures Verlet's error as its distance to an RK4 run at
2 dt (dt where 4 dt is unstable for RK4), whose own error (from a second RK4 run at twice its step)
must be small beside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: an observed order within this of the nominal one confirms it
ORDER_SLACK = 0.75
#: an observed order up to this above the highest is the error expansion's next term mixing in
NEXT_TERM = 1.0
#: an observed order below this is not convergence: the estimate is unreliable
MIN_ORDER = 1.0
#: differences below this many units in the last place of the value are round-off
ROUNDOFF_ULPS = 64.0
#: differences up to this many times the run's round-off floor are noise, not the step's error: a
#: difference of two runs carries both their round-off (each at most the floor)
ROUNDOFF_MARGIN = 2.0
#: the most an estimate may overstate the error: the issue's bar (estimated / true within 1/3 - 3)
MAX_OVERESTIMATE = 3.0


def highest_trusted_order(p: int) -> float:
    """The highest observed order q for which Richardson with the nominal p still gives a number.

    On a clean order-q sequence the nominal estimate |Q(dt) - Q(2 dt)| / (2^p - 1) is
    (2^q - 1) / (2^p - 1) times the true error; above this q that exceeds MAX_OVERESTIMATE
    (p = 1: 2.0, p = 2: 3.32, p = 4: 5.52) and the estimate is marked unreliable instead.
    """
    return math.log2(1.0 + MAX_OVERESTIMATE * (2.0**p - 1.0))


@dataclass
class ErrorBars:
    """Per-item error estimates of a quantity measured at dt (the run reported)."""

    error: np.ndarray  # absolute error estimate of the value at dt; nan where there is none
    status: np.ndarray  # object array of status strings (see the module docstring)
    order: np.ndarray  # the order used (nan where none)

    @property
    def reliable(self) -> np.ndarray:
        """Which items have an error estimate (a number, not only a status)."""
        return np.isfinite(self.error)


def richardson(
    fine: np.ndarray,
    coarse: np.ndarray,
    coarser: np.ndarray | None,
    order: int,
    times: tuple[np.ndarray, np.ndarray, np.ndarray | None] | None = None,
    jump_time: float | None = None,
    orders: tuple[float, float] | None = None,
    floor: np.ndarray | None = None,
) -> ErrorBars:
    """Error estimates of `fine` (the values at dt) from the same quantities at 2 dt and 4 dt.

    Parameters
    ----------
    fine, coarse, coarser : array_like
        The quantity at dt, 2 dt and 4 dt (coarser None: no 4 dt run, the order is not checked).
        nan where a run did not measure it.
    order : int
        The integrator's order p.
    times : tuple of arrays, optional
        The times at which each run measured each item (a peak's time): an item whose time moved by
        more than jump_time between two runs is another pulse there, and has no estimate.
    jump_time : float, optional
        See times (half the shortest period of the chain, pi / omega_max).
    orders : (float, float), optional
        The lowest and highest order this integrator's error can show on this scene (default
        (order, order)): an observed order outside them, widened by ORDER_SLACK (and above, at
        most highest_trusted_order(order)), leaves the item without an estimate.
    floor : array_like, optional
        The run's own round-off in each item (workflows.error_estimates.roundoff_floor; nan or absent: only
        ROUNDOFF_ULPS of the value): where the differences, or the Richardson estimate, are within
        it the item is "round-off" with this bound (module docstring).

    Returns
    -------
    ErrorBars
    """
    f = np.atleast_1d(np.asarray(fine, dtype=float))
    c = np.atleast_1d(np.asarray(coarse, dtype=float))
    cc = None if coarser is None else np.atleast_1d(np.asarray(coarser, dtype=float))
    n = f.size
    err = np.full(n, np.nan)
    used = np.full(n, np.nan)
    status = np.empty(n, dtype=object)
    lo, hi = (order, order) if orders is None else orders
    # above: up to the order of the error expansion's next term (hi + 1), a preasymptotic mixture
    # the nominal order overstates by at most (2^(p+1) - 1) / (2^p - 1) < 2.2, and never beyond
    # highest_trusted_order (effect-striker, RK4: observed 4.8-4.9 on 65 of 94 peaks, within 1/3-3)
    accepted = (max(MIN_ORDER, lo - ORDER_SLACK), min(hi + NEXT_TERM, highest_trusted_order(order)))
    fl = np.zeros(n) if floor is None else np.nan_to_num(np.broadcast_to(np.asarray(floor, dtype=float), (n,)))
    # the items as Python floats (the same doubles), each time array once: numpy's per-call cost on a
    # scalar (isfinite, spacing, indexing) was most of a point's error bars (benchmarks/RESULTS.md)
    columns = [f.tolist(), c.tolist(), [None] * n if cc is None else cc.tolist(), fl.tolist()]
    when = None if times is None else [None if t is None else np.atleast_1d(t).astype(float).tolist() for t in times]
    for i, (fi, ci, cci, fli) in enumerate(zip(*columns, strict=True)):
        err[i], used[i], status[i] = _one(
            fi,
            ci,
            cci,
            order,
            None if when is None else tuple(None if t is None else t[i] for t in when),
            jump_time,
            accepted,
            fli,
        )
    return ErrorBars(err, status, used)


#: the status of a value a run or its companion lacks: a peak is nan there until it is complete (its force
#: fell to half of it), a leading pulse until the contact had a maximum (error_estimates.per_contact)
NOT_COMPLETE = "not measured: not complete"
NOT_PASSED = " (the peak or pulse had not passed when that run ended)"


def _one(f, c, cc, p, times, jump_time, accepted, floor=0.0):
    e, used, status = _richardson_one(f, c, cc, p, times, jump_time, accepted, floor)
    unmeasured = status.startswith("not measured") or "another pulse" in status
    if floor > 0.0 and status != "round-off" and not unmeasured:
        # the differences are within the two runs' round-off, or the estimate within one's: whatever they say
        # (an order, a sign change), the error is the round-off's, and the bound is the floor
        # (the runs at dt and 2 dt agreeing to within their round-off bound dt's step error by it too,
        # whatever the 4 dt run says)
        if abs(f - c) <= ROUNDOFF_MARGIN * floor or (math.isfinite(e) and e <= floor):
            return float(floor), float(p), "round-off"
    return e, used, status


def _richardson_one(f, c, cc, p, times, jump_time, accepted, floor):
    # (f, c, cc, floor and the times: Python floats; math's isfinite and ulp are numpy's isfinite and
    # spacing on them, for a non-negative argument)
    if not (math.isfinite(f) and math.isfinite(c)):
        return math.nan, math.nan, NOT_COMPLETE + " in the run or its 2 dt companion" + NOT_PASSED
    if times is not None and jump_time is not None:
        tf, tc, tcc = times
        moved = [abs(a - b) for a, b in ((tf, tc), (tc, tcc)) if a is not None and b is not None]
        if any(not math.isfinite(m) for m in moved):
            return math.nan, math.nan, NOT_COMPLETE + " in a companion run" + NOT_PASSED
        if any(m > jump_time for m in moved):
            return (
                math.nan,
                math.nan,
                "unreliable: another pulse in a companion run (its time moved by more than half the shortest period)",
            )
    d1 = f - c
    ulp = max(ROUNDOFF_ULPS * math.ulp(max(abs(f), abs(c))), floor)
    if abs(d1) <= ulp:
        return float(ulp), float(p), "round-off"
    if cc is None:
        return abs(d1) / (2.0**p - 1.0), float(p), "order not checked"
    if not math.isfinite(cc):
        return math.nan, math.nan, NOT_COMPLETE + " in the 4 dt companion" + NOT_PASSED
    d2 = c - cc
    if abs(d2) <= ulp:
        # the coarser pair agrees to round-off but the finer does not: no convergence to speak of
        return math.nan, math.nan, "unreliable: the differences do not shrink with the time step"
    ratio = d2 / d1
    if ratio <= 0.0:
        return math.nan, math.nan, "unreliable: the differences change sign between the runs (not converging)"
    q = math.log2(ratio)
    if q < MIN_ORDER:
        return math.nan, math.nan, f"unreliable: observed order {q:.2g} (< {MIN_ORDER:g}): not converging"
    if not accepted[0] <= q <= accepted[1]:
        # an order this integrator does not show on this scene: the three runs are not in the
        # asymptotic range (or the error is near a sign change), and neither p nor q can be trusted
        # (measured: with q used, 3-96x too large; with p, up to 70x too large or 3x too small)
        bound = abs(d1) / (2.0**p - 1.0)
        return (
            math.nan,
            math.nan,
            f"unreliable: observed order {q:.2g}, outside the {accepted[0]:.3g}-{accepted[1]:.3g} this integrator "
            f"shows here (not asymptotic); with order {p} it would be {bound:.3g}",
        )
    if abs(q - p) <= ORDER_SLACK:
        return abs(d1) / (2.0**p - 1.0), float(p), f"nominal order {p}"
    if q > p:
        # a mixed-order error (Verlet with a dashpot: orders 1 and 2) nearer its higher order: the
        # nominal (lowest) order overstates a clean order-q error at most MAX_OVERESTIMATE times
        return abs(d1) / (2.0**p - 1.0), float(p), f"nominal order {p} (observed {q:.2g})"
    return abs(d1) / (2.0**q - 1.0), q, f"observed order {q:.2g}"


#: the order a bound (erratic_bounds) grants the error: the first, the least that still converges
BOUND_ORDER = 1
#: the status of a bound (erratic_bounds)
BOUND_STATUS = "bound: kinked law, the error's sign is erratic; may overstate it"


def erratic_bounds(
    fine: np.ndarray,
    coarse: np.ndarray,
    coarser: np.ndarray | None,
    order: int,
    times: tuple[np.ndarray, np.ndarray, np.ndarray | None] | None = None,
    jump_time: float | None = None,
    orders: tuple[float, float] | None = None,
    floor: np.ndarray | None = None,
) -> ErrorBars:
    """Error bounds of a quantity whose error in dt is erratic in sign (Verlet on a kinked law), from
    the runs at dt, 2 dt and 4 dt alone.

    Every item richardson measures (the same pulse in every run, measured in the run and at 2 dt)
    gets the bound max(|d1|, |d2| / 2^BOUND_ORDER), d1 = Q(dt) - Q(2 dt), d2 = Q(2 dt) - Q(4 dt)
    (|d1| alone without the 4 dt run), status BOUND_STATUS; a round-off bound (richardson) stays where
    it is the larger. Why: with E(h) the error at step h, the bound is below E(dt) / 3 only where
    |d1| < E(dt) / 3, so that E(2 dt) is within 2/3 - 4/3 of E(dt) with its sign, and |d2| / 2 <
    E(dt) / 3, so that |E(4 dt)| < 2 |E(dt)|: the error did not even halve from 4 dt to dt. Order 1,
    not Verlet's 2: where the error is erratic it can fall locally as order 1 between 2 dt and dt while
    the three runs look like order 2, and Richardson's estimate then understates it (measured below).
    On a clean order-2 error the bound is 6 times the error (|d2| / 2 = 6 E(dt)).

    Measured on generated bilinear and Thornton chains without a dashpot (docs/error-bars.md, "Bounds
    from dt, 2 dt, 4 dt"; docs/measure_kinked_verlet_peaks.py, three hypothesis seeds, reference Verlet
    planned for rtol 1e-3, true error against RK4 at dt / 2): bilinear (48 scenes) 1291 of 1304 peaks
    bounded (the rest another pulse in a companion), 2 below 1/3 of the true error (0.32, 0.33: errors
    that grew from 4 dt to dt), est/true 5-50-95% 2.5 - 6.1 - 29; Thornton (46 scenes) 1275 of 1275,
    none below (least 0.68), 3.5 - 6.0 - 23. Richardson's own estimate where its checks passed: below
    1/3 on 5 of 835 bilinear peaks (down to 0.07) and 1 of 946 Thornton ones (0.21).

    Parameters and returns as richardson.
    """
    bars = richardson(fine, coarse, coarser, order, times=times, jump_time=jump_time, orders=orders, floor=floor)
    f = np.atleast_1d(np.asarray(fine, dtype=float))
    c = np.atleast_1d(np.asarray(coarse, dtype=float))
    cc = None if coarser is None else np.atleast_1d(np.asarray(coarser, dtype=float))
    err, status, used = bars.error.copy(), bars.status.copy(), bars.order.copy()
    for i, st in enumerate(bars.status):
        st = str(st)
        if "another pulse" in st or st.startswith(NOT_COMPLETE + " in the run"):
            continue  # (not the same peak, or not measured at dt or 2 dt: nothing to bound)
        if "not measured" in st and not (np.isfinite(f[i]) and np.isfinite(c[i])):
            continue
        d1 = abs(f[i] - c[i])
        d2 = abs(c[i] - cc[i]) if cc is not None and np.isfinite(cc[i]) else 0.0
        bound = max(d1, d2 / 2.0**BOUND_ORDER)
        if st == "round-off" and err[i] >= bound:
            continue
        err[i], used[i] = bound, float(BOUND_ORDER)
        status[i] = (
            BOUND_STATUS if cc is not None and np.isfinite(cc[i]) else f"{BOUND_STATUS} (no 4 dt run: |d1| alone)"
        )
    return ErrorBars(err, status, used)


#: the order one_companion assumes unless told: the middle of the orders RK4 (event location) shows on a
#: chain, 1 + 3/2 at a Hertzian onset to 4 (workflows.error_estimates.expected_orders; the onset's 1 + n
#: is the law's, workflows.error_estimates.onset_order: 2 to 4 for the power law's n = 1, still about 3)
ONE_COMPANION_ORDER = 3
#: the status of one_companion's estimates
ONE_COMPANION_STATUS = "estimate: one companion at 2 dt, order 3 assumed, not checked"
#: the status of one_companion's bounds (order BOUND_ORDER: |Q(dt) - Q(2 dt)| itself), a kinked law's times
ONE_COMPANION_BOUND_STATUS = (
    "bound: one companion at 2 dt, |Q(dt) - Q(2 dt)|, the error's order not assumed; may overstate it"
)


def one_companion(
    fine: np.ndarray,
    coarse: np.ndarray,
    order: float = ONE_COMPANION_ORDER,
    times: tuple[np.ndarray, np.ndarray] | None = None,
    jump_time: float | None = None,
    floor: np.ndarray | None = None,
) -> ErrorBars:
    """Error estimates of `fine` (the values at dt) from the same quantities at 2 dt alone, with an
    assumed order: |Q(dt) - Q(2 dt)| / (2^order - 1), status ONE_COMPANION_STATUS.

    A true order q in [2, 4] puts the estimate at (2^q - 1) / 7 of the error with the order 3 assumed,
    0.43 - 2.14, whatever q is; but an error that does not follow an order between dt and 2 dt (stalls,
    or changes sign) is not caught, which the checks of three runs would catch (richardson, checked):
    for RK4 on the kinked laws 2-10% of such estimates fell below 1/3 of the true error
    (docs/error-bars.md). Order BOUND_ORDER gives |Q(dt) - Q(2 dt)| itself, a bound
    (ONE_COMPANION_BOUND_STATUS; RK4's default on a kinked law, workflows.error_estimates
    .one_companion_because), below E(dt) / 3 only where E(2 dt) is within 2/3 - 4/3 of E(dt) with its
    sign. Another pulse in the companion, a missing value and round-off are as in richardson.

    Parameters
    ----------
    fine, coarse : array_like
        The quantity at dt and 2 dt (nan where a run did not measure it).
    order : float
        The order assumed.
    times : (array, array), optional
        When the run and the companion measured each item (another pulse, see richardson).
    jump_time, floor : see richardson

    Returns
    -------
    ErrorBars
    """
    t = None if times is None else (times[0], times[1], None)
    bars = richardson(fine, coarse, None, order, times=t, jump_time=jump_time, floor=floor)
    if order == BOUND_ORDER:
        given = ONE_COMPANION_BOUND_STATUS
    else:
        given = ONE_COMPANION_STATUS.replace("order 3", f"order {order:g}")
    status = np.array([given if s == "order not checked" else s for s in bars.status], dtype=object)
    return ErrorBars(bars.error, status, bars.order)


#: the check run's step, as a fraction of the run's (checked)
CHECK_FACTOR = 0.5


def checked(
    bars: ErrorBars,
    finer: np.ndarray,
    fine: np.ndarray,
    coarse: np.ndarray,
    order: int,
    times: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    jump_time: float | None = None,
    orders: tuple[float, float] | None = None,
    floor: np.ndarray | None = None,
) -> ErrorBars:
    """Richardson's bars of the values at dt, checked against a run at dt / 2 (CHECK_FACTOR).

    The runs at dt, 2 dt and 4 dt show one observed order, but that order need not hold between dt
    and the converged value: where the error mixes orders (RK4 on a chain: 2.5 at every Hertzian
    onset, whose coefficient depends on where in a step the contact closes, with 4 and the terms
    beyond it) the local order between 2 dt and dt can differ from the one the coarser runs show, or
    the error change sign just below dt. Measured on generated varied Hertz chains (reference RK4,
    docs/error-bars.md): estimates 0.21-0.25 of the true error where the local order fell to 2.1-2.3
    below a clean-looking 3.9-4.8, and 3.2-3.8 where it rose to 5.6-5.8 or the error changed sign
    past dt. A run at dt / 2 sees the order below dt: every estimate given is kept only where
    - the triple dt / 2, dt, 2 dt passes the same checks as dt, 2 dt, 4 dt (richardson: a sign change,
      an order outside the integrator's range, another pulse), and
    - the estimate is within the bar's own factor MAX_OVERESTIMATE of every error at dt that the
      difference d = |Q(dt / 2) - Q(dt)| allows: with an order at least the integrator's lowest, lo,
      between dt / 2 and dt, that error is d / (1 + 2^-lo) to d / (1 - 2^-lo) (RK4, lo = 2.5:
      0.85 d to 1.21 d; a draw whose estimate was 0.33 of the true error passed a check against d
      alone, the estimate then 0.36 d).
    Elsewhere the item has no estimate, and its status says which check failed and what the estimate
    would have been. A "round-off" bound and an item already without an estimate are kept as they are.

    Parameters
    ----------
    bars : ErrorBars
        richardson(fine, coarse, coarser, ...): the bars to check.
    finer, fine, coarse : array_like
        The quantity at dt / 2, dt and 2 dt (nan where a run did not measure it).
    order, orders, floor, jump_time : see richardson
    times : (array, array, array), optional
        When each item was measured at dt / 2, dt and 2 dt (another pulse, see richardson).

    Returns
    -------
    ErrorBars
    """
    h = np.atleast_1d(np.asarray(finer, dtype=float))
    f = np.atleast_1d(np.asarray(fine, dtype=float))
    below = richardson(h, f, coarse, order, times=times, jump_time=jump_time, orders=orders, floor=floor)
    lo = float(order if orders is None else orders[0])
    err, status, used = bars.error.copy(), bars.status.copy(), bars.order.copy()
    for i in np.flatnonzero(bars.reliable):
        if status[i] == "round-off":
            continue
        e = float(bars.error[i])
        why = None
        if not np.isfinite(h[i]):
            why = "not measured in the run at dt / 2 that checks it"
        elif not below.reliable[i]:
            why = str(below.status[i]).removeprefix("unreliable: ")
            why = f"between dt / 2, dt and 2 dt {why}"
        else:
            # the errors at dt the difference to dt / 2 allows (a difference at round-off stands for at
            # most its bound)
            seen = abs(h[i] - f[i]) if below.status[i] != "round-off" else max(abs(h[i] - f[i]), below.error[i])
            least, most = seen / (1.0 + 2.0**-lo), seen / (1.0 - 2.0**-lo)
            if not (most / MAX_OVERESTIMATE <= e <= MAX_OVERESTIMATE * least):
                why = (
                    f"the run at dt / 2 puts the error at {least:.3g}-{most:.3g}, not within {MAX_OVERESTIMATE:g}x "
                    "of this estimate"
                )
        if why is not None:
            err[i], used[i] = math.nan, math.nan
            status[i] = f"unreliable: {why} (from 2 dt and 4 dt it would be {e:.3g})"
    return ErrorBars(err, status, used)


#: the reference's error may be at most this fraction of the distance it measures: the estimate
#: (distance + reference error) is then within 1 - 3 times a true error in distance +- reference error
REFERENCE_SHARE = 0.5


def against_reference(
    values: np.ndarray,
    reference: np.ndarray,
    reference_coarse: np.ndarray,
    times: tuple[np.ndarray, np.ndarray] | None = None,
    jump_time: float | None = None,
    *,
    order: float,
) -> ErrorBars:
    """Error estimates of `values` (a Verlet run at dt) from RK4 runs at h and 2 h (module docstring).

    Parameters
    ----------
    values : array_like
        The quantity from the run (nan where not measured).
    reference, reference_coarse : array_like
        The same quantity from RK4 (event location) at a step h (2 dt, or dt) and at 2 h.
    times : (array, array), optional
        When the run and the RK4 run at dt measured each item: an item whose time differs by more
        than jump_time is another pulse in one of them, and has no estimate.
    jump_time : float, optional
        Half the shortest period of the chain (pi / omega_max).
    order : float
        The reference's lowest order on the scene, at which its own error from its runs at h and 2 h
        is taken (the larger, conservative bound): its law's onset order 1 + n, at most RK4's 4
        (workflows.errorbars.facts.reference_order; ContactLaw.onset_order). No default: a law's
        onset is its own fact, not Hertz's 2.5.

    Returns
    -------
    ErrorBars
        error = |value - reference| + the reference's own error |reference - reference_coarse| /
        (2^order - 1), where that is at most REFERENCE_SHARE of the distance; else none.
    """
    v = np.atleast_1d(np.asarray(values, dtype=float))
    r = np.atleast_1d(np.asarray(reference, dtype=float))
    rc = np.atleast_1d(np.asarray(reference_coarse, dtype=float))
    n = v.size
    err = np.full(n, np.nan)
    status = np.empty(n, dtype=object)
    for i in range(n):
        err[i], status[i] = _against_one(
            v[i], r[i], rc[i], None if times is None else (float(times[0][i]), float(times[1][i])), jump_time, order
        )
    return ErrorBars(err, status, np.full(n, np.nan))


def _against_one(v, r, rc, times, jump_time, order):
    if not (np.isfinite(v) and np.isfinite(r) and np.isfinite(rc)):
        return math.nan, NOT_COMPLETE + " in the run or an RK4 companion" + NOT_PASSED
    if times is not None and jump_time is not None:
        if not all(np.isfinite(times)):
            return math.nan, NOT_COMPLETE + " in the run or an RK4 companion" + NOT_PASSED
        if abs(times[0] - times[1]) > jump_time:
            return (
                math.nan,
                "unreliable: another pulse in the RK4 run (its time moved by more than half the shortest period)",
            )
    distance = abs(v - r)
    ulp = ROUNDOFF_ULPS * np.spacing(max(abs(v), abs(r)))
    own = abs(r - rc) / (2.0**order - 1.0)
    if distance <= ulp and own <= ulp:
        return float(ulp), "round-off"
    if own > REFERENCE_SHARE * distance:
        return (
            math.nan,
            f"unreliable: the RK4 run's own error ({own:.3g}) is not small beside its distance to the run "
            f"({distance:.3g})",
        )
    return float(distance + own), f"against RK4 (its own error {own:.2g})"


def largest_relative(values: np.ndarray, bars: ErrorBars) -> float | None:
    """The largest relative error over the items that have an estimate (None if none has)."""
    v = np.asarray(values, dtype=float)
    ok = bars.reliable & np.isfinite(v) & (v != 0)
    if not ok.any():
        return None
    return float(np.max(bars.error[ok] / np.abs(v[ok])))
