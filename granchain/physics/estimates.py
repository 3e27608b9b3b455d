"""Estimates from the paper's models that the planner, the deck, the peak floors and the regimes need
before anything runs: the step load a loading acts like, the largest contact force to expect, the
stiffest tangent of a contact and the highest frequency (and damping decay rate) of the chain.

Every function reads a scene (granchain.scene.Scene) for its numbers; none imports the scene.
linearised_first_maximum solves the precompressed chain's small-amplitude equations exactly (its modes)
for the time a front's first maximum reaches a contact.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import eigh_tridiagonal

from granchain.physics import models
from granchain.physics.effects import OVERLAP_WATCH, Bounds, active_effects, watched_force


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
    if ld.is_shaker:  # as the force drive of its driver's force scale (Scene.drive_amplitude)
        return scene.drive_amplitude, ld.duration
    if ld.kind != "striker":
        return None
    # the front's F = k alpha^n onset (ContactLaw.loading_exponent: Hertz 3/2, a loading line 1); with
    # per-contact values (a power law's lists) the largest A over the contacts': the planner's
    # estimates bound the force from above, and the striker's front meets each contact's law
    laws = {(scene.stiffness, float(scene.law.loading_exponent()))}
    if scene.contact.coefficients.varies:
        laws = {(float(law.k), float(law.loading_exponent())) for law in scene.contact_laws}
    a = max(models.piston_step_amplitude(ld.velocity, k, scene.mass, scene.diameter, n) for k, n in laws)
    return a, scene.striker_mass * ld.velocity / a


#: a harmonic drive's expected dynamic force, in drive amplitudes: a driven chain below its cutoff
#: carries about A on its first contacts (the static response of a spring chain to a slow force), more
#: near a resonance of the finite chain and where a reflection adds to the incoming wave; the planner
#: bounds the peak with 3 A above F0
HARMONIC_PEAK_AMPLITUDES = 3.0


def expected_peak_force(scene) -> float:
    """An upper estimate of the largest contact force of the run above its static force (N), from the
    paper's models; a harmonic drive's HARMONIC_PEAK_AMPLITUDES x its amplitude."""
    if scene.loading.is_harmonic:
        return HARMONIC_PEAK_AMPLITUDES * scene.drive_amplitude  # (a shaker's: its driver's force)
    return scene.contact.law_class.expected_peak_force(scene, scene.input_impulse, step_equivalent(scene))


def contact_force_bound(scene) -> float:
    """The largest force (N) the nominal contact is expected to carry: the expected peak force, on top
    of a precompression's F0 (every contact carries F0 at rest: PrecompressionEffect.chain_bounds)."""
    return expected_peak_force(scene) + float(scene.effects.precompression)


def max_stiffness(scene) -> float:
    """The nominal contact's stiffest tangent (N/m) at the largest force it is expected to carry
    (contact_force_bound; Hertz: 3/2 k^(2/3) F^(1/3), under precompression about k_lin at F0), k_u
    (bilinear): the stiffness highest_frequency bounds a uniform chain's omega_max with."""
    return float(scene.law.tangent_stiffness(contact_force_bound(scene)))


def _tangent(law, force: float) -> np.ndarray:
    """The stiffest tangent of contacts at the force they are expected to reach: the law's own
    tangent_stiffness (granchain.physics.laws: Hertz 3/2 k^(2/3) F^(1/3), bilinear k_u)."""
    return np.asarray(law.tangent_stiffness(force), dtype=float)


def damping_rate(scene) -> float:
    """The fastest decay rate (1/s) the scene's damping gives any mode: the Gershgorin bound of
    M^-1/2 C M^-1/2 (see highest_frequency); 0 without a damping part that depends on velocity."""
    return highest_frequency(scene, return_damping=True) if scene.damping.velocity_dependent else 0.0


