"""Pure-Python (numpy) solvers of the chain equations (Eqs. 1-4): classical RK4 and velocity Verlet.

    m_i u_i'' = F_{i-1,i}(alpha_{i-1,i}) - F_{i,i+1}(alpha_{i,i+1}),   alpha_{i,i+1} = u_i - u_{i+1}
    m_1 u_1'' = -F_{1,2} + f(t),   f(t) = A for 0 < t <= T (Eq. 4)

The solver is an integrator plus observers, run by a short driver over the step plan:

* granchain.reference.state: ChainState, the state (u, v, alpha_max, the force buffer and work
  arrays, RK4's dense output) and the force evaluation over it;
* granchain.reference.integrators: VerletIntegrator and RK4Integrator (with event location at the
  kinks the contact law declares), each a step function over the state;
* granchain.reference.observers: peak tracking (HermitePeaks for RK4, ForceSamplePeaks for Verlet),
  the leading pulse, the history/snapshot Recorder, the EnergyLedger, the RunWatch and the EarlyStop;
* this module: solve_chain (striker and wall as extra beads), _solve (builds the three and drives them).

Design choices (each tested in tests/test_reference.py):

* The step load is exact: T, every snapshot time and the end time are step boundaries (the step
  before a boundary is shortened to land on it), and f is constant over every step. The impulse
  delivered is then sum(f h) = A T to round-off, for both methods. For velocity Verlet this is
  what LAMMPS does when the run is split at T (both half-kicks of a step see that step's load).
* History (alpha_max) is frozen during a step and updated once per accepted step.
  Stage values of a multi-stage method are trial points, not states of the trajectory, so
  letting them raise alpha_max would write non-physical history. Freezing costs nothing at
  loading (the loading curve does not depend on alpha_max) and only perturbs the step
  in which a contact turns from loading to unloading.
  - RK4: after the step alpha_max is raised to the maximum of the quartic interpolant of alpha
    over the step (alpha and d(alpha)/dt at both ends, d2(alpha)/dt2 at the start: reference.hermite
    says why not the cubic), so the history misses the true maximum by O(h^4), not O(h^2).
  - Verlet: alpha_max is raised to alpha at the step's end, which is what a LAMMPS pair style
    does at each force evaluation, so the two agree step for step.
* Peaks are tracked while running: a running maximum of every contact's overlap with its time,
  refined inside a step by the same interpolant. Every law is monotone in alpha on the
  loading path, so the peak force is F(alpha_peak). No step is stored for this.
* Energies: kinetic, stored (elastic), dissipated (the law's and the dashpot's) and the work of
  f(t), which for a step load is exactly A times the displacement of bead 1 while the load acts.
"""

from __future__ import annotations

import time

import numpy as np

from granchain.integrators import INTEGRATORS
from granchain.invariants import InvariantError
from granchain.peaks import complete_peaks, unreached_as_nan
from granchain.physics.effects import EFFECTS
from granchain.physics.harmonic import drive_function
from granchain.physics.shaker import shaker_acceleration
from granchain.problem import ChainProblem, static_contact_forces
from granchain.progress import Progress
from granchain.reference.drive import energy_ledger
from granchain.reference.event import EventTracker
from granchain.reference.hermite import hermite_max
from granchain.reference.integrators import (
    EPS,
    KINK_ROUNDOFF,
    EventLocationError,
    Integrator,
    RK4Integrator,
    VerletIntegrator,
)
from granchain.reference.leading import LeadingPulse
from granchain.reference.observers import (
    EarlyStop,
    ForceSamplePeaks,
    HermitePeaks,
    Observer,
    Recorder,
    RunWatch,
)
from granchain.reference.sensors import sensor_observers
from granchain.reference.state import ChainState
from granchain.results import ChainSolution
from granchain.schedule import STOP_CHECK_EVERY, Segment, step_plan

__all__ = [
    "EPS",
    "KINK_ROUNDOFF",
    "MAX_SPLITS_BASE",
    "MAX_SPLITS_PER_CONTACT",
    "IMPLEMENTATIONS",
    "METHODS",
    "ChainProblem",
    "EventLocationError",
    "InvariantError",
    "solve_chain",
]

