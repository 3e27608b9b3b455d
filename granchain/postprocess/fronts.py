"""Fronts: a contact's half-amplitude arrival from its crossing-time ladder; the loading and unloading
fronts of a bilinear chain under a long step load (Sec. III B, Table I).

The crossing-time ladder (both backends, in the run: the pair styles' d2_ladder, the reference's
observers.CrossingLadder): rung k is the force level F0 + lead_floor * 2^(k / LADDER_PER_OCTAVE) above
the static force; each contact records the time its force rose through each rung, interpolated
inside the step (Verlet and LAMMPS: on the line between the two force samples; RK4: on the step's
Hermite interpolant of the overlap), until its leading pulse (peaks.leading_pulse) is frozen, and
keeps the last LADDER_SLOTS of them. Each rung is counted once, when the force first rises through it;
before the leading pulse freezes the force falls back below a counted rung by less than lead_fall
only (peaks.lead_fall), so the ladder is the rise that led to it. front_times reads the half-amplitude
arrival off it: the time the dynamic force F - F0 rose through FRONT_FRACTION of the leading pulse's
rise (the amplitude), interpolated between rungs (docs/observables.md).

long_load_fronts(scene, solution) measures, from the run's snapshots and peak forces, the plateau
values the quasi-steady model of Eqs. 35-38 predicts (physics.models.long_load_bilinear):

F_1, v_1   force and bead velocity behind the loading front, while the load acts (t < T)
v_t        bead velocity behind the unloading front, before the fronts meet (T < t, a contact
           still above A/2 ahead)
F_2, v_2   force and bead velocity of the loaded block after the fronts have met (no contact
           above A/2 any more)
x_t        where the fronts meet: the first contact whose peak force falls below (F_1 + F_2)/2

Each phase is recognised from the data (not from the model's T_t); a plateau value is the median
over the middle 60% of its region, away from the fronts' oscillating edges. Snapshot times must
include one of each phase that is to be measured; values of a missing phase are NaN.
"""

from __future__ import annotations

import math

import numpy as np

#: rungs per octave of the crossing-time ladder: close enough that a cubic through four rungs around
#: half the amplitude reads the crossing to far below the time step's error (the deck passes it to the
#: pair styles: templates/contact.lmp.j2)
LADDER_PER_OCTAVE = 8
#: crossing times each contact keeps (a ring of the last ones): half the amplitude lies an octave
#: (LADDER_PER_OCTAVE rungs) below the leading pulse, and the cubic needs one rung below it
LADDER_SLOTS = 16
#: the front's arrival at a contact: when its dynamic force rose through this fraction of its amplitude
FRONT_FRACTION = 0.5
#: the smallest amplitude, as a fraction of the static force F0, whose arrival is read: LAMMPS integrates
#: absolute positions and resolves a precompressed contact's total force only to about 1.5e-9 F0 (a
#: 300-bead brass chain at F0 = 100 N); ahead of a small front its round-off makes maxima of up to 1.8e-8
#: F0 above F0, which the leading pulse's floor stays above (peaks.position_resolution, 2.7e-6 N = 2.7e-8
#: F0 on that chain); amplitudes are read only above this fraction of F0
FRONT_RESOLUTION = 1e-6


def ladder_level(k: int, floor: float) -> float:
    """Rung k's rise above F0 (N): floor * 2^(k / LADDER_PER_OCTAVE), as the pair styles compute it
    (Python's float ** is C's pow, the same bits)."""
    return floor * 2.0 ** (k / LADDER_PER_OCTAVE)


def front_times(ladder: np.ndarray, lead_force: np.ndarray, f0: float, floor: float) -> np.ndarray:
    """Each contact's half-amplitude arrival (s) from its crossing-time ladder; nan where it has none.

    Parameters
    ----------
    ladder : ndarray (contacts, LADDER_SLOTS + 1)
        Rungs crossed, then the ring of crossing times (rung k in column 1 + k % LADDER_SLOTS).
    lead_force : ndarray (contacts,)
        The leading pulse's total force (nan: none); its rise above f0 is the amplitude.
    f0, floor : float
        The static force and the leading pulse's floor the ladder's rungs were laid from.

    Returns
    -------
    ndarray
        The time the dynamic force rose through FRONT_FRACTION of the amplitude: a cubic in the rung
        index through the four rungs around that level (a line through the two around it where the
        ring no longer holds the four); nan without a leading pulse, with an amplitude at most
        FRONT_RESOLUTION F0 (one that cannot be told from the total force's resolution), or without
        both rungs around the level.
    """
    ladder = np.asarray(ladder, dtype=float)
    out = np.full(ladder.shape[0], np.nan)
    lead_force = np.asarray(lead_force, dtype=float)
    for i in np.flatnonzero(np.isfinite(lead_force) & (lead_force - f0 > FRONT_RESOLUTION * f0)):
        out[i] = _front_time(ladder[i], float(lead_force[i]) - f0, floor)
    return out


