"""Reading each section of a scene: [chain] (with its materials), [contact], [loading], [run],
[outputs] and the registered effects' sections, each into its dataclass of granchain.scene.model."""

from __future__ import annotations

import math
from typing import Any

from granchain.physics import materials as mat
from granchain.physics.effects import sections
from granchain.physics.laws import law_class
from granchain.scene.limits import (
    AUTO,
    DURATION_TEXT,
    LAWS,
    LOADING_KINDS,
    MAX_BEADS,
    MAX_TIME,
    MAX_VARIED_BEADS,
    MIN_DURATION,
    MIN_TIMESTEP,
    TIME_TEXT,
)
from granchain.scene.model import Chain, Contact, Effects, Loading, Outputs, Run
from granchain.scene.section import SceneError, _did_you_mean, _Section


def _read_effects(source: str, data: dict) -> Effects:
    """The sections of the registered effects (granchain.physics.effects) the scene has."""
    fields: dict[str, Any] = {}
    for name, effect in sections().items():
        if name in data:
            fields.update(effect.read(_Section(source, name, data[name])))
    return Effects(**fields)


def _read_material(s: _Section, source: str, required: bool = True) -> tuple[mat.Material | None, str | None]:
    """`material` of a section: a built-in name or an inline table."""
    allowed = f"a built-in name ({', '.join(mat.MATERIALS)}) or a [{s.name}.material] table"
    if not required and not s.has("material"):
        return None, None
    m = s.required("material", allowed)
    if isinstance(m, str):
        if m not in mat.MATERIALS:
            raise s.fail("material", m, allowed)
        return mat.MATERIALS[m], m
    if isinstance(m, dict):
        return mat.read_material_table(_Section(source, f"{s.name}.material", m)), None
    raise s.fail("material", m, allowed)


def _read_material_list(s: _Section, source: str, beads: int | None) -> tuple[str | mat.Material, ...]:
    """A per-bead [chain] material list: per bead, what `material` takes (a built-in name, or a
    table of values written inline, read as a [chain.material] table is)."""
    v = s.raw("material")
    entry = (
        f"a built-in material name ({', '.join(mat.MATERIALS)}) or an inline table of the values a "
        "[chain.material] table takes, {density = ..., youngs_modulus = ..., poisson_ratio = ...} "
        "(SI; yield_strength optional)"
    )
    if beads is None or len(v) != beads:
        count = 'a number of beads (not "auto")' if beads is None else f"{beads}"
        raise s.fail("material", v, f"a list of {count} materials, one per bead, each {entry}")
    out: list[str | mat.Material] = []
    for i, x in enumerate(v, 1):
        where = f"material[{i}]"  # numbered as beads are, from 1
        if isinstance(x, str):
            if x not in mat.MATERIALS:
                raise s.fail(where, x, f"bead {i}'s material: {_did_you_mean(x, mat.MATERIALS)}{entry}")
            out.append(x)
        elif isinstance(x, dict):
            out.append(mat.read_material_table(_Section(source, f"chain.{where}", x)))
        else:
            raise s.fail(where, x, f"bead {i}'s material: {entry}")
    return tuple(out)


