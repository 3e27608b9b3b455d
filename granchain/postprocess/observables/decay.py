"""The leading pulse's decay along the measurement window: an exponential and a power-law fit.

The leading pulses of the window's contacts (granchain.peaks.leading_pulse: each contact's first
maximum, once passed; above each contact's own static force under precompression or gravity) are fitted
against the contact i (1-based) by least squares in log space: ln F = ln A - i / L for the exponential
F = A exp(-i / L) (leading_pulse_decay_length, in contacts), ln F = ln A - p ln i for the power law
F = A i^-p (leading_pulse_decay_exponent); each slope's standard error is propagated to its constant.

A decay is reported only where the fit resolves one: the slope at least DECAY_SIGNIFICANCE standard
errors below zero and the fitted pulse falling by DECAY_RESOLUTION or more over the fitted contacts.
Elsewhere the constant is None, with the reason: a uniform Hertz chain's solitary wave keeps its
amplitude, so a fit there gives a decay length of millions of contacts or a negative one, a number
that says nothing. Dissipation (a dashpot) and a taper of shrinking beads make the pulse decay.
"""

from __future__ import annotations

from typing import ClassVar, NamedTuple

import numpy as np

from granchain.postprocess.observables.base import Measurement, Observable
from granchain.postprocess.observables.fit import FIT_CONTACTS, window_unfittable
from granchain.problem import scene_static_forces

#: the least fall of the fitted pulse over the fitted contacts (a fraction of its first value) that
#: counts as a decay: a uniform chain's solitary wave changes by far less (round-off, the wave's forming)
DECAY_RESOLUTION = 0.01
#: how many standard errors below zero a fitted log slope must lie to be a decay, not the fit's scatter
DECAY_SIGNIFICANCE = 2.0


class LogFit(NamedTuple):
    """ln F = intercept + slope x, fitted by least squares, and the slope's standard error."""

    slope: float
    intercept: float
    stderr: float


def fit_log_line(x: np.ndarray, force: np.ndarray) -> LogFit:
    """The least-squares line of ln force (N, > 0) against x (FIT_CONTACTS points or more), its slope's
    standard error from the residuals (not scipy's linregress, whose sqrt(1 - r^2) leaves sqrt(eps) of
    the slope where the points lie on a line)."""
    x = np.asarray(x, dtype=float)
    y = np.log(np.asarray(force, dtype=float))
    xm, ym = x.mean(), y.mean()
    sxx = float(np.sum((x - xm) ** 2))
    slope = float(np.sum((x - xm) * (y - ym))) / sxx
    resid = y - (ym + slope * (x - xm))
    return LogFit(slope, float(ym - slope * xm), float(np.sqrt(np.sum(resid**2) / (x.size - 2) / sxx)))


def why_no_decay(fit: LogFit, x: np.ndarray) -> str | None:
    """Why a log fit over x shows no decay (the slope within DECAY_SIGNIFICANCE standard errors of
    zero or above it, or a fall under DECAY_RESOLUTION over x's span), or None where it shows one."""
    fall = 1.0 - float(np.exp(fit.slope * (float(np.max(x)) - float(np.min(x)))))
    if fit.slope < -DECAY_SIGNIFICANCE * fit.stderr and fall >= DECAY_RESOLUTION:
        return None
    return (
        f"no decay: the fit changes the leading pulse by {-100 * fall:+.2g}% over the fitted contacts (slope "
        f"{fit.slope:.2g} +- {fit.stderr:.2g}), not a fall of {100 * DECAY_RESOLUTION:g}% or more "
        f"{DECAY_SIGNIFICANCE:g} standard errors below zero (a uniform chain's solitary wave keeps its amplitude)"
    )


def exponential_decay(contacts: np.ndarray, force: np.ndarray) -> tuple[float, float, float] | str:
    """(A (N), L (contacts), L's standard error) of F = A exp(-i / L), or why there is no decay."""
    fit = fit_log_line(contacts, force)
    why = why_no_decay(fit, contacts)
    if why:
        return why
    return float(np.exp(fit.intercept)), -1.0 / fit.slope, fit.stderr / fit.slope**2


def power_law_decay(contacts: np.ndarray, force: np.ndarray) -> tuple[float, float, float] | str:
    """(A (N), p, p's standard error) of F = A i^-p, or why there is no decay."""
    x = np.log(np.asarray(contacts, dtype=float))
    fit = fit_log_line(x, force)
    why = why_no_decay(fit, x)
    if why:
        return why
    return float(np.exp(fit.intercept)), -fit.slope, fit.stderr


