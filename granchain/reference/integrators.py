"""The reference solver's integrators: velocity Verlet, and classical RK4 with event location.

Each advances a ChainState (granchain.reference.state) by one step of the step plan, with the step
load constant over the step (f enters as a_ext, its acceleration of bead 1), and writes the law's
history alpha_max once per accepted step:

* Verlet raises alpha_max to alpha at the step's end, which is what a LAMMPS pair style does at each
  force evaluation, so the two agree step for step.
* RK4 freezes alpha_max over its stages (trial points, not states of the trajectory) and raises it
  after each accepted piece to the maximum of the cubic Hermite interpolant of alpha over the piece,
  so the history misses the true maximum by O(h^4), not O(h^2). With event location a step that
  crosses a kink of the contact law (law.kinks, law.turn_level) is split there, so that no piece
  integrates across a jump in the force's derivatives.

An integrator also says what "the contact forces now" are for outputs (contact_forces): Verlet's are
the last force evaluation, at the step's end, which is what LAMMPS dumps.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np

from granchain.physics.laws import ContactLaw
from granchain.reference.hermite import _root, hermite_max, hermite_root, max1
from granchain.reference.state import ChainState

EPS = float(np.finfo(float).eps)
# RK4 event location (first_kink_crossing): a contact closer to a kink of its law than
# KINK_ROUNDOFF eps (|u_i| + |u_i+1| + |kink|) is at it (an overlap is a difference of two
# displacements and carries their round-off)
KINK_ROUNDOFF = 16.0

#: RK4 with event location and no dashpot steps between two stacked (u; v) buffers instead of saving
#: and restoring the state (RK4Integrator._lean_step); False: the plain save-and-restore step (the
#: tests compare the two bit for bit)
_LEAN = True

#: called after every piece of an RK4 step that event location split off, but the last: (state, t0, t1)
SplitHook = Callable[[ChainState, float, float], None]
#: (s, contacts, kind): kink crossings found in a piece, s the fraction of the piece per contact
Crossings = list[tuple[np.ndarray, np.ndarray, str]]


class EventLocationError(RuntimeError):
    """RK4 event location could not get past a kink: the step was split more than the cap allows."""


class Integrator:
    """What the driver asks of an integrator (granchain.reference.solver._drive)."""

    name = ""
    extra_steps = 0  # steps beyond the plan's: rejected and split steps (RK4 event location)

    def start(self, state: ChainState) -> None:
        """The run begins at state (t = 0)."""

    def start_segment(self, state: ChainState, seg_start: float) -> None:
        """A segment of the step plan begins at seg_start (a new LAMMPS run in the deck)."""

    def step(
        self, state: ChainState, t0: float, t1: float, h: float, a_ext: float, on_split: Sequence[SplitHook]
    ) -> float:
        """Advance from t0 to t1; return where the step's last piece began (t0 unless it was split).

        h is the step's length as the plan has it (timestep, or the segment's last step); RK4 with
        event location steps t1 - t0 instead, which may differ from h in the last bit (as it always did).
        on_split: called after every piece but the last of a split step (the RK4 peak tracking).
        """
        raise NotImplementedError

    def contact_forces(self, state: ChainState) -> np.ndarray:
        """The contact forces of the current state, as histories and snapshots record them (a new array)."""
        raise NotImplementedError


class VerletIntegrator(Integrator):
    """Velocity Verlet as LAMMPS's fix nve runs it: half kick, drift, force, half kick."""

    name = "verlet"

    def __init__(self, state: ChainState) -> None:
        self.history = state.law.history
        self.load_bead = state.load_bead  # where the external load acts (a_ext): bead 1
        self.kick = np.empty(state.n)  # h/2 a and h v, into a preallocated buffer
        self.alpha = np.empty(state.n - 1)  # the overlaps at the step's end (the history)
        self.u_left, self.u_right = state.u[:-1], state.u[1:]
        self.consts: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def start_segment(self, state: ChainState, seg_start: float) -> None:
        if state.gamma and seg_start > 0.0:
            # LAMMPS starts each run by recomputing forces with the full-step velocities; the dashpot
            # is the only force that notices, and the reference does the same to stay step for step
            state.accel(state.u, state.a_int, state.v)

    def step(
        self, state: ChainState, t0: float, t1: float, h: float, a_ext: float, on_split: Sequence[SplitHook]
    ) -> float:
        u, v, a_int, kick = state.u, state.v, state.a_int, self.kick
        half = 0.5 * h
        consts = self.consts.get(h)
        if consts is None:  # the plan's step and a segment's last: 0-d arrays, cheaper operands than floats
            consts = self.consts[h] = (np.array(half), np.array(h))
        half_h, h_ = consts
        add, mul = _add, _multiply  # outputs by position (RK4Integrator.rk4)
        mul(a_int, half_h, kick)
        add(v, kick, v)
        if a_ext:  # (x + 0.0 is x: an unloaded segment skips it)
            v[self.load_bead] += half * a_ext
        mul(v, h_, kick)
        add(u, kick, u)
        power = state.accel(u, a_int, v)  # the dashpot sees the half-step velocity, as in LAMMPS
        if power:
            state.dash_energy += h * power
        mul(a_int, half_h, kick)
        add(v, kick, v)
        if a_ext:
            v[self.load_bead] += half * a_ext
        if self.history:
            _subtract(self.u_left, self.u_right, self.alpha)
            state.law.update_history(state.alpha_hist, self.alpha)
        return t0

    def contact_forces(self, state: ChainState) -> np.ndarray:
        return state.fc.copy()  # the last force evaluation, at this step's end: what LAMMPS dumps


