"""The run's schedule, the same for every backend: the step plan (segments between breakpoints, so
that the load's end, every snapshot and the end time are step boundaries), the time after every
step, how often a stop condition is checked, and the sampling strides of histories and dumps.

Both backends and the deck builder read it, so their steps, stop checks and samples coincide.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from granchain.exceptions import UsageError
from granchain.physics.estimates import highest_frequency

STOP_CHECK_EVERY = 10  # steps between checks of a stop condition (the decks' fix halt uses the same)


@dataclass(frozen=True)
class Segment:
    """A stretch of the run between two breakpoints (load end, snapshot, end), in equal steps.

    ``steps`` steps: all of length dt except the last, of length ``last`` (<= dt), which lands
    exactly on ``end``. ``loaded``: the step load acts over the whole segment.
    """

    start: float
    end: float
    steps: int
    last: float
    loaded: bool


def step_plan(end_time: float, dt: float, load_duration: float = 0.0, snapshots=()) -> list[Segment]:
    """Split a run into segments so that T (if a load ends inside the run), every snapshot time and
    the end time are step boundaries. Used by every backend, so their steps coincide."""
    pts = {float(end_time)}
    if 0.0 < load_duration < end_time:
        pts.add(float(load_duration))
    pts.update(float(s) for s in snapshots if 0.0 < s < end_time)
    plan, start = [], 0.0
    for bp in sorted(pts):
        n = max(1, math.ceil((bp - start) / dt * (1.0 - 1e-12)))
        last = (bp - start) - (n - 1) * dt
        if abs(last - dt) <= 1e-9 * dt:  # a whole number of steps up to round-off: keep dt exactly
            last = dt
        plan.append(Segment(start, bp, n, last, load_duration > 0.0 and start < load_duration))
        start = bp
    return plan


def step_times(plan: list[Segment], dt: float) -> np.ndarray:
    """Time after every step of a plan, index = step number (0 = start): maps dump steps to times."""
    # start + k dt in numpy's float64 arithmetic: the same products and sums, bit for bit, as the
    # Python loop it replaces (float(k) * dt + start), without a Python step per step (a campaign
    # point's readback and watch made it ~10 ms a run)
    parts = [np.zeros(1)]
    for g in plan:
        parts.append(g.start + np.arange(1, g.steps, dtype=float) * dt)
        parts.append(np.array([g.end], dtype=float))
    return np.concatenate(parts)


def scene_step_plan(scene) -> list[Segment]:
    """The step plan of a scene's run: breakpoints at the end of a force load, every snapshot and the end."""
    ld = scene.loading
    return step_plan(scene.run.end_time, scene.run.timestep, ld.duration if ld.timed else 0.0, scene.outputs.snapshots)


def output_stride(omega_max: float, timestep: float, rtol: float = 1e-3) -> int:
    """Steps between output samples: the largest whose three-point-parabola peaks stay within rtol
    at the chain's highest frequency ((omega_max D)^4 / 16 <= rtol, see workflows.plan.plan_scene)."""
    return max(1, math.floor((16.0 * rtol) ** 0.25 / omega_max / timestep))


def history_stride(scene) -> int:
    """Steps between history samples: history_interval / timestep, at least 1 ("auto": the planner's)."""
    if scene.outputs.history_interval is None:
        return 1
    return _stride(scene, scene.outputs.history_interval)


def dump_stride(scene) -> int:
    """Steps between whole-chain dump frames (0: no whole-chain dump; "auto": the planner's)."""
    if scene.outputs.dump_interval is None:
        return 0
    return _stride(scene, scene.outputs.dump_interval)


def _stride(scene, interval) -> int:
    if scene.run.timestep is None:
        raise UsageError('[run] timestep = "auto": plan the scene first (granchain.plan or granchain.run)')
    if interval == "auto":  # what plan_scene would choose at its default rtol (the same function)
        return output_stride(highest_frequency(scene)[0], scene.run.timestep)
    return max(1, round(interval / scene.run.timestep))


#: Chain length (beads) at which two MPI ranks first beat one in LAMMPS's loop time on two otherwise
#: idle cores: below it the ranks' synchronisation every step (ghost positions, the neighbour check's
#: reduction) costs more than halving the chain saves. Measured by `python benchmarks/bench_pair.py mpi`
#: on a 2-core machine with both cores idle (benchmarks/RESULTS.md): np 1 / np 2 loop
#: time 1.12-1.24x at 1e3-3e3 beads (within the noise of 1), 1.67x at 1e4,
#: 1.86-2.12x at 3e4-3e5, 1.51x at 1e6. On cores that are busy with other work the ranks wait for each
#: other every step and the crossover moves far out (0.85x at 1e5, 1.12x at 3e5 with both cores busy), which
#: is why auto_ranks counts only idle cores.
MPI_CROSSOVER_BEADS = 10_000


def idle_cores(cores: int, load: float | None = None) -> int:
    """Cores not already busy: `cores` less the 1-minute load average (rounded), at least 1.

    Parameters
    ----------
    cores : int
        Cores this process may run on.
    load : float, optional
        Runnable processes averaged over the last minute; by default the OS's (os.getloadavg),
        taken as 0 where the OS has none.
    """
    if load is None:
        try:
            load = os.getloadavg()[0]
        except (AttributeError, OSError):  # pragma: no cover - not on a Unix
            load = 0.0
    return max(1, cores - round(load))


def auto_ranks(beads: int, cores: int) -> int:
    """MPI ranks for `--np auto`: one rank per MPI_CROSSOVER_BEADS / 2 beads (two ranks from the
    crossover on), at most one per (idle) core, at least 1."""
    return max(1, min(cores, (2 * beads) // MPI_CROSSOVER_BEADS))
