"""The invariants every run keeps, and the bounds the run watch uses (one place for both backends).

These are blow-up and garbage detectors, not accuracy targets: a run inside them may still be too
coarse for a given rtol (that is the planner's and `granchain accuracy`'s job). The accuracy-level
bounds (elastic drift, bilinear balance to 1e-6 of the work, momentum = impulse to round-off) are
tested on planned runs in tests/test_hard_cases.py and listed in docs/hard-cases.md.

finite state      no NaN or inf in displacements and velocities
overlap           every contact's overlap below OVERLAP_WATCH x the smaller radius of its own two
                  bodies (contact_overlap_bounds: beads, a striker; a wall's flat has no radius, so
                  bead N's); LAMMPS holds each contact's force to its law's virgin-curve force at
                  that overlap (templates.run_control.contact_force_bounds). Why each contact's own
                  radii: Hertz's theory (the paper's Eqs. 1-3) needs the overlap small against the
                  radii of curvature of the two bodies that touch (its R* = R_a R_b / (R_a + R_b) lies
                  between half the smaller radius and the smaller radius); no other bead's radius
                  enters. The smaller one fails first: the smaller sphere's cap inside the overlap is
                  up to alpha deep, so at alpha = R_small it reaches about its centre, and beads passing
                  through each other go far beyond. The paper's own I = 0.4 N s pulse reaches 11% of
                  R. A taper's big beads may overlap more than half its smallest bead's radius and be
                  fine: a bound on the whole chain's smallest radius would stop them. On a uniform chain
                  this is the same bound, OVERLAP_WATCH x R, on every contact. (OVERLAP_WATCH lives in
                  granchain.physics.effects: the planner's frequency bound holds each contact's force
                  to its law's force there, physics.effects.watched_force.)
energy balance    |kinetic + stored + dissipated - work| <= ENERGY_WATCH x the largest energy put in
                  so far. Numbers behind the bound (default scene, dt as a fraction of the
                  predicted stability limit): Verlet 0.4% / 1.9% / 9% at 0.25 / 0.5 / 0.9 of it and
                  38% at the limit; RK4 loses energy instead (1.9% at 0.25, 34% at 0.5: its damping
                  of the stiffest contact's frequency), while planned steps keep both below 1e-4.
momentum          a chain without an effect that exerts external forces (wall, precompression:
                  Effect.conserves_momentum): total momentum = initial momentum + the
                  impulse delivered so far, to MOMENTUM_WATCH of the larger of the two (forces
                  between beads are equal and opposite, so this holds to round-off in both backends)
"""

from __future__ import annotations

import numpy as np

from granchain.exceptions import GranchainError
from granchain.physics.effects import OVERLAP_WATCH, external_forces
from granchain.schedule import step_plan, step_times

ENERGY_WATCH = 0.05
MOMENTUM_WATCH = 1e-6
# DRIVE_MOMENTUM: why no momentum watch runs under a harmonic drive (the deck's, the reference's and
# check_solution's): each integrator delivers the drive's impulse by its own quadrature of f(t) over a
# step (velocity Verlet the trapezoid, RK4 Simpson's rule), which misses the closed form
# (granchain.physics.harmonic.drive_impulse) by O((w h)^2 w t / 12) of A / w, above MOMENTUM_WATCH's
# round-off bound; the energy watch still runs (the drive's work summed per step)


def contact_overlap_bounds(scene) -> np.ndarray:
    """The run watch's overlap bound of every contact, m: OVERLAP_WATCH x the smaller radius of its two
    bodies (the module's docstring says why).

    Parameters
    ----------
    scene : granchain.scene.Scene
        The scene.

    Returns
    -------
    ndarray
        One bound per contact of the chain the solvers integrate (ChainProblem.with_ends): a
        striker's contact with bead 1 first (the smaller of the striker's and bead 1's radii; a
        shaker's driver's flat: bead 1's), then
        contacts 1 .. N-1 (beads i and i+1), then a wall's contact with bead N (a flat: bead N's
        radius). LAMMPS's atoms are in the same order (templates.atoms.AtomLayout), each contact on
        its left body's atom.
    """
    r = np.asarray(scene.bead_radii, dtype=float)
    smaller = [np.minimum(r[:-1], r[1:])]
    if scene.loading.kind == "striker":
        smaller.insert(0, np.array([min(float(scene.loading.striker_radius), float(r[0]))]))
    if scene.loading.is_shaker:  # the driver's flat on bead 1: bead 1's radius
        smaller.insert(0, r[:1])
    if scene.effects.far_end == "wall":
        smaller.append(r[-1:])
    return OVERLAP_WATCH * np.concatenate(smaller)


def front_body(shaker: bool, front: int) -> bool | str:
    """contact_bodies' body in front of bead 1: "the shaker's driver", a striker (True) or none (False)."""
    return "the shaker's driver" if shaker else front > 0


