"""The error bars of every number of a run from its companions' solutions.

Richardson's family (extrapolated_bars: Richardson's estimates, the bounds of the kinked laws, one
companion's bounds; each checked against a run at dt / 2 where one was made) and the distance to RK4
runs (against_rk4_bars), for the contacts' peaks and leading pulses, the effects' own contacts
(end_peaks) and the scalar observables, and the largest relative error over the measured contacts.
"""

from __future__ import annotations

import functools

import numpy as np

from granchain.postprocess.observables import END_PEAKS as _END_OBSERVABLES
from granchain.postprocess.observables import OBSERVABLES, measure, with_error_bars
from granchain.postprocess.sensors import sensor_key, sensor_static_forces
from granchain.problem import scene_static_forces
from granchain.richardson import ErrorBars, against_reference, checked
from granchain.workflows.errorbars.facts import expected_orders, onset_order, reference_order
from granchain.workflows.errorbars.observables import (
    _observable_error,
    _observable_floor,
    _withheld_step_bound,
    roundoff_floor,
)
from granchain.workflows.errorbars.onset import hidden_onset, unseen, withhold_hidden
from granchain.workflows.errorbars.report import ErrorReport


def measured_contacts(scene, solution) -> np.ndarray:
    """0-based contacts whose peaks are measured outputs: complete, up to the last measured contact."""
    from granchain.workflows.plan import last_measured_contact

    last = last_measured_contact(scene) or len(solution.peak_force)
    c = np.asarray(solution.complete, dtype=bool)[:last]
    return np.flatnonzero(c)


def per_contact(solutions, name: str, n: int, complete_only: bool = False) -> list:
    """One per-contact quantity (the first n contacts) of each solution (None stays None: no such
    companion); complete_only: nan where that run's peak is not complete."""
    out = []
    for s in solutions:
        if s is None:
            out.append(None)
            continue
        v = np.asarray(getattr(s, name), dtype=float)[:n].copy()
        if complete_only:
            v[~np.asarray(s.complete, dtype=bool)[:n]] = np.nan
        out.append(v)
    return out


