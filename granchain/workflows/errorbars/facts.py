"""What the error bars read of the integrator and the law, and the companions' steps and price.

The orders an integrator's error can show on a scene (onset_order, expected_orders, integrator_order),
whether its law's kinks make the error erratic (kinked_law), the companion scenes and their steps, and
the steps and price of the RK4 runs a Verlet run is measured against (against_rk4_factors,
rk4_companions_cost).
"""

from __future__ import annotations

from dataclasses import replace

from granchain.integrators import RK4, integrator
from granchain.postprocess.observables.spectral import far_end_contact


def onset_order(scene) -> float:
    """The order of an integrator's error where a contact of the scene closes: the nominal law's
    declared ContactLaw.onset_order (1 + n of its onset F ~ alpha^n, the smallest over its contacts:
    2.5 for Hertz and Thornton, 1 + n for the power law, the bilinear loading line's measured 2.5)."""
    return scene.law.onset_order()


def reference_order(scene) -> float:
    """The lowest order of RK4's error on the scene, at which a Verlet run's RK4 references take their
    own error (richardson.against_reference): its onset's (onset_order: 1 + n, 2.5 on the kinked
    Hertzian-onset laws and the bilinear loading line), at most RK4's order."""
    return float(min(onset_order(scene), RK4.order))


def expected_orders(method: str, scene) -> tuple[float, float]:
    """The lowest and highest order the integrator's error can show on this scene (richardson): from
    the lower of its order on the scene (integrator_order: Verlet's 1 with a velocity-dependent
    damping force, its first-order
    term mixing with Verlet's second) and the onset's (onset_order), to its order."""
    return float(min(onset_order(scene), integrator_order(method, scene))), float(integrator(method).order)


def integrator_order(method: str, scene) -> int:
    """The order the error estimate assumes (see granchain.workflows.error_estimates' docstring): the
    integrator's, or its order with a velocity-dependent damping force
    (IntegratorFacts.damping_order)."""
    facts = integrator(method)
    return facts.damping_order if scene.damping.velocity_dependent else facts.order


def companion_scene(scene, factor: float):
    """The scene at factor x its time step, with no outputs that no estimate needs: under a harmonic
    drive the histories its spectral observables read (postprocess.observables.spectral: the far end's;
    spatial: every contact's, as the run keeps them), at the run's interval (at least the companion's
    step)."""
    o = scene.outputs
    step = scene.run.timestep * factor
    driven = scene.loading.is_harmonic and scene.n_contacts and isinstance(o.history_interval, float)
    histories = tuple(c for c in o.histories if 1 <= c <= scene.n_contacts) if driven else ()
    if driven and far_end_contact(scene) not in histories:
        histories += (far_end_contact(scene),)
    interval = max(o.history_interval, step) if driven else None
    return replace(
        scene,
        run=replace(scene.run, timestep=step),
        outputs=replace(o, histories=histories, snapshots=(), history_interval=interval, dump_interval=None),
    )


def kinked_law(method: str, scene) -> bool:
    """Whether this is a run of an integrator that does not locate kinks (IntegratorFacts.locates_kinks:
    Verlet) on a law whose slope jumps at kinks the contacts cross (ContactLaw.slope_kinks: bilinear,
    Thornton), without velocity-dependent damping: its error in dt is erratic in sign."""
    from granchain.physics.laws import law_class

    locates = integrator(method).locates_kinks
    return not locates and not scene.damping.velocity_dependent and bool(law_class(scene.contact.law).slope_kinks)


def companion_steps(scene, factor: float) -> int:
    """The steps a companion of this concrete scene at factor x its time step takes to its end time
    (schedule.scene_step_plan; fewer where a stop check ends it earlier)."""
    from granchain.schedule import scene_step_plan

    return sum(g.steps for g in scene_step_plan(companion_scene(scene, factor)))


#: the RK4 companions a Verlet run is measured against aim at this fraction of the Verlet run's
#: predicted error (the planner's error model): small beside the distance they measure
#: (richardson.REFERENCE_SHARE checks it run by run: where it is not, no estimate), at the largest
#: step that reaches it. RK4's error goes as h^4, so this share sets the step only weakly (0.02 -> 0.1:
#: 1.5x the step). Measured on the bundled bilinear and Thornton short impulses (LAMMPS, planned for
#: rtol 1e-3, true error against dt / 8): at 0.02, 59 of 59 and 39 of 39 peaks estimated; at 0.1, 58
#: and 36, every one within 0.65-1.7 of the true error, for about two thirds of the RK4 steps; at 0.25,
#: 58 and 33 (docs/error-bars.md)
RK4_COMPANION_SHARE = 0.1
#: below this many dt the RK4 companions stay at 2 dt and 4 dt: the reference's own companions there
#: (granchain compare makes each run once for both backends) cost less than slightly coarser new ones
SHARED_BELOW = 3.0


#: what an RK4 step of the reference costs in numpy, in steps of its Verlet (four force evaluations to
#: one, but both pay the same per-step bookkeeping, and a kink crossing costs RK4 two more tries):
#: measured 3.3 on plastic-short-impulse and 2.5 on thornton-short-impulse (bench_errorbar_price.py,
#: 2026-11-27: the RK4 companions' time over the Verlet run's, times their steps' share)
RK4_STEP_COST = 3.3


def rk4_companions_cost(scene) -> float:
    """What the RK4 runs a numpy Verlet run of this scene is measured against cost, as a share of that
    run: their two steps' shares of its steps (against_rk4_factors) times RK4_STEP_COST."""
    return RK4_STEP_COST * sum(1.0 / f for f in against_rk4_factors(scene))


def against_rk4_factors(scene) -> tuple[float, float]:
    """The steps (as multiples of the run's dt) of the RK4 runs a Verlet run is measured against: RK4's
    planned step for RK4_COMPANION_SHARE of the Verlet run's predicted error, and twice it (its own
    error), within RK4's stability, where that is at least SHARED_BELOW dt; else 2 dt and 4 dt, or dt
    and 2 dt where 4 dt is unstable."""
    from granchain.workflows.plan import accurate_timestep, highest_frequency, predicted_error

    omega = highest_frequency(scene)[0]
    dt = scene.run.timestep
    stable = RK4.stability / omega
    h = accurate_timestep("rk4", omega, 0.0, RK4_COMPANION_SHARE * predicted_error("verlet", omega, 0.0, dt))
    h = min(h, 0.5 * stable)
    if h >= SHARED_BELOW * dt:
        return (h / dt, 2.0 * h / dt)
    return (2.0, 4.0) if 4 * dt <= stable else (1.0, 2.0)
