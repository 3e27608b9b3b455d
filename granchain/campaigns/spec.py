"""Campaign files: what varies over a base scene, read and validated before anything runs.

A campaign file is TOML::

    [campaign]
    base = "elastic-short-pulse"       # a bundled scene, a scene file inside this file's folder, or an inline [scene]
    backend = "lammps"                 # or "reference" (with method = "rk4" | "verlet"; default per point:
                                       # verlet where it has a dashpot, else rk4)
    rtol = 1e-3                        # optional: plan every point for this tolerance
    error_estimate = true              # default: every observable gets its error bar from companion runs
                                       # (workflows.error_estimates.planned_companions)
    regime_contact = 20                # optional: the contact whose force history gives the table's
                                       # pulse count and regime (default: the last of [outputs] histories)

    [vary]                             # a grid: the product of every key's values
    "loading.amplitude" = { log = [1e2, 1e6], num = 9 }
    "loading.duration" = [1e-6, 1e-5, 1e-4]
    # { linear = [a, b], num = n } spaces evenly; a plain list is taken as it is

    [zip]                              # keys that vary together (equal lengths): one more axis of the grid
    "chain.beads" = [20, 40]
    "run.end_time" = [1e-4, 2e-4]

    [derive]                           # a key computed from others (+ - * / ** and parentheses)
    "loading.duration" = "impulse / amplitude"

A dotted key is a scene key (``section.key``, ``chain.material.density``); a key without a dot is a
free parameter: it is not a scene key, it only feeds [derive] (``impulse = [0.1, 0.4]``). An
expression reads a varied key by its full name or, when that is unambiguous, by its last part
(``amplitude``), a derived key set above it, or a number of the base scene by its full name
(``chain.radius``).

The search kind adds a [search] table: for each point of the grid (the outer keys; no [vary] is one
search), bisect one key until a predicate of the run flips, to a tolerance::

    [search]
    key = "loading.duration"
    range = [1e-7, 1e-4]
    scale = "log"                      # or "linear"
    tolerance = 0.01                   # log: the bracket's hi/lo - 1; linear: its width, in the key's unit
    predicate = { quantity = "pulses", contact = 20, op = ">", value = 1 }

``quantity`` is ``pulses`` (distinct pulses in the force history of ``contact``, which must be one of
the scene's [outputs] histories, on the dynamic force F - F0 of a precompressed chain;
granchain.postprocess.response_regimes.count_pulses) or an observable of
summary.json (``leading_peak_force``, ``wave_speed``, ...).

Every problem is a :class:`CampaignError` naming the file, the table, the key and the fix; every
point is made and validated as a scene (and planned, and its time step checked) before anything runs.
"""

from __future__ import annotations

import errno
import math
import os
import tomllib
from pathlib import Path
from typing import Any

from granchain import safe_files
from granchain.backends import BACKENDS, METHODS
from granchain.campaigns import expr
from granchain.campaigns.model import (
    MAX_POINT_BEADS,
    MAX_POINTS,
    MAX_RANKS,
    Axis,
    Campaign,
    CampaignError,
    Derived,
    Point,
    Predicate,
    Search,
    check_nesting,
    check_size,
    params_text,
    scene_numbers,
    whole,
)
from granchain.campaigns.optimize_spec import DESIGN_NUMBERS, check_names, read_kind, read_optimize
from granchain.campaigns.sections import read_sections
from granchain.postprocess.observables import table_columns
from granchain.scene import (
    MAX_SCENE_BYTES,
    SECTIONS,
    SceneError,
    _did_you_mean,
    bundled_scenes,
    load_scene,
    parse_scene,
    scene_from_dict,
    scene_to_dict,
)

KINDS = ("grid", "search", "optimize")
CAMPAIGN_KEYS = ("base", "backend", "method", "rtol", "error_estimate", "regime_contact", "title", "kind", "ranks")
TABLES = ("campaign", "scene", "vary", "zip", "derive", "sections", "search", "optimize", "cluster")
SEARCH_KEYS = ("key", "range", "scale", "tolerance", "predicate")
PREDICATE_KEYS = ("quantity", "contact", "op", "value")
OPS = (">", ">=", "<", "<=", "==", "!=")