def highest_frequency(scene, return_damping: bool = False) -> tuple[float, str]:
    """An upper bound of the chain's highest frequency (rad/s) over every contact the scene has, and
    the node that sets it.

    The linearised chain at the stiffest tangents K_t has frequencies sqrt(eig(M^-1/2 K_t M^-1/2)); by
    Gershgorin's theorem the largest is at most the largest row sum,
    (k_l + k_r) / m_i + k_l / sqrt(m_(i-1) m_i) + k_r / sqrt(m_i m_(i+1)), which for a uniform chain is
    exactly omega_max = 2 sqrt(k_t / m) (the linear chain's cut-off). Every effect enters where it acts:
    per-bead masses and pair stiffnesses (taper, materials), the wall (an infinite mass; its contact is
    stiffer, k_w, and sees the reflected wave, up to twice the force), a striker (its mass and pair
    stiffness on bead 1), precompression (every contact carries F0 on top of the wave), damping (the
    overdamped modes decay at up to the Gershgorin bound of M^-1/2 C M^-1/2, and an explicit integrator
    must resolve that rate like a frequency). Each effect says what it changes
    (granchain.physics.effects: chain_bounds along the chain, end_bounds at its ends). No contact's
    force is taken above what the run watch lets it carry (physics.effects.watched_force: its law at
    an overlap of OVERLAP_WATCH x the smaller radius of its bodies): a run that reached more is
    stopped, and on a taper's micron beads the nominal chain's force would be an overlap of many
    radii (a 0.806 taper's 1.3 um last bead: 667 N on the wall, 171 radii; the watch holds it to 0.1 N).
    """
    # beads = "auto" (a uniform chain: no per-bead lists): three beads hold every kind of node
    n = scene.chain.beads or 3
    b = Bounds(
        force=expected_peak_force(scene),
        mass=np.full(n, scene.mass),
        radius=np.full(n, float(scene.chain.radius)),
        law=scene.law.per_contact(n - 1),
    )
    active = active_effects(scene)
    for effect in active:  # along the chain: masses, radii, laws, the force level, the damping
        effect.chain_bounds(scene, b)
    m = b.mass
    # no contact carries more than the run watch lets it (watched_force): on a taper's micron beads the
    # nominal chain's expected force is an overlap of many radii, far outside the law's domain
    held = watched_force(b.law, np.minimum(b.radius[:-1], b.radius[1:]))
    force = np.minimum(b.force, held)
    kt = np.broadcast_to(_tangent(b.law, force), (n - 1,))
    # neighbours as (stiffness, neighbour mass) on each side; a missing neighbour adds nothing
    b.kl, b.ml = np.concatenate(([0.0], kt)), np.concatenate(([np.inf], m[:-1]))
    b.kr, b.mr = np.concatenate((kt, [0.0])), np.concatenate((m[1:], [np.inf]))
    # the damping matrix's entries: each contact's viscous coefficient (a dashpot's gamma, Kuwabara-Kono's
    # A k_t), none on a missing neighbour
    c = np.broadcast_to(np.asarray(b.viscous(kt), dtype=float), (n - 1,))
    b.gl, b.gr = np.concatenate(([0.0], c)), np.concatenate((c, [0.0]))
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
    beside = [c for c in (i - 1, i) if 0 <= c < n - 1]
    held_here = bool(np.any(force[beside] < b.force)) or (i == n - 1 and "wall_held" in extra)
    if "striker" in extra and max(math.sqrt(extra["striker"]), 0.0) > omega:
        omega, where, held_here = math.sqrt(extra["striker"]), "the striker", False
    if scene.loading.is_harmonic and 2.0 * math.pi * scene.loading.frequency > omega:  # a drive above the chain's
        return 2.0 * math.pi * scene.loading.frequency, "the harmonic drive's frequency (above the chain's)"
    if damp[i] > np.sqrt(rows[i]):
        where += f" (the {b.damping.noun}'s decay rate {damp[i]:.3g} 1/s)"
    elif "wall" in extra and i == n - 1:
        where += " (on the wall)"
    if held_here:
        where += (
            f", its contacts' forces held to the run watch's overlap bound ({OVERLAP_WATCH:g} x the smaller "
            "radius): the expected force would crush them"
        )
    return omega, where


def one_bead_impacts(scene) -> list[tuple[str, dict[str, float]]]:
    """A one-bead scene's contacts as two-body impacts (models.two_body_impact), in the order they
    happen: the striker on the bead (reduced mass, the striker's speed), then the bead on the wall (the
    bead's mass, at the speed it was given or the striker's). Two free beads, bead 1 given a velocity and
    nothing pressing them together: bead 1 on bead 2 (their reduced mass). Empty for longer chains."""
    ld = scene.loading
    if scene.chain.beads == 2 and ld.kind == "velocity" and scene.effects.far_end == "free":
        if scene.effects.precompression:  # a contact loaded from the start: not an impact
            return []
        m1, m2 = (float(m) for m in scene.bead_masses)
        return [("pair", models.two_body_impact(scene.contact_laws[0], m1 * m2 / (m1 + m2), ld.velocity))]
    if scene.chain.beads != 1:
        return []
    m1 = float(scene.bead_masses[0])
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


#: the longest chain whose linearised response linearised_first_maximum solves exactly (its modes: an
#: n x n eigenvector matrix, and a time grid of a few thousand samples per mode); a longer one is left
#: to the planner's asymptotic estimate
LINEAR_EXACT_BEADS = 600
#: samples of the modal sum per period of the chain's highest linear frequency: a maximum is located to
#: within 1 / LINEAR_SAMPLES_PER_PERIOD of that period
LINEAR_SAMPLES_PER_PERIOD = 32