def extrapolated_bars(
    report: ErrorReport, result, runs: list, method: str, extrapolate, finer=None, absolute_positions: bool = False
) -> None:
    """The error bars of every number of the run from its companions by the strategy's extrapolate
    (richardson.richardson, erratic_bounds, or one companion's bounds: ErrorBarStrategy.extrapolate),
    checked against the run at dt / 2 where there is one (richardson.checked); absolute_positions:
    the backend's (roundoff_floor)."""
    scene, sol = result.scene, result.solution
    p = report.order
    coarse = runs[0]
    coarser = runs[1] if len(runs) > 1 else None
    from granchain.workflows.plan import highest_frequency

    jump = np.pi / highest_frequency(scene)[0]  # half the shortest period of the chain
    n = len(sol.peak_force)

    def values(name: str, complete_only: bool = False) -> list:
        return per_contact((sol, coarse, coarser, finer), name, n, complete_only)

    orders = expected_orders(method, scene)

    def bars(v, t, order=p, floor=None, span=orders) -> ErrorBars:
        # Richardson over dt, 2 dt, 4 dt; checked against dt / 2 where that run was made
        b = extrapolate(*v[:3], order, times=tuple(t[:3]), jump_time=jump, orders=span, floor=floor)
        if finer is None:
            return b
        return checked(b, v[3], v[0], v[1], order, times=(t[3], t[0], t[1]), jump_time=jump, orders=span, floor=floor)

    pf, tp = values("peak_force", True), values("time_of_peak", True)
    lf, lt = values("leading_pulse_force"), values("leading_pulse_time")
    floor = roundoff_floor(scene, sol, absolute_positions)
    report.peak_force = bars(pf, tp, floor=floor)
    report.time_of_peak = bars(tp, tp)
    # a leading pulse rises no higher than its contact's peak, and a contact's slope grows with its
    # force (Hertz; constant on a loading line): the peak's floor bounds the leading pulse's round-off
    report.leading_pulse_force = bars(lf, lt, floor=floor)
    report.arrival_time = bars(lt, lt)
    # the struck contact's onset term, which the runs at dt, 2 dt and 4 dt can miss (errorbars.onset)
    hidden = hidden_onset(scene)
    if unseen(report.peak_force, pf[0], hidden):
        withhold_hidden(report.peak_force, pf[0], hidden)
        withhold_hidden(report.leading_pulse_force, lf[0], hidden)

    _largest(report, scene, sol)

    # a striker's or a wall's contact is one impact from zero overlap: an integrator's error there is its
    # onset's, order 1 + n (Hertz: 1 + 3/2), where its own is higher (RK4, two spheres, planned step: with
    # order 4 the bar was 1/2.9 of the true error); not where the law says its closing does not limit it (a
    # loading line: ContactLaw.closing_limits_order), nor for one companion's bounds
    onset = report.one_companion is None and scene.contact.law_class.closing_limits_order
    p_end = onset_order(scene) if onset and onset_order(scene) < p else p

    def bars_of(values, times):
        values, times = list(values), None if times is None else list(times)
        if finer is not None:  # the run at dt / 2 comes last (below)
            h, th = float(values.pop()), None if times is None else float(times.pop())
        v = [float(x) for x in values] + ([None] if coarser is None else [])
        t = None if times is None else tuple([float(x)] for x in times) + ((None,) if coarser is None else ())
        c = None if v[2] is None else [v[2]]
        b = extrapolate([v[0]], [v[1]], c, p_end, times=t, jump_time=jump, orders=orders)
        if finer is None:
            return b
        t = None if times is None else ([th], [float(times[0])], [float(times[1])])
        return checked(b, [h], [v[0]], [v[1]], p_end, times=t, jump_time=jump, orders=orders)

    report.end_peaks = _end_peaks((sol, *runs) + (() if finer is None else (finer,)), bars_of)
    # the sensor beads' peaks by the contacts' own route (their order and check at dt / 2); a sensor's time
    # is the vertex of the parabola through step-end samples, an error of order 2 in dt whatever the
    # integrator's (RK4 with order 4 gave bars 0.1-0.23 of the true error on effect-sensors)
    span = None if orders is None else (min(2.0, orders[0]), orders[1])
    sensor_times = (lambda v, t: bars(v, t, order=min(p, 2), span=span)) if p > 2 else bars
    report.end_peaks.update(_sensor_bars(scene, (sol, coarse, coarser, finer), bars, sensor_times))
    _observable_bars(report, scene, (sol, coarse, coarser, finer), extrapolate, (p, jump, orders), floor)