def load_campaign_file(path: str | Path) -> Campaign:
    """Read and validate a campaign file (its base scene: a bundled scene's name or a scene file inside
    the campaign file's folder, named relative to it)."""
    p = Path(path)
    if not p.is_file():
        raise CampaignError(f"{p}: no such campaign file; give the path of a .toml campaign (docs/campaigns.md)")
    try:
        with open(p, "rb") as fh:
            data = fh.read(MAX_SCENE_BYTES + 1)  # at most the limit: a file of gigabytes is not read whole
        text = data.decode("utf-8") if len(data) <= MAX_SCENE_BYTES else ""
    except (OSError, UnicodeDecodeError) as e:
        raise CampaignError(f"{p}: cannot be read as UTF-8 text ({e})") from None
    if len(data) > MAX_SCENE_BYTES:
        raise CampaignError(_too_large(str(p)))
    return parse_campaign(text, source=str(p), base_dir=p.parent)


def _too_large(source: str) -> str:
    return (
        f"{source}: is over {MAX_SCENE_BYTES:,} bytes; a campaign file, like a scene file, is text of at most that "
        "(a [vary] list of 100,000 values takes about 2 MB)"
    )


def parse_campaign(text: str, source: str = "<campaign>", base_dir: str | Path | None = None) -> Campaign:
    """Read and validate campaign TOML text.

    Parameters
    ----------
    text : str
        The campaign file's text.
    source : str
        What messages name as the file.
    base_dir : str or Path, optional
        The campaign file's folder: a base scene file is named relative to it and read only inside it.
        None: the text is the caller's own (not a shared file), and a base path is read as given.

    Returns
    -------
    Campaign
        The validated campaign (its points are made by :meth:`Campaign.points`).

    Raises
    ------
    CampaignError
        The text is not TOML or not a valid campaign.
    """
    if len(text) > MAX_SCENE_BYTES or len(text.encode("utf-8", "surrogatepass")) > MAX_SCENE_BYTES:
        raise CampaignError(_too_large(source))
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise CampaignError(f"{source}: is not valid TOML: {e}") from None
    except RecursionError:  # the TOML reader recurses once per level of nested arrays or tables
        raise CampaignError(
            f"{source}: nests arrays or tables too deeply for a campaign file (hundreds of levels); no campaign "
            "key takes more than a list of values, each a number, a string or a short list"
        ) from None
    return campaign_from_dict(data, source=source, base_dir=base_dir, text=text)


def campaign_from_dict(
    data: dict, source: str = "<campaign>", base_dir: str | Path | None = None, text: str | None = None
) -> Campaign:
    """A validated campaign from its tables (the TOML file's content as a dict)."""
    if not isinstance(data, dict):
        raise CampaignError(f"{source}: a campaign is a table with [campaign] and [vary] (or [search])")
    check_nesting(data, source)
    for key in data:
        if key not in TABLES:
            raise CampaignError(
                f"{source}: unknown table or key {key!r}; {_did_you_mean(key, TABLES)}allowed: {', '.join(TABLES)}"
            )
        if not isinstance(data[key], dict):
            raise CampaignError(f"{source}: {key} = {data[key]!r} must be a table: write it as a [{key}] section")
    c = dict(data.get("campaign", {}))
    for key in c:
        if key not in CAMPAIGN_KEYS:
            raise CampaignError(
                f"{source}: [campaign] has unknown key {key!r}; {_did_you_mean(key, CAMPAIGN_KEYS)}"
                f"allowed keys: {', '.join(CAMPAIGN_KEYS)}"
            )
    settings = _read_settings(c, source)
    cluster = None
    if "cluster" in data:
        from granchain.campaigns.cluster_settings import ClusterError, from_table

        try:
            cluster = from_table(data["cluster"], source)
        except ClusterError as e:
            raise CampaignError(str(e)) from None
    axes = _read_axes(data, source)
    base, base_source, base_table = _read_base(c, data.get("scene"), source, base_dir)
    kind = read_kind(c, data, source, axes, KINDS)
    search = _read_search(data["search"], source) if kind == "search" else None
    optimize = read_optimize(data["optimize"], source, _did_you_mean) if kind == "optimize" else None
    if kind == "grid" and not axes:
        raise CampaignError(
            f'{source}: nothing varies: the grid is empty; add a [vary] table, e.g. "loading.amplitude" = [10.0, 100.0]'
        )
    grid_keys = [k for a in axes for k in a.keys]
    if search is not None and search.key in grid_keys:
        raise CampaignError(f"{source}: [search] key {search.key!r} is also varied in [vary]/[zip]; drop it there")
    searched = [search.key] if search else list(optimize.keys) if optimize else []
    derive = _read_derive(data.get("derive", {}), grid_keys + searched, (base, base_table), source)
    sections = read_sections(data.get("sections", {}), {*grid_keys, *searched, *(d.key for d in derive)}, source)
    if optimize is not None:
        for k in optimize.keys:
            _check_key(k, "optimize.variables", source)
        readable = set(searched) | {d.key for d in derive} | set(scene_numbers(base)) | set(scene_numbers(base_table))
        readable |= {k.rsplit(".", 1)[-1] for k in searched} | set(DESIGN_NUMBERS)
        check_names(optimize, readable, table_columns(), source, _did_you_mean)
    return Campaign(
        source=source,
        text=text if text is not None else "",
        base=base,
        base_table=base_table,
        base_source=base_source,
        kind=kind,
        axes=tuple(axes),
        derive=tuple(derive),
        search=search,
        optimize=optimize,
        sections=sections,
        cluster=cluster,
        **settings,
    )


