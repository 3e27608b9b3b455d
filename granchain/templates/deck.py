"""The deck builder: render_deck(scene) renders chain.lmp.j2 (or the built-in granular yardstick's
template) with the scene, its atoms, its run control and the effects' blocks, and returns the deck
text and its data file."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from importlib import resources

import jinja2
import numpy as np

from granchain._version import __version__
from granchain.exceptions import UsageError
from granchain.peaks import lead_fall, lead_floor, stop_force_floor
from granchain.physics.effects import active_effects
from granchain.physics.shaker import shaker_velocity
from granchain.problem import scene_static_forces
from granchain.results import scene_hash
from granchain.scene import SceneError
from granchain.templates.atoms import AtomLayout, pair_coeffs, render_data
from granchain.templates.columns import BUILTIN_GRANULAR_PER_ATOM, RESULTS_DUMP, RUN_END_FILE, PerAtom
from granchain.templates.drive import DRIVE_WORK_COLUMN, drive_force_expression, driver_acceleration_expression
from granchain.templates.filters import comment, float_repr, is_atom_x, law_parameters, one_line
from granchain.templates.run_control import EventCheck, Schedule, StopCheck, Watch


@dataclass(frozen=True)
class DeckOptions:
    """How a deck computes what it computes, none of which changes its numbers
    (tests/test_plugin_watch.py and tests/test_history_output.py hold each choice against the other).

    neigh_every: steps between two checks of the neighbour list (neigh_modify every N delay 0 check yes);
        our pair styles fail a run with a dangerous build at its end, so a too sparse check cannot pass
        unnoticed (pair_style granular, the yardstick's, only counts them in log.lammps)
    watch_computes: the run watch's largest force and momentum by the plugin's computes chain/fmax and
        chain/momentum (one pass, the same doubles) instead of atom-style variables and compute reduce
    chain_nve: fix chain/nve (the plugin's velocity Verlet along x: fix nve's updates of x and vx, the
        same doubles) instead of fix nve
    history_file: "dump", a text dump custom histories.dump (read with MDAnalysis), or "npy", fix
        chain/history buffering the history contacts' d_fc and vx and writing histories.npy at the
        end of each run (granchain.postprocess.histories reads both)
    energy_fix: the energy samples and the run watch's energy balance by the plugin's fix chain/energy
        (the samples' lines kept in memory and written at each run's end; the balance computed once
        from the sample's own numbers) instead of fix print, which flushes every line, and the balance
        as LAMMPS variables read by fix ave/time and fix halt
    """

    neigh_every: int = 10
    watch_computes: bool = False
    chain_nve: bool = False
    history_file: str = "dump"
    energy_fix: bool = False

    def __post_init__(self):
        """Refuse an unknown history_file and a neigh_every below 1 (UsageError)."""
        if self.history_file not in ("dump", "npy"):
            raise UsageError(f"history_file = {self.history_file!r}: 'dump' or 'npy'")
        if not (isinstance(self.neigh_every, int) and self.neigh_every >= 1):
            raise UsageError(f"neigh_every = {self.neigh_every!r}: an integer >= 1")


#: every piece of the plugin: the watch by its computes, fix chain/nve, histories by fix chain/history,
#: energy samples and balance by fix chain/energy (benchmarks/bench_pair.py: 0.28-0.39x the built-in
#: granular style's time per bead-step against 0.42-0.48 with the built-ins; histories' share of the
#: loop 3-17% on the bundled scenes, 7-42% as text; benchmarks/RESULTS.md)
PLUGIN_DECK_OPTIONS = DeckOptions(watch_computes=True, chain_nve=True, history_file="npy", energy_fix=True)
#: the options render_deck uses unless told otherwise; DeckOptions() is the built-ins' deck
#: (tests/test_plugin_watch.py and tests/test_history_output.py hold the two to the same doubles)
DECK_OPTIONS = PLUGIN_DECK_OPTIONS


@dataclass(frozen=True)
class Deck:
    """A rendered deck: the text of deck.lmp, of the data file chain.data it reads, and its step count.

    Attributes
    ----------
    deck : str
        The text of deck.lmp.
    data : str
        The text of chain.data (render_data).
    total_steps : int
        The steps of the whole run, every segment of the step plan (Schedule.total).
    """

    deck: str  # deck.lmp
    data: str  # chain.data
    total_steps: int


@functools.lru_cache(maxsize=1)
def _env() -> jinja2.Environment:
    # one environment per process: it keeps the compiled templates (compiling every template again for
    # each deck costs 25-50 ms of a campaign point's overhead)
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(resources.files("granchain") / "templates")),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
        finalize=one_line,
    )
    env.filters["float_repr"] = float_repr
    env.filters["comment"] = comment
    env.filters["parameters"] = law_parameters
    env.tests["atom_x"] = is_atom_x
    env.globals.update(RESULTS_DUMP=RESULTS_DUMP, RUN_END_FILE=RUN_END_FILE)
    return env


def builtin_granular_refusal(scene) -> str | None:
    """Why LAMMPS's built-in pair_style granular cannot run this scene as our pair style would, or
    None: the yardstick is an elastic Hertz chain of one material (pair_coeff * * hertz/material E 0 nu)."""
    materials = set(scene.bead_materials)
    if scene.loading.kind == "striker":
        materials.add(scene.loading.striker_material)
    normal = scene.contact.law_class.builtin_granular_normal  # (Hertz's hertz/material)
    why = {
        f"the {scene.contact.law} law (the yardstick is Hertz)": normal is None,
        **{y: True for e in active_effects(scene) if (y := e.yardstick_refusal(scene))},
        "beads or a striker of another material (the yardstick takes one E and nu)": len(materials) > 1,
    }
    refused = [k for k, v in why.items() if v]
    return "the built-in granular yardstick cannot run a chain with " + "; ".join(refused) if refused else None


def _template(scene, yardstick: str | None) -> tuple[str, PerAtom]:
    """The deck's template and the per-atom vectors it declares."""
    if yardstick is None:
        return "chain.lmp.j2", PerAtom.of(scene)
    if yardstick != "builtin":
        raise UsageError(f"yardstick = {yardstick!r} is unknown: the yardstick is 'builtin' (pair_style granular)")
    why = builtin_granular_refusal(scene)
    if why:
        raise SceneError(f"{scene.source or '<scene>'}: {why}")
    return "builtin_granular.lmp.j2", BUILTIN_GRANULAR_PER_ATOM


#: where chain.lmp.j2 includes the effects' blocks: after the pair style (interactions), after the
#: dissipated-energy sum (ends: extra atoms' groups), after the load (forces)
DECK_SLOTS = ("interactions", "ends", "forces")


def effect_blocks(scene) -> dict[str, list[str]]:
    """slot -> the deck blocks (templates) of the effects the scene declares, in registry order."""
    active = active_effects(scene)
    return {slot: [e.deck_blocks[slot] for e in active if slot in e.deck_blocks] for slot in DECK_SLOTS}


def stop_statics(scene, stop: int | None) -> dict[str, float]:
    """StopCheck's static forces of the stop contact, the wall's contact and contact 1."""
    if not stop:
        return {}
    forces = scene_static_forces(scene)
    return {"static": float(forces[stop - 1]), "wall_static": float(forces[-1]), "back_static": float(forces[0])}


def energy_columns(scene, layout: AtomLayout) -> dict[str, tuple[str, str]]:
    """The energy samples' columns after x1 that the effects add, and a harmonic drive's summed work
    (templates/loading_harmonic.lmp.j2): name -> (LAMMPS expression, words)."""
    columns = {k: v for e in active_effects(scene) for k, v in e.energy_columns(layout).items()}
    if scene.loading.is_harmonic:
        columns[DRIVE_WORK_COLUMN] = ("v_drive_work", "the harmonic drive's work")
    return columns


def drive_values(scene) -> dict[str, object]:
    """A harmonic drive's deck values: its force's expression (drive_force; a shaker's, its driver's
    acceleration), and a shaker's driver's velocity at t = 0 and its power there, F0 v_d(0)."""
    ld = scene.loading
    if not ld.is_harmonic:
        return {"drive_force": ""}
    if not ld.is_shaker:
        return {"drive_force": drive_force_expression(ld)}
    v0 = float(shaker_velocity(0.0, ld.amplitude, ld.frequency, ld.ramp_time, ld.duration))
    return {
        "drive_force": driver_acceleration_expression(ld),
        "driver_velocity": v0,
        "drive_p0": float(scene.effects.precompression) * v0,
    }


def sensor_args(scene, layout: AtomLayout) -> str:
    """The pair style's sensor beads (postprocess.sensors): ' sensors K' and their atom IDs, or ''."""
    beads = scene.outputs.sensors
    return f" sensors {len(beads)} " + " ".join(str(b + layout.offset) for b in beads) if beads else ""


def render_deck(scene, yardstick: str | None = None, options: DeckOptions = DECK_OPTIONS) -> Deck:
    """The scene's deck and its data file.

    Parameters
    ----------
    scene : granchain.scene.Scene
        A planned scene (no "auto" values left).
    yardstick : {None, "builtin"}
        None: chain.lmp.j2, our pair style. "builtin": the same chain with LAMMPS's built-in
        pair_style granular instead (builtin_granular.lmp.j2 extends chain.lmp.j2), the yardstick
        chain/hertz is tested and timed against.
    options : DeckOptions
        How the deck computes what it computes (none of it changes its numbers).

    Returns
    -------
    Deck
        deck.lmp's and chain.data's text and the run's total steps.

    Raises
    ------
    SceneError
        The chain has more bead kinds than the deck takes, or the yardstick cannot run the scene.
    UsageError
        An unknown yardstick.
    """
    template, per_atom = _template(scene, yardstick)
    schedule, layout = Schedule.of(scene), AtomLayout.of(scene)
    pairs = pair_coeffs(scene, layout)
    stop = scene.run.stop_after_contact
    watch = Watch.of(scene, pairs)
    deck = (
        _env()
        .get_template(template)
        .render(
            scene=scene,
            options=options,
            version=__version__,
            scene_sha256=scene_hash(scene),
            layout=layout,
            schedule=schedule,
            pair_coeffs=pairs,
            # the leading pulse (peaks.leading_pulse): above the static force plus the reached floor
            lead_floor=lead_floor(scene),
            # the static force the leading pulse rises above: F0, or under gravity the largest (the
            # wall's: F0 + the chain's weight), a floor above every contact's own (ChainState.f0)
            lead_static=float(np.max(scene_static_forces(scene), initial=0.0)),
            # ... counted once the force has fallen by LAMMPS's force resolution below it (0: at once)
            lead_fall=lead_fall(scene),
            per_atom=per_atom,
            watch=watch,
            effect_blocks=effect_blocks(scene),
            pair_style_args="".join(e.pair_style_args(scene) for e in active_effects(scene))
            + sensor_args(scene, layout),
            energy_columns=energy_columns(scene, layout),
            **drive_values(scene),
            event=EventCheck.of(scene) if scene.wall_event else None,
            stop=(
                StopCheck(
                    stop,
                    stop + layout.offset,
                    stop_force_floor(scene),
                    fall=lead_fall(scene),
                    # the wall's contact lives on bead N's atom
                    wall_atom=scene.chain.beads + layout.offset if scene.run.stop_after_wall else 0,
                    # ... and contact 1's, for the wall's reflection coming back
                    back_atom=1 + layout.offset if scene.run.stop_after_reflection else 0,
                    **stop_statics(scene, stop),
                )
                if stop
                else None
            ),
        )
    )
    return Deck(deck=deck, data=render_data(scene) + watch.data_section, total_steps=schedule.total)
