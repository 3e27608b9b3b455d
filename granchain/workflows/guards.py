"""What a run will need before it starts -- steps, memory, disk, time -- and the refusal of a run this
machine cannot finish.

A planned scene says how many steps a run makes (end_time / timestep), how many beads it integrates
and what it writes (granchain.workflows.run.output_sizes). From these: the steps are refused above a
stated limit (MAX_STEPS, or GRANCHAIN_MAX_STEPS in the environment); the memory above what this
machine has available now (/proc/meminfo's MemAvailable); the disk above what is free where the run
directory and LAMMPS's work directory go (shutil.disk_usage). Each refusal gives the estimate and the
way out; above WARN_SECONDS of estimated wall time, or half the available memory, a warning.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

from granchain.backends import Backend, backend_named
from granchain.exceptions import UsageError
from granchain.schedule import dump_stride, history_stride

#: the most steps a run may make unless GRANCHAIN_MAX_STEPS says otherwise: 1e9 steps of even a short
#: chain are a day of the reference solver; more is a time step or an end time mistyped
MAX_STEPS = 1e9
#: a run estimated to take longer than this is announced before it starts
WARN_SECONDS = 3600.0
#: bytes per bead the solvers hold: positions, velocities, overlaps, forces and the integrator's
#: stages (RK4: four of each), the peak tracker's per-contact arrays, the tables written (a reference
#: run of 10^6 beads with its error estimate: 420 MB above the process's own); LAMMPS's per-atom
#: arrays are of the same order
BYTES_PER_BEAD = 500
#: the reference solver's cost of a step: a fixed part and a part per bead (RK4 on a Hertz chain,
#: measured on 100 and 10^4 beads: 97 and 666 us a step, Verlet about half; a plastic law with its error
#: estimate's companions: 1.1 us per bead-step on 10^5 beads), taken between the two. Only for the
#: announcement of a long run
STEP_SECONDS, BEAD_STEP_SECONDS = 60e-6, 3e-7
#: the size of the files every run writes whatever its length (peak table, summary, scene, log)
FIXED_BYTES = 1e6


#: bytes of one atom line of a granchain dump: 10 columns at %.17g (granchain/templates/*dump*.j2)
DUMP_LINE_BYTES = 230
DUMP_FRAME_HEADER_BYTES = 200


#: the files of output_sizes every backend's run directory gets (the others are Backend.work_files)
RUN_DIR_TABLES = ("histories.csv",)


def output_sizes(scene) -> dict[str, float]:
    """Estimated bytes of each file a planned scene's run writes in proportion to its length:
    the LAMMPS history and whole-chain dumps and histories.csv (the peak table, energy and
    snapshots are small)."""
    steps = scene.run.end_time / scene.run.timestep
    sizes = {}
    if scene.outputs.histories:
        frames = steps / history_stride(scene) + 1
        n = len(scene.outputs.histories)
        sizes["histories.npy"] = 8 * (1 + frames) * (1 + 2 * n)  # LAMMPS: float64 time, forces, velocities
        sizes["histories.csv"] = frames * (1 + 2 * n) * 24
    if dump_stride(scene):
        frames = steps / dump_stride(scene) + 1
        sizes["chain.dump"] = frames * (DUMP_FRAME_HEADER_BYTES + scene.chain.beads * DUMP_LINE_BYTES)
    return sizes


def written_sizes(scene, backend: str | Backend = "reference") -> dict[str, float]:
    """output_sizes of the files this backend writes: the run directory's tables (RUN_DIR_TABLES) and
    its Backend.work_files (LAMMPS's dumps); the reference writes no chain.dump."""
    kept = (*RUN_DIR_TABLES, *backend_named(backend).work_files)
    return {name: size for name, size in output_sizes(scene).items() if name in kept}


class ResourceError(UsageError):
    """A run needs more steps, memory or disk than it may have; the message gives the estimate and the fix."""


class LongRunWarning(UserWarning):
    """A run is estimated to take longer than WARN_SECONDS, or to use more than half the free memory."""


class DriveBeyondLinearWarning(UserWarning):
    """A harmonic drive's amplitude is above the static force F0: it pulls bead 1 at its troughs."""


@dataclass(frozen=True)
class Estimate:
    """What a planned scene's run needs: steps, beads, bytes of memory and of disk, seconds."""

    steps: float
    beads: int
    memory: float
    disk: float
    seconds: float
    files: dict


def max_steps() -> float:
    """The step limit: GRANCHAIN_MAX_STEPS if set (a positive number), else MAX_STEPS."""
    text = os.environ.get("GRANCHAIN_MAX_STEPS")
    if not text:
        return MAX_STEPS
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 1):
        raise UsageError(f"GRANCHAIN_MAX_STEPS = {text!r} is invalid: a number of steps >= 1 (or unset: {MAX_STEPS:g})")
    return value