class RK4Integrator(Integrator):
    """Classical RK4 on (u, v), with the step split where a contact crosses a kink of its law.

    Parameters
    ----------
    state : ChainState
        The run's state (sizes, dashpot).
    timestep : float
        The plan's step: a crossing closer than 1e-6 of it to a piece's start is not split off.
    event_location : bool
        Split steps at kinks (else every step is one piece of length h).
    max_splits : int
        The most splits of one step before EventLocationError: a bug, not a slow run.
    """

    name = "rk4"

    def __init__(self, state: ChainState, timestep: float, event_location: bool, max_splits: int) -> None:
        n = state.n
        self.load_bead = state.load_bead  # where the external load acts (a_ext): bead 1
        self.timestep = timestep
        self.event_location = event_location
        self.max_splits = max_splits
        self.extra_steps = 0
        self.k1v, self.k2v, self.k3v, self.k4v = (np.empty(n) for _ in range(4))
        self.ut = np.empty(n)
        self.hv = np.empty(n)  # h/2 v, and the update's products
        self.ut2, self.tmp = np.empty(n), np.empty(n)
        # the factors of rk4 per step length: a step is t1 - t0 with event location, which takes a
        # handful of values a few ulps apart (the times are sums of steps), each thousands of times
        self.consts: dict[float, tuple[np.ndarray, ...]] = {}
        self.scratch = tuple(np.zeros(()) for _ in range(6))
        self.vt = np.empty(n) if state.gamma else None  # stage velocities, needed only by the dashpot
        self.u_save, self.v_save = np.empty(n), np.empty(n)
        self.views = (state.u[:-1], state.u[1:], state.v[:-1], state.v[1:])  # (u and v change in place)
        self.history = state.law.history
        self.history_floor: np.ndarray | None = None
        # equal masses (ChainState.net_force): the stages' k are net forces and 1/m is in the factors
        self.net_force = None if state.gamma else state.net_force
        self.inv_m = state.uniform_inv_m if self.net_force is not None else 1.0
        # a law without history has the same kinks all run (its alpha_max is never written): ask once
        # stages 2-4 evaluate the forces inline (make_accel's parts) at the stage positions ut, ut2
        accel = self.net_force or state.accel
        self.parts = None if state.gamma else getattr(accel, "parts", None)
        self.stage_views = ((self.ut[:-1], self.ut[1:]), (self.ut2[:-1], self.ut2[1:]))
        law = state.law
        self.fixed_kinks = None if law.history else (law.kinks(state.alpha_hist), law.turn_level(state.alpha_hist))
        # the lean step (lean_step): (u, v) lives in one of two pairs of buffers, the state's own and a
        # second; a try writes the other pair, which becomes the state's when the try is accepted (a
        # rejected try leaves the state as it was: nothing to save or restore). Not with a dashpot (its
        # stages update u and v in place). (Stacking u and v as the rows of one (2, N) array to take
        # overlaps and rates in one call costs more: numpy walks the strided views slower than two calls.)
        self.lean = _LEAN and event_location and not state.gamma
        if self.lean:
            self.pairs = ((state.u, state.v), (np.empty(n), np.empty(n)))
            self.pair_views = tuple((u[:-1], u[1:], v[:-1], v[1:]) for u, v in self.pairs)
            self.current = 0

    def start(self, state: ChainState) -> None:
        # alpha_max follows the running maximum of the overlap since t = 0, whose start is the t = 0
        # overlap (precompressed: a few units of round-off off the static alpha_max); it joins the
        # history at the first step's end, so the first step sees the history the problem set
        self.history_floor = state.alpha_now.copy() if self.history else None

    def step(
        self, state: ChainState, t0: float, t1: float, h: float, a_ext: float, on_split: Sequence[SplitHook]
    ) -> float:
        if not self.event_location:
            self.rk4(state, h, a_ext)
            self.end_piece(state, t0, t1, state.u[:-1] - state.u[1:], state.v[:-1] - state.v[1:])
            return t0
        if self.lean:
            return self.lean_step(state, t0, t1, a_ext, on_split)
        return self.located_step(state, t0, t1, a_ext, on_split)

    def located_step(
        self, state: ChainState, t0: float, t1: float, a_ext: float, on_split: Sequence[SplitHook]
    ) -> float:
        """One plan step with event location: try the rest of the step; while it crosses a kink, take
        the piece up to the first crossing instead and try again from there. Returns the last piece's start."""
        u, v = state.u, state.v
        u_left, u_right, v_left, v_right = self.views
        t = t0
        splits = 0
        while True:
            h_sub = t1 - t
            np.copyto(self.u_save, u)
            np.copyto(self.v_save, v)
            e_save = state.dash_energy
            self.rk4(state, h_sub, a_ext)
            a_new, adot_new = np.subtract(u_left, u_right), np.subtract(v_left, v_right)
            piece = Piece(state.alpha_now, state.adot_now, a_new, adot_new, self.u_save, u, h_sub)
            crossing = first_kink_crossing(state.law, state.alpha_hist, piece, self.timestep, self.fixed_kinks)
            if crossing is None:
                break
            s_ev, contact, kind = crossing
            splits += 1
            if splits > self.max_splits:
                raise self.too_many_splits(state, t, h_sub, crossing)
            np.copyto(u, self.u_save)
            np.copyto(v, self.v_save)
            state.dash_energy = e_save
            # the piece starts where the rejected try did, with the same history: its first stage too
            self.rk4(state, s_ev * h_sub, a_ext, same_start=True)
            self.extra_steps += 2  # the rejected try and the split piece
            t_split = t + s_ev * h_sub
            self.end_piece(state, t, t_split, np.subtract(u_left, u_right), np.subtract(v_left, v_right))
            for hook in on_split:
                hook(state, t, t_split)
            t = t_split
        self.end_piece(state, t, t1, a_new, adot_new)
        return t

    def too_many_splits(self, state: ChainState, t: float, h_sub: float, crossing: tuple) -> EventLocationError:
        s_ev, contact, kind = crossing
        return EventLocationError(
            f"RK4 event location split step {state.step + 1} (t = {t:.6g} s, time step "
            f"{self.timestep:.6g} s) {self.max_splits} times and still finds a kink: contact "
            f"{contact + 1} ({kind}) at s = {s_ev:.3g} of "
            f"the remaining {h_sub:.3g} s. This is a bug of the reference solver: please "
            "report it with the scene; meanwhile method 'verlet' (--method verlet) runs "
            "without event location"
        )

    def lean_step(self, state: ChainState, t0: float, t1: float, a_ext: float, on_split: Sequence[SplitHook]) -> float:
        """located_step over the two stacked buffers (see __init__): the same pieces, the same numbers.

        A try writes the pair of buffers the state is not in; accepted, the state moves there (state.u
        and state.v are that pair), rejected, it is left behind. The contacts whose rate falls from > 0
        to <= 0 (end_piece's turning screen, a superset of the event location's turn screen) are
        screened once a try and handed to both."""
        law, hist, timestep, fixed = state.law, state.alpha_hist, self.timestep, self.fixed_kinks
        t = t0
        splits = 0
        cur = self.current
        while True:
            h_sub = t1 - t
            nxt = 1 - cur
            out = self.pairs[nxt]
            # (alpha_now: the overlaps of the state's u, from the last piece's end or from t = 0)
            self.rk4(state, h_sub, a_ext, False, out, state.alpha_now, t != t0)
            u_left, u_right, v_left, v_right = self.pair_views[nxt]
            a_new, adot_new = _subtract(u_left, u_right), _subtract(v_left, v_right)
            adot_old = state.adot_now
            turning = (_greater(adot_old, _ZERO) & _less_equal(adot_new, _ZERO)).nonzero()[0]
            piece = Piece(state.alpha_now, adot_old, a_new, adot_new, state.u, out[0], h_sub)
            crossing = first_kink_crossing(law, hist, piece, timestep, fixed, turning)
            if crossing is None:
                break
            splits += 1
            if splits > self.max_splits:
                raise self.too_many_splits(state, t, h_sub, crossing)
            s_ev = crossing[0]
            # the piece starts where the rejected try did, with the same history: its first stage too
            self.rk4(state, s_ev * h_sub, a_ext, True, out, None, True)
            self.extra_steps += 2  # the rejected try and the split piece
            t_split = t + s_ev * h_sub
            state.u, state.v = out
            cur = self.current = nxt
            self.end_piece(state, t, t_split, _subtract(u_left, u_right), _subtract(v_left, v_right))
            for hook in on_split:
                hook(state, t, t_split)
            t = t_split
        state.u, state.v = out
        self.current = nxt
        self.end_piece(state, t, t1, a_new, adot_new, turning)
        return t

    def rk4(
        self,
        state: ChainState,
        h: float,
        a_ext: float,
        same_start: bool = False,
        out: tuple[np.ndarray, np.ndarray] | None = None,
        overlaps: np.ndarray | None = None,
        once: bool = False,
    ) -> None:
        """Classical RK4 on (u, v) in place; the external load is constant over the step.

        same_start: (u, v) and alpha_max are those of the last call's start (a step split by event
        location), so its first stage k1v, still in its buffer, is this one's (without a dashpot,
        whose first stage also gives a power): the same numbers without the force evaluation.
        out: (u, v) of the step's end go there instead of into the state's u and v (lean_step; not
        with a dashpot). overlaps: u[:-1] - u[1:] of the state (its alpha_now, lean_step), which the
        first stage's force evaluation then takes instead of subtracting again (the same numbers).
        once: h is a length seen once (a split piece, the rest of a split step): its factors go into
        scratch 0-d arrays instead of the cache (consts).

        Every product lands in a preallocated buffer (its out, by position), and what two stages need is
        taken once: the stage 2 position P = u + h/2 v, from which stage 3's is P + h^2/4 k1v and
        Q = P + h/2 v = u + h v, from which stage 4's and the new u are; 15 numpy calls besides the
        four force evaluations (on a short chain their per-call cost, not the arithmetic, is the price).
        The step's scalar factors are 0-d arrays, made once per step length (consts): numpy takes a
        Python float operand at about half again the cost of the whole call on a short chain.
        """
        u, v, gamma = state.u, state.v, state.gamma
        accel = self.net_force or state.accel
        k1v, k2v, k3v, k4v, hv = self.k1v, self.k2v, self.k3v, self.k4v, self.hv
        consts = None if once else self.consts.get(h)
        if consts is None:
            consts = self.factors(h, once)
        half_h, quarter_h2, h_, half_h2, h2_6, h_6 = consts
        add, mul = _add, _multiply
        if gamma:
            self.rk4_dashpot(state, h, a_ext, consts)
            return
        if a_ext and self.net_force is not None:
            a_ext = a_ext / self.inv_m  # the load's force (the k are forces)
        if not same_start:
            if overlaps is None:
                accel(u, k1v, v)
            else:
                accel(u, k1v, v, overlaps)
            if a_ext:  # (x + 0.0 is x: an unloaded segment skips the four)
                k1v[self.load_bead] += a_ext
        b2, t = self.ut2, self.tmp
        if self.parts is None:
            self.stages_by_calls(accel, u, v, a_ext, consts)
        else:
            self.stages_written_out(u, v, a_ext, consts)
        # u += h/6 (k1u + 2 k2u + 2 k3u + k4u) with k1u = v, k2u = v + h/2 k1v, k3u = v + h/2 k2v,
        # k4u = v + h k3v  =>  u = Q + h^2/6 S, S = k1v + k2v + k3v; v += h/6 (S + (k2v + k3v) + k4v)
        add(k2v, k3v, t)
        add(t, k1v, hv)  # S (hv is free)
        add(hv, t, t)
        add(t, k4v, t)
        mul(hv, h2_6, hv)
        u_out, v_out = (u, v) if out is None else out
        add(b2, hv, u_out)
        mul(t, h_6, t)
        add(v, t, v_out)

    def factors(self, h: float, once: bool) -> tuple[np.ndarray, ...]:
        """rk4's scalar factors of a step of length h, as 0-d arrays: cached per length, or for a
        length seen once (lean_step's split pieces and retries) in the scratch ones."""
        c = self.inv_m  # (1.0 when the k are accelerations: x * 1.0 is x)
        values = (0.5 * h, 0.25 * h * h * c, h, 0.5 * h * h * c, h * h / 6.0 * c, h / 6.0 * c)
        if once:
            for x, value in zip(self.scratch, values, strict=True):
                x[()] = value
            return self.scratch
        if len(self.consts) >= 32:  # split pieces: lengths seen once
            self.consts.clear()
        consts = self.consts[h] = tuple(np.array(x) for x in values)
        return consts

    def stages_written_out(self, u: np.ndarray, v: np.ndarray, a_ext: float, consts: tuple[np.ndarray, ...]) -> None:
        """rk4's stages 2-4 with the force evaluations written out: accel's steps (make_accel's parts),
        the same calls on the same buffers, without a Python call and the views lookup each."""
        alpha, ftmp, fc, fp_left, fp_right, force_into, clip, zero, inv_m, hist = self.parts
        (b1_left, b1_right), (b2_left, b2_right) = self.stage_views
        k1v, k2v, k3v, k4v, hv = self.k1v, self.k2v, self.k3v, self.k4v, self.hv
        b1, b2, t = self.ut, self.ut2, self.tmp
        half_h, quarter_h2, _, half_h2, _, _ = consts
        add, mul, sub = _add, _multiply, _subtract
        mul(v, half_h, hv)
        add(u, hv, b1)  # stage 2 position P = u + h/2 v
        sub(b1_left, b1_right, alpha)
        if clip:
            np.maximum(alpha, zero, out=alpha)
        force_into(alpha, hist, fc, ftmp)
        sub(fp_left, fp_right, k2v)
        if inv_m is not None:
            mul(k2v, inv_m, k2v)
        if a_ext:
            k2v[self.load_bead] += a_ext
        mul(k1v, quarter_h2, t)
        add(b1, t, b2)  # stage 3: u + h/2 (v + h/2 k1v) = P + h^2/4 k1v
        sub(b2_left, b2_right, alpha)
        if clip:
            np.maximum(alpha, zero, out=alpha)
        force_into(alpha, hist, fc, ftmp)
        sub(fp_left, fp_right, k3v)
        if inv_m is not None:
            mul(k3v, inv_m, k3v)
        if a_ext:
            k3v[self.load_bead] += a_ext
        add(b1, hv, b2)  # Q = u + h v
        mul(k2v, half_h2, t)
        add(b2, t, b1)  # stage 4: u + h (v + h/2 k2v) = Q + h^2/2 k2v
        sub(b1_left, b1_right, alpha)
        if clip:
            np.maximum(alpha, zero, out=alpha)
        force_into(alpha, hist, fc, ftmp)
        sub(fp_left, fp_right, k4v)
        if inv_m is not None:
            mul(k4v, inv_m, k4v)
        if a_ext:
            k4v[self.load_bead] += a_ext

    def stages_by_calls(
        self,
        accel: Callable[..., float],
        state_u: np.ndarray,
        v: np.ndarray,
        a_ext: float,
        consts: tuple[np.ndarray, ...],
    ) -> None:
        """rk4's stages 2-4 with a force evaluation that has no parts to write out: by calls."""
        k1v, k2v, k3v, k4v, hv = self.k1v, self.k2v, self.k3v, self.k4v, self.hv
        b1, b2, t = self.ut, self.ut2, self.tmp
        half_h, quarter_h2, _, half_h2, _, _ = consts
        add, mul = _add, _multiply
        mul(v, half_h, hv)
        add(state_u, hv, b1)  # stage 2 position P = u + h/2 v
        accel(b1, k2v, None)
        if a_ext:
            k2v[self.load_bead] += a_ext
        mul(k1v, quarter_h2, t)
        add(b1, t, b2)  # stage 3: u + h/2 (v + h/2 k1v) = P + h^2/4 k1v
        accel(b2, k3v, None)
        if a_ext:
            k3v[self.load_bead] += a_ext
        add(b1, hv, b2)  # Q = u + h v
        mul(k2v, half_h2, t)
        add(b2, t, b1)  # stage 4: u + h (v + h/2 k2v) = Q + h^2/2 k2v
        accel(b1, k4v, None)
        if a_ext:
            k4v[self.load_bead] += a_ext

    def rk4_dashpot(self, state: ChainState, h: float, a_ext: float, consts: tuple[np.ndarray, ...]) -> None:
        """rk4 with a dashpot: the stage velocities too (the dashpot force), and its energy."""
        u, v, accel = state.u, state.v, state.accel
        k1v, k2v, k3v, k4v, ut, vt, hv = self.k1v, self.k2v, self.k3v, self.k4v, self.ut, self.vt, self.hv
        half_h, quarter_h2, h_, half_h2, h2_6, h_6 = consts
        power = 0.0
        power += accel(u, k1v, v)
        k1v[self.load_bead] += a_ext
        np.multiply(v, half_h, out=hv)
        np.add(hv, u, out=ut)
        np.multiply(k1v, half_h, out=vt)
        vt += v
        power += 2.0 * accel(ut, k2v, vt)
        k2v[self.load_bead] += a_ext
        # stage 3 position: u + h/2 (v + h/2 k1v)
        np.multiply(k1v, quarter_h2, out=ut)
        ut += u
        ut += hv
        np.multiply(k2v, half_h, out=vt)
        vt += v
        power += 2.0 * accel(ut, k3v, vt)
        k3v[self.load_bead] += a_ext
        # stage 4 position: u + h (v + h/2 k2v)
        np.multiply(v, h_, out=hv)
        np.multiply(k2v, half_h2, out=ut)
        ut += u
        ut += hv
        np.multiply(k3v, h_, out=vt)
        vt += v
        power += accel(ut, k4v, vt)
        k4v[self.load_bead] += a_ext
        state.dash_energy += h / 6.0 * power  # dashpot energy with the method's own weights
        np.add(k1v, k2v, out=ut)
        ut += k3v
        u += hv
        np.multiply(ut, h2_6, out=hv)
        u += hv
        ut += k2v
        ut += k3v
        ut += k4v
        np.multiply(ut, h_6, out=hv)
        v += hv

    def end_piece(
        self,
        state: ChainState,
        t0: float,
        t1: float,
        alpha_new: np.ndarray,
        adot_new: np.ndarray,
        turning: np.ndarray | None = None,
    ) -> None:
        """Accept the piece [t0, t1]: its dense output into the state (overlaps and rates at its end,
        the contacts that turned inside it and their Hermite maxima), and the history raised to them.
        turning: the contacts whose rate went from > 0 to <= 0, if the caller screened them already."""
        alpha_old, adot_old = state.alpha_now, state.adot_now
        if turning is None:
            turning = (np.greater(adot_old, _ZERO) & np.less_equal(adot_new, _ZERO)).nonzero()[0]
        peak = alpha_new
        if not turning.size:
            p = tp = _EMPTY
        elif turning.size <= _SCALAR_CONTACTS:
            # a handful turn: on Python floats (numpy calls on a few elements cost more than the
            # arithmetic), the same operations as below: hermite_max's _max_scalar, np.maximum
            h = t1 - t0
            kept, ps, ts = [], [], []
            for i in turning.tolist():
                x1 = alpha_new.item(i)
                if x1 > 0.0:  # in contact
                    pk, sk = max1(h, alpha_old.item(i), x1, adot_old.item(i), adot_new.item(i))
                    kept.append(i)
                    ps.append(pk)
                    ts.append(t0 + sk * h)
            turning, p, tp = np.array(kept, dtype=turning.dtype), np.array(ps), np.array(ts)
            if kept and self.history:
                peak = alpha_new.copy()
                for i, pk in zip(kept, ps, strict=True):
                    x1 = alpha_new.item(i)
                    peak[i] = pk if (pk > x1 or pk != pk) else x1  # np.maximum(x1, pk): a nan wins
        else:
            turning = turning[alpha_new[turning] > 0.0]  # in contact
            if turning.size:
                p, tp = hermite_max(
                    t0, t1, alpha_old[turning], alpha_new[turning], adot_old[turning], adot_new[turning]
                )
                if self.history:
                    peak = alpha_new.copy()
                    peak[turning] = np.maximum(alpha_new[turning], p)
            else:
                p = tp = _EMPTY
        state.alpha_now, state.adot_now = alpha_new, adot_new
        state.turning, state.turn_peak, state.turn_time = turning, p, tp
        if not self.history:
            return
        # alpha_max = max(alpha_max, the piece's largest overlap): its end, or the interpolant's
        # maximum where the overlap turned inside it (peak; whole-chain arrays: the law may hold
        # per-contact ones)
        state.law.update_history(state.alpha_hist, peak)
        if self.history_floor is not None:
            state.law.update_history(state.alpha_hist, self.history_floor)
            self.history_floor = None

    def contact_forces(self, state: ChainState) -> np.ndarray:
        law, u, v = state.law, state.u, state.v
        alpha = u[:-1] - u[1:]
        f = law.force(alpha, state.alpha_hist)
        if state.gamma:
            f = np.where(alpha > 0.0, np.maximum(f + state.gamma * (v[:-1] - v[1:]), 0.0), f)
        return f


_EMPTY = np.empty(0)
_add, _multiply, _subtract, _less, _greater, _less_equal = (
    np.add,
    np.multiply,
    np.subtract,
    np.less,
    np.greater,
    np.less_equal,
)  # RK4Integrator.rk4: outputs by position, ~0.15 us a call cheaper than out=
_ZERO = np.array(0.0)  # 0-d: a cheaper operand than the Python float (RK4Integrator.rk4)


# ---- event location: where a tentative RK4 piece first meets a kink of the contact law


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
