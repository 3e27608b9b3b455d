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
Here: the error model, the time step, refinement and extension, and plan_scene; the waves' speeds
and travel times are granchain.workflows.planning.travel, the end-time and stop choices
planning.end_time (this module re-exports the names others import).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from granchain.exceptions import UsageError
from granchain.integrators import integrator
from granchain.physics.estimates import (
    damping_rate,
    expected_peak_force,
    highest_frequency,
    max_stiffness,
)
from granchain.postprocess.observables.spectral import HISTORY_SAMPLES_PER_PERIOD
from granchain.scene import AUTO, Scene, SceneError, scene_from_dict, scene_to_dict
from granchain.scene.display import html_table, key_unit, number, printable, with_unit
from granchain.schedule import output_stride
from granchain.workflows.planning.choice import (
    PlanChoice,
)
from granchain.workflows.planning.end_time import (
    PEAK_DETECTION_STEPS,
    REFLECTION_CROSSINGS,
    WALL_PULSE_CONTACTS,
    _beads_choice,
    _front_end_time,
    _one_bead_end_time,
    _reflection_end_time,
    _stop_choice,
    _wall_end_time,
    end_time_choice,
    reflection_planned,
    wall_peak_planned,
)
from granchain.workflows.planning.travel import (
    LINEAR_HORIZON,
    PRECOMPRESSED_LAG,
    PRECOMPRESSED_NEIGHBOURS,
    PRECOMPRESSED_TAIL,
    STEP_LAG,
    extension_budget,
    front_travel_time,
    last_measured_contact,
    leading_edge_speed,
    precompressed_front_time,
    sonic_travel_times,
    wave_speeds,
)

#: The error model  rel. error of peak forces ~ C (omega_max dt)^p, its constant C and order p, and the
#: omega_max dt limits of stability are each integrator's (granchain.integrators: calibration, order,
#: stability, with the measurements behind them).


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

    def __repr__(self) -> str:
        """One line: the integrator, rtol and scene, each choice with its unit, omega_max and the stable step."""
        title = printable(self.scene.title or self.scene.source or "untitled scene", 60)
        chosen = ", ".join(f"{c.name} = {with_unit(number(c.value), key_unit(c.name))}" for c in self.choices)
        return (
            f"<Plan {self.method} for rtol {self.rtol:g} of {title}: {chosen or 'nothing chosen'}; omega_max = "
            f"{self.omega_max:.4g} rad/s, stable step {self.stable_timestep:.4g} s (.choices: each with its reason)>"
        )

    def _repr_html_(self) -> str:
        """A small table for notebooks: each choice, its unit and its reason, under the integrator and rtol."""
        rows = [(c.name, number(c.value), key_unit(c.name), c.reason) for c in self.choices]
        rows += [
            ("omega_max", f"{self.omega_max:.4g}", "rad/s", ""),
            ("stable step", f"{self.stable_timestep:.4g}", "s", ""),
        ]
        caption = f"granchain Plan: {self.method} for rtol {self.rtol:g}, {self.scene.title or self.scene.source or ''}"
        return html_table(rows, caption, ("choice", "value", "unit", "reason"))