def _observable_bars(report: ErrorReport, scene, sols: tuple, extrapolate, rule: tuple, floor) -> None:
    """The scalar observables' bars (those registered with one: with_error_bars) for extrapolated_bars:
    measured on each of sols = (the run, 2 dt, 4 dt or None, dt / 2 or None), extrapolated with the run's rule (order,
    jump_time, orders) and checked against dt / 2 where that run was made."""
    sol, coarse, coarser, finer = sols
    p, jump, orders = rule
    run = measure(scene, sol)  # why the run itself lacks a value: that, not its companions', is said
    missing = run.missing
    obs = [run.values] + [measure(scene, s).values for s in (coarse,) + ((coarser,) if coarser is not None else ())]
    obs_h = None if finer is None else measure(scene, finer).values
    b = max(scene.window[1] - 1, 0)
    for name in with_error_bars():
        vals = [o.get(name) for o in obs]
        v = [np.nan if x is None else float(x) for x in vals] + ([None] if coarser is None else [])
        times = None
        if OBSERVABLES[name].at_leading_pulse and scene.n_contacts:  # the same pulse in every run
            times = tuple(None if s is None else float(s.leading_pulse_time[b]) for s in (sol, coarse, coarser))
        # max_peak_force: the largest over contacts is continuous in the runs even where its contact
        # changes (a steady wave peaks alike everywhere), so no pulse check; wave_speed: a fit
        fl = _observable_floor(name, obs[0], floor, b)
        bars = extrapolate(
            [v[0]], [v[1]], None if v[2] is None else [v[2]], p, times=times, jump_time=jump, orders=orders, floor=fl
        )
        if obs_h is not None:
            h = obs_h.get(name)
            th = None
            if times is not None:
                th = float(finer.leading_pulse_time[b])
                times = ([th], [times[0]], [times[1]])
            bars = checked(
                bars,
                [np.nan if h is None else float(h)],
                [v[0]],
                [v[1]],
                p,
                times=times,
                jump_time=jump,
                orders=orders,
                floor=fl,
            )
        bound = None
        if obs_h is not None:
            bound = _withheld_step_bound(obs_h.get(name), v[0], v[1], float(p if orders is None else orders[0]))
        report.observables[name] = _observable_error(name, vals[0], bars, obs[0], bound)
        if vals[0] is None and name in missing:
            report.observables[name]["status"] = f"not measured: {missing[name]}"


def against_rk4_bars(report: ErrorReport, result, runs: list) -> None:
    """A Verlet run's error bars against RK4 runs at 2 dt and 4 dt, or dt and 2 dt, into the report
    (richardson.against_reference; the runs: rk4_runs)."""
    from granchain.workflows.plan import highest_frequency

    scene, sol = result.scene, result.solution
    # the references' own error at their onset's order, 1 + n of the scene's law (reference_order)
    against = functools.partial(
        against_reference, jump_time=np.pi / highest_frequency(scene)[0], order=reference_order(scene)
    )
    n = len(sol.peak_force)

    def values(name: str, complete_only: bool = False) -> list:
        return per_contact((sol, *runs), name, n, complete_only)

    pf, tp = values("peak_force", True), values("time_of_peak", True)
    lf, lt = values("leading_pulse_force"), values("leading_pulse_time")
    report.peak_force = against(*pf, times=(tp[0], tp[1]))
    report.time_of_peak = against(*tp, times=(tp[0], tp[1]))
    report.leading_pulse_force = against(*lf, times=(lt[0], lt[1]))
    report.arrival_time = against(*lt, times=(lt[0], lt[1]))
    _largest(report, scene, sol)

    def bars_of(values, times):
        v = [float(x) for x in values]
        t = None if times is None else ([float(times[0])], [float(times[1])])
        return against([v[0]], [v[1]], [v[2]], times=t)

    report.end_peaks = _end_peaks((sol, *runs), bars_of)
    report.end_peaks.update(_sensor_bars(scene, (sol, *runs), lambda v, t: against(*v, times=(t[0], t[1]))))
    obs = [measure(scene, s).values for s in (sol, *runs)]
    b = max(scene.window[1] - 1, 0)
    for name in with_error_bars():
        vals = [o.get(name) for o in obs]
        v = [np.nan if x is None else float(x) for x in vals]
        times = None
        if OBSERVABLES[name].at_leading_pulse and scene.n_contacts:  # the same pulse in every run
            times = tuple([float(s.leading_pulse_time[b])] for s in (sol, runs[0]))
        bars = against([v[0]], [v[1]], [v[2]], times=times)
        report.observables[name] = _observable_error(name, vals[0], bars, obs[0])


#: the effects' own contacts that get error bars: peak force -> its time (ChainSolution fields)
END_PEAKS = {name: obs.time_field for name, obs in _END_OBSERVABLES.items()}
#: why an end peak has no bar: the run's own peak, or a companion's, had not passed when it ended
END_PEAK_INCOMPLETE = (
    "incomplete: the wave had not reached it, or its force had not fallen to half its peak, when the run ended"
)
END_PEAK_COMPANION_INCOMPLETE = "not measured: incomplete in a companion run"


