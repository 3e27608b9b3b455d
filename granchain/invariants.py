"""The invariants every run keeps, and the bounds the run watch uses (one place for both backends).

These are blow-up and garbage detectors, not accuracy targets: a run inside them may still be too
coarse for a given rtol (that is the planner's and `granchain accuracy`'s job). The accuracy-level
bounds (elastic drift, bilinear balance to 1e-6 of the work, momentum = impulse to round-off) are
tested on planned runs in tests/test_hard_cases.py and listed in docs/hard-cases.md.

finite state      no NaN or inf in displacements and velocities
overlap           every overlap below OVERLAP_WATCH x the smallest radius (the paper's own
                  I = 0.4 N s pulse reaches 11% of R; beads passing through each other go far beyond)
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
from granchain.physics.effects import external_forces
from granchain.schedule import step_plan, step_times

ENERGY_WATCH = 0.05
MOMENTUM_WATCH = 1e-6
OVERLAP_WATCH = 0.5


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
    if not external_forces(scene):  # no effect exerts external forces
        detail = momentum_violation(sol.momentum, scene.initial_momentum + sol.impulse_delivered)
        if detail:
            raise InvariantError("momentum", sol.end_time, steps, _busiest_contact(sol), detail)


def _busiest_contact(sol) -> int:
    """1-based contact with the largest peak force (where a numerical failure starts)."""
    f = np.nan_to_num(np.asarray(sol.peak_force, dtype=float), nan=-1.0)
    return int(np.argmax(f)) + 1 if f.size else 1