def predicted_error(method: str, omega_max: float, rate: float, dt: float) -> float:
    """The planner's error model for the relative error of peak forces at a time step dt: C (omega_max
    dt)^p, plus D x rate x dt for an integrator whose velocity-dependent damping force is first-order accurate
    (velocity Verlet and LAMMPS evaluate it with the half-step velocities; IntegratorFacts.damping_error)."""
    facts = integrator(method)
    err = facts.calibration * (omega_max * dt) ** facts.order
    if facts.damping_error:
        err += facts.damping_error * rate * dt
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
    if scene.loading.is_harmonic:  # a drive's wave train has no leading pulse (observables.base.HARMONIC_DRIVE)
        lead = np.zeros(0)
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
    names = [line.split(":", 1)[0] for line in unmeasured]
    budget = extension_budget(plan.scene, wave_speeds(scene)[0])
    horizon = f"{LINEAR_HORIZON:g} x the slowest front's crossing of the whole chain"
    if _event_unended(plan.scene, names):  # its planned end is a cap of its own, far past that horizon
        budget, horizon = EVENT_EXTENSION * run.end_time, f"{EVENT_EXTENSION:g} x the planned end"
    if budget <= run.end_time * (1.0 + 1e-9):
        return None
    what = "the wall's contact" if names == ["wall_peak_force"] else "the window's last contact"
    what = "the wall's event ended" if _event_unended(plan.scene, names) else f"{what} was measured"
    stop = _extended_stop(plan.scene, names)
    names = ", ".join(names)
    note = (
        f"extended after a first run to {run.end_time:.4g} s ended before {what} "
        f"(not measured: {names}): at most {horizon} ({budget:.4g} s), the stop check ending it once the wave has "
        f"passed contact {stop}" + (" and the wall's" if run.stop_after_wall else "")
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


#: a planned run that ended inside the wall's event (its end a cap: the push and EVENT_CROSSINGS
#: crossings) runs again to this many times its end, the stop check ending it at the event's end (so
#: the rerun costs the event's length, not the cap, wherever the event ends). Measured: a striker of 8
#: beads' mass at 0.3 m/s on 8 stainless beads tapered by 0.93 to a rigid wall, planned to 1.626e-3 s:
#: the chain was proved gone for good at 1.855e-3 s (1.14x); on a PTFE wall, stainless chains of 7-8
#: beads tapered by 0.80-0.97 struck at 0.3 m/s by 0.1-2 g: events ended at 2.6x, 3.4x and 7.9x the
#: planned end (LAMMPS, end time 30x given), so the first cap of 3x left two of three unmeasured
EVENT_EXTENSION = 10.0


def _event_unended(scene: Scene, names: list[str]) -> bool:
    """Whether the unmeasured outputs `names` include the wall's event quantities of a run planned to
    the event's end (planning.end_time.event_planned)."""
    from granchain.postprocess.observables import OBSERVABLES
    from granchain.workflows.planning.end_time import event_planned

    return event_planned(scene) and any(n in OBSERVABLES and "event" in OBSERVABLES[n].needs for n in names)


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
    damping force's first-order term enters: IntegratorFacts.damping_error)."""
    facts = integrator(method)
    c, p = facts.calibration, facts.order
    if not facts.damping_error or rate <= 0.0:
        return (rtol / c) ** (1.0 / p) / omega_max
    return min((rtol / 2 / c) ** (1.0 / p) / omega_max, rtol / 2 / (facts.damping_error * rate))


#: the smallest --rtol: below it round-off, not the time step, limits every number (and the planned
#: step would fall below any a scene accepts)
MIN_RTOL = 1e-12


def _timestep_choice(scene, method: str, rtol_plan: float, omega: float, stiffest: str, stable: float) -> PlanChoice:
    """The time step: the error model's for rtol_plan, within the stability limit, resolving the load."""
    k_t = max_stiffness(scene)
    facts = integrator(method)
    c, p = facts.calibration, facts.order
    rate = damping_rate(scene)
    dt_acc = accurate_timestep(method, omega, rate, rtol_plan)
    dt_new = min(dt_acc, 0.5 * stable)
    if scene.contact.law_class.constant_tangent:  # (the bilinear law's k_u)
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
    if facts.damping_error and rate > 0:
        why += (
            f"; the {scene.damping.noun}'s first-order error {facts.damping_error:g} x rate {rate:.3g} 1/s x dt "
            f"({facts.label})"
        )
    ld = scene.loading
    if ld.is_force and ld.duration < dt_new:
        # the step plan ends a step at T exactly and f is constant within it: one step is the
        # whole pulse, integrated like any other (a 1e-10 s pulse does not force 1e-11 s steps)
        why += f"; the pulse (T = {ld.duration:.3g} s) is one step of its own"
    elif ld.is_force and ld.duration < dt_new * 4:
        dt_new = ld.duration / 4
        why += f"; resolves the load (T/4 = {dt_new:.3g} s)"
    return PlanChoice("timestep", dt_new, why)


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
            why = (
                f"every {stride} steps: dump-derived peaks within rtol {rtol_plan:g} "
                f"((omega_max D)^4 / 16 <= rtol, D <= {(16.0 * rtol_plan) ** 0.25 / omega:.3g} s)"
            )
            drive = _drive_stride(scene, step)
            if key == "history_interval" and drive is not None and drive < stride:
                stride = drive
                why = (
                    f"every {stride} steps: at least {HISTORY_SAMPLES_PER_PERIOD} samples a period of the "
                    f"{scene.loading.frequency:g} Hz drive, for its lock-in (observables.spectral)"
                )
            d["outputs"][key] = stride * step
            choices.append(PlanChoice(key, stride * step, why))
    return choices


def _drive_stride(scene, step: float) -> int | None:
    """The most steps between history samples that keep HISTORY_SAMPLES_PER_PERIOD samples in a period
    of a harmonic drive (None: no drive)."""
    if not scene.loading.is_harmonic:
        return None
    return max(1, int(1.0 / (HISTORY_SAMPLES_PER_PERIOD * scene.loading.frequency * step)))


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
        choices.append(end_time_choice(scene, last, slow, omega))
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
    drive = scene.loading.is_harmonic  # a drive's forces rise and fall for its whole length: no stop check
    if scene.run.end_time is None and stop is None and last is not None and not scene.outputs.snapshots and not drive:
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


#: the planner's names, its parts' among them (granchain.workflows.planning), as other modules import them
__all__ = [
    "end_time_choice",
    "LINEAR_HORIZON",
    "MAX_PEAK_RATIO",
    "MAX_REFINE_STEP",
    "MIN_RTOL",
    "PEAK_DETECTION_STEPS",
    "PRECOMPRESSED_LAG",
    "PRECOMPRESSED_NEIGHBOURS",
    "PRECOMPRESSED_TAIL",
    "Plan",
    "PlanChoice",
    "REFINE_ABOVE",
    "REFLECTION_CROSSINGS",
    "STEP_LAG",
    "WALL_PULSE_CONTACTS",
    "_beads_choice",
    "_front_end_time",
    "_one_bead_end_time",
    "_reflection_end_time",
    "_stop_choice",
    "_wall_end_time",
    "accurate_timestep",
    "damping_rate",
    "extended_plan",
    "extension_budget",
    "front_travel_time",
    "highest_frequency",
    "last_measured_contact",
    "leading_edge_speed",
    "peak_ratio",
    "plan_scene",
    "precompressed_front_time",
    "predicted_error",
    "refined_plan",
    "reflection_planned",
    "sonic_travel_times",
    "wall_peak_planned",
    "wave_speeds",
]
