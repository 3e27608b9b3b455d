"""The harmonic force load ([loading] kind = "harmonic"): a sine drive on bead 1 switched on smoothly.

The drive adds to whatever static force already pushes bead 1 (a precompression's F0):

    f(t) = A sin(2 pi f t) r(t)          for 0 < t <= T, and 0 after,
    r(t) = sin^2(pi t / (2 t_r))         for t < t_r, and 1 after (r = 1 throughout when t_r = 0),

with T the drive's length (its cycles / f, the ramp included) and t_r the ramp's (its cycles / f).
The sin^2 switch-on is continuous with zero slope at t = 0 and at t_r (r' = (pi / 2 t_r) sin(pi t /
t_r)), so the drive's spectrum stays narrow about f and the chain reaches its steady response without
the broadband transient an abrupt start would launch (the standard tapered drive of linear response
measurements, e.g. Boechler et al., PRL 104, 244302 (2010), who drive precompressed chains below
and above their cutoff f_c = (1/pi) sqrt(k_lin / m)).

Its impulse has a closed form (product to sum: sin(w x) cos(b x) = [sin((w+b) x) + sin((w-b) x)] / 2,
with r = (1 - cos(b x)) / 2 and b = pi / t_r), which the run watches and the results' delivered
impulse use on both backends.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["drive_force", "drive_function", "drive_impulse", "ramp_factor"]


def ramp_factor(t, ramp_time: float):
    """The switch-on factor r(t): sin^2(pi t / (2 t_r)) before t_r, 1 from t_r on (and for t_r = 0).

    Parameters
    ----------
    t : float or array_like
        Time, s (t >= 0).
    ramp_time : float
        t_r, the ramp's length, s (0: no ramp).

    Returns
    -------
    float or ndarray
        r(t), between 0 and 1.
    """
    t = np.asarray(t, dtype=float)
    if ramp_time <= 0.0:
        out = np.ones_like(t)
    else:
        out = np.where(t < ramp_time, np.sin(0.5 * math.pi * np.clip(t, 0.0, ramp_time) / ramp_time) ** 2, 1.0)
    return float(out) if out.ndim == 0 else out


def drive_force(t, amplitude: float, frequency: float, ramp_time: float, duration: float):
    """The drive's force on bead 1, f(t) = A sin(2 pi f t) r(t) on 0 < t <= T, 0 elsewhere, N.

    Parameters
    ----------
    t : float or array_like
        Time, s.
    amplitude : float
        A, N.
    frequency : float
        f, Hz.
    ramp_time : float
        t_r, s.
    duration : float
        T, the drive's length, s.

    Returns
    -------
    float or ndarray
        f(t) (the static F0 not included: the precompression's own force).
    """
    t = np.asarray(t, dtype=float)
    on = (t > 0.0) & (t <= duration)
    out = np.where(on, amplitude * np.sin(2.0 * math.pi * frequency * t) * ramp_factor(t, ramp_time), 0.0)
    return float(out) if out.ndim == 0 else out


def _one_minus_cos_over(c: float, s):
    """(1 - cos(c s)) / c = 2 sin^2(c s / 2) / c, 0 for c = 0: the integral of sin(c x) over [0, s]
    (the sin^2 form keeps its digits where c s is small)."""
    if c == 0.0:
        return np.zeros_like(s)
    return 2.0 * np.sin(0.5 * c * s) ** 2 / c


def drive_impulse(t, amplitude: float, frequency: float, ramp_time: float, duration: float):
    """The drive's impulse delivered by t, the integral of f over [0, min(t, T)], N s (closed form).

    Parameters
    ----------
    t : float or array_like
        Time, s.
    amplitude, frequency, ramp_time, duration : float
        A (N), f (Hz), t_r (s) and T (s), as drive_force takes them.

    Returns
    -------
    float or ndarray
        I(t) = A [ (1/2) C(w, s) - (1/4) (C(w + b, s) + C(w - b, s)) + (cos(w t_r) - cos(w u)) / w ],
        s = min(t, t_r), u = min(max(t, t_r), T), w = 2 pi f, b = pi / t_r, C(c, s) = (1 - cos(c s)) / c.
    """
    t = np.clip(np.asarray(t, dtype=float), 0.0, duration)
    w = 2.0 * math.pi * frequency
    tr = min(ramp_time, duration)
    s = np.minimum(t, tr)
    ramp_part = np.zeros_like(t)
    if tr > 0.0:
        b = math.pi / tr
        ramp_part = 0.5 * _one_minus_cos_over(w, s) - 0.25 * (
            _one_minus_cos_over(w + b, s) + _one_minus_cos_over(w - b, s)
        )
    u = np.maximum(t, tr)
    # cos(w tr) - cos(w u) = 2 sin(w (u + tr) / 2) sin(w (u - tr) / 2), exact where u = tr
    steady = 2.0 * np.sin(0.5 * w * (u + tr)) * np.sin(0.5 * w * (u - tr)) / w
    out = amplitude * (ramp_part + steady)
    return float(out) if out.ndim == 0 else out


def drive_function(amplitude: float, frequency: float, ramp_time: float, scale: float = 1.0):
    """scale x f(t) as a function of a float t inside the drive's time (0, T], on Python floats (a
    solver calls it at every stage of every step: the numpy drive_force costs ten times more a call).

    Parameters
    ----------
    amplitude, frequency, ramp_time : float
        A (N), f (Hz) and t_r (s), as drive_force takes them.
    scale : float
        A factor on the force (1 / m of bead 1: its acceleration).

    Returns
    -------
    callable
        t -> scale A sin(2 pi f t) r(t); the caller keeps t within (0, T].
    """
    w, a = 2.0 * math.pi * frequency, scale * amplitude
    h = 0.5 * math.pi / ramp_time if ramp_time > 0.0 else 0.0
    sin = math.sin

    def f(t: float) -> float:
        if t < ramp_time:
            r = sin(h * t)
            return a * sin(w * t) * r * r
        return a * sin(w * t)

    return f
