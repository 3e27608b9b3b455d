"""The planner: as short, as coarse and as small a run as the requested outputs allow.

plan_scene(scene, rtol) fills every "auto" value (and, with a tolerance, the time step) and says why:

time step   the stiffest contact the run will see sets the highest chain frequency
            omega_max = 2 sqrt(k_t / m), with k_t the Hertz tangent stiffness 3/2 k^(2/3) F^(1/3) at
            the largest expected force (from the paper's peak-force models) or k_u (bilinear).
            The step is the largest one whose error model C (omega_max dt)^p stays below rtol
            (p the integrator's order, 4 for RK4, 2 for Verlet; C calibrated on the reference
            solver: granchain.integrators, IntegratorFacts.calibration),
            below the stability limit, and short enough to resolve the load (T/4; a pulse shorter than
            one step is a step of its own, the step plan ends a step at T).
beads       just enough that nothing reflected from the far end reaches the last measured contact
            before the end: the disturbance reaches bead N no sooner than N D / c_lead and comes back
            to contact L no sooner than (N - L) D / c_max, so N > (t_end + L D / c_max) /
            (D / c_lead + D / c_max); c_max is the fastest wave expected anywhere, c_lead the fastest
            that can enter the undisturbed chain (Hertz: c_max; bilinear: the loading line's sound
            speed D sqrt(k/m), the largest group velocity of a linear chain; the faster unloading
            speed D sqrt(k_u/m) only exists behind the front).
end time    long enough for the leading wave to pass the last measured contact L, at the slowest
            leading speed expected, plus the load duration (long loads); under precompression no
            later than the first maximum of the chain linearised about F0 at L, solved exactly on
            the actual chain (its masses, contacts and wall: scattering, a dimer's light beads, a
            front that rises until the wall's reflection comes back) where it is short enough.
            A run of a chain of given length that still ends before its window's last contact
            has a first maximum, or while the force there still rises (a main wave behind a
            smaller precursor), says so and is run again, once, longer (extended_plan), its stop
            check ending it. On a wall, with peak forces asked for (wall_peak_planned: a kick, a
            striker, or a force load that ends within LINEAR_HORIZON crossings of the chain), until the wall's peak is
            measured too: the end for contact N-1 (or the load's end crossing the chain) and
            WALL_PULSE_CONTACTS contacts' travel more, the stop check also waiting for the wall's
            contact ([run] stop_after_wall; a stop check the scene gives without it keeps its end).

The estimates it plans with (step equivalent, expected peak force, stiffest tangents, highest
frequency, dashpot rate) are granchain.physics.estimates; the output strides granchain.schedule.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from granchain.exceptions import UsageError
from granchain.integrators import INTEGRATORS, integrator
from granchain.peaks import LEAD_FRACTION
from granchain.physics.effects.base import watched_force
from granchain.physics.estimates import (
    damping_rate,
    expected_peak_force,
    highest_frequency,
    linearised_first_maximum,
    linearised_stiffnesses,
    max_stiffness,
    one_bead_impacts,
    step_equivalent,
)
from granchain.scene import AUTO, Scene, SceneError, scene_from_dict, scene_to_dict
from granchain.schedule import output_stride

#: The error model  rel. error of peak forces ~ C (omega_max dt)^p, its constant C and order p, and the
#: omega_max dt limits of stability are each integrator's (granchain.integrators: calibration, order,
#: stability, with the measurements behind them).


@dataclass(frozen=True)
class PlanChoice:
    """One choice of the planner (time step, end time, beads, an output interval, the stop check): its
    value and the reason, in words with the scene's numbers."""

    name: str
    value: float
    reason: str


@dataclass
class Plan:
    """The planner's choices for a scene (``plan_scene``): the concrete scene they make, the rtol and
    integrator planned for, each choice with its reason, omega_max and the stable step
    integrator(method).stability / omega_max."""

    scene: Scene  # concrete: no "auto" left
    rtol: float
    method: str
    choices: list[PlanChoice] = field(default_factory=list)
    omega_max: float = 0.0
    stable_timestep: float = 0.0


def predicted_error(method: str, omega_max: float, rate: float, dt: float) -> float:
    """The planner's error model for the relative error of peak forces at a time step dt: C (omega_max
    dt)^p, plus D x rate x dt for an integrator whose dashpot force is first-order accurate (velocity
    Verlet and LAMMPS evaluate it with the half-step velocities; IntegratorFacts.dashpot_error)."""
    facts = integrator(method)
    err = facts.calibration * (omega_max * dt) ** facts.order
    if facts.dashpot_error:
        err += facts.dashpot_error * rate * dt
    return err