def _read_settings(c: dict, source: str) -> dict:
    """[campaign] backend, method, rtol, error_estimate, regime_contact, title, checked."""
    backend = c.get("backend", "reference")
    if backend not in BACKENDS:
        raise CampaignError(
            f"{source}: [campaign] backend = {backend!r} is invalid: one of {', '.join(map(repr, BACKENDS))}"
        )
    method = c.get("method")
    runs = BACKENDS[backend]
    if method in METHODS and method not in runs.methods:
        raise CampaignError(
            f"{source}: [campaign] method = {method!r}: the {runs.title} backend integrates with {runs.method_text} "
            "only (drop method)"
        )
    if method not in (None, *METHODS):
        raise CampaignError(f"{source}: [campaign] method = {method!r} is invalid: {' or '.join(map(repr, METHODS))}")
    rtol = c.get("rtol")
    if rtol is not None and (isinstance(rtol, bool) or not isinstance(rtol, (int, float)) or not 0 < rtol < 1):
        raise CampaignError(f"{source}: [campaign] rtol = {rtol!r} is invalid: a number between 0 and 1, e.g. 1e-3")
    ee = c.get("error_estimate", True)
    if not isinstance(ee, bool):
        raise CampaignError(f"{source}: [campaign] error_estimate = {ee!r} is invalid: true or false")
    rc = c.get("regime_contact")
    if rc is not None and (isinstance(rc, bool) or not isinstance(rc, int) or rc < 1):
        raise CampaignError(f"{source}: [campaign] regime_contact = {rc!r} is invalid: a contact number >= 1")
    title = c.get("title", "")
    if not isinstance(title, str):
        raise CampaignError(f"{source}: [campaign] title = {title!r} is invalid: a string")
    ranks = check_ranks(c.get("ranks", 1), backend, f"{source}: [campaign] ranks")
    return {
        "ranks": ranks,
        "backend": backend,
        "method": method,
        "rtol": None if rtol is None else float(rtol),
        "error_estimate": ee,
        "regime_contact": rc,
        "title": title,
    }


def check_ranks(ranks, backend: str, where: str) -> int | str:
    """MPI ranks per point: a whole number from 1 to MAX_RANKS or "auto", for the LAMMPS backend only.
    where: what the message names ("FILE: [campaign] ranks", "--ranks")."""
    if ranks != "auto" and (isinstance(ranks, bool) or not isinstance(ranks, int) or not 1 <= ranks <= MAX_RANKS):
        raise CampaignError(
            f"{where} = {ranks!r} is invalid: MPI ranks per point, a whole number from 1 to {MAX_RANKS}, or "
            "\"auto\" (the plan's --np auto rule for each point's chain)"
        )
    if not BACKENDS[backend].mpi and ranks != 1:
        raise CampaignError(
            f"{where} = {ranks!r}: the {backend} backend runs a point in one process; MPI ranks are for "
            'backend = "lammps" (drop ranks)'
        )
    return ranks


