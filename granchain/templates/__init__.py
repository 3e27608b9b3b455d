"""Jinja2 LAMMPS decks: a base chain deck plus one block per effect the scene declares.

render_deck(scene) returns the deck text and the data file it reads (chain.data). Blocks: contact
(the scene's law: its pair style and coefficients), loading_<force | velocity>, energy, histories
(only when asked for), and a snapshot write_dump at each snapshot time. Every number is written with repr(), the
shortest text that reads back to the same double. StrictUndefined: a missing value is an error.
Free text (title, file name) enters a deck only through the `comment` filter, as an inert comment;
any other template value that is not one line of printable text is an error.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from importlib import resources

import jinja2
import numpy as np

from granchain._version import __version__
from granchain.invariants import ENERGY_WATCH, MOMENTUM_WATCH, OVERLAP_WATCH
from granchain.peaks import PEAK_PASSED_FRACTION, lead_floor, stop_force_floor
from granchain.problem import ChainProblem, initial_energy, precompressed_displacements
from granchain.results import scene_hash
from granchain.scene import SceneError
from granchain.schedule import STOP_CHECK_EVERY, dump_stride, history_stride, scene_step_plan

#: steps between two checks of the LAMMPS run watch (the reference checks every 20 steps as well)
WATCH_EVERY = 20

LAMMPS_FILES = ("deck.lmp", "chain.data")

#: The per-atom results a LAMMPS run ends with: the one list. The deck's last command writes them,
#: by atom ID at full precision, into RESULTS_DUMP (results_dump_command), and
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


def results_dump_command(columns) -> str:
    """The deck's write_dump of the results (RESULT_COLUMNS), by atom ID, %.17g (round-trip doubles)."""
    return f"write_dump      all custom {RESULTS_DUMP} id {' '.join(columns)} modify format float %.17g sort id"


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


def _env() -> jinja2.Environment:
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
    return env


def atom_layout(scene) -> dict:
    """Atom IDs and types: an optional striker first (ID 1), beads, an optional wall last.

    Contact i (beads i and i+1) lives on the atom of bead i, ID i + offset.
    """
    striker = scene.loading.kind == "striker"
    wall = scene.effects.far_end == "wall"
    types = {"bead": 1}
    if wall:
        types["wall"] = len(types) + 1
    if striker:
        types["striker"] = len(types) + 1
    return {
        "offset": int(striker),
        "striker": striker,
        "wall": wall,
        "types": types,
        "natoms": scene.chain.beads + striker + wall,
    }


def precompression_overlaps(scene) -> dict:
    """Static overlaps for the deck: bead-bead contacts, and the wall's (0 without precompression)."""
    if not scene.effects.precompression:
        return {"beads": 0.0, "wall": 0.0}
    alpha0 = precompressed_displacements(scene)[1]
    wall = scene.effects.far_end == "wall"
    return {"beads": float(alpha0[0]), "wall": float(alpha0[-1]) if wall else 0.0}


MAX_BEAD_KINDS = 200  # pair_coeff lines grow as kinds^2 / 2


def bead_kinds(scene) -> tuple[list[tuple[float, object]], list[int]]:
    """Distinct (radius, material) kinds of a per-bead chain and each bead's kind; atom type = kind + 1."""
    kinds: list[tuple[float, object]] = []
    index: dict = {}
    kind_of = []
    for r, m in zip(scene.bead_radii, scene.bead_materials, strict=True):
        key = (float(r), m)
        if key not in index:
            index[key] = len(kinds)
            kinds.append(key)
        kind_of.append(index[key])
    if len(kinds) > MAX_BEAD_KINDS:
        raise SceneError(
            f"{scene.source}: the chain has {len(kinds)} distinct bead kinds (radius, material); the LAMMPS "
            f"backend takes at most {MAX_BEAD_KINDS} (one atom type each); use the reference backend"
        )
    return kinds, kind_of


