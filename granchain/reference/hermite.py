"""The cubic Hermite interpolant of a contact's overlap over one step: its maximum and its first root.

RK4 knows, at both ends of a step, each overlap alpha and its rate d(alpha)/dt. The cubic through
those four numbers is the step's dense output: accurate to O(h^4), so a kink located on it is as
accurate as the method; the event location reads it. A peak's value is another matter: the cubic's
error at its maximum, alpha^(4) / 24 s^2 (1 - s)^2 h^4, is of the method's order but depends on where
in the step the maximum falls (s), a fraction that jumps from run to run as the step changes. On a
precompressed aluminium taper it was half of RK4's peak error at the first contacts, and a run at
2 dt whose peak fell mid-step (s = 0.48) had 5.7x, not 16x, the error at dt (s = 0.96): Richardson
gave 0.31 of the true error. The peak tracking and the history update therefore read the quartic
through the same four numbers and the overlap's second derivative at the step's start, which RK4's
first stage has already evaluated (hermite_max_quartic): its error is O(h^5), smaller than the
method's by about omega h.
"""

from __future__ import annotations

import math

import numpy as np


def hermite_max(
    t0: float, t1: float, a0: np.ndarray, a1: np.ndarray, d0: np.ndarray, d1: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Maximum over [t0, t1] of the cubic Hermite interpolant of alpha, where d0 > 0 >= d1.

    Parameters
    ----------
    t0, t1 : float
        The step's ends.
    a0, a1, d0, d1 : ndarray
        alpha and d(alpha)/dt at t0 and t1, one per contact.

    Returns
    -------
    (alpha_max, t_max) : tuple of ndarray
        The interpolant's largest value and where it is taken. p(s) = a s^3 + b s^2 + c s + d on s in [0, 1].
    """
    if a0.size <= _SCALAR_ROOTS:
        # a few contacts turn in a step: Python floats, as in hermite_root (the same numbers)
        return _max_scalar(t0, t1, a0, a1, d0, d1)
    h = t1 - t0
    a, b, c = _coefficients(h, a0, a1, d0, d1)
    s = _cubic_argmax(a, b, c)
    p = ((a * s + b) * s + c) * s + a0
    return p, t0 + s * h


def _coefficients(h, x0, x1, y0, y1):
    """The cubic Hermite interpolant's coefficients (a, b, c) in p(s) = a s^3 + b s^2 + c s + x0 on
    s in [0, 1], from the ends' values x0, x1 and rates y0, y1 over a step h (arrays or floats)."""
    c = h * y0
    b = 3.0 * (x1 - x0) - 2.0 * h * y0 - h * y1
    a = 2.0 * (x0 - x1) + h * y0 + h * y1
    return a, b, c


def _cubic_argmax(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Where in [0, 1] the cubic of _coefficients is largest, where c > 0 (it rises at s = 0)."""
    # p'(s) = 3a s^2 + 2b s + c falls through zero at s = (-b - sqrt(b^2 - 3ac)) / (3a), written
    # as c / (sqrt(b^2 - 3ac) - b), which also holds for a -> 0 (no cancellation, p'' = -2 disc).
    disc = np.sqrt(np.maximum(b * b - 3.0 * a * c, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        s = c / (disc - b)
    # nan (0/0) and +inf -> 1, -inf -> 0, the rest clipped to [0, 1]: fmin takes 1 over a nan
    return np.maximum(np.fmin(s, 1.0), 0.0)


def _max_scalar(
    t0: float, t1: float, a0: np.ndarray, a1: np.ndarray, d0: np.ndarray, d1: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """hermite_max on Python floats, contact by contact: the same operations in the same order."""
    h = t1 - t0
    ps, ts = [], []
    for x0, x1, y0, y1 in zip(a0.tolist(), a1.tolist(), d0.tolist(), d1.tolist(), strict=True):
        p, s = max1(h, x0, x1, y0, y1)
        ps.append(p)
        ts.append(t0 + s * h)
    return np.array(ps), np.array(ts)


def max1(h: float, x0: float, x1: float, y0: float, y1: float) -> tuple[float, float]:
    """hermite_max of one contact on Python floats over a step of length h: (the maximum, its
    fraction s of the step). The same operations in the same order as the numpy path."""
    a, b, c = _coefficients(h, x0, x1, y0, y1)
    q = b * b - 3.0 * a * c
    disc = math.sqrt(q if not q < 0.0 else 0.0)  # np.maximum(q, 0.0): a nan stays nan
    den = disc - b
    if den != 0.0 or den != den:
        s = c / den if den == den else math.nan
    elif c != 0.0 and c == c:  # c / +-0: +-inf, by the signs of both
        s = math.copysign(math.inf, c) * math.copysign(1.0, den)
    else:
        s = math.nan  # 0 / 0 or nan / 0
    s = 1.0 if not s <= 1.0 else s if s > 0.0 else 0.0  # nan and > 1 -> 1, < 0 -> 0
    return ((a * s + b) * s + c) * s + x0, s


def hermite_root(a0: np.ndarray, a1: np.ndarray, d0: np.ndarray, d1: np.ndarray) -> np.ndarray:
    """A root in [0, 1] of the cubic Hermite interpolant with ends a0, a1 of opposite signs.

    Parameters
    ----------
    a0, a1 : ndarray
        The interpolant at s = 0 and s = 1 (alpha minus the level sought).
    d0, d1 : ndarray
        Its slopes there in s: h d(alpha)/dt.

    Returns
    -------
    ndarray
        The fraction s of the step, by 40 bisections (2^-40 of the step: far below any tolerance
        the event location needs, and a fixed count keeps it vectorised over contacts).
    """
    if a0.size <= _SCALAR_ROOTS:
        # a step crosses a kink at one contact or a few: 40 bisections of numpy calls on arrays of one
        # element cost ~20 us each, the same arithmetic on Python floats ~1 us (bit for bit the same:
        # both are IEEE double, operation by operation in the same order)
        return np.array([_root(*x) for x in zip(a0.tolist(), a1.tolist(), d0.tolist(), d1.tolist(), strict=True)])
    lo, hi = np.zeros(a0.size), np.ones(a0.size)
    for _ in range(40):  # bisection on the Hermite cubic, which brackets a root
        mid = 0.5 * (lo + hi)
        p = _cubic(mid, a0, a1, d0, d1)
        left = np.sign(p) == np.sign(a0)
        lo = np.where(left, mid, lo)
        hi = np.where(left, hi, mid)
    return 0.5 * (lo + hi)


def _cubic(s, a0, a1, d0, d1):
    """The Hermite cubic through (a0, d0) at s = 0 and (a1, d1) at s = 1, at s (floats or arrays alike:
    the same operations in the same order, so both bisections give the same bits)."""
    m2 = s * s
    return (
        (2 * m2 * s - 3 * m2 + 1) * a0 + (m2 * s - 2 * m2 + s) * d0 + (-2 * m2 * s + 3 * m2) * a1 + (m2 * s - m2) * d1
    )


#: hermite_root on Python floats up to this many contacts, on numpy arrays beyond
_SCALAR_ROOTS = 32


def _sign(x: float) -> float:
    """np.sign of a float (nan for nan)."""
    return 1.0 if x > 0.0 else -1.0 if x < 0.0 else x


def _root(a0: float, a1: float, d0: float, d1: float) -> float:
    """hermite_root of one contact, on Python floats: the same bisection step by step.

    _cubic and _sign written out in the loop, with m2 s (m3) taken once: 2 m2 s, -2 m2 s and m2 s in
    _cubic are 2 m3, -(2 m3) and m3 to the bit (a factor 2 is exact), the rest the same operations in
    the same order (tests/test_rk4_events checks the roots against the numpy path).

    Each step first evaluates the cubic in Horner's form (6 operations instead of 17); where that value
    is farther from zero than _HORNER_SLACK (|a0| + |a1| + |d0| + |d1|), more than both forms'
    round-off apart, it has the sign of _cubic's value and decides the step alone; else (near the
    root, and for any nan or inf) _cubic's value decides, as before. Either way the same bits."""
    lo, hi = 0.0, 1.0
    s0 = _sign(a0)
    c3 = 2.0 * (a0 - a1) + d0 + d1  # p(s) = ((c3 s + c2) s + d0) s + a0
    c2 = 3.0 * (a1 - a0) - 2.0 * d0 - d1
    slack = _HORNER_SLACK * (abs(a0) + abs(a1) + abs(d0) + abs(d1))
    if not slack > 1e-280:  # (subnormal round-off is not relative; nan) inf: _cubic decides every step
        slack = math.inf
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        q = ((c3 * mid + c2) * mid + d0) * mid + a0
        if q > slack:
            sign = 1.0
        elif q < -slack:
            sign = -1.0
        else:
            m2 = mid * mid
            m3 = m2 * mid
            w = 2 * m3
            t = 3 * m2
            p = (w - t + 1) * a0 + (m3 - 2 * m2 + mid) * d0 + (-w + t) * a1 + (m3 - m2) * d1
            sign = 1.0 if p > 0.0 else -1.0 if p < 0.0 else p  # _sign(p): nan never equals s0
        if sign == s0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


#: _root: Horner's value of the cubic and _cubic's differ by less than about 80 eps (|a0| + |a1| +
#: |d0| + |d1|) on [0, 1] (the coefficients' and the sums' round-off, every term at most 7 times that
#: sum); Horner's decides a bisection step only beyond 1024 eps of it, where both have the same sign
_HORNER_SLACK = 1024.0 * 2.0**-52


def hermite_max_quartic(
    t0: float, t1: float, a0: np.ndarray, a1: np.ndarray, d0: np.ndarray, d1: np.ndarray, dd0: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Maximum over [t0, t1] of the quartic through alpha and d(alpha)/dt at both ends and
    d2(alpha)/dt2 at t0, where d0 > 0 >= d1 (module docstring: why not the cubic).

    Parameters
    ----------
    t0, t1 : float
        The step's ends.
    a0, a1, d0, d1 : ndarray
        alpha and d(alpha)/dt at t0 and t1, one per contact.
    dd0 : ndarray
        d2(alpha)/dt2 at t0 (RK4's first stage: the two beads' accelerations), one per contact.

    Returns
    -------
    (alpha_max, t_max) : tuple of ndarray
        The maximum of the quartic H(s) + e s^2 (1 - s)^2 and where it is taken, H the cubic of
        hermite_max: the added term keeps the four end values and sets p''(0) = h^2 dd0
        (e = h^2 dd0 / 2 - b). Found by two Newton steps on p' from the cubic's maximum (e is
        O(h^4) of the cubic's curvature).
    """
    h = t1 - t0
    if a0.size <= _SCALAR_ROOTS:
        rows = zip(a0.tolist(), a1.tolist(), d0.tolist(), d1.tolist(), dd0.tolist(), strict=True)
        out = [max1_quartic(h, *row) for row in rows]
        return np.array([p for p, _ in out]), np.array([t0 + s * h for _, s in out])
    a, b, c = _coefficients(h, a0, a1, d0, d1)
    s = _cubic_argmax(a, b, c)
    e = 0.5 * (h * h * dd0) - b
    for _ in range(2):
        w = s * (1.0 - s)
        g = (3.0 * a * s + 2.0 * b) * s + c + 2.0 * e * w * (1.0 - 2.0 * s)
        gg = 6.0 * a * s + 2.0 * b + 2.0 * e * (1.0 - 6.0 * w)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(gg < 0.0, s - g / gg, s)
        s = np.maximum(np.fmin(s, 1.0), 0.0)
    w = s * (1.0 - s)
    return ((a * s + b) * s + c) * s + a0 + e * (w * w), t0 + s * h


def max1_quartic(h: float, x0: float, x1: float, y0: float, y1: float, z0: float) -> tuple[float, float]:
    """hermite_max_quartic of one contact on Python floats over a step of length h: (the maximum,
    its fraction s of the step). The same operations in the same order as the numpy path."""
    _, s = max1(h, x0, x1, y0, y1)
    a, b, c = _coefficients(h, x0, x1, y0, y1)
    e = 0.5 * (h * h * z0) - b
    for _ in range(2):
        w = s * (1.0 - s)
        g = (3.0 * a * s + 2.0 * b) * s + c + 2.0 * e * w * (1.0 - 2.0 * s)
        gg = 6.0 * a * s + 2.0 * b + 2.0 * e * (1.0 - 6.0 * w)
        if gg < 0.0:
            s = s - g / gg
        s = 1.0 if not s <= 1.0 else s if s > 0.0 else 0.0  # as np.maximum(np.fmin(s, 1), 0)
    w = s * (1.0 - s)
    return ((a * s + b) * s + c) * s + x0 + e * (w * w), s
