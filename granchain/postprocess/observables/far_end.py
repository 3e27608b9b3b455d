"""A free far end's event ([outputs] event = true on a chain without a far-end wall): what the last
bead carries off.

With no wall, the wave that reaches the far end throws bead N off the chain. Its event has ended once
bead N has left the rest for good: its contact with bead N - 1 is open and no body behind it can ever
catch it. The proof (left_behind_for_good) is physics.event.left_for_good's, with bead N in the
wall's place: every body before bead N (the striker too), taken as one group, moves relative to its
centre of mass no faster than the group's internal energy allows (its kinetic energy less its centre
of mass's, plus all the energy stored in the contacts: no external force acts once the load is over,
the contacts only store or dissipate), so the fastest any of them can ever move is
V_g + sqrt(2 E_g / m_(N-1)); at most v_N, bead N flies free for ever. From then on bead N's velocity
is constant: its kinetic energy and momentum at the end of the run are what reached the far end, on
both backends alike (read from the end state, no per-step sum).
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from granchain.postprocess.observables.base import Measurement, Observable


def left_behind_for_good(v: np.ndarray, m: np.ndarray, gap_open: bool, stored: float) -> bool:
    """Whether bead N has left the rest of an unloaded free chain for good (the module's rule).

    Parameters
    ----------
    v, m : ndarray
        Every moving body's velocity (m/s, towards the far end positive) and mass (kg), in chain
        order (a striker first, bead N last).
    gap_open : bool
        Whether bead N's contact with bead N - 1 is open (its overlap at most 0).
    stored : float
        The energy stored in every contact (J).

    Returns
    -------
    bool
        The contact is open and V_g + sqrt(2 E_g / m_(N-1)) <= v_N, the group being every body but
        bead N.
    """
    if not gap_open or v.size < 2:
        return False
    mg = float(np.sum(m[:-1]))
    pg = float(np.sum(m[:-1] * v[:-1]))
    vg = pg / mg
    e = max(float(np.sum(0.5 * m[:-1] * v[:-1] ** 2)) - 0.5 * pg * vg + stored, 0.0)
    return vg + math.sqrt(2.0 * e / float(m[-2])) <= float(v[-1])


class FarEndEnergy(Observable):
    """The kinetic energy and momentum bead N carries off a free far end, once it has left for good."""

    name = "far_end_energy"
    unit = "J"
    definition = (
        "the energy that reaches a free far end: bead N's kinetic energy once it has left the rest of the chain "
        "for good (its contact open, no body behind able to catch it); far_end_momentum: its momentum m_N v_N"
    )
    needs = frozenset({"end_state"})
    companions: ClassVar[dict[str, str]] = {"far_end_momentum": "N s"}
    shares_reason = ("far_end_momentum",)
    table_fields = ("far_end_momentum",)
    asked = True
    compared = True
    # bead N's velocity is constant once it has left for good: each companion run's end state measures the
    # same number, its time-step error smooth in dt (Verlet's order 2), so the companions' route applies
    error_bar = (
        "the time step's error from the companion runs at 2 dt and 4 dt, each reading bead N's end state once it "
        "has left for good"
    )
    applies_where = "a chain with a free far end, unprecompressed, with [outputs] event = true"

    def applies(self, scene) -> str | None:
        """None on a free, unprecompressed chain asking for the event, else why not."""
        if scene.effects.far_end == "wall":
            return "a chain on a far-end wall: what reaches it is the wall's (wall_energy, wall_impulse)"
        if not scene.outputs.event:
            return "not asked for: [outputs] event = true measures what reaches the far end"
        if scene.effects.precompression:
            return "a precompressed free chain: bead N is held on the chain, it does not leave"
        return super().applies(scene)

    def measure(self, scene, solution) -> Measurement:
        """Bead N's kinetic energy and momentum at the end of the run, where it has left for good."""
        m = np.asarray(scene.bead_masses, dtype=float)
        v = np.asarray(solution.velocity, dtype=float)
        u = np.asarray(solution.displacement, dtype=float)
        ld = scene.loading
        if ld.kind == "striker":  # the striker is a body behind bead 1
            m = np.concatenate(([float(scene.striker_mass)], m))
            v = np.concatenate(([float(solution.striker_velocity)], v))
        over = not ld.is_force or solution.end_time > float(ld.duration)
        stored = float(solution.potential[-1]) if solution.potential.size else 0.0
        if not (over and left_behind_for_good(v, m, bool(u[-2] - u[-1] <= 0.0), stored)):
            return Measurement(
                None,
                {"far_end_momentum": None},
                f"bead N had not left the chain for good when the run ended (t = {solution.end_time:g} s): its "
                "contact still closed, or a body behind it still able to catch it. Run longer: a longer [run] end_time",
            )
        return Measurement(0.5 * float(m[-1]) * float(v[-1]) ** 2, {"far_end_momentum": float(m[-1]) * float(v[-1])})
