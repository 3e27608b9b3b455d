"""The chain as equations, built from a scene: masses, one contact law over the contacts, the load at
bead 1 and the effects (wall, striker, dashpot, precompression); its static precompressed state and
the energy it holds at t = 0. Both backends and the deck builder start from these.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from granchain.physics.contact import BilinearLaw, HertzLaw


@dataclass(frozen=True)
class ChainProblem:
    """A chain of point masses joined by contact springs, loaded at bead 1."""

    mass: np.ndarray  # (N,) kg
    law: HertzLaw | BilinearLaw
    amplitude: float = 0.0  # A, N
    duration: float = 0.0  # T, s
    initial_velocity: float = 0.0  # m/s of bead 1 at t = 0
    wall_stiffness: float | None = None  # far end: None free, else bead N on a rigid flat (same law)
    striker_mass: float | None = None  # a striker before bead 1 (moving at initial_velocity), or None
    striker_stiffness: float | None = None  # its contact with bead 1
    dashpot: float = 0.0  # gamma, N s/m, while beads overlap; the total force never pulls
    precompression: float = 0.0  # F0, N: every contact starts in equilibrium at F0 (bead 1 pushed
    # by F0; the far end held by the wall, or pulled by F0 on bead N when free)

    @property
    def beads(self) -> int:
        return int(self.mass.shape[0])

    @classmethod
    def from_scene(cls, scene) -> ChainProblem:
        n = scene.chain.beads
        mass = scene.bead_masses if scene.per_bead else np.full(n, scene.mass)
        k = scene.contact_stiffnesses if scene.per_bead else scene.stiffness
        if scene.contact.law == "hertz":
            law: HertzLaw | BilinearLaw = HertzLaw(k=k)
        else:
            law = BilinearLaw(k=k, beta=scene.contact.unloading_coeff)
        ld = scene.loading
        fx = scene.effects
        extra = {
            "wall_stiffness": scene.wall_stiffness if fx.far_end == "wall" else None,
            "dashpot": fx.dashpot,
            "precompression": fx.precompression,
        }
        if ld.kind == "striker":
            extra.update(striker_mass=scene.striker_mass, striker_stiffness=scene.striker_stiffness)
        if ld.is_force:
            return cls(mass=mass, law=law, amplitude=ld.amplitude, duration=ld.duration, **extra)
        return cls(mass=mass, law=law, initial_velocity=ld.velocity, **extra)

    def with_ends(self) -> ChainProblem:
        """The chain a solver integrates: a striker as an extra first bead (moving at initial_velocity;
        its contact has the striker-bead stiffness) and a wall as an immovable extra last bead (zero
        inverse mass; its contact has the wall's stiffness). Itself when it has neither."""
        wall, striker = self.wall_stiffness is not None, self.striker_mass is not None
        if not (wall or striker):
            return self
        n = self.beads
        law = self.law
        k = np.broadcast_to(np.asarray(law.k, dtype=float), (n - 1,))
        mass = self.mass
        if striker:  # an extra bead in front, moving; its contact has the striker-bead stiffness
            k, mass = np.concatenate(([self.striker_stiffness], k)), np.concatenate(([self.striker_mass], mass))
        if wall:  # an immovable extra bead at the end (zero inverse mass)
            k, mass = np.append(k, self.wall_stiffness), np.append(mass, np.inf)
        law_x = HertzLaw(k=k) if isinstance(law, HertzLaw) else BilinearLaw(k=k, beta=law.beta)
        return ChainProblem(
            mass=mass,
            law=law_x,
            amplitude=self.amplitude,
            duration=self.duration,
            initial_velocity=self.initial_velocity,
            dashpot=self.dashpot,
            precompression=self.precompression,
        )


def static_state(law, force: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Displacements (n,) and overlaps (n-1,) of a chain whose every contact carries `force` in static
    equilibrium, the last bead (or wall) at u = 0: Hertz alpha0 = (F0/k)^(2/3), bilinear F0/k."""
    k_c = np.broadcast_to(np.asarray(law.k, dtype=float), (n - 1,))
    alpha0 = force / k_c if isinstance(law, BilinearLaw) else (force / k_c) ** (2.0 / 3.0)
    u = np.zeros(n)
    u[:-1] = np.cumsum(alpha0[::-1])[::-1]
    return u, alpha0


def precompressed_displacements(scene) -> tuple[np.ndarray, np.ndarray]:
    """Static displacements of the scene's beads and overlaps of its contacts (the wall's last)."""
    p = ChainProblem.from_scene(scene)
    n = p.beads
    k = np.broadcast_to(np.asarray(p.law.k, dtype=float), (n - 1,))
    if p.wall_stiffness is not None:
        k = np.append(k, p.wall_stiffness)
        n += 1
    law = HertzLaw(k=k) if isinstance(p.law, HertzLaw) else BilinearLaw(k=k, beta=p.law.beta)
    u, alpha0 = static_state(law, p.precompression, n)
    return u[: p.beads], alpha0


def initial_state(problem: ChainProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, v, alpha_max) at t = 0 of a chain without wall or striker beads (ChainProblem.with_ends):
    at rest but for bead 1's initial velocity; with precompression every contact in static
    equilibrium at F0 (bilinear: loaded plastically to it, so alpha_max is the static overlap)."""
    n = problem.beads
    u = np.zeros(n)
    v = np.zeros(n)
    v[0] = problem.initial_velocity
    alpha_hist = np.zeros(n - 1)  # bilinear history alpha_max
    f0 = float(problem.precompression)
    if f0:
        u[:], alpha0 = static_state(problem.law, f0, n)
        if isinstance(problem.law, BilinearLaw):
            alpha_hist[:] = alpha0  # the precompression loaded every contact plastically
    return u, v, alpha_hist


def moving_mass(mass: np.ndarray) -> np.ndarray:
    """Masses that count for kinetic energy and momentum: an immovable wall bead (inf) counts 0."""
    return np.where(np.isfinite(mass), mass, 0.0)


def state_energy(law, mass_ke: np.ndarray, u: np.ndarray, v: np.ndarray, alpha_hist: np.ndarray) -> float:
    """Kinetic + stored + dissipated energy of a state (mass_ke: moving_mass)."""
    return (
        0.5 * float(np.dot(mass_ke, v * v))
        + float(np.sum(law.energy(u[:-1] - u[1:], alpha_hist)))
        + (float(np.sum(law.dissipated(alpha_hist))) if isinstance(law, BilinearLaw) else 0.0)
    )


def initial_energy(problem: ChainProblem) -> float:
    """The energy in the chain at t = 0 (kinetic + stored + dissipated, striker and wall included):
    where both backends' energy put in starts (the reference's bookkeeping; the deck's watch)."""
    p = problem.with_ends()
    u, v, alpha_hist = initial_state(p)
    return state_energy(p.law, moving_mass(p.mass), u, v, alpha_hist)