def _read_chain(s: _Section, source: str) -> Chain:
    if s.table.get("beads") == AUTO:
        s.raw("beads")  # mark the key as read
        beads = None  # "auto": the planner chooses (granchain plan)
    else:
        beads = s.integer("beads", low=1, high=MAX_BEADS, what='number of beads; bead 1 is the loaded end, or "auto"')
    radii = materials = None
    if isinstance(s.table.get("radius"), list):
        v = s.raw("radius")
        allowed = f"a list of {beads} radii in m, all from 1e-6 to 1 (one per bead)"
        if (
            beads is None
            or len(v) != beads
            or any(isinstance(x, bool) or not isinstance(x, (int, float)) or not 1e-6 <= x <= 1.0 for x in v)
        ):
            raise s.fail("radius", v, allowed)
        radii = tuple(float(x) for x in v)
        radius = radii[0]
    else:
        radius = s.number(
            "radius",
            low=1e-6,
            low_open=False,
            high=1.0,
            high_open=False,
            what="bead radius in m (1 um to 1 m: granular-chain beads), or a list of one radius per bead",
        )
    taper = s.number(
        "taper", required=False, low=0.0, what="radius ratio of neighbouring beads: R_i = radius taper^(i-1)"
    )
    if taper is not None:
        if radii is not None or beads is None:
            raise s.fail("taper", taper, "a rule for a single nominal radius and a given number of beads")
        # the last bead's radius, in logarithms (taper^(beads-1) over- or underflows long before)
        last = math.log10(radius) + (beads - 1) * math.log10(taper)
        if not math.log10(1e-6) <= last <= 0.0:
            raise s.fail(
                "taper",
                taper,
                f"a ratio that keeps every radius from 1e-6 to 1 m: bead {beads} would have radius "
                f"10^{last:.4g} m = {radius:g} x taper^{beads - 1}; choose taper between "
                f"{(1e-6 / radius) ** (1 / max(beads - 1, 1)):.6g} and {(1 / radius) ** (1 / max(beads - 1, 1)):.6g}",
            )
    varied = taper is not None or radii is not None or isinstance(s.table.get("material"), list)
    if varied and beads is not None and beads > MAX_VARIED_BEADS:
        raise s.fail(
            "beads",
            beads,
            f"at most {MAX_VARIED_BEADS:,} beads for a chain whose beads differ (a taper or per-bead lists): each "
            f"contact gets its own law; a uniform chain takes up to {MAX_BEADS:,}",
        )
    if taper is not None:
        radii = tuple(radius * taper**i for i in range(beads))
    if isinstance(s.table.get("material"), list):
        materials = _read_material_list(s, source, beads)
        first = materials[0]
        material, name = mat.bead_material(first), first if isinstance(first, str) else None
    else:
        material, name = _read_material(s, source)
    s.finish(("beads", "radius", "material", "taper"))
    if len(set(radii or ())) <= 1 and len(set(materials or ())) <= 1:
        radii = materials = None  # a uniform list is the plain chain
    return Chain(beads=beads, radius=radius, material=material, material_name=name, radii=radii, materials=materials)


def _read_contact(s: _Section, chain: Chain) -> Contact:
    law = s.choice("law", LAWS)
    return Contact(law=law, coefficients=law_class(law).read_contact(s, chain))


def _read_loading(s: _Section, chain: Chain, source: str) -> Loading:
    kind = s.choice("kind", LOADING_KINDS)
    if kind == "step":
        s.forbid(("impulse", "velocity"), "a step load is given by amplitude (N) and duration (s)")
        a = s.number(
            "amplitude", low=1e-9, low_open=False, high=1e12, high_open=False, what="force A in N, 1e-9 to 1e12"
        )
        t = s.number("duration", low=MIN_DURATION, low_open=False, high=MAX_TIME, high_open=False, what=DURATION_TEXT)
        s.finish(("kind", "amplitude", "duration"))
        return Loading(kind=kind, amplitude=a, duration=t)
    if kind == "impulse":
        s.forbid(
            ("amplitude", "velocity"),
            "an impulse load is given by impulse (N s) and duration (s); amplitude = impulse/duration",
        )
        i = s.number(
            "impulse", low=1e-18, low_open=False, high=1e9, high_open=False, what="impulse I in N s, 1e-18 to 1e9"
        )
        t = s.number("duration", low=MIN_DURATION, low_open=False, high=MAX_TIME, high_open=False, what=DURATION_TEXT)
        s.finish(("kind", "impulse", "duration"))
        return Loading(kind=kind, amplitude=i / t, duration=t)
    if kind == "striker":
        return _read_striker(s, chain, source)
    if kind in ("harmonic", "shaker"):
        return _read_harmonic(s, kind)
    s.forbid(
        ("amplitude", "duration", "impulse", "radius", "material", "mass", "frequency", "cycles", "ramp"),
        "a velocity load is given by velocity (m/s) of bead 1 at t = 0",
    )
    v = s.number(
        "velocity",
        low=1e-15,
        low_open=False,
        high=1e5,
        high_open=False,
        what="initial velocity of bead 1 in m/s, 1e-15 to 1e5",
    )
    s.finish(("kind", "velocity"))
    return Loading(kind=kind, velocity=v)


