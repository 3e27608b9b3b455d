"""The chain as equations, built from a scene: masses, one contact law over the contacts, the load at
bead 1 and the effects (wall, striker, damping, precompression); its static precompressed state and
the energy it holds at t = 0. Both backends and the deck builder start from these.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from granchain.physics.damping import DAMPING, DampingPart
from granchain.physics.effects import EFFECTS, active_effects
from granchain.physics.effects.gravity import scene_static_forces
from granchain.physics.effects.gravity import static_profile as static_contact_forces
from granchain.physics.harmonic import drive_force, drive_impulse
from granchain.physics.laws import ContactLaw
from granchain.physics.shaker import shaker_velocity

__all__ = ["scene_static_forces", "static_contact_forces"]  # (re-exported: the problem's static load)


@dataclass(frozen=True)
class ChainProblem:
    """A chain of point masses joined by contact springs, loaded at bead 1: the paper's Eqs. 1-3,
    m_i u_i'' = F_(i-1,i)(alpha_(i-1,i)) - F_(i,i+1)(alpha_(i,i+1)) with the overlaps of Eq. 2 and
    the load on bead 1 (a step f(t) = A for 0 < t <= T, Eq. 4, or an initial velocity), and the
    effects' fields (a wall, a striker, damping, precompression)."""

    mass: np.ndarray  # (N,) kg
    law: ContactLaw  # over the N-1 contacts (parameters scalar or one per contact)
    amplitude: float = 0.0  # A, N
    duration: float = 0.0  # T, s
    frequency: float = 0.0  # f, Hz: a harmonic drive A sin(2 pi f t) r(t) on (0, T] (0: the step A)
    ramp_time: float = 0.0  # t_r, s: the drive's sin^2 switch-on (granchain.physics.harmonic)
    initial_velocity: float = 0.0  # m/s of bead 1 at t = 0
    wall_law: ContactLaw | None = None  # far end: None free, else bead N on a rigid flat (scene.wall_law)
    striker_mass: float | None = None  # a striker before bead 1 (moving at initial_velocity), or None
    striker_law: ContactLaw | None = None  # its contact with bead 1
    damping: str = "none"  # the damping part (granchain.physics.damping), while beads overlap
    damping_coefficient: float = 0.0  # its coefficient (a dashpot's gamma N s/m, Kuwabara-Kono's A s)
    precompression: float = 0.0  # F0, N: every contact starts in equilibrium at F0 (bead 1 pushed
    # by F0; the far end held by the wall, or pulled by F0 on bead N when free)
    gravity: float = 0.0  # g, m/s^2: every moving bead carries m_i g toward the far end (a vertical
    # chain on the wall), each contact starts in equilibrium at the weight above it (plus F0)
    front: int = 0  # beads in front of bead 1 (with_ends: a striker), whose contacts start unloaded
    shaker: bool = False  # the load is a shaker (granchain.physics.shaker): amplitude in m, a rigid driver
    # against bead 1 whose motion is prescribed; with_ends puts it in front as bead 0 of infinite mass
    shaker_law: ContactLaw | None = None  # the driver's contact with bead 1 (scene.driver_law; None after with_ends)

    @property
    def damping_part(self) -> type[DampingPart]:
        """The damping part's class (DAMPING[damping])."""
        return DAMPING[self.damping]

    @property
    def driven(self) -> bool:
        """The load on bead 1 is a harmonic drive, whose force changes within a step (load_force), or a
        shaker, whose driver's acceleration does (granchain.physics.shaker)."""
        return bool(self.frequency) and bool(self.amplitude)

    def load_force(self, t: float) -> float:
        """The load's force on bead 1 at t inside its loaded time (0, T], N: A (a step), or the drive's
        A sin(2 pi f t) r(t) (granchain.physics.harmonic.drive_force); 0 for a shaker (its force is its
        contact's)."""
        if self.shaker:
            return 0.0
        if not self.frequency:
            return self.amplitude
        return drive_force(t, self.amplitude, self.frequency, self.ramp_time, self.duration)

    def load_impulse(self, t: float) -> float:
        """The load's impulse delivered by t, N s: A min(t, T), or the drive's closed form; 0 for a
        shaker (its driver's push is a contact force, counted with the chain's)."""
        if self.shaker:
            return 0.0
        if not self.frequency:
            return self.amplitude * min(self.duration, t)
        return drive_impulse(t, self.amplitude, self.frequency, self.ramp_time, self.duration)

    @property
    def first_bead(self) -> int:
        """Bead 1's index in the chain a solver integrates: behind the beads in front (a striker) and a
        shaker's driver (whose contact, unlike a striker's, starts at the static force)."""
        return self.front + int(self.shaker and not np.isfinite(self.mass[0]))

    @property
    def beads(self) -> int:
        """Number of beads the problem integrates (with_ends: the effects' extra beads included)."""
        return int(self.mass.shape[0])

    @classmethod
    def from_scene(cls, scene) -> ChainProblem:
        """The scene's chain: uniform beads and the nominal law, changed by every effect it declares
        (granchain.physics.effects: masses, contact laws, wall, striker, damping, precompression)."""
        fields: dict[str, Any] = {"mass": np.full(scene.chain.beads, scene.mass), "law": scene.law}
        for effect in active_effects(scene):
            effect.problem_fields(scene, fields)
        ld = scene.loading
        if ld.is_shaker:
            drive = {"frequency": ld.frequency, "ramp_time": ld.ramp_time, "shaker": True}
            return cls(amplitude=ld.amplitude, duration=ld.duration, shaker_law=scene.driver_law, **drive, **fields)
        if ld.is_force:
            drive = {"frequency": ld.frequency, "ramp_time": ld.ramp_time} if ld.is_harmonic else {}
            return cls(amplitude=ld.amplitude, duration=ld.duration, **drive, **fields)
        return cls(initial_velocity=ld.velocity, **fields)

    def with_ends(self) -> ChainProblem:
        """The chain a solver integrates: the extra beads of the effects (Effect.ends: a striker as an
        extra first bead moving at initial_velocity with the striker-bead law, a wall as an immovable
        extra last bead with the wall's law). Itself when it has none."""
        parts = [(self.law, self.beads - 1)]
        mass = self.mass
        for effect in EFFECTS.values():
            mass = effect.ends(self, parts, mass)
        v0 = self.initial_velocity
        if self.shaker_law is not None:  # the driver: a rigid flat in front, its motion prescribed
            parts.insert(0, (self.shaker_law, 1))
            mass = np.concatenate(([np.inf], mass))
            v0 = float(shaker_velocity(0.0, self.amplitude, self.frequency, self.ramp_time, self.duration))
        if len(parts) == 1:
            return self
        return ChainProblem(
            mass=mass,
            law=type(self.law).join(parts),
            amplitude=self.amplitude,
            duration=self.duration,
            frequency=self.frequency,
            ramp_time=self.ramp_time,
            initial_velocity=v0,
            damping=self.damping,
            damping_coefficient=self.damping_coefficient,
            precompression=self.precompression,
            gravity=self.gravity,
            front=sum(e.beads_in_front for e in EFFECTS.values() if e.in_problem(self)),
            shaker=self.shaker,
        )