#: A peak much smaller than the run's force scale carries the absolute error the model predicts for
#: the scale: the error model bounds a peak's error by C (omega_max dt)^p times the forces it was
#: calibrated on (the largest of the run), not times the peak itself. Measured (LAMMPS at the
#: step planned for rtol 1e-3 against a quarter of it; complete peaks of the window's contacts):
#: a 500-bead steel bilinear chain whose front decays from 2.3 kN to 49 N (scale over
#: smallest peak 123), missed by 36 x rtol; the bundled Table I chain (ratio 3) was 0.07 x rtol and a
#: plastic short impulse (ratio 42) 0.7 x rtol. A planned run whose measured peaks fall below its
#: force scale is therefore run again at the step planned for rtol / ratio (refined_plan); the ratio
#: counts up to MAX_PEAK_RATIO, below which a peak is too small to be planned for (it is named).
MAX_PEAK_RATIO = 1e4
#: A run is refined only when its smallest peaks miss rtol by more than the margin the calibration keeps
#: (C = 1 against measured 0.1-0.6): a peak within a factor 2 of the scale is what the calibration
#: measured (an elastic chain's first contacts peak 1.2 x above its formed wave) and costs no rerun.
REFINE_ABOVE = 2.0


def peak_ratio(scene, solution) -> tuple[float, float, int] | None:
    """(force scale / smallest measured peak, that peak (N), its 1-based contact), or None.

    The measured peaks are the complete peaks (peaks.complete_peaks) of contacts 1 .. the last
    measured contact (last_measured_contact: the window's end, a peak_force list, histories), and the
    leading pulse at the window's end; forces are counted above the static force F0. The force scale
    is the largest of those peaks: the forces at which the run makes its largest errors (the
    planner's expected force is an upper estimate with a margin, not a measurement). None when the
    run measured no complete peak.
    """
    last = last_measured_contact(scene)
    if last is None:
        return None
    f0 = scene.effects.precompression or 0.0
    rise = np.asarray(solution.peak_force, dtype=float)[:last] - f0
    complete = np.asarray(solution.complete, dtype=bool)[:last] if np.size(solution.complete) else np.zeros(0, bool)
    if complete.size == 0 or not complete.any():
        return None
    idx = np.flatnonzero(complete & (rise > 0))
    if idx.size == 0:
        return None
    i = int(idx[np.argmin(rise[idx])])
    smallest = float(rise[i])
    lead = np.asarray(solution.leading_pulse_force, dtype=float)
    if last <= lead.size and np.isfinite(lead[last - 1]) and lead[last - 1] - f0 > 0 and lead[last - 1] - f0 < smallest:
        i, smallest = last - 1, float(lead[last - 1] - f0)
    scale = float(np.max(rise[complete]))
    return scale / smallest, smallest, i + 1


#: a refined run's step is at most this much finer than the first run's: Verlet with a dashpot plans
#: its step proportional to rtol (first order), so a scale 1e4 above the smallest peak asked for a
#: 1e4x finer step (measured: 3e8 steps for a 24-bead generated chain); the rest is said, not run
MAX_REFINE_STEP = 16.0


def refined_plan(scene: Scene, plan: Plan, solution) -> Plan | None:
    """The plan to run again when a planned run's measured peaks fell far below its force scale.

    scene: the scene as given (with its "auto" values); plan: the plan the run used (its time step
    chosen by the planner); solution: that run's ChainSolution. Returns None when every measured peak
    met plan.rtol by the error model (predicted_error x peak_ratio <= rtol); else the plan for
    rtol / ratio, its time step choice saying why (see MAX_PEAK_RATIO).
    """
    if not any(c.name == "timestep" for c in plan.choices):
        return None
    found = peak_ratio(plan.scene, solution)
    if found is None:
        return None
    ratio, smallest, contact = found
    dt = plan.scene.run.timestep
    predicted = predicted_error(plan.method, plan.omega_max, damping_rate(plan.scene), dt) * ratio
    if predicted <= REFINE_ABOVE * plan.rtol:
        return None
    used = min(ratio, MAX_PEAK_RATIO)
    new = plan_scene(scene, rtol=plan.rtol, method=plan.method, peak_ratio=used)
    if new.scene.run.timestep >= dt * (1 - 1e-12):
        return None  # the step is set by stability or the load, already finer than needed
    capped = new.scene.run.timestep < dt / MAX_REFINE_STEP
    if capped:  # the largest ratio whose step is at least dt / MAX_REFINE_STEP (bisection in log ratio)
        lo, hi = 1.0, used
        for _ in range(30):
            mid = math.sqrt(lo * hi)
            trial = plan_scene(scene, rtol=plan.rtol, method=plan.method, peak_ratio=mid)
            lo, hi = (mid, hi) if trial.scene.run.timestep >= dt / MAX_REFINE_STEP else (lo, mid)
        used = lo
        new = plan_scene(scene, rtol=plan.rtol, method=plan.method, peak_ratio=used)
    note = (
        f"refined after a first run at {dt:.4g} s: its measured peaks fell to 1/{ratio:.3g} of the force "
        f"scale (contact {contact}: {smallest:.4g} N), where the error model predicts {predicted:.2g} > rtol "
        f"{plan.rtol:g}; planned for rtol / {used:.3g}"
    )
    if capped:
        note += (
            f" (the step at most {MAX_REFINE_STEP:g}x finer than the first run's: peaks below 1/{used:.3g} of "
            "the scale stay outside rtol)"
        )
    elif ratio > MAX_PEAK_RATIO:
        note += f" (at most {MAX_PEAK_RATIO:g}: peaks below 1/{MAX_PEAK_RATIO:g} of the scale stay outside rtol)"
    choices = [PlanChoice(c.name, c.value, f"{c.reason}; {note}") if c.name == "timestep" else c for c in new.choices]
    return replace(new, choices=choices)


