"""The event at the far-end wall ([outputs] event = true): what it is, and what both backends sum
over it at every step.

A load (a striker, a kick, a pulse) sends the chain into the wall; the wall takes its force, and the
impact is over once the chain has left the wall for good. Definitions (docs/observables.md):

* F_w(t): the wall's contact force (bead N on the flat), F_s its static force (precompression's F0
  plus, under gravity, the chain's weight; 0 otherwise); v_N bead N's velocity (towards the wall
  positive); P the momentum of every moving body (the beads and a striker).
* The event has begun once the wall's force has risen above its static force by the floor (the stop
  check's: REACHED_FRACTION of the largest expected force, under precompression the leading
  pulse's floor): round-off ahead of the wave is no event.
* It ends once the chain has left the wall for good:
  - an unloaded chain (no precompression, no gravity), at the first check (every STOP_CHECK_EVERY
    steps, as the stop check) after the load at which the wall's contact is open and it is proved
    from the state that no body touches the wall again (left_for_good): a group of bodies holds
    every closed contact, the bodies before it fly free and away from it and the bodies after it
    fly free towards nothing (sorted velocities, open contacts, the last <= 0), and the group's
    internal energy (kinetic less its centre of mass's, plus all stored energy) keeps its end
    bodies from ever catching them or the wall (a body of a group moves relative to its centre of
    mass at most as fast as the group's energy allows; no external force acts, the contacts only
    store or dissipate energy). A heavy striker's second push, a rebound, a taper's light end bead
    pushed back onto the wall are inside the event (every body merely moving away from the wall
    was not enough: on a 6-bead taper the beads behind pushed the last one back onto it with
    12.7 N);
  - a chain held on the wall (precompression's F0 or gravity press it there for ever), tested after
    every step: once the wall's dynamic force has returned to its static value, F_w - F_s crossing
    0 in the step, and the chain moves away from it, v_N <= 0 and P <= 0 (the momentum of every
    moving body: the wall only pushes, so the momentum still towards it must reach it first). The
    end is the crossing, interpolated in the step, and the sums end there (a total impulse under a
    static force grows with the end: a check's spacing would have been its error). That is the
    wave's first return from the wall; its later returns (the held end reflects it back) are
    further events, not counted.
* Over [0, t_end], at every step (trapezoids over the step's two end samples):
  - wall_max_force: the largest F_w - F_s, the running maximum of the samples refined by the
    vertex of the parabola through three samples around a local maximum (as the contacts' peaks);
  - wall_impulse: the integral of F_w dt, the momentum the wall takes (total: with the static force);
  - wall_dynamic_impulse: the integral of (F_w - F_s) dt, the impulse of the impact alone;
  - wall_energy: the integral of (F_w - F_s) max(v_N, 0) dt, the work bead N does pressing into the
    wall's contact: the energy that reaches the far end (stored in the wall's contact, dissipated
    there, or, on a wall of a material, taken into it). A rigid wall does no work (it does not
    move): the energy reaching it is what its contact takes in, counted on every compression and
    not given back by the unloading (v_N < 0).
After the end the sums freeze: a run that goes on (a given end time) reports the event's.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: the ChainSolution fields of the event (None where no event was tracked)
EVENT_FIELDS = (
    "event_end_time",
    "wall_max_force",
    "wall_time_of_max",
    "wall_impulse",
    "wall_dynamic_impulse",
    "wall_energy",
)


class EventSums:
    """The event's running sums and its end (the reference's EventTracker feeds it; the LAMMPS
    plugin's fix chain/event is the same arithmetic in C++, in the same order)."""

    def __init__(self, static: float, floor: float, f_start: float, v_start: float) -> None:
        self.static, self.floor = static, floor
        self.t = [-math.inf, -math.inf, 0.0]  # the last three sample times, oldest first
        self.f = [0.0, 0.0, f_start]  # ... and the wall's force at them
        self.g = (f_start - static) * max(v_start, 0.0)  # the power into the wall's contact now
        self.fmax, self.tmax = f_start, 0.0
        self.impulse = self.dynamic = self.energy = 0.0
        self.ended = False
        self.end_time: float | None = None

    def add(self, t: float, f: float, v: float) -> None:
        """A new sample at time t: the wall's force f and bead N's velocity v after the step."""
        s = self.static
        h = t - self.t[2]
        fp = self.f[2]
        self.impulse += 0.5 * h * (fp + f)
        self.dynamic += 0.5 * h * ((fp - s) + (f - s))
        g = (f - s) * max(v, 0.0)
        self.energy += 0.5 * h * (self.g + g)
        self.g = g
        self.t = [self.t[1], self.t[2], t]
        self.f = [self.f[1], fp, f]
        if f > self.fmax:
            self.fmax, self.tmax = f, t
        f2, f1 = self.f[0], self.f[1]
        if math.isfinite(self.t[0]) and f1 > f and f1 >= f2 and f1 > 0.0:
            self.refine()

    def refine(self) -> None:
        """The middle sample is a local maximum: the vertex of the parabola through the three where
        that opens downwards (peaks' rule, pair_chain.h's track_one)."""
        t1 = self.t[1]
        a, b = self.t[0] - t1, self.t[2] - t1
        det = a * b * (b - a)
        fa, fb = self.f[0] - self.f[1], self.f[2] - self.f[1]
        c1 = (fa * b * b - fb * a * a) / det
        c2 = (a * fb - b * fa) / det
        if c2 < 0.0:
            sv = min(max(-c1 / (2.0 * c2), a), b)
            val = self.f[1] + (c1 + c2 * sv) * sv
            if val > self.fmax:
                self.fmax, self.tmax = val, t1 + sv

    def check(self, t: float, free: bool) -> None:
        """An unloaded chain's end at a check (t: now; free: whether it has left the wall for good)."""
        if self.fmax - self.static > self.floor and free:
            self.ended, self.end_time = True, t

    def cross(self, v: float, momentum) -> None:
        """A held chain's end, tested after every step: the wall's dynamic force crossed its static value
        in this step with bead N (v) and the chain (momentum(): every moving body's) moving away. The end
        is the crossing, interpolated linearly in the step, and the step's trapezoids lose their part
        after it: the sums converge with the step, not with the stop check's spacing."""
        s, (t0, t1), (f0, f1) = self.static, self.t[1:], self.f[1:]
        if not (self.fmax - s > self.floor and f0 - s > 0.0 and f1 - s <= 0.0 and v <= 0.0):
            return
        if momentum() > 0.0:
            return
        tc = t0 + (t1 - t0) * ((f0 - s) / (f0 - f1))
        after = t1 - tc  # the force runs linearly from s at tc to f1 at t1
        self.impulse -= 0.5 * after * (s + f1)
        self.dynamic -= 0.5 * after * (f1 - s)
        self.energy -= 0.5 * after * self.g  # the power is 0 at the crossing
        self.ended, self.end_time = True, tc

    def fields(self) -> dict[str, Any]:
        """The solution's event fields (EVENT_FIELDS): the sums so far, and the end (None: not ended)."""
        return {
            "event_end_time": self.end_time,
            "wall_max_force": self.fmax - self.static,
            "wall_time_of_max": self.tmax,
            "wall_impulse": self.impulse,
            "wall_dynamic_impulse": self.dynamic,
            "wall_energy": self.energy,
        }


