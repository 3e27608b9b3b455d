"""Writing a scene: the canonical dict of a scene (read back by scene_from_dict to an equal scene)
and its TOML text. Only the keys a scene sets are written; floats as their repr, so that they read
back exactly."""

from __future__ import annotations

from typing import Any

from granchain.physics import materials as mat
from granchain.physics.effects import sections
from granchain.scene.limits import AUTO


def _loading_to_dict(ld) -> dict[str, Any]:
    """The [loading] table of a Loading: the keys its kind is given by."""
    if ld.kind == "step":
        return {"kind": "step", "amplitude": ld.amplitude, "duration": ld.duration}
    if ld.kind == "impulse":
        return {"kind": "impulse", "impulse": ld.impulse, "duration": ld.duration}
    if ld.is_harmonic:  # its length as duration: exact (cycles / f would not read back bit for bit)
        keys = ("amplitude", "frequency", "duration", "ramp")
        return {"kind": ld.kind, **{k: getattr(ld, k) for k in keys}}
    if ld.kind == "velocity":
        return {"kind": "velocity", "velocity": ld.velocity}
    st: dict[str, Any] = {"kind": "striker", "velocity": ld.velocity, "radius": ld.striker_radius}
    # its yield_strength too: a plastic law's mixing rule for the striker's contact reads it
    st["material"] = ld.striker_material_name or mat.material_values(ld.striker_material)
    if ld.striker_mass is not None:
        st["mass"] = ld.striker_mass
    return st


def _outputs_to_dict(o) -> dict[str, Any]:
    """The [outputs] table of an Outputs: the keys it sets."""
    out: dict[str, Any] = {"peak_force": o.peak_force if isinstance(o.peak_force, bool) else list(o.peak_force)}
    lists = (("histories", o.histories), ("snapshots", o.snapshots), ("window", o.window), ("sensors", o.sensors))
    lists += (("event_max_contacts", o.event_max_contacts), ("event_max_sensors", o.event_max_sensors))
    out.update({k: list(v) for k, v in lists if v})
    scalars = (("history_interval", o.history_interval), ("dump_interval", o.dump_interval))
    out.update({k: v for k, v in scalars if v is not None})
    if o.event:
        out["event"] = True
    return out


def scene_to_dict(scene) -> dict:
    """The canonical dict of a scene: the tables and keys of its TOML file.

    The model imports this module (``Scene.to_toml``), so the scene is not annotated here.

    Parameters
    ----------
    scene : granchain.scene.Scene
        A validated scene; values left "auto" are written as "auto".

    Returns
    -------
    dict
        Section name -> table (title a string); :func:`granchain.scene.scene_from_dict` reads it back
        to an equal scene, and campaigns use it as a point's canonical state.
    """
    c = scene.chain
    contact = scene.contact.law_class.contact_to_dict(scene.contact)
    material: Any
    if c.materials:  # per bead, a built-in name or an inline table (each contact's law reads its yield_strength)
        material = [e if isinstance(e, str) else mat.material_values(e) for e in c.materials]
    elif c.material_name is not None:
        material = c.material_name
    else:
        material = mat.material_values(c.material)
        if c.material.yield_strength is not None:  # the law's value derived from it is read back from it
            contact.pop(scene.contact.law_class.yield_strength_key, None)
    d: dict[str, Any] = {}
    if scene.title:
        d["title"] = scene.title
    d["chain"] = {
        "beads": AUTO if c.beads is None else c.beads,
        "radius": list(c.radii) if c.radii else c.radius,
        "material": material,
    }
    d["contact"] = contact
    d["loading"] = _loading_to_dict(scene.loading)
    d["run"] = {
        k: AUTO if v is None else v for k, v in (("end_time", scene.run.end_time), ("timestep", scene.run.timestep))
    }
    d["run"].update(scene.run.stop_check())
    d["outputs"] = _outputs_to_dict(scene.outputs)
    for name, effect in sections().items():
        section = effect.to_dict(scene.effects)
        if section is not None:
            d[name] = section
    return d


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return '"' + "".join(_toml_char(c) for c in v) + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):  # an inline table (an entry of a per-bead material list)
        return "{" + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {v!r} as TOML")


def _toml_char(c: str) -> str:
    r"""One character of a TOML basic string: quote and backslash escaped, control characters as
    \uXXXX (TOML allows none raw), a lone surrogate (not a Unicode scalar value) as U+FFFD."""
    if c in '"\\':
        return "\\" + c
    o = ord(c)
    if o < 0x20 or o == 0x7F:
        return f"\\u{o:04X}"
    if 0xD800 <= o <= 0xDFFF:
        return "\ufffd"
    return c


def dump_toml(d: dict) -> str:
    """A scene's dict as TOML text: top-level keys, then one table per section and its sub-tables.

    Parameters
    ----------
    d : dict
        A dict as :func:`scene_to_dict` makes it: values bool, int, float, str, lists of them, or
        tables of them nested at most twice.

    Returns
    -------
    str
        The TOML text, ending in a newline.
    """
    lines: list[str] = []
    for key, value in d.items():
        if not isinstance(value, dict):
            lines.append(f"{key} = {_toml_value(value)}")
    for key, value in d.items():
        if isinstance(value, dict):
            lines.append(f"\n[{key}]")
            subtables = []
            for k, v in value.items():
                if isinstance(v, dict):
                    subtables.append((k, v))
                else:
                    lines.append(f"{k} = {_toml_value(v)}")
            for k, v in subtables:
                lines.append(f"\n[{key}.{k}]")
                lines.extend(f"{kk} = {_toml_value(vv)}" for kk, vv in v.items())
    return "\n".join(lines).lstrip("\n") + "\n"
