"""What steers a deck's run: its steps (Schedule), the run watch's bounds (Watch) and the stop check
(StopCheck)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from granchain.invariants import ENERGY_WATCH, MOMENTUM_WATCH, contact_overlap_bounds
from granchain.peaks import PEAK_PASSED_FRACTION, event_floor
from granchain.physics.effects import active_effects, external_forces
from granchain.problem import (
    ChainProblem,
    initial_energy,
    precompressed_displacements,
    scene_static_forces,
    scene_static_load,
)
from granchain.schedule import STOP_CHECK_EVERY, dump_stride, history_stride, scene_step_plan
from granchain.templates.atoms import AtomLayout, bead_kinds
from granchain.templates.filters import float_repr

#: steps between two checks of the LAMMPS run watch (the reference checks every 20 steps as well)
WATCH_EVERY = 20


@dataclass(frozen=True)
class Watch:
    """The run watch's bounds (granchain.invariants, the same as the reference's) and what its energy
    and momentum balances start from: the energy at t = 0 (problem.initial_energy, where the
    reference's bookkeeping starts), bead 1's and bead N's x at t = 0, the initial momentum.

    The overlap watch is a force bound per contact: the force its law's virgin curve gives at its own
    overlap bound (invariants.contact_overlap_bounds; on the virgin curve a force above it means an
    overlap above it). Where every contact has the same bound (a uniform chain), the deck compares the
    largest contact force with that one number; otherwise each contact's bound is a per-atom value,
    d_fwatch, on the atom it lives on (chain.data's Watch section, read_data's fix keyword: one pass,
    where a set command per atom took N^2 time), and the deck compares the largest d_fc / d_fwatch with 1.

    Attributes
    ----------
    force : float
        The largest contact force bound, N (the one bound of a uniform chain).
    bounds : tuple of float
        Each atom's contact force bound in N, in ID order, where the contacts' bounds differ (an atom
        without a contact on its right, bead N of a free chain or the wall, has its neighbour's: its
        d_fc stays 0); empty where one bound holds.
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

    force: float  # the largest contact force bound (a uniform chain's only one)
    bounds: tuple[float, ...]  # each atom's contact force bound, N, in ID order; () where one holds
    e0: float
    x1_0: float
    xn_0: float
    p0: float
    momentum: bool  # no effect exerts external forces: the momentum is the impulse delivered
    effects_work: str  # the effects' work as LAMMPS expression terms (Effect.watch_work)
    every: int = WATCH_EVERY
    energy_bound: float = ENERGY_WATCH
    momentum_bound: float = MOMENTUM_WATCH

    @property
    def data_section(self) -> str:
        """chain.data's Watch section (read_data ... fix watch_bound NULL Watch): "ID bound" per atom;
        empty where one bound holds."""
        if not self.bounds:
            return ""
        return "\nWatch\n\n" + "".join(f"{i} {float_repr(f)}\n" for i, f in enumerate(self.bounds, start=1))

    @classmethod
    def of(cls, scene, pairs) -> Watch:
        """The watch of a scene's deck, whose pair coefficients (PairCoeff) give the laws to bound."""
        e0 = initial_energy(ChainProblem.from_scene(scene))
        u0 = precompressed_displacements(scene)[0] if scene_static_load(scene) else np.zeros(scene.chain.beads)
        x0 = scene.bead_positions  # as render_data writes them
        problem, layout = ChainProblem.from_scene(scene), AtomLayout.of(scene)
        force, bounds = contact_force_bounds(scene, pairs, layout)
        x1_0, xn_0 = float(x0[0] + u0[0]), float(x0[-1] + u0[-1])
        x_first, x_last = f"x[{layout.first_id}] - {x1_0!r}", f"x[{layout.last_id}] - {xn_0!r}"
        x_mass = f"{moving_mass_x(layout)} - {initial_mass_x(scene, x0 + u0)!r}"
        return cls(
            force=force,
            bounds=bounds,
            e0=e0,
            x1_0=x1_0,
            xn_0=xn_0,
            p0=scene.initial_momentum,
            # (a drive's impulse is delivered by the integrator's quadrature: invariants.DRIVE_MOMENTUM)
            momentum=not external_forces(scene) and not scene.loading.is_harmonic,
            effects_work="".join(e.watch_work(problem, x_first, x_last, x_mass) for e in active_effects(scene)),
        )


def moving_mass_x(layout: AtomLayout) -> str:
    """The moving atoms' sum of m_i x_i as a LAMMPS expression (a wall's atom left out)."""
    group = "mobile" if layout.wall else "all"
    return f"mass({group})*xcm({group},x)"


def initial_mass_x(scene, x: np.ndarray) -> float:
    """The moving atoms' sum of m_i x_i at t = 0 (x: the beads' positions there; a striker touches
    bead 1), moving_mass_x's value at t = 0 as granchain's masses give it."""
    masses = np.asarray(scene.bead_masses if scene.per_bead else np.full(scene.chain.beads, scene.mass), dtype=float)
    total = float(np.dot(masses, x))
    if scene.loading.kind == "striker":
        xs = float(x[0]) - (float(scene.loading.striker_radius) + float(scene.bead_radii[0]))
        total += float(scene.striker_mass) * xs
    return total


#: contact force bounds this close (relative) are one bound: a uniform chain's contacts, whose laws a
#: striker or the per-contact law may give in other round-off
SAME_BOUND = 1e-12


def contact_force_bounds(scene, pairs, layout: AtomLayout) -> tuple[float, tuple]:
    """The overlap watch's force bound of every contact: its law's virgin curve (Hertz k a^1.5,
    bilinear k a, ...) at its own overlap bound (invariants.contact_overlap_bounds).

    Parameters
    ----------
    scene : granchain.scene.Scene
        The planned scene.
    pairs : list of PairCoeff
        The deck's pair coefficients: a contact's law is its two atoms' types' (the law LAMMPS runs).
    layout : AtomLayout
        The deck's atoms: contact k of the chain with its ends (a striker's contact first, a wall's
        last) lives on atom k + 1, its left body's.

    Returns
    -------
    force : float
        The largest bound, N.
    bounds : tuple of float
        Each atom's bound in ID order (an atom without a contact on its right has its neighbour's); empty
        when every contact's bound is the largest to SAME_BOUND (a uniform chain: the deck's one number).
    """
    alpha = contact_overlap_bounds(scene)
    types = atom_types(scene, layout)
    left, right = types[:-1][: alpha.size], types[1:][: alpha.size]
    law_of = {(min(p.i, p.j), max(p.i, p.j)): p.law for p in pairs}
    # one virgin-curve evaluation per (type pair, bound), a scalar one (a uniform chain: the one bound)
    keys = np.column_stack((np.minimum(left, right), np.maximum(left, right), alpha))
    unique, which = np.unique(keys, axis=0, return_inverse=True)
    values = [float(law_of[int(i), int(j)].loading_force(float(a))) for i, j, a in unique]
    f = np.asarray(values)[np.ravel(which)]
    force = float(f.max())
    if bool((f >= force * (1.0 - SAME_BOUND)).all()):
        return force, ()
    # atoms with no contact on their right (bead N of a free chain, the wall) take the last contact's
    return force, tuple(np.concatenate((f, np.full(types.size - f.size, f[-1]))).tolist())


def atom_types(scene, layout: AtomLayout) -> np.ndarray:
    """Every atom's type, in ID order as chain.data lists them (templates.atoms.render_data): the
    effects' atoms in front of bead 1 (a striker), the beads (bead kind k: type k + 1), the others (a
    wall)."""
    effects = [e for e in active_effects(scene) if e.atom_type]
    front = [layout.types[e.atom_type] for e in effects if e.beads_in_front]
    back = [layout.types[e.atom_type] for e in effects if not e.beads_in_front]
    beads = np.asarray(bead_kinds(scene)[1]) + 1 if scene.per_bead else np.ones(scene.chain.beads, dtype=int)
    return np.concatenate((np.asarray(front, dtype=int), beads, np.asarray(back, dtype=int)))


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
    fall : float
        How far the force must also have fallen below the peak (peaks.lead_fall): then the leading
        pulse, which waits for that fall, has frozen. 0: no further condition.
    wall_atom : int
        [run] stop_after_wall: the atom the wall's contact lives on (bead N's), whose force must also
        have fallen back below the fraction of its peak; 0: no wall to wait for.
    back_atom : int
        [run] stop_after_reflection: the atom contact 1 lives on (bead 1's), through which the wall's
        reflection must have passed back: its force, sampled at the checks after the wall's contact
        has passed, risen above the floor and back below the fraction of its largest; 0: no wait.
    static, wall_static, back_static : float
        The force at rest of the stop contact, the wall's contact and contact 1 (precompression's F0
        plus gravity's weight above each: problem.scene_static_forces), N.
    """

    contact: int
    atom: int
    floor: float
    every: int = STOP_CHECK_EVERY
    fraction: float = PEAK_PASSED_FRACTION
    fall: float = 0.0
    wall_atom: int = 0
    back_atom: int = 0
    static: float = 0.0
    wall_static: float = 0.0
    back_static: float = 0.0


@dataclass(frozen=True)
class EventCheck:
    """[outputs] event: fix chain/event's arguments (templates/event.lmp.j2; granchain.physics.event).

    Attributes
    ----------
    wall_atom : int
        The atom the wall's contact lives on (bead N's).
    static : float
        The wall's static force, N (problem.scene_static_forces: F0 plus the chain's weight).
    floor : float
        The rise above it at which the event has begun (peaks.event_floor), N.
    held : bool
        The chain is pressed on the wall (precompression or gravity): the event ends at its first
        return; else once it moves away from the wall.
    load_end : float
        The time after which no load acts (a force load's duration; 0 otherwise), s.
    every : int
        Steps between two checks of the event's end (the stop check's).
    track : tuple of (int, int)
        The forces whose largest value over the event is tracked ([outputs] event_max_contacts, then
        event_max_sensors): (atom ID, 0 for its d_fc, the contact it carries, or 1 for its d_sfc, a
        sensor bead's average force).
    """

    wall_atom: int
    static: float
    floor: float
    held: bool
    load_end: float
    every: int = STOP_CHECK_EVERY
    track: tuple[tuple[int, int], ...] = ()

    @classmethod
    def of(cls, scene) -> EventCheck:
        """The event check of a planned walled scene."""
        ld, out, lay = scene.loading, scene.outputs, AtomLayout.of(scene)
        return cls(
            wall_atom=scene.chain.beads + lay.offset,
            static=float(scene_static_forces(scene)[-1]),
            floor=event_floor(scene),
            held=bool(scene.effects.precompression or scene.effects.gravity),
            load_end=float(ld.duration) if ld.timed else 0.0,
            track=tuple((i + lay.offset, 0) for i in out.event_max_contacts)
            + tuple((b + lay.offset, 1) for b in out.event_max_sensors),
        )