def extended_plan(scene: Scene, plan: Plan, solution) -> Plan | None:
    """The plan to run again, longer, when a run of the planner's end time ended before measuring what
    the scene asked for (postprocess.observables.unmeasured_outputs: the window's last contact without
    a leading pulse, or with its force still rising at the end, peaks.still_rising; the wall's peak
    its stop check waits for, not complete).

    The end time is an estimate; where the actual chain is slower than every estimate (a nonlinear front
    scattered by soft, light beads among stiff ones rises at a contact without a maximum until a
    reflection comes back) the run says so and runs again, once, to LINEAR_HORIZON x the slowest front's
    crossing of the whole chain (front_travel_time to its last contact), its stop check ending it as soon
    as the wave has passed the stop contact (on a wall, the window's last contact when the rerun is for
    its peak: _extended_stop). scene: the scene as given; plan: the plan the run used;
    solution: that run's ChainSolution. None when the end time was not the planner's, the number of beads
    was (chosen for that end), there is no stop check, the stop check ended the run, everything asked for
    was measured, or the budget is no longer than the end that ran.
    """
    from granchain.postprocess.observables import unmeasured_outputs

    run = plan.scene.run
    chosen = {c.name for c in plan.choices}
    # a chain of "auto" length is as long as the planned end keeps its far end's reflection out
    if "end_time" not in chosen or "beads" in chosen or run.stop_after_contact is None or not plan.scene.n_contacts:
        return None
    unmeasured = unmeasured_outputs(plan.scene, solution)
    if solution.end_time < run.end_time * (1.0 - 1e-9) or not unmeasured:
        return None
    budget = extension_budget(plan.scene, wave_speeds(scene)[0])
    if budget <= run.end_time * (1.0 + 1e-9):
        return None
    names = [line.split(":", 1)[0] for line in unmeasured]
    what = "the wall's contact" if names == ["wall_peak_force"] else "the window's last contact"
    stop = _extended_stop(plan.scene, names)
    names = ", ".join(names)
    note = (
        f"extended after a first run to {run.end_time:.4g} s ended before {what} was measured "
        f"(not measured: {names}): at most {LINEAR_HORIZON:g} x the slowest front's crossing of the whole chain "
        f"({budget:.4g} s), the stop check ending it once the wave has passed contact {stop}"
        + (" and the wall's" if run.stop_after_wall else "")
    )
    longer = replace(plan.scene, run=replace(run, end_time=budget, stop_after_contact=stop))
    choices = [PlanChoice(c.name, budget, f"{c.reason}; {note}") if c.name == "end_time" else c for c in plan.choices]
    if stop != run.stop_after_contact:
        why = (
            f"; extended: the rerun is for contact {stop}'s peak, so its stop check waits for contact {stop} "
            f"(not {run.stop_after_contact}, which the wave has passed once it has passed the wall beyond it)"
        )
        choices = [PlanChoice(c.name, stop, c.reason + why) if c.name == "stop_after_contact" else c for c in choices]
    return replace(plan, scene=longer, choices=choices)


def _extended_stop(scene: Scene, names: list[str]) -> int:
    """The stop contact of a run extended for the outputs `names` (extended_plan): the planned one, but
    the window's last contact b where the rerun is for b's peak (peak_force_contact_b: its force still
    rising at the end) and the stop check also waits for the wall: a stop at a contact beyond b ends the
    rerun as soon as the wall and that contact have passed, whatever b does (on a precompressed plastic
    chain hit by a striker, thornton_F10_striker_wall_nodp: contact 14's reflected peak, 0.988 N above
    F0 at 5.48e-4 s, had not fallen to half at the stop at 6.53e-4 s, 11 us before it did, and was
    flagged as still rising). The wall's stop keeps the rerun going until the wave has reached the wall,
    past every contact before it; without a wall the planned stop contact stays (a stop at b could end
    the rerun before the wave reaches the contacts beyond it)."""
    run = scene.run
    b = scene.window[1]
    if run.stop_after_wall and f"peak_force_contact_{b}" in names and b < run.stop_after_contact:
        return b
    return run.stop_after_contact


