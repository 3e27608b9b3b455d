"""Jinja2 LAMMPS decks: a base chain deck plus one block per effect the scene declares.

render_deck(scene) returns the deck text and the data file it reads (chain.data). chain.lmp.j2 includes
a piece per effect: contact (the scene's law: its pair style and coefficients), damping, dissipation,
wall, loading_<force | velocity | striker>, precompression, energy, the run watch, histories, dumps, a
stop check, and a snapshot write_dump at each snapshot time. Its blocks (contact, energy_watch,
results) are what a yardstick overrides: render_deck(scene, yardstick="builtin") renders
builtin_granular.lmp.j2, which {% extends %} it with LAMMPS's built-in pair_style granular.

The templates read the scene's own objects (scene.loading, scene.effects, scene.law, ...) and a few
computed ones: layout (AtomLayout), schedule (Schedule), per_atom (PerAtom), pair_coeffs (PairCoeff),
watch (Watch), stop (StopCheck). Every number is written with repr(), the shortest text that reads
back to the same double. StrictUndefined: a missing value is an error. Free text (title, file name)
enters a deck only through the `comment` filter, as an inert comment; any other template value that
is not one line of printable text is an error."""

from __future__ import annotations

import dataclasses
import functools
import re
from dataclasses import dataclass
from importlib import resources

import jinja2
import numpy as np

from granchain._version import __version__
from granchain.errors import UsageError
from granchain.invariants import ENERGY_WATCH, MOMENTUM_WATCH, OVERLAP_WATCH
from granchain.peaks import PEAK_PASSED_FRACTION, lead_floor, stop_force_floor
from granchain.physics.effects import active_effects, external_forces
from granchain.physics.laws import ContactLaw
from granchain.problem import ChainProblem, initial_energy, precompressed_displacements
from granchain.results import scene_hash
from granchain.scene import SceneError
from granchain.schedule import STOP_CHECK_EVERY, dump_stride, history_stride, scene_step_plan

#: steps between two checks of the LAMMPS run watch (the reference checks every 20 steps as well)
WATCH_EVERY = 20

LAMMPS_FILES = ("deck.lmp", "chain.data")

#: The per-atom results a LAMMPS run ends with: the one list. The deck's last command writes them,
#: by atom ID at full precision, into RESULTS_DUMP (the results block of chain.lmp.j2), and
#: granchain.lammps.runner.read_results reads them back by the dump's own column names, for runs
#: through the Python module and for plain-LAMMPS runs (granchain collect) alike; a column added
#: here is written by every deck rendered from now on and read by both. Each is a dump custom
#: column; a per-atom vector d_NAME is written only when the deck declares it (d_amax: a law with
#: history; the built-in granular yardstick has d_fpeak and d_tpeak only) and is read as NAME.
RESULT_COLUMNS = (
    "x",  # final position (m)
    "vx",  # final velocity (m/s)
    "d_fpeak",  # running peak force of the contact that lives on this atom (N)
    "d_tpeak",  # its time (s)
    "d_fmin",  # the smallest force since that peak (complete peaks)
    "d_flead",  # the leading pulse: the contact's first maximum above the floor (N)
    "d_tlead",  # its time (s)
    "d_amax",  # a law with history: the largest overlap so far (m)
)

#: the deck's results dump (RESULT_COLUMNS) and the run's last step and time ("step time"); the
#: dump is the last file a deck writes, so its presence marks a finished run
RESULTS_DUMP = "peaks.dump"
RUN_END_FILE = "run_end.txt"


