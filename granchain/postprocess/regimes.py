"""Response regimes: single solitary wave vs wave train (Sec. II B), and the two force-decay regimes
of elastoplastic chains (exponential, then inverse power law; Sec. III A): measured from a run's
force histories and peaks, and expected from the scene alone (:func:`loading_regime`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from granchain.physics import models
from granchain.workflows.plan import step_equivalent  # the one striker-as-a-step rule

#: A pulse counts when it rises at least this fraction of the leading pulse above the dip before it.
PULSE_FRACTION = 0.1


def count_pulses(force: np.ndarray, fraction: float = PULSE_FRACTION) -> int:
    """Distinct pulses in a contact-force history.

    A pulse rises at least `fraction` of the largest force above the lowest value since the previous
    pulse, and then falls at least as much below its own top (or the record ends on it). A wave
    train shows several; a single solitary wave one. The constant-force plateau behind the front of
    a long load is not a pulse: it neither rises nor falls.
    """
    f = np.asarray(force, dtype=float)
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


def classify_wave(force: np.ndarray, fraction: float = PULSE_FRACTION) -> str:
    """'single solitary wave' or 'wave train' from a contact's force history (0: 'no wave')."""
    n = count_pulses(force, fraction)
    return "no wave" if n == 0 else "single solitary wave" if n == 1 else "wave train"


@dataclass(frozen=True)
class DecayFit:
    """Peak force vs contact index i (1-based): F = F_1 exp(-lambda (i-1)) for i < transition,
    F = a i^(-p) from the transition on."""

    transition_contact: int
    decay_per_contact: float  # lambda, exponential regime
    power: float  # p, inverse regime
    rms_log_residual: float


def _line(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    slope, icpt = np.polyfit(x, y, 1)
    return float(slope), float(icpt), float(np.sum((y - (icpt + slope * x)) ** 2))


def fit_decay(peak_force: np.ndarray, last_contact: int | None = None, min_points: int = 3) -> DecayFit:
    """Split the peak-force curve into an exponential and an inverse power-law part.

    The transition contact is the split that minimises the summed squared residuals of log F, with an
    exponential (log F linear in i) before it and a power law (log F linear in log i) from it on.
    """
    f = np.asarray(peak_force, dtype=float)
    n = len(f) if last_contact is None else last_contact
    i = np.arange(1, n + 1, dtype=float)
    y = np.log(f[:n])
    best = None
    for c in range(min_points + 1, n - min_points + 2):
        s1, _, r1 = _line(i[: c - 1], y[: c - 1])
        s2, _, r2 = _line(np.log(i[c - 1 :]), y[c - 1 :])
        if best is None or r1 + r2 < best[0]:
            best = (r1 + r2, c, -s1, -s2)
    if best is None:
        raise ValueError(f"need at least {2 * min_points} contacts to fit two decay regimes, got {n}")
    return DecayFit(
        transition_contact=best[1],
        decay_per_contact=best[2],
        power=best[3],
        rms_log_residual=float(np.sqrt(best[0] / n)),
    )


# ------------------------------------------------------------------ expected from the scene

#: Hertz chains: a load is short below this fraction of the crossover time T_c and long above the
#: multiple. T_c is the corner of Fig. 3's master curve, the loading time at which Eq. 8's peak
#: (I = A T, F ~ I^(6/5)) equals the long-load upper bound (Eq. 15 + Nesterenko, F ~ A); it goes as
#: A^(-1/6), the transition law of Fig. 1. Measured on the reference solver (brass, I = 0.4 N s, peak at
#: contact 80 of 120): the leading peak is within 3% of Eq. 8 up to T = T_c/3, 8% at T_c/2 and 40% at
#: T_c; it lies between the long-load bounds (Eqs. 15, 19 + Nesterenko) from T = 1.7 T_c on.
HERTZ_SHORT_BELOW = 0.5
HERTZ_LONG_ABOVE = 2.0
#: Bilinear chains: T against t_c = pi sqrt(m / 2k), the contact time of two beads on the plastic
#: loading line k (Sec. III). Measured: contact 1's peak is within 0.5% of Eq. A2 at T = 0.1 t_c and
#: 5% at 0.36 t_c; the steady fronts of Sec. III B need many contact times.
BILINEAR_SHORT_BELOW = 0.1
BILINEAR_LONG_ABOVE = 10.0


@dataclass(frozen=True)
class LoadingRegime:
    """Which of the paper's loading regimes a scene is in, expected from the scene alone."""

    regime: str  # "short", "long" or "transition"
    ratio: float  # T / T_c (Hertz) or T / t_c (bilinear); 0 for a velocity kick
    text: str  # how it was decided, with the numbers


def _regime_of(ratio: float, short_below: float, long_above: float, unit: str) -> tuple[str, str]:
    if ratio < short_below:
        return "short", f"< {short_below:g} {unit}"
    if ratio > long_above:
        return "long", f"> {long_above:g} {unit}"
    return "transition", f"between {short_below:g} and {long_above:g} {unit}"


def bilinear_contact_time(scene) -> float:
    """t_c = pi sqrt(m / 2k): two beads on a linear spring k (the plastic loading line)."""
    return math.pi * math.sqrt(scene.mass / (2.0 * scene.stiffness))


def loading_regime(scene) -> LoadingRegime:
    """Short load (single solitary wave; Eq. 8, Eqs. A1-A4, 26-34), long load (wave train behind a
    steady front; Eqs. 12-19, 35-38) or the transition between them, from the loading time T.

    A velocity kick of bead 1 is the zero-duration limit (short). A striker counts as the step load
    it pushes like (granchain.workflows.plan.step_equivalent: A from Eqs. 12 and 19, T = M V / A).
    """
    ld = scene.loading
    if ld.kind == "velocity":
        return LoadingRegime("short", 0.0, "short load: a velocity kick of bead 1, the zero-duration limit")
    amp, dur = step_equivalent(scene)
    load = ""
    if ld.kind == "striker":
        load = f"the striker (M = {scene.striker_mass / scene.mass:.3g} m) pushes like a step A = {amp:.3g} N, "
    if scene.contact.law == "hertz":
        m, d, k = scene.mass, scene.diameter, scene.stiffness
        f_short = models.short_load_peak_force(amp * dur, m, scene.e_star, scene.r_star)
        f_long = models.solitary_wave_peak_force(models.front_speed_upper(amp, k, m, d), k, m, d)
        ratio = (f_short / f_long) ** (5.0 / 6.0)  # Eq. 8 grows as T^(6/5) at fixed A
        regime, rule = _regime_of(ratio, HERTZ_SHORT_BELOW, HERTZ_LONG_ABOVE, "T_c")
        text = (
            f"{regime} load: {load}T = {dur / scene.tau:.3g} tau = {ratio:.3g} T_c ({rule}; "
            f"T_c = {dur / ratio / scene.tau:.3g} tau, where Eq. 8 meets Eq. 15)"
        )
        return LoadingRegime(regime, ratio, text)
    t_c = bilinear_contact_time(scene)
    ratio = dur / t_c
    regime, rule = _regime_of(ratio, BILINEAR_SHORT_BELOW, BILINEAR_LONG_ABOVE, "t_c")
    text = f"{regime} load: {load}T = {ratio:.3g} t_c ({rule}; t_c = pi sqrt(m/2k) = {t_c:.3g} s)"
    return LoadingRegime(regime, ratio, text)