def estimate(scene, backend: str | Backend = "reference") -> Estimate:
    """The steps, memory, disk and wall time of a planned scene's run (no "auto" left in it).

    Parameters
    ----------
    scene : Scene
        A planned scene: beads, end_time and timestep given.
    backend : str or Backend
        A backend or its name: the files of output_sizes it writes (Backend.work_files: LAMMPS's
        dumps, first in a work directory) count beside the run directory's own tables.

    Returns
    -------
    Estimate
        Upper bounds: a run that stops after a contact makes fewer steps.
    """
    beads = int(scene.chain.beads)
    steps = scene.run.end_time / scene.run.timestep
    history = output_sizes(scene).get("histories.npy", 0.0)  # the histories as doubles, in memory until written
    files = written_sizes(scene, backend)
    snapshots = 16.0 * beads * len(scene.outputs.snapshots)
    # the solver's arrays, the histories and snapshots kept until the run is written (LAMMPS's
    # whole-chain dump goes to disk and is only copied)
    memory = BYTES_PER_BEAD * beads + 2 * history + snapshots
    disk = FIXED_BYTES + sum(files.values()) + 24.0 * beads * (3 + len(scene.outputs.snapshots))
    seconds = steps * (STEP_SECONDS + BEAD_STEP_SECONDS * beads)
    return Estimate(steps=steps, beads=beads, memory=memory, disk=disk, seconds=seconds, files=files)