def _read_axes(data: dict, source: str) -> list[Axis]:
    """The grid's axes: one per [vary] key, and one for the [zip] keys together."""
    axes = []
    for name in ("vary", "zip"):
        if name in data and not data[name]:
            raise CampaignError(f"{source}: [{name}] is empty: the grid has no points; give each key a list of values")
    check_size(data, source)
    for key, spec in data.get("vary", {}).items():
        _check_key(key, "vary", source)
        values = _spaced(key, spec, _values_of(spec, f"{source}: [vary] {key!r}"))
        axes.append(Axis((key,), tuple((v,) for v in values)))
    if "zip" in data:
        cols = {}
        for key, spec in data["zip"].items():
            _check_key(key, "zip", source)
            if key in {a.keys[0] for a in axes}:
                raise CampaignError(f"{source}: {key!r} is in both [vary] and [zip]; keep it in one")
            cols[key] = _spaced(key, spec, _values_of(spec, f"{source}: [zip] {key!r}"))
        lengths = {k: len(v) for k, v in cols.items()}
        if len(set(lengths.values())) > 1:
            raise CampaignError(
                f"{source}: [zip] keys vary together and need equal lengths; got "
                + ", ".join(f"{k}: {n}" for k, n in lengths.items())
            )
        axes.append(Axis(tuple(cols), tuple(zip(*cols.values(), strict=True))))
    return axes


def _read_base(c: dict, inline: dict | None, source: str, base_dir) -> tuple[dict, str, dict]:
    """The base scene: canonical (scene_to_dict), where it came from, and its tables as written (a
    taper as its rule, not the radii it makes: what the points' keys are set on)."""
    base = c.get("base")
    if base is not None and inline is not None:
        raise CampaignError(f"{source}: both [campaign] base = {base!r} and an inline [scene]: keep one")
    if inline is not None:
        try:
            scene = scene_from_dict(inline, source=f"{source} [scene]")
        except SceneError as e:
            raise CampaignError(str(e)) from None
        return scene_to_dict(scene), f"{source} [scene]", inline
    if base is None:
        raise CampaignError(
            f"{source}: no base scene: set [campaign] base = a bundled scene name or a path, or give an inline [scene]"
        )
    if not isinstance(base, str):
        raise CampaignError(f"{source}: [campaign] base = {base!r} is invalid: a scene name or a path (a string)")
    if base_dir is None:  # a dict of the caller's own code: a path is theirs to name, as on a command line
        try:
            scene = load_scene(base)
        except SceneError as e:
            raise CampaignError(f"{source}: [campaign] base = {base!r}: {e}") from None
        return scene_to_dict(scene), base, _tables(scene)
    return _read_base_file(base, source, Path(base_dir))


def _tables(scene) -> dict:
    """A parsed scene's tables as its text writes them."""
    return tomllib.loads(scene.source_text)


def _read_base_file(base: str, source: str, folder: Path) -> tuple[dict, str, dict]:
    """A campaign file's base scene: a bundled scene's name, or a scene file inside the campaign file's
    folder, named relative to it. A campaign file is shared: its base is never read outside that
    folder (no absolute path, no '..', no symbolic link at any part of it, wherever it points), and
    is refused before anything is read, so no outside file's content reaches a message."""
    fix = (
        f"a campaign file's base is a bundled scene's name or a scene file inside its folder ({folder}): put the "
        "scene file beside the campaign file (or in a folder below it) and name it relative to it, with no '..' "
        "and no symbolic link"
    )
    where = f"{source}: [campaign] base = {base!r}"
    plain_name = "/" not in base and "\\" not in base and not base.endswith(".toml") and base not in ("", ".")
    if plain_name and not os.path.lexists(folder / base):
        scenes = bundled_scenes()
        if base not in scenes:
            raise CampaignError(
                f"{where}: is neither a bundled scene nor a file beside the campaign file; bundled: "
                f"{', '.join(scenes)} (or give a .toml file beside the campaign file)"
            )
        scene = parse_scene(scenes[base], source=f"<bundled scene {base}>")
        return scene_to_dict(scene), base, _tables(scene)
    why = safe_files.escapes(base)
    if why is not None:
        raise CampaignError(f"{where}: {why}; {fix}")
    path = folder / base
    try:
        text = safe_files.read_text_inside(folder, base, limit=MAX_SCENE_BYTES)
    except FileNotFoundError:
        raise CampaignError(f"{where}: {path}: no such scene file; {fix}") from None
    except safe_files.UnsafeFileError as e:
        if e.errno == errno.ELOOP:
            raise CampaignError(f"{where}: {e.filename}: is a symbolic link; {fix}") from None
        raise CampaignError(f"{where}: {e}") from None
    except OSError as e:
        raise CampaignError(f"{where}: {path}: cannot be read ({e.strerror or e})") from None
    try:
        scene = parse_scene(text, source=str(path))
    except SceneError as e:
        raise CampaignError(f"{where}: {e}") from None
    return scene_to_dict(scene), str(path), _tables(scene)


