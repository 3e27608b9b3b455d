"""The loading regime a scene is in, expected from the scene alone: short load (single solitary wave),
long load (wave train behind a steady front) or the transition between them (Sec. II B, Sec. III).
What a run measured (pulses, decay regimes) is granchain.postprocess.response_regimes."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from granchain.physics import models
from granchain.physics.estimates import step_equivalent  # the one striker-as-a-step rule
from granchain.physics.laws.power import power_impact

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
    ratio: float  # T / T_c (a Hertz onset) or T / t_c (a loading line, a power law); 0 for a velocity kick
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
    it pushes like (granchain.physics.estimates.step_equivalent: A from Eqs. 12 and 19, T = M V / A).
    """
    ld = scene.loading
    if ld.kind == "velocity":
        return LoadingRegime("short", 0.0, "short load: a velocity kick of bead 1, the zero-duration limit")
    amp, dur = step_equivalent(scene)
    load = ""
    if ld.kind == "striker":
        load = f"the striker (M = {scene.striker_mass / scene.mass:.3g} m) pushes like a step A = {amp:.3g} N, "
    if scene.contact.law_class.hertz_onset:  # Hertz; Thornton by its elastic (Hertz) onset
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
    if scene.contact.law_class.loading_is_linear():
        t_c = bilinear_contact_time(scene)
        how = "pi sqrt(m/2k)"
    else:
        t_c = power_contact_time(scene, amp)
        how = "two beads' F = K alpha^n impact at the front's bead speed v = D A / (m c), c of Eq. 19"
    ratio = dur / t_c
    regime, rule = _regime_of(ratio, BILINEAR_SHORT_BELOW, BILINEAR_LONG_ABOVE, "t_c")
    text = f"{regime} load: {load}T = {ratio:.3g} t_c ({rule}; t_c = {how} = {t_c:.3g} s)"
    return LoadingRegime(regime, ratio, text)


def power_contact_time(scene, amplitude: float) -> float:
    """t_c of a law without a Hertz onset (the power law F = K alpha^n): the two-body contact time
    (power_impact, m* = m/2) at the bead speed behind a long load's front, v = D A / (m c) (Eq. 12)
    with c the front speed of Eq. 19 on that law (models.power_front_speed). The contact time depends
    on v unless n = 1, where it is the loading line's pi sqrt(m/2k). With per-contact n the smallest
    over the contacts: the shortest contact time is the first a load outlasts (long sooner)."""
    laws = scene.contact_laws if scene.contact.coefficients.varies else [scene.law]
    m, d = scene.mass, scene.diameter
    times = []
    for law in laws:
        k, n = float(law.k), float(np.max(law.loading_exponent()))
        v = d * amplitude / (m * models.power_front_speed(amplitude, k, n, m, d))
        times.append(power_impact(k, n, m / 2.0, v)["duration"])
    return min(times)
