"""The struck contact's onset term, which Richardson over dt, 2 dt and 4 dt cannot see.

A contact that closes at t = 0 at a rate (bead 1 given a velocity, or a striker's contact) has a
force that grows as t^n from the first step, which every run starts at a step boundary. RK4's velocity
update weighs its stages as Simpson's rule, which is exact for t, t^2 and t^3 but errs on t^n
otherwise: the first steps' quadrature errors sum to a velocity error of the closing motion

    e_v = S_n a h^(1 + n),   a = K v^n / m*,   S_n = sum_k [Simpson_k(t^n) - integral_k(t^n)]

(onset_constant; K v^n the force at unit time, m* the pair's reduced mass, h the step), which lowers
the impact's peak force by (2n / (n + 1)) e_v / v (the impact's peak goes as v^(2n/(n+1))): at
n = 1.2, h = T / 20 of the contact time T, 4.5e-5 of it, as the two-body impact's distance to its
closed form measured (benchmarks/RESULTS.md, 2026-12-03). The wave carries that error to every
contact. Its order 1 + n is below RK4's 4 but its constant is small, so at the planned step it can
hide behind the fourth-order term at dt, 2 dt and 4 dt (which grows 2^(4 - 1 - n) times faster with
the step) and take over below dt: on a disorder chain struck at n = 1.2 the runs showed order 4-5,
and two bars were 0.21 and 6.5 of the true error (the two terms of opposite sign at dt).

Where the struck contact is a bead-bead one whose own bar, taken at an order above the onset's (by
more than richardson.ORDER_SLACK), is below MAX_OVERESTIMATE times this term (unseen: the companions
missed it where the two-body model holds), a bar at such an order is kept only where the term at its
value is below 1 / MAX_OVERESTIMATE of it, else withheld with a status that says why
(withhold_hidden). The struck contact decides, not the term alone: its reach down the chain is not the
two-body model's (effect-striker, effect-gravity: the term alone would have withheld 38 and 39 bars
within [1/3, 3]; docs/error-bars.md). Integer n (1, 2, 3) has S_n = 0: Simpson is exact there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import zeta

from granchain.problem import ChainProblem, initial_state
from granchain.richardson import MAX_OVERESTIMATE, ORDER_SLACK, ErrorBars

#: the steps of onset_constant's sum taken one by one; beyond, the Simpson error term h^5 f''''/2880
#: of each step, summed by Hurwitz's zeta function (their sum to 1e-7 of S_n at 64 steps)
SUMMED_STEPS = 64


def onset_constant(n: float) -> float:
    """S_n: the summed error of Simpson's rule on t^n over the unit steps [k, k + 1], k = 0, 1, ...
    (2.36e-3 at n = 1.2, 2.49e-3 at n = 3/2, -9.2e-4 at n = 2.2; 0 at n = 1, 2, 3)."""
    if n == round(n) and 0 <= n <= 3:
        return 0.0
    k = np.arange(SUMMED_STEPS, dtype=float)
    simpson = (k**n + 4.0 * (k + 0.5) ** n + (k + 1.0) ** n) / 6.0
    exact = ((k + 1.0) ** (n + 1.0) - k ** (n + 1.0)) / (n + 1.0)
    tail = n * (n - 1.0) * (n - 2.0) * (n - 3.0) / 2880.0 * float(zeta(4.0 - n, SUMMED_STEPS + 0.5))
    return float(np.sum(simpson - exact)) + tail


@dataclass(frozen=True)
class HiddenOnset:
    """The struck contact whose onset term is largest: its name, n, closing rate and the term's size
    relative to the impact's force at the run's step (see the module docstring)."""

    contact: str
    exponent: float
    rate: float
    relative: float
    #: its index among the bead-bead contacts (0-based), None for the striker's or the wall's
    index: int | None = None

    @property
    def order(self) -> float:
        """1 + n: the term's order in dt."""
        return 1.0 + self.exponent


