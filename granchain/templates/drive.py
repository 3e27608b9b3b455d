"""The harmonic drive (granchain.physics.harmonic) as a LAMMPS equal-style expression of the time, for
``fix addforce`` (templates/loading_harmonic.lmp.j2); the name of its work's energy column.

LAMMPS's equal-style formulas have no if: a comparison is 1 or 0, so the ramp is
(t < t_r) sin^2(...) + (t >= t_r).

(No momentum watch runs under a drive, granchain.invariants says why: the deck needs no formula of its
impulse.)
"""

from __future__ import annotations

import math

from granchain.templates.filters import float_repr

#: the energy samples' column of the drive's work (templates/loading_harmonic.lmp.j2), by name
DRIVE_WORK_COLUMN = "drive_work"


def drive_force_expression(loading, time: str = "time") -> str:
    """f(t) = A sin(2 pi f t) r(t), r the sin^2 ramp (1 from t_r on), as a LAMMPS expression of `time`.

    Parameters
    ----------
    loading : granchain.scene.Loading
        A harmonic load.
    time : str
        The expression of the time (LAMMPS's ``time``; a test's variable).

    Returns
    -------
    str
        The formula; the deck applies it only inside (0, T] (``unfix`` at T).
    """
    w, tr = 2.0 * math.pi * loading.frequency, loading.ramp_time
    f = f"{float_repr(loading.amplitude)}*sin({float_repr(w)}*{time})"
    if tr <= 0.0:
        return f
    h = 0.5 * math.pi / tr
    ramp = f"(({time}) < {float_repr(tr)})*sin({float_repr(h)}*{time})^2 + (({time}) >= {float_repr(tr)})"
    return f"{f}*({ramp})"


def driver_acceleration_expression(loading, time: str = "time") -> str:
    """A shaker's driver's x_d''(t) (granchain.physics.shaker.shaker_acceleration) as a LAMMPS expression.

    Parameters
    ----------
    loading : granchain.scene.Loading
        A shaker.
    time : str
        The expression of the time.

    Returns
    -------
    str
        A (-w^2 sin(w t) r + 2 w cos(w t) r' + sin(w t) r''), r the sin^2 ramp (1 from t_r on); the deck
        applies it only inside (0, T] (``unfix`` at T).
    """
    a, w, tr = loading.amplitude, 2.0 * math.pi * loading.frequency, loading.ramp_time
    steady = f"{float_repr(-a * w * w)}*sin({float_repr(w)}*{time})"
    if tr <= 0.0:
        return steady
    h = 0.5 * math.pi / tr
    s, c = f"sin({float_repr(w)}*{time})", f"cos({float_repr(w)}*{time})"
    ramp = (
        f"{float_repr(-a * w * w)}*{s}*sin({float_repr(h)}*{time})^2"
        f" + {float_repr(2.0 * a * w * h)}*{c}*sin({float_repr(2.0 * h)}*{time})"
        f" + {float_repr(2.0 * a * h * h)}*{s}*cos({float_repr(2.0 * h)}*{time})"
    )
    before = f"(({time}) < {float_repr(tr)})"
    return f"{before}*({ramp}) + (({time}) >= {float_repr(tr)})*{steady}"
