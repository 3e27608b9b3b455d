"""What the subcommands share: scene arguments, the plan's notes, --np, JSON and terminal output,
and what a finished run prints."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from granchain.backends import Backend, backend_named
from granchain.exceptions import UsageError
from granchain.peaks import REACHED_FRACTION, end_contact_reached, reflection_pending
from granchain.physics.effects import unbalanced_forces
from granchain.postprocess.comparison_table import dynamic_name
from granchain.postprocess.observables import END_PEAKS, SENSOR_OBSERVABLES, units
from granchain.results import printable
from granchain.scene import Scene, load_scene

DEFAULT_SCENE = "default"
#: the help of a subcommand's SCENE argument
SCENE_HELP = "scene file or bundled scene name"


def tolerant_output() -> None:
    """Make every line granchain prints printable on any terminal: a character stdout's or stderr's
    encoding lacks (a title's "ü" under PYTHONIOENCODING=ascii) is written as a backslash escape
    instead of raising UnicodeEncodeError after the run directory was written."""
    for stream in (sys.stdout, sys.stderr):
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")


def shown(text) -> str:
    """Text from a scene, a file or a path as printed on a terminal: control characters escaped
    (a title's ESC sequences cannot retitle the window or clear the screen); newlines and tabs kept."""
    return printable(str(text), keep="\n\t")


def scene_name(scene: Scene) -> str:
    """The scene's title (or file) as printed: control characters escaped."""
    return printable(scene.title or scene.source or "")


def json_safe(o):
    """o with every non-finite float as None (null) and numpy numbers as Python's: strict JSON for
    scripts (json.dumps refuses NaN with allow_nan=False)."""
    if isinstance(o, dict):
        return {str(k): json_safe(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [json_safe(v) for v in o]
    if hasattr(o, "tolist") and not isinstance(o, (str, bytes)):  # numpy scalars and arrays
        return json_safe(o.tolist())
    if isinstance(o, float) and not math.isfinite(o):
        return None
    if isinstance(o, Path):
        return str(o)
    return o


#: the version of every ``--json`` document's layout (docs/notebook.md, "Scripts and the command line"):
#: raised when a key is removed or renamed or its meaning changes, not when one is added
JSON_SCHEMA_VERSION = 1
#: the key that carries it: at the top of an object, and in every row of a list (predict's)
SCHEMA_KEY = "schema_version"


def versioned(data):
    """data with the ``--json`` schema version: first key of an object; in every row of a list of
    objects (predict's list stays a list, so scripts that loop over its rows keep working)."""
    if isinstance(data, dict):
        if SCHEMA_KEY in data:
            raise ValueError(f"a --json document has its own {SCHEMA_KEY!r} key")
        return {SCHEMA_KEY: JSON_SCHEMA_VERSION, **data}
    if isinstance(data, list) and all(isinstance(row, dict) for row in data):
        return [versioned(row) for row in data]
    raise TypeError(f"a --json document is an object or a list of objects, not {type(data).__name__}")


def print_json(data) -> None:
    """data as strict JSON on stdout (one document; NaN and infinities as null), with the schema
    version (``versioned``)."""
    print(json.dumps(json_safe(versioned(data)), indent=2, allow_nan=False))


def resolve_scene(arg: str | None) -> Scene:
    """A scene from a path, or from the name of a bundled scene (the default scene if None)."""
    return load_scene(arg or DEFAULT_SCENE)


#: how a force is marked on a precompressed chain: the dynamic force F - F0 or the total force F
DYNAMIC, TOTAL = "above F0", "total"


def force_unit(name: str, f0: float) -> str:
    """The unit an observable is printed with; on a precompressed chain (f0 > 0) a force's says whether
    it is dynamic (the peaks, F - F0, docs/observables.md) or total (static_force, F0 itself)."""
    unit = units().get(name, "?")  # the registry's (granchain.postprocess.observables)
    if not f0 or not (unit == "N" or name.endswith("_force_nondim")):
        return unit
    return f"{unit}, {TOTAL if name == 'static_force' else DYNAMIC}"


def fmt(v) -> str:
    """A number as the result lines print it (6 significant digits; "-" for None; a list, as the chosen
    contacts' largest forces over the event, item by item)."""
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return "[" + ", ".join(fmt(x) for x in v) + "]"
    return str(v)


def planned(scene: Scene, rtol: float | None, backend: str | Backend, method: str | None):
    """The scene with its "auto" values (and, given rtol, its time step) chosen by the planner for
    the integrator this backend runs; the plan's notes go to stderr (stdout may be a deck)."""
    from granchain.progress import is_quiet
    from granchain.workflows.run import integrator, plan_for

    used = integrator(backend, method, scene)
    scene, plan = plan_for(scene, backend, method, rtol)
    if plan is not None and not is_quiet():  # (--quiet: no plan lines either)
        for c in plan.choices:
            print(f"plan ({used}): {c.name} = {c.value:.6g}  ({shown(c.reason)})", file=sys.stderr)
    return scene, plan


def np_arg(text: str) -> int | str:
    """--np: a whole number of MPI ranks, or "auto"."""
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of MPI ranks or 'auto', got {text!r}") from None


def auto_np(scene: Scene, backend: str | Backend) -> int:
    """--np auto: one rank where MPI does not pay (a backend without MPI, a chain shorter than the
    measured crossover, one idle core), else granchain.schedule.auto_ranks over the idle cores; said
    on stderr."""
    from granchain.schedule import MPI_CROSSOVER_BEADS, auto_ranks, idle_cores
    from granchain.workflows.run import available_cores

    if not backend_named(backend).mpi:
        return 1
    cores = available_cores()
    idle = idle_cores(cores)
    n = auto_ranks(scene.chain.beads, idle)
    print(
        f"--np auto: {n} rank{'s' if n > 1 else ''} for {scene.chain.beads} beads on {idle} idle of {cores} cores "
        f"(two ranks pay from {MPI_CROSSOVER_BEADS} beads on idle cores)",
        file=sys.stderr,
    )
    return n


def add_quiet(parser) -> None:
    """-q/--quiet: no progress lines on stderr."""
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")


def check_out(args) -> None:
    """Refuse an empty --out: every subcommand's default takes over from an absent one, and an empty
    one would silently write there (runs/...) instead of where the user pointed."""
    if getattr(args, "out", None) == "":
        raise UsageError(
            '--out "" is empty: give the directory (or path) to write to, or leave --out out for the default'
        )


def scene_stem(args) -> str:
    """The name of the run's default output: the scene file's stem, or the default scene's name."""
    return Path(args.scene).stem if args.scene else DEFAULT_SCENE


def ended_too_soon(result, planned_end: bool, then: str | None = None) -> int:
    """Say on stderr what the scene asked for that the run ended before measuring (a wave that had
    not passed the window's end), with why; 1 when the end time was the planner's ("auto", which
    promised to cover it), else 0 (a fixed end_time the user chose, now told what it missed).
    then: a last line after them, what to do (granchain collect: granchain run would run it longer)."""
    from granchain.postprocess.observables import unmeasured_outputs

    unmeasured = unmeasured_outputs(result.scene, result.solution)
    for line in unmeasured:
        print(f"granchain: not measured: {shown(line)}", file=sys.stderr)
    if unmeasured and then:
        print(f"granchain: {then}", file=sys.stderr)
    return 1 if unmeasured and planned_end else 0


def print_end_peaks(result, s: dict, f0: float) -> None:
    """The striker's and the wall's contact lines of print_result (s: the run's summary, f0: the
    precompression): a peak, the largest force so far, or "not reached"."""
    end_errors = (s.get("errors") or {}).get("end_peaks", {})
    # the end peaks (postprocess.observables.END_PEAKS), each with the static force its contact carries
    ends = [
        (o.name, f"{o.label.removeprefix('the ')} contact", o.static_force(result.scene)) for o in END_PEAKS.values()
    ]
    rises = [*(np.asarray(result.solution.peak_force, dtype=float) - f0)]
    rises += [s[name] - static for name, _, static in ends if s.get(name) is not None]
    for name, label, static in ends:
        value = s.get(name)
        if value is None:
            continue
        # the wall's contact carries F0 at rest: shown dynamic, as compare names it (dynamic_name)
        shown_name, shown_value = (dynamic_name(name), value - static) if static else (name, value)
        row = f"{shown_name} (N{f', {DYNAMIC}' if static else ''})"
        complete = s.get(END_PEAKS[name].complete_field)
        if complete is False and not end_contact_reached(value, static, rises):
            print(
                f"  {row:38s} -   not reached: the wave had not reached the {label} when the run "
                f"ended (t = {result.solution.end_time:g} s)"
                + (
                    f"; its largest force{f' above F0 = {static:g} N' if static else ''}, {value - static:.2g} N, "
                    f"is round-off ahead of the wave, under {REACHED_FRACTION:g} of the largest contact's"
                    if value != static
                    else ""
                )
            )
            continue
        e = end_errors.get(name)
        bar = (
            ""
            if e is None
            else (f" +- {e['error']:.2g}   ({e['status']})" if e["error"] is not None else f"   ({e['status']})")
        )
        what = f"the {label} peak"
        if complete is False:  # a running maximum (ChainSolution)
            what = f"the {label} largest force so far, not a peak"
            what += (
                ": the wave had not reached it, or its force had not fallen to half of it, when the run ended"
                if e is None
                else ""
            )
        if static:
            what += f"; total {fmt(value)} N"
        print(f"  {row:38s} {fmt(shown_value)}{bar}   ({what})")


def print_sensors(s: dict) -> None:
    """print_result's sensor bead lines (summary.json's ``sensors``: postprocess.sensors), bead by bead:
    each quantity with its error bar, or why it is not measured."""
    sensors = s.get("sensors")
    if not sensors:
        return
    errors = (s.get("errors") or {}).get("end_peaks", {})
    for k, bead in enumerate(sensors["beads"]):
        for quantity, obs in SENSOR_OBSERVABLES.items():
            unit, key, v = obs.unit, obs.key(bead), sensors[quantity][k]
            e = errors.get(key)
            bar = ""
            if e is not None and v is not None:  # the measured error bar, or why there is none
                bar = f" +- {e['error']:.2g}   ({e['status']})" if e["error"] is not None else f"   ({e['status']})"
            why = f"   not measured: {shown(sensors['missing'].get(key, ''))}" if v is None else ""
            print(f"  {key + f' ({unit})':38s} {fmt(v)}{bar}{why}")


def print_incomplete_peaks(result) -> None:
    """print_result's line on the measured contacts ([outputs] peak_force) whose peak was not complete
    when the run ended (reached, the force not yet fallen to half of its peak, or never reached): how
    many and which, as contact runs; none when every peak is complete."""
    from granchain.postprocess.domains import contact_runs

    contacts = np.asarray(result.scene.peak_contacts, dtype=int)
    if contacts.size == 0:
        return
    s = result.solution
    complete = np.asarray(s.complete, dtype=bool)[contacts - 1]
    reached = np.isfinite(np.asarray(s.time_of_peak, dtype=float)[contacts - 1])
    open_ = contacts[~complete]
    if open_.size == 0:
        return
    never = contacts[~reached]
    # not complete although passed: the wave reflected from a wall may still exceed them (peaks.reflection_pending)
    back = contacts[~complete & reflection_pending(result.scene, s)[contacts - 1]]
    falling = np.setdiff1d(open_, np.union1d(back, never))  # the force had not fallen to half of its peak
    row = "peaks not complete (contacts)"
    said = [f"never reached: {contact_runs(never)}"] if never.size else []
    if falling.size:
        said.append(f"the force had not fallen to half of its peak: {contact_runs(falling)}")
    if back.size:
        said.append(
            f"the wall's reflection, which can be larger, had not passed back through {contact_runs(back)} "
            '(their largest force came before the wall\'s; end_time = "auto" runs until it has)'
        )
    print(
        f"  {row:38s} {open_.size} of {contacts.size}: {contact_runs(open_)}   (not measured when the run ended, "
        f"t = {s.end_time:g} s: "
        + "; ".join(said)
        + "; peaks.csv's complete = 0, its peak_force the largest force so far)"
    )


def print_result(result, out) -> None:
    """What `granchain run` (and `granchain collect`) prints about a finished run."""
    scene = result.scene
    s = result.summary()
    print(f"scene      {scene_name(scene)}")
    print(
        f"backend    {s['backend']} ({s['method']}), dt = {s['timestep']:g} s, {s['steps']} steps, "
        f"{s['wall_time']:.3g} s wall"
    )
    if s.get("method_reason"):  # the scene chose the integrator (workflows.run.method_choice)
        print(f"           ({shown(s['method_reason'])})")
    missing = s.get("observables_missing", {})
    notes = s.get("observables_notes", {})
    errors = (s.get("errors") or {}).get("observables", {})
    f0 = float(scene.effects.precompression)
    if f0:  # the observables' forces are dynamic, peaks.csv's and summary.json's contact forces total
        print(
            f"  {'forces (precompressed)':38s} '{DYNAMIC}': dynamic, F - F0 over the static force F0 = {f0:g} N; "
            f"'{TOTAL}': F (peaks.csv's peak_force and peak_force_nondim are total, its dynamic_peak_force F - F0)"
        )
    said = None  # the last reason printed: a companion that shares it says "as above" (shares_reason)
    # where an observable does not apply (a wall's event on a free chain, a leading pulse under a harmonic
    # drive) one line per reason says so, not a line each: summary.json keeps every one with its reason
    inapplicable: dict[str, list[str]] = {}
    for k, v in s["observables"].items():
        if v is None and k in missing and k in set(s.get("observables_inapplicable") or ()):
            inapplicable.setdefault(missing[k], []).append(k)
            continue
        if k == "wave_speed_sections":  # one line per uniform stretch of the window
            for sec in v:
                first, last = sec["contacts"]
                row = f"wave_speed, contacts {first}-{last} (m/s)"
                print(f"  {row:38s} {fmt(sec['speed'])} +- {sec['stderr']:.2g}   (fit over {sec['arrivals']} arrivals)")
            continue
        label = f"{k} ({force_unit(k, f0)})"
        why = ""
        if v is None and k in missing:
            why = "   not measured: " + ("as above" if missing[k] == said else shown(missing[k]))
            said = missing[k]
        bar = ""
        if v is not None and k in errors:  # the measured error bar, or why there is none
            e = errors[k]
            bar = f" +- {e['error']:.2g}" if e["error"] is not None else ""
            window = s["observables"].get(f"{k}_error")  # a lock-in's finite window's own bar (spectral)
            if window is not None:
                bar += f"{' (the step)' if bar else ''} +- {window:.2g} (the window)"
            bar += f"   ({e['status']})"
        note = f"   note: {shown(notes[k])}" if v is not None and k in notes else ""
        print(f"  {label:38s} {fmt(v)}{bar}{why}{note}")
    _print_inapplicable(inapplicable)
    print_end_peaks(result, s, f0)
    print_sensors(s)
    print_incomplete_peaks(result)
    outside = "beyond first yield"
    for line in s.get("outside_domain") or ():  # an elastic law beyond first yield (postprocess.domains)
        print(f"  {outside:38s} {shown(line)}")
    _print_conservation(scene, s)
    _print_error_summary(s.get("errors"))
    print(f"run directory: {shown(out)}")


def _print_inapplicable(inapplicable: dict[str, list[str]]) -> None:
    """One line per reason for the observables that do not apply to the run (its scene's effects and
    outputs): the first one's name, how many share the reason, and the reason."""
    row = "not applicable (observables)"
    for reason, names in inapplicable.items():
        more = f" and {len(names) - 1} more" if len(names) > 1 else ""
        print(f"  {row:38s} {names[0]}{more}: {shown(reason)}")


def _print_conservation(scene, s: dict) -> None:
    """print_result's lines on the momentum put in and kept and the energy balance (s: the summary)."""
    c = s["conservation"]
    ld = scene.loading
    if ld.is_force:  # A min(T, t_end): the load delivers A T only if it ended before the run
        end = float(c.get("time", s["end_time"]))
        how = (
            ("the drive's closed-form integral" if ld.is_harmonic else "A T delivered by the force")
            if end >= ld.duration
            else f"A t_end: delivered up to the end, t_end = {end:.4g} s; the load lasts T = {ld.duration:.4g} s"
        )
        print(f"  {'impulse of the load (N s)':38s} {fmt(c['impulse_delivered'])}   ({how})")
    else:
        who = "the striker's M V" if ld.kind == "striker" else "bead 1's m v0"
        print(f"  {'momentum put in at t = 0 (N s)':38s} {fmt(scene.initial_momentum)}   ({who}; no force load)")
    free = not unbalanced_forces(scene)
    print(
        f"  {'momentum at the end (N s)':38s} {fmt(c['momentum'])}"
        + (
            "   (a free chain keeps what was put in"
            + (": the static push on bead 1 and pull on bead N balance)" if scene.effects.precompression else ")")
            if free
            else "   (the wall takes some)"
        )
    )
    err = fmt(c["energy_balance_error_relative"])
    print(f"  {'energy balance error (1)':38s} {err}   (relative to the energy put in)")


def _print_error_summary(e: dict | None) -> None:
    """print_result's lines on the run's error bars as a whole (e: the summary's errors, or None)."""
    if e is not None:
        if e["why_none"]:
            print(f"  {'error estimate':38s} none: {shown(e['why_none'])}")
        else:
            worst = e["error_estimate"]
            where = f" at contact {e['error_estimate_contact']}" if worst is not None else ""
            n_bad = len(e["unreliable_contacts"])
            # bounds: Verlet's on a kinked law (bound), RK4's there from its one companion (one_companion)
            bounded = bool(e.get("bound") or e.get("one_companion"))
            times = e["companion_timesteps"]
            print(
                f"  {'largest peak-force error (1)':38s} {fmt(worst)}{where}   ("
                + ("bounds from " if bounded else "measured: ")
                + ("reference RK4 " if e.get("companion_method") == "rk4" else "")
                + ("a run at 2 dt = " if len(times) == 1 and e.get("one_companion") else "runs at ")
                + ", ".join(f"{t:g}" for t in times)
                + f" s, {e['companion_wall_time']:.3g} s more)"
            )
            if n_bad:
                print(f"  {'peaks without an estimate':38s} {n_bad}   (peaks.csv error_status says why)")
            if e.get("why_unchecked"):
                label = "bounds, not measured" if bounded else "not checked at dt / 2"
                print(f"  {label:38s} {shown(e['why_unchecked'])}")
