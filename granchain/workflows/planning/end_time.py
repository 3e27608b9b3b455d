"""The planner's end-time and stop choices: a chain's front past its last measured contact, a wall's
pulse, the reflection, one bead's impacts, and the stop check that ends a run once they are measured."""

from __future__ import annotations

import math

from granchain.integrators import INTEGRATORS
from granchain.physics.effects.base import watched_force
from granchain.physics.estimates import (
    expected_peak_force,
    one_bead_impacts,
    step_equivalent,
)
from granchain.scene import SceneError
from granchain.workflows.planning.choice import PlanChoice
from granchain.workflows.planning.travel import (
    PRECOMPRESSED_TAIL,
    extension_budget,
    front_travel_time,
    leading_edge_speed,
    precompressed_front_time,
    wave_speeds,
)


def _one_bead_end_time(scene, impacts) -> PlanChoice:
    """A one-bead (or two free beads') scene's end time: 1.5 x its impacts' contact times, after the load."""
    load = scene.loading.duration if scene.loading.is_force else 0.0
    end = load + 1.5 * sum(i["duration"] for _, i in impacts)
    return PlanChoice(
        "end_time",
        end,
        f"{'one bead' if scene.chain.beads == 1 else 'two free beads'}: 1.5 x the contact time of "
        + " then ".join(f"the {name}'s impact ({i['duration']:.3g} s)" for name, i in impacts)
        + (f", after a load of {load:.3g} s" if load else ""),
    )


#: a maximum is seen once the force has fallen after it: within two time steps of it (the sample past the
#: maximum's own, which may fall a step after the maximum). The end time allows two of the largest stable
#: step of either integrator (IntegratorFacts.stability / omega_max), so that it does not depend on the integrator: both
#: backends of a compare end together
PEAK_DETECTION_STEPS = 2


def _front_end_time(scene, last: int | None, slow: float, omega_max: float) -> PlanChoice:
    """The end time of a chain: the slowest leading front passes the last measured contact
    (front_travel_time), after a long load; at least the pulse of an impulse and the last snapshot. A
    precompressed chain's front time is its linearised chain's first maximum (precompressed_front_time),
    which the run sees PEAK_DETECTION_STEPS time steps later (steps of either integrator up to its
    stability limit at omega_max)."""
    if last is None:
        raise SceneError(
            f'{scene.source}: end_time = "auto" needs the contacts you measure: give [outputs] '
            "window, histories or a peak_force list"
        )
    ld = scene.loading
    step = step_equivalent(scene)
    load = step[1] if step is not None and step[1] < 1e3 else 0.0
    travel = front_travel_time(scene, last, slow)
    # a long load's leading peak trails its front; a precompressed chain's front is sonic, its
    # peak forms within a few periods of it (dispersion): at most PRECOMPRESSED_TAIL of the travel
    cap, cap_text = (
        (PRECOMPRESSED_TAIL * travel, f"{PRECOMPRESSED_TAIL:g} x the travel under precompression")
        if scene.effects.precompression
        else (travel, "the travel")
    )
    tail = min(load, cap)
    end = travel + tail
    # the reason states the arithmetic that gives the end, one term at a time
    sums = [f"{travel:.3g} s to pass contact {last}"]
    if tail:
        sums.append(
            f"{tail:.3g} s for the leading peak, which trails the front under a load (the load's {load:.3g} s, "
            f"at most {cap_text})"
        )
    notes = []
    if step is not None and scene.effects.precompression and scene.has_contacts:
        sonic = precompressed_front_time(scene, last), precompressed_front_time(scene, last, step=True)
        if sonic[0] <= travel:  # the travel is the linearised chain's (the load is small against F0)
            # a lasting force's first maximum trails a kick's by more than that tail near the loaded end
            # (STEP_LAG); a pulse's comes no later than a step's, nor than the load's end after the front
            later = min(float(sonic[1]), travel + step[1])
            if later > end:
                end = later
                sums = [
                    f"{later:.3g} s for the first maximum under the load to pass contact {last} (the chain "
                    "linearised about F0; later than the front and its peak's tail)"
                ]
    if scene.effects.precompression:
        seen = PEAK_DETECTION_STEPS * max(f.stability for f in INTEGRATORS.values()) / omega_max
        end += seen
        sums.append(f"{seen:.3g} s to see it ({PEAK_DETECTION_STEPS} of the largest stable steps)")
    if ld.kind == "impulse" and end < ld.duration:
        end = ld.duration  # an impulse is measured whole: the run lasts at least the pulse
        notes.append(f"at least the pulse ({ld.duration:.3g} s)")
    if scene.outputs.snapshots and end < max(scene.outputs.snapshots):
        end = max(scene.outputs.snapshots)  # every requested snapshot is taken
        notes.append(f"at least the last snapshot ({end:.3g} s)")
    arithmetic = " + ".join(sums) + "".join(f"; {n}" for n in notes)
    return PlanChoice(
        "end_time",
        end,
        f"the leading wave (no slower than {slow:.4g} m/s on the nominal chain"
        + (", each contact's own stiffness and masses" if scene.per_bead else "")
        + (", and the first maximum of the chain linearised about F0" if scene.effects.precompression else "")
        + f") passes contact {last} by {travel:.3g} s: t_end = {arithmetic} = {end:.3g} s",
    )


