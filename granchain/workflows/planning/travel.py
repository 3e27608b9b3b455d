"""The waves the planner plans with: their speeds, the front's travel time to a contact (sonic,
precompressed, the linear chain's first maximum), and the last contact whose peak is measured."""

from __future__ import annotations

import numpy as np

from granchain.peaks import LEAD_FRACTION
from granchain.physics.estimates import (
    expected_peak_force,
    linearised_first_maximum,
    linearised_stiffnesses,
    step_equivalent,
)


def leading_edge_speed(scene) -> float:
    """The fastest a disturbance can enter the undisturbed chain, m/s (see granchain.workflows.plan's docstring)."""
    return scene.contact.law_class.leading_edge_speed(scene, expected_peak_force(scene), step_equivalent(scene))


def wave_speeds(scene) -> tuple[float, float]:
    """(slowest leading-wave speed, fastest wave speed) expected, m/s (the law's estimate)."""
    return scene.contact.law_class.wave_speeds(scene, expected_peak_force(scene), step_equivalent(scene))


#: The first maximum of a linear chain's force trails the sonic front by dispersion. Bead 1 of a
#: uniform chain (mass m, linearised stiffness k_lin, tau = sqrt(m / k_lin)) kicked at t = 0: the force
#: of contact n goes as (2n / x) J_2n(x) with x = 2 t / tau (the free end as a mirror image of the
#: infinite chain's Bessel solution), whose first maximum is near x = 2n + 0.81 (2n)^(1/3) (Abramowitz
#: and Stegun 9.5.16), t = tau (n + 0.51 n^(1/3)): the front's travel is planned as
#: sum(tau_i) (1 + PRECOMPRESSED_LAG n^(-2/3)). Measured (reference, Verlet): a uniform brass chain at
#: F0 = 1e3 x the kick's force, 0.99 of the planned time at contact 35 (the Bessel value; 0.6 > 0.51).
PRECOMPRESSED_LAG = 0.6
#: A chain whose masses and stiffnesses vary from contact to contact (random radii, materials, a dimer)
#: slows its first maximum more than the sum of local times sqrt(m_i / k_i) says: scattering at each
#: change. Its long waves move at the homogenised slowness sqrt(<m> <1 / k_lin>) (masses in sum,
#: springs in series), never less than the mean local time (Cauchy-Schwarz); averaged over the whole
#: chain it overestimates a taper's time (heavy beads at one end, soft contacts at the other) by up to
#: 2.6x, so each contact takes it over its PRECOMPRESSED_NEIGHBOURS neighbours on each side. Measured
#: with the lag above (reference, Verlet; 13 chains at F0 = 10 to 1e3 x the kick's force, every
#: contact): at most 0.99 of the planned time (the uniform chain), random materials with PTFE 0.96
#: (1.12 with the local times alone), tapers 0.96, dimers 0.95, random radii 0.86; at the window's end
#: the plan is at most 1.48 x the arrival (1.56 on a taper 0.8, where the stop check ends the run).
PRECOMPRESSED_NEIGHBOURS = 2
#: ... and the time after the front's arrival a long load's first maximum needs, as a fraction of the
#: front's travel
PRECOMPRESSED_TAIL = 0.3
#: A lasting force on bead 1 of the linear chain (a step): the force of contact n is the integral of
#: the kick's response, whose first maximum is where (2n / x) J_2n(x) first crosses zero, at
#: x = j_2n,1 = 2n + 1.856 (2n)^(1/3) + 1.033 (2n)^(-1/3) (Abramowitz and Stegun 9.5.14), that is
#: t = tau (n + 1.17 n^(1/3) + 0.41 n^(-1/3)): planned as sum(tau_i) (1 + STEP_LAG[0] n^(-2/3) +
#: STEP_LAG[1] n^(-4/3)). Measured: a 300-bead brass chain at F0 = 100 N, a 0.1 N step: contact 1's first
#: maximum at 1.6x the kick's planned travel (2.57 tau, j_2,1 / 2), contact 2's at 1.38x (j_4,1 / 2).
STEP_LAG = (1.2, 0.45)