def accurate_timestep(method: str, omega_max: float, rate: float, rtol: float) -> float:
    """The largest dt whose predicted_error is at most rtol (each term gets half of rtol when a
    dashpot's first-order term enters: IntegratorFacts.dashpot_error)."""
    facts = integrator(method)
    c, p = facts.calibration, facts.order
    if not facts.dashpot_error or rate <= 0.0:
        return (rtol / c) ** (1.0 / p) / omega_max
    return min((rtol / 2 / c) ** (1.0 / p) / omega_max, rtol / 2 / (facts.dashpot_error * rate))


def leading_edge_speed(scene) -> float:
    """The fastest a disturbance can enter the undisturbed chain, m/s (see the module docstring)."""
    return scene.contact.law_class.leading_edge_speed(scene, expected_peak_force(scene), step_equivalent(scene))


def wave_speeds(scene) -> tuple[float, float]:
    """(slowest leading-wave speed, fastest wave speed) expected, m/s (the law's estimate)."""
    return scene.contact.law_class.wave_speeds(scene, expected_peak_force(scene), step_equivalent(scene))


#: the smallest --rtol: below it round-off, not the time step, limits every number (and the planned
#: step would fall below any a scene accepts)
MIN_RTOL = 1e-12


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
        # 1/(1 + n) of the onset F ~ alpha^n: 0.4 Hertz, 0.5 a loading line (the impact's force ~ k^(1/(1+n)))
        e = 0.5 if scene.contact.law_class.loading_is_linear() else 1.0 / (1.0 + float(scene.law.loading_exponent()))
        k = scene.contact_stiffnesses[:last]
        m = scene.bead_masses
        heavier = np.maximum(m[:-1], m[1:])[:last]
        per_contact = per_contact * (float(scene.stiffness) / k) ** e * np.sqrt(heavier / scene.mass)
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


def _timestep_choice(scene, method: str, rtol_plan: float, omega: float, stiffest: str, stable: float) -> PlanChoice:
    """The time step: the error model's for rtol_plan, within the stability limit, resolving the load."""
    k_t = max_stiffness(scene)
    facts = integrator(method)
    c, p = facts.calibration, facts.order
    rate = damping_rate(scene)
    dt_acc = accurate_timestep(method, omega, rate, rtol_plan)
    dt_new = min(dt_acc, 0.5 * stable)
    if scene.contact.law_class.loading_is_linear():  # k_u: the same at any force
        at = ""
    elif scene.effects.precompression:
        f0 = scene.effects.precompression
        at = f" at F0 + the expected peak force = {f0:g} + {expected_peak_force(scene):.4g} N"
    else:
        at = f" at the expected peak force {expected_peak_force(scene):.4g} N"
    why = (
        f"{method}: error model {c:g} (omega_max dt)^{p} <= rtol {rtol_plan:g} with omega_max = "
        f"{omega:.4g} rad/s at {stiffest} (nominal contact's tangent stiffness {k_t:.4g} N/m{at}); "
        f"stability limit {stable:.3g} s"
    )
    if facts.dashpot_error and rate > 0:
        why += f"; the dashpot's first-order error {facts.dashpot_error:g} x rate {rate:.3g} 1/s x dt ({facts.label})"
    ld = scene.loading
    if ld.is_force and ld.duration < dt_new:
        # the step plan ends a step at T exactly and f is constant within it: one step is the
        # whole pulse, integrated like any other (a 1e-10 s pulse does not force 1e-11 s steps)
        why += f"; the pulse (T = {ld.duration:.3g} s) is one step of its own"
    elif ld.is_force and ld.duration < dt_new * 4:
        dt_new = ld.duration / 4
        why += f"; resolves the load (T/4 = {dt_new:.3g} s)"
    return PlanChoice("timestep", dt_new, why)


def _one_bead_end_time(scene, impacts) -> PlanChoice:
    """A one-bead (or two free beads') scene's end time: 1.5 x its impacts' contact times, after the load."""
    load = scene.loading.duration if scene.loading.is_force else 0.0
    end = load + 1.5 * sum(i["duration"] for _, i in impacts)
    return PlanChoice(
        "end_time",
        end,
        f"{'one bead' if scene.chain.beads == 1 else 'two free beads'}: 1.5 x the contact time of "
        + " then ".join(f"the {name}'s impact ({i['duration']:.3g} s)" for name, i in impacts)
        + (f", after a load of {load:.3g} s" if load else ""),
    )


