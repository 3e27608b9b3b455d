"""What the reference solver records and checks while it runs: observers of the state.

The driver (granchain.reference.solver._drive) calls every observer at the same points of the run:

* ``start(state)`` once, at t = 0, before the first step;
* ``after_step(state, t0, t1)`` after every ``every``-th step (0: never), in list order; [t0, t1] is
  the step's last piece (an RK4 step split by event location ends with a shorter one); a True
  return stops the run once every observer has seen this step;
* ``after_split(state, t0, t1)`` after every other piece of a split RK4 step (peak tracking only);
* ``end_segment(state)`` once a segment's steps are done (or the run stopped), before
* ``at_breakpoint(state, stopped)``: the time is a breakpoint (the load's end, a snapshot, the end)
  or the stop;
* ``finish(state)`` once at the end, in list order: fields of ChainSolution.

Observers only read the state (u, v, alpha_max, the force buffer, RK4's dense output); what they
compute for each other they hand over by reference (the leading pulse asks the peak tracker for its
peaks, the early stop for a contact's force and peak, the run watch checks each energy row).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from operator import attrgetter
from typing import Any

import numpy as np
from typing_extensions import override

from granchain.invariants import InvariantError, contact_bodies, energy_violation, front_body, momentum_violation
from granchain.peaks import PEAK_PASSED_FRACTION, every_contact_complete, unreached_as_nan
from granchain.physics.effects import EFFECTS, momentum_kept
from granchain.problem import state_energy
from granchain.reference.ladder import CrossingLadder
from granchain.reference.state import ChainState

#: (t, kinetic, stored, dissipated, work) of one energy sample
EnergyRow = tuple[float, float, float, float, float]
#: up to this many contacts at a maximum, the peak tracking updates them on Python floats
_SCALAR_CONTACTS = 16


class Observer:
    """The common interface: every hook does nothing unless an observer overrides it."""

    every = 0  # after_step every `every` steps; 0: never

    def start(self, state: ChainState) -> None:
        """The run begins (t = 0)."""

    def after_split(self, state: ChainState, t0: float, t1: float) -> None:
        """An RK4 piece [t0, t1] that event location split off a step (not the step's last)."""

    def after_step(self, state: ChainState, t0: float, t1: float) -> bool:
        """A step ended at t1 (its last piece began at t0). True: stop the run after this step."""
        return False

    def after_setup(self, state: ChainState) -> None:
        """The integrator recomputed the forces of the state at state.t, as a LAMMPS run's setup does
        (Integrator.start_segment): the same time's sample again, not a new one."""

    def end_segment(self, state: ChainState) -> None:
        """The steps of a segment are done, or the run stopped."""

    def at_breakpoint(self, state: ChainState, stopped: bool) -> None:
        """The state is at a breakpoint of the step plan (stopped: at the early stop instead)."""

    def finish(self, state: ChainState) -> dict[str, Any]:
        """The fields of ChainSolution this observer fills."""
        return {}


# ---- peaks


class PeakTracker(Observer):
    """Running peak of every contact, its time and the smallest force since (peaks.complete_peaks).

    Tells its ``listeners`` (state, contacts) when contacts reach a local maximum, after the running
    peak took it in (the leading pulse freezes the first one).
    """

    every = 1

    def __init__(self, state: ChainState) -> None:
        self.static = state.static_force  # each contact's force at rest
        # the chain's own contacts, between a striker's in front (which starts unloaded) and a wall's
        self.chain = slice(state.problem.first_bead, state.n - 1 - (0 if state.free_end else 1))
        self.amax = state.overlap()  # the running peak overlap: the static overlap at t = 0
        self.listeners: list[Callable[[ChainState, np.ndarray], None]] = []
        self.ladder: CrossingLadder | None = None  # the leading pulse's, climbed at every step before the maxima
        self.time_of_peak = np.empty(0)  # set by finish

    def peak_at(self, state: ChainState, ix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The running peak force and its time of contacts ix."""
        raise NotImplementedError

    def now_and_peak(self, state: ChainState, c: int) -> tuple[float, float]:
        """Contact c's force now and its running peak force."""
        raise NotImplementedError

    def now_and_peaks(self, state: ChainState, ix: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Contacts ix's force now, their running peak forces and the peaks' times."""
        raise NotImplementedError

    def peak_fields(self, peak_force: np.ndarray, tmax: np.ndarray, force_min: np.ndarray) -> dict[str, Any]:
        """The peak fields of ChainSolution from the running peaks: the chain's own contacts with nan
        where one was not reached (above F0, among the chain's contacts: unreached_as_nan), the effects'
        contacts (a striker's, a wall's) with their running peak's time as it is, for
        peaks.every_contact_complete to judge with each one's own static force, as the LAMMPS read-back
        does with the pair styles' times; complete: every_contact_complete of every contact."""
        chain = self.chain
        self.time_of_peak = np.array(tmax, dtype=float)
        self.time_of_peak[chain] = unreached_as_nan(peak_force[chain], tmax[chain], self.static[chain])
        static = self.static  # a striker touches bead 1 unloaded; a wall carries F0 and the weight
        return {
            "peak_overlap": self.amax,
            "peak_force": peak_force,
            "time_of_peak": self.time_of_peak,
            "force_min_after_peak": force_min,
            "complete": every_contact_complete(peak_force, force_min, self.time_of_peak, static),
        }


class HermitePeaks(PeakTracker):
    """RK4: the running maximum of each overlap at piece ends, refined inside a piece where the overlap
    turns by the maximum of the Hermite interpolant (the integrator's dense output). Every law is
    monotone in alpha on its loading path, so the peak force is the virgin curve at the peak overlap.
    With a dashpot that is the elastic force where the overlap turns, not the largest total force (the
    dashpot adds gamma alpha' > 0 before the turn): on effect-dashpot 4.4e-5 of the peak below
    Verlet's converged total (docs/error-bars.md); RK4 gives such runs no error bars
    (workflows.error_estimates.withheld_because).
    """

    def __init__(self, state: ChainState) -> None:
        super().__init__(state)
        self.tmax = np.where(self.amax > 0.0, 0.0, np.nan)
        self.amin = self.amax.copy()  # smallest overlap at a piece end since the peak
        self.rising = np.empty(self.amax.shape, dtype=bool)

    @override
    def after_step(self, state: ChainState, t0: float, t1: float) -> bool:
        alpha_new = state.alpha_now
        if self.ladder is not None:
            self.ladder.climb_hermite(state, t0, t1)
        amax, amin, tmax = self.amax, self.amin, self.tmax
        np.minimum(amin, alpha_new, out=amin)
        rising = np.greater(alpha_new, amax, out=self.rising)
        # where the overlap rises above its running peak (copyto with where=: no temporaries)
        np.copyto(amax, alpha_new, where=rising)
        np.copyto(tmax, t1, where=rising)
        np.copyto(amin, alpha_new, where=rising)
        turning = state.turning
        if turning.size:
            p, tp = state.turn_peak, state.turn_time
            if turning.size <= _SCALAR_CONTACTS:  # a handful: on Python floats, the same assignments
                for k, i in enumerate(turning.tolist()):
                    pk = p.item(k)
                    if pk > amax.item(i):
                        amax[i] = pk
                        tmax[i] = tp.item(k)
                        amin[i] = alpha_new.item(i)
            else:
                better = p > amax[turning]
                ix = turning[better]
                amax[ix] = p[better]
                tmax[ix] = tp[better]
                amin[ix] = alpha_new[ix]  # the peak lies inside this piece: only its end comes after it
            for listener in self.listeners:
                listener(state, turning)
        return False

    @override
    def after_split(self, state: ChainState, t0: float, t1: float) -> None:
        self.after_step(state, t0, t1)

    @override
    def peak_at(self, state: ChainState, ix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # at a contact's maximum its running peak is that maximum; the force there: F is monotone in
        # the overlap at a fixed history. Whole-chain evaluation: per-contact stiffness arrays
        # (striker, wall, per-bead chains) broadcast only against whole-chain arrays
        f = np.asarray(state.law.force(np.maximum(self.amax, 0.0), state.alpha_hist), dtype=float)
        return f[ix], self.tmax[ix]

    @override
    def now_and_peak(self, state: ChainState, c: int) -> tuple[float, float]:
        # whole-chain evaluation (every STOP_CHECK_EVERY steps), as in peak_at
        now = float(state.law.force(state.overlap(), state.alpha_hist)[c])
        return now, float(state.law.force_at_peak_overlap(self.amax)[c])

    @override
    def now_and_peaks(self, state: ChainState, ix: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        # whole-chain evaluations, as in peak_at (only while a leading pulse waits for its fall)
        now = np.asarray(state.law.force(np.maximum(state.overlap(), 0.0), state.alpha_hist), dtype=float)
        peak, time = self.peak_at(state, ix)
        return now[ix], peak, time

    @override
    def finish(self, state: ChainState) -> dict[str, Any]:
        law = state.law
        peak_force = np.asarray(law.force_at_peak_overlap(self.amax), dtype=float)
        force_min = np.asarray(law.force(np.maximum(self.amin, 0.0), state.alpha_hist), dtype=float)
        return self.peak_fields(peak_force, self.tmax, force_min)


class ForceSamplePeaks(PeakTracker):
    """Verlet: the peak tracking of granchain's LAMMPS pair styles, so that the two agree step for
    step: the running maximum of the force samples at step ends, refined by the vertex of the parabola
    through three consecutive samples where the middle one is a local maximum."""

    _samples = staticmethod(attrgetter("fc"))  # the forces tracked: every contact's (reference.sensors: beads')

    def __init__(self, state: ChainState) -> None:
        super().__init__(state)
        self.f_now = self._samples(state).copy()  # the t = 0 sample (nonzero only with precompression)
        self.f_prev, self.f_prev2 = np.zeros_like(self.f_now), np.zeros_like(self.f_now)
        self.t_now, self.t_prev, self.t_prev2 = 0.0, -math.inf, -math.inf
        self.fpk = self.f_now.copy()
        self.tpk = np.where(self.fpk > 0.0, 0.0, np.nan)
        self.fmin = self.fpk.copy()  # smallest force sample since the peak, as the pair styles
        self.alpha = np.empty(state.n - 1)  # work arrays of after_step
        self.u_left, self.u_right = state.u[:-1], state.u[1:]  # (u changes in place)
        self.rising = np.empty(self.f_now.shape, dtype=bool)

    @override
    def start(self, state: ChainState) -> None:
        # the t = 0 sample climbs the ladder as the pair styles' first evaluation does: a rung it is
        # above already (a dashpot's force on a kicked bead) was crossed at t = 0
        if self.ladder is not None:
            self.ladder.climb_samples(self.f_now, self.f_now, -math.inf, 0.0)

    @override
    def after_setup(self, state: ChainState) -> None:
        # the pair styles' setup evaluation: overwrites the current sample (fc), tracks it unrefined (no new sample)
        f_now = self.f_now
        if self.ladder is not None:
            self.ladder.climb_samples(self.f_prev, state.fc, self.t_prev, self.t_now)
        np.copyto(f_now, self._samples(state))
        np.minimum(self.fmin, f_now, out=self.fmin)
        rising = np.greater(f_now, self.fpk, out=self.rising)
        np.copyto(self.fpk, f_now, where=rising)
        np.copyto(self.tpk, self.t_now, where=rising)
        np.copyto(self.fmin, f_now, where=rising)

    @override
    def after_step(self, state: ChainState, t0: float, t1: float) -> bool:
        # the three samples rotate through three arrays (the oldest is overwritten with the new one)
        f_now = self.f_prev2
        np.copyto(f_now, self._samples(state))
        self.f_prev2, self.f_prev, self.f_now = self.f_prev, self.f_now, f_now
        self.t_prev2, self.t_prev, self.t_now = self.t_prev, self.t_now, t1
        if self.ladder is not None:
            self.ladder.climb_samples(self.f_prev, f_now, self.t_prev, t1)
        fpk, f_prev = self.fpk, self.f_prev
        np.subtract(self.u_left, self.u_right, out=self.alpha)
        np.maximum(self.amax, self.alpha, out=self.amax)
        np.minimum(self.fmin, f_now, out=self.fmin)
        rising = np.greater(f_now, fpk, out=self.rising)
        if rising.any():  # above the running peak (rare once the front passed: 3 copies of nothing cost more)
            np.copyto(fpk, f_now, where=rising)
            np.copyto(self.tpk, t1, where=rising)
            np.copyto(self.fmin, f_now, where=rising)
        if not math.isfinite(self.t_prev2):
            return False
        # a local maximum in the middle sample: screened on the fall to the last sample first
        ix = np.greater(f_prev, f_now, out=self.rising).nonzero()[0]
        if ix.size:
            ix = ix[(f_prev[ix] >= self.f_prev2[ix]) & (f_prev[ix] > 0.0)]
        if ix.size:
            self.refine(state, ix)
        return False

    def refine(self, state: ChainState, ix: np.ndarray) -> None:
        """The middle sample of contacts ix is a local maximum: its value is the vertex of the parabola
        through the three samples where that opens downwards, else the sample itself (as the pair styles)."""
        a, b = self.t_prev2 - self.t_prev, self.t_now - self.t_prev
        det = a * b * (b - a)
        f_prev, fpk, tpk = self.f_prev, self.fpk, self.tpk
        fa, fb = self.f_prev2[ix] - f_prev[ix], self.f_now[ix] - f_prev[ix]
        c1 = (fa * b * b - fb * a * a) / det
        c2 = (a * fb - b * fa) / det
        ok = c2 < 0.0
        sv = np.zeros(ix.size)
        sv[ok] = np.clip(-c1[ok] / (2.0 * c2[ok]), a, b)
        val = f_prev[ix].copy()
        val[ok] += (c1[ok] + c2[ok] * sv[ok]) * sv[ok]
        better = ok & (val > fpk[ix])
        fpk[ix[better]] = val[better]
        tpk[ix[better]] = self.t_prev + sv[better]
        self.fmin[ix[better]] = self.f_now[ix[better]]  # the refined peak lies before this sample
        for listener in self.listeners:
            listener(state, ix)

    @override
    def peak_at(self, state: ChainState, ix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.fpk[ix], self.tpk[ix]

    @override
    def now_and_peak(self, state: ChainState, c: int) -> tuple[float, float]:
        return state.fc[c], self.fpk[c]

    @override
    def now_and_peaks(self, state: ChainState, ix: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.f_now[ix], self.fpk[ix], self.tpk[ix]

    @override
    def finish(self, state: ChainState) -> dict[str, Any]:
        return self.peak_fields(self.fpk, self.tpk, self.fmin)


# ---- recording


class Recorder(Observer):
    """Histories (the force of chosen contacts and the velocity of their left bead, every
    history_stride steps from t = 0) and snapshots (whole-chain profiles at breakpoints).

    No extra history row at the end: the samples are every history_stride steps from t = 0 in both
    backends (LAMMPS's dump writes only those), so the two tables have the same rows.
    """

    def __init__(
        self,
        state: ChainState,
        forces: Callable[[ChainState], np.ndarray],
        histories: Sequence[int],
        history_stride: int,
        snapshots: Sequence[float],
        total_steps: int,
    ) -> None:
        self.forces = forces  # the integrator's contact_forces
        self.n = state.n
        self.idx = np.asarray(histories, dtype=int)
        self.every = history_stride if len(self.idx) else 0
        rows = (total_steps // history_stride + 2) if len(self.idx) else 0
        self.h_t = np.empty(rows)
        self.h_f = np.empty((rows, len(self.idx)))
        self.h_v = np.empty((rows, len(self.idx)))
        self.rows = 0
        self.snapshot_times = {float(s) for s in snapshots}
        self.snaps: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def record(self, state: ChainState, t: float) -> None:
        """Append one history row at time t: the recorded contacts' forces and beads' velocities."""
        self.h_t[self.rows] = t
        self.h_f[self.rows] = self.forces(state)[self.idx]
        self.h_v[self.rows] = state.v[self.idx]
        self.rows += 1

    @override
    def start(self, state: ChainState) -> None:
        if self.every:
            self.record(state, 0.0)

    @override
    def after_step(self, state: ChainState, t0: float, t1: float) -> bool:
        self.record(state, t1)
        return False

    @override
    def at_breakpoint(self, state: ChainState, stopped: bool) -> None:
        if not stopped and state.t in self.snapshot_times:
            self.snaps[state.t] = (state.u.copy(), state.v.copy(), self.forces(state))

    @override
    def finish(self, state: ChainState) -> dict[str, Any]:
        n, snaps = self.n, self.snaps
        snap_t = np.asarray(sorted(snaps))
        return {
            "history_contacts": tuple(int(i) for i in self.idx),
            "history_time": self.h_t[: self.rows].copy(),
            "history_force": self.h_f[: self.rows].copy(),
            "history_velocity": self.h_v[: self.rows].copy(),
            "snapshot_time": snap_t,
            "snapshot_displacement": np.array([snaps[s][0] for s in snap_t]).reshape(len(snap_t), n),
            "snapshot_velocity": np.array([snaps[s][1] for s in snap_t]).reshape(len(snap_t), n),
            "snapshot_force": np.array([snaps[s][2] for s in snap_t]).reshape(len(snap_t), n - 1),
        }


class EnergyLedger(Observer):
    """Energy samples (~energy_samples per run, and at every breakpoint): kinetic, stored, dissipated
    (the law's, from alpha_max, plus the dashpot's) and the energy put in: the initial energy, the work
    of the step load (exactly A times the displacement of bead 1 while it acts: f is constant over
    every step) and of the effects' external forces (Effect.work: precompression's static forces on
    bead 1 and a free bead N).

    Tells its ``listeners`` (state, row) about every row as it is taken (the run watch checks it).
    """

    def __init__(self, state: ChainState, energy_every: int) -> None:
        self.every = energy_every
        self.problem = state.problem
        self.u_init = state.u.copy()
        self.u0_at_load_end: float | None = None  # bead 1's displacement when the load stopped
        # kinetic + stored + dissipated at t = 0 (problem.initial_energy: the deck's too)
        self.e_initial = state_energy(state.law, state.mass_ke, state.u, state.v, state.alpha_hist)
        self.rows: list[EnergyRow] = []
        self.listeners: list[Callable[[ChainState, EnergyRow], None]] = []

    def work(self, state: ChainState) -> float:
        """Energy put in: the initial energy, the work of f(t) and of the static forces."""
        p, u, s0 = self.problem, state.u, self.problem.front  # bead 1: behind the beads in front
        w = self.e_initial
        if p.amplitude and not p.driven:  # (a drive's work: reference.drive.DrivenEnergyLedger)
            u0 = u[s0] if self.u0_at_load_end is None else self.u0_at_load_end
            w += p.amplitude * (u0 - self.u_init[s0])
        dx_mass = float(np.dot(state.mass_ke, u - self.u_init))  # (a body force does m_i g dx_i)
        for effect in EFFECTS.values():  # the effects' external forces (precompression's static ones)
            w += effect.work(p, u[s0] - self.u_init[s0], u[-1] - self.u_init[-1], dx_mass)
        return w

    def row(self, state: ChainState, t: float) -> None:
        """Append one energy row at time t (kinetic, potential and dissipated energy, the work done)
        and pass it to the listeners."""
        law, v = state.law, state.v
        ke = 0.5 * float(np.dot(state.mass_ke, v * v))
        pe = float(np.sum(law.energy(state.overlap(), state.alpha_hist)))
        de = (float(np.sum(law.dissipated(state.alpha_hist))) if law.history else 0.0) + state.damping_energy
        row = (t, ke, pe, de, self.work(state))
        self.rows.append(row)
        for listener in self.listeners:
            listener(state, row)

    @override
    def start(self, state: ChainState) -> None:
        self.row(state, 0.0)

    @override
    def after_step(self, state: ChainState, t0: float, t1: float) -> bool:
        if t1 < state.seg_end:  # a breakpoint takes its own row
            self.row(state, t1)
        return False

    @override
    def at_breakpoint(self, state: ChainState, stopped: bool) -> None:
        p = self.problem
        if not stopped and p.amplitude and state.t == p.duration:
            self.u0_at_load_end = float(state.u[p.front])
        self.row(state, state.t)

    @override
    def finish(self, state: ChainState) -> dict[str, Any]:
        e = np.asarray(self.rows)
        _, keep = np.unique(e[:, 0], return_index=True)  # duplicate times: a breakpoint on a periodic sample
        e = e[np.sort(keep)]
        names = ("energy_time", "kinetic", "potential", "dissipated", "work")
        return {name: e[:, i] for i, name in enumerate(names)}


# ---- checks


class RunWatch(Observer):
    """The run watch (granchain.invariants): InvariantError on a broken invariant.

    A finite state and overlaps below max_overlap every watch_every steps and at the end of every
    segment (so a short run is watched too); the energy balance (against the largest energy put in
    so far) and the momentum of a free chain without precompression at every energy row.
    None switches a check off. max_overlap is one bound for every contact or one per contact of the
    state's chain (a striker's first, a wall's last: invariants.contact_overlap_bounds), and a
    broken bound names the contact with the largest overlap relative to its own bound, numbered as
    the scene's (a striker's contact is 0).
    """

    def __init__(
        self,
        state: ChainState,
        ledger: EnergyLedger,
        watch_every: int,
        max_overlap: float | np.ndarray | None,
        energy_watch: float | None,
        momentum_watch: float | None,
    ) -> None:
        self.every = watch_every
        self.max_overlap: float | np.ndarray | None = None
        if max_overlap is not None:
            bounds = np.broadcast_to(np.asarray(max_overlap, dtype=float), (state.n - 1,))
            # one bound for all (a uniform chain): the overlaps' largest against it, no division
            self.max_overlap = float(bounds[0]) if bool((bounds == bounds[0]).all()) else bounds.copy()
        self.front, self.shaken = state.problem.first_bead, state.problem.shaker  # (a striker, a driver in front)
        self.energy_watch = energy_watch
        self.momentum_watch = momentum_watch if momentum_kept(state.problem) and not state.problem.driven else None
        self.p_initial = float(np.dot(state.mass_ke, state.v))  # (a striker's or bead 1's initial momentum)
        self.put_in = 0.0  # the largest energy put in so far (the energy watch's scale)
        if self.energy_watch is not None or self.momentum_watch is not None:
            ledger.listeners.append(self.check_energy)

    @override
    def after_step(self, state: ChainState, t0: float, t1: float) -> bool:
        self.check_state(state, t1)
        return False

    @override
    def end_segment(self, state: ChainState) -> None:
        self.check_state(state, state.t)

    def scene_contact(self, i: int) -> int:
        """The scene's number of the state's contact i (0-based over the state's chain): a striker's
        contact is 0, the chain's 1 .. N - 1, a wall's N."""
        return i + 1 - self.front

    def check_state(self, state: ChainState, t: float) -> None:
        """A finite state, overlaps below max_overlap."""
        u, v = state.u, state.v
        if not np.isfinite(u.sum() + v.sum()):
            bad = int(np.flatnonzero(~(np.isfinite(u) & np.isfinite(v)))[0])
            body = "the striker" if bad < self.front else f"bead {bad + 1 - self.front}"
            raise InvariantError(
                "finite state",
                t,
                state.step,
                self.scene_contact(min(bad, state.n - 2)),
                f"displacement or velocity of {body} is not finite",
            )
        bound = self.max_overlap
        if bound is not None:
            a = state.overlap()
            if isinstance(bound, float):
                i, b = int(np.argmax(a)), bound
            else:  # each contact against its own bound: the largest overlap relative to it
                i = int(np.argmax(a / bound))
                b = float(bound[i])
            if a[i] > b:
                contact, wall = self.scene_contact(i), not state.free_end
                bodies = contact_bodies(contact, state.n - self.front - wall, front_body(self.shaken, self.front), wall)
                raise InvariantError(
                    "overlap far below the radius",
                    t,
                    state.step,
                    contact,
                    f"the overlap of {bodies}, {a[i]:.3g} m, exceeds its bound {b:.3g} m (half the smaller "
                    "radius of its two bodies)",
                )

    def check_energy(self, state: ChainState, row: EnergyRow) -> None:
        """The energy balance and the momentum at an energy row."""
        t, ke, pe, de, w = row
        if self.energy_watch is not None:
            self.put_in = max(self.put_in, abs(w), ke + pe)
            detail = energy_violation(ke + pe + de - w, self.put_in, self.energy_watch)
            if detail:
                busiest = self.scene_contact(int(np.argmax(state.overlap())))
                raise InvariantError("energy balance", t, state.step, busiest, detail)
        if self.momentum_watch is not None:
            p = state.problem
            delivered = float(p.load_impulse(t))
            momentum = float(np.dot(state.mass_ke, state.v))
            detail = momentum_violation(momentum, self.p_initial + delivered, self.momentum_watch)
            if detail:
                busiest = self.scene_contact(int(np.argmax(state.overlap())))
                raise InvariantError("momentum", t, state.step, busiest, detail)


class EarlyStop(Observer):
    """Stop once the force of each of contacts cs has fallen below half its peak (checked every every
    steps, as LAMMPS's fix halt does): the leading wave has passed them. Only a peak above stop_floor
    counts (round-off forces ahead of the wave must not stop the run), and only once the force has
    also fallen by lead_fall below it: then a leading pulse that waits for that fall
    (leading.LeadingPulse, which sees every step before this check) has frozen.

    back (a wall's reflection, [run] stop_after_reflection): the last of cs is the wall's contact, and
    the stop also waits for the reflection to pass back through contact `back`: its force above F0 at
    the checks where the wall's contact has passed (0 at the others, as templates/stop.lmp.j2's fix
    vector stores it) has a largest value above stop_floor - F0 and is back below half of it."""

    def __init__(
        self,
        state: ChainState,
        peaks: PeakTracker,
        contacts: tuple[int, ...],
        every: int,
        stop_floor: float,
        lead_fall: float = 0.0,
        back: int | None = None,
    ) -> None:
        self.peaks = peaks
        self.contacts = contacts
        self.every = every
        self.stop_floor = stop_floor
        self.lead_fall = lead_fall
        self.static = state.static_force  # each contact's force at rest
        self.back = back
        self.back_max = -math.inf  # the largest sample so far (the deck's max(f_back))

    @override
    def after_step(self, state: ChainState, t0: float, t1: float) -> bool:
        passed = [self.passed(state, c) for c in self.contacts]
        if self.back is None:
            return all(passed)
        f0 = self.static[self.back]
        now = self.peaks.now_and_peak(state, self.back)[0] - f0
        self.back_max = max(self.back_max, now if passed[-1] else 0.0)
        return all(passed) and self.back_max > self.stop_floor - f0 and now < PEAK_PASSED_FRACTION * self.back_max

    def passed(self, state: ChainState, c: int) -> bool:
        """Whether the wave has passed contact c."""
        now, peak = self.peaks.now_and_peak(state, c)
        passed = peak > self.stop_floor and now - self.static[c] < PEAK_PASSED_FRACTION * (peak - self.static[c])
        return passed and (self.lead_fall <= 0.0 or now <= peak - self.lead_fall)