def result_columns(declared) -> list[str]:
    """RESULT_COLUMNS that a deck declaring these per-atom vectors (d_NAME) can write."""
    return [c for c in RESULT_COLUMNS if not c.startswith("d_") or c in set(declared)]


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
        from the sample's own numbers) instead of fix print, which flushed every line, and the balance
        as LAMMPS variables read by fix ave/time and fix halt
    """

    neigh_every: int = 10
    watch_computes: bool = False
    chain_nve: bool = False
    history_file: str = "dump"
    energy_fix: bool = False

    def __post_init__(self):
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
    deck: str  # deck.lmp
    data: str  # chain.data
    total_steps: int


def _g(x) -> str:
    return repr(float(x))


def comment(text) -> str:
    """Any text (a scene's title, a file name) as the payload of one inert comment line of a deck.

    LAMMPS reads a line up to '\\n' only, joins the next line when the last non-blank character is
    '&', keeps reading while a line holds an odd number of triple quotes, loses the line end after a
    NUL, and only then drops the comment (input.cpp: Input::file, Input::parse). So: every character
    that is not printable (line and paragraph breaks of C and of str.splitlines, NUL, tabs, other
    controls, lone surrogates from undecodable file names) becomes a space (white space) or '?';
    '&' becomes '+' and '"' becomes "'", so the text holds no continuation and no triple quote
    wherever it sits on the line. '$' stays: LAMMPS drops a comment before it substitutes variables.
    """
    out = []
    for ch in str(text):
        if ch == "&":
            out.append("+")
        elif ch == '"':
            out.append("'")
        elif ch.isprintable():
            out.append(ch)
        else:
            out.append(" " if ch.isspace() else "?")
    return "".join(out)


def _one_line(value):
    """Every {{ expression }} of the templates: text that would break a deck line is an error (free
    text goes through the comment filter; the rest is numbers and the templates' own words)."""
    if isinstance(value, str) and not value.isprintable():
        raise ValueError(f"deck template value {value!r} is not one line of printable text")
    return value


def law_parameters(law) -> dict:
    """The law's parameters, name -> value (the deck's comment on the nominal pair names them)."""
    return {f.name: float(getattr(law, f.name)) for f in dataclasses.fields(law)}


def _is_atom_x(expr: str) -> bool:
    """A LAMMPS expression that is an atom's x by ID, x[ID] (fix chain/energy reads those itself)."""
    return re.fullmatch(r"x\[\d+\]", expr) is not None


@functools.lru_cache(maxsize=1)
def _env() -> jinja2.Environment:
    # one environment per process: it keeps the compiled templates (a new one per deck recompiled every
    # template, 25-50 ms of a campaign point's overhead)
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(resources.files("granchain") / "templates")),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
        finalize=_one_line,
    )
    env.filters["g"] = _g
    env.filters["comment"] = comment
    env.filters["parameters"] = law_parameters
    env.tests["atom_x"] = _is_atom_x
    env.globals.update(RESULTS_DUMP=RESULTS_DUMP, RUN_END_FILE=RUN_END_FILE)
    return env


def largest_radius(scene) -> float:
    """The largest radius of the deck's moving bodies: the beads' and a striker's (a striker larger than
    the beads must not see its own periodic image across y and z, and its cutoff sets the bins)."""
    r = float(max(scene.bead_radii)) if scene.per_bead else float(scene.chain.radius)
    if scene.loading.kind == "striker":
        r = max(r, float(scene.loading.striker_radius))
    return r


@dataclass(frozen=True)
class AtomLayout:
    """Atom IDs and types: the atoms of effects with beads in front (a striker, ID 1), the beads, the
    other effects' atoms (a wall, last); each effect's atom a type of its own (Effect.atom_type), in
    registry order after the beads'.

    Contact i (beads i and i+1) lives on the atom of bead i, ID i + offset.
    """

    beads: int
    extra_types: tuple[str, ...]  # the effects' atom types, in registry order
    offset: int  # atoms in front of bead 1 (Effect.beads_in_front)
    skin: float  # neighbor skin: 0.2 x the smallest bead diameter
    rmax: float  # the largest radius of a body that moves (beads, a striker)
    bead_types: int = 1  # bead kinds (Scene.bead_kinds): types 1..bead_types
    last_bead_type: int = 1  # bead N's type

    @classmethod
    def of(cls, scene) -> AtomLayout:
        skin = 0.2 * 2.0 * float(min(scene.bead_radii)) if scene.per_bead else 0.2 * scene.diameter
        rmax = largest_radius(scene)
        active = active_effects(scene)
        extra = tuple(e.atom_type for e in active if e.atom_type)
        kinds, kind_of = bead_kinds(scene) if scene.per_bead else ([None], [0])
        front = sum(e.beads_in_front for e in active)
        return cls(scene.chain.beads, extra, front, skin, rmax, len(kinds), kind_of[-1] + 1)

    @property
    def binsize(self) -> float:
        """Bins for neighbour builds and atom sorting: 2 x (the contact distance + skin), wider than
        LAMMPS's default half of it. A chain along x needs few bins across; at the default 1e6 beads
        took 83 million bins (a third of a GB)."""
        return 2.0 * (2.0 * self.rmax + self.skin)

    @property
    def striker(self) -> bool:
        return "striker" in self.extra_types

    @property
    def wall(self) -> bool:
        """A wall atom: the deck integrates the group mobile (all but the wall) instead of all."""
        return "wall" in self.extra_types

    @property
    def types(self) -> dict[str, int]:
        """Atom types: the bead kinds first (1..bead_types; "bead" names the first), then each
        effect's atom, in registry order."""
        first = self.bead_types + 1
        return {"bead": 1, **{name: first + i for i, name in enumerate(self.extra_types)}}

    @property
    def natoms(self) -> int:
        return self.beads + len(self.extra_types)

    @property
    def first_id(self) -> int:
        """Bead 1's atom."""
        return 1 + self.offset

    @property
    def last_id(self) -> int:
        """Bead N's atom."""
        return self.beads + self.offset

    @property
    def wall_id(self) -> int:
        return self.last_id + 1

    def ids(self, contacts) -> list[int]:
        """The atoms contacts live on (bead i's)."""
        return [i + self.offset for i in contacts]


