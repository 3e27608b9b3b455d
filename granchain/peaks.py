"""What a peak is, in one place for both backends, the deck and the observables.

A contact is reached once its peak rises above REACHED_FRACTION of the chain's largest (unreached_as_nan);
its peak is complete once its force has fallen to PEAK_PASSED_FRACTION of it since (complete_peaks); its
leading pulse is its first maximum rising above LEAD_FRACTION of the largest expected force
(leading_pulse). The floors below turn those fractions into forces for a scene (stop_force_floor,
lead_floor, reached_floor), from the planner's largest expected force (physics.estimates).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from granchain.physics.effects.gravity import scene_static_forces
from granchain.physics.estimates import expected_peak_force

#: A contact counts as reached by the wave when its peak force exceeds this fraction of the largest
#: peak in the chain. Below it a "peak" is round-off: an ulp of a bead's position is an overlap of
#: ~1e-18 m (granchain.physics.positions places LAMMPS's beads so that at-rest contacts have none).
REACHED_FRACTION = 1e-9


def unreached_as_nan(peak_force: np.ndarray, time_of_peak: np.ndarray, static_force: float = 0.0) -> np.ndarray:
    """time_of_peak with nan where the contact was not reached (see REACHED_FRACTION).

    static_force: a precompression F0 every contact starts at; reached means rising above it.
    """
    rise = np.asarray(peak_force) - static_force
    floor = REACHED_FRACTION * float(np.max(rise, initial=0.0))
    return np.where(rise > floor, time_of_peak, np.nan)


def end_contact_reached(force: float, static_force: float, rises) -> bool:
    """Whether a striker's or a wall's contact was reached by the wave, by unreached_as_nan's rule.

    Parameters
    ----------
    force : float
        The contact's largest force (N).
    static_force : float
        The force it carries at rest (a wall: the precompression F0; a striker: 0).
    rises : array_like
        Every other contact's largest rise above its static force (N); nan for a contact without one
        (a peak_force list's other contacts) is left out.

    Returns
    -------
    bool
        Its rise exceeds REACHED_FRACTION of the largest rise of any contact. Below that its force is
        round-off ahead of the wave (a Hertz chain's precursor touches a wall the wave has not reached
        with forces of 1e-18 N and less), not a force the run measured.
    """
    rise = float(force) - float(static_force)
    rises = np.asarray(rises, dtype=float)
    # a nan (a contact not measured) left out: np.max's nan made every wall and striker "not reached"
    largest = max(float(np.max(rises[~np.isnan(rises)], initial=0.0)), rise)
    return rise > REACHED_FRACTION * largest


#: A contact's peak is complete once the contact's force has fallen to at most this fraction of its
#: peak (both counted above the static force F0) at some sample after the peak. It is the fraction
#: by which [run] stop_after_contact decides that the leading wave has passed a contact (the
#: reference's wave_passed and the deck's v_wave_passed), so a run stopped by it ends with its stop
#: contact complete. Why this value:
#: - A peak that is not complete is the force at the end of the run (still rising), or a maximum so
#:   recent that the next samples might still exceed it; neither converges with the time step.
#: - A fall to half the peak cannot be round-off or integration noise, nor a flat top: the peak is a
#:   genuine local maximum with samples on both sides, refined inside its step (Hermite / parabola),
#:   so its value converges at the method's order.
#: - It is checked on the minimum since the peak, not on the force at the end: behind a long load's
#:   front the force oscillates (elastic-step-40N: between 0.01 and 0.85 of the peak at the end of
#:   the run), and the force at the end alone would mark 39 of that scene's 151 window contacts,
#:   passed long before, as incomplete. Every one of them fell below 0.03 of its peak.
#: - A later, larger peak (a reflection, a second wave) moves the peak and restarts the minimum.
PEAK_PASSED_FRACTION = 0.5


#: A leading pulse must rise above this fraction of the planner's largest expected force. Ahead of a
#: front, dispersive precursors make maxima: on a 500-bead steel bilinear chain (2 kN step) they
#: reached 1e-5 N, 3e-9 of the expected 3.4 kN, 0.6 ms before the 50 N front, and taken as the first
#: maximum they moved the wave speed by 3% between two time steps. Leading pulses
#: decay along a chain by far less than 1e6 (the same chain: 46x over 374 contacts); one that decays
#: more is reported as not measured, with the reason.
LEAD_FRACTION = 1e-6


def leading_pulse(
    flead: np.ndarray, tlead: np.ndarray, time_of_peak: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The leading pulse of each contact, read back from a backend's frozen values (0: none yet).

    Definition (docs/observables.md): the first maximum of a contact's force whose rise above the
    static force F0 exceeds LEAD_FRACTION of the largest expected force (lead_floor) and below which
    the force then falls by lead_fall before it rises above it, frozen from then on: the first sample
    above both neighbours, refined by the vertex of the parabola through the three (as the running
    peak), in both backends at every step (RK4: the first maximum of the overlap inside a step, on its
    Hermite interpolant, and the force there); a rise above it before the fall moves it on to the
    running peak. Its time is the front's arrival at the contact. In a forming wave train this is
    the first pulse, whatever larger pulses follow; on a front that rises to a plateau it is the
    plateau's first overshoot, not the largest of the oscillations that follow (those do not converge
    with the time step: docs/observables.md). Measured limit: a shoulder on the rise whose slope only
    just turns negative is a maximum at one time step and not at another.
    A backend writes 0 where no maximum rose above the floor and -1 where one still waits for its
    fall at the end of the run: neither is a leading pulse.
    """
    flead = np.asarray(flead, dtype=float)
    done = flead > 0.0
    if time_of_peak is not None:  # a contact that counts as not reached (unreached_as_nan) has no pulse
        done &= np.isfinite(time_of_peak)
    return np.where(done, flead, np.nan), np.where(done, np.asarray(tlead, dtype=float), np.nan)


def complete_peaks(
    peak_force: np.ndarray, force_min_after_peak: np.ndarray, time_of_peak: np.ndarray, static_force: float = 0.0
) -> np.ndarray:
    """Which contacts' peaks are complete: the one definition, used by every backend.

    force_min_after_peak: the smallest force sample of each contact since (the sample of) its peak;
    time_of_peak: nan for contacts the wave has not reached (see unreached_as_nan), never complete.
    Complete: reached and min - F0 <= PEAK_PASSED_FRACTION (peak - F0) (see PEAK_PASSED_FRACTION).
    """
    rise = np.asarray(peak_force, dtype=float) - static_force
    fell = np.asarray(force_min_after_peak, dtype=float) - static_force <= PEAK_PASSED_FRACTION * rise
    return np.isfinite(time_of_peak) & fell


def every_contact_complete(
    peak_force: np.ndarray, force_min_after_peak: np.ndarray, time_of_peak: np.ndarray, static_force: np.ndarray
) -> np.ndarray:
    """complete_peaks over a whole chain with its effects' contacts (a striker's first, a wall's last),
    each with its own static force (a striker touches bead 1 unloaded; a wall carries F0 as every
    bead-bead contact does): reached above REACHED_FRACTION of the largest rise of any of them.

    The effects' contacts (Effect.end_fields) take theirs from here: a wall the wave has not passed
    by the end of the run, or has not reached, holds a running maximum that is not a peak.
    """
    static = np.asarray(static_force, dtype=float)
    return complete_peaks(peak_force, force_min_after_peak, unreached_as_nan(peak_force, time_of_peak, static), static)


def still_rising(complete: np.ndarray, time_of_peak: np.ndarray, velocity: np.ndarray) -> np.ndarray:
    """Which contacts the wave is still arriving at when the run ends: the one definition, used for
    every backend (from the recorded end state, not in-run).

    complete: complete_peaks; time_of_peak: nan for contacts not reached; velocity: every bead's
    velocity at the end of the run (N,), m/s, along the chain. Still rising: reached, its peak not
    complete (its force has stayed above PEAK_PASSED_FRACTION of its peak since: the stop check's
    "not passed"), and its overlap still closing at the end (the bead behind the contact moving
    faster than the one ahead): the force grows towards a peak the run has not seen, which may exceed
    the peak so far (a main wave rising behind a smaller precursor). A peak not complete whose force
    falls at the end is a maximum the run has seen.
    """
    complete = np.asarray(complete, dtype=bool)
    v = np.asarray(velocity, dtype=float)
    if v.size != complete.size + 1:  # a backend without the end state: nothing is known to rise
        return np.zeros(complete.shape, dtype=bool)
    return np.isfinite(np.asarray(time_of_peak, dtype=float)) & ~complete & (v[:-1] > v[1:])


def stop_force_floor(scene) -> float:
    """The smallest peak that counts as the leading wave for [run] stop_after_contact (both backends):
    the static force plus REACHED_FRACTION of the largest expected force. Round-off forces ahead of
    the wave (an ulp of overlap: ~1e-11 N on a linear contact) stay far below.
    Under precompression the chain is linear about F0 and carries precursors ahead of the front (the
    integrator's dispersion too: a 300-bead brass chain at F0 = 100 N, a 0.1 N step, stopped at 2 dt
    on one a millisecond before the front): there the leading pulse's floor (lead_floor).
    Under gravity the static force is the largest, the wall's (F0 + the chain's weight): a floor above
    every contact's own, as the leading pulse's (a contact opening below its weight is no reflection)."""
    static = float(np.max(scene_static_forces(scene), initial=0.0))
    return static + (lead_floor(scene) if scene.effects.precompression else reached_floor(scene))


def lead_floor(scene) -> float:
    """The smallest rise above the static force that can be a leading pulse (both backends; the deck
    passes it to the pair styles, the reference solver gets it from its backend).

    Parameters
    ----------
    scene : Scene
        A planned scene (a precompressed one needs its end time and time step).

    Returns
    -------
    float
        LEAD_FRACTION of the largest expected force; on a precompressed chain at least
        position_resolution(scene), the total force LAMMPS resolves, so that its round-off is never a
        leading pulse (docs/observables.md).
    """
    floor = LEAD_FRACTION * expected_peak_force(scene)
    if scene.effects.precompression:
        floor = max(floor, position_resolution(scene))
    return floor


def lead_fall(scene) -> float:
    """How far the force must fall below a maximum before it counts as the leading pulse (N; both
    backends: the deck passes it to the pair styles, the reference solver gets it from its backend).

    Parameters
    ----------
    scene : Scene
        A planned scene (a precompressed one needs its end time and time step).

    Returns
    -------
    float
        position_resolution(scene): on a precompressed chain LAMMPS's round-off on a slow rise makes
        local maxima of its own, smaller than this; 0 without precompression (a maximum counts at once).
    """
    return position_resolution(scene)


#: the leading pulse's floor on a precompressed chain in standard deviations of LAMMPS's force round-off
#: (position_resolution): a Gaussian reaches 6 sigma with probability 1e-9 per independent sample, and a
#: run has far fewer independent samples of a contact's noise than that
RESOLUTION_SIGMAS = 6.0


def position_resolution(scene) -> float:
    """The rise above F0 that LAMMPS's round-off of positions cannot make on a precompressed chain (N).

    LAMMPS integrates absolute positions x (up to the chain's length L): every step rounds each moving
    bead's new position to a multiple of ulp(x) <= ulp(L) (Scene.contact_quantum), an error uniform in
    +- ulp / 2, standard deviation ulp / sqrt(12). The chain does not damp them: over the run's n steps
    they add up as a random walk, sqrt(n / 12) ulp per bead, and a contact's overlap, the difference of
    two beads' positions, carries sqrt(n / 6) ulp. Its force carries that times the contact's slope at
    F0, k_lin (Hertz 3/2 K^(2/3) F0^(1/3): the linearised chain; the stiffest contact's). The errors
    made behind a front travel with it, so the wave's precursors carry them too, and there a maximum of
    the round-off on the slowly rising force counts as a leading pulse. The reference integrates
    displacements from the static state and resolves far finer (3e-13 N where LAMMPS resolves 1e-7 N);
    both backends use this floor, so runs at the same step report the same leading pulses (a run at
    another step, a companion or RK4 beside LAMMPS in a compare, has the floor of its own step count).

    Measured (a 300-bead brass chain at F0 = 100 N, a 0.1 N step, the planned step 2.3e-7 s; LAMMPS
    against the reference's Verlet at the same step, every contact at every step): k_lin ulp(L) =
    7.9e-9 N, sqrt(n / 6) = 56 of them (n = 18 730); the largest difference before a contact's leading
    pulse 67 of them (1.2 sigma), 185 at a quarter of the step (1.65 sigma), and at 1.5 sigma on a
    100-bead chain; noise counts as leading pulses at 12 contacts, 4.1e-7 - 7e-7 N above F0, under
    LEAD_FRACTION's floor alone (4e-7 N). The floor is RESOLUTION_SIGMAS of this standard deviation: 2.7e-6 N there.

    Parameters
    ----------
    scene : Scene
        A planned precompressed scene: its end time and time step give the steps n.

    Returns
    -------
    float
        RESOLUTION_SIGMAS k_lin ulp(L) sqrt(n / 6); 0 without precompression.
    """
    f0 = float(scene.effects.precompression)
    if not f0:
        return 0.0
    if scene.run.end_time is None or scene.run.timestep is None:
        raise ValueError("position_resolution needs a planned scene (its end time and time step)")
    steps = math.ceil(scene.run.end_time / scene.run.timestep)
    k_lin = max(float(np.max(law.tangent_stiffness(f0))) for law in chain_laws(scene))
    return RESOLUTION_SIGMAS * k_lin * scene.contact_quantum * math.sqrt(steps / 6.0)


def chain_laws(scene) -> list:
    """The contact laws of every distinct pair of bead kinds the chain joins (the nominal law alone on
    a uniform chain)."""
    laws = [scene.law]
    if scene.per_bead:
        kinds, kind_of = scene.bead_kinds
        first: dict[tuple[int, int], int] = {}  # each pair's first contact (its [contact] values)
        for c, pair in enumerate(zip(kind_of[:-1], kind_of[1:], strict=True)):
            first.setdefault(pair, c)
        laws = [scene.bead_pair_law(*kinds[i], *kinds[j], c) for (i, j), c in sorted(first.items())] or laws
    return laws


def event_floor(scene) -> float:
    """The rise above the wall's static force at which the event has begun (granchain.physics.event):
    the stop check's floor above the static force (stop_force_floor less the largest static force)."""
    return lead_floor(scene) if scene.effects.precompression else reached_floor(scene)


def reached_floor(scene) -> float:
    """REACHED_FRACTION of the largest expected force: round-off forces ahead of the wave stay below."""
    return REACHED_FRACTION * expected_peak_force(scene)


def free_flight(scene, solution) -> bool:
    """Whether the run ended with no force able to act again: every peak so far is then final.

    Provable only on an uncompressed chain whose load has stopped acting: every contact open (its
    overlap, the beads' displacements' difference from the touching placement, at most 0) and not
    closing (the bead behind no faster than the one ahead), and, with a wall, bead N neither pressing
    it nor moving towards it. Then each bead flies free, every gap only grows, and no contact closes
    again. A striker's end position is not recorded: with a striker nothing is proved.

    Parameters
    ----------
    scene : Scene
        The planned scene that ran.
    solution : ChainSolution
        Its result: the end state's displacement and velocity (N,).

    Returns
    -------
    bool
        The end state is free flight (False where a backend left the end state out).
    """
    u, v = np.asarray(solution.displacement, dtype=float), np.asarray(solution.velocity, dtype=float)
    ld = scene.loading
    if scene.effects.precompression or ld.kind == "striker" or u.size != scene.chain.beads or v.size != u.size:
        return False
    if ld.is_force and ld.duration >= solution.end_time:
        return False
    free = bool(np.all(u[:-1] - u[1:] <= 0.0) and np.all(v[:-1] <= v[1:]))
    if scene.effects.far_end == "wall":
        free = free and u[-1] <= 0.0 and v[-1] <= 0.0
    return free


def reflection_pending(scene, solution) -> np.ndarray:
    """Which contacts' peaks the wave reflected from a wall may still exceed when the run ends (N-1,).

    On an uncompressed chain against a wall the wave comes back from the wall through every contact,
    and at a contact it passed on its way in the reflection can be the larger pulse (a dimer, mass
    ratio 1/8, struck at 1 m/s: contact 21's 114.5 N was 122.3 N once the reflection had passed). A
    contact whose largest force came before the wall's (its incoming pulse's) is pending unless the
    run ended in free flight (free_flight) or its stop check ended it once the reflection had passed
    back through contact 1 ([run] stop_after_reflection, the planner's on such a chain: the run ended
    before its end time), the last the reflection reaches: a run that stops once the wave has passed
    the wall, or a fixed end time, can end before the reflection has passed the contacts behind it.
    On a precompressed chain the reflection
    comes back too, but the chain never flies apart and nothing is proved: not marked (a limit,
    docs/observables.md).
    """
    t = np.asarray(solution.time_of_peak, dtype=float)
    pending = np.zeros(t.shape, dtype=bool)
    tw = solution.wall_time_of_peak
    if scene.effects.far_end != "wall" or scene.effects.precompression or tw is None:
        return pending
    returned = scene.run.stop_after_reflection and solution.end_time < scene.run.end_time * (1.0 - 1e-9)
    if returned or free_flight(scene, solution):
        return pending
    if not math.isfinite(tw):  # the wave has not reached the wall: its reflection is still to come everywhere
        return np.isfinite(t)
    return np.isfinite(t) & (t < tw)


def mark_reflection_pending(scene, solution) -> None:
    """Make the peaks the wall's reflection may still exceed (reflection_pending) not complete in
    solution, in place: every backend's result, and a collected plain-LAMMPS run's, the same way; a
    sensor bead's (granchain.postprocess.sensors) by the same rule on its own peak's time."""
    solution.complete = solution.complete & ~reflection_pending(scene, solution)
    if np.size(solution.sensor_time_of_peak):
        sensors = replace(solution, time_of_peak=solution.sensor_time_of_peak)
        solution.sensor_complete = solution.sensor_complete & ~reflection_pending(scene, sensors)
