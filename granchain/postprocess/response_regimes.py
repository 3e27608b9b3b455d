"""Response regimes: single solitary wave vs wave train (Sec. II B), a weakly nonlinear wave on a
precompressed chain, and the two force-decay regimes of elastoplastic chains (exponential, then
inverse power law; Sec. III A), measured from a run's force histories and peaks. The regime expected
from the scene alone is granchain.physics.loading_regime.loading_regime."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from granchain.physics.models import weakly_nonlinear_ratio

#: A pulse counts when it rises at least this fraction of the leading pulse above the dip before it.
PULSE_FRACTION = 0.1


def count_pulses(force: np.ndarray, fraction: float = PULSE_FRACTION, static_force: float = 0.0) -> int:
    """Distinct pulses in a contact-force history.

    A pulse rises at least `fraction` of the largest dynamic force above the lowest value since the
    previous pulse, and then falls at least as much below its own top (or the record ends on it). A
    wave train shows several; a single solitary wave one. The constant-force plateau behind the front
    of a long load is not a pulse: it neither rises nor falls.

    Parameters
    ----------
    force : numpy.ndarray
        The contact's force history (N), as recorded: the total force.
    fraction : float
        The rise and fall a pulse needs, as a fraction of the largest dynamic force.
    static_force : float
        The precompression F0 every contact carries at rest: pulses are counted on the dynamic force
        F - F0 (a 2 N pulse on F0 = 2000 N is a pulse; a tenth of the total force it never rises).

    Returns
    -------
    int
        The number of pulses.
    """
    f = np.asarray(force, dtype=float) - float(static_force)
    if f.size == 0 or f.max() <= 0:
        return 0
    threshold = fraction * f.max()
    pulses, rising = 0, False
    low = high = f[0]
    for x in f:
        if not rising:
            low = min(low, x)
            if x - low >= threshold:
                rising, high = True, x
        else:
            high = max(high, x)
            if high - x >= threshold:
                pulses, rising, low = pulses + 1, False, x
    return pulses + int(rising)


def classify_wave(force: np.ndarray, fraction: float = PULSE_FRACTION, static_force: float = 0.0) -> str:
    """The wave a contact's force history shows, from its pulses (count_pulses) on the dynamic force.

    'single solitary wave' (one pulse) or 'wave train' (several), the paper's short- and long-load
    responses (Sec. II B); 'no wave' without a pulse. On a precompressed chain whose dynamic force
    stays small against F0 (below physics.models.weakly_nonlinear_ratio F0: Nesterenko's V_s within
    1e-3 of the sound speed c0), 'weakly nonlinear wave' (or 'weakly nonlinear wave train'): a
    perturbation of the linearised chain moving at c0, which disperses, not the paper's strongly
    nonlinear solitary wave.

    Parameters
    ----------
    force : numpy.ndarray
        The contact's force history (N), the total force.
    fraction : float
        As count_pulses.
    static_force : float
        The precompression F0 (0: none).

    Returns
    -------
    str
        The regime's name.
    """
    n = count_pulses(force, fraction, static_force)
    if n == 0:
        return "no wave"
    if static_force > 0:
        amplitude = float(np.max(np.asarray(force, dtype=float))) - float(static_force)
        if amplitude <= weakly_nonlinear_ratio() * static_force:
            return "weakly nonlinear wave" if n == 1 else "weakly nonlinear wave train"
    return "single solitary wave" if n == 1 else "wave train"


#: the transition range: splits whose summed squared residuals exceed the least by at most this many
#: residual variances (the F test at 95% for one parameter, F(1, n - 4) ~ 4 for the chains' n)
TRANSITION_F = 4.0


@dataclass(frozen=True)
class DecayFit:
    """Peak force vs contact index i (1-based): F = F_1 exp(-lambda (i-1)) for i < transition,
    F = a i^(-p) from the transition on; each with its uncertainty from the fit: the slopes' standard
    errors, and the range of transition contacts the data cannot tell from the best (their summed
    squared residuals within TRANSITION_F residual variances of the least)."""

    transition_contact: int
    decay_per_contact: float  # lambda, exponential regime
    power: float  # p, inverse regime
    rms_log_residual: float
    decay_per_contact_stderr: float = float("nan")
    power_stderr: float = float("nan")
    transition_range: tuple[int, int] = (0, 0)


def _line(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    slope, icpt = np.polyfit(x, y, 1)
    return float(slope), float(icpt), float(np.sum((y - (icpt + slope * x)) ** 2))


def _slope_stderr(x: np.ndarray, rss: float) -> float:
    """The least-squares slope's standard error (nan with fewer than 3 points)."""
    if x.size < 3:
        return float("nan")
    return float(np.sqrt(rss / (x.size - 2) / np.sum((x - x.mean()) ** 2)))


def fit_decay(peak_force: np.ndarray, last_contact: int | None = None, min_points: int = 3) -> DecayFit:
    """Split the peak-force curve into an exponential and an inverse power-law part.

    The transition contact is the split that minimises the summed squared residuals of log F, with an
    exponential (log F linear in i) before it and a power law (log F linear in log i) from it on.
    """
    f = np.asarray(peak_force, dtype=float)
    n = len(f) if last_contact is None else last_contact
    i = np.arange(1, n + 1, dtype=float)
    y = np.log(f[:n])
    fits = []
    for c in range(min_points + 1, n - min_points + 2):
        s1, _, r1 = _line(i[: c - 1], y[: c - 1])
        s2, _, r2 = _line(np.log(i[c - 1 :]), y[c - 1 :])
        fits.append((r1 + r2, c, -s1, -s2, r1, r2))
    if not fits:
        raise ValueError(f"need at least {2 * min_points} contacts to fit two decay regimes, got {n}")
    best = min(fits)
    rss, c = best[0], best[1]
    variance = rss / max(n - 4, 1)  # four fitted numbers
    # splits no worse than the best by the F test's 95% level for one parameter (F(1, n-4) ~ 4)
    near = [x[1] for x in fits if x[0] <= rss + TRANSITION_F * variance]
    return DecayFit(
        transition_contact=c,
        decay_per_contact=best[2],
        power=best[3],
        rms_log_residual=float(np.sqrt(rss / n)),
        decay_per_contact_stderr=_slope_stderr(i[: c - 1], best[4]),
        power_stderr=_slope_stderr(np.log(i[c - 1 :]), best[5]),
        transition_range=(min(near), max(near)),
    )