#: a maximum is seen once the force has fallen after it: within two time steps of it (the sample past the
#: maximum's own, which may fall a step after the maximum). The end time allows two of the largest stable
#: step of either integrator (IntegratorFacts.stability / omega_max), so that it does not depend on the integrator: both
#: backends of a compare end together
PEAK_DETECTION_STEPS = 2


def _front_end_time(scene, last: int | None, slow: float, omega_max: float) -> PlanChoice:
    """The end time of a chain: the slowest leading front passes the last measured contact
    (front_travel_time), after a long load; at least the pulse of an impulse and the last snapshot. A
    precompressed chain's front time is its linearised chain's first maximum (precompressed_front_time),
    which the run sees PEAK_DETECTION_STEPS time steps later (steps of either integrator up to its
    stability limit at omega_max)."""
    if last is None:
        raise SceneError(
            f'{scene.source}: end_time = "auto" needs the contacts you measure: give [outputs] '
            "window, histories or a peak_force list"
        )
    ld = scene.loading
    step = step_equivalent(scene)
    load = step[1] if step is not None and step[1] < 1e3 else 0.0
    travel = front_travel_time(scene, last, slow)
    # a long load's leading peak trails its front; a precompressed chain's front is sonic, its
    # peak forms within a few periods of it (dispersion): at most PRECOMPRESSED_TAIL of the travel
    cap, cap_text = (
        (PRECOMPRESSED_TAIL * travel, f"{PRECOMPRESSED_TAIL:g} x the travel under precompression")
        if scene.effects.precompression
        else (travel, "the travel")
    )
    tail = min(load, cap)
    end = travel + tail
    # the reason states the arithmetic that gives the end, one term at a time
    sums = [f"{travel:.3g} s to pass contact {last}"]
    if tail:
        sums.append(
            f"{tail:.3g} s for the leading peak, which trails the front under a load (the load's {load:.3g} s, "
            f"at most {cap_text})"
        )
    notes = []
    if step is not None and scene.effects.precompression and scene.has_contacts:
        sonic = precompressed_front_time(scene, last), precompressed_front_time(scene, last, step=True)
        if sonic[0] <= travel:  # the travel is the linearised chain's (the load is small against F0)
            # a lasting force's first maximum trails a kick's by more than that tail near the loaded end
            # (STEP_LAG); a pulse's comes no later than a step's, nor than the load's end after the front
            later = min(float(sonic[1]), travel + step[1])
            if later > end:
                end = later
                sums = [
                    f"{later:.3g} s for the first maximum under the load to pass contact {last} (the chain "
                    "linearised about F0; later than the front and its peak's tail)"
                ]
    if scene.effects.precompression:
        seen = PEAK_DETECTION_STEPS * max(f.stability for f in INTEGRATORS.values()) / omega_max
        end += seen
        sums.append(f"{seen:.3g} s to see it ({PEAK_DETECTION_STEPS} of the largest stable steps)")
    if ld.kind == "impulse" and end < ld.duration:
        end = ld.duration  # an impulse is measured whole: the run lasts at least the pulse
        notes.append(f"at least the pulse ({ld.duration:.3g} s)")
    if scene.outputs.snapshots and end < max(scene.outputs.snapshots):
        end = max(scene.outputs.snapshots)  # every requested snapshot is taken
        notes.append(f"at least the last snapshot ({end:.3g} s)")
    arithmetic = " + ".join(sums) + "".join(f"; {n}" for n in notes)
    return PlanChoice(
        "end_time",
        end,
        f"the leading wave (no slower than {slow:.4g} m/s on the nominal chain"
        + (", each contact's own stiffness and masses" if scene.per_bead else "")
        + (", and the first maximum of the chain linearised about F0" if scene.effects.precompression else "")
        + f") passes contact {last} by {travel:.3g} s: t_end = {arithmetic} = {end:.3g} s",
    )


#: The wall's contact (bead N on the flat) is measured once its force has fallen back to half its peak
#: after the reflection: the front's hop from contact N-1 to it and the pulse's width there. A Hertz
#: solitary wave spans about five diameters (Nesterenko), so its force at a contact rises and falls
#: within about five contacts' travel; with the hop, WALL_PULSE_CONTACTS contacts' travel at the chain's
#: far end. Measured (reference RK4, stop check on the wall's contact): a striker on a 20-bead stainless
#: chain at F0 = 2e4 N (linear, dispersed: the slowest case) complete 2.1 of its last contact's times
#: after the end planned for contact N-1; unprecompressed chains long before that end (its slowest
#: front). On 40 generated walled chains (tests/test_wall_end.py) the planned end is 1.1 to 4.4x the time
#: the stop check ended the run (1.5 to 2 typical: the slowest front's own margin)
WALL_PULSE_CONTACTS = 6