def linearised_stiffnesses(scene, contacts: int | None = None) -> tuple[np.ndarray, float]:
    """Each bead-bead contact's stiffness about the precompression F0 and the wall contact's (0 without
    a wall), N/m: the slope of its law's virgin curve at F0 (ContactLaw.loading_stiffness: Hertz's
    tangent 3/2 k^(2/3) F0^(1/3), the paper's Eq. 16 differentiated, a linear loading line's own k,
    Thornton's plastic line beyond F_y). contacts: how many of a uniform chain's contacts, default all
    (Scene.n_contacts); a chain of beads = "auto" (uniform: no per-bead lists) has no count of its own."""
    f0 = float(scene.effects.precompression)
    if scene.per_bead:
        k = np.array([float(law.loading_stiffness(f0)) for law in scene.contact_laws])
    else:  # the nominal law's, as the scene's other uniform-chain estimates
        k = np.full(scene.n_contacts if contacts is None else contacts, float(scene.law.loading_stiffness(f0)))
    kw = float(scene.wall_law.loading_stiffness(f0)) if scene.effects.far_end == "wall" else 0.0
    return k, kw


def linearised_first_maximum(scene, contact: int, horizon: float, step: bool = False, floor: float = 0.0):
    """The time (s) of the first maximum of contact `contact`'s force in the precompressed chain
    linearised about F0, or None.

    The chain as it is (every bead's mass, every contact's stiffness linearised_stiffnesses, the wall's
    contact or the free far end, which precompression holds by a constant force): M x'' = -K x, bead 1
    given a unit impulse at t = 0 (step = False: a kick) or a unit force from t = 0 on (step = True), is
    a sum over the modes (K v = w^2 M v): the force of contact c is sum_j k_c (v_j[c] - v_j[c+1]) v_j[1]
    g_j(t), g_j = sin(w_j t) / w_j for the impulse, (1 - cos(w_j t)) / w_j^2 for the force. Its first
    local maximum rising above `floor` (per unit load) within `horizon` is the front's first maximum, with
    what the actual chain does to it: scattering at each change of mass or stiffness, a dimer's optical
    branch, the wall's reflection when the front rises monotonically until it comes back. None when the
    chain is longer than LINEAR_EXACT_BEADS, its length is not given, or no maximum comes within horizon.
    The chain's stiffening with the wave's force only makes a front faster than this.
    """
    n = scene.chain.beads
    if n is None or n < 2 or n > LINEAR_EXACT_BEADS or not 1 <= contact <= n - 1:
        return None
    m = np.asarray(scene.bead_masses, dtype=float)
    k, kw = linearised_stiffnesses(scene)
    # symmetric form M^-1/2 K M^-1/2 (tridiagonal): its eigenvectors u_j = M^1/2 v_j
    diag = (np.concatenate((k, [kw])) + np.concatenate(([0.0], k))) / m
    off = -k / np.sqrt(m[:-1] * m[1:])
    w2, u = eigh_tridiagonal(diag, off)
    v = u / np.sqrt(m)[:, None]
    c = contact - 1
    amp = k[c] * (v[c] - v[c + 1]) * v[0]  # compression of contact c per unit load, mode by mode
    w2 = np.clip(w2, 0.0, None)
    w = np.sqrt(w2)
    moving = w > 1e-9 * w[-1]  # a free chain's rigid mode compresses no contact
    amp, w, w2 = amp[moving], w[moving], w2[moving]
    dt = 2.0 * np.pi / w[-1] / LINEAR_SAMPLES_PER_PERIOD
    # the modal sum in chunks of times (memory), the first local maximum above floor
    chunk = max(64, 2_000_000 // max(1, amp.size))
    start = 0
    total = int(math.ceil(horizon / dt)) + 2
    while start < total:
        t = dt * np.arange(start, min(total, start + chunk + 2))
        phase = np.outer(t, w)
        g = np.sin(phase) / w if not step else (1.0 - np.cos(phase)) / w2
        f = g @ amp
        inner = (f[1:-1] > f[:-2]) & (f[1:-1] >= f[2:]) & (f[1:-1] > floor)
        hit = np.flatnonzero(inner)
        if hit.size:
            i = hit[0] + 1
            # the vertex of the parabola through the maximum's sample and its neighbours (as the peak
            # tracker refines a run's maxima)
            curvature = f[i - 1] - 2.0 * f[i] + f[i + 1]
            shift = 0.5 * (f[i - 1] - f[i + 1]) / curvature if curvature < 0.0 else 0.0
            return float(t[i] + shift * dt)
        start += chunk
    return None
