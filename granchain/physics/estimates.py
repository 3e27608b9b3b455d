"""Estimates from the paper's models that the planner, the deck, the peak floors and the regimes need
before anything runs: the step load a loading acts like, the largest contact force to expect, the
stiffest tangent of a contact and the highest frequency (and dashpot decay rate) of the chain.

Every function reads a scene (granchain.scene.Scene) for its numbers; none imports the scene.
"""

from __future__ import annotations

import math

import numpy as np

from granchain.physics import models
from granchain.physics.effects import Bounds, active_effects


def step_equivalent(scene) -> tuple[float, float] | None:
    """(A, T) of the step load a scene's loading acts like, or None for a velocity kick of bead 1.

    Force loads: their own A and T. A striker of mass M at speed V pushes like a piston at V for as
    long as it carries momentum: A = models.piston_step_amplitude (Eqs. 12 and 19), for T = M V / A.
    A light striker gives a short T, and the short-pulse model (Eq. 8 with I = M V) takes over
    through the min below.
    """
    ld = scene.loading
    if ld.is_force:
        return ld.amplitude, ld.duration
    if ld.kind != "striker":
        return None
    linear = scene.contact.law_class.loading_is_linear()  # the bilinear loading line
    a = models.piston_step_amplitude(ld.velocity, scene.stiffness, scene.mass, scene.diameter, linear=linear)
    return a, scene.striker_mass * ld.velocity / a


def expected_peak_force(scene) -> float:
    """An upper estimate of the largest contact force of the run (N), from the paper's models."""
    return scene.contact.law_class.expected_peak_force(scene, scene.input_impulse, step_equivalent(scene))


def max_stiffness(scene) -> float:
    """The nominal contact's stiffest tangent (N/m) at the expected peak force (Hertz), k_u (bilinear)."""
    return float(scene.law.tangent_stiffness(expected_peak_force(scene)))


def _tangent(law, force: float) -> np.ndarray:
    """The stiffest tangent of contacts at the force they are expected to reach: the law's own
    tangent_stiffness (granchain.physics.laws: Hertz 3/2 k^(2/3) F^(1/3), bilinear k_u)."""
    return np.asarray(law.tangent_stiffness(force), dtype=float)


def damping_rate(scene) -> float:
    """The fastest decay rate (1/s) a dashpot gives any mode: the Gershgorin bound of M^-1/2 C M^-1/2
    (see highest_frequency); 0 without a dashpot."""
    return highest_frequency(scene, return_damping=True) if scene.effects.dashpot else 0.0


def highest_frequency(scene, return_damping: bool = False) -> tuple[float, str]:
    """An upper bound of the chain's highest frequency (rad/s) over every contact the scene has, and
    the node that sets it.

    The linearised chain at the stiffest tangents K_t has frequencies sqrt(eig(M^-1/2 K_t M^-1/2)); by
    Gershgorin's theorem the largest is at most the largest row sum,
    (k_l + k_r) / m_i + k_l / sqrt(m_(i-1) m_i) + k_r / sqrt(m_i m_(i+1)), which for a uniform chain is
    exactly omega_max = 2 sqrt(k_t / m) (the linear chain's cut-off). Every effect enters where it acts:
    per-bead masses and pair stiffnesses (taper, materials), the wall (an infinite mass; its contact is
    stiffer, k_w, and sees the reflected wave, up to twice the force), a striker (its mass and pair
    stiffness on bead 1), precompression (every contact carries F0 on top of the wave), a dashpot (the
    overdamped modes decay at up to the Gershgorin bound of M^-1/2 C M^-1/2, and an explicit integrator
    must resolve that rate like a frequency). Each effect says what it changes
    (granchain.physics.effects: chain_bounds along the chain, end_bounds at its ends).
    """
    # beads = "auto" (a uniform chain: no per-bead lists): three beads hold every kind of node
    n = scene.chain.beads or 3
    b = Bounds(force=expected_peak_force(scene), mass=np.full(n, scene.mass), law=scene.law.per_contact(n - 1))
    active = active_effects(scene)
    for effect in active:  # along the chain: masses, laws, the force level, the dashpot
        effect.chain_bounds(scene, b)
    m = b.mass
    kt = np.broadcast_to(_tangent(b.law, b.force), (n - 1,))
    # neighbours as (stiffness, neighbour mass) on each side; a missing neighbour adds nothing
    b.kl, b.ml = np.concatenate(([0.0], kt)), np.concatenate(([np.inf], m[:-1]))
    b.kr, b.mr = np.concatenate((kt, [0.0])), np.concatenate((m[1:], [np.inf]))
    b.gl = np.where(np.arange(n) > 0, b.gamma, 0.0)
    b.gr = np.where(np.arange(n) < n - 1, b.gamma, 0.0)
    for effect in active:  # the ends: a wall's contact, a striker's mass and contact
        effect.end_bounds(scene, b)
    kl, ml, kr, mr, gl, gr, extra = b.kl, b.ml, b.kr, b.mr, b.gl, b.gr, b.extra
    rows = (kl + kr) / m + kl / np.sqrt(m * ml) + kr / np.sqrt(m * mr)
    damp = (gl + gr) / m + gl / np.sqrt(m * ml) + gr / np.sqrt(m * mr)
    if return_damping:
        return float(max(np.max(damp), extra.get("striker_damp", 0.0)))
    i = int(np.argmax(np.maximum(np.sqrt(rows), damp)))
    omega = float(max(np.sqrt(rows[i]), damp[i]))
    where = f"bead {i + 1}"
    if "striker" in extra and max(math.sqrt(extra["striker"]), 0.0) > omega:
        omega, where = math.sqrt(extra["striker"]), "the striker"
    if damp[i] > np.sqrt(rows[i]):
        where += f" (the dashpot's decay rate {damp[i]:.3g} 1/s)"
    elif "wall" in extra and i == n - 1:
        where += " (on the wall)"
    return omega, where


def one_bead_impacts(scene) -> list[tuple[str, dict[str, float]]]:
    """A one-bead scene's contacts as two-body impacts (models.two_body_impact), in the order they
    happen: the striker on the bead (reduced mass, the striker's speed), then the bead on the wall (the
    bead's mass, at the speed it was given or the striker's). Empty for longer chains."""
    if scene.chain.beads != 1:
        return []
    m1, ld = float(scene.bead_masses[0]), scene.loading
    v = 0.0 if ld.is_force else ld.velocity
    out = []
    if ld.kind == "striker":
        ms = scene.striker_mass
        out.append(("striker", models.two_body_impact(scene.striker_law, ms * m1 / (ms + m1), ld.velocity)))
        v = ld.velocity * 2.0 * ms / (ms + m1)  # the bead's speed after an elastic impact, at most
    elif ld.is_force:
        v = ld.impulse / m1  # the load's momentum, all in the bead
    if scene.effects.far_end == "wall" and v > 0.0:
        out.append(("wall", models.two_body_impact(scene.wall_law, m1, v)))
    return out
