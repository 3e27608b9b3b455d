"""SciPy's solve_ivp (DOP853, adaptive 8th order) on the elastic chain: an outside yardstick.

Hertz chains only: the bilinear law's history (alpha_max) is not a function of the state, and an
adaptive solver evaluates the right-hand side at trial points that must not write history.
"""

from __future__ import annotations

import time

import numpy as np

from granchain.peaks import unreached_as_nan
from granchain.physics.laws import HertzLaw
from granchain.problem import ChainProblem
from granchain.reference.solver import _hermite_max
from granchain.results import ChainSolution
from granchain.schedule import step_plan


def solve_chain_dop853(problem: ChainProblem, end_time: float, rtol: float, atol: float | None = None) -> ChainSolution:
    """A Hertz chain solved by SciPy's DOP853 at rtol (the accuracy study's outside yardstick)."""
    from scipy.integrate import solve_ivp

    if not isinstance(problem.law, HertzLaw):
        raise ValueError("the DOP853 yardstick handles Hertz chains only (the bilinear history is not a state)")
    t0 = time.perf_counter()
    n = problem.beads
    k, inv_m = problem.law.k, 1.0 / problem.mass
    y = np.zeros(2 * n)
    y[n] = problem.initial_velocity
    amax = np.zeros(n - 1)
    tmax = np.full(n - 1, np.nan)
    steps = 0
    # segments: the load is constant on each (T is a boundary), as in the other solvers
    plan = step_plan(end_time, end_time, problem.duration if problem.amplitude else 0.0)
    scale_u = max(problem.initial_velocity, problem.amplitude * problem.duration * inv_m[0]) * end_time
    atol = atol if atol is not None else rtol * max(scale_u, 1e-300)
    for g in plan:
        loaded = g.loaded

        def rhs(_t, yy, loaded=loaded):
            u, v = yy[:n], yy[n:]
            a = np.maximum(u[:-1] - u[1:], 0.0)
            fc = k * a * np.sqrt(a)
            acc = np.zeros(n)
            acc[:-1] -= fc
            acc[1:] += fc
            acc[0] += problem.load_force(_t) if loaded else 0.0  # (a drive's changes within the segment)
            return np.concatenate((v, acc * inv_m))

        sol = solve_ivp(rhs, (g.start, g.end), y, method="DOP853", rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(f"DOP853 failed: {sol.message}")
        ts, ys = sol.t, sol.y
        steps += len(ts) - 1
        al = ys[: n - 1] - ys[1:n]
        ad = ys[n : 2 * n - 1] - ys[n + 1 :]
        for j in range(1, len(ts)):
            a1 = al[:, j]
            rising = a1 > amax
            amax[rising] = a1[rising]
            tmax[rising] = ts[j]
            turn = np.flatnonzero((ad[:, j - 1] > 0) & (ad[:, j] <= 0) & (a1 > 0))
            if turn.size:
                p, tp = _hermite_max(ts[j - 1], ts[j], al[turn, j - 1], a1[turn], ad[turn, j - 1], ad[turn, j])
                better = p > amax[turn]
                amax[turn[better]] = p[better]
                tmax[turn[better]] = tp[better]
        y = ys[:, -1]
    peak = problem.law.force_at_peak_overlap(amax)
    return ChainSolution(
        method="dop853",
        timestep=float("nan"),
        steps=steps,
        wall_time=time.perf_counter() - t0,
        end_time=end_time,
        peak_overlap=amax,
        peak_force=np.asarray(peak, dtype=float),
        time_of_peak=unreached_as_nan(np.asarray(peak), tmax),
        displacement=y[:n],
        velocity=y[n:],
        momentum=float(np.dot(problem.mass, y[n:])),
        impulse_delivered=float(problem.load_impulse(end_time)),
        energy_time=np.zeros(1),
        kinetic=np.zeros(1),
        potential=np.zeros(1),
        dissipated=np.zeros(1),
        work=np.zeros(1),
    )
