"""The reference solver's integrators: velocity Verlet, and classical RK4 with event location.

Each advances a ChainState (granchain.reference.state) by one step of the step plan, with the step
load constant over the step (f enters as a_ext, its acceleration of bead 1), and writes the law's
history alpha_max once per accepted step:

* Verlet raises alpha_max to alpha at the step's end, which is what a LAMMPS pair style does at each
  force evaluation, so the two agree step for step.
* RK4 freezes alpha_max over its stages (trial points, not states of the trajectory) and raises it
  after each accepted piece to the maximum of the quartic interpolant of alpha over the piece,
  so the history misses the true maximum by O(h^4), not O(h^2). With event location a step that
  crosses a kink of the contact law (law.kinks, law.turn_level) is split there, so that no piece
  integrates across a jump in the force's derivatives.

An integrator also says what "the contact forces now" are for outputs (contact_forces): Verlet's are
the last force evaluation, at the step's end, which is what LAMMPS dumps.

The integrators live in their own modules: the interface in granchain.reference.stepping, velocity
Verlet in granchain.reference.verlet, RK4 in granchain.reference.rk4 and its event location in
granchain.reference.events; this module names them all.
"""

from granchain.reference.events import (
    EPS,
    KINK_ROUNDOFF,
    Crossings,
    Piece,
    crossing,
    earliest,
    first_crossing_scalar,
    first_kink_crossing,
    kink_roots,
    roundoff,
    turns_above,
)
from granchain.reference.rk4 import EventLocationError, RK4Integrator
from granchain.reference.stepping import Integrator, SplitHook
from granchain.reference.verlet import VerletIntegrator

__all__ = [
    "EPS",
    "KINK_ROUNDOFF",
    "Crossings",
    "EventLocationError",
    "Integrator",
    "Piece",
    "RK4Integrator",
    "SplitHook",
    "VerletIntegrator",
    "crossing",
    "earliest",
    "first_crossing_scalar",
    "first_kink_crossing",
    "kink_roots",
    "roundoff",
    "turns_above",
]