#: the harmonic drive's ramp when [loading] ramp is not given: two periods (granchain.physics.harmonic)
DEFAULT_RAMP_CYCLES = 2.0
#: the shortest ramp but none, in periods: a shorter switch-on is an abrupt start (write ramp = 0), and
#: one of a few ulps of a period overflows the ramp's pi / t_r
MIN_RAMP_CYCLES = 1e-3
HARMONIC_KEYS = ("kind", "amplitude", "frequency", "cycles", "duration", "ramp")


#: the largest shaker amplitude, m: a driver that moves more than this is no small-signal shaker
MAX_SHAKER_AMPLITUDE = 1e-2


def _read_harmonic(s: _Section, kind: str = "harmonic") -> Loading:
    """A harmonic drive: amplitude (N of force, or m of the shaker's displacement), frequency (Hz), its
    length as cycles or as duration (s), exactly one, and ramp (periods of the sin^2 switch-on, default
    DEFAULT_RAMP_CYCLES, within the length)."""
    shaker = kind == "shaker"
    name = "shaker" if shaker else "harmonic drive"
    s.forbid(
        ("impulse", "velocity", "radius", "material", "mass"),
        f"a {name} is given by amplitude ({'m' if shaker else 'N'}), frequency (Hz), cycles or duration (s), "
        "and ramp (periods)",
    )
    high = MAX_SHAKER_AMPLITUDE if shaker else 1e12
    what = (
        f"the shaker's displacement amplitude A in m, > 0 and <= {MAX_SHAKER_AMPLITUDE:g}"
        if shaker
        else "the drive's force amplitude A in N, > 0 and <= 1e12"
    )
    a = s.number("amplitude", low=0.0, high=high, high_open=False, what=what)
    f = s.number("frequency", low=0.0, high=1e15, high_open=False, what="the drive's frequency f in Hz, > 0")
    if s.has("cycles") == s.has("duration"):
        raise s.error(
            f"[loading] a {name} needs exactly one of cycles (its length in periods) and duration (its "
            f"length T in s, the ramp included); it has {'both: remove one' if s.has('cycles') else 'neither: add one'}"
        )
    if s.has("cycles"):
        n = s.number("cycles", low=0.0, high=1e9, high_open=False, what="the drive's length in periods, > 0")
        t = n / f
    else:
        t = s.number(
            "duration", low=0.0, high=MAX_TIME, high_open=False, what=f"the drive's length T in s, > 0, {TIME_TEXT}"
        )
        n = t * f
    if not (t >= MIN_DURATION):
        raise s.fail("cycles" if s.has("cycles") else "duration", n if s.has("cycles") else t, DURATION_TEXT)
    ramp = s.number(
        "ramp",
        required=False,
        default=DEFAULT_RAMP_CYCLES,
        low=0.0,
        low_open=False,
        what=f"the switch-on's length in periods, >= 0 (default {DEFAULT_RAMP_CYCLES:g})",
    )
    if 0.0 < ramp < MIN_RAMP_CYCLES:
        why = f"0 (no ramp) or at least {MIN_RAMP_CYCLES:g} periods: a shorter one is no ramp, write 0"
        raise s.fail("ramp", ramp, why)
    if ramp > n * (1.0 + 1e-12):
        raise s.fail(
            "ramp",
            ramp,
            f"at most the drive's length, {n:g} periods (the ramp is part of it): lengthen the drive or "
            "shorten the ramp",
        )
    s.finish(HARMONIC_KEYS)
    return Loading(kind=kind, amplitude=a, duration=t, frequency=f, ramp=ramp)