def _check_key(key: str, table: str, source: str) -> None:
    if "." not in key:
        if not key.isidentifier():
            raise CampaignError(
                f"{source}: [{table}] {key!r} is neither a scene key (section.key) nor a free parameter name "
                "(letters, digits, _)"
            )
        return  # a free parameter: it feeds [derive]
    section = key.split(".", 1)[0]
    if section not in SECTIONS or section == "title" or not all(key.split(".")):
        raise CampaignError(
            f"{source}: [{table}] has unknown key {key!r}: {section!r} is not a scene section; "
            f"{_did_you_mean(section, SECTIONS)}a scene key is section.key with section one of "
            f"{', '.join(s for s in SECTIONS if s != 'title')}"
        )


def _spaced(key: str, spec: Any, values: list) -> list:
    """A { log / linear, num } entry's values, for an integer key the integral ones as integers
    (model.whole); a list's values as written (beads = 20.0 is refused as in a scene file)."""
    return [whole(key, v) for v in values] if isinstance(spec, dict) else values


def _values_of(spec: Any, where: str) -> list:
    if isinstance(spec, list):
        if not spec:
            raise CampaignError(f"{where} = []: an empty list makes an empty grid; give at least one value")
        return list(spec)
    if isinstance(spec, dict):
        kinds = [k for k in ("log", "linear") if k in spec]
        unknown = [k for k in spec if k not in ("log", "linear", "num")]
        if unknown or len(kinds) != 1 or "num" not in spec:
            raise CampaignError(
                f"{where} = {spec!r} is invalid: a list of values, {{ log = [a, b], num = n }} or "
                "{ linear = [a, b], num = n }"
            )
        kind = kinds[0]
        ends, num = spec[kind], spec["num"]
        if (
            not isinstance(ends, list)
            or len(ends) != 2
            or any(isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) for x in ends)
        ):
            raise CampaignError(f"{where}: {kind} = {ends!r} is invalid: two finite numbers [first, last]")
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise CampaignError(f"{where}: num = {num!r} is invalid: a whole number >= 1 (0 makes an empty grid)")
        a, b = (float(x) for x in ends)
        if kind == "log":
            if a <= 0 or b <= 0:
                raise CampaignError(
                    f"{where}: log = {ends!r}: both ends must be > 0 (use linear for zero or negatives)"
                )
            if num == 1:
                return [a]
            la, lb = math.log10(a), math.log10(b)
            vals = [10 ** (la + (lb - la) * i / (num - 1)) for i in range(num)]
            vals[0], vals[-1] = a, b
            return [float(f"{v:.12g}") for v in vals]  # 1e2..1e6 in 9 steps: 100, 316.227766017, 1000, ...
        if num == 1:
            return [a]
        return [float(f"{a + (b - a) * i / (num - 1):.12g}") for i in range(num)]
    raise CampaignError(
        f"{where} = {spec!r} is invalid: a list of values, {{ log = [a, b], num = n }} or "
        "{ linear = [a, b], num = n }"
    )


def _read_derive(table: dict, varied: list[str], bases: tuple[dict, ...], source: str) -> list[Derived]:
    """The [derive] keys, each expression reading only varied keys, derived keys above it and numbers
    of the base scene (bases: canonical and as written, Campaign.base and base_table)."""
    out: list[Derived] = []
    known = set(varied).union(*(scene_numbers(b) for b in bases))
    shorts: dict[str, list[str]] = {}
    for k in varied:
        shorts.setdefault(k.rsplit(".", 1)[-1], []).append(k)
    for key, text in table.items():
        _check_key(key, "derive", source)
        if key in varied:
            raise CampaignError(f"{source}: [derive] {key!r} is also varied ([vary], [zip] or [search]); keep one")
        if not isinstance(text, str):
            raise CampaignError(
                f"{source}: [derive] {key!r} = {text!r} is invalid: an expression as a string, e.g. "
                '"impulse / amplitude"'
            )
        try:
            tree = expr.parse(text)
        except expr.ExpressionError as e:
            raise CampaignError(f"{source}: [derive] {key!r}: {e}") from None
        readable = known | {s for s, ks in shorts.items() if len(ks) == 1 and s not in known}
        for name in sorted(expr.names(tree)):
            if name not in readable:
                amb = shorts.get(name, [])
                why = (
                    f"it is ambiguous ({', '.join(amb)}): write the full name"
                    if len(amb) > 1
                    else f"{_did_you_mean(name, sorted(readable))}it is not a varied key, a derived key above it "
                    "or a number of the base scene"
                )
                raise CampaignError(f"{source}: [derive] {key!r} = {text!r} reads {name!r}: {why}")
        out.append(Derived(key, text, tree))
        known.add(key)
        shorts.setdefault(key.rsplit(".", 1)[-1], []).append(key)
    return out


