"""What the reference solver's driver asks of an integrator, and the ufuncs its inner loops share.

The integrators (granchain.reference.verlet, granchain.reference.rk4) subclass Integrator; the ufunc
aliases below are taken from module globals in their inner loops: outputs passed by position, about
0.15 us a call cheaper than out=.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from granchain.reference.state import ChainState

#: called after every piece of an RK4 step that event location split off, but the last: (state, t0, t1)
SplitHook = Callable[[ChainState, float, float], None]

_add, _multiply, _subtract, _less, _greater, _less_equal = (
    np.add,
    np.multiply,
    np.subtract,
    np.less,
    np.greater,
    np.less_equal,
)  # RK4Integrator.rk4: outputs by position, ~0.15 us a call cheaper than out=
_ZERO = np.array(0.0)  # 0-d: a cheaper operand than the Python float (RK4Integrator.rk4)


class Integrator:
    """What the driver asks of an integrator (granchain.reference.solver._drive)."""

    name = ""  # the integrator's name in granchain.integrators.INTEGRATORS, whose facts it implements
    extra_steps = 0  # steps beyond the plan's: rejected and split steps (RK4 event location)
    #: a load that changes within a step (a harmonic drive): t -> its acceleration of bead 1, added to
    #: a_ext at each stage's time; None: the load is constant over the step (the driver sets it per segment)
    drive: Callable[[float], float] | None = None

    @classmethod
    def for_run(cls, state: ChainState, timestep: float, event_location: bool, max_splits: int) -> Integrator:
        """The integrator of a run's state (solver._solve): timestep, the plan's step; event_location and
        max_splits, the splits at the law's kinks for an integrator that locates them (RK4)."""
        return cls(state)

    def start(self, state: ChainState) -> None:
        """The run begins at state (t = 0)."""

    def start_segment(self, state: ChainState, seg_start: float) -> bool:
        """A new LAMMPS run in the deck begins at seg_start: a segment of the step plan, or a segment's
        shorter last step (the deck's ``timestep``; ``run 1``). True if the integrator recomputed the
        contact forces there, as LAMMPS's setup does (the observers then see them: after_setup)."""
        return False

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