def window_leading_pulses(scene, solution) -> tuple[np.ndarray, np.ndarray, str]:
    """The window's contacts with a passed leading pulse above their static force (1-based), those
    pulses (N), and why fewer than FIT_CONTACTS of them are there ("" otherwise)."""
    a, b = scene.window
    contacts = np.arange(a, b + 1)
    lead = np.asarray(solution.leading_pulse_force, dtype=float)[contacts - 1]
    dynamic = lead - scene_static_forces(scene)[contacts - 1]  # each contact's own (gravity: the weight above)
    ok = np.isfinite(dynamic) & (dynamic > 0)
    why = ""
    if np.sum(ok) < FIT_CONTACTS:
        why = (
            f"{int(np.sum(ok))} of the window's contacts {a}-{b} have a passed leading pulse; the decay fit needs "
            f"{FIT_CONTACTS}: run longer (or widen [outputs] window)"
        )
    return contacts[ok], dynamic[ok], why


class _DecayFit(Observable):
    """What the two decay fits share: their data, where they apply, their error bar's route."""

    unit = "1"
    needs = frozenset({"leading_pulses"})
    compared = True
    error_bar = "the time step's error from the companion runs and the fit's standard error, in quadrature"
    applies_where = f"a measurement window of {FIT_CONTACTS} contacts or more"
    #: the fit (exponential_decay or power_law_decay) and its companions' names: amplitude, stderr
    law = staticmethod(exponential_decay)
    amplitude: str
    stderr: str

    def applies(self, scene) -> str | None:
        """None where the window has FIT_CONTACTS contacts or more (fit.window_unfittable)."""
        return super().applies(scene) or window_unfittable(scene, "the leading pulse's decay fit")

    def measure(self, scene, solution) -> Measurement:
        """The fitted constant, its amplitude and standard error, or None and why."""
        contacts, force, why = window_leading_pulses(scene, solution)
        fields = {self.amplitude: None, self.stderr: None}
        if why:
            return Measurement(None, fields, why)
        fit = self.law(contacts, force)
        if isinstance(fit, str):
            return Measurement(None, fields, fit)
        return Measurement(fit[1], {self.amplitude: fit[0], self.stderr: fit[2]})


class LeadingPulseDecayLength(_DecayFit):
    """The decay length L of F_lead(i) = A exp(-i / L) over the window (see the module docstring)."""

    name = "leading_pulse_decay_length"
    unit = "contacts"
    definition = (
        "L of a least-squares fit ln F = ln A - i / L of the window's leading pulses (above F0) against "
        "contact i; None where they do not decay"
    )
    companions = {
        "leading_pulse_decay_amplitude": "N",
        "leading_pulse_decay_length_stderr": "contacts",
        "leading_pulse_decay_contacts": "contacts fitted",
    }
    amplitude, stderr = "leading_pulse_decay_amplitude", "leading_pulse_decay_length_stderr"
    shares_reason = (amplitude, stderr)
    table_fields = (stderr, "leading_pulse_decay_contacts")
    field_kinds: ClassVar[dict[str, str]] = {"leading_pulse_decay_contacts": "integer"}
    fit_stderr = stderr

    def measure(self, scene, solution) -> Measurement:
        """The decay length and its companions, with the count of leading pulses fitted."""
        m = super().measure(scene, solution)
        m.fields["leading_pulse_decay_contacts"] = int(window_leading_pulses(scene, solution)[0].size)
        return m


class LeadingPulseDecayExponent(_DecayFit):
    """The exponent p of F_lead(i) = A i^-p over the window (see the module docstring)."""

    name = "leading_pulse_decay_exponent"
    definition = (
        "p of a least-squares fit ln F = ln A - p ln i of the window's leading pulses (above F0) against "
        "contact i; None where they do not decay"
    )
    companions = {"leading_pulse_power_amplitude": "N", "leading_pulse_decay_exponent_stderr": "1"}
    amplitude, stderr = "leading_pulse_power_amplitude", "leading_pulse_decay_exponent_stderr"
    shares_reason = (amplitude, stderr)
    table_fields = (stderr,)
    fit_stderr = stderr
    law = staticmethod(power_law_decay)
