"""Jinja2 LAMMPS decks: a base chain deck plus one block per effect the scene declares.

render_deck(scene) returns the deck text and the data file it reads (chain.data). Blocks:
contact_<law> (hertz | bilinear), loading_<force | velocity>, energy, histories (only when asked
for), and a snapshot write_dump at each snapshot time. Every number is written with repr(), the
shortest text that reads back to the same double. StrictUndefined: a missing value is an error.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources

import jinja2

from granchain.reference.solver import STOP_CHECK_EVERY, step_plan

LAMMPS_FILES = ("deck.lmp", "chain.data")


@dataclass(frozen=True)
class Deck:
    deck: str  # deck.lmp
    data: str  # chain.data
    total_steps: int


def _g(x) -> str:
    return repr(float(x))


def _env() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(resources.files("granchain") / "templates")),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
    )
    env.filters["g"] = _g
    return env


def history_stride(scene) -> int:
    """Steps between history samples: history_interval / timestep, at least 1."""
    if scene.outputs.history_interval is None:
        return 1
    return max(1, round(scene.outputs.history_interval / scene.run.timestep))


def dump_stride(scene) -> int:
    """Steps between whole-chain dump frames (0: no whole-chain dump)."""
    if scene.outputs.dump_interval is None:
        return 0
    return max(1, round(scene.outputs.dump_interval / scene.run.timestep))


def render_data(scene) -> str:
    n, d = scene.chain.beads, scene.diameter
    wall = scene.effects.far_end == "wall"
    w = 2.0 * d  # periodic y/z sides wider than cutoff + skin, so no bead sees its own image
    lines = [
        "granchain chain: bead i at x = (i-1) D, in contact with zero force",
        "",
        f"{n + wall} atoms",
        f"{1 + wall} atom types",
        "",
        f"{_g(-d)} {_g(n * d)} xlo xhi",
        f"{_g(-w)} {_g(w)} ylo yhi",
        f"{_g(-w)} {_g(w)} zlo zhi",
        "",
        "Atoms # sphere",
        "",
    ]
    rho = scene.chain.material.density
    lines += [f"{i + 1} 1 {_g(d)} {_g(rho)} {_g(i * d)} 0.0 0.0" for i in range(n)]
    if wall:  # the rigid flat: an atom at bead N's surface, never integrated
        lines.append(f"{n + 1} 2 {_g(d)} {_g(rho)} {_g((n - 1) * d + scene.chain.radius)} 0.0 0.0")
    return "\n".join(lines) + "\n"


def render_deck(scene) -> Deck:
    from granchain import __version__

    ld = scene.loading
    plan = step_plan(
        scene.run.end_time, scene.run.timestep, ld.duration if ld.is_force else 0.0, scene.outputs.snapshots
    )
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
    bilinear = scene.contact.law == "bilinear"
    peratom = ["d_fc", "d_fprev", "d_fprev2", "d_fpeak", "d_tpeak"]
    peratom += ["d_amax", "d_edis"] if bilinear else []
    peratom += ["d_edash"] if fx.dashpot else []
    r = scene.chain.radius
    coeffs = [{"i": 1, "j": 1, "k": scene.stiffness, "d0": scene.diameter}]
    if wall:  # bead-wall contact: distance from the bead's centre to the flat, R
        coeffs += [
            {"i": 1, "j": 2, "k": scene.wall_stiffness, "d0": r},
            {"i": 2, "j": 2, "k": scene.wall_stiffness, "d0": r},
        ]
    ctx = {
        "peratom": peratom,
        "pair_args": f" dashpot {fx.dashpot!r}" if fx.dashpot else "",
        "pair_coeffs": coeffs,
        "dashpot": fx.dashpot,
        "dissipation_terms": (["d_edis"] if bilinear else []) + (["d_edash"] if fx.dashpot else []),
        "wall": wall,
        "wall_k": scene.wall_stiffness if wall else 0.0,
        "beads": scene.chain.beads,
        "title": scene.title or "(untitled scene)",
        "source": scene.source or "<scene>",
        "version": __version__,
        "law": scene.contact.law,
        "k": scene.stiffness,
        "d0": scene.diameter,
        "beta": scene.contact.unloading_coeff if scene.contact.law == "bilinear" else 0.0,
        "skin": 0.2 * scene.diameter,
        "dt": dt,
        "loading": "force" if ld.is_force else "velocity",
        "amplitude": ld.amplitude,
        "duration": ld.duration,
        "velocity": ld.velocity,
        "energy_every": max(1, total // 200),
        "thermo_every": max(1, total // 20),
        "histories": list(scene.outputs.histories),
        "snapshots": list(scene.outputs.snapshots),
        "dump_stride": dump_stride(scene),
        "history_stride": history_stride(scene),
        "segments": segments,
        "stop_after": scene.run.stop_after_contact,
        "stop_every": STOP_CHECK_EVERY,
    }
    deck = _env().get_template("chain.lmp.j2").render(**ctx)
    return Deck(deck=deck, data=render_data(scene), total_steps=total)