def _read_striker(s: _Section, chain: Chain, source: str) -> Loading:
    """A striker load: its speed, radius, material and mass (radius and material default to bead 1's)."""
    s.forbid(
        ("amplitude", "duration", "impulse", "frequency", "cycles", "ramp"),
        "a striker is given by velocity (m/s), radius (m), material and mass (kg, optional)",
    )
    v = s.number(
        "velocity",
        low=1e-15,
        low_open=False,
        high=1e5,
        high_open=False,
        what="the striker's speed in m/s at bead 1, 1e-15 to 1e5",
    )
    r = s.number(
        "radius",
        required=False,
        default=chain.radius,
        low=1e-6,
        low_open=False,
        high=1.0,
        high_open=False,
        what="the striker's radius in m, 1e-6 to 1 (as a bead's)",
    )
    material, name = _read_material(s, source, required=False)
    if material is None:
        material, name = chain.material, chain.material_name
    m = s.number(
        "mass",
        required=False,
        low=1e-18,
        low_open=False,
        high=1e6,
        high_open=False,
        what="the striker's mass in kg, 1e-18 to 1e6 (default: from radius and density)",
    )
    s.finish(("kind", "velocity", "radius", "material", "mass"))
    return Loading(
        kind="striker",
        velocity=v,
        striker_radius=r,
        striker_material=material,
        striker_material_name=name,
        striker_mass=m,
    )


def _read_run(s: _Section, loading: Loading) -> Run:
    def num_or_auto(key: str) -> float | None:
        if s.table.get(key) == AUTO:
            s.raw(key)
            return None
        if key == "timestep":
            return s.number(
                key,
                low=MIN_TIMESTEP,
                low_open=False,
                high=MAX_TIME,
                high_open=False,
                what='s, at least 1e-24 s (a step count must stay a number), or "auto" for the planner to choose',
            )
        return s.number(
            key, low=0.0, high=MAX_TIME, high_open=False, what=f's, {TIME_TEXT}, or "auto" for the planner to choose'
        )

    end = num_or_auto("end_time")
    dt = num_or_auto("timestep")
    if dt is not None and end is not None and dt > end:
        raise s.fail("timestep", dt, f"a time step no longer than end_time = {end:g} s")
    if end is not None and loading.kind == "impulse" and end < loading.duration:
        raise s.fail(
            "end_time",
            end,
            f"at least the impulse's duration {loading.duration:g} s, or the impulse is never fully delivered",
        )
    stop = None
    if s.has("stop_after_contact"):
        stop = s.raw("stop_after_contact")
        if isinstance(stop, bool) or not isinstance(stop, int) or stop < 1:
            raise s.fail(
                "stop_after_contact",
                stop,
                "a contact number >= 1: the run stops once its force has "
                "fallen below half its peak (the leading wave has passed it)",
            )
        if loading.is_harmonic:
            raise s.fail(
                "stop_after_contact",
                stop,
                "not with a harmonic drive, whose contact forces rise and fall every period: remove it (the run "
                "lasts end_time)",
            )
    wall = _read_flag(
        s,
        "stop_after_wall",
        "true also waits for the wall's contact (bead N on the flat) to fall below half its peak after the reflection",
    )
    back = _read_flag(
        s,
        "stop_after_reflection",
        "true also waits for the wall's reflection to pass back through contact 1 (its force risen and fallen "
        "below half of its largest after the wall's)",
    )
    s.finish(("end_time", "timestep", "stop_after_contact", "stop_after_wall", "stop_after_reflection"))
    return Run(end_time=end, timestep=dt, stop_after_contact=stop, stop_after_wall=wall, stop_after_reflection=back)


def _read_flag(s: _Section, key: str, what: str) -> bool:
    """A true/false field of s (false when absent); what: what true does."""
    v = s.raw(key, False) if s.has(key) else False
    if not isinstance(v, bool):
        raise s.fail(key, v, f"true or false: {what}")
    return v


