"""Why each error-bar strategy applies to a run: the predicates, each returning its reason or None.

Each reason is the measurement that chose the strategy (docs/error-bars.md); the strategies
(granchain.workflows.errorbars.strategies) ask these, in the registry's order.
"""

from __future__ import annotations

from granchain.integrators import integrator
from granchain.workflows.errorbars.facts import kinked_law, rk4_companions_cost


def withheld_because(method: str, scene) -> str | None:
    """Why no error bar is given for this integrator on this scene, or None.

    An integrator whose error follows no order with a velocity-dependent damping force
    (IntegratorFacts.unordered_with_damping; RK4: the damped force is clipped where it would pull, a
    kink in time RK4 does not locate, so its runs converge at no definite order). Measured on 14
    generated Hertz chains planned for rtol 1e-3 (/tmp experiment recorded in docs/error-bars.md): on
    the 9 with a dashpot 14 of 55 estimates were outside 1/3-3 of the true error (0.013-12x), although
    the three runs' differences looked like orders 1-5; on the 5 without, none of 51 (another sample of
    12 chains had 4 of about 100 outside, 0.21-3.5:
    RK4's Hertz onsets, docs/error-bars.md).
    """
    if scene.damping.velocity_dependent:
        return integrator(method).unordered_with_damping
    return None


def check_because(method: str, scene, checked: bool = False) -> str | None:
    """Why Richardson's bars of this run are checked against a run at dt / 2, or None (always None
    unless the check was asked for: ``checked``, error_estimate="checked").

    RK4 on a chain: its error mixes orders (1 + 3/2 at every Hertzian onset, with a coefficient that
    depends on where in a step the contact closes, 4 and the terms beyond), so the order the runs at
    dt, 2 dt and 4 dt show need not hold below dt. Measured on generated varied Hertz chains (reference
    RK4, planned for rtol 1e-3, true error against dt / 8; docs/error-bars.md): 8 of 243 estimates
    outside 1/3-3 of the true error (0.21-3.8), each where the order between dt and 2 dt (seen with the
    true value) was 2.1-2.3 or 5.6-5.8 while the three runs showed 3.9-4.8, or the error changed sign
    just below dt. The run at dt / 2 costs twice the run (richardson.checked).
    """
    if checked:
        return integrator(method).mixes_orders  # (IntegratorFacts.mixes_orders: RK4's, why)
    return None


#: what RK4's default bars (no run at dt / 2) say of themselves: measured on generated varied chains
#: (docs/error-bars.md, docs/measure_varied_error_ratios.py)
UNCHECKED_BY_DEFAULT = (
    "RK4's bars are not checked below dt by default: about 5% of them fell outside 1/3-3 of the true error "
    "on generated chains, where contacts open and close (docs/error-bars.md); --error-estimate checked "
    '(error_estimate="checked") checks each at dt / 2 and withholds one it contradicts, at twice the run'
)


def unchecked_because(method: str, scene) -> str:
    """Why a run's bars get no check at dt / 2 although it was asked for (error_estimate="checked").

    The check is RK4's (check_because): Verlet's error on a chain is of one order (2; 1 with a
    dashpot, expected_orders), which the runs at dt, 2 dt and 4 dt check already; a Verlet run whose
    law has kinks is then measured against RK4 runs, not extrapolated, so no order is assumed.
    """
    if against_rk4_because(method, scene, checked=True):
        return "its error is measured against RK4 runs (event location), not extrapolated: no check at dt / 2 needed"
    return (
        f"the check at dt / 2 is RK4's: {method}'s error is of one order, which the runs at dt, 2 dt and 4 dt "
        "check already"
    )


def bounded_because(method: str, scene) -> str | None:
    """Why this run's bars are bounds (richardson.erratic_bounds), not Richardson's estimates, or None.

    A law whose slope jumps at kinks a moving contact crosses gives fixed-step Verlet an error that
    depends on where in a step each contact crosses them: erratic in sign in dt (generated bilinear
    and Thornton chains without a dashpot, reference Verlet: the runs at dt, 2 dt, 4 dt changed sign
    on 14-22% of the peaks, Richardson's checks failed on 26-36%, and where they passed its estimate
    was below 1/3 of the true error on 6 of 1781, down to 0.07; docs/error-bars.md, "Verlet on the
    kinked laws" and "Bounds from dt, 2 dt, 4 dt"). The default bars are bounds from the same
    companions at 2 dt and 4 dt (3/4 of the run's steps), which may overstate the error many times and
    say so. With a dashpot Verlet is first order and Richardson stays (expected_orders).
    """
    if not kinked_law(method, scene):
        return None
    law = scene.contact.law
    return f"the {law} law's slope jumps at kinks the contacts cross, so Verlet's error is erratic in sign"