#: the ChainSolution fields of the chosen contacts' and sensor beads' largest force over the event
#: ([outputs] event_max_contacts, event_max_sensors; EventMaxima): the total force's maximum (N) and
#: its time (s), one per chosen contact or sensor in the scene's order (empty where none was chosen)
EVENT_MAXIMA_FIELDS = (
    "event_contact_max_force",
    "event_contact_time_of_max",
    "event_sensor_max_force",
    "event_sensor_time_of_max",
)


class EventMaxima:
    """The running maximum of chosen forces over the event ([outputs] event_max_contacts: contact
    forces; event_max_sensors: sensor beads' average forces), as EventSums keeps the wall's: every
    step's sample, and the vertex of the parabola through three samples around a local maximum where
    it opens downwards. Fed the same steps as the event's sums, until the event ends (fix chain/event
    does the same per tracked atom, in the same order)."""

    def __init__(self, f_start: np.ndarray) -> None:
        f = np.asarray(f_start, dtype=float)
        self.t = [-math.inf, -math.inf, 0.0]
        self.f = [np.zeros_like(f), np.zeros_like(f), f.copy()]
        self.fmax, self.tmax = f.copy(), np.zeros_like(f)

    def add(self, t: float, f: np.ndarray) -> None:
        """A new sample of every tracked force at time t (after the step)."""
        f = np.asarray(f, dtype=float)
        self.t = [self.t[1], self.t[2], t]
        self.f = [self.f[1], self.f[2], f.copy()]
        up = f > self.fmax
        self.fmax[up], self.tmax[up] = f[up], t
        f2, f1 = self.f[0], self.f[1]
        if not math.isfinite(self.t[0]):
            return
        peak = (f1 > f) & (f1 >= f2) & (f1 > 0.0)
        if not peak.any():
            return
        t1 = self.t[1]
        a, b = self.t[0] - t1, t - t1
        det = a * b * (b - a)
        fa, fb = f2 - f1, f - f1
        c1 = (fa * b * b - fb * a * a) / det
        c2 = (a * fb - b * fa) / det
        with np.errstate(divide="ignore", invalid="ignore"):
            sv = np.minimum(np.maximum(-c1 / (2.0 * c2), a), b)
            val = f1 + (c1 + c2 * sv) * sv
        better = peak & (c2 < 0.0) & (val > self.fmax)
        self.fmax[better], self.tmax[better] = val[better], t1 + sv[better]


