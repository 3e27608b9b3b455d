"""What steers a deck's run: its steps (Schedule), the run watch's bounds (Watch) and the stop check
(StopCheck)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from granchain.invariants import ENERGY_WATCH, MOMENTUM_WATCH, OVERLAP_WATCH
from granchain.peaks import PEAK_PASSED_FRACTION
from granchain.physics.effects import active_effects, external_forces
from granchain.problem import ChainProblem, initial_energy, precompressed_displacements
from granchain.schedule import STOP_CHECK_EVERY, dump_stride, history_stride, scene_step_plan
from granchain.templates.atoms import AtomLayout

#: steps between two checks of the LAMMPS run watch (the reference checks every 20 steps as well)
WATCH_EVERY = 20


@dataclass(frozen=True)
class Watch:
    """The run watch's bounds (granchain.invariants, the same as the reference's) and what its energy
    and momentum balances start from: the energy at t = 0 (problem.initial_energy, where the
    reference's bookkeeping starts), bead 1's and bead N's x at t = 0, the initial momentum.

    Attributes
    ----------
    force : float
        The overlap watch as a force, N: the largest force any contact's virgin curve gives at
        OVERLAP_WATCH x the smallest bead radius; a contact force above it is a blow-up.
    e0 : float
        The energy at t = 0, J (problem.initial_energy: a precompression's stored energy, the
        kinetic energy of a velocity load or a striker).
    x1_0, xn_0 : float
        Bead 1's and bead N's x at t = 0, m, from which the load's and the effects' work are counted.
    p0 : float
        The momentum at t = 0, kg m/s (Scene.initial_momentum).
    momentum : bool
        No effect exerts external forces, so the momentum balance is watched: momentum = p0 + the
        impulse delivered so far.
    effects_work : str
        The effects' work as terms of a LAMMPS expression (Effect.watch_work).
    every : int
        Steps between two checks of the largest force.
    energy_bound, momentum_bound : float
        ENERGY_WATCH and MOMENTUM_WATCH, the relative bounds of the two balances.
    """

    force: float  # the largest force any contact can have at OVERLAP_WATCH x the smallest radius
    e0: float
    x1_0: float
    xn_0: float
    p0: float
    momentum: bool  # no effect exerts external forces: the momentum is the impulse delivered
    effects_work: str  # the effects' work as LAMMPS expression terms (Effect.watch_work)
    every: int = WATCH_EVERY
    energy_bound: float = ENERGY_WATCH
    momentum_bound: float = MOMENTUM_WATCH

    @classmethod
    def of(cls, scene, pairs) -> Watch:
        """The watch of a scene's deck, whose pair coefficients (PairCoeff) give the laws to bound."""
        e0 = initial_energy(ChainProblem.from_scene(scene))
        u0 = precompressed_displacements(scene)[0] if scene.effects.precompression else np.zeros(scene.chain.beads)
        x0 = scene.bead_positions  # as render_data writes them
        # on each contact's virgin curve: Hertz k a^1.5, bilinear k a, ...
        a_watch = OVERLAP_WATCH * float(min(scene.bead_radii))
        problem, layout = ChainProblem.from_scene(scene), AtomLayout.of(scene)
        x1_0, xn_0 = float(x0[0] + u0[0]), float(x0[-1] + u0[-1])
        x_first, x_last = f"x[{layout.first_id}] - {x1_0!r}", f"x[{layout.last_id}] - {xn_0!r}"
        return cls(
            force=max(float(p.law.loading_force(a_watch)) for p in pairs),
            e0=e0,
            x1_0=x1_0,
            xn_0=xn_0,
            p0=scene.initial_momentum,
            momentum=not external_forces(scene),
            effects_work="".join(e.watch_work(problem, x_first, x_last) for e in active_effects(scene)),
        )


@dataclass(frozen=True)
class Schedule:
    """The deck's steps: the step plan (granchain.schedule: its segments end at the load's end, every
    snapshot and the end time) and the strides of the samples.

    Attributes
    ----------
    segments : list of schedule.Segment
        The step plan: the segments between two breakpoints, each in equal steps.
    dump_stride : int
        Steps between whole-chain dump frames; 0: no whole-chain dump.
    history_stride : int
        Steps between history samples.
    """

    segments: list  # schedule.Segment
    dump_stride: int  # 0: no whole-chain dump
    history_stride: int

    @classmethod
    def of(cls, scene) -> Schedule:
        """The schedule of a planned scene (granchain.schedule.scene_step_plan and its strides)."""
        return cls(scene_step_plan(scene), dump_stride(scene), history_stride(scene))

    @property
    def total(self) -> int:
        """The run's steps, all segments together."""
        return sum(g.steps for g in self.segments)

    @property
    def energy_every(self) -> int:
        """Steps between energy samples (and the energy and momentum balances' checks): about 200 a run."""
        return max(1, self.total // 200)

    @property
    def thermo_every(self) -> int:
        """Steps between LAMMPS's thermo lines: about 20 a run."""
        return max(1, self.total // 20)


@dataclass(frozen=True)
class StopCheck:
    """[run] stop_after_contact: the wave has passed the contact once its force is back below
    PEAK_PASSED_FRACTION of its rise above F0, after a peak above the floor.

    Attributes
    ----------
    contact : int
        The contact (1-based) the wave must pass.
    atom : int
        The atom it lives on (bead i's, contact + AtomLayout.offset).
    floor : float
        The smallest peak in N that counts as the leading wave (peaks.stop_force_floor).
    every : int
        Steps between two checks.
    fraction : float
        The force, as a fraction of the peak's rise above F0, below which the wave has passed.
    """

    contact: int
    atom: int
    floor: float
    every: int = STOP_CHECK_EVERY
    fraction: float = PEAK_PASSED_FRACTION