def atom_layout(scene) -> dict:
    """AtomLayout as a dict: offset, striker, wall, types, natoms."""
    lay = AtomLayout.of(scene)
    return {"offset": lay.offset, "striker": lay.striker, "wall": lay.wall, "types": lay.types, "natoms": lay.natoms}


def precompression_overlaps(scene) -> dict:
    """Static overlaps for the deck: bead-bead contacts ("beads": one value on a chain of one bead
    kind; "per_contact": (atom, overlap) of each bead-bead contact on a per-bead chain, on its left
    bead's atom), and the wall's (0 without precompression). A striker's contact starts unloaded."""
    if not scene.effects.precompression:
        return {"beads": 0.0, "wall": 0.0, "per_contact": []}
    alpha0 = precompressed_displacements(scene)[1]
    wall = scene.effects.far_end == "wall"
    layout = AtomLayout.of(scene)
    per_contact = []
    if scene.per_bead:
        per_contact = [(layout.first_id + i, float(alpha0[i])) for i in range(scene.n_contacts)]
    beads = float(alpha0[0]) if scene.n_contacts else 0.0  # (one bead: only the wall's contact)
    return {"beads": beads, "wall": float(alpha0[-1]) if wall else 0.0, "per_contact": per_contact}


MAX_BEAD_KINDS = 200  # pair_coeff lines grow as kinds^2 / 2


def bead_kinds(scene) -> tuple[list[tuple[float, object]], list[int]]:
    """Scene.bead_kinds, at most MAX_BEAD_KINDS of them (one atom type each); atom type = kind + 1."""
    kinds, kind_of = scene.bead_kinds
    if len(kinds) > MAX_BEAD_KINDS:
        raise SceneError(
            f"{scene.source}: the chain has {len(kinds)} distinct bead kinds (radius, material); the LAMMPS "
            f"backend takes at most {MAX_BEAD_KINDS} (one atom type each); use the reference backend"
        )
    return kinds, kind_of