def wall_peak_planned(scene) -> bool:
    """Whether "auto" plans the run to measure the wall's peak: a chain of given length on a wall whose
    peak forces are asked for ([outputs] peak_force), with a stop check (no snapshots), under a load that
    ends: a force load within the longest end a run is ever run to (extension_budget: LINEAR_HORIZON x
    the slowest front's crossing of the whole chain), a kick, or a striker. A force load lasting longer
    is a lasting force: it keeps pressing the
    wall, whose force need not fall back before its end has crossed the chain, and an end planned to
    that (_wall_end_time: the crossing after the whole load) would outlast any run the planner makes
    (a 40 N step for 1 s on 30 brass beads: 1.001 s, 8.8e5 steps, 4.2e9 with a dashpot, for a
    budget of 2.7e-3 s). The run then ends as without a wall, the wall's peak not measured."""
    if scene.effects.far_end != "wall" or not scene.outputs.peak_force or scene.outputs.snapshots:
        return False
    if scene.chain.beads is None or scene.n_contacts < 1:
        return False
    # the reflected wave, up to F0 + twice the expected force, must stay within what the run watch lets
    # the far end's contacts carry (watched_force): on a taper's micron end beads it would crush them, a
    # force the contact law does not describe; the run then ends at contact N-1 as without a wall
    far = scene.effects.precompression + 2.0 * expected_peak_force(scene)
    r = scene.bead_radii
    held = min(
        float(watched_force(scene.contact_laws[-1], min(r[-2], r[-1]))),
        float(watched_force(scene.wall_law, r[-1])),
    )
    if far > held:
        return False
    step = step_equivalent(scene)
    if step is None:
        return True
    if scene.loading.is_force:
        return step[1] <= extension_budget(scene, wave_speeds(scene)[0])
    # a striker's push ends by itself (its momentum over the piston force, step_equivalent): a heavy one
    # pushes for several crossings and the wall's peak completes when it has turned back (generated
    # heavy strikers on walls: 3.4-5.9 crossings of push, the wall's peak complete at 2.3-3.5 ms), the
    # stop check ending the run then; the absolute cap only keeps an absurd striker from planning years
    return step[1] < 1e3


def _wall_end_time(scene, choice: PlanChoice, measured: int, slow: float, omega_max: float) -> PlanChoice:
    """The end time that also measures the wall's peak (wall_peak_planned): the end planned for the
    chain's last contact N-1 (_front_end_time), or the slowest front's crossing to it after the whole
    load (a long load's end must cross the chain before the wall's force falls), plus
    WALL_PULSE_CONTACTS x that contact's own time on the slowest front; at least the end planned for
    the measured contacts (choice, up to contact `measured`)."""
    nc = scene.n_contacts
    last = choice if measured == nc else _front_end_time(scene, nc, slow, omega_max)
    travel = front_travel_time(scene, nc, slow)
    hop = travel - (front_travel_time(scene, nc - 1, slow) if nc > 1 else 0.0)
    # a long load presses the wall until its end has crossed the chain too
    step = step_equivalent(scene)
    load = step[1] if step is not None else 0.0
    wall = max(last.value, travel + load) + WALL_PULSE_CONTACTS * hop
    if wall <= choice.value:
        return choice
    return PlanChoice(
        "end_time",
        wall,
        f"{choice.reason}; the wall's contact {nc + 1} (bead {nc + 1} on the flat) measured: the end for contact "
        f"{nc} ({last.value:.3g} s), or the load's end crossing the chain ({travel + load:.3g} s), and "
        f"{WALL_PULSE_CONTACTS} x contact {nc}'s time on that front ({hop:.3g} s), the hop to the wall and the "
        "pulse's rise and fall there",
    )


def _beads_choice(scene, end: float, last: int, fast: float) -> PlanChoice:
    """The number of beads: no reflection from bead N reaches contact `last` before the end (see the
    module docstring)."""
    lead, d = leading_edge_speed(scene), scene.diameter
    n = math.ceil(1.1 * (end + last * d / fast) / (d / lead + d / fast)) + 5
    n = max(n, last + 5)
    return PlanChoice(
        "beads",
        n,
        f"a reflection from bead N (into the chain at up to {lead:.4g} m/s, back at up to "
        f"{fast:.4g} m/s) reaches contact {last} after t_end = {end:.3g} s: "
        "N > (t_end + L D / c_back) / (D / c_lead + D / c_back), +10% and 5 beads",
    )