def _front_time(row: np.ndarray, amplitude: float, floor: float) -> float:
    """One contact's half-amplitude arrival from its ladder row (front_times)."""
    level = FRONT_FRACTION * amplitude
    if not level >= floor:
        return math.nan
    crossed = int(row[0])
    lowest = max(0, crossed - LADDER_SLOTS)  # the rungs the ring still holds: lowest .. crossed - 1
    k = int(math.floor(LADDER_PER_OCTAVE * math.log2(level / floor)))
    while k > 0 and ladder_level(k, floor) > level:  # rung k at or below the level, rung k + 1 above it
        k -= 1
    while ladder_level(k + 1, floor) <= level:
        k += 1
    if k < lowest or k + 1 >= crossed:
        return math.nan

    def t(j: int) -> float:
        return float(row[1 + j % LADDER_SLOTS])

    x = LADDER_PER_OCTAVE * math.log2(level / floor) - k  # in [0, 1): the level between rungs k and k + 1
    if k - 1 < lowest or k + 2 >= crossed:
        return t(k) + x * (t(k + 1) - t(k))
    # Lagrange cubic through rungs k - 1 .. k + 2 (equally spaced in the rung index)
    w = (
        -x * (x - 1) * (x - 2) / 6,
        (x + 1) * (x - 1) * (x - 2) / 2,
        -(x + 1) * x * (x - 2) / 2,
        (x + 1) * x * (x - 1) / 6,
    )
    return sum(wj * t(k - 1 + j) for j, wj in enumerate(w))


#: the part of a region used for its plateau value (from its rear edge, in fractions of its length)
PLATEAU = (0.2, 0.8)


def _middle(lo: int, hi: int) -> slice:
    n = hi - lo
    return slice(lo + int(PLATEAU[0] * n), lo + max(int(PLATEAU[1] * n), int(PLATEAU[0] * n) + 1))


#: the plateau values long_load_fronts measures (the module docstring), each a long_load_* model of a law
FRONTS = ("F_1", "v_1", "v_t", "F_2", "v_2", "x_t")


def long_load_fronts(scene, sol) -> dict[str, float]:
    """Measured F_1, v_1, v_t, F_2, v_2 (N, m/s) and x_t (m, from bead 1's centre); see the module doc."""
    out = dict.fromkeys(FRONTS, float("nan"))
    # the quasi-steady fronts are a model of the law (the bilinear law's long_load_* of Eqs. 35-38)
    modelled = all(f"long_load_{key}" in scene.contact.law_class.model_domains for key in out)
    if not modelled or not scene.loading.is_step:
        raise ValueError("long_load_fronts measures a bilinear chain under a step load (Sec. III B)")
    a, t_load, d = scene.loading.amplitude, scene.loading.duration, scene.diameter
    for k, t in enumerate(sol.snapshot_time):
        f, v = sol.snapshot_force[k], sol.snapshot_velocity[k]
        above = np.flatnonzero(f > 0.5 * a)
        if t < t_load and above.size:  # loading: A pushes a plateau F_1 ahead of it
            s = _middle(0, int(above.max()))
            out["F_1"], out["v_1"] = float(np.median(f[s])), float(np.median(v[s]))
        elif t > t_load and above.size and above.min() > 0:  # unloading front running after it
            s = _middle(0, int(above.min()))
            out["v_t"] = float(np.median(v[s]))
        elif t > t_load and not above.size:  # the fronts have met: one loaded block of F_2
            loaded = np.flatnonzero(f > 0.25 * f.max()) if f.max() > 0 else np.zeros(0, int)
            if loaded.size:
                s = _middle(int(loaded.min()), int(loaded.max()) + 1)
                out["F_2"], out["v_2"] = float(np.median(f[s])), float(np.median(v[s]))
    if np.isfinite(out["F_1"]) and np.isfinite(out["F_2"]):
        pk = np.nan_to_num(np.asarray(sol.peak_force, dtype=float))
        below = np.flatnonzero(pk[10:] < 0.5 * (out["F_1"] + out["F_2"]))
        j = int(below[0]) + 10 if below.size else len(pk)
        if j + 1 < len(pk) and pk[j + 1] > 0.5 * out["F_2"]:  # a merge, not the wave's reach
            out["x_t"] = (j + 0.5) * d  # contact j + 1 (1-based) sits at (j + 1/2) D from bead 1
    return out
