"""The loading regime a scene is in, expected from the scene alone: short load (single solitary wave),
long load (wave train behind a steady front) or the transition between them (Sec. II B, Sec. III).
What a run measured (pulses, decay regimes) is granchain.postprocess.response_regimes."""

from __future__ import annotations

from dataclasses import dataclass

from granchain.physics.estimates import step_equivalent  # the one striker-as-a-step rule

# (each law's time scale and its thresholds are the law's: ContactLaw.loading_time_scale; Hertz's
# measured thresholds are read here by the tests)
from granchain.physics.laws.hertz import HERTZ_LONG_ABOVE, HERTZ_SHORT_BELOW

__all__ = ["HERTZ_LONG_ABOVE", "HERTZ_SHORT_BELOW", "LoadingRegime", "loading_regime"]


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
    scale = scene.contact.law_class.loading_time_scale(scene, amp, dur)
    regime, rule = _regime_of(scale.ratio, scale.short_below, scale.long_above, scale.unit)
    return LoadingRegime(regime, scale.ratio, f"{regime} load: {load}{scale.ratio_text} ({rule}; {scale.definition})")