#: The wall's contact (bead N on the flat) is measured once its force has fallen back to half its peak
#: after the reflection: the front's hop from contact N-1 to it and the pulse's width there. A Hertz
#: solitary wave spans about five diameters (Nesterenko), so its force at a contact rises and falls
#: within about five contacts' travel; with the hop, WALL_PULSE_CONTACTS contacts' travel at the chain's
#: far end. Measured (reference RK4, stop check on the wall's contact): a striker on a 20-bead stainless
#: chain at F0 = 2e4 N (linear, dispersed: the slowest case) complete 2.1 of its last contact's times
#: after the end planned for contact N-1; unprecompressed chains long before that end (its slowest
#: front). On 40 generated walled chains (tests/test_wall_end.py) the planned end is 1.1 to 4.4x the time
#: the stop check ended the run (1.5 to 2 typical: the slowest front's own margin)
WALL_PULSE_CONTACTS = 6


def wall_peak_planned(scene) -> bool:
    """Whether "auto" plans the run to measure the wall's peak: a chain of given length on a wall whose
    peak forces are asked for ([outputs] peak_force), with a stop check (no snapshots), under a load that
    ends: a force load within the longest end a run is ever run to (extension_budget: LINEAR_HORIZON x
    the slowest front's crossing of the whole chain), a kick, or a striker. A force load lasting longer
    is a lasting force: it keeps pressing the
    wall, whose force need not fall back before its end has crossed the chain, and an end planned to
    that (_wall_end_time: the crossing after the whole load) would outlast any run the planner makes
    (a 40 N step for 1 s on 30 brass beads: 1.001 s, 8.8e5 steps, 4.2e9 with a dashpot, for a
    budget of 2.7e-3 s). The run then ends as without a wall, the wall's peak not measured."""
    if scene.effects.far_end != "wall" or not scene.outputs.peak_force or scene.outputs.snapshots:
        return False
    if scene.chain.beads is None or scene.n_contacts < 1:
        return False
    # the reflected wave, up to F0 + twice the expected force, must stay within what the run watch lets
    # the far end's contacts carry (watched_force): on a taper's micron end beads it would crush them, a
    # force the contact law does not describe; the run then ends at contact N-1 as without a wall
    far = scene.effects.precompression + 2.0 * expected_peak_force(scene)
    r = scene.bead_radii
    held = min(
        float(watched_force(scene.contact_laws[-1], min(r[-2], r[-1]))),
        float(watched_force(scene.wall_law, r[-1])),
    )
    if far > held:
        return False
    step = step_equivalent(scene)
    if step is None:
        return True
    if scene.loading.is_force:
        return step[1] <= extension_budget(scene, wave_speeds(scene)[0])
    # a striker's push ends by itself (its momentum over the piston force, step_equivalent): a heavy one
    # pushes for several crossings and the wall's peak completes when it has turned back (generated
    # heavy strikers on walls: 3.4-5.9 crossings of push, the wall's peak complete at 2.3-3.5 ms), the
    # stop check ending the run then; the absolute cap only keeps an absurd striker from planning years
    return step[1] < 1e3