def render_data(scene) -> str:
    n, d = scene.chain.beads, scene.diameter
    lay = atom_layout(scene)
    rmax = largest_radius(scene)
    w = 4.0 * rmax  # periodic y/z sides wider than cutoff + skin, so no body sees its own image
    rho = scene.chain.material.density
    u0 = np.zeros(n)
    if scene.effects.precompression:
        u0 = precompressed_displacements(scene)[0]
    # touching with zero force, overlaps exactly 0 in LAMMPS's arithmetic; displaced by a precompression
    x = scene.bead_positions + u0
    front: list[tuple[int, float, float, float]] = []  # the effects' atoms (Effect.data_atoms)
    back: list[tuple[int, float, float, float]] = []
    for effect in active_effects(scene):
        (front if effect.beads_in_front else back).extend(effect.data_atoms(scene, lay["types"], x))
    atoms = list(front)
    if scene.per_bead:  # one atom type per distinct (radius, material): see bead_kinds
        kinds, kind_of = bead_kinds(scene)
        atoms += [(kind_of[i] + 1, 2.0 * kinds[kind_of[i]][0], kinds[kind_of[i]][1].density, x[i]) for i in range(n)]
    else:
        atoms += [(1, d, rho, x[i]) for i in range(n)]
    atoms += back
    xlo = min(a[3] for a in atoms) - 2.0 * rmax
    xhi = max(a[3] for a in atoms) + 2.0 * rmax
    lines = [
        "granchain chain: beads in contact with zero force, on an exact grid (granchain.physics.positions)",
        "",
        f"{len(atoms)} atoms",
        f"{max(a[0] for a in atoms)} atom types",
        "",
        f"{_g(xlo)} {_g(xhi)} xlo xhi",
        f"{_g(-w)} {_g(w)} ylo yhi",
        f"{_g(-w)} {_g(w)} zlo zhi",
        "",
        "Atoms # sphere",
        "",
    ]
    lines += [f"{i + 1} {t} {_g(dd)} {_g(rr)} {_g(x)} 0.0 0.0" for i, (t, dd, rr, x) in enumerate(atoms)]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class Watch:
    """The run watch's bounds (granchain.invariants, the same as the reference's) and what its energy
    and momentum balances start from: the energy at t = 0 (problem.initial_energy, where the
    reference's bookkeeping starts), bead 1's and bead N's x at t = 0, the initial momentum."""

    force: float  # the largest force any contact can have at OVERLAP_WATCH x the smallest radius
    e0: float
    x1_0: float
    xn_0: float
    p0: float
    momentum: bool  # no effect exerts external forces: the momentum is the impulse delivered
    effects_work: str  # the effects' work as LAMMPS expression terms (Effect.watch_work)
    every: int = WATCH_EVERY
    energy_bound: float = ENERGY_WATCH
    momentum_bound: float = MOMENTUM_WATCH

    @classmethod
    def of(cls, scene, pairs) -> Watch:
        e0 = initial_energy(ChainProblem.from_scene(scene))
        u0 = precompressed_displacements(scene)[0] if scene.effects.precompression else np.zeros(scene.chain.beads)
        x0 = scene.bead_positions  # as render_data writes them
        # on each contact's virgin curve: Hertz k a^1.5, bilinear k a, ...
        a_watch = OVERLAP_WATCH * float(min(scene.bead_radii))
        problem, layout = ChainProblem.from_scene(scene), AtomLayout.of(scene)
        x1_0, xn_0 = float(x0[0] + u0[0]), float(x0[-1] + u0[-1])
        x_first, x_last = f"x[{layout.first_id}] - {x1_0!r}", f"x[{layout.last_id}] - {xn_0!r}"
        return cls(
            force=max(float(p.law.loading_force(a_watch)) for p in pairs),
            e0=e0,
            x1_0=x1_0,
            xn_0=xn_0,
            p0=scene.initial_momentum,
            momentum=not external_forces(scene),
            effects_work="".join(e.watch_work(problem, x_first, x_last) for e in active_effects(scene)),
        )


@dataclass(frozen=True)
class PairCoeff:
    """One pair_coeff line: atom types I and J, their contact's law and contact distance d0."""

    i: int
    j: int
    law: ContactLaw
    d0: float

    @property
    def args(self) -> list[float]:
        """pair_coeff I J k d0 [the law's other coefficients] (granchain.physics.laws.base, rule 5)."""
        k, *extra = self.law.pair_coefficients()
        return [k, self.d0, *extra]


def pair_coeffs(scene, layout: AtomLayout) -> list[PairCoeff]:
    """Every type pair's contact: beads (one type per bead kind of a per-bead chain), the wall's
    (distance from the bead's centre to the flat, R) and the striker's (R_s + R; striker and wall
    never meet, but their coefficients are required)."""
    rc = scene.contact_radius  # contact distances on the positions' grid: at-rest overlaps exactly 0
    pairs = [PairCoeff(1, 1, scene.law, 2.0 * rc(scene.chain.radius))]
    if scene.per_bead:
        kinds, _ = bead_kinds(scene)
        pairs = [
            PairCoeff(a + 1, b + 1, scene.bead_pair_law(*kinds[a], *kinds[b]), rc(kinds[a][0]) + rc(kinds[b][0]))
            for a in range(len(kinds))
            for b in range(a, len(kinds))
        ]
    for effect in active_effects(scene):  # the effects' atom types (Effect.pair_coeffs)
        pairs += [PairCoeff(*c) for c in effect.pair_coeffs(scene, layout.types)]
    return pairs


