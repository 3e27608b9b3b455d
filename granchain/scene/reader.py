"""Reading a scene: a file, a bundled scene's name, TOML text or a dict, validated section by
section and then as a whole (the scales its values give together, the effects it combines)."""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import replace
from pathlib import Path

from granchain.physics import materials as mat
from granchain.physics.effects import OVERLAP_WATCH, PrecompressionEffect, active_effects, refusal, sections
from granchain.scene import model
from granchain.scene.limits import AUTO, MAX_FORCE, MAX_SCENE_BYTES, MIN_TAU
from granchain.scene.model import Chain, Scene
from granchain.scene.read_sections import (
    _read_chain,
    _read_contact,
    _read_effects,
    _read_loading,
    _read_outputs,
    _read_run,
)
from granchain.scene.section import SceneError, _did_you_mean, _Section, _shown
from granchain.scene.writer import scene_to_dict


def bundled_scenes() -> dict[str, str]:
    """The bundled example scenes: name -> TOML text."""
    from importlib import resources

    root = resources.files("granchain") / "scenes"
    return {
        p.name.removesuffix(".toml"): p.read_text(encoding="utf-8")
        for p in sorted(root.iterdir(), key=lambda p: p.name)
        if p.name.endswith(".toml")
    }


def load_scene(path_or_name: str | Path) -> Scene:
    """Read and validate a scene.

    Parameters
    ----------
    path_or_name : str or Path
        A ``.toml`` scene file, or the name of a bundled scene (``granchain scenes`` lists them).

    Returns
    -------
    Scene
        The validated scene; values given as ``"auto"`` are left for :func:`granchain.plan`.

    Raises
    ------
    SceneError
        The file does not exist or is invalid; the message names the file, the key and the fix.
    """
    p = Path(path_or_name)
    arg = str(path_or_name)
    if not p.exists() and p.suffix != ".toml" and "/" not in arg and "\\" not in arg:
        scenes = bundled_scenes()
        if arg in scenes:
            return parse_scene(scenes[arg], source=f"<bundled scene {arg}>")
        raise SceneError(
            f"{arg}: is neither a scene file nor a bundled scene; bundled: {', '.join(scenes)} "
            "(or give the path of a .toml file)"
        )
    if not p.exists():
        raise SceneError(f"{p}: no such scene file; give the path of a .toml scene (see 'granchain scenes')")
    if not p.is_file():
        raise SceneError(f"{p}: is not a file; give the path of a .toml scene (see 'granchain scenes')")
    try:
        with open(p, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > MAX_SCENE_BYTES:
                raise SceneError(
                    f"{p}: is {size:,} bytes; a scene file is text of at most {MAX_SCENE_BYTES:,} bytes "
                    "(a per-bead list of the longest varied chain takes about 3 MB)"
                )
            data = fh.read(min(size, MAX_SCENE_BYTES) + 1)  # a file that grows while read stops here
        if len(data) > MAX_SCENE_BYTES:
            raise SceneError(f"{p}: is over {MAX_SCENE_BYTES:,} bytes; a scene file is text of at most that")
        text = data.decode("utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SceneError(f"{p}: cannot be read as UTF-8 text ({e})") from None
    return parse_scene(text, source=str(p))


def parse_scene(text: str, source: str = "<scene>") -> Scene:
    """Parse and validate scene TOML text.

    Parameters
    ----------
    text : str
        The scene as TOML.
    source : str
        What messages name as the scene's file.

    Returns
    -------
    Scene
        The validated scene, with ``source`` and ``source_text`` set.

    Raises
    ------
    SceneError
        The text is not TOML or not a valid scene.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{source}: is not valid TOML: {e}") from None
    except RecursionError:  # the TOML reader recurses once per level of nested arrays or tables
        raise SceneError(
            f"{source}: nests arrays or tables too deeply for a scene file (hundreds of levels); "
            "no scene key takes more than a list of numbers"
        ) from None
    scene = scene_from_dict(data, source=source)
    return _with_source(scene, source, text)


def _with_source(scene: Scene, source: str, text: str) -> Scene:
    from dataclasses import replace

    return replace(scene, source=source, source_text=text)


def set_key(data: dict, key: str, value, source: str) -> None:
    """Set one dotted scene key (``loading.amplitude``, ``chain.material.density``) in a scene's dict
    (as TOML reads it), making the tables it names; the reader validates the value afterwards.

    Raises
    ------
    SceneError
        A part of the key names a value that is not a table (``title.x``, ``chain.radius.x``).
    """
    parts = key.split(".")
    node = data
    for i, part in enumerate(parts[:-1]):
        nxt = node.setdefault(part, {})
        if not isinstance(nxt, dict):
            head = ".".join(parts[: i + 1])
            raise SceneError(
                f"{source}: cannot set {_shown(key)}: {head} is {_shown(nxt)}, not a table (set {_shown(head)} itself)"
            )
        node = nxt
    node[parts[-1]] = value


def replaced(scene: Scene, changes: dict) -> Scene:
    """Scene.replace: the scene's canonical dict (scene_to_dict, what to_toml writes) with each dotted
    key of changes set (set_key), read by scene_from_dict as a file of that text would be, under the
    scene's source; its source_text the changed text (run directories copy it)."""
    source = scene.source or "<scene>"
    data = scene_to_dict(scene)
    for key, value in changes.items():
        if not isinstance(key, str):
            raise SceneError(f"{source}: scene key {_shown(key)} is invalid: a dotted name such as 'loading.amplitude'")
        set_key(data, key, value, source)
    new = scene_from_dict(data, source=source)
    return _with_source(new, scene.source, new.to_toml())


model._REPLACED = replaced  # Scene.replace's reader (the model is below it: granchain.scene's layers)


SECTIONS = ("title", "chain", "contact", "loading", "run", "outputs", *sections())


def _check_scene(scene: Scene, source: str) -> None:
    """Refuse a scene whose sections, each valid, do not go together: its scales (_check_scales), and
    sensor beads ([outputs] sensors) on bead 1 under a force loading, whose loaded face carries the
    applied force, not a contact a sensor averages (postprocess.sensors)."""
    _check_scales(scene, source)
    if 1 in scene.outputs.sensors and scene.loading.is_force:
        raise SceneError(
            f"{source}: [outputs] sensors = {list(scene.outputs.sensors)} is invalid with [loading] kind = "
            f"{scene.loading.kind!r}: bead 1's loaded face carries the applied force, not a contact a sensor "
            'averages; put the sensors on beads 2 and beyond, or strike bead 1 (kind = "striker": its contact counts)'
        )


def _driven_outputs(outputs, loading, chain):
    """The outputs of a harmonic drive: every bead-bead contact's history (the far end's, the last
    bead-bead one, and those the spatial decay fits), sampled at the planner's "auto" interval unless
    the scene gives one, which the spectral observables read (granchain.postprocess.observables.spectral
    and .spatial: N - 1 columns at 32 samples a period, 0.2 MB for 20 beads over 40 periods); the
    outputs as given otherwise, and while [chain] beads is "auto" (the planned scene gets them)."""
    if not loading.is_harmonic or chain.beads is None or chain.beads < 2:
        return outputs
    histories = tuple(range(1, chain.beads))
    interval = AUTO if outputs.history_interval is None else outputs.history_interval
    return replace(outputs, histories=histories, history_interval=interval)


def scene_from_dict(data: dict, source: str = "<scene>") -> Scene:
    """Validate a scene given as a dict of sections (TOML read, or :func:`scene_to_dict`'s).

    Parameters
    ----------
    data : dict
        Section name -> table, as a scene file has them.
    source : str
        What messages name as the scene's file.

    Returns
    -------
    Scene
        The validated scene (``source_text`` None).

    Raises
    ------
    SceneError
        A section or key is missing, unknown or invalid, the values together leave double precision
        or mechanics, or the declared effects do not go together.
    """
    for key in data:
        if key not in SECTIONS:
            raise SceneError(
                f"{source}: unknown section or key {_shown(key)}; {_did_you_mean(key, SECTIONS)}"
                f"allowed: {', '.join(SECTIONS)}"
            )
    for sec in ("chain", "contact", "loading", "run"):
        if sec not in data:
            raise SceneError(
                f"{source}: missing section [{sec}]; every scene needs [chain], [contact], [loading] and [run]"
            )
    title = data.get("title", "")
    if not isinstance(title, str):
        raise SceneError(f"{source}: title = {_shown(title)} is invalid: a string")

    chain = _read_chain(_Section(source, "chain", data["chain"]), source)
    contact = _read_contact(_Section(source, "contact", data["contact"]), chain)
    loading = _read_loading(_Section(source, "loading", data["loading"]), chain, source)
    run = _read_run(_Section(source, "run", data["run"]), loading)
    effects = _read_effects(source, data)
    outputs = _read_outputs(_Section(source, "outputs", data.get("outputs", {})), chain, run, effects.far_end == "wall")
    scene = Scene(
        effects=effects,
        chain=chain,
        contact=contact,
        loading=loading,
        run=run,
        outputs=_driven_outputs(outputs, loading, chain),
        title=title,
        source=source,
    )
    if chain.beads is None and effects.far_end == "wall":
        raise SceneError(
            f'{source}: [chain] beads = "auto" with [boundary] far_end = "wall" is invalid: an "auto" chain is '
            "made long enough that no reflection from its far end reaches the measured contacts, so a wall "
            'there is never felt; give [chain] beads = N for a wall N beads away, or far_end = "free"'
        )
    _check_scene(scene, source)
    why = refusal(active_effects(scene)) or next(
        filter(None, (e.requirement(scene) for e in active_effects(scene))), None
    )
    if why:
        raise SceneError(f"{source}: {why}")
    why = contact.law_class.unsupported(chain) if scene.per_bead else None
    if why:
        raise SceneError(f"{source}: {why}")
    if chain.beads == 1 and loading.kind != "striker" and effects.far_end != "wall":
        raise SceneError(
            f"{source}: [chain] beads = 1 has no contact to load: a single bead needs a striker "
            '([loading] kind = "striker") or a wall ([boundary] far_end = "wall") to touch'
        )
    if chain.beads == 1 and effects.precompression and effects.far_end != "wall":
        raise SceneError(
            f"{source}: [precompression] force = {effects.precompression:g} N on [chain] beads = 1 with a free far "
            "end compresses no contact: the push on bead 1 and the pull holding its far end act on the same "
            "bead and cancel, and the striker touches it unloaded; remove [precompression], or give "
            '[boundary] far_end = "wall" for the wall\'s contact to carry it'
        )
    return scene


def _material_keys(chain: Chain) -> str:
    return "[chain] material" if chain.material_name or chain.materials else "[chain.material] values"


def _check_scales(scene: Scene, source: str) -> None:
    """Refuse a scene whose values, each within its own range, together give a chain outside double
    precision or outside any mechanics: a contact time scale below MIN_TAU, a law's constants that
    over- or underflow, a dashpot that damps faster than an attosecond, a precompression beyond
    MAX_FORCE or beyond what a contact it compresses carries within the run watch's overlap bound
    (PrecompressionEffect.largest_force: a run would stop at its first step). Each message names the
    keys the scene set that make it so, and the fix."""
    chain = scene.chain
    radii = (min(chain.radii), max(chain.radii)) if chain.radii else (chain.radius,)
    materials = list(dict.fromkeys(map(mat.bead_material, chain.materials))) if chain.materials else [chain.material]
    keys = f"[chain] radius and {_material_keys(chain)}"
    for r in radii:
        for m in materials:
            tau = mat.time_scale(m, r)
            if not (math.isfinite(tau) and tau >= MIN_TAU):
                raise SceneError(
                    f"{source}: {keys} give beads of radius {r:g} m a contact time scale tau = {tau:.3g} s, "
                    f"below {MIN_TAU:g} s: no chain of real spheres is this fast; check the radius, density, "
                    "youngs_modulus and poisson_ratio (a Poisson ratio near -1 makes E* unbounded)"
                )
    laws = {"the beads' contact": (scene.law, keys + " and [contact]")}
    if scene.loading.kind == "striker":
        laws["the striker's contact"] = (scene.striker_law, "[loading] radius, material and [contact]")
    if scene.effects.far_end == "wall":
        laws["the wall's contact"] = (_wall_law(scene, source), keys + " and [contact]")
    for what, (law, keys_of) in laws.items():
        values = {
            "k": law.k,
            **{k: getattr(law, k) for k in ("yield_overlap", "yield_force", "k_unloading") if hasattr(law, k)},
        }
        for name, v in values.items():
            v = float(v)
            if not (math.isfinite(v) and v > 0.0):
                raise SceneError(
                    f"{source}: {keys_of} give {what} a law with {name} = {v:g}, outside double precision: "
                    f"bring the {' and '.join(law.scene_keys) or 'material values'} closer to those of real beads "
                    f"(e.g. {law.example_contact or 'brass: E = 115e9 Pa'})"
                )
    if scene.damping.velocity_dependent:
        m_min = float(min(mat.bead_mass(m, radii[0]) for m in materials))
        if scene.loading.kind == "striker":
            m_min = min(m_min, float(scene.striker_mass))
        why = scene.damping.scale_refusal(scene.damping_coefficient, m_min, MIN_TAU)
        if why:
            raise SceneError(f"{source}: {why}")
    f0 = float(scene.effects.precompression)
    if f0 > MAX_FORCE:
        raise SceneError(
            f"{source}: [precompression] force = {f0:g} N is invalid: a static force F0 in N of at most {MAX_FORCE:g}"
        )
    held = PrecompressionEffect.largest_force(scene) if f0 else None
    if held is not None and not f0 <= held[0]:
        f_max, which, bound, law = held
        alpha = float(law.static_overlap(f0))
        raise SceneError(
            f"{source}: [precompression] force = {f0:g} N is invalid: it presses {which} to a static overlap of "
            f"{alpha:.3g} m, beyond {bound:.3g} m ({OVERLAP_WATCH:g} x the smaller radius of its two bodies), where "
            f"the run watch stops a run; a force of at most {_below(f_max):.4g} N (and less, for the wave's own "
            "force on top of it)"
        )


def _below(x: float) -> float:
    """x rounded down to 4 significant digits: a bound a message may quote that still holds when read back."""
    if not (math.isfinite(x) and x > 0.0):
        return x
    q = 10.0 ** (math.floor(math.log10(x)) - 3)
    v = math.floor(x / q) * q
    while float(f"{v:.4g}") > x:
        v -= q
    return float(f"{v:.4g}")


def _wall_law(scene: Scene, source: str):
    """The wall's law (Scene.wall_law), or why a plastic law cannot mix bead N's material with the
    wall's (a yield strength missing: the softer one's sets the wall's contact)."""
    try:
        return scene.wall_law
    except mat.MissingYieldStrength as e:
        raise SceneError(
            f"{source}: [boundary] wall_material with [contact] law = {scene.contact.law_class.name!r}: the wall's "
            f"contact takes the softer material's yield strength, as between beads, but {e}: give "
            "yield_strength in [boundary.wall_material] and [chain.material] tables (Pa), choose materials that "
            "have one (granchain materials), or remove wall_material for a rigid wall"
        ) from None