def _wall_end_time(scene, choice: PlanChoice, measured: int, slow: float, omega_max: float) -> PlanChoice:
    """The end time that also measures the wall's peak (wall_peak_planned): the end planned for the
    chain's last contact N-1 (_front_end_time), or the slowest front's crossing to it after the whole
    load (a long load's end must cross the chain before the wall's force falls), plus
    WALL_PULSE_CONTACTS x that contact's own time on the slowest front; at least the end planned for
    the measured contacts (choice, up to contact `measured`)."""
    nc = scene.n_contacts
    last = choice if measured == nc else _front_end_time(scene, nc, slow, omega_max)
    travel = front_travel_time(scene, nc, slow)
    hop = travel - (front_travel_time(scene, nc - 1, slow) if nc > 1 else 0.0)
    # a long load presses the wall until its end has crossed the chain too
    step = step_equivalent(scene)
    load = step[1] if step is not None else 0.0
    wall = max(last.value, travel + load) + WALL_PULSE_CONTACTS * hop
    if wall <= choice.value:
        return choice
    return PlanChoice(
        "end_time",
        wall,
        f"{choice.reason}; the wall's contact {nc + 1} (bead {nc + 1} on the flat) measured: the end for contact "
        f"{nc} ({last.value:.3g} s), or the load's end crossing the chain ({travel + load:.3g} s), and "
        f"{WALL_PULSE_CONTACTS} x contact {nc}'s time on that front ({hop:.3g} s), the hop to the wall and the "
        "pulse's rise and fall there",
    )


def _beads_choice(scene, end: float, last: int, fast: float) -> PlanChoice:
    """The number of beads: no reflection from bead N reaches contact `last` before the end (see
    granchain.workflows.plan's docstring)."""
    lead, d = leading_edge_speed(scene), scene.diameter
    n = math.ceil(1.1 * (end + last * d / fast) / (d / lead + d / fast)) + 5
    n = max(n, last + 5)
    return PlanChoice(
        "beads",
        n,
        f"a reflection from bead N (into the chain at up to {lead:.4g} m/s, back at up to "
        f"{fast:.4g} m/s) reaches contact {last} after t_end = {end:.3g} s: "
        "N > (t_end + L D / c_back) / (D / c_lead + D / c_back), +10% and 5 beads",
    )


def reflection_planned(scene) -> bool:
    """Whether the planned run waits for the wall's reflection to pass back through contact 1 ([run]
    stop_after_reflection): an uncompressed chain of given length against a wall whose wall's peak is
    planned (wall_peak_planned), end time "auto", the stop check the planner's or one that asks for it.
    There the reflection can exceed a contact's incoming peak (peaks.reflection_pending), and a run
    that stopped once the wave had passed the wall would leave those peaks not complete."""
    run = scene.run
    own = run.stop_after_contact is None and not scene.outputs.snapshots
    return (
        run.end_time is None
        and (own or run.stop_after_reflection)
        and scene.chain.beads is not None
        and not scene.effects.precompression
        and wall_peak_planned(scene)
    )


#: the planned end's time for the wall's reflection to come back to contact 1, in crossings of the
#: chain by the slowest expected front: the reflected front is weaker (slower: speed ~ F^(1/6)) and a
#: dimer scatters it; a cap only, the stop check ends the run once the reflection has passed
REFLECTION_CROSSINGS = 2.0


def _reflection_end_time(scene, choice: PlanChoice, slow: float) -> PlanChoice:
    """The end time that also lets the wall's reflection pass back through contact 1
    (reflection_planned): the wall's end (choice) and REFLECTION_CROSSINGS x the slowest front's
    crossing of the chain."""
    back = REFLECTION_CROSSINGS * front_travel_time(scene, scene.n_contacts, slow)
    return PlanChoice(
        "end_time",
        choice.value + back,
        f"{choice.reason}; and the wall's reflection back through contact 1 (uncompressed: it can exceed a "
        f"contact's incoming peak): {REFLECTION_CROSSINGS:g} x the slowest front's crossing of the chain "
        f"({back:.3g} s), a cap: the stop check ends the run once the reflection has passed",
    )


def _stop_choice(scene, last: int) -> PlanChoice:
    """The stop check (_contact_stop_choice), which with [outputs] event also waits for the wall's event's end."""
    choice = _contact_stop_choice(scene, last)
    if not scene.wall_event:
        return choice
    return PlanChoice(
        choice.name,
        choice.value,
        f"{choice.reason}; and the wall's event to its end ([outputs] event: the chain has left the wall for good)",
    )


def _contact_stop_choice(scene, last: int) -> PlanChoice:
    """The stop check at the last measured contact, and at the wall's contact (stop_after_wall) where
    the wall's peak is measured (wall_peak_planned), and the reflection's return through contact 1
    (stop_after_reflection) where reflection_planned."""
    if reflection_planned(scene):
        return PlanChoice(
            "stop_after_contact",
            last,
            f"stop as soon as the leading wave has passed contact {last} and the wall's contact (bead "
            f"{scene.n_contacts + 1} on the flat; stop_after_wall), and the wall's reflection has passed back "
            "through contact 1 (its force after the wall's risen and back below half of its largest: "
            "stop_after_reflection), both backends: on an uncompressed chain the reflection can exceed a "
            "contact's incoming peak",
        )
    if wall_peak_planned(scene):
        return PlanChoice(
            "stop_after_contact",
            last,
            f"stop as soon as the leading wave has passed contact {last} (its force below half its peak) and the "
            f"wall's contact (bead {scene.n_contacts + 1} on the flat, its force below half its peak after the "
            "reflection: stop_after_wall), both backends: the wall's peak is asked for (peak_force)",
        )
    return PlanChoice(
        "stop_after_contact",
        last,
        f"stop as soon as the leading wave has passed contact {last} (its force below half its peak), both backends",
    )