def _int_list(s: _Section, key: str, low: int, high: int, what: str) -> tuple[int, ...]:
    allowed = f"a list of integers from {low} to {high} ({what})"
    v = s.raw(key)
    if not isinstance(v, list) or any(isinstance(x, bool) or not isinstance(x, int) for x in v):
        raise s.fail(key, v, allowed)
    bad = [x for x in v if not low <= x <= high]
    if bad:
        raise s.fail(key, v, allowed + f"; {bad[0]} is out of range")
    if len(set(v)) != len(v):
        raise s.fail(key, v, allowed + "; without repeats")
    return tuple(sorted(v))


def _read_snapshots(s: _Section, run: Run) -> tuple[float, ...]:
    if not s.has("snapshots"):
        return ()
    v = s.raw("snapshots")
    end = run.end_time if run.end_time is not None else MAX_TIME
    allowed = f"a list of times in s with 0 < t <= end_time = {end:g}"
    if not isinstance(v, list) or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v):
        raise s.fail("snapshots", v, allowed)
    if any(not (0.0 < x <= end) for x in v):
        raise s.fail("snapshots", v, allowed)
    return tuple(sorted({float(x) for x in v}))


def _read_window(s: _Section, nc: int) -> tuple[int, int] | None:
    if not s.has("window"):
        return None
    v = s.raw("window")
    allowed = f"[first, last] contacts with 1 <= first < last <= {nc}"
    if (
        not isinstance(v, list)
        or len(v) != 2
        or any(isinstance(x, bool) or not isinstance(x, int) for x in v)
        or not 1 <= v[0] < v[1] <= nc
    ):
        raise s.fail("window", v, allowed)
    return (v[0], v[1])


def _check_stop(s: _Section, run: Run, nc: int, snapshots, wall: bool) -> None:
    """[run]'s stop check against the chain and the outputs: a contact of the chain, no snapshots; the
    wall's contact only on a wall and with a stop contact (so never with snapshots either)."""
    if run.stop_after_contact is not None:
        if run.stop_after_contact > nc:
            raise SceneError(
                f"{s.file}: [run] stop_after_contact = {run.stop_after_contact} is invalid: "
                f"a contact of this chain, 1..{nc}"
            )
        if snapshots:
            raise SceneError(
                f"{s.file}: [run] stop_after_contact = {run.stop_after_contact} and [outputs] snapshots "
                "do not go together: snapshots need the run to reach their times; remove one"
            )
    if run.stop_after_wall:
        if run.stop_after_contact is None:
            raise SceneError(
                f"{s.file}: [run] stop_after_wall = true needs [run] stop_after_contact: the contact the leading "
                "wave passes first (the run stops once it has passed both)"
            )
        if not wall:
            raise SceneError(
                f'{s.file}: [run] stop_after_wall = true needs a wall: [boundary] far_end = "wall" (or remove it)'
            )
    if run.stop_after_reflection and not run.stop_after_wall:
        raise SceneError(
            f"{s.file}: [run] stop_after_reflection = true needs [run] stop_after_wall = true: the reflection "
            "comes back once the wave has passed the wall"
        )


