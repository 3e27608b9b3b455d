"""Loading and unloading fronts of a bilinear chain under a long step load (Sec. III B, Table I).

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

import numpy as np

#: the part of a region used for its plateau value (from its rear edge, in fractions of its length)
PLATEAU = (0.2, 0.8)


def _middle(lo: int, hi: int) -> slice:
    n = hi - lo
    return slice(lo + int(PLATEAU[0] * n), lo + max(int(PLATEAU[1] * n), int(PLATEAU[0] * n) + 1))


def long_load_fronts(scene, sol) -> dict[str, float]:
    """Measured F_1, v_1, v_t, F_2, v_2 (N, m/s) and x_t (m, from bead 1's centre); see the module doc."""
    if scene.contact.law != "bilinear" or not scene.loading.is_force:
        raise ValueError("long_load_fronts measures a bilinear chain under a step load (Sec. III B)")
    a, t_load, d = scene.loading.amplitude, scene.loading.duration, scene.diameter
    out = dict.fromkeys(("F_1", "v_1", "v_t", "F_2", "v_2", "x_t"), float("nan"))
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