#: the reference's integrators, one per integrator of granchain.integrators, by name
IMPLEMENTATIONS: dict[str, type[Integrator]] = {cls.name: cls for cls in (RK4Integrator, VerletIntegrator)}
#: the methods the reference runs (in the order of granchain.integrators.INTEGRATORS)
METHODS = tuple(name for name in INTEGRATORS if name in IMPLEMENTATIONS)
# RK4 event location: no step is split more often than MAX_SPLITS_PER_CONTACT per contact +
# MAX_SPLITS_BASE (each crossing takes one split, rarely two or three while the located point
# converges), else EventLocationError: a bug, not a slow run. Read by _solve at every run (so a test
# can lower the cap here); KINK_ROUNDOFF, the round-off within which a contact is at a kink, is the
# integrator's (granchain.reference.integrators).
MAX_SPLITS_PER_CONTACT = 8
MAX_SPLITS_BASE = 64

#: the maximum of the cubic Hermite interpolant over a step (granchain.reference.hermite; the
#: DOP853 yardstick, scipy_solver, refines its peaks with it too)
_hermite_max = hermite_max


def solve_chain(problem: ChainProblem, end_time: float, timestep: float, method: str = "rk4", **kw) -> ChainSolution:
    """Integrate the chain from rest (bead 1 possibly moving) to end_time.

    The effects' extra beads (ChainProblem.with_ends: a far-end wall is an immovable extra bead whose
    contact with bead N has the wall's law, a striker a moving one in front) are integrated with the
    chain and reported by Effect.end_fields (wall_peak_force, striker_velocity, ...). Keywords: see _solve.
    """
    if "progress" not in kw:  # progress on stderr for a long run (granchain.progress); closed if the run raises
        with Progress(None, f"reference {method}") as progress:
            return solve_chain(problem, end_time, timestep, method, progress=progress, **kw)
    inner = problem.with_ends()  # the effects' extra beads: a striker in front, a wall (immovable) at the end
    if inner is problem:
        return _solve(problem, end_time, timestep, method, **kw)
    n = problem.beads
    carried = [e for e in EFFECTS.values() if e.in_problem(problem)]
    # index of bead 1 inside: behind the effects' beads in front (a striker) and a shaker's driver
    s0 = sum(e.beads_in_front for e in carried) + int(problem.shaker)
    for key in ("histories", "sensors"):  # contacts and beads inside count the beads in front first
        if key in kw:
            kw[key] = tuple(i + s0 for i in kw[key])
    if "event_maxima" in kw:
        kw["event_maxima"] = tuple(tuple(i + s0 for i in x) for x in kw["event_maxima"])
    if kw.get("stop_after") is not None:
        kw["stop_after"] += s0  # contact numbers inside count the striker's contact first
    sol = _solve(inner, end_time, timestep, method, **kw)
    every = sol.complete  # every contact's, each with its own static force (peaks.every_contact_complete)
    for effect in carried:  # what the results report of the extra beads (Effect.end_fields)
        for name, value in effect.end_fields(sol.peak_force, sol.time_of_peak, sol.velocity, -1, every).items():
            setattr(sol, name, value)
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
    static = static_contact_forces(np.append(problem.mass, np.inf), problem.precompression, problem.gravity)[: n - 1]
    sol.time_of_peak = unreached_as_nan(sol.peak_force, sol.time_of_peak, static)
    sol.complete = complete_peaks(sol.peak_force, sol.force_min_after_peak, sol.time_of_peak, static)
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
    sensors: tuple[int, ...] = (),
    sensor_stride: int = 0,
    history_stride: int = 1,
    snapshots: tuple[float, ...] = (),
    energy_samples: int = 200,
    event_location: bool = True,
    stop_after: int | None = None,
    stop_at_wall: bool = False,
    stop_at_reflection: bool = False,
    stop_floor: float = 0.0,
    event_floor: float | None = None,
    event_maxima: tuple = ((), ()),
    lead_floor: float = 0.0,
    lead_fall: float = 0.0,
    max_overlap: float | np.ndarray | None = None,
    energy_watch: float | None = None,
    momentum_watch: float | None = None,
    watch_every: int = 20,
    progress: Progress | None = None,
) -> ChainSolution:
    """Integrate the chain from rest (bead 1 possibly moving) to end_time.

    histories: 0-based contacts whose force (and the velocity of their left bead) is recorded every history_stride
    steps. sensors: 0-based beads (reference.sensors), every sensor_stride steps (0: none). snapshots: times (exact step
    boundaries) of whole-chain profiles. event_location (RK4 only): split steps where a contact's force law has a kink
    (see module doc). stop_after: 0-based contact; stop (checked every STOP_CHECK_EVERY steps, as LAMMPS's fix halt
    does) once its force has fallen below half its peak: the leading wave has passed it. Only a peak above stop_floor
    counts (round-off forces ahead of the wave must not stop the run). stop_at_wall, stop_at_reflection: it also waits
    for the wall's contact, then its reflection (EarlyStop); event_floor: the wall's event tracked (physics.event),
    begun above this rise (N), and waited for; event_maxima: the 0-based contacts and sensor beads whose largest force
    over it is tracked. lead_floor, lead_fall: a leading pulse's least rise above F0, and its fall that makes it one
    (peaks). max_overlap, energy_watch, momentum_watch: the run watch (granchain.invariants); None = off. max_overlap:
    one bound in m for every contact, or one per contact of the problem's chain with its ends (ChainProblem.with_ends: a
    striker's contact first, a wall's last; contact_overlap_bounds). Overlaps and a finite state are checked every
    watch_every steps and at breakpoints, the energy balance and the momentum of a free chain at every energy sample
    (~200 per run, as LAMMPS).
    progress: told the step count every ~0.1 s of steps (its update() names the next step to call it at).
    """
    _check_arguments(method, timestep, end_time)
    t_wall = time.perf_counter()
    state = ChainState(problem)
    plan = step_plan(end_time, timestep, problem.duration if problem.amplitude else 0.0, snapshots)
    total_steps = sum(g.steps for g in plan)
    integrator = _integrator(method, state, timestep, event_location)
    # where the overlap turns (Hermite), or the force sampled at step ends (IntegratorFacts.peaks_by_overlap)
    peaks = HermitePeaks(state) if INTEGRATORS[method].peaks_by_overlap else ForceSamplePeaks(state)
    ledger = energy_ledger(state, max(1, total_steps // max(1, energy_samples)))  # (a drive's: DrivenEnergyLedger)
    observers: list[Observer] = [
        peaks,
        LeadingPulse(state, peaks, lead_floor, lead_fall),
        Recorder(state, integrator.contact_forces, histories, history_stride, snapshots, total_steps),
        ledger,
        RunWatch(state, ledger, watch_every, max_overlap, energy_watch, momentum_watch),
    ]
    observers += sensor_observers(state, integrator.contact_forces, sensors, sensor_stride, total_steps)
    stop = (stop_after, stop_at_wall, stop_at_reflection, stop_floor, lead_fall, event_floor, event_maxima)
    observers += _event_and_stop(state, peaks, integrator, stop)
    _drive(state, integrator, plan, observers, timestep, progress)
    fields = {k: v for o in observers for k, v in o.finish(state).items()}  # in list order: leading pulse after peaks
    return ChainSolution(
        method=method,
        timestep=timestep,
        steps=state.step,
        extra_steps=integrator.extra_steps,
        wall_time=time.perf_counter() - t_wall,
        end_time=state.t,
        displacement=state.u,
        velocity=state.v,
        alpha_max=state.alpha_hist,
        impulse_delivered=float(problem.load_impulse(state.t)),
        momentum=float(np.dot(state.mass_ke, state.v)),
        **fields,
    )


def _check_arguments(method: str, timestep: float, end_time: float) -> None:
    """A caller's bug (the scene reader refuses a user's bad values first): an unknown method, a step
    or an end time that is not positive."""
    if method not in METHODS:
        raise ValueError(f"method = {method!r} is not known; choose one of {', '.join(METHODS)}")
    if not (timestep > 0 and end_time > 0):
        raise ValueError("timestep and end_time must be positive")


def _event_and_stop(state, peaks, integrator, stop: tuple) -> list[Observer]:
    """The stop check (stop: _early_stop's arguments after the peaks, then the event's floor and maxima;
    none where its contact is None) and the wall's event tracker (event_floor not None), which asks the
    stop check itself (both must have come to stop the run); maxima: the 0-based contacts and sensor
    beads whose largest force over the event it tracks."""
    *stop, event_floor, maxima = stop
    early = None if stop[0] is None else _early_stop(state, peaks, *stop)
    if event_floor is not None:
        return [EventTracker(state, integrator.contact_forces, event_floor, STOP_CHECK_EVERY, early, maxima)]
    return [] if early is None else [early]


def _early_stop(state, peaks, stop_after: int, at_wall: bool, at_reflection: bool, floor: float, fall: float):
    """The stop check's observer: contact stop_after, then the wall's (the last), then its reflection's
    through contact 1 (beads 1 and 2: inside, the contact after bead 1, past a striker's contact)."""
    contacts = (stop_after, state.n - 2) if at_wall else (stop_after,)
    back = state.load_bead if at_wall and at_reflection else None
    return EarlyStop(state, peaks, contacts, STOP_CHECK_EVERY, floor, fall, back)


def _integrator(method: str, state: ChainState, timestep: float, event_location: bool) -> Integrator:
    """The method's integrator of the state (RK4 with at most so many kink splits per step)."""
    max_splits = MAX_SPLITS_BASE + MAX_SPLITS_PER_CONTACT * (state.n - 1)  # per step
    return IMPLEMENTATIONS[method].for_run(state, timestep, event_location, max_splits)


def _start_run(integrator: Integrator, state: ChainState, t: float, observers: list[Observer]) -> None:
    """A LAMMPS run of the deck starts at t: its setup, and the observers see the forces it recomputed."""
    if integrator.start_segment(state, t):
        for observer in observers:
            observer.after_setup(state)


def _drive_function(p: ChainProblem, inv_m1: float):
    """The load's acceleration as a function of the time within a step (Integrator.drive), or None: a
    harmonic drive's on bead 1 (inv_m1: its 1 / m), a shaker's driver's own (granchain.physics.shaker)."""
    if not p.driven:
        return None
    if p.shaker:
        return shaker_acceleration(p.amplitude, p.frequency, p.ramp_time)
    return drive_function(p.amplitude, p.frequency, p.ramp_time, inv_m1)


def _drive(
    state: ChainState,
    integrator: Integrator,
    plan: list[Segment],
    observers: list[Observer],
    timestep: float,
    progress: Progress | None,
) -> None:
    """Step through the plan: the integrator advances the state, the observers look at it.

    Each step of a segment is timestep long but the last, which lands exactly on the segment's end
    (a breakpoint). The observers' after_step runs in list order every `every` steps; a stop takes
    effect once all of them have seen the step.
    """
    calls = [(ob.every, ob.after_step) for ob in observers if ob.every > 0]
    on_split = [ob.after_split for ob in observers if type(ob).after_split is not Observer.after_split]
    progress_at = -1 if progress is None else progress.start(sum(g.steps for g in plan))  # one int comparison per step
    inv_m1 = float(state.inv_m[state.load_bead])  # the load (and a striker's F0 push) act on bead 1
    push = state.static_push
    p = state.problem
    # a harmonic drive changes within a step: the integrator adds it at each stage's time (Integrator.drive);
    # a shaker's driver (bead 0, of infinite mass) moves with its prescribed acceleration
    drive = _drive_function(p, inv_m1)
    amplitude = 0.0 if p.driven else p.amplitude
    integrator.start(state)
    for observer in observers:
        observer.start(state)
    step, t = 0, 0.0
    for g in plan:
        a_ext = ((amplitude if g.loaded else 0.0) + push) * inv_m1
        integrator.drive = drive if g.loaded else None
        if p.shaker and not g.loaded:  # the drive's end: the driver stops where it is, and holds
            state.v[0] = 0.0
        _start_run(integrator, state, g.start, observers)
        state.seg_end = g.end
        stopped = False
        # a shorter last step is a LAMMPS run of its own in the deck (templates/chain.lmp.j2): its setup
        # recomputes the forces before it, as at a segment's start
        split_last = g.steps - 1 if g.steps > 1 and g.last != timestep else -1
        for j in range(g.steps):
            if j == split_last:
                _start_run(integrator, state, t, observers)
            h = timestep if j < g.steps - 1 else g.last
            t_new = g.start + (j + 1) * timestep if j < g.steps - 1 else g.end
            t0 = integrator.step(state, t, t_new, h, a_ext, on_split)
            step += 1
            state.step, state.t = step, t_new
            if step == progress_at:
                progress_at = progress.update(step)
            for every, after_step in calls:
                if step % every == 0 and after_step(state, t0, t_new):
                    stopped = True
            t = t_new
            if stopped:
                break
        for observer in observers:
            observer.end_segment(state)
        for observer in observers:
            observer.at_breakpoint(state, stopped)
        if stopped:
            break
    if progress is not None:
        progress.finish(step)