def _end_peaks(solutions, bars_of) -> dict[str, dict]:
    """Error bars of the striker's and the wall's peak forces and times from the run and its
    companions (bars_of(values, times) -> ErrorBars of one number, the estimator of the report)."""
    out: dict[str, dict] = {}
    for force, when in END_PEAKS.items():
        vals = [getattr(s, force) for s in solutions]
        if vals[0] is None or any(v is None for v in vals):
            continue
        times = [getattr(s, when) for s in solutions]
        # a running maximum is not a peak (ChainSolution.wall_peak_complete); None: not tracked
        done = [getattr(s, _END_OBSERVABLES[force].complete_field) is not False for s in solutions]
        if not all(done):
            why = END_PEAK_INCOMPLETE if not done[0] else END_PEAK_COMPANION_INCOMPLETE
            for name, values in ((force, vals), (when, times)):
                out[name] = {"value": float(values[0]), "error": None, "status": why}
            continue
        for name, values, at in ((force, vals, times), (when, times, None)):
            bars = bars_of(values, at)
            err = float(bars.error[0])
            out[name] = {
                "value": float(values[0]),
                "error": err if np.isfinite(err) else None,
                "status": str(bars.status[0]),
            }
    return out


def _sensor_bars(scene, solutions, bars, time_bars=None) -> dict[str, dict]:
    """Error bars of each sensor bead's dynamic peak and its time (postprocess.sensors), from the run
    and its companions (solutions: None where a companion was not made) by the contacts' estimator
    (bars(values, times) -> ErrorBars over the sensors; a value nan where that run's peak is not
    complete; time_bars the times', default bars), keyed as sensor_key names them."""
    if not scene.outputs.sensors or not np.size(solutions[0].sensor_peak_force):
        return {}
    static = sensor_static_forces(scene)

    def values(name: str) -> list:
        out = []
        for s in solutions:
            v = None if s is None else np.asarray(getattr(s, name), dtype=float).copy()
            if v is not None:
                v[~np.asarray(s.sensor_complete, dtype=bool)] = np.nan
            out.append(v)
        return out

    force, time = values("sensor_peak_force"), values("sensor_time_of_peak")
    force = [None if v is None else v - static for v in force]
    out: dict[str, dict] = {}
    timed = (time_bars or bars)(time, time)
    for quantity, b in (("sensor_peak_force", bars(force, time)), ("sensor_time_of_peak", timed)):
        for k, bead in enumerate(scene.outputs.sensors):
            own = (force if quantity == "sensor_peak_force" else time)[0][k]
            if not np.isfinite(own):  # the run's own peak is not complete: unmeasured (summary.json says why)
                continue
            err = float(b.error[k])
            out[sensor_key(quantity, bead)] = {
                "value": float(own),
                "error": err if np.isfinite(err) else None,
                "status": str(b.status[k]),
            }
    return out


def _largest(report: ErrorReport, scene, sol) -> None:
    """The largest relative peak-force error over the measured contacts, and the contacts without one."""
    n = len(sol.peak_force)
    measured = measured_contacts(scene, sol)
    rel = np.full(n, np.nan)
    # relative to the wave's force: above the static force a contact carries at rest (F0, and under
    # gravity the weight above it)
    dynamic = np.abs(np.asarray(sol.peak_force, dtype=float) - scene_static_forces(scene)[:n])
    ok = report.peak_force.reliable & (dynamic > 0)
    rel[ok] = report.peak_force.error[ok] / dynamic[ok]
    m = measured[np.isfinite(rel[measured])]
    if m.size:
        i = int(m[np.argmax(rel[m])])
        report.error_estimate, report.error_estimate_contact = float(rel[i]), i + 1
    report.unreliable_contacts = [int(i) + 1 for i in measured if not np.isfinite(rel[i])]