#: the planned end's time for the wall's event to end (granchain.physics.event), in crossings of the
#: chain by the slowest expected front, after the wall's end and a load's or a striker's push: the
#: reflected wave must come back through the chain until every body moves away from the wall (a heavy
#: striker turned back). A cap only: the stop check ends the run at the event's end. Measured (reference
#: Verlet, tests/test_event.py's generated walled chains of 4-10 beads, kicks and strikers up to 8x a
#: bead's mass, tapers, precompression): the event ended 1.0 to 3.5 crossings after t = 0
EVENT_CROSSINGS = 10.0


def event_planned(scene) -> bool:
    """Whether "auto" plans the run to the wall's event's end: [outputs] event on a walled chain of
    given length whose wall's peak is planned (wall_peak_planned: a load that ends)."""
    return scene.wall_event and wall_peak_planned(scene)


def _event_end_time(scene, choice: PlanChoice, slow: float) -> PlanChoice:
    """The end time that also covers the wall's event (event_planned): the wall's end (choice), a load's
    or a striker's push (step_equivalent), and EVENT_CROSSINGS x the slowest front's crossing."""
    step = step_equivalent(scene)
    push = step[1] if step is not None else 0.0
    crossing = front_travel_time(scene, scene.n_contacts, slow)
    back = push + EVENT_CROSSINGS * crossing
    return PlanChoice(
        "end_time",
        choice.value + back,
        f"{choice.reason}; and the wall's event to its end ([outputs] event: the chain has left the wall for good): "
        f"the push ({push:.3g} s) and {EVENT_CROSSINGS:g} x the slowest front's crossing of the chain "
        f"({EVENT_CROSSINGS * crossing:.3g} s), a cap: the stop check ends the run at the event's end",
    )


def _harmonic_end_time(scene, last: int | None, slow: float, omega_max: float) -> PlanChoice:
    """A harmonic drive's end time: the drive's length T, then the slowest front's transit of the chain
    (to its last contact; to the last measured one on an "auto" chain), so that the last of the drive
    reaches its end; under precompression also PEAK_DETECTION_STEPS of the largest stable steps."""
    ld = scene.loading
    to = scene.n_contacts if scene.chain.beads is not None and scene.has_contacts else last
    transit = front_travel_time(scene, to, slow) if to else 0.0
    seen = PEAK_DETECTION_STEPS * max(f.stability for f in INTEGRATORS.values()) / omega_max
    end = ld.duration + transit + seen
    return PlanChoice(
        "end_time",
        end,
        f"a harmonic drive of {ld.duration:.3g} s ({ld.cycles:.4g} cycles at {ld.frequency:.4g} Hz), then its "
        f"last part's transit to contact {to} on the slowest expected front ({slow:.4g} m/s: {transit:.3g} s), and "
        f"{seen:.3g} s to see it ({PEAK_DETECTION_STEPS} of the largest stable steps): t_end = {end:.3g} s",
    )


def end_time_choice(scene, last: int | None, slow: float, omega_max: float) -> PlanChoice:
    """The planned end time: one bead's (or two free beads') impacts, a harmonic drive's length and the
    chain's transit, else the front past the last measured contact, then the wall's pulse and the
    reflection where they are planned."""
    if scene.loading.is_harmonic:
        return _harmonic_end_time(scene, last, slow, omega_max)
    impacts = one_bead_impacts(scene)
    if impacts:
        return _one_bead_end_time(scene, impacts)
    choice = _front_end_time(scene, last, slow, omega_max)
    # only where the stop check waits for the wall: the planner's own (plan_scene's) or a given one
    # with stop_after_wall; a given stop without it ends the run before the wall's peak
    waits = scene.run.stop_after_contact is None or scene.run.stop_after_wall
    if waits and wall_peak_planned(scene):
        choice = _wall_end_time(scene, choice, last, slow, omega_max)
    if reflection_planned(scene):
        choice = _reflection_end_time(scene, choice, slow)
    if waits and event_planned(scene):
        choice = _event_end_time(scene, choice, slow)
    return choice