def reflection_planned(scene) -> bool:
    """Whether the planned run waits for the wall's reflection to pass back through contact 1 ([run]
    stop_after_reflection): an uncompressed chain of given length against a wall whose wall's peak is
    planned (wall_peak_planned), end time "auto", the stop check the planner's or one that asks for it.
    There the reflection can exceed a contact's incoming peak (peaks.reflection_pending), and a run
    that stopped once the wave had passed the wall would leave those peaks not complete."""
    run = scene.run
    own = run.stop_after_contact is None and not scene.outputs.snapshots
    return (
        run.end_time is None
        and (own or run.stop_after_reflection)
        and scene.chain.beads is not None
        and not scene.effects.precompression
        and wall_peak_planned(scene)
    )


#: the planned end's time for the wall's reflection to come back to contact 1, in crossings of the
#: chain by the slowest expected front: the reflected front is weaker (slower: speed ~ F^(1/6)) and a
#: dimer scatters it; a cap only, the stop check ends the run once the reflection has passed
REFLECTION_CROSSINGS = 2.0


def _reflection_end_time(scene, choice: PlanChoice, slow: float) -> PlanChoice:
    """The end time that also lets the wall's reflection pass back through contact 1
    (reflection_planned): the wall's end (choice) and REFLECTION_CROSSINGS x the slowest front's
    crossing of the chain."""
    back = REFLECTION_CROSSINGS * front_travel_time(scene, scene.n_contacts, slow)
    return PlanChoice(
        "end_time",
        choice.value + back,
        f"{choice.reason}; and the wall's reflection back through contact 1 (uncompressed: it can exceed a "
        f"contact's incoming peak): {REFLECTION_CROSSINGS:g} x the slowest front's crossing of the chain "
        f"({back:.3g} s), a cap: the stop check ends the run once the reflection has passed",
    )


def _stop_choice(scene, last: int) -> PlanChoice:
    """The stop check at the last measured contact, and at the wall's contact (stop_after_wall) where
    the wall's peak is measured (wall_peak_planned), and the reflection's return through contact 1
    (stop_after_reflection) where reflection_planned."""
    if reflection_planned(scene):
        return PlanChoice(
            "stop_after_contact",
            last,
            f"stop as soon as the leading wave has passed contact {last} and the wall's contact (bead "
            f"{scene.n_contacts + 1} on the flat; stop_after_wall), and the wall's reflection has passed back "
            "through contact 1 (its force after the wall's risen and back below half of its largest: "
            "stop_after_reflection), both backends: on an uncompressed chain the reflection can exceed a "
            "contact's incoming peak",
        )
    if wall_peak_planned(scene):
        return PlanChoice(
            "stop_after_contact",
            last,
            f"stop as soon as the leading wave has passed contact {last} (its force below half its peak) and the "
            f"wall's contact (bead {scene.n_contacts + 1} on the flat, its force below half its peak after the "
            "reflection: stop_after_wall), both backends: the wall's peak is asked for (peak_force)",
        )
    return PlanChoice(
        "stop_after_contact",
        last,
        f"stop as soon as the leading wave has passed contact {last} (its force below half its peak), both backends",
    )


