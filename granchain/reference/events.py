"""RK4 event location: where a tentative piece first meets a kink of the contact law.

A piece's overlaps and rates at both ends give each contact a cubic Hermite interpolant; a contact
crossing one of its law's kinks (ContactLaw.kinks) or turning above its turn level is located on it.
The screens leave a handful of contacts or none, which are tested on Python floats
(first_crossing_scalar), or on arrays when many remain (kink_roots, turns_above, earliest).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from granchain.physics.laws import ContactLaw
from granchain.reference.hermite import _root, hermite_max, hermite_root, max1
from granchain.reference.stepping import _ZERO, _greater, _less

EPS = float(np.finfo(float).eps)
# RK4 event location (first_kink_crossing): a contact closer to a kink of its law than
# KINK_ROUNDOFF eps (|u_i| + |u_i+1| + |kink|) is at it (an overlap is a difference of two
# displacements and carries their round-off)
KINK_ROUNDOFF = 16.0

#: (s, contacts, kind): kink crossings found in a piece, s the fraction of the piece per contact
Crossings = list[tuple[np.ndarray, np.ndarray, str]]


class Piece(NamedTuple):
    """A tentative RK4 piece of length h: each overlap and its rate at both ends, and the displacements
    at both ends (the overlaps' round-off, roundoff)."""

    a0: np.ndarray
    d0: np.ndarray
    a1: np.ndarray
    d1: np.ndarray
    u0: np.ndarray
    u1: np.ndarray
    h: float


def roundoff(piece: Piece, idx: np.ndarray) -> np.ndarray:
    """KINK_ROUNDOFF eps (|u_i| + |u_i+1|) at both ends of the piece, for contacts idx: an overlap is
    the difference of two displacements, and carries their round-off. Only for the few contacts a
    screen left (crossing, turns_above): the same numbers as over the whole chain, element by element."""
    u0, u1, j = piece.u0, piece.u1, idx + 1
    return KINK_ROUNDOFF * EPS * (np.abs(u0[idx]) + np.abs(u0[j]) + np.abs(u1[idx]) + np.abs(u1[j]))


def _full(x, shape: tuple[int, ...]) -> np.ndarray:
    """x broadcast to one value per contact (a law may give a scalar); an array of that shape as it is."""
    if isinstance(x, np.ndarray) and x.shape == shape:
        return x
    return np.broadcast_to(x, shape)


def first_kink_crossing(
    law: ContactLaw,
    alpha_hist: np.ndarray,
    piece: Piece,
    timestep: float,
    fixed: tuple[Sequence, np.ndarray | None] | None = None,
    turning: np.ndarray | None = None,
) -> tuple[float, int, str] | None:
    """Where in the piece the first contact meets a kink of its force law, or None.

    Kinks (the law's kinks(alpha_max): Hertz zero overlap, where F'' is infinite; bilinear zero force
    at beta alpha_max and reloading meeting alpha_max; Thornton's yield, ...) and a turn from rising
    to falling above the law's turn_level (a new alpha_max: the slope changes to the unloading
    curve's). Located on the cubic Hermite interpolant of alpha over the piece.

    A contact counts only if it crosses the kink by more than its overlap's round-off (both ends of
    the piece farther than KINK_ROUNDOFF eps (|u_i| + |u_i+1| + |level|) from it, a turn's maximum
    that far above the level): within that it is at the kink already, the slope change acts over no
    overlap that double precision can hold, and a step split there need not move the overlap at all,
    so the same crossing would be found again after the split. A crossing within 1e-6 of the step
    from either end is not split either (that contact only).

    fixed: (kinks, turn_level) when they do not depend on alpha_max (a law without history), else
    None: asked of the law. turning: the contacts whose rate goes from > 0 to <= 0 over the piece, if
    the caller screened them (RK4Integrator.lean_step, for end_piece): the turn screen's contacts are
    those of them whose rate ends below 0.

    Returns
    -------
    (s, contact, kind) or None
        The fraction s of the piece, the 0-based contact and the kink's name (the split cap's error).
    """
    # the screens (a few numpy calls over the chain) leave a handful of contacts or none; those are
    # tested on Python floats (first_crossing_scalar: numpy calls on arrays of a few elements cost
    # more than the arithmetic), unless a screen leaves many (then all on arrays, as before)
    a0, a1, shape = piece.a0, piece.a1, piece.a0.shape
    if fixed is None:  # (law.kink_screens: the loop below over law.kinks(alpha_hist), maybe with fewer calls)
        kinks, turn_level = None, law.turn_level(alpha_hist)
        screened = law.kink_screens(alpha_hist, a0, a1)
    else:
        kinks, turn_level = fixed
        screened = []
        for kink in kinks:
            level = _full(kink.level, shape)
            idx = (_less(a0, level) ^ _less(a1, level)).nonzero()[0]
            if idx.size:
                screened.append((kink, level, idx))
    few = True  # every screen left at most _SCALAR_CONTACTS
    for _, _, idx in screened:
        few = few and idx.size <= _SCALAR_CONTACTS
    turn = None
    if turn_level is not None:
        if turning is None:
            turn = (_greater(piece.d0, _ZERO) & _less(piece.d1, _ZERO)).nonzero()[0]
        elif not turning.size:
            turn = turning
        elif turning.size <= _SCALAR_CONTACTS:  # (a handful: Python floats)
            d1 = piece.d1
            turn = np.array([i for i in turning.tolist() if d1.item(i) < 0.0], dtype=np.intp)
        else:
            turn = turning[_less(piece.d1[turning], _ZERO)]
    if turn is None or turn.size <= _SCALAR_CONTACTS:
        if not screened and (turn is None or not turn.size):
            return None  # (most pieces: nothing near a kink)
        if few:
            return first_crossing_scalar(screened, turn, turn_level, piece, timestep)
    found = kink_roots(law.kinks(alpha_hist) if kinks is None else kinks, piece)
    if turn_level is not None:
        found += turns_above(turn_level, piece)
    return earliest(found, piece.h, timestep) if found else None


#: first_kink_crossing tests the contacts its screens leave on Python floats up to this many per screen
_SCALAR_CONTACTS = 16
_TOL = KINK_ROUNDOFF * EPS  # (the same product as roundoff's and crossing's)
_INSIDE = 1.0 - 1e-6


def first_crossing_scalar(
    screened: list, turn: np.ndarray | None, turn_level: np.ndarray | None, piece: Piece, timestep: float
) -> tuple[float, int, str] | None:
    """first_kink_crossing's tests of the screened contacts on Python floats, contact by contact:
    the same operations in the same order as crossing, kink_roots, turns_above and earliest (so the
    same crossing, to the bit), without the numpy calls on arrays of a few elements.

    screened: (kink, its level per contact, the contacts whose ends lie on both sides of it) per
    kink; turn: the contacts whose rate goes from > 0 to < 0 (None: the law has no turn level)."""
    a0, d0, a1, d1, u0, u1, h = piece
    s_min = 1e-6 * timestep
    best_s, best_i, best_kind = math.inf, -1, ""
    for kink, level, idx in screened:
        where = None if kink.where is None else _full(kink.where, a0.shape)
        for i in idx.tolist():
            lv = level.item(i)
            x0 = a0.item(i)
            if kink.from_below and not x0 < lv:
                continue
            x1 = a1.item(i)
            tol = _TOL * (abs(u0.item(i)) + abs(u0.item(i + 1)) + abs(u1.item(i)) + abs(u1.item(i + 1))) + _TOL * abs(
                lv
            )
            lo, hi = lv - tol, lv + tol
            if not ((x0 < lo and x1 > hi) or (x0 > hi and x1 < lo)):
                continue
            if where is not None and not where.item(i):
                continue
            s = _root(x0 - lv, x1 - lv, h * d0.item(i), h * d1.item(i))
            if s * h >= s_min and s <= _INSIDE and s < best_s:
                best_s, best_i, best_kind = s, i, kink.kind
    if turn is not None and turn.size:
        levels = _full(turn_level, a0.shape)
        for i in turn.tolist():
            x1 = a1.item(i)
            if not x1 > 0.0:
                continue
            x0 = a0.item(i)
            p, s = max1(1.0, x0, x1, d0.item(i) * h, d1.item(i) * h)
            lv = levels.item(i)
            r = _TOL * (abs(u0.item(i)) + abs(u0.item(i + 1)) + abs(u1.item(i)) + abs(u1.item(i + 1)))
            if p > lv + r + _TOL * lv and s * h >= s_min and s <= _INSIDE and s < best_s:
                best_s, best_i, best_kind = s, i, "turn above alpha_max"
    return None if best_i < 0 else (best_s, best_i, best_kind)


def crossing(piece: Piece, level: np.ndarray) -> np.ndarray:
    """Contacts that cross `level` (one per contact) from one side to the other, beyond round-off at
    both ends.

    Most pieces cross no kink: a screen of the contacts whose ends lie strictly on both sides of the
    level (a superset: a tolerance is never negative, so beyond it means beyond the level) leaves a
    handful or none, and only those are tested against their round-off.
    """
    a0, a1 = piece.a0, piece.a1
    idx = (np.less(a0, level) ^ np.less(a1, level)).nonzero()[0]
    if not idx.size:
        return idx
    lv, a0, a1 = level[idx], a0[idx], a1[idx]
    tol = roundoff(piece, idx) + KINK_ROUNDOFF * EPS * np.abs(lv)
    below0, above0 = a0 < lv - tol, a0 > lv + tol
    below1, above1 = a1 < lv - tol, a1 > lv + tol
    return idx[(below0 & above1) | (above0 & below1)]


def kink_roots(kinks: Sequence, piece: Piece) -> Crossings:
    """(s, contacts, kind) of every kink some contact crosses in the piece (s: the first root per contact)."""
    found = []
    shape = piece.a0.shape
    for kink in kinks:
        level = _full(kink.level, shape)
        idx = crossing(piece, level)
        if not idx.size:
            continue
        if kink.from_below:
            idx = idx[piece.a0[idx] < level[idx]]
        if kink.where is not None:
            idx = idx[_full(kink.where, shape)[idx]]
        if idx.size:
            lv = level[idx]
            s = hermite_root(piece.a0[idx] - lv, piece.a1[idx] - lv, piece.h * piece.d0[idx], piece.h * piece.d1[idx])
            found.append((s, idx, kink.kind))
    return found


def turns_above(turn_level: np.ndarray, piece: Piece) -> Crossings:
    """(s, contacts, kind) of the contacts whose overlap turns inside the piece above the turn level
    (beyond round-off): they start unloading on a new curve there."""
    turn = (np.greater(piece.d0, _ZERO) & np.less(piece.d1, _ZERO)).nonzero()[0]
    if turn.size:
        turn = turn[piece.a1[turn] > 0.0]
    if not turn.size:
        return []
    h = piece.h
    p, sp = hermite_max(0.0, 1.0, piece.a0[turn], piece.a1[turn], piece.d0[turn] * h, piece.d1[turn] * h)
    lv = _full(turn_level, piece.a0.shape)[turn]
    loading = p > lv + roundoff(piece, turn) + KINK_ROUNDOFF * EPS * lv
    if not loading.any():
        return []
    return [(sp[loading], turn[loading], "turn above alpha_max")]


def earliest(found: Crossings, h: float, timestep: float) -> tuple[float, int, str] | None:
    """The first crossing of all found that lies inside the piece (not within 1e-6 of either end)."""
    best = None
    for s_arr, idx, kind in found:
        inside = (s_arr * h >= 1e-6 * timestep) & (s_arr <= 1.0 - 1e-6)
        if inside.any():
            j = int(np.argmin(np.where(inside, s_arr, np.inf)))
            if best is None or s_arr[j] < best[0]:
                best = (float(s_arr[j]), int(idx[j]), kind)
    return best