def available_memory() -> float | None:
    """Bytes of memory this machine can give a new allocation now (MemAvailable), or None if unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def free_disk(path) -> float | None:
    """Bytes free on the file system of path (its nearest existing parent), or None if unknown."""
    p = Path(path).absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    try:
        return float(shutil.disk_usage(p).free)
    except OSError:
        return None


def _size(n: float) -> str:
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} B"


def _duration(seconds: float) -> str:
    for unit, scale in (("years", 3.15e7), ("days", 86400.0), ("hours", 3600.0), ("minutes", 60.0)):
        if seconds >= scale:
            return f"{seconds / scale:.3g} {unit}"
    return f"{seconds:.3g} s"


def _check_disk(est: Estimate, source, places) -> None:
    """Refuse a run whose files need more disk than is free at one of the places it writes to."""
    for place in places:
        free = free_disk(place)
        if free is not None and est.disk > free:
            big = max(est.files.items(), key=lambda kv: kv[1], default=("the run's files", est.disk))
            raise ResourceError(
                f"{source}: this run writes about {_size(est.disk)} ({big[0]} {_size(big[1])}), more than the "
                f"{_size(free)} free at {place}: set a larger [outputs] dump_interval or history_interval, or "
                "fewer histories, or write to a disk with more room"
            )


def _check_steps(est: Estimate, scene, planned_step: bool) -> None:
    """Refuse a run of more steps than max_steps(), naming what to shorten (planned_step: the planner's
    step, so the fix is not a larger [run] timestep)."""
    source = scene.source
    run = scene.run
    limit = max_steps()
    if est.steps > limit:
        raise ResourceError(
            f"{source}: this run is {est.steps:.3g} steps (end time {run.end_time:g} s, "
            f"time step {run.timestep:.3g} s), "
            f"more than the limit of {limit:.3g} (about {_duration(est.seconds)} of the reference solver on "
            f"{est.beads} beads): shorten [run] end_time (or stop after a contact: [run] stop_after_contact), "
            + (
                "soften what makes the planner's step this short (`granchain plan` names it: the stiffest contact "
                f"or the {scene.damping.noun}'s rate), "
                if planned_step
                else 'set [run] timestep = "auto" or a larger one, '
            )
            + "or raise the limit with GRANCHAIN_MAX_STEPS if you mean it"
        )


def _check_memory(est: Estimate, source, memory: float | None) -> None:
    """Refuse a run that needs more memory than is available (None: not checked, a cluster job)."""
    if memory is not None and est.memory > memory:
        raise ResourceError(
            f"{source}: this run needs about {_size(est.memory)} of memory ({est.beads} beads"
            + (", the histories kept until written" if est.memory > 2 * BYTES_PER_BEAD * est.beads else "")
            + f"), more than the {_size(memory)} this machine has available: use fewer [chain] beads, fewer "
            "[outputs] histories or a larger history_interval/dump_interval, or a machine with more memory"
        )


def check_run(
    scene,
    backend: str | Backend = "reference",
    out=None,
    machine: bool = True,
    stacklevel: int = 2,
    planned_step: bool = False,
) -> Estimate:
    """Refuse a planned scene's run that cannot finish here, before anything runs; warn about a long one.

    Refused (ResourceError, with the estimate and the fix): more steps than max_steps(); more memory
    than available_memory(); more disk than free_disk() where `out` goes (and, for LAMMPS, where its
    work directory goes). Warned (LongRunWarning): an estimated wall time above WARN_SECONDS, or more
    than half the available memory.

    Parameters
    ----------
    scene : Scene
        The planned scene.
    backend : str or Backend
        A backend or its name (Backend.work_in_tmp: its free disk is checked in the temporary
        directory too).
    out : path or None
        The run directory to be written, if any.
    machine : bool
        The run is made on this machine: check its memory and disk (not for a cluster job).
    stacklevel : int
        The warnings' stacklevel (the caller of the run).
    planned_step : bool
        The time step is the planner's, not the scene's: the fix is not a larger [run] timestep.

    Returns
    -------
    Estimate
        The estimate the checks used.
    """
    backend = backend_named(backend)
    est = estimate(scene, backend)
    source = scene.source
    _check_steps(est, scene, planned_step)
    memory = available_memory() if machine else None
    _check_memory(est, source, memory)
    places = [out] if out is not None and machine else []
    if backend.work_in_tmp and machine:
        places.append(tempfile.gettempdir())
    _check_disk(est, source, places)
    if est.seconds > WARN_SECONDS:
        warnings.warn(
            f"{source}: this run makes {est.steps:.3g} steps on {est.beads} beads: about {_duration(est.seconds)} "
            "of the reference solver (LAMMPS is faster); a larger timestep or a shorter end_time shortens it",
            LongRunWarning,
            stacklevel=stacklevel,
        )
    if memory is not None and est.memory > memory / 2:
        warnings.warn(
            f"{source}: this run needs about {_size(est.memory)} of memory, more than half of the "
            f"{_size(memory)} available",
            LongRunWarning,
            stacklevel=stacklevel,
        )
    _warn_drive(scene, stacklevel + 1)
    return est


def _warn_drive(scene, stacklevel: int) -> None:
    """Warn (DriveBeyondLinearWarning) where a harmonic drive's amplitude exceeds F0: F0 - A < 0 at its
    troughs pulls bead 1 off the chain, far outside the linearised chain the bands and the transmission's
    oracle describe (a dynamic force a few per cent of F0: physics/bands.py's DOMAIN). A valid scene (a
    nonlinear drive is a study of its own), so a warning, not a refusal."""
    f0, a = float(scene.effects.precompression or 0.0), float(scene.loading.amplitude)
    if not scene.loading.is_harmonic or scene.loading.is_shaker or a <= f0:  # (a shaker never pulls)
        return
    warnings.warn(
        f"{scene.source}: [loading] amplitude = {a:g} N is above the static force F0 = {f0:g} N: at the drive's "
        "troughs the force on bead 1 pulls (F0 - A < 0), bead 1 leaves the chain and its contact opens and "
        "closes; the run is the nonlinear chain's, outside the linear bands' domain (physics/bands.py). For "
        f"the linear spectrum give amplitude <= {0.05 * f0:g} N (5% of F0) or a larger [precompression] force",
        DriveBeyondLinearWarning,
        stacklevel=stacklevel,
    )
