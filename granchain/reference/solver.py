"""Pure-Python (numpy) solvers of the chain equations (Eqs. 1-4): classical RK4 and velocity Verlet.

    m_i u_i'' = F_{i-1,i}(alpha_{i-1,i}) - F_{i,i+1}(alpha_{i,i+1}),   alpha_{i,i+1} = u_i - u_{i+1}
    m_1 u_1'' = -F_{1,2} + f(t),   f(t) = A for 0 < t <= T (Eq. 4)

Design choices (each tested in tests/test_reference.py):

* The step load is exact: T, every snapshot time and the end time are step boundaries (the step
  before a boundary is shortened to land on it), and f is constant over every step. The impulse
  delivered is then sum(f h) = A T to round-off, for both methods. For velocity Verlet this is
  what LAMMPS does when the run is split at T (both half-kicks of a step see that step's load).
* Bilinear history (alpha_max) is frozen during a step and updated once per accepted step.
  Stage values of a multi-stage method are trial points, not states of the trajectory, so
  letting them raise alpha_max would write non-physical history. Freezing costs nothing at
  loading (the loading line F = k alpha does not depend on alpha_max) and only perturbs the step
  in which a contact turns from loading to unloading.
  - RK4: after the step alpha_max is raised to the maximum of the cubic Hermite interpolant of
    alpha over the step (alpha and d(alpha)/dt at both ends), so the history misses the true
    maximum by O(h^4), not O(h^2).
  - Verlet: alpha_max is raised to alpha at the step's end, which is what a LAMMPS pair style
    does at each force evaluation, so the two agree step for step.
* Peaks are tracked while running: a running maximum of every contact's overlap with its time,
  refined inside a step by the same Hermite interpolant. Both laws are monotone in alpha on the
  loading path, so the peak force is F(alpha_peak). No step is stored for this.
* Energies: kinetic, stored (elastic), dissipated (bilinear, Eq. 20) and the work of f(t), which
  for a step load is exactly A times the displacement of bead 1 while the load acts.
"""

from __future__ import annotations

import math
import time

import numpy as np

from granchain.invariants import InvariantError, energy_violation, momentum_violation
from granchain.peaks import PEAK_PASSED_FRACTION, complete_peaks, unreached_as_nan
from granchain.problem import ChainProblem, initial_state, moving_mass, state_energy
from granchain.progress import Progress
from granchain.results import ChainSolution
from granchain.schedule import STOP_CHECK_EVERY, step_plan

METHODS = ("rk4", "verlet")
EPS = float(np.finfo(float).eps)
# RK4 event location (first_kink_crossing): a contact closer to a kink of its law than
# KINK_ROUNDOFF eps (|u_i| + |u_i+1| + |kink|) is at it (an overlap is a difference of two
# displacements and carries their round-off); and no step is split more often than
# MAX_SPLITS_PER_CONTACT per contact + MAX_SPLITS_BASE (each crossing takes one split, rarely two
# or three while the located point converges), else EventLocationError: a bug, not a slow run.
KINK_ROUNDOFF = 16.0
MAX_SPLITS_PER_CONTACT = 8
MAX_SPLITS_BASE = 64


class EventLocationError(RuntimeError):
    """RK4 event location could not get past a kink: the step was split more than the cap allows."""