@dataclass(frozen=True)
class PerAtom:
    """The per-atom vectors a deck declares (fix contact ... property/atom) and, of them, the
    energies dissipated so far; the results dump writes the RESULT_COLUMNS among them."""

    vectors: tuple[str, ...]
    dissipated: tuple[str, ...] = ()

    @classmethod
    def of(cls, scene) -> PerAtom:
        """The chain deck's: force, its last two values, running peak and its time; a law with history:
        alpha_max and the energy it dissipated; a dashpot: its energy; completion; the leading pulse."""
        history = scene.contact.law_class.history
        dissipated = (["d_edis"] if history else []) + [v for e in active_effects(scene) for v in e.dissipated_vectors]
        vectors = ["d_fc", "d_fprev", "d_fprev2", "d_fpeak", "d_tpeak"] + (["d_amax"] if history else [])
        return cls((*vectors, *dissipated, "d_fmin", "d_flead", "d_tlead"), tuple(dissipated))

    @property
    def results(self) -> list[str]:
        return result_columns(self.vectors)


@dataclass(frozen=True)
class Schedule:
    """The deck's steps: the step plan (granchain.schedule: its segments end at the load's end, every
    snapshot and the end time) and the strides of the samples."""

    segments: list  # schedule.Segment
    dump_stride: int  # 0: no whole-chain dump
    history_stride: int

    @classmethod
    def of(cls, scene) -> Schedule:
        return cls(scene_step_plan(scene), dump_stride(scene), history_stride(scene))

    @property
    def total(self) -> int:
        return sum(g.steps for g in self.segments)

    @property
    def energy_every(self) -> int:
        return max(1, self.total // 200)

    @property
    def thermo_every(self) -> int:
        return max(1, self.total // 20)


@dataclass(frozen=True)
class StopCheck:
    """[run] stop_after_contact: the wave has passed the contact once its force is back below
    PEAK_PASSED_FRACTION of its rise above F0, after a peak above the floor."""

    contact: int
    atom: int
    floor: float
    every: int = STOP_CHECK_EVERY
    fraction: float = PEAK_PASSED_FRACTION


#: the per-atom vectors of the built-in granular yardstick: the chain deck's first five, which its
#: run watch, stop check and results dump read (pair_style granular fills none of them)
BUILTIN_GRANULAR_PER_ATOM = PerAtom(("d_fc", "d_fprev", "d_fprev2", "d_fpeak", "d_tpeak"))


def builtin_granular_refusal(scene) -> str | None:
    """Why LAMMPS's built-in pair_style granular cannot run this scene as our pair style would, or
    None: the yardstick is an elastic Hertz chain of one material (pair_coeff * * hertz/material E 0 nu)."""
    materials = set(scene.bead_materials)
    if scene.loading.kind == "striker":
        materials.add(scene.loading.striker_material)
    why = {
        f"the {scene.contact.law} law (the yardstick is Hertz)": scene.contact.law != "hertz",
        **{e.yardstick: True for e in active_effects(scene) if e.yardstick},
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


def energy_columns(scene, layout: AtomLayout) -> dict[str, tuple[str, str]]:
    """The energy samples' columns after x1 that the effects add: name -> (LAMMPS expression, words)."""
    return {k: v for e in active_effects(scene) for k, v in e.energy_columns(layout).items()}


def render_deck(scene, yardstick: str | None = None, options: DeckOptions = DECK_OPTIONS) -> Deck:
    """The scene's deck (chain.lmp.j2: our pair style) and its data file. yardstick="builtin": the
    same chain with LAMMPS's built-in pair_style granular instead (builtin_granular.lmp.j2 extends
    chain.lmp.j2), the yardstick chain/hertz is tested and timed against. options: DeckOptions."""
    template, per_atom = _template(scene, yardstick)
    schedule, layout = Schedule.of(scene), AtomLayout.of(scene)
    pairs = pair_coeffs(scene, layout)
    stop = scene.run.stop_after_contact
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
            per_atom=per_atom,
            static_overlaps=precompression_overlaps(scene),
            watch=Watch.of(scene, pairs),
            effect_blocks=effect_blocks(scene),
            pair_style_args="".join(e.pair_style_args(scene) for e in active_effects(scene)),
            energy_columns=energy_columns(scene, layout),
            stop=StopCheck(stop, stop + layout.offset, stop_force_floor(scene)) if stop else None,
        )
    )
    return Deck(deck=deck, data=render_data(scene), total_steps=schedule.total)