def _read_outputs(s: _Section, chain: Chain, run: Run, wall: bool = False) -> Outputs:
    """The [outputs] section (and the checks of [run]'s stop against it); wall: the chain ends on a
    wall, whose contact a stop check may wait for ([run] stop_after_wall)."""
    nc = chain.beads - 1 if chain.beads is not None else 10**9  # beads = "auto": the planner checks
    contacts = f"contact i is between bead i and i+1; this chain has contacts 1..{nc}"
    peak: bool | tuple[int, ...] = True
    if s.has("peak_force"):
        v = s.table["peak_force"]
        if isinstance(v, bool):
            peak = s.raw("peak_force")
        elif isinstance(v, list):
            peak = _int_list(s, "peak_force", 1, nc, contacts)
        else:
            raise s.fail("peak_force", v, f"true, false, or a list of contacts ({contacts})")
    histories = _int_list(s, "histories", 1, nc, contacts) if s.has("histories") else ()
    snapshots = _read_snapshots(s, run)
    window = _read_window(s, nc)

    def interval_or_auto(key: str, what: str):
        if s.table.get(key) == AUTO:
            s.raw(key)
            return AUTO
        v = s.number(
            key,
            required=False,
            low=0.0,
            high=MAX_TIME,
            high_open=False,
            what=what + ', or "auto" for the planner to choose',
        )
        if v is not None and run.timestep is not None and v < run.timestep:
            raise s.fail(key, v, f"at least the time step {run.timestep:g} s")
        if v is not None and run.end_time is not None and v > run.end_time:
            raise s.fail(key, v, f"at most the run's end_time {run.end_time:g} s (one sample per interval)")
        return v

    interval = interval_or_auto("history_interval", "s between history samples, at least the time step")
    sensors = _read_sensors(s, chain) if s.has("sensors") else ()
    if interval is None and (histories or sensors):  # a sensor's history is sampled as the contacts' are
        # a sample every step makes a 245 MB dump of 454k steps x 3 contacts: by default the planner's largest
        # interval whose dump-derived peaks stay within rtol (granchain.workflows.plan)
        interval = AUTO
    dump = interval_or_auto("dump_interval", "s between whole-chain dump frames (LAMMPS), at least the time step")
    _check_stop(s, run, nc, snapshots, wall)
    event = _read_flag(
        s,
        "event",
        "true tracks the far-end wall's largest force, impulse and energy over the event (a walled chain), or "
        "what bead N carries off a free far end",
    )
    maxima = _read_event_maxima(s, chain, nc, sensors, event and wall)
    s.finish(
        ("peak_force", "histories", "snapshots", "window", "history_interval", "dump_interval", "event", "sensors")
        + EVENT_MAXIMA_KEYS
    )
    return Outputs(
        peak_force=peak,
        histories=histories,
        snapshots=snapshots,
        window=window,
        history_interval=interval,
        dump_interval=dump,
        event=event,
        sensors=sensors,
        event_max_contacts=maxima[0],
        event_max_sensors=maxima[1],
    )


#: [outputs]' keys choosing the contacts and sensor beads whose largest force over the wall's event is
#: tracked (granchain.physics.event.EventMaxima)
EVENT_MAXIMA_KEYS = ("event_max_contacts", "event_max_sensors")


def _read_event_maxima(s: _Section, chain: Chain, nc: int, sensors, walled_event: bool):
    """[outputs] event_max_contacts and event_max_sensors: contacts (1..N-1) and sensor beads (of
    [outputs] sensors, whose average force the run tracks) whose largest force over the far-end wall's
    event is tracked; they need the event itself ([outputs] event = true on a walled chain)."""
    out: list[tuple[int, ...]] = []
    for key in EVENT_MAXIMA_KEYS:
        if not s.has(key):
            out.append(())
            continue
        if not walled_event:
            raise s.fail(
                key,
                s.raw(key),
                "a list that needs the wall's event: [outputs] event = true on a chain with "
                '[boundary] far_end = "wall" (the event is what the largest force is taken over)',
            )
        if key == "event_max_contacts":
            what = f"contact i is between bead i and i+1; this chain has contacts 1..{nc}"
            out.append(_int_list(s, key, 1, nc, what))
            continue
        beads = chain.beads if chain.beads is not None else 10**9
        chosen = _int_list(s, key, 1, beads, "sensor beads, 1-based, each one of [outputs] sensors")
        extra = [b for b in chosen if b not in sensors]
        if extra:
            raise s.fail(
                key,
                s.raw(key),
                f"sensor beads of [outputs] sensors = {list(sensors)} (the run tracks only their average "
                f"force); bead {extra[0]} is not one: add it to [outputs] sensors",
            )
        out.append(chosen)
    return tuple(out)


def _read_sensors(s: _Section, chain: Chain) -> tuple[int, ...]:
    """[outputs] sensors: sensor beads, 1-based, each once, on a chain of a given length."""
    if chain.beads is None:
        raise s.fail(
            "sensors",
            s.raw("sensors"),
            'sensor beads need a chain of a given length: set [chain] beads = N (not "auto"), then beads 1..N',
        )
    return _int_list(s, "sensors", 1, chain.beads, f"sensor beads, 1-based: this chain has beads 1..{chain.beads}")