def sonic_travel_times(scene, last: int, step: bool = False) -> np.ndarray:
    """The time the first maximum of a precompressed chain's front takes from bead 1 to each contact
    1 .. last (s), at the linear sound speed: per contact tau_i = sqrt(<m> <1 / k_lin>) over the contact
    and its PRECOMPRESSED_NEIGHBOURS neighbours on each side, with the heavier bead of each contact and
    k_lin the slope of the law's virgin curve at F0 (estimates.linearised_stiffnesses: for Hertz
    3/2 k^(2/3) F0^(1/3), dF/dalpha of the paper's Eq. 16, a linear loading line's own k, Thornton's
    plastic line beyond F_y), so that
    c0 = a sqrt(k_lin / m) on a uniform chain; summed, with the dispersion lag PRECOMPRESSED_LAG of a
    kick or, with step = True, STEP_LAG of a lasting force. A chain of beads = "auto" is uniform and
    reaches past `last` (the planner's N is at least last + 5: _beads_choice): its contacts up to
    last + PRECOMPRESSED_NEIGHBOURS are every window's."""
    n_c = scene.n_contacts if scene.chain.beads is not None else last + PRECOMPRESSED_NEIGHBOURS
    k_lin = linearised_stiffnesses(scene, n_c)[0]
    m = scene.bead_masses if scene.per_bead else np.full(n_c + 1, scene.mass)
    heavier = np.maximum(m[:-1], m[1:])
    h = PRECOMPRESSED_NEIGHBOURS
    # running sums give each contact's window [i - h, i + h] (clipped at the chain's ends)
    cm, ck = np.concatenate(([0.0], np.cumsum(heavier))), np.concatenate(([0.0], np.cumsum(1.0 / k_lin)))
    i = np.arange(last)
    lo, hi = np.maximum(i - h, 0), np.minimum(i + h + 1, n_c)
    width = hi - lo
    tau = np.sqrt((cm[hi] - cm[lo]) / width * (ck[hi] - ck[lo]) / width)
    n = np.arange(1, last + 1)
    if step:
        return np.cumsum(tau) * (1.0 + STEP_LAG[0] * n ** (-2.0 / 3.0) + STEP_LAG[1] * n ** (-4.0 / 3.0))
    return np.cumsum(tau) * (1.0 + PRECOMPRESSED_LAG * n ** (-2.0 / 3.0))


#: how far past the whole chain's sonic crossing (sonic_travel_times at its last contact) the linearised
#: chain's response is searched for a contact's first maximum: a front that rises monotonically at a
#: contact meets its maximum when a reflection comes back (the wall's adds to it, a free end's takes
#: away), within a round trip through the chain and back. A run that ended before measuring its window
#: is extended to as many crossings of the whole chain by the slowest front (extended_plan), for the same
#: reason
LINEAR_HORIZON = 3.0


def precompressed_front_time(scene, last: int, step: bool = False) -> float:
    """The time (s) the first maximum of a precompressed chain's front takes from bead 1 to contact `last`,
    a kick's or (step = True) a lasting force's: the linearised chain solved exactly
    (estimates.linearised_first_maximum: each bead's mass and contact's stiffness, the wall), with the
    leading pulse's floor per unit load; on a chain too long to solve exactly (or one
    of "auto" length, which is uniform), the asymptotic sonic_travel_times."""
    asymptotic = float(sonic_travel_times(scene, last, step)[-1])
    n = scene.chain.beads
    if n is None or not scene.n_contacts:
        return asymptotic
    load = step_equivalent(scene)[0] if step else scene.input_impulse
    horizon = LINEAR_HORIZON * float(sonic_travel_times(scene, scene.n_contacts, step)[-1])
    # the leading pulse's floor (peaks.lead_floor) without its part for LAMMPS's round-off, which needs
    # the planned end and time step and lies far below a front's rise
    floor = LEAD_FRACTION * expected_peak_force(scene)
    exact = linearised_first_maximum(scene, last, horizon, step=step, floor=floor / load)
    return asymptotic if exact is None else max(asymptotic, exact)


