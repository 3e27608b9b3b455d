"""Classical RK4 on (u, v), its steps split where a contact crosses a kink of its law.

The integration and the acceptance of each piece (its dense output, the history raised to the Hermite
maximum); where a tentative piece first meets a kink is granchain.reference.events.
granchain.reference.integrators has the overview.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from granchain.physics.effects.damping import damped_accel
from granchain.reference import events
from granchain.reference.events import Piece, first_kink_crossing
from granchain.reference.hermite import hermite_max_quartic, max1_quartic
from granchain.reference.state import ChainState, with_body_force
from granchain.reference.stepping import (
    _ZERO,
    Integrator,
    SplitHook,
    _add,
    _greater,
    _less_equal,
    _multiply,
    _subtract,
)

#: RK4 with event location and no damping steps between two stacked (u; v) buffers instead of saving
#: and restoring the state (RK4Integrator._lean_step); False: the plain save-and-restore step (the
#: tests compare the two bit for bit)
_LEAN = True

_EMPTY = np.empty(0)


class EventLocationError(RuntimeError):
    """RK4 event location could not get past a kink: the step was split more than the cap allows."""


class RK4Integrator(Integrator):
    """Classical RK4 on (u, v), with the step split where a contact crosses a kink of its law.

    Parameters
    ----------
    state : ChainState
        The run's state (sizes, damping).
    timestep : float
        The plan's step: a crossing closer than 1e-6 of it to a piece's start is not split off.
    event_location : bool
        Split steps at kinks (else every step is one piece of length h).
    max_splits : int
        The most splits of one step before EventLocationError: a bug, not a slow run.
    """

    name = "rk4"

    @classmethod
    def for_run(cls, state: ChainState, timestep: float, event_location: bool, max_splits: int) -> RK4Integrator:
        """RK4 of a run's state, splitting its steps at kinks (event_location) at most max_splits times."""
        return cls(state, timestep, event_location, max_splits)

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
        self.vt = np.empty(n) if state.damped else None  # stage velocities, needed only by damping
        # the damping's forces at the stages: a contact touching and closing counts as closed (the
        # force just after the touch: damped_accel's closing_at_touch)
        p = state.problem
        self.dash_accel = (
            with_body_force(  # (gravity's weight on every bead too)
                damped_accel(
                    p.damping_part,
                    float(p.damping_coefficient),
                    state.law,
                    state.inv_m,
                    state.fp,
                    state.alpha_hist,
                    closing_at_touch=True,
                ),
                p,
                state.inv_m,
            )
            if state.damped
            else None
        )
        self.u_save, self.v_save = np.empty(n), np.empty(n)
        self.views = (state.u[:-1], state.u[1:], state.v[:-1], state.v[1:])  # (u and v change in place)
        self.history = state.law.history
        self.history_floor: np.ndarray | None = None
        # equal masses (ChainState.net_force): the stages' k are net forces and 1/m is in the factors
        self.net_force = None if state.damped else state.net_force
        self.inv_m = state.uniform_inv_m if self.net_force is not None else 1.0
        # a law without history has the same kinks all run (its alpha_max is never written): ask once
        # stages 2-4 evaluate the forces inline (make_accel's parts) at the stage positions ut, ut2
        accel = self.net_force or state.accel
        self.parts = None if state.damped else getattr(accel, "parts", None)
        self.stage_views = ((self.ut[:-1], self.ut[1:]), (self.ut2[:-1], self.ut2[1:]))
        law = state.law
        self.fixed_kinks = None if law.history else (law.kinks(state.alpha_hist), law.turn_level(state.alpha_hist))
        # the lean step (lean_step): (u, v) lives in one of two pairs of buffers, the state's own and a
        # second; a try writes the other pair, which becomes the state's when the try is accepted (a
        # rejected try leaves the state as it was: nothing to save or restore). Not with damping (its
        # stages update u and v in place). (Stacking u and v as the rows of one (2, N) array to take
        # overlaps and rates in one call costs more: numpy walks the strided views slower than two calls.)
        self.lean = _LEAN and event_location and not state.damped
        if self.lean:
            self.pairs = ((state.u, state.v), (np.empty(n), np.empty(n)))
            self.pair_views = tuple((u[:-1], u[1:], v[:-1], v[1:]) for u, v in self.pairs)
            self.current = 0

    def start(self, state: ChainState) -> None:
        """Set the integrator up for a run from this state (the plastic history's floor)."""
        # alpha_max follows the running maximum of the overlap since t = 0, whose start is the t = 0
        # overlap (precompressed: a few units of round-off off the static alpha_max); it joins the
        # history at the first step's end, so the first step sees the history the problem set
        self.history_floor = state.alpha_now.copy() if self.history else None

    def step(
        self, state: ChainState, t0: float, t1: float, h: float, a_ext: float, on_split: Sequence[SplitHook]
    ) -> float:
        """Advance the state from t0 by one step h (to t1), locating the law's kinks inside it.

        Returns the time the step started from (a split step's last piece starts later)."""
        if not self.event_location:
            self.rk4(state, h, a_ext, t0=t0)
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
            e_save = state.damping_energy
            self.rk4(state, h_sub, a_ext, t0=t)
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
            state.damping_energy = e_save
            # the piece starts where the rejected try did, with the same history: its first stage too
            self.rk4(state, s_ev * h_sub, a_ext, same_start=True, t0=t)
            self.extra_steps += 2  # the rejected try and the split piece
            t_split = t + s_ev * h_sub
            self.end_piece(state, t, t_split, np.subtract(u_left, u_right), np.subtract(v_left, v_right))
            for hook in on_split:
                hook(state, t, t_split)
            t = t_split
        self.end_piece(state, t, t1, a_new, adot_new)
        return t

    def too_many_splits(self, state: ChainState, t: float, h_sub: float, crossing: tuple) -> EventLocationError:
        """The error for a step whose event location split it max_splits times (a solver bug)."""
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
            self.rk4(state, h_sub, a_ext, False, out, state.alpha_now, t != t0, t)
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
            self.rk4(state, s_ev * h_sub, a_ext, True, out, None, True, t)
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
        t0: float = 0.0,
    ) -> None:
        """Classical RK4 on (u, v) in place from t0; the external load a_ext is constant over the step,
        and a drive (Integrator.drive, a harmonic load) adds its value at each stage's time: t0 (k1),
        t0 + h/2 (k2, k3), t0 + h (k4), the classical tableau's nodes.

        same_start: (u, v) and alpha_max are those of the last call's start (a step split by event
        location), so its first stage k1v, still in its buffer, is this one's (without damping,
        whose first stage also gives a power): the same numbers without the force evaluation.
        out: (u, v) of the step's end go there instead of into the state's u and v (lean_step; not
        with damping). overlaps: u[:-1] - u[1:] of the state (its alpha_now, lean_step), which the
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
        u, v, damped = state.u, state.v, state.damped
        accel = self.net_force or state.accel
        k1v, k2v, k3v, k4v, hv = self.k1v, self.k2v, self.k3v, self.k4v, self.hv
        consts = None if once else self.consts.get(h)
        if consts is None:
            consts = self.factors(h, once)
        half_h, quarter_h2, h_, half_h2, h2_6, h_6 = consts
        add, mul = _add, _multiply
        a1 = a2 = a4 = a_ext
        if self.drive is not None:
            drive = self.drive
            a1, a2, a4 = a_ext + drive(t0), a_ext + drive(t0 + 0.5 * h), a_ext + drive(t0 + h)
        if damped:
            self.rk4_damped(state, h, (a1, a2, a4), consts)
            return
        if self.net_force is not None and (a1 or a2 or a4):
            a1, a2, a4 = a1 / self.inv_m, a2 / self.inv_m, a4 / self.inv_m  # the load's force (the k are forces)
        if not same_start:
            if overlaps is None:
                accel(u, k1v, v)
            else:
                accel(u, k1v, v, overlaps)
            if a1:  # (x + 0.0 is x: an unloaded segment skips the four)
                k1v[self.load_bead] += a1
        b2, t = self.ut2, self.tmp
        if self.parts is None:
            self.stages_by_calls(accel, u, v, (a2, a4), consts)
        else:
            self.stages_written_out(u, v, (a2, a4), consts)
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

    def stages_written_out(
        self, u: np.ndarray, v: np.ndarray, a_ext: tuple[float, float], consts: tuple[np.ndarray, ...]
    ) -> None:
        """rk4's stages 2-4 with the force evaluations written out: accel's steps (make_accel's parts),
        the same calls on the same buffers, without a Python call and the views lookup each. a_ext: the
        load at the stages' times, (t0 + h/2: stages 2 and 3, t0 + h: stage 4)."""
        a_mid, a_end = a_ext
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
        if a_mid:
            k2v[self.load_bead] += a_mid
        mul(k1v, quarter_h2, t)
        add(b1, t, b2)  # stage 3: u + h/2 (v + h/2 k1v) = P + h^2/4 k1v
        sub(b2_left, b2_right, alpha)
        if clip:
            np.maximum(alpha, zero, out=alpha)
        force_into(alpha, hist, fc, ftmp)
        sub(fp_left, fp_right, k3v)
        if inv_m is not None:
            mul(k3v, inv_m, k3v)
        if a_mid:
            k3v[self.load_bead] += a_mid
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
        if a_end:
            k4v[self.load_bead] += a_end

    def stages_by_calls(
        self,
        accel: Callable[..., float],
        state_u: np.ndarray,
        v: np.ndarray,
        a_ext: tuple[float, float],
        consts: tuple[np.ndarray, ...],
    ) -> None:
        """rk4's stages 2-4 with a force evaluation that has no parts to write out: by calls (a_ext:
        the load at t0 + h/2 and at t0 + h, as stages_written_out)."""
        a_mid, a_end = a_ext
        k1v, k2v, k3v, k4v, hv = self.k1v, self.k2v, self.k3v, self.k4v, self.hv
        b1, b2, t = self.ut, self.ut2, self.tmp
        half_h, quarter_h2, _, half_h2, _, _ = consts
        add, mul = _add, _multiply
        mul(v, half_h, hv)
        add(state_u, hv, b1)  # stage 2 position P = u + h/2 v
        accel(b1, k2v, None)
        if a_mid:
            k2v[self.load_bead] += a_mid
        mul(k1v, quarter_h2, t)
        add(b1, t, b2)  # stage 3: u + h/2 (v + h/2 k1v) = P + h^2/4 k1v
        accel(b2, k3v, None)
        if a_mid:
            k3v[self.load_bead] += a_mid
        add(b1, hv, b2)  # Q = u + h v
        mul(k2v, half_h2, t)
        add(b2, t, b1)  # stage 4: u + h (v + h/2 k2v) = Q + h^2/2 k2v
        accel(b1, k4v, None)
        if a_end:
            k4v[self.load_bead] += a_end

    def rk4_damped(
        self, state: ChainState, h: float, a_ext: tuple[float, float, float], consts: tuple[np.ndarray, ...]
    ) -> None:
        """rk4 with damping: the stage velocities too (the damping force), and its energy (a_ext: the
        load at t0, t0 + h/2 and t0 + h)."""
        a1, a_mid, a_end = a_ext
        u, v, accel = state.u, state.v, self.dash_accel
        k1v, k2v, k3v, k4v, ut, vt, hv = self.k1v, self.k2v, self.k3v, self.k4v, self.ut, self.vt, self.hv
        half_h, quarter_h2, h_, half_h2, h2_6, h_6 = consts
        power = 0.0
        power += accel(u, k1v, v)
        k1v[self.load_bead] += a1
        np.multiply(v, half_h, out=hv)
        np.add(hv, u, out=ut)
        np.multiply(k1v, half_h, out=vt)
        vt += v
        power += 2.0 * accel(ut, k2v, vt)
        k2v[self.load_bead] += a_mid
        # stage 3 position: u + h/2 (v + h/2 k1v)
        np.multiply(k1v, quarter_h2, out=ut)
        ut += u
        ut += hv
        np.multiply(k2v, half_h, out=vt)
        vt += v
        power += 2.0 * accel(ut, k3v, vt)
        k3v[self.load_bead] += a_mid
        # stage 4 position: u + h (v + h/2 k2v)
        np.multiply(v, h_, out=hv)
        np.multiply(k2v, half_h2, out=ut)
        ut += u
        ut += hv
        np.multiply(k3v, h_, out=vt)
        vt += v
        power += accel(ut, k4v, vt)
        k4v[self.load_bead] += a_end
        state.damping_energy += h / 6.0 * power  # damping energy with the method's own weights
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
        the contacts that turned inside it and their maxima: the quartic through the ends' overlaps and
        rates and the start's second derivative, which the first stage k1v still holds: reference
        .hermite), and the history raised to them.
        turning: the contacts whose rate went from > 0 to <= 0, if the caller screened them already."""
        alpha_old, adot_old = state.alpha_now, state.adot_now
        if turning is None:
            turning = (np.greater(adot_old, _ZERO) & np.less_equal(adot_new, _ZERO)).nonzero()[0]
        peak = alpha_new
        if not turning.size:
            p = tp = _EMPTY
        elif turning.size <= events._SCALAR_CONTACTS:
            # a handful turn: on Python floats (numpy calls on a few elements cost more than the
            # arithmetic), the same operations as below: hermite_max's _max_scalar, np.maximum
            h = t1 - t0
            kept, ps, ts = [], [], []
            k1, inv_m = self.k1v, self.inv_m
            for i in turning.tolist():
                x1 = alpha_new.item(i)
                if x1 > 0.0:  # in contact
                    z0 = (k1.item(i) - k1.item(i + 1)) * inv_m
                    pk, sk = max1_quartic(h, alpha_old.item(i), x1, adot_old.item(i), adot_new.item(i), z0)
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
                dd0 = (self.k1v[turning] - self.k1v[turning + 1]) * self.inv_m
                p, tp = hermite_max_quartic(
                    t0, t1, alpha_old[turning], alpha_new[turning], adot_old[turning], adot_new[turning], dd0
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
        """Each contact's force at the state's overlaps and velocities (damping clipped at zero)."""
        law, u, v = state.law, state.u, state.v
        alpha = u[:-1] - u[1:]
        f = law.force(alpha, state.alpha_hist)
        if state.damped:
            p = state.problem
            total = p.damping_part.damped_force(
                float(p.damping_coefficient), law, alpha, state.alpha_hist, v[:-1] - v[1:], f
            )
            f = np.where(alpha > 0.0, total, f)
        return f