def render_data(scene) -> str:
    n, d = scene.chain.beads, scene.diameter
    lay = atom_layout(scene)
    rmax = float(max(scene.bead_radii)) if scene.per_bead else scene.chain.radius
    w = 4.0 * rmax  # periodic y/z sides wider than cutoff + skin, so no bead sees its own image
    rho = scene.chain.material.density
    atoms = []
    if lay["striker"]:  # touching bead 1 from the left
        ld = scene.loading
        ds = 2.0 * ld.striker_radius
        rho_s = scene.striker_mass / (math.pi * ds**3 / 6.0)  # the requested mass exactly
        atoms.append((lay["types"]["striker"], ds, rho_s, -(ld.striker_radius + scene.chain.radius)))
    u0 = np.zeros(n)
    if scene.effects.precompression:
        u0 = precompressed_displacements(scene)[0]
    if scene.per_bead:  # one atom type per distinct (radius, material): see bead_kinds
        kinds, kind_of = bead_kinds(scene)
        x0 = scene.bead_positions
        atoms += [(kind_of[i] + 1, 2.0 * kinds[kind_of[i]][0], kinds[kind_of[i]][1].density, x0[i]) for i in range(n)]
    else:
        atoms += [(1, d, rho, i * d + u0[i]) for i in range(n)]
    if lay["wall"]:  # the rigid flat: an atom at bead N's surface, never integrated
        atoms.append((lay["types"]["wall"], d, rho, (n - 1) * d + scene.chain.radius))
    xlo = min(a[3] for a in atoms) - 2.0 * rmax
    xhi = max(a[3] for a in atoms) + 2.0 * rmax
    lines = [
        "granchain chain: bead i at x = (i-1) D, in contact with zero force",
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


def energy_watch_terms(scene) -> dict:
    """What the deck's in-run energy and momentum watch needs (granchain.invariants, same bounds as
    the reference): the energy at t = 0 (problem.initial_energy, where the reference's bookkeeping
    starts), bead 1's and bead N's x at t = 0, and the initial momentum of a free chain."""
    e0 = initial_energy(ChainProblem.from_scene(scene))
    u0 = precompressed_displacements(scene)[0] if scene.effects.precompression else np.zeros(scene.chain.beads)
    x0 = scene.bead_positions if scene.per_bead else np.arange(scene.chain.beads) * scene.diameter
    f0, lay = float(scene.effects.precompression), atom_layout(scene)
    static_work = ""  # the static forces' work: the push on bead 1 and, without a wall, the pull on bead N
    if f0:
        static_work = f" + {f0!r}*(x[{1 + lay['offset']}] - {float(x0[0] + u0[0])!r})"
        if scene.effects.far_end != "wall":
            static_work += f" - {f0!r}*(x[{scene.chain.beads + lay['offset']}] - {float(x0[-1] + u0[-1])!r})"
    return {
        "watch_static_work": static_work,
        "energy_watch": ENERGY_WATCH,
        "momentum_watch": MOMENTUM_WATCH,
        "e0": e0,
        "x1_0": float(x0[0] + u0[0]),
        "xn_0": float(x0[-1] + u0[-1]),
        "p0": scene.initial_momentum,
        "watch_momentum": scene.effects.far_end == "free" and not scene.effects.precompression,
    }


def law_parameters(law) -> dict:
    """The nominal pair's law parameters (the deck's comment names them)."""
    return {f.name: float(getattr(law, f.name)) for f in dataclasses.fields(law)}


def builtin_granular_deck(deck: str, scene) -> str:
    """The same deck with LAMMPS's built-in pair_style granular (hertz/material, no damping, no
    tangential force) instead of chain/hertz: the yardstick our pair style is tested and timed
    against. The built-in style tallies no contact energy, so the energy watch is left out."""
    m = scene.chain.material
    builtin = ("d_fc", "d_fprev", "d_fprev2", "d_fpeak", "d_tpeak")
    deck = re.sub(
        rf"^write_dump\s+all custom {re.escape(RESULTS_DUMP)} .*$",
        results_dump_command(result_columns(builtin)),
        deck,
        flags=re.M,
    )
    start = deck.index("\n# ---- contact law") + 1  # at a line start: a title may hold these words
    end = deck.index("\nneighbor ", start) + 1
    return (
        deck[:start]
        + f"fix             contact all property/atom {' '.join(builtin)} ghost yes\n"
        + "pair_style      granular\n"
        + f"pair_coeff      * * hertz/material {m.youngs_modulus!r} 0.0 {m.poisson_ratio!r} "
        + "tangential linear_nohistory 0.0 0.0 damping viscoelastic\n"
        + "comm_modify     vel yes\n\n"
        + deck[end:]
    ).replace("\nfix             watch_energy", "\n# (no energy tallied) fix watch_energy")


def render_deck(scene) -> Deck:
    ld = scene.loading
    plan = scene_step_plan(scene)
    snaps = {t: k for k, t in enumerate(scene.outputs.snapshots)}
    dt = scene.run.timestep
    segments = [
        {
            "start": g.start,
            "end": g.end,
            "steps": g.steps,
            "last": g.last,
            "last_is_dt": g.last == dt,
            "load_ends": ld.is_force and g.end == ld.duration,
            "snapshot": snaps.get(g.end),
        }
        for g in plan
    ]
    total = sum(g.steps for g in plan)
    fx = scene.effects
    wall = fx.far_end == "wall"
    law_cls = scene.contact.law_class
    peratom = ["d_fc", "d_fprev", "d_fprev2", "d_fpeak", "d_tpeak"]
    peratom += ["d_amax", "d_edis"] if law_cls.history else []  # alpha_max and the energy it dissipated
    peratom += ["d_edash"] if fx.dashpot else []
    peratom += ["d_fmin", "d_flead", "d_tlead"]  # completion; the leading pulse
    r = scene.chain.radius
    lay = atom_layout(scene)
    tw, ts = lay["types"].get("wall"), lay["types"].get("striker")
    pairs = [(1, 1, scene.law, scene.diameter)]  # (type I, type J, the pair's law, contact distance d0)
    if scene.per_bead:
        kinds, _ = bead_kinds(scene)
        pairs = [
            (
                a + 1,
                b + 1,
                scene.bead_pair_law(kinds[a][0], kinds[a][1], kinds[b][0], kinds[b][1]),
                kinds[a][0] + kinds[b][0],
            )
            for a in range(len(kinds))
            for b in range(a, len(kinds))
        ]
    if wall:  # bead-wall contact: distance from the bead's centre to the flat, R
        pairs += [(1, tw, scene.wall_law, r), (tw, tw, scene.wall_law, r)]
    if ts:  # striker-bead contact at R_s + R; striker-wall never meet (coefficients are required)
        rs = scene.loading.striker_radius
        pairs += [(1, ts, scene.striker_law, rs + r), (ts, ts, scene.striker_law, 2 * rs)]
        if wall:
            pairs.append((tw, ts, scene.striker_law, rs))
    # pair_coeff I J k d0 [the law's other coefficients] (granchain.physics.laws.base, rule 5)
    coeffs = []
    for i, j, law, d0 in pairs:
        k, *extra = law.pair_coefficients()
        coeffs.append({"i": i, "j": j, "args": [k, d0, *extra]})
    # the run watch's force bound: the largest force any contact can have at OVERLAP_WATCH x the
    # smallest radius (on its virgin curve: Hertz k a^1.5, bilinear k a, ...)
    a_watch = OVERLAP_WATCH * float(min(scene.bead_radii))
    watch_force = max(float(law.loading_force(a_watch)) for _, _, law, _ in pairs)
    ctx = {
        **energy_watch_terms(scene),
        "watch_force": watch_force,
        "watch_every": WATCH_EVERY,
        "peratom": peratom,
        "results_dump": results_dump_command(result_columns(peratom)),
        "results_end": RUN_END_FILE,
        "results_file": RESULTS_DUMP,
        "scene_sha256": scene_hash(scene),
        # the leading pulse (peaks.leading_pulse): above the static force plus the reached floor
        "pair_args": f" lead {lead_floor(scene)!r} {float(fx.precompression)!r}"
        + (f" dashpot {fx.dashpot!r}" if fx.dashpot else ""),
        "pair_coeffs": coeffs,
        "dashpot": fx.dashpot,
        "dissipation_terms": (["d_edis"] if law_cls.history else []) + (["d_edash"] if fx.dashpot else []),
        "wall": wall,
        "wall_k": scene.wall_stiffness if wall else 0.0,
        "beads": scene.chain.beads,
        "title": scene.title or "(untitled scene)",
        "source": scene.source or "<scene>",
        "version": __version__,
        "law": scene.contact.law,
        "pair_style": law_cls.pair_style,
        "law_history": law_cls.history,
        "law_parameters": ", ".join(f"{k} = {v!r}" for k, v in law_parameters(scene.law).items()),
        "skin": 0.2 * 2.0 * float(min(scene.bead_radii)) if scene.per_bead else 0.2 * scene.diameter,
        "dt": dt,
        "loading": "force" if ld.is_force else ld.kind,
        "amplitude": ld.amplitude,
        "duration": ld.duration,
        "velocity": ld.velocity,
        "energy_every": max(1, total // 200),
        "thermo_every": max(1, total // 20),
        "histories": list(scene.outputs.histories),
        "history_ids": [i + lay["offset"] for i in scene.outputs.histories],
        "offset": lay["offset"],
        "striker": lay["striker"],
        "striker_mass": scene.striker_mass if lay["striker"] else 0.0,
        "wall_id": scene.chain.beads + lay["offset"] + 1,
        "snapshots": list(scene.outputs.snapshots),
        "dump_stride": dump_stride(scene),
        "history_stride": history_stride(scene),
        "segments": segments,
        "precompression": fx.precompression,
        "pre_alpha": precompression_overlaps(scene),
        "first_id": 1 + lay["offset"],
        "last_id": scene.chain.beads + lay["offset"],
        "stop_after": scene.run.stop_after_contact,
        "stop_id": (scene.run.stop_after_contact or 0) + lay["offset"],
        "stop_every": STOP_CHECK_EVERY,
        "stop_floor": stop_force_floor(scene) if scene.run.stop_after_contact else 0.0,
        "stop_f0": float(fx.precompression),  # the wave has passed: its force back below half its rise
        "stop_fraction": PEAK_PASSED_FRACTION,
    }
    deck = _env().get_template("chain.lmp.j2").render(**ctx)
    return Deck(deck=deck, data=render_data(scene), total_steps=total)