def front_travel_time(scene, last: int, slow: float) -> float:
    """The time the slowest expected leading front takes from bead 1 to contact `last`: per contact,
    the nominal chain's time per diameter (D / slow) scaled by the contact's own stiffness and the
    heavier of its beads (speed ~ k^(2/5) / sqrt(m) for a Hertzian front, whose force also scales as
    k^(2/5) at a given momentum (the Hertz impact) and whose speed as k^(1/3) F^(1/6); k^(1/2) / sqrt(m)
    for a linear one; times the spacing: the time per contact does not depend on the spacing); under
    precompression at most the time of the linearised chain's first maximum (precompressed_front_time):
    a front moves at least at the sound speed c0 = a sqrt(k_lin / m), faster as its force grows."""
    d0 = scene.diameter
    per_contact = np.full(last, d0 / slow)
    if scene.per_bead and scene.n_contacts:
        # 1/(1 + n) of the onset F ~ alpha^n (ContactLaw.loading_exponent): 0.4 Hertz, 0.5 a loading line
        # (the impact's force ~ k^(1/(1+n)))
        e = 1.0 / (1.0 + float(np.max(scene.law.loading_exponent())))
        m = scene.bead_masses
        heavier = np.maximum(m[:-1], m[1:])[:last]
        per_contact = per_contact * _stiffness_scaling(scene, last, e) * np.sqrt(heavier / scene.mass)
    travel = float(np.sum(per_contact))
    if scene.effects.precompression and scene.has_contacts:  # an "auto" chain: the asymptotic front
        travel = min(travel, precompressed_front_time(scene, last))
    return travel


def extension_budget(scene, slow: float) -> float:
    """The longest end a run of `scene` (a chain of given length) is ever run to (s): LINEAR_HORIZON x
    the slowest front's crossing of the whole chain (front_travel_time to its last contact at the
    slowest expected speed `slow`), the end extended_plan runs a run again to. A load lasting longer
    than it is a lasting one for the wall (wall_peak_planned)."""
    return LINEAR_HORIZON * front_travel_time(scene, scene.n_contacts, slow)


def last_measured_contact(scene) -> int | None:
    """The farthest contact a requested output measures: histories, a peak_force list, the window;
    peak_force = true on a chain of given length measures the leading peak and the wave speed over
    the window, so the run lasts until the wave has passed the window's end (scene.window)."""
    o = scene.outputs
    cands = list(o.histories)
    if isinstance(o.peak_force, tuple) and o.peak_force:
        cands.append(max(o.peak_force))
    if o.window is not None:
        cands.append(o.window[1])
    elif o.peak_force is True and scene.chain.beads is not None and scene.n_contacts:
        cands.append(scene.window[1])
    return max(cands) if cands else None


def _stiffness_scaling(scene, last: int, e: float) -> np.ndarray:
    """Each of the first `last` contacts' time per diameter over the nominal one's, from its stiffness:
    (k_nominal / k)^e; with per-contact n (a power law's lists, whose K differ in units) the ratio of
    the linearised speeds instead, sqrt(k_t,nominal / k_t) of the tangents at the expected force: a
    contact of larger n is softer below a force and stiffer above, and the wave's force sets which."""
    if not scene.contact.coefficients.varies:
        return (float(scene.stiffness) / scene.contact_stiffnesses[:last]) ** e
    f = expected_peak_force(scene)
    kt = np.array([float(law.tangent_stiffness(f)) for law in scene.contact_laws[:last]])
    return np.sqrt(float(scene.law.tangent_stiffness(f)) / kt)
