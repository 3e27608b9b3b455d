"""How granchain's objects show themselves in a terminal and a notebook: printable text, numbers as a
researcher writes them, the small HTML table every ``_repr_html_`` draws, and a scene's facts (its
source, beads, law, loading, run and effects, each with its unit) that Scene's reprs are made of.

It sits at the bottom of the scene package so that the scene's model and everything above it (the
results, the plan, the comparison) draw their displays with the same code.
"""

from __future__ import annotations

import html
from typing import Any

from granchain.physics.effects import sections
from granchain.scene.limits import MATERIAL_UNITS, SCENE_KEY_UNITS

#: units of the scene keys a campaign varies or a display shows, by dotted name ("1": dimensionless):
#: the scene reader's (limits.SCENE_KEY_UNITS) and the chain's material's
KEY_UNITS = {**SCENE_KEY_UNITS, **{f"chain.material.{k}": u for k, u in MATERIAL_UNITS.items()}}


def printable(text: str, limit: int | None = None, keep: str = "") -> str:
    r"""text with its control characters escaped (ESC as \x1b, a newline as \n ...): scene text
    shown on a terminal can neither move the cursor nor retitle the window. Cut to limit characters;
    the characters in keep (e.g. "\n" for a message of several lines) stay as they are."""
    out = "".join(
        ch
        if ch.isprintable() or ch in keep
        else (ch.encode("unicode_escape").decode("ascii") if ord(ch) < 0x10000 else repr(ch)[1:-1])
        for ch in str(text)
    )
    if limit is not None and len(out) > limit:
        out = out[: limit - 3] + "..."
    return out


def number(v: Any) -> str:
    """A value as a researcher writes it: a float to 6 significant digits (400000.00000000006 as
    400000, 4.76e-3 as 0.00476), None as "auto" (the planner's), anything else as it prints."""
    if v is None:
        return "auto"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def html_table(rows: list[tuple], caption: str, header: tuple = ()) -> str:
    """A small HTML table under a caption: each row's first cell its name, then its values (a value
    and its unit; a plan's choice, its unit and reason), an optional header row; every cell escaped (a
    scene's title or a summary's text cannot inject markup into a notebook)."""
    esc = lambda x: html.escape(printable(str(x), 1000))  # noqa: E731
    head = "<tr>" + "".join(f"<th>{esc(h)}</th>" for h in header) + "</tr>" if header else ""
    body = "".join(
        f"<tr><th style='text-align:left'>{esc(row[0])}</th>" + "".join(f"<td>{esc(c)}</td>" for c in row[1:]) + "</tr>"
        for row in rows
    )
    return f"<table><caption>{esc(caption)}</caption>{head}{body}</table>"


def key_unit(name: str) -> str:
    """The unit of a scene key by its name in [chain], [run] or [outputs] (a plan's choice: "timestep",
    "beads"), or by its dotted name; "" unknown."""
    if name in KEY_UNITS:
        return KEY_UNITS[name]
    return next((KEY_UNITS[f"{s}.{name}"] for s in ("chain", "run", "outputs") if f"{s}.{name}" in KEY_UNITS), "")


def _material(name: str | None, material) -> str:
    return name if name is not None else f"inline (rho {number(material.density)} kg/m^3)"


def _loading_facts(ld) -> list[tuple[str, str, str]]:
    """(name, value, unit) of the load: its kind, then the values that kind is given by."""
    if ld.kind == "step":
        values = [("amplitude A", ld.amplitude, "N"), ("duration T", ld.duration, "s")]
    elif ld.kind == "impulse":
        values = [("impulse I", ld.impulse, "N s"), ("duration T", ld.duration, "s")]
    elif ld.is_harmonic:
        values = [("amplitude A", ld.amplitude, "m" if ld.is_shaker else "N"), ("frequency f", ld.frequency, "Hz")]
        values += [("duration T", ld.duration, "s"), ("cycles", ld.cycles, ""), ("ramp", ld.ramp, "periods")]
    elif ld.kind == "velocity":
        values = [("bead 1's velocity v", ld.velocity, "m/s")]
    else:
        values = [("striker's velocity v", ld.velocity, "m/s"), ("striker's radius", ld.striker_radius, "m")]
        if ld.striker_mass is not None:
            values.append(("striker's mass M", ld.striker_mass, "kg"))
    return [("loading", ld.kind, ""), *((k, number(v), u) for k, v, u in values)]


def with_unit(value: str, unit: str) -> str:
    """A shown value and its unit ("2.5e-07 s"); a dimensionless ("1") or "auto" value alone."""
    return f"{value} {unit}" if unit not in ("", "1") and value != "auto" else value


def effect_facts(effects) -> list[tuple[str, str, str]]:
    """(dotted key, value, unit) of every declared effect's section key (Effect.to_dict)."""
    rows = []
    for name, effect in sections().items():
        for key, value in (effect.to_dict(effects) or {}).items():
            shown = value if isinstance(value, (str, int, float)) else "inline table"
            rows.append((f"{name}.{key}", number(shown), KEY_UNITS.get(f"{name}.{key}", "")))
    return rows


def scene_facts(scene) -> list[tuple[str, str, str]]:
    """(name, value, unit) rows of a scene: its source, beads, radius, material, law, loading, run
    and declared effects; what Scene's repr and HTML show."""
    c = scene.chain
    radius = f"{number(c.radius)} (bead 1; {len(c.radii)} per bead)" if c.radii else number(c.radius)
    material = _material(c.material_name, c.material)
    if c.materials:
        material += f" (bead 1; {len(set(map(str, c.materials)))} materials per bead)"
    rows = [
        ("scene", scene.title or scene.source or "untitled scene", ""),
        ("beads", number(c.beads), ""),
        ("radius", radius, "m"),
        ("material", material, ""),
        ("contact law", scene.contact.law, ""),
        *_loading_facts(scene.loading),
        ("end time", number(scene.run.end_time), "s"),
        ("time step", number(scene.run.timestep), "s"),
    ]
    return rows + effect_facts(scene.effects)


def scene_line(scene) -> str:
    """A scene in one line of at most a few hundred characters (Scene.__repr__)."""
    c = scene.chain
    name = printable(scene.title or scene.source or "untitled scene", 80)
    where = f" ({printable(scene.source, 60)})" if scene.title and scene.source else ""
    per_bead = " (per-bead radii or materials; bead 1's)" if c.radii or c.materials else ""
    kind, *values = _loading_facts(scene.loading)
    load = ", ".join(f"{k.rsplit(' ', 1)[-1]} = {with_unit(v, u)}" for k, v, u in values)
    effects = ", ".join(f"{k} = {with_unit(v, u)}" for k, v, u in effect_facts(scene.effects))
    return (
        f"<Scene {name}{where}: {number(c.beads)} {printable(_material(c.material_name, c.material), 40)} beads "
        f"R = {number(c.radius)} m{per_bead}, {scene.contact.law}; {kind[1]} {load}; "
        f"end {with_unit(number(scene.run.end_time), 's')}, dt {with_unit(number(scene.run.timestep), 's')}"
        + (f"; {printable(effects, 120)}" if effects else "")
        + ">"
    )
