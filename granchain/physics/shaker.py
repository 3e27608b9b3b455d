"""The shaker ([loading] kind = "shaker"): a rigid flat driver against bead 1 whose position is prescribed.

The driver is a rigid flat (a far-end wall's twin at the loaded end) touching bead 1 through the
scene's contact law and damping (the law of a bead on a rigid flat: R* = R, E* = E / (1 - nu^2), as
the wall's). Its position is

    x_d(t) = x_d0 + A sin(2 pi f t) r(t)        for 0 <= t <= T,

with r the sin^2 switch-on of the harmonic force drive (granchain.physics.harmonic.ramp_factor: r
and r' vanish at t = 0, so the driver starts at rest) and x_d0 where it holds the static force F0 of a
precompression (touching bead 1 unloaded without one). At T the driver stops where it is and holds
there. It pushes bead 1 through the contact and loses it where the contact opens: it never pulls.

The solvers integrate it as an extra bead in front of bead 1 of infinite mass whose acceleration is
prescribed, x_d''(t) (shaker_acceleration), from x_d(0) = x_d0 and x_d'(0) = A 2 pi f r(0): the
method's own quadrature of the driver's motion, of the method's order (RK4: Simpson's rule on the
stages, velocity Verlet: its kicks), the same numbers on both backends for Verlet.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["shaker_acceleration", "shaker_displacement", "shaker_velocity"]


def _ramp_terms(t, ramp_time: float):
    """r, r' and r'' of the sin^2 switch-on at t (arrays): r = sin^2(h t), h = pi / (2 t_r), before t_r."""
    t = np.asarray(t, dtype=float)
    if ramp_time <= 0.0:
        return np.ones_like(t), np.zeros_like(t), np.zeros_like(t)
    h = 0.5 * math.pi / ramp_time
    on = t < ramp_time
    s = np.clip(t, 0.0, ramp_time)
    r = np.where(on, np.sin(h * s) ** 2, 1.0)
    r1 = np.where(on, h * np.sin(2.0 * h * s), 0.0)
    r2 = np.where(on, 2.0 * h * h * np.cos(2.0 * h * s), 0.0)
    return r, r1, r2


def _inside(t, duration: float, out):
    t = np.asarray(t, dtype=float)
    out = np.where((t >= 0.0) & (t <= duration), out, 0.0)
    return float(out) if out.ndim == 0 else out


def shaker_displacement(t, amplitude: float, frequency: float, ramp_time: float, duration: float):
    """The driver's displacement from x_d0, A sin(2 pi f t) r(t) on [0, T] (0 outside; after T the driver
    holds at its value at T), m.

    Parameters
    ----------
    t : float or array_like
        Time, s.
    amplitude : float
        A, m.
    frequency : float
        f, Hz.
    ramp_time : float
        t_r, the switch-on's length, s (0: none).
    duration : float
        T, the drive's length, s.

    Returns
    -------
    float or ndarray
        x_d(t) - x_d0 (for t > T: 0 here; the caller holds the value at T).
    """
    w = 2.0 * math.pi * frequency
    r, _, _ = _ramp_terms(t, ramp_time)
    return _inside(t, duration, amplitude * np.sin(w * np.asarray(t, dtype=float)) * r)


def shaker_velocity(t, amplitude: float, frequency: float, ramp_time: float, duration: float):
    """The driver's velocity x_d'(t) = A (w cos(w t) r + sin(w t) r') on [0, T], 0 outside, m/s
    (arguments as shaker_displacement)."""
    w = 2.0 * math.pi * frequency
    t = np.asarray(t, dtype=float)
    r, r1, _ = _ramp_terms(t, ramp_time)
    return _inside(t, duration, amplitude * (w * np.cos(w * t) * r + np.sin(w * t) * r1))


def shaker_acceleration(amplitude: float, frequency: float, ramp_time: float):
    """x_d''(t) = A (-w^2 sin(w t) r + 2 w cos(w t) r' + sin(w t) r'') as a function of a float t inside
    (0, T], on Python floats (a solver calls it at every stage of every step).

    Parameters
    ----------
    amplitude, frequency, ramp_time : float
        A (m), f (Hz) and t_r (s), as shaker_displacement takes them.

    Returns
    -------
    callable
        t -> the driver's acceleration, m/s^2; the caller keeps t within [0, T].
    """
    w = 2.0 * math.pi * frequency
    a, w2 = float(amplitude), w * w
    h = 0.5 * math.pi / ramp_time if ramp_time > 0.0 else 0.0
    h2, h22 = 2.0 * h, 2.0 * h * h
    sin, cos = math.sin, math.cos

    def accel(t: float) -> float:
        s, c = sin(w * t), cos(w * t)
        if t < ramp_time:
            sr = sin(h * t)
            return a * (-w2 * s * sr * sr + 2.0 * w * c * h * sin(h2 * t) + s * h22 * cos(h2 * t))
        return -a * w2 * s

    return accel