def one_companion_because(method: str, scene, checked: bool = False) -> str | None:
    """Why this run's bars are bounds from one companion at 2 dt (richardson.one_companion with
    BOUND_ORDER: |Q(dt) - Q(2 dt)|), or None (always None when checked bars were asked for, ``checked``).

    RK4 (event location) on a law whose slope jumps at kinks the contacts cross (ContactLaw.slope_kinks:
    bilinear, Thornton): each crossing costs a rejected try and the split piece in every run, so
    companions at 2 dt and 4 dt, 3/4 of the run's steps but its crossings twice, cost about 1.0-1.6 times
    the run (bench_errorbar_price.py); the one at 2 dt alone costs less than the run. An estimate from it
    needs an order assumed, and order 3 (0.43-2.14 of a clean order-2-4 error) did not hold: measured on
    generated chains against RK4 at dt / 4 (docs/error-bars.md, "RK4 on the kinked laws: one companion";
    docs/measure_kinked_rk4_companion.py), below 1/3 of the true error on 112 of 1 983 Thornton numbers
    (mostly times, whose error stalls or changes sign between 2 dt and dt) and, for forces, on 41 of 606
    Thornton peaks of a second sample and 3 of 59 on plastic-short-impulse. The bound |Q(dt) - Q(2 dt)|
    (below E(dt) / 3 only where E(2 dt) is within 2/3 - 4/3 of E(dt) with its sign) was below 1/3 of the
    true error on 0.2-1.3% of the numbers of each sample, and overstates the error about 10-15 times at
    the median, as Verlet's kinked bounds (bounded_because) about 6 times.
    """
    if checked or not integrator(method).locates_kinks or scene.damping.velocity_dependent:
        return None
    from granchain.physics.laws import law_class

    if not law_class(scene.contact.law).slope_kinks:
        return None
    return (
        f"the {scene.contact.law} law's kinks cost RK4 two more tries at every crossing, so runs at 2 dt and 4 dt "
        "would cost more than the run: bounds from the one at 2 dt alone"
    )


#: what RK4's default bars on a kinked law (one_companion_because) say of themselves
ONE_COMPANION_BY_DEFAULT = (
    "RK4's bars on a kinked law are bounds from one companion at 2 dt, |Q(dt) - Q(2 dt)|, about 10-15 times the "
    "error (at times 50 times or more; docs/error-bars.md); --error-estimate checked "
    '(error_estimate="checked") estimates it from runs at 2 dt and 4 dt with their order checks and a run at '
    "dt / 2, at about three times the run"
)


#: what a kinked law's default Verlet bars (bounded_because) say of themselves: what they leave and what
#: measures them instead
BOUNDED_BY_DEFAULT = (
    "Verlet's bars on a kinked law are bounds from the runs at 2 dt and 4 dt, about 6 times the error (at times "
    "30 times or more; docs/error-bars.md); --error-estimate checked "
    '(error_estimate="checked") measures it against RK4 runs (event location) instead, at several times a '
    "LAMMPS run's price"
)


def against_rk4_because(method: str, scene, checked: bool = False, numpy_speed: bool = False) -> str | None:
    """Why this Verlet run's error is measured against RK4 runs rather than by Richardson, or None
    (always None unless checked bars were asked for, ``checked``: error_estimate="checked", or the run's
    backend integrates at numpy's speed, ``numpy_speed``: Backend.numpy_speed).

    A law whose slope jumps at kinks a moving contact crosses (ContactLaw.slope_kinks: bilinear,
    Thornton) gives fixed-step Verlet an error that depends on where in a step each contact crosses
    them and follows no order in dt (plastic-short-impulse, reference Verlet: Richardson's three runs
    changed sign on 47 of 59 peaks; docs/error-bars.md). RK4 locates those kinks; it cannot with a dashpot
    (withheld_because), where Richardson stays. By default (bounded_because) a LAMMPS run's bars come
    from its own companions instead: RK4 runs in numpy cost some ten times a LAMMPS run. A reference
    Verlet run's RK4 companions give truthful bars, not bounds, and are its default where they cost at
    most the run (rk4_companions_cost; on the bundled plastic scenes 0.6-0.7 of it, against 0.9-1.1 for
    its own companions at 2 dt and 4 dt: bench_errorbar_price.py).
    """
    if not kinked_law(method, scene):
        return None
    if not checked and not (numpy_speed and rk4_companions_cost(scene) <= 1.0):
        return None
    return (
        f"the {scene.contact.law} law's slope jumps at kinks the contacts cross, so Verlet's error follows no order "
        "in dt: "
        "measured against RK4 (event location) at 2 dt, its own error from RK4 at 4 dt"
    )
