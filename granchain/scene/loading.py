"""The scene's [loading] section as a frozen dataclass: the load on bead 1 (a step, an impulse, a
harmonic drive, an initial velocity or a striker) and what follows from it alone (its impulse, its
force and impulse at a time)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from granchain.physics import materials as mat
from granchain.physics.harmonic import drive_force, drive_impulse


@dataclass(frozen=True)
class Loading:
    """The [loading] section: f(t) = A for 0 < t <= T on bead 1 (Eq. 4), a harmonic drive, or a velocity at t = 0.

    Attributes
    ----------
    kind : str
        "step" (amplitude and duration given), "impulse" (I and T given, A = I / T), "harmonic"
        (A sin(2 pi f t) r(t) for 0 < t <= T, r a sin^2 switch-on: granchain.physics.harmonic),
        "shaker" (a rigid flat driver against bead 1 whose position moves by A sin(2 pi f t) r(t) from
        where it holds the static F0: granchain.physics.effects.shaker),
        "velocity" (bead 1 moves at t = 0) or "striker" (a sphere hits bead 1).
    amplitude : float
        A in N (step, impulse, harmonic), in m (shaker); else 0.
    duration : float
        T, the loading time in s (step, impulse; the drive's length, its ramp included, harmonic; else 0).
    velocity : float
        In m/s: bead 1's at t = 0 (velocity) or the striker's (striker); else 0.
    striker_radius : float
        The striker's radius in m (striker; default bead 1's).
    striker_material : Material or None
        The striker's material (striker; default the chain's).
    striker_material_name : str or None
        Its built-in name, or None for an inline table.
    striker_mass : float or None
        The striker's mass in kg if the scene gives it; None: from its radius and density.
    frequency : float
        f in Hz (harmonic, shaker; else 0).
    ramp : float
        The switch-on's length in periods of the drive (harmonic, shaker; else 0).
    """

    kind: str  # "step" | "impulse" | "harmonic" | "shaker" | "velocity" | "striker"
    amplitude: float = 0.0  # N (step, impulse, harmonic); m (shaker: the driver's displacement)
    duration: float = 0.0  # s (step, impulse, harmonic)
    velocity: float = 0.0  # m/s (velocity: of bead 1; striker: of the striker)
    striker_radius: float = 0.0  # m (striker)
    striker_material: mat.Material | None = None  # (striker) default: the chain's
    striker_material_name: str | None = None
    striker_mass: float | None = None  # kg (striker) default: from radius and density
    frequency: float = 0.0  # Hz (harmonic)
    ramp: float = 0.0  # periods (harmonic)

    @property
    def impulse(self) -> float:
        """The force load's impulse: I = A T (Eq. 4), the drive's closed-form integral (harmonic), N s;
        0 for a velocity or striker load (their momentum is Scene.input_impulse)."""
        if self.kind == "harmonic":
            return self.impulse_until(self.duration)
        return self.amplitude * self.duration if self.is_force else 0.0

    @property
    def is_force(self) -> bool:
        """The load is a force f(t) on bead 1 for 0 < t <= T (step, impulse or harmonic), not an
        initial velocity."""
        return self.kind in ("step", "impulse", "harmonic")

    @property
    def timed(self) -> bool:
        """The load acts on 0 < t <= T and stops at T, a breakpoint of the step plan: a force load, or a
        shaker (whose driver stops there)."""
        return self.is_force or self.is_shaker

    @property
    def is_step(self) -> bool:
        """The load is the paper's constant force A on 0 < t <= T (Eq. 4: step or impulse), whose work
        is A times bead 1's displacement and whose models (Eqs. 8, 15) apply."""
        return self.kind in ("step", "impulse")

    @property
    def is_harmonic(self) -> bool:
        """The load is a harmonic drive (granchain.physics.harmonic): of force on bead 1 (harmonic), or of
        the position of a rigid driver against it (shaker)."""
        return self.kind in ("harmonic", "shaker")

    @property
    def is_shaker(self) -> bool:
        """The load is a prescribed displacement of the driver against bead 1 (granchain.physics.effects.shaker)."""
        return self.kind == "shaker"

    @property
    def cycles(self) -> float:
        """The drive's length in periods, f T (harmonic, shaker; else 0)."""
        return self.frequency * self.duration

    @property
    def ramp_time(self) -> float:
        """t_r, the switch-on's length in s: ramp / f (harmonic, shaker; else 0)."""
        return self.ramp / self.frequency if self.frequency else 0.0

    def force_at(self, t):
        """The load's force on bead 1 at t (float or array), N: A on 0 < t <= T (step, impulse), the
        drive (harmonic: granchain.physics.harmonic.drive_force), 0 otherwise; the static F0 not included."""
        if self.kind == "harmonic":
            return drive_force(t, self.amplitude, self.frequency, self.ramp_time, self.duration)
        t = np.asarray(t, dtype=float)
        out = np.where((t > 0.0) & (t <= self.duration), self.amplitude if self.is_force else 0.0, 0.0)
        return float(out) if out.ndim == 0 else out

    def impulse_until(self, t):
        """The load's impulse delivered by t (float or array), N s: A min(t, T) (step, impulse), the
        drive's closed form (harmonic: granchain.physics.harmonic.drive_impulse), 0 otherwise."""
        if self.kind == "harmonic":
            return drive_impulse(t, self.amplitude, self.frequency, self.ramp_time, self.duration)
        if not self.is_force:
            return 0.0 * np.asarray(t, dtype=float)
        return self.amplitude * np.minimum(np.maximum(np.asarray(t, dtype=float), 0.0), self.duration)