def _output_interval_choices(scene, d: dict, omega: float, end: float, rtol_plan: float) -> list[PlanChoice]:
    """The "auto" output intervals, written into d["outputs"]: the largest sampling interval whose
    dump-derived peaks (three-point parabola, postprocess.dumps.peaks_from_samples) stay within rtol at
    the stiffest frequency: the parabola misses a cosine's peak by about (omega D)^4 / 16 (measured on
    dumps: (omega D)^4 / 100); a multiple of the time step."""
    choices = []
    o = scene.outputs
    for key in ("history_interval", "dump_interval"):
        if getattr(o, key) == AUTO:
            step = d["run"]["timestep"]
            stride = min(output_stride(omega, step, rtol_plan), max(1, int(end // step)))  # within the run
            d["outputs"][key] = stride * step
            choices.append(
                PlanChoice(
                    key,
                    stride * step,
                    f"every {stride} steps: dump-derived peaks within rtol {rtol_plan:g} "
                    f"((omega_max D)^4 / 16 <= rtol, D <= {(16.0 * rtol_plan) ** 0.25 / omega:.3g} s)",
                )
            )
    return choices


def _fitted_step(scene, choices: list[PlanChoice], dt: float, end: float) -> float:
    """The run's step: the planned (or given) step dt, shortened to fit inside the end time and any
    given output interval (a sample every interval needs a step no longer than it); where that shortens
    the planner's step its time step choice says so, with its value and the field that set it."""
    o = scene.outputs
    given = (("history_interval", o.history_interval), ("dump_interval", o.dump_interval))
    bounds = [(f"[outputs] {k} = {v:g} s", v) for k, v in given if isinstance(v, float)]
    bounds.append((f"the end time {end:.3g} s", end))
    what, step = min(bounds, key=lambda b: b[1])
    if step >= dt:
        return dt
    at = next((i for i, c in enumerate(choices) if c.name == "timestep"), None)
    if at is not None:
        c = choices[at]
        why = f"; {what} is shorter than this step {dt:.3g} s: the step is {step:.3g} s"
        if what.startswith("[outputs]"):
            why += f" ({dt / step:.3g}x the steps; {what.split(' =')[0]} >= {dt:.3g} s keeps the planned step)"
        choices[at] = PlanChoice("timestep", step, c.reason + why)
    return step


def plan_scene(scene: Scene, rtol: float | None = None, method: str = "rk4", peak_ratio: float = 1.0) -> Plan:
    """Fill "auto" values (and the time step, when rtol is given) with the reasons.

    Parameters
    ----------
    scene : Scene
        The scene as given, "auto" values allowed.
    rtol : float, optional
        The relative tolerance the time step is planned for; without it a given time step stands.
    method : str
        The integrator: a name in granchain.integrators.INTEGRATORS ("rk4" or "verlet").
    peak_ratio : float
        The run's force scale over its smallest measured peak, when a first run measured it
        (refined_plan); the time step and the output intervals are planned for rtol / peak_ratio.

    Returns
    -------
    Plan
        The concrete scene and each choice with its reason, in the order: time step, end time, beads,
        stop check, output intervals.
    """
    if rtol is not None and not (MIN_RTOL <= rtol < 1):
        raise UsageError(
            f"--rtol = {rtol!r}: a relative tolerance must be at least {MIN_RTOL:g} (round-off) and below 1"
        )
    rtol_eff = 1e-3 if rtol is None else rtol
    rtol_plan = rtol_eff / peak_ratio  # what the step must meet at the run's force scale
    choices: list[PlanChoice] = []
    omega, stiffest = highest_frequency(scene)
    stable = integrator(method).stability / omega
    dt = scene.run.timestep
    if dt is None or rtol is not None:
        choices.append(_timestep_choice(scene, method, rtol_plan, omega, stiffest, stable))
        dt = choices[-1].value
    last = last_measured_contact(scene)
    slow, fast = wave_speeds(scene)
    end = scene.run.end_time
    if end is None:
        impacts = one_bead_impacts(scene)
        if impacts:
            choices.append(_one_bead_end_time(scene, impacts))
        else:
            choices.append(_front_end_time(scene, last, slow, omega))
            # only where the stop check waits for the wall: the planner's own (below) or a given one
            # with stop_after_wall; a given stop without it ends the run before the wall's peak
            waits = scene.run.stop_after_contact is None or scene.run.stop_after_wall
            if waits and wall_peak_planned(scene):
                choices[-1] = _wall_end_time(scene, choices[-1], last, slow, omega)
            if reflection_planned(scene):
                choices[-1] = _reflection_end_time(scene, choices[-1], slow)
        end = choices[-1].value
    if scene.run.timestep is not None and rtol is None and scene.run.timestep > end:
        # the scene's own step, longer than the end the planner chose: the run would be one step of another
        # length than the scene says (scene_from_dict refuses a step above a given end_time alike)
        raise SceneError(
            f"{scene.source or '<scene>'}: [run] timestep = {scene.run.timestep:g} s is invalid: it is longer than "
            f'the whole run (end_time = "auto": {end:.3g} s); give a time step of at most the stability '
            f'limit {stable:.3g} s ({method}), or timestep = "auto"'
        )
    beads = scene.chain.beads
    if beads is None:
        if last is None:
            last = 1
        choices.append(_beads_choice(scene, end, last, fast))
        beads = choices[-1].value
    d = scene_to_dict(scene)
    d["chain"]["beads"] = beads
    # a finer step is always allowed: the step also fits inside the end time and any explicit output
    # interval (a 1e-18 s load with history_interval = 1e-7 s: the interval stands, the step is the load's)
    step = _fitted_step(scene, choices, dt, end)
    # the given stop check travels with the planned run (scene_to_dict writes every stop field)
    d["run"].update(end_time=end, timestep=step)
    stop = scene.run.stop_after_contact
    if scene.run.end_time is None and stop is None and last is not None and not scene.outputs.snapshots:
        choices.append(_stop_choice(scene, last))
        stop = last
        if wall_peak_planned(scene):
            d["run"]["stop_after_wall"] = True
        if reflection_planned(scene):
            d["run"]["stop_after_reflection"] = True
    if stop is not None:
        d["run"]["stop_after_contact"] = stop
    choices += _output_interval_choices(scene, d, omega, end, rtol_plan)
    planned = scene_from_dict(d, source=scene.source or "<scene>")
    planned = replace(planned, source=scene.source, source_text=None)
    return Plan(scene=planned, rtol=rtol_eff, method=method, choices=choices, omega_max=omega, stable_timestep=stable)