def _read_search(s: dict, source: str) -> Search:
    for key in s:
        if key not in SEARCH_KEYS:
            raise CampaignError(
                f"{source}: [search] has unknown key {key!r}; {_did_you_mean(key, SEARCH_KEYS)}"
                f"allowed keys: {', '.join(SEARCH_KEYS)}"
            )
    for key in ("key", "range", "predicate"):
        if key not in s:
            raise CampaignError(f"{source}: [search] is missing {key!r} (key, range, predicate; docs/campaigns.md)")
    key = s["key"]
    if not isinstance(key, str) or "." not in key:
        raise CampaignError(f"{source}: [search] key = {key!r} is invalid: a scene key, e.g. 'loading.duration'")
    _check_key(key, "search", source)
    rng = s["range"]
    if (
        not isinstance(rng, list)
        or len(rng) != 2
        or any(isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) for x in rng)
        or rng[0] == rng[1]
    ):
        raise CampaignError(f"{source}: [search] range = {rng!r} is invalid: two different finite numbers [low, high]")
    low, high = sorted(float(x) for x in rng)
    scale = s.get("scale", "log")
    if scale not in ("log", "linear"):
        raise CampaignError(f"{source}: [search] scale = {scale!r} is invalid: 'log' or 'linear'")
    if scale == "log" and low <= 0:
        raise CampaignError(f"{source}: [search] range = {rng!r}: a log search needs both ends > 0")
    tol = s.get("tolerance", 0.01)
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not tol > 0:
        raise CampaignError(
            f"{source}: [search] tolerance = {tol!r} is invalid: a number > 0 (log: the bracket's hi/lo - 1; "
            "linear: its width)"
        )
    return Search(key, low, high, scale, float(tol), _read_predicate(s["predicate"], source))


def _read_predicate(p: Any, source: str) -> Predicate:
    form = '{ quantity = "pulses", contact = 20, op = ">", value = 1 }'
    if not isinstance(p, dict):
        raise CampaignError(f"{source}: [search] predicate = {p!r} is invalid: a table such as {form}")
    for key in p:
        if key not in PREDICATE_KEYS:
            raise CampaignError(
                f"{source}: [search] predicate has unknown key {key!r}; {_did_you_mean(key, PREDICATE_KEYS)}"
                f"allowed keys: {', '.join(PREDICATE_KEYS)}"
            )
    q = p.get("quantity")
    observables = table_columns()  # the observables of summary.json a predicate may test (the registry's)
    if q != "pulses" and q not in observables:
        raise CampaignError(
            f"{source}: [search] predicate quantity = {q!r} is invalid: 'pulses' (at a contact) or an observable: "
            + ", ".join(observables)
        )
    contact = p.get("contact")
    if q == "pulses":
        if isinstance(contact, bool) or not isinstance(contact, int) or contact < 1:
            raise CampaignError(
                f"{source}: [search] predicate contact = {contact!r} is invalid: the pulse count needs a contact "
                "number >= 1 that is in the scene's [outputs] histories"
            )
    elif contact is not None:
        raise CampaignError(f"{source}: [search] predicate contact: {q} is one number per run; drop contact")
    op = p.get("op")
    if op not in OPS:
        raise CampaignError(f"{source}: [search] predicate op = {op!r} is invalid: one of {' '.join(OPS)}")
    v = p.get("value")
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise CampaignError(f"{source}: [search] predicate value = {v!r} is invalid: a finite number")
    return Predicate(q, op, float(v) if isinstance(v, float) else v, contact)


__all__ = [
    "BACKENDS",
    "CAMPAIGN_KEYS",
    "KINDS",
    "MAX_POINTS",
    "MAX_POINT_BEADS",
    "MAX_RANKS",
    "OPS",
    "PREDICATE_KEYS",
    "SEARCH_KEYS",
    "TABLES",
    "Axis",
    "Campaign",
    "CampaignError",
    "Derived",
    "Point",
    "Predicate",
    "Search",
    "campaign_from_dict",
    "check_ranks",
    "load_campaign_file",
    "params_text",
    "parse_campaign",
]
