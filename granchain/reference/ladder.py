"""The crossing-time ladder in the reference solver (granchain.postprocess.fronts defines it; the pair
styles' d2_ladder is the same): per contact, the times its force rose through the rungs
F0 + ladder_level(k), until its leading pulse froze. The peak trackers climb it (observers.py).
"""

from __future__ import annotations

import math

import numpy as np

from granchain.postprocess.fronts import LADDER_SLOTS, ladder_level
from granchain.reference.hermite import hermite_root
from granchain.reference.state import ChainState

#: up to this many contacts crossing a rung in a step, the Verlet climb runs on Python floats
_SCALAR_CONTACTS = 16


class CrossingLadder:
    """Each contact's crossing-time ladder (granchain.postprocess.fronts; the pair styles' d2_ladder):
    the times its force rose through the rungs F0 + ladder_level(k), until its leading pulse froze.

    rows() (contacts, LADDER_SLOTS + 1): rungs crossed, then the ring of the last crossing times. The
    peak tracker climbs it at every step and piece before it looks for maxima, as the pair styles do.
    RK4 keeps each crossing's piece (its ends' overlaps less the rung's, their rates, its start and
    length) and solves the Hermite interpolant for the crossings still in the ring at the end only.
    """

    def __init__(self, state: ChainState, lead_floor: float) -> None:
        m = state.n - 1
        self.f0, self.floor = state.f0, lead_floor
        self.crossed = np.zeros(m, dtype=np.intp)
        self.times = np.zeros((m, LADDER_SLOTS))
        # total force of rung k (the pair styles' arithmetic), as a list and an array, grown as needed
        self.level_list: list[float] = []
        self.grow(8 * LADDER_SLOTS)
        self.screen = np.empty(m, dtype=bool)
        self.law = state.law.per_contact(m)
        # the next rung of each contact as a total force and (RK4) as the overlap the virgin curve
        # carries it at; inf once the leading pulse froze
        self.next_force = np.full(m, self.levels[0])
        self.next_alpha: np.ndarray | None = None
        self.a_prev, self.d_prev = state.alpha_now.copy(), state.adot_now.copy()
        self.pieces: np.ndarray | None = None  # RK4: (m, LADDER_SLOTS, 6) a0, a1, h d0, h d1, t0, h

    def grow(self, k: int) -> None:
        """Rung levels up to rung k at least."""
        have = len(self.level_list)
        if k >= have:
            self.level_list += [self.f0 + ladder_level(j, self.floor) for j in range(have, max(2 * have, k + 1))]
            self.levels = np.asarray(self.level_list)

    def advance(self, ix: np.ndarray) -> np.ndarray:
        """Contacts ix crossed their next rung: count it; the ring slots it takes."""
        k = self.crossed[ix]
        self.crossed[ix] = k + 1
        self.grow(int(k.max()) + 1)
        self.next_force[ix] = self.levels[k + 1]
        return k % LADDER_SLOTS

    def advance1(self, i: int) -> int:
        """advance for one contact on Python numbers: its ring slot."""
        k = self.crossed.item(i)
        self.crossed[i] = k + 1
        self.grow(k + 1)
        self.next_force[i] = self.level_list[k + 1]
        return k % LADDER_SLOTS

    def freeze(self, ix: np.ndarray) -> None:
        """Contacts ix have their leading pulse: their ladders stop."""
        self.next_force[ix] = np.inf
        if self.next_alpha is not None:
            self.next_alpha[ix] = np.inf

    def climb_samples(self, f_prev: np.ndarray, f_now: np.ndarray, t_prev: float, t_now: float) -> None:
        """Verlet: the rungs crossed between two force samples, on the line between them (as climb in
        the pair styles, operation for operation)."""
        ix = np.greater_equal(f_now, self.next_force, out=self.screen).nonzero()[0]
        line_ok = math.isfinite(t_prev)
        if ix.size <= _SCALAR_CONTACTS:  # (mostly: a contact or two cross a rung in a step)
            # advance1 inlined on Python numbers: a contact's next rung is level_list[crossed] (the ladder
            # of a contact in ix is not frozen), so the rung count and the next force are written once
            # per contact, not once per rung
            levels, times, crossed, nxt = self.level_list, self.times, self.crossed, self.next_force
            for i in ix.tolist():
                fc, fp = f_now.item(i), f_prev.item(i)
                k = crossed.item(i)
                level = levels[k]
                while fc >= level:
                    tc = t_now
                    if line_ok and fc > fp and fp < level:
                        tc = t_prev + (level - fp) / (fc - fp) * (t_now - t_prev)
                    times[i, k % LADDER_SLOTS] = tc
                    k += 1
                    if k >= len(levels):
                        self.grow(k)
                        levels = self.level_list
                    level = levels[k]
                crossed[i] = k
                nxt[i] = level
            return
        while ix.size:
            level, fc, fp = self.next_force[ix], f_now[ix], f_prev[ix]
            tc = np.full(ix.size, t_now)
            if line_ok:
                line = (fc > fp) & (fp < level)
                tc[line] = t_prev + (level[line] - fp[line]) / (fc[line] - fp[line]) * (t_now - t_prev)
            self.times[ix, self.advance(ix)] = tc
            ix = ix[f_now[ix] >= self.next_force[ix]]

    def climb_hermite(self, state: ChainState, t0: float, t1: float) -> None:
        """RK4: the rungs crossed over the piece [t0, t1]; each crossing's time is the root of the
        piece's Hermite interpolant of the overlap at the overlap of the rung's force on the virgin
        curve (solved in rows(), for the crossings the ring keeps)."""
        if self.next_alpha is None:
            self.next_alpha = np.asarray(self.law.static_overlap(self.next_force), dtype=float)
            self.pieces = np.zeros((self.crossed.size, LADDER_SLOTS, 6))
        a1, d1 = state.alpha_now, state.adot_now
        ix = np.greater_equal(a1, self.next_alpha, out=self.screen).nonzero()[0]
        h = t1 - t0
        while ix.size:
            lvl = self.next_alpha[ix]
            piece = np.empty((ix.size, 6))
            piece[:, 0] = self.a_prev[ix] - lvl
            piece[:, 1] = a1[ix] - lvl
            piece[:, 2] = h * self.d_prev[ix]
            piece[:, 3] = h * d1[ix]
            piece[:, 4], piece[:, 5] = t0, h
            if ix.size == 1:
                i = ix.item(0)
                self.pieces[i, self.advance1(i)] = piece[0]
            else:
                self.pieces[ix, self.advance(ix)] = piece
            self.next_alpha = np.asarray(self.law.static_overlap(self.next_force), dtype=float)
            ix = ix[a1[ix] >= self.next_alpha[ix]]
        np.copyto(self.a_prev, a1)
        np.copyto(self.d_prev, d1)

    def rows(self) -> np.ndarray:
        """The ladder as the pair styles write it: rungs crossed, then the ring of crossing times."""
        times = self.times
        if self.pieces is not None:  # RK4: the roots of the kept crossings' pieces
            p = self.pieces.reshape(-1, 6)
            kept = np.flatnonzero(p[:, 5] > 0.0)
            s = np.zeros(kept.size)
            bracket = p[kept, 0] < 0.0  # (an overlap at the rung at the piece's start: the start)
            if bracket.any():
                q = p[kept[bracket]]
                s[bracket] = hermite_root(q[:, 0], q[:, 1], q[:, 2], q[:, 3])
            flat = np.zeros(p.shape[0])
            flat[kept] = p[kept, 4] + s * p[kept, 5]
            times = flat.reshape(self.times.shape)
        return np.column_stack([self.crossed.astype(float), times])