def maxima_summary(solution) -> dict[str, list]:
    """summary.json's ``event_maxima`` (EVENT_MAXIMA_FIELDS as lists; {} where none was tracked)."""
    out = {k: [float(x) for x in getattr(solution, k)] for k in EVENT_MAXIMA_FIELDS}
    return out if any(out.values()) else {}


def left_for_good(v: np.ndarray, m: np.ndarray, f: np.ndarray, stored: float) -> bool:
    """Whether an unloaded chain whose load is over will never touch the wall again (the module's rule).

    Parameters
    ----------
    v, m : ndarray
        Every moving body's velocity (towards the wall positive, m/s) and mass (kg), in chain order
        (a striker first, bead N last; the wall left out).
    f : ndarray
        Every contact's force (N), contact i between body i and body i + 1, the last the wall's.
    stored : float
        The energy stored in every contact (J).

    Returns
    -------
    bool
        Some group of bodies k .. j - 1 holds every closed contact, the bodies before it fly free
        away from it (open contacts, v_0 <= ... <= v_(k-1), v_(k-1) at most the slowest its first body
        can ever move, V_g - sqrt(2 E_g / m_k)) and the bodies after it fly free towards nothing
        (open contacts, v_j <= ... <= v_N <= 0, v_j at least the fastest its last body can ever move,
        V_g + sqrt(2 E_g / m_(j-1))); j = N + 1: the group ends at bead N, and that fastest is at
        most 0 (the wall at rest). E_g: the group's internal energy, kinetic less P_g^2 / 2 M_g plus
        the chain's stored energy (all of it in the group). Bodies of a group move no faster relative
        to its centre of mass than its energy allows, so no gap outside it closes, and none reaches
        the wall.
    """
    n = v.size
    if f[-1] > 0.0:  # (the same test in C++: lammps/fix_chain_event.cpp's left_for_good)
        return False
    ahead = np.append(v[1:], 0.0)  # the wall at rest after bead N
    free = (f <= 0.0) & (v <= ahead)  # body i flies away from body i + 1 (or the wall), its contact open
    if free.all():
        return True
    tail = np.append(np.logical_and.accumulate(free[::-1])[::-1], True)  # bodies j .. N all free
    left = np.concatenate(([True], np.logical_and.accumulate(free)))  # bodies 0 .. k - 1 all free
    cp = np.concatenate(([0.0], np.cumsum(m * v)))
    cm = np.concatenate(([0.0], np.cumsum(m)))
    ck = np.concatenate(([0.0], np.cumsum(0.5 * m * v * v)))
    vend = np.append(v, 0.0)
    for j in range(1, n + 1):
        if not tail[j] or f[j - 1] > 0.0:
            continue
        lefts = np.flatnonzero(left[:j])
        for k in {0, int(lefts[-1])}:
            pg, mg = cp[j] - cp[k], cm[j] - cm[k]
            vg = pg / mg
            e = max(ck[j] - ck[k] + stored - 0.5 * pg * vg, 0.0)
            if vg + math.sqrt(2.0 * e / m[j - 1]) <= vend[j] and (k == 0 or v[k - 1] <= vg - math.sqrt(2.0 * e / m[k])):
                return True
    return False