def has_static_load(problem: ChainProblem) -> bool:
    """Its contacts start loaded: a precompression's F0 or gravity's weight."""
    return bool(problem.precompression) or bool(problem.gravity)


def static_state(law: ContactLaw, force, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Displacements (n,) and overlaps (n-1,) of a chain whose contacts carry `force` (one value, or
    one per contact) in static equilibrium, the last bead (or wall) at u = 0: the law's virgin curve
    at each contact's force (Hertz (F/k)^(2/3), bilinear F/k)."""
    alpha0 = np.broadcast_to(np.asarray(law.per_contact(n - 1).static_overlap(force), dtype=float), (n - 1,))
    u = np.zeros(n)
    u[:-1] = np.cumsum(alpha0[::-1])[::-1]
    return u, alpha0


def scene_static_load(scene) -> bool:
    """The scene's contacts start loaded: a precompression's F0 or gravity's weight (has_static_load)."""
    return bool(scene.effects.precompression) or bool(scene.effects.gravity)


def precompressed_displacements(scene) -> tuple[np.ndarray, np.ndarray]:
    """Static displacements of the scene's beads and overlaps of its contacts (the wall's last), under
    its precompression and gravity."""
    p = ChainProblem.from_scene(scene)
    n = p.beads
    parts = [(p.law, n - 1)]
    mass = p.mass
    if p.wall_law is not None:
        parts.append((p.wall_law, 1))
        mass = np.append(mass, np.inf)
        n += 1
    force = static_contact_forces(mass, p.precompression, p.gravity)
    u, alpha0 = static_state(type(p.law).join(parts), force, n)
    return u[: p.beads], alpha0


def initial_state(problem: ChainProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, v, alpha_max) at t = 0 of a chain (also with its extra beads, ChainProblem.with_ends):
    at rest but for the first bead's initial velocity (bead 1's, or a striker's); with precompression
    or gravity every contact from bead 1 on (the wall's included) in static equilibrium at its static
    force (static_contact_forces: F0 plus the weight above it; a law with history was loaded to it:
    alpha_max is the static overlap as the steps compute it from u), and the beads in front of bead 1
    (a striker) touching it unloaded (docs/effects.md, the conventions)."""
    n, s0 = problem.beads, problem.front
    u = np.zeros(n)
    v = np.zeros(n)
    v[0] = problem.initial_velocity
    alpha_hist = np.zeros(n - 1)  # the history alpha_max (laws with history)
    if has_static_load(problem):
        law = problem.law.contacts(n - 1, s0) if s0 else problem.law
        # (a shaker's driver, mass inf, is held by its actuator: its weight is on no contact)
        force = static_contact_forces(moving_mass(problem.mass[s0:]), problem.precompression, problem.gravity)
        u[s0:], _ = static_state(law, force, n - s0)
        u[:s0] = u[s0]  # the striker touches bead 1 with no overlap
        if problem.law.history:
            # the static load brought every contact to its overlap, as the steps compute it from u (a
            # round-off off alpha0; alpha_max above it would start a contact struck at t = 0 on its
            # unloading branch: tests/test_static_history.py); LAMMPS's setup does the same from its positions
            alpha_hist[s0:] = u[s0:-1] - u[s0 + 1 :]
    return u, v, alpha_hist


def moving_mass(mass: np.ndarray) -> np.ndarray:
    """Masses that count for kinetic energy and momentum: an immovable wall bead (inf) counts 0."""
    return np.where(np.isfinite(mass), mass, 0.0)


def state_energy(law: ContactLaw, mass_ke: np.ndarray, u: np.ndarray, v: np.ndarray, alpha_hist: np.ndarray) -> float:
    """Kinetic + stored + dissipated energy of a state (mass_ke: moving_mass)."""
    return (
        0.5 * float(np.dot(mass_ke, v * v))
        + float(np.sum(law.energy(u[:-1] - u[1:], alpha_hist)))
        + (float(np.sum(law.dissipated(alpha_hist))) if law.history else 0.0)
    )


def initial_energy(problem: ChainProblem) -> float:
    """The energy in the chain at t = 0 (kinetic + stored + dissipated, striker and wall included):
    where both backends' energy put in starts (the reference's bookkeeping; the deck's watch)."""
    p = problem.with_ends()
    u, v, alpha_hist = initial_state(p)
    return state_energy(p.law, moving_mass(p.mass), u, v, alpha_hist)


def contact_positions(scene) -> np.ndarray:
    """Where each bead-bead contact sits at t = 0 (m, along the chain; contact i between beads i and
    i+1): bead i's centre plus its radius, less half the static overlap under precompression. The
    distances a front travels between contacts (a taper's or a dimer's differ from bead 1's diameter)."""
    r = np.asarray(scene.bead_radii, dtype=float)
    x = np.asarray(scene.bead_positions, dtype=float)
    if scene.n_contacts == 0:
        return np.zeros(0)
    at = x[:-1] + r[:-1]
    if scene.effects.precompression or scene.effects.gravity:
        u0, alpha0 = precompressed_displacements(scene)
        at = at + u0[:-1] - 0.5 * alpha0[: scene.n_contacts]
    return at