def contact_bodies(contact: int, beads: int, striker: bool | str, wall: bool) -> str:
    """What contact number `contact` joins, as the scene numbers contacts: "beads i and i+1", "the
    striker and bead 1" (contact 0 behind a striker; striker: a str names the body in front, a shaker's
    driver), "bead N and the wall" (contact N with a wall)."""
    if striker and contact == 0:
        return f"{striker if isinstance(striker, str) else 'the striker'} and bead 1"
    if wall and contact == beads:
        return f"bead {beads} and the wall"
    return f"beads {contact} and {contact + 1}"


class InvariantError(GranchainError, RuntimeError):
    """A run broke an invariant; says which, when, where, and (from the workflow) the fix."""

    def __init__(self, invariant: str, time: float, step: int, contact: int, detail: str, fix: str = ""):
        self.invariant, self.time, self.step, self.contact, self.detail = invariant, time, step, contact, detail
        msg = f"invariant '{invariant}' broken at t = {time:.6g} s (step {step}), contact {contact}: {detail}"
        super().__init__(msg + (f"; {fix}" if fix else ""))


def energy_violation(balance_error: float, scale: float, bound: float = ENERGY_WATCH) -> str | None:
    """The detail text if |E - W| exceeds bound x scale (scale: the largest energy put in so far)."""
    if scale > 0.0 and not abs(balance_error) <= bound * scale:  # `not <=` also catches NaN
        what = "created" if balance_error > 0 else "lost"
        return (
            f"kinetic + stored + dissipated - work = {balance_error:.3g} J: {abs(balance_error) / scale:.2g} "
            f"of the {scale:.3g} J put in was {what} by the integrator (bound {bound:g})"
        )
    return None


def momentum_violation(momentum: float, expected: float, bound: float = MOMENTUM_WATCH) -> str | None:
    """The detail text if the total momentum misses the expected one by more than bound x the larger.

    Parameters
    ----------
    momentum : float
        The chain's total momentum (kg m/s).
    expected : float
        The initial momentum plus the impulse the load delivered so far (kg m/s): what a chain
        whose forces are all between its beads keeps, to round-off.
    bound : float
        Relative bound, MOMENTUM_WATCH by default.

    Returns
    -------
    str or None
        What broke, with both numbers and the bound; None when the momentum is kept.
    """
    scale = max(abs(momentum), abs(expected))
    if scale > 0.0 and not abs(momentum - expected) <= bound * scale:
        return (
            f"total momentum {momentum:.9g} kg m/s differs from the initial momentum plus the impulse "
            f"delivered, {expected:.9g} kg m/s (relative bound {bound:g})"
        )
    return None


def check_solution(scene, sol, steps: int | None = None) -> None:
    """Post-run check of a finished LAMMPS solution, behind the deck's own in-run watch (fix halt on
    the same bounds, templates/watch.lmp.j2): it also uses the running maximum of the energy put in.

    Raises InvariantError for the first broken invariant found: finite state, energy balance at
    every energy sample, and momentum at the end where no effect exerts external forces.
    """
    steps = sol.steps if steps is None else steps
    u, v = np.asarray(sol.displacement), np.asarray(sol.velocity)
    bad = np.flatnonzero(~(np.isfinite(u) & np.isfinite(v)))
    if bad.size:
        b = int(bad[0])
        raise InvariantError(
            "finite state",
            sol.end_time,
            steps,
            min(b, len(u) - 2) + 1,
            f"displacement or velocity of bead {b + 1} is not finite",
        )
    e = np.asarray(sol.kinetic) + np.asarray(sol.potential) + np.asarray(sol.dissipated) - np.asarray(sol.work)
    put_in = np.maximum.accumulate(
        np.maximum(np.abs(np.asarray(sol.work)), np.asarray(sol.kinetic) + np.asarray(sol.potential))
    )
    for k in range(len(e)):
        detail = energy_violation(float(e[k]), float(put_in[k]))
        if detail:
            t = float(sol.energy_time[k])
            ld = scene.loading
            grid = step_times(
                step_plan(scene.run.end_time, scene.run.timestep, ld.duration if ld.is_force else 0.0),
                scene.run.timestep,
            )
            step = int(np.searchsorted(grid, t * (1 - 1e-12)))
            raise InvariantError("energy balance", t, step, _busiest_contact(sol), detail)
    if not external_forces(scene) and not scene.loading.is_harmonic:  # no external forces (DRIVE_MOMENTUM)
        detail = momentum_violation(sol.momentum, scene.initial_momentum + sol.impulse_delivered)
        if detail:
            raise InvariantError("momentum", sol.end_time, steps, _busiest_contact(sol), detail)


def _busiest_contact(sol) -> int:
    """1-based contact with the largest peak force (where a numerical failure starts)."""
    f = np.nan_to_num(np.asarray(sol.peak_force, dtype=float), nan=-1.0)
    return int(np.argmax(f)) + 1 if f.size else 1
