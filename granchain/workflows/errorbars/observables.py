"""The round-off floor of a run's numbers and the scalar observables' entries (value, error, status)."""

from __future__ import annotations

import numpy as np

from granchain.postprocess.observables import OBSERVABLES

#: a withheld step error the fit's standard error outweighs this many times over is left out of the
#: wave speed's error: in quadrature it would add under 0.5% of the fit's
FIT_DOMINATES = 10.0


def _withheld_step_bound(finer, fine, coarse, lo: float) -> float | None:
    """A bound on the step's error at dt that holds on either reading of a check that failed
    (richardson.checked): MAX_OVERESTIMATE times the larger of the most the difference to dt / 2
    allows (|Q(dt / 2) - Q(dt)| / (1 - 2^-lo), lo the integrator's lowest order) and the change from
    2 dt, |Q(dt) - Q(2 dt)| (above any estimate from 2 dt and 4 dt at an order of 1 or more). None
    where a run did not measure the value."""
    from granchain.richardson import MAX_OVERESTIMATE

    q = [np.nan if x is None else float(x) for x in (finer, fine, coarse)]
    if not all(np.isfinite(q)):
        return None
    return MAX_OVERESTIMATE * max(abs(q[0] - q[1]) / (1.0 - 2.0**-lo), abs(q[1] - q[2]))


def _observable_floor(name: str, measured: dict, floor: np.ndarray | None, b: int) -> float | None:
    """The round-off floor of a scalar observable (N, or its nondimensional form; b: the window's last
    contact, 0-based): the registered observable's (Observable.roundoff_floor; the leading peak's is its
    contact's, the largest peak's its contact's, a wave speed, a fit of arrival times, has none)."""
    if floor is None:
        return None
    fl = OBSERVABLES[name].roundoff_floor(measured, floor, b)
    return fl if fl is not None and np.isfinite(fl) else None


def roundoff_floor(scene, sol, absolute_positions: bool = False) -> np.ndarray | None:
    """Each contact's peak force's round-off in a run (N), or None where the run gives no displacements.

    The reference integrates displacements u (from the undeformed chain) and takes overlaps as
    u_i - u_(i+1): every step rounds u at eps |u|, and over the run's n steps those roundings add as a
    random walk, sqrt(n) eps U (U the largest |u|, from the final state: the drift and the static
    compression of a precompressed chain). A contact's force carries it times its slope, at most
    3/2 F / alpha at its peak (Hertz; a linear loading line's F / alpha is below). Where the step is
    far finer than accuracy needs (the stability limit of a chain's smallest beads: a taper to 0.8,
    a precompressed 20-bead chain, docs/error-bars.md) the step's error falls below this, and the
    three runs' differences are round-off that can look like any order: measured there 0.013-0.62 of
    the distance to a run at dt / 16, itself round-off (the runs at dt / 2 to dt / 16 scattered by
    1e-13 - 1e-12 N about one another, 20-150x eps U dF/dalpha).

    A backend that integrates absolute positions (LAMMPS, Backend.absolute_positions) rounds each at
    eps |x|, up to the chain's length: there U is the largest |x|, and, without overlaps in its
    output, the slope is the stiffest of the chain's laws at the contact's peak force
    (ContactLaw.tangent_stiffness). The same random walk as peaks.position_resolution, which bounds
    it at 6 standard deviations for the leading pulse's floor.
    """
    u = np.asarray(getattr(sol, "displacement", ()), dtype=float)
    if u.size == 0 or not sol.steps:
        return None
    f = np.asarray(sol.peak_force, dtype=float)
    from granchain.peaks import chain_laws

    if absolute_positions:
        size = float(np.max(np.abs(scene.bead_positions[: u.size] + u)))
        force = np.nan_to_num(np.abs(f))
        slope = np.max(
            [np.broadcast_to(law.tangent_stiffness(force), force.shape) for law in chain_laws(scene)], axis=0
        )
        slope = np.where(np.isfinite(f), slope, np.nan)
    else:
        overlap = getattr(sol, "peak_overlap", None)
        if overlap is None:
            return None
        size = float(np.max(np.abs(u)))
        a = np.asarray(overlap, dtype=float)
        # dF/dalpha = n F / alpha on the onset's F = k alpha^n, at least Hertz's 3/2 (above a loading
        # line's F / alpha), the largest n of a power law's contacts: the round-off bound is an upper one
        n = max(1.5, *(float(np.max(law.loading_exponent())) for law in chain_laws(scene)))
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = np.where(a > 0, n * np.abs(f) / a, np.nan)
    return np.sqrt(float(sol.steps)) * np.finfo(float).eps * size * slope


def _observable_error(name: str, value, bars, measured: dict, withheld_bound: float | None = None) -> dict:
    """An observable's entry: its time-step error (bars) and, for the wave speed, the fit's standard
    error too: the reported error is both in quadrature (on a taper or a dimer the fit's spread is
    30x to 20 000x the step's), each kept under its own name.

    Where a check withheld the step's error (the run at dt / 2, or the order checks of 2 dt and 4 dt) but
    withheld_bound (_withheld_step_bound)
    puts it under 1 / FIT_DOMINATES of the fit's standard error, the wave speed's error is the fit's
    alone (the step's stays withheld, its bound given as step_error_bound) and the status says so.
    """
    step = float(bars.error[0])
    out = {"value": value, "error": step if np.isfinite(step) else None, "status": str(bars.status[0])}
    fit_stderr = OBSERVABLES[name].fit_stderr  # a fit's standard error beside the value (the wave speed's)
    fit = measured.get(fit_stderr) if fit_stderr else None
    if fit is not None and value is not None:
        out["step_error"] = out["error"]
        out["fit_stderr"] = float(fit)
        out["error"] = float(np.hypot(step, fit)) if np.isfinite(step) else None
        if out["error"] is not None:
            out["status"] += "; error: the step's and the fit's standard error in quadrature"
        elif withheld_bound is not None and FIT_DOMINATES * withheld_bound <= float(fit):
            out["error"] = float(fit)
            out["step_error_bound"] = float(withheld_bound)
            out["status"] = (
                f"fit's spread alone: the step's error is withheld ({out['status'].removeprefix('unreliable: ')}); "
                f"the runs at dt / 2, dt and 2 dt bound it at {withheld_bound:.2g} whichever reading of the "
                f"check that withheld it is right, under 1/{FIT_DOMINATES:g} of the fit's standard error "
                f"{float(fit):.2g}"
            )
    return out
