"""The state a reference integrator advances and its observers read.

One object per run holds the chain's displacements u, velocities v and the law's history alpha_max,
the padded contact-force buffer and the work arrays the force evaluation writes into (allocated once:
the inner loop allocates as little as numpy lets it), the damping's energy, the time and step count,
and the last accepted piece's overlaps, rates and turning contacts (RK4's dense output, which the
peak tracking reads instead of computing it again).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from granchain.physics.effects import EFFECTS, body_acceleration
from granchain.physics.laws import ContactLaw
from granchain.problem import ChainProblem, initial_state, moving_mass, static_contact_forces

#: accel(u, out, v) -> damping power: the accelerations of the state (u, v) into out; also leaves the
#: contact forces in the state's force buffer. make_accel's own also take overlaps = u[:-1] - u[1:]
#: where the caller has them already (RK4Integrator.lean_step: the state's alpha_now)
Accel = Callable[..., float]


class ChainState:
    """(u, v, alpha_max) of a chain and what a step needs preallocated.

    Attributes
    ----------
    u, v : ndarray (N,)
        Displacements and velocities, updated in place (observers may hold references).
    alpha_hist : ndarray (N-1,)
        The law's history alpha_max, frozen within a step and raised once per accepted step.
    static_force : ndarray (N-1,)
        Each contact's static force at t = 0 (precompression's F0 plus gravity's weight above it).
    fp, fc : ndarray
        The padded force buffer: fp[0] the static push on bead 1, fc = fp[1:N] the contact forces of
        the last force evaluation, fp[N] the pull on a free bead N; a = (fp[:-1] - fp[1:]) / m.
    a_int : ndarray (N,)
        Accelerations of the last full-step evaluation (velocity Verlet's second half-kick).
    accel : Accel
        The force evaluation over these buffers.
    damped : bool
        The problem's damping part depends on velocity: the force evaluation takes the velocities.
    damping_energy : float
        Energy the damping has taken out so far.
    t, step, seg_end : float, int, float
        Time and steps taken (set by the driver after each step), and the end of the current segment.
    alpha_now, adot_now : ndarray (N-1,)
        Overlaps and their rates at the end of the last accepted piece (RK4; the t = 0 values before).
    turning, turn_peak, turn_time : ndarray
        Contacts whose overlap turned from rising to falling within that piece, and the maximum of
        the Hermite interpolant there and its time (RK4).
    """

    def __init__(self, problem: ChainProblem) -> None:
        n = problem.beads
        self.problem = problem
        self.law: ContactLaw = problem.law
        self.n = n
        self.inv_m = 1.0 / problem.mass  # 0 for an immovable wall bead
        self.mass_ke = moving_mass(problem.mass)  # the wall neither moves nor counts
        self.damped = problem.damping_part.velocity_dependent
        # each contact's force at rest: F0 plus the weight above it (a striker's in front: unloaded)
        self.static_force = np.zeros(n - 1)
        f0 = float(problem.precompression)
        # (a shaker's driver, mass inf, carries its weight itself: moving_mass)
        self.static_force[problem.front :] = static_contact_forces(
            moving_mass(problem.mass[problem.front :]), f0, problem.gravity
        )
        # the static force the leading pulse and its ladder rise above: F0, or under gravity the largest
        # (the wall's, F0 + the chain's weight: the deck's pair style takes one value for every contact)
        self.f0 = float(np.max(self.static_force, initial=0.0))
        self.free_end = bool(np.isfinite(problem.mass[-1]))
        # at rest (bead 1 possibly moving), or precompressed in static equilibrium
        self.u, self.v, self.alpha_hist = initial_state(problem)
        self.t = 0.0
        self.step = 0
        self.seg_end = 0.0
        self.damping_energy = 0.0
        self.fp = np.zeros(n + 1)
        self.fc = self.fp[1:n]
        # the static push on bead 1 and pull on a free bead N (precompression): the push is fp[0] when
        # bead 1 is the first bead; behind a striker it joins the load on bead 1 (a_ext, load_bead)
        self.load_bead = problem.front
        push = sum(effect.static_forces(problem, self.fp) for effect in EFFECTS.values())
        self.static_push = push if self.load_bead else 0.0
        if not self.load_bead:
            self.fp[0] = push
        self.accel = make_accel(problem, self.law, self.inv_m, self.fp, self.alpha_hist)
        # a chain of equal masses: RK4 takes the net forces and folds 1/m into its step's factors
        # (one numpy call fewer per force evaluation); None with unequal masses (a striker, a wall,
        # a taper) or an effect's own force evaluation (damping)
        inv_m0 = float(self.inv_m[0])
        self.uniform_inv_m = inv_m0 if inv_m0 > 0.0 and bool((self.inv_m == inv_m0).all()) else None
        self.net_force = None
        if self.uniform_inv_m is not None:
            self.net_force = make_accel(problem, self.law, None, self.fp, self.alpha_hist)
        self.a_int = np.empty(n)
        self.accel(self.u, self.a_int, self.v)  # the forces at t = 0 (Verlet's first kick, the first force sample)
        self.alpha_now = self.u[:-1] - self.u[1:]
        self.adot_now = self.v[:-1] - self.v[1:]
        self.turning = np.empty(0, dtype=np.intp)
        self.turn_peak = self.turn_time = np.empty(0)

    def overlap(self) -> np.ndarray:
        """alpha = u_i - u_i+1 of every contact, now (a new array)."""
        return self.u[:-1] - self.u[1:]


def make_accel(
    problem: ChainProblem, law: ContactLaw, inv_m: np.ndarray | None, fp: np.ndarray, alpha_hist: np.ndarray
) -> Accel | None:
    """The force evaluation of a run: a closure over the preallocated buffers.

    A closure rather than a method: the inner loop calls it four times per RK4 step, and reading the
    buffers from cells costs less than from attributes. The contact forces land in fc = fp[1:-1]
    (with alpha_max frozen: the history is the caller's, see ChainState); the returned float is the
    damping's power at this evaluation (0 without one), which the integrator weights into its energy.
    An effect that changes the contact forces supplies its own (Effect.reference_accel: damping).
    inv_m None: the net contact force on each bead instead of its acceleration (a chain of equal
    masses, whose RK4 divides by the mass in its step's factors), or None where an effect has its own.
    A body force (gravity: Effect.body_acceleration) is added to every moving bead after the contacts.
    """
    return with_body_force(_contact_accel(problem, law, inv_m, fp, alpha_hist), problem, inv_m)


def with_body_force(accel: Accel | None, problem: ChainProblem, inv_m: np.ndarray | None) -> Accel | None:
    """accel plus the effects' body force (Effect.body_acceleration: gravity's g) on every moving bead
    (its force m g where accel gives net forces, inv_m None); accel itself without one. Without
    make_accel's parts: RK4 calls it at every stage rather than writing the contact forces out (a
    vertical chain's run is that much slower, every other run unchanged)."""
    g = body_acceleration(problem)
    if accel is None or not g:
        return accel
    mass = problem.mass
    moving = np.isfinite(mass)
    body = np.where(moving, g, 0.0) if inv_m is not None else np.where(moving, g * np.where(moving, mass, 0.0), 0.0)
    add = np.add

    def with_body(
        uu: np.ndarray, out: np.ndarray, vv: np.ndarray | None = None, overlaps: np.ndarray | None = None
    ) -> float:
        power = accel(uu, out, vv, overlaps) if overlaps is not None else accel(uu, out, vv)
        add(out, body, out)
        return power

    return with_body


def _contact_accel(
    problem: ChainProblem, law: ContactLaw, inv_m: np.ndarray | None, fp: np.ndarray, alpha_hist: np.ndarray
) -> Accel | None:
    """make_accel's contact forces alone."""
    for effect in EFFECTS.values():
        if inv_m is None:
            if effect.reference_accel(problem, law, np.ones(fp.size - 1), fp, alpha_hist) is not None:
                return None
            continue
        accel_effect = effect.reference_accel(problem, law, inv_m, fp, alpha_hist)
        if accel_effect is not None:
            return accel_effect
    n = fp.size - 1
    fc = fp[1:n]
    fp_left, fp_right = fp[:-1], fp[1:]
    alpha = np.empty(n - 1)
    tmp = np.empty(n - 1)
    zero = np.array(0.0)  # 0-d: numpy takes it faster than the Python float
    clip = not law.force_into_any_sign  # else force_into clips alpha itself
    force_into = law.force_into
    # ufuncs from cells and outputs passed by position: each call ~0.15 us cheaper than np.x(..., out=)
    subtract, multiply, maximum = np.subtract, np.multiply, np.maximum
    # the two views uu[:-1], uu[1:] of the arrays accel is called with (the state's u and RK4's stage
    # positions: a few, all run long), made once: slicing costs as much as a small ufunc call
    views: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    per_mass = inv_m is not None  # else the net contact forces (a chain of equal masses)

    def accel(
        uu: np.ndarray, out: np.ndarray, vv: np.ndarray | None = None, overlaps: np.ndarray | None = None
    ) -> float:
        if overlaps is None:
            view = views.get(id(uu))
            if view is None or view[0] is not uu:  # (the entry holds uu: its id is not reused while cached)
                view = (uu, uu[:-1], uu[1:])
                if len(views) < 8:
                    views[id(uu)] = view
            subtract(view[1], view[2], alpha)
            a = alpha
            if clip:
                maximum(alpha, zero, out=alpha)
        elif clip:  # overlaps: uu[:-1] - uu[1:] as the caller has them (RK4's state at a piece's start)
            maximum(overlaps, zero, out=alpha)
            a = alpha
        else:
            a = overlaps  # (force_into only reads it)
        force_into(a, alpha_hist, fc, tmp)  # with alpha_max frozen within the step
        subtract(fp_left, fp_right, out)
        if per_mass:
            multiply(out, inv_m, out)
        return 0.0

    # its buffers and steps, for a caller that writes the evaluation out in its own loop (RK4's stages
    # 2-4: the same calls on the same buffers, without a Python call and the views lookup each)
    accel.parts = (alpha, tmp, fc, fp_left, fp_right, force_into, clip, zero, inv_m if per_mass else None, alpha_hist)
    return accel