def hidden_onset(scene) -> HiddenOnset | None:
    """The struck contact (closing at t = 0 at a rate) with the largest onset term at the scene's step,
    or None where no contact closes so or every struck one has integer n."""
    h = scene.run.timestep
    if not isinstance(h, float):  # (a scene not planned: its bars are the planned run's)
        return None
    problem = ChainProblem.from_scene(scene).with_ends()
    u, v, _ = initial_state(problem)
    alpha, rate = u[:-1] - u[1:], v[:-1] - v[1:]
    struck = np.flatnonzero((alpha == 0.0) & (rate > 0.0))
    if not struck.size:
        return None
    law = problem.law.per_contact(len(alpha))
    exponents = np.broadcast_to(law.loading_exponent(), alpha.shape)
    best = None
    for c in struck:
        n, w = float(exponents[c]), float(rate[c])
        near = w * h  # the overlap after a step, where the term is made: F = K alpha^n there
        k = float(law.contacts(len(alpha), int(c), int(c) + 1).loading_force(near)[0]) / near**n
        m1, m2 = problem.mass[c], problem.mass[c + 1]
        reduced = m1 if not np.isfinite(m2) else m1 * m2 / (m1 + m2)
        e_v = abs(onset_constant(n)) * k * w**n * h ** (1.0 + n) / reduced
        relative = 2.0 * n / (n + 1.0) * e_v / w
        if relative > 0.0 and (best is None or relative > best.relative):
            index = int(c) - problem.front
            if index >= problem.beads - problem.front - 1 - (problem.wall_law is not None):
                index = None  # (the wall's)
            best = HiddenOnset(
                _contact_name(problem, int(c), len(alpha)), n, w, relative, None if c < problem.front else index
            )
    return best


def _contact_name(problem, c: int, contacts: int) -> str:
    """How a status names contact c of the chain with its ends (a striker in front, a wall last)."""
    if c < problem.front:
        return "the striker's contact"
    if problem.wall_law is not None and c == contacts - 1:
        return "the wall's contact"
    return f"contact {c - problem.front + 1}"


def unseen(bars: ErrorBars | None, values, onset: HiddenOnset | None) -> bool:
    """Whether the companions missed the onset term where it is made: the struck contact (a bead-bead
    one) has a peak bar taken at an order above the onset's that is below MAX_OVERESTIMATE times the
    term (there the two-body model holds). A striker's or a wall's contact has its bar at the onset's
    own order (errorbars.bars.extrapolated_bars): the term is in it, and nothing is withheld."""
    if bars is None or onset is None or onset.index is None or onset.index >= len(bars.error):
        return False
    i = onset.index
    if not (np.isfinite(bars.error[i]) and bars.order[i] > onset.order + ORDER_SLACK):
        return False
    return bool(MAX_OVERESTIMATE * onset.relative * abs(float(np.atleast_1d(values)[i])) > bars.error[i])


def withhold_hidden(bars: ErrorBars | None, values, onset: HiddenOnset | None) -> None:
    """Withhold, in place, the bars of `values` (at dt) taken at an order above the onset's whose hidden
    onset term (onset.relative of the value) is above 1 / MAX_OVERESTIMATE of the bar, with a status
    saying why and the bar withheld."""
    if bars is None or onset is None:
        return
    v = np.abs(np.atleast_1d(np.asarray(values, dtype=float)))
    for i in np.flatnonzero(np.isfinite(bars.error) & (bars.order > onset.order + ORDER_SLACK)):
        term = onset.relative * v[i]
        if not MAX_OVERESTIMATE * term > bars.error[i]:
            continue
        bars.status[i] = (
            f"unreliable: {onset.contact} closes at {onset.rate:.3g} m/s at t = 0 (n = {onset.exponent:.3g}): its "
            f"onset errs as dt^{onset.order:.3g}, about {term:.3g} here, over 1/{MAX_OVERESTIMATE:g} of the bar, and "
            f"the runs at dt, 2 dt and 4 dt cannot see it (it takes over below dt); with order "
            f"{bars.order[i]:.2g} it would be {bars.error[i]:.3g}"
        )
        bars.error[i] = np.nan
        bars.order[i] = np.nan