def _hermite_max(t0, t1, a0, a1, d0, d1):
    """Maximum over [t0, t1] of the cubic Hermite interpolant of alpha, where d0 > 0 >= d1.

    Returns (alpha_max, t_max) arrays. p(s) = a s^3 + b s^2 + c s + d on s in [0, 1].
    """
    h = t1 - t0
    c = h * d0
    b = 3.0 * (a1 - a0) - 2.0 * h * d0 - h * d1
    a = 2.0 * (a0 - a1) + h * d0 + h * d1
    # p'(s) = 3a s^2 + 2b s + c falls through zero at s = (-b - sqrt(b^2 - 3ac)) / (3a), written
    # as c / (sqrt(b^2 - 3ac) - b), which also holds for a -> 0 (no cancellation, p'' = -2 disc).
    disc = np.sqrt(np.maximum(b * b - 3.0 * a * c, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        s = c / (disc - b)
    s = np.clip(np.nan_to_num(s, nan=1.0, posinf=1.0), 0.0, 1.0)
    p = ((a * s + b) * s + c) * s + a0
    return p, t0 + s * h


def solve_chain(problem: ChainProblem, end_time: float, timestep: float, method: str = "rk4", **kw) -> ChainSolution:
    """Integrate the chain from rest (bead 1 possibly moving) to end_time.

    A far-end wall is an immovable extra bead (zero inverse mass) whose contact with bead N has the
    wall's stiffness; its peak is reported as wall_peak_force. Keywords: see _solve.
    """
    if "progress" not in kw:  # progress on stderr for a long run (granchain.progress); closed if the run raises
        with Progress(None, f"reference {method}") as progress:
            return solve_chain(problem, end_time, timestep, method, progress=progress, **kw)
    wall, striker = problem.wall_law is not None, problem.striker_mass is not None
    if not (wall or striker):
        return _solve(problem, end_time, timestep, method, **kw)
    n = problem.beads
    inner = problem.with_ends()  # the striker an extra bead in front, the wall an immovable one at the end
    s0 = 1 if striker else 0  # index of bead 1 inside
    if "histories" in kw:
        kw["histories"] = tuple(i + s0 for i in kw["histories"])
    if kw.get("stop_after") is not None:
        kw["stop_after"] += s0  # contact numbers inside count the striker's contact first
    sol = _solve(inner, end_time, timestep, method, **kw)
    if wall:
        sol.wall_peak_force = float(sol.peak_force[-1])
        sol.wall_time_of_peak = float(sol.time_of_peak[-1])
    if striker:
        sol.striker_peak_force = float(sol.peak_force[0])
        sol.striker_time_of_peak = float(sol.time_of_peak[0])
        sol.striker_velocity = float(sol.velocity[0])
    for name in (
        "peak_overlap",
        "peak_force",
        "time_of_peak",
        "alpha_max",
        "force_min_after_peak",
        "leading_pulse_force",
        "leading_pulse_time",
    ):
        setattr(sol, name, getattr(sol, name)[s0 : s0 + n - 1])
    sol.time_of_peak = unreached_as_nan(sol.peak_force, sol.time_of_peak, problem.precompression)
    sol.complete = complete_peaks(sol.peak_force, sol.force_min_after_peak, sol.time_of_peak, problem.precompression)
    unreached = ~np.isfinite(sol.time_of_peak)
    sol.leading_pulse_force[unreached] = sol.leading_pulse_time[unreached] = np.nan
    sol.history_contacts = tuple(i - s0 for i in sol.history_contacts)
    sol.displacement, sol.velocity = sol.displacement[s0 : s0 + n], sol.velocity[s0 : s0 + n]
    sol.snapshot_displacement = sol.snapshot_displacement[:, s0 : s0 + n]
    sol.snapshot_velocity = sol.snapshot_velocity[:, s0 : s0 + n]
    sol.snapshot_force = sol.snapshot_force[:, s0 : s0 + n - 1]
    return sol


def _solve(
    problem: ChainProblem,
    end_time: float,
    timestep: float,
    method: str = "rk4",
    *,
    histories: tuple[int, ...] = (),
    history_stride: int = 1,
    snapshots: tuple[float, ...] = (),
    energy_samples: int = 200,
    event_location: bool = True,
    stop_after: int | None = None,
    stop_floor: float = 0.0,
    lead_floor: float = 0.0,
    max_overlap: float | None = None,
    energy_watch: float | None = None,
    momentum_watch: float | None = None,
    watch_every: int = 20,
    progress: Progress | None = None,
) -> ChainSolution:
    """Integrate the chain from rest (bead 1 possibly moving) to end_time.

    histories: 0-based contacts whose force (and the velocity of their left bead) is recorded
    every history_stride steps. snapshots: times (exact step boundaries) of whole-chain profiles.
    event_location (RK4 only): split steps where a contact's force law has a kink (see module doc).
    stop_after: 0-based contact; stop (checked every STOP_CHECK_EVERY steps, as LAMMPS's fix halt
    does) once its force has fallen below half its peak: the leading wave has passed it. Only a
    peak above stop_floor counts (round-off forces ahead of the wave must not stop the run).
    lead_floor: the smallest rise above F0 that can be a leading pulse (peaks.leading_pulse).
    max_overlap, energy_watch, momentum_watch: the run watch (granchain.invariants); None = off.
    Overlaps and a finite state are checked every watch_every steps and at breakpoints, the energy
    balance and the momentum of a free chain at every energy sample (~200 per run, as LAMMPS).
    progress: told the step count every ~0.1 s of steps (its update() names the next step to call it at).
    """
    if method not in METHODS:
        raise ValueError(f"method = {method!r} is not known; choose one of {', '.join(METHODS)}")
    if not (timestep > 0 and end_time > 0):
        raise ValueError("timestep and end_time must be positive")
    t_wall = time.perf_counter()
    n = problem.beads
    law = problem.law
    history = law.history  # the law keeps alpha_max per contact
    inv_m = 1.0 / problem.mass  # 0 for an immovable wall bead
    inv_m0 = float(inv_m[0])
    mass_ke = moving_mass(problem.mass)  # the wall neither moves nor counts
    gamma = float(problem.dashpot)
    dash = {"power": 0.0, "energy": 0.0}  # dashpot power at the last force evaluation, energy so far

    # at rest (bead 1 possibly moving), or precompressed in static equilibrium; alpha_hist: the
    # law's history alpha_max (frozen within a step)
    u, v, alpha_hist = initial_state(problem)
    f0 = float(problem.precompression)
    free_end = bool(np.isfinite(problem.mass[-1]))
    p_initial = float(np.dot(mass_ke, v))  # (a striker's or bead 1's initial momentum)
    u_init = u.copy()

    # ---- contact force into a padded buffer: fp[0] = 0 (external force added separately),
    # fp[1:n] = contact forces, fp[n] = 0 (free far end); a_int = (fp[:-1] - fp[1:]) / m.
    fp = np.zeros(n + 1)
    fc = fp[1:n]
    if f0:
        fp[0] = f0  # the static push on bead 1
        if free_end:
            fp[n] = f0  # ... held by an equal pull on bead N when there is no wall
    alpha = np.empty(n - 1)
    tmp = np.empty(n - 1)
    fe = np.empty(n - 1) if gamma else None

    def accel(uu: np.ndarray, out: np.ndarray, vv: np.ndarray | None = None) -> np.ndarray:
        np.subtract(uu[:-1], uu[1:], out=alpha)
        np.maximum(alpha, 0.0, out=alpha)
        law.force_into(alpha, alpha_hist, fc, tmp)  # with alpha_max frozen within the step
        if gamma:
            # dashpot gamma * d(alpha)/dt while the beads overlap; the total never pulls
            rate = vv[:-1] - vv[1:]
            fe[:] = fc
            fc[:] = np.where(uu[:-1] - uu[1:] > 0.0, np.maximum(fc + gamma * rate, 0.0), fc)
            dash["power"] = float(np.dot(fc - fe, rate))
        np.subtract(fp[:-1], fp[1:], out=out)
        out *= inv_m
        return out

    # ---- bookkeeping
    plan = [
        (g.start, g.end, g.steps, g.last, problem.amplitude if g.loaded else 0.0)
        for g in step_plan(end_time, timestep, problem.duration if problem.amplitude else 0.0, snapshots)
    ]
    total_steps = sum(p[2] for p in plan)
    progress_at = -1 if progress is None else progress.start(total_steps)  # one int comparison per step
    hist_idx = np.asarray(histories, dtype=int)
    nh = (total_steps // history_stride + 2) if len(hist_idx) else 0
    h_t = np.empty(nh)
    h_f = np.empty((nh, len(hist_idx)))
    h_v = np.empty((nh, len(hist_idx)))
    nrec = 0
    energy_every = max(1, total_steps // max(1, energy_samples))
    e_rows: list[tuple[float, float, float, float, float]] = []
    snaps: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    snapshot_set = {float(s) for s in snapshots}
    u0_at_load_end: float | None = None

    amax = u[:-1] - u[1:]  # running peak overlap (refined): the static overlap at t = 0
    tmax = np.where(amax > 0.0, 0.0, np.nan)
    amin = amax.copy()  # RK4: smallest overlap at a step end since the peak (peaks.complete_peaks)
    lead_f, lead_t = np.full(n - 1, np.nan), np.full(n - 1, np.nan)  # the leading pulse
    lead_done = np.zeros(n - 1, dtype=bool)
    a_int = np.empty(n)
    accel(u, a_int, v)

    def forces_now() -> np.ndarray:
        """Contact forces of the current state (what histories and snapshots record)."""
        if method == "verlet":
            return fc.copy()  # the last force evaluation, at this step's end: what LAMMPS dumps
        f = law.force(u[:-1] - u[1:], alpha_hist)
        if gamma:
            f = np.where(u[:-1] - u[1:] > 0.0, np.maximum(f + gamma * (v[:-1] - v[1:]), 0.0), f)
        return f

    def work_now(t: float) -> float:
        """Energy put in: work of f(t), of the static forces, the initial kinetic and stored energy."""
        w = e_initial
        if problem.amplitude:
            u0 = u[0] if u0_at_load_end is None else u0_at_load_end
            w += problem.amplitude * (u0 - u_init[0])
        if f0:
            w += f0 * (u[0] - u_init[0]) - (f0 * (u[-1] - u_init[-1]) if free_end else 0.0)
        return w

    put_in = {"max": 0.0}  # the largest energy put in so far (the energy watch's scale)
    step = 0  # steps taken (named by the watch)

    def energy_row(t: float):
        a_now = u[:-1] - u[1:]
        ke = 0.5 * float(np.dot(mass_ke, v * v))
        pe = float(np.sum(law.energy(a_now, alpha_hist)))
        de = (float(np.sum(law.dissipated(alpha_hist))) if history else 0.0) + dash["energy"]
        w = work_now(t)
        e_rows.append((t, ke, pe, de, w))
        if energy_watch is not None:
            put_in["max"] = max(put_in["max"], abs(w), ke + pe)
            detail = energy_violation(ke + pe + de - w, put_in["max"], energy_watch)
            if detail:
                raise InvariantError("energy balance", t, step, int(np.argmax(a_now)) + 1, detail)
        if momentum_watch is not None and free_end and not f0:
            delivered = problem.amplitude * min(problem.duration, t)
            detail = momentum_violation(float(np.dot(mass_ke, v)), p_initial + delivered, momentum_watch)
            if detail:
                raise InvariantError("momentum", t, step, int(np.argmax(a_now)) + 1, detail)

    def record_history(t: float):
        nonlocal nrec
        if len(hist_idx):
            h_t[nrec] = t
            h_f[nrec] = forces_now()[hist_idx]
            h_v[nrec] = v[hist_idx]
            nrec += 1

    e_initial = state_energy(law, mass_ke, u, v, alpha_hist)  # problem.initial_energy: the deck's too
    record_history(0.0)
    energy_row(0.0)

    # RK4 work arrays
    if method == "rk4":
        k1v, k2v, k3v, k4v = (np.empty(n) for _ in range(4))
        ut = np.empty(n)
        u_save, v_save = np.empty(n), np.empty(n)

    vt = np.empty(n) if gamma else None  # stage velocities, needed only by the dashpot

    def rk4_step(h: float, a_ext: float) -> None:
        """Classical RK4 on (u, v); the external load is constant over the step."""
        nonlocal u, v, ut, vt  # updated in place (augmented assignment on arrays)
        power = 0.0
        accel(u, k1v, v)
        power += dash["power"]
        k1v[0] += a_ext
        np.multiply(v, 0.5 * h, out=ut)
        ut += u
        if gamma:
            np.multiply(k1v, 0.5 * h, out=vt)
            vt += v
        accel(ut, k2v, vt)
        power += 2.0 * dash["power"]
        k2v[0] += a_ext
        # stage 3 position: u + h/2 (v + h/2 k1v)
        np.multiply(k1v, 0.25 * h * h, out=ut)
        ut += u
        ut += 0.5 * h * v
        if gamma:
            np.multiply(k2v, 0.5 * h, out=vt)
            vt += v
        accel(ut, k3v, vt)
        power += 2.0 * dash["power"]
        k3v[0] += a_ext
        # stage 4 position: u + h (v + h/2 k2v)
        np.multiply(k2v, 0.5 * h * h, out=ut)
        ut += u
        ut += h * v
        if gamma:
            np.multiply(k3v, h, out=vt)
            vt += v
        accel(ut, k4v, vt)
        power += dash["power"]
        k4v[0] += a_ext
        if gamma:
            dash["energy"] += h / 6.0 * power  # dashpot energy with the method's own weights
        # u += h/6 (k1u + 2 k2u + 2 k3u + k4u) with k1u = v, k2u = v + h/2 k1v,
        # k3u = v + h/2 k2v, k4u = v + h k3v  =>  u += h v + h^2/6 (k1v + k2v + k3v)
        ut[:] = k1v
        ut += k2v
        ut += k3v
        u += h * v
        u += (h * h / 6.0) * ut
        # v += h/6 (k1v + 2 k2v + 2 k3v + k4v)
        ut += k2v
        ut += k3v
        ut += k4v
        v += (h / 6.0) * ut

    def first_kink_crossing(h: float) -> float | None:
        """Fraction of the step at which the first contact meets a kink of its force law.

        Kinks: the overlap where the force reaches zero, 0 (Hertz: F'' is infinite there) or
        beta alpha_max (bilinear: F' jumps); and, bilinear only, the turn from loading to
        unloading at a new alpha_max and the return of reloading to the loading line at alpha_max
        (the slope changes between k and k_u). Located on the cubic
        Hermite interpolant of alpha over the tentative step.

        A contact counts only if it crosses the kink by more than its overlap's round-off (both
        ends of the step farther than KINK_ROUNDOFF eps (|u_i| + |u_i+1| + |level|) from it, a
        turn's maximum that far above alpha_max): within that it is at the kink already, the slope
        change acts over no overlap that double precision can hold, and a step split there need not
        move the overlap at all, so the same crossing would be found again after the split. A
        crossing within 1e-6 of the step from either end is not split either (that contact only).
        The contact and kind of the crossing returned are left in last_event (the split cap's error).
        """
        a_new = u[:-1] - u[1:]
        adot_new = v[:-1] - v[1:]
        # an overlap is the difference of two displacements: round-off of order eps (|u_i| + |u_i+1|)
        scale = KINK_ROUNDOFF * EPS * (np.abs(u_save[:-1]) + np.abs(u_save[1:]) + np.abs(u[:-1]) + np.abs(u[1:]))
        found: list[tuple[np.ndarray, np.ndarray, str]] = []

        def crossing(level) -> np.ndarray:
            """Contacts that cross `level` from one side to the other, beyond round-off at both ends."""
            tol = scale + KINK_ROUNDOFF * EPS * np.abs(level)
            below0, above0 = alpha_old < level - tol, alpha_old > level + tol
            below1, above1 = a_new < level - tol, a_new > level + tol
            return np.flatnonzero((below0 & above1) | (above0 & below1))

        def first_root(idx: np.ndarray, level, kind: str) -> None:
            a0, a1 = alpha_old[idx] - level, a_new[idx] - level
            d0, d1 = h * adot_old[idx], h * adot_new[idx]
            lo, hi = np.zeros(idx.size), np.ones(idx.size)
            for _ in range(40):  # bisection on the Hermite cubic, which brackets a root
                mid = 0.5 * (lo + hi)
                m2 = mid * mid
                p = (
                    (2 * m2 * mid - 3 * m2 + 1) * a0
                    + (m2 * mid - 2 * m2 + mid) * d0
                    + (-2 * m2 * mid + 3 * m2) * a1
                    + (m2 * mid - m2) * d1
                )
                left = np.sign(p) == np.sign(a0)
                lo = np.where(left, mid, lo)
                hi = np.where(left, hi, mid)
            found.append((0.5 * (lo + hi), idx, kind))

        # the law's kinks (granchain.physics.laws: Hertz zero overlap; bilinear zero force at
        # beta alpha_max and reloading meeting alpha_max; ...) and a turn above its turn level
        for kink in law.kinks(alpha_hist):
            level = np.broadcast_to(kink.level, alpha_old.shape)
            idx = crossing(level)
            if kink.from_below:
                idx = idx[alpha_old[idx] < level[idx]]
            if kink.where is not None:
                idx = idx[np.broadcast_to(kink.where, alpha_old.shape)[idx]]
            if idx.size:
                first_root(idx, level[idx], kink.kind)
        turn_level = law.turn_level(alpha_hist)
        if turn_level is not None:
            turn_level = np.broadcast_to(turn_level, alpha_old.shape)
            turn = np.flatnonzero((adot_old > 0.0) & (adot_new < 0.0) & (a_new > 0.0))
            if turn.size:
                p, sp = _hermite_max(0.0, 1.0, alpha_old[turn], a_new[turn], adot_old[turn] * h, adot_new[turn] * h)
                lv = turn_level[turn]
                loading = p > lv + scale[turn] + KINK_ROUNDOFF * EPS * lv
                if loading.any():
                    found.append((sp[loading], turn[loading], "turn above alpha_max"))
        best = None
        for s_arr, idx, kind in found:
            inside = (s_arr * h >= 1e-6 * timestep) & (s_arr <= 1.0 - 1e-6)
            if inside.any():
                j = int(np.argmin(np.where(inside, s_arr, np.inf)))
                if best is None or s_arr[j] < best[0]:
                    best = (float(s_arr[j]), int(idx[j]), kind)
        if best is None:
            return None
        last_event["contact"], last_event["kind"] = best[1], best[2]
        return best[0]

    def track_peaks(t0: float, t1: float) -> None:
        """Running peak of every contact's overlap, refined inside the step [t0, t1]."""
        nonlocal alpha_old, adot_old
        alpha_new = u[:-1] - u[1:]
        adot_new = v[:-1] - v[1:]
        np.minimum(amin, alpha_new, out=amin)
        rising = alpha_new > amax
        if rising.any():
            amax[rising] = alpha_new[rising]
            tmax[rising] = t1
            amin[rising] = alpha_new[rising]
        turning = np.flatnonzero((adot_old > 0.0) & (adot_new <= 0.0) & (alpha_new > 0.0))
        if turning.size:
            p, tp = _hermite_max(t0, t1, alpha_old[turning], alpha_new[turning], adot_old[turning], adot_new[turning])
            better = p > amax[turning]
            ix = turning[better]
            amax[ix] = p[better]
            tmax[ix] = tp[better]
            amin[ix] = alpha_new[ix]  # the peak lies inside this step: only its end comes after it
            first = ~lead_done[turning]
            if first.any():
                # the leading pulse: at a contact's first maximum, its running peak is that maximum
                # (before it the overlap only rose; a maximum at a split step's end is the running
                # peak already); the force there (F is monotone in the overlap at a fixed history);
                # whole-chain evaluation: per-contact stiffness arrays broadcast only against those
                f_at = np.asarray(law.force(np.maximum(amax, 0.0), alpha_hist), dtype=float)[turning]
                freeze_leading(turning[first], f_at[first], tmax[turning][first])
        if history and method == "rk4":
            law.update_history(alpha_hist, amax)
        alpha_old, adot_old = alpha_new, adot_new

    def freeze_leading(ix, force, time) -> None:
        """The leading pulse (peaks.leading_pulse): the first maximum of each contact's force that
        rises more than lead_floor above F0, frozen from then on (the pair styles' d_flead, d_tlead).
        ix: contacts at their first maximum now; force, time: that maximum (refined) and its time."""
        now = force - f0 > lead_floor
        if now.any():
            j = ix[now]
            lead_f[j], lead_t[j] = force[now], time[now]
            lead_done[j] = True

    # Verlet: the peak tracking of granchain's LAMMPS pair styles, so that the two agree step for
    # step: running maximum of the force samples at step ends, refined by the vertex of the
    # parabola through three consecutive samples where the middle one is a local maximum.
    f_now = fc.copy()
    f_prev, f_prev2 = np.zeros(n - 1), np.zeros(n - 1)
    t_now, t_prev, t_prev2 = 0.0, -math.inf, -math.inf
    fpk = f_now.copy()  # the t = 0 sample (nonzero only with precompression)
    tpk = np.where(fpk > 0.0, 0.0, np.nan)
    fmin = fpk.copy()  # smallest force sample since the peak (peaks.complete_peaks), as the pair styles

    def sample_forces(t1: float) -> None:
        nonlocal f_now, f_prev, f_prev2, t_now, t_prev, t_prev2
        f_prev2, f_prev, f_now = f_prev, f_now, fc.copy()
        t_prev2, t_prev, t_now = t_prev, t_now, t1
        np.maximum(amax, u[:-1] - u[1:], out=amax)
        np.minimum(fmin, f_now, out=fmin)
        rising = f_now > fpk
        fpk[rising] = f_now[rising]
        tpk[rising] = t1
        fmin[rising] = f_now[rising]
        if not math.isfinite(t_prev2):
            return
        ix = np.flatnonzero((f_prev > f_now) & (f_prev >= f_prev2) & (f_prev > 0.0))
        if ix.size == 0:
            return
        # the middle sample is a local maximum: its value is the vertex of the parabola through the
        # three samples where that opens downwards, else the sample itself (as the pair styles)
        a, b = t_prev2 - t_prev, t_now - t_prev
        det = a * b * (b - a)
        fa, fb = f_prev2[ix] - f_prev[ix], f_now[ix] - f_prev[ix]
        c1 = (fa * b * b - fb * a * a) / det
        c2 = (a * fb - b * fa) / det
        ok = c2 < 0.0
        sv = np.zeros(ix.size)
        sv[ok] = np.clip(-c1[ok] / (2.0 * c2[ok]), a, b)
        val = f_prev[ix].copy()
        val[ok] += (c1[ok] + c2[ok] * sv[ok]) * sv[ok]
        better = ok & (val > fpk[ix])
        fpk[ix[better]] = val[better]
        tpk[ix[better]] = t_prev + sv[better]
        fmin[ix[better]] = f_now[ix[better]]  # the refined peak lies before this sample
        first = ~lead_done[ix]
        if first.any():  # at a contact's first maximum its running peak is that maximum (as the pair styles)
            j = ix[first]
            freeze_leading(j, fpk[j], tpk[j])

    def wave_passed(c: int) -> bool:
        if method == "verlet":
            now, peak = fc[c], fpk[c]
        else:
            # whole-chain evaluation (every STOP_CHECK_EVERY steps): per-contact stiffness arrays
            # (striker, wall, per-bead chains) only broadcast against whole-chain arrays
            now = float(law.force(u[:-1] - u[1:], alpha_hist)[c])
            peak = float(law.force_at_peak_overlap(amax)[c])
        return peak > stop_floor and now - f0 < PEAK_PASSED_FRACTION * (peak - f0)

    def watch(step: int, t: float) -> None:
        """Cheap invariants, every watch_every steps: a finite state, overlaps below max_overlap."""
        if not np.isfinite(u.sum() + v.sum()):
            bad = int(np.flatnonzero(~(np.isfinite(u) & np.isfinite(v)))[0])
            raise InvariantError(
                "finite state",
                t,
                step,
                min(bad, n - 2) + 1,
                f"displacement or velocity of bead {bad + 1} is not finite",
            )
        if max_overlap is not None:
            a = u[:-1] - u[1:]
            i = int(np.argmax(a))
            if a[i] > max_overlap:
                raise InvariantError(
                    "overlap far below the radius",
                    t,
                    step,
                    i + 1,
                    f"overlap {a[i]:.3g} m exceeds {max_overlap:.3g} m (half the radius)",
                )

    stopped = False
    step = 0
    extra_steps = 0
    max_splits = MAX_SPLITS_BASE + MAX_SPLITS_PER_CONTACT * (n - 1)  # per step (EventLocationError)
    last_event = {"contact": -1, "kind": ""}  # the crossing first_kink_crossing located last
    t = 0.0
    alpha_old = u[:-1] - u[1:]
    adot_old = v[:-1] - v[1:]
    for seg_start, seg_end, nseg, last, f_ext in plan:
        a_ext = f_ext * inv_m0
        if method == "verlet" and gamma and seg_start > 0.0:
            # LAMMPS starts each run by recomputing forces with the full-step velocities; the dashpot
            # is the only force that notices, and the reference does the same to stay step for step
            accel(u, a_int, v)
        for j in range(nseg):
            h = timestep if j < nseg - 1 else last
            t_new = seg_start + (j + 1) * timestep if j < nseg - 1 else seg_end
            if method == "verlet":
                v += 0.5 * h * a_int
                v[0] += 0.5 * h * a_ext
                u += h * v
                accel(u, a_int, v)  # the dashpot sees the half-step velocity, as in LAMMPS
                dash["energy"] += h * dash["power"]
                v += 0.5 * h * a_int
                v[0] += 0.5 * h * a_ext
                if history:
                    law.update_history(alpha_hist, u[:-1] - u[1:])
            elif event_location:
                # RK4 with the step split where a contact crosses a kink of its law, so that no
                # step integrates across a discontinuity of the force's derivative
                splits = 0
                while True:
                    h_sub = t_new - t
                    u_save[:] = u
                    v_save[:] = v
                    e_save = dash["energy"]
                    rk4_step(h_sub, a_ext)
                    s_ev = first_kink_crossing(h_sub)
                    if s_ev is None:
                        break
                    splits += 1
                    if splits > max_splits:
                        raise EventLocationError(
                            f"RK4 event location split step {step + 1} (t = {t:.6g} s, time step "
                            f"{timestep:.6g} s) {max_splits} times and still finds a kink: contact "
                            f"{last_event['contact'] + 1} ({last_event['kind']}) at s = {s_ev:.3g} of "
                            f"the remaining {h_sub:.3g} s. This is a bug of the reference solver: please "
                            "report it with the scene; meanwhile method 'verlet' (--method verlet) runs "
                            "without event location"
                        )
                    u[:] = u_save
                    v[:] = v_save
                    dash["energy"] = e_save
                    rk4_step(s_ev * h_sub, a_ext)
                    extra_steps += 2
                    track_peaks(t, t + s_ev * h_sub)
                    t = t + s_ev * h_sub
            else:
                rk4_step(h, a_ext)
            step += 1
            if step == progress_at:
                progress_at = progress.update(step)
            if method == "verlet":
                sample_forces(t_new)
            else:
                track_peaks(t, t_new)
            t = t_new
            if len(hist_idx) and step % history_stride == 0:
                record_history(t)
            if step % energy_every == 0 and t < seg_end:
                energy_row(t)
            if step % watch_every == 0:
                watch(step, t)
            if stop_after is not None and step % STOP_CHECK_EVERY == 0 and wave_passed(stop_after):
                stopped = True
                break
        if stopped:
            watch(step, t)
            energy_row(t)
            break
        watch(step, t)  # also at every breakpoint, so a short run is watched too
        # ---- breakpoint reached exactly
        t = seg_end
        if problem.amplitude and seg_end == problem.duration:
            u0_at_load_end = float(u[0])
        if seg_end in snapshot_set:
            snaps[seg_end] = (u.copy(), v.copy(), forces_now())
        energy_row(t)

    if progress is not None:
        progress.finish(step)

    # no extra history row at the end: the samples are every history_stride steps from t = 0 in both
    # backends (LAMMPS's dump writes only those), so the two tables have the same rows

    if method == "verlet":
        peak_force, tmax, force_min = fpk, tpk, fmin
    else:
        peak_force = np.asarray(law.force_at_peak_overlap(amax), dtype=float)
        force_min = np.asarray(law.force(np.maximum(amin, 0.0), alpha_hist), dtype=float)
    time_of_peak = unreached_as_nan(peak_force, tmax, f0)
    e = np.asarray(e_rows)
    # remove duplicate times (a breakpoint may coincide with a periodic sample)
    _, keep = np.unique(e[:, 0], return_index=True)
    e = e[np.sort(keep)]
    snap_t = np.asarray(sorted(snaps))
    sol = ChainSolution(
        method=method,
        timestep=timestep,
        steps=step,
        extra_steps=extra_steps,
        wall_time=time.perf_counter() - t_wall,
        end_time=t,
        peak_overlap=amax,
        peak_force=peak_force,
        time_of_peak=time_of_peak,
        force_min_after_peak=force_min,
        complete=complete_peaks(peak_force, force_min, time_of_peak, f0),
        leading_pulse_force=np.where(np.isfinite(time_of_peak), lead_f, np.nan),
        leading_pulse_time=np.where(np.isfinite(time_of_peak), lead_t, np.nan),
        history_contacts=tuple(int(i) for i in hist_idx),
        history_time=h_t[:nrec].copy(),
        history_force=h_f[:nrec].copy(),
        history_velocity=h_v[:nrec].copy(),
        snapshot_time=snap_t,
        snapshot_displacement=np.array([snaps[s][0] for s in snap_t]).reshape(len(snap_t), n),
        snapshot_velocity=np.array([snaps[s][1] for s in snap_t]).reshape(len(snap_t), n),
        snapshot_force=np.array([snaps[s][2] for s in snap_t]).reshape(len(snap_t), n - 1),
        energy_time=e[:, 0],
        kinetic=e[:, 1],
        potential=e[:, 2],
        dissipated=e[:, 3],
        work=e[:, 4],
        displacement=u,
        velocity=v,
        alpha_max=alpha_hist,
        impulse_delivered=problem.amplitude * min(problem.duration, t),
        momentum=float(np.dot(mass_ke, v)),
    )
    return sol
