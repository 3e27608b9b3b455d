"""A validated campaign: its grid's axes, its search, its derived keys, and the points it makes,
each a validated scene (granchain.campaigns.spec reads a campaign file into one)."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

from granchain.campaigns import expr
from granchain.exceptions import GranchainError
from granchain.scene import Scene, SceneError, scene_from_dict, scene_to_dict, set_key
from granchain.scene.section import _shown

#: a point's status, in the words of the table's status column (workspace.job_state; "stale" is the
#: table's) and of the progress line: a point lost in flight has no run and no failure.json: missing
DONE, FAILED, MISSING, STALE = "done", "failed", "missing", "stale"


class CampaignError(GranchainError, ValueError):
    """A campaign file or one of its points is invalid; the message names the key and the fix."""


class CampaignInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a campaign run: its workers are stopped and what is complete is kept.

    Attributes
    ----------
    said : bool
        The run has said so on its stream (not quiet); the command line then adds no line of its own.
    """

    def __init__(self, said: bool):
        super().__init__()
        self.said = said


def _num_text(v: Any) -> str:
    """A parameter's value in a message: a float to 6 digits, anything else as its repr, shortened (a
    list of a million values is not a message of megabytes)."""
    return f"{v:.6g}" if isinstance(v, float) else str(v) if isinstance(v, int) else _shown(v)


def params_text(params: dict) -> str:
    """'loading.amplitude = 100, loading.duration = 1e-05': a point's parameters, for messages."""
    return ", ".join(f"{k} = {_num_text(v)}" for k, v in params.items())


@dataclass(frozen=True)
class Axis:
    """One axis of the grid: a single [vary] key, or the keys of [zip] (values: one tuple per step).

    Attributes
    ----------
    keys : tuple of str
        The key, or the [zip] keys that vary together (dotted scene keys, or free parameters).
    values : tuple of tuple
        The axis's steps, each a tuple of one value per key.
    """

    keys: tuple[str, ...]
    values: tuple[tuple, ...]


@dataclass(frozen=True)
class Predicate:
    """quantity op value, on one run: ``pulses at contact 20 > 1``.

    Attributes
    ----------
    quantity : str
        "pulses" (distinct pulses in one contact's force history) or an observable of summary.json
        (granchain.postprocess.observables.table_columns).
    op : str
        The comparison, one of ``> >= < <= == !=``.
    value : float
        What the quantity is compared with, in the quantity's unit.
    contact : int or None
        The contact (1-based) whose history the pulses are counted in; None for an observable.
    """

    quantity: str
    op: str
    value: float
    contact: int | None = None

    @property
    def text(self) -> str:
        """The predicate as messages and the search table write it: ``pulses at contact 20 > 1``."""
        where = f" at contact {self.contact}" if self.contact is not None else ""
        return f"{self.quantity}{where} {self.op} {_num_text(self.value)}"

    def holds(self, x: float) -> bool:
        """Whether the predicate holds for a run whose quantity is x."""
        v = self.value
        return {
            ">": x > v,
            ">=": x >= v,
            "<": x < v,
            "<=": x <= v,
            "==": x == v,
            "!=": x != v,
        }[self.op]


@dataclass(frozen=True)
class Search:
    """The [search] table: bisect ``key`` over [low, high] (on a log or linear scale) to ``tolerance``
    until ``predicate`` flips.

    Attributes
    ----------
    key : str
        The searched key (a dotted scene key, or a free parameter that [derive] reads).
    low, high : float
        The range the bracket starts as, in the key's unit.
    scale : str
        "log" (geometric midpoints; low > 0) or "linear".
    tolerance : float
        When the bracket [lo, hi] is narrow enough: log, hi/lo - 1 <= tolerance; linear,
        hi - lo <= tolerance in the key's unit.
    predicate : Predicate
        What is tested on each run.
    """

    key: str
    low: float
    high: float
    scale: str  # "log" | "linear"
    tolerance: float
    predicate: Predicate

    def midpoint(self, lo: float, hi: float) -> float:
        """The bracket's next value: sqrt(lo hi) on a log scale, (lo + hi) / 2 on a linear one."""
        return math.sqrt(lo * hi) if self.scale == "log" else 0.5 * (lo + hi)

    def converged(self, lo: float, hi: float) -> bool:
        """The bracket is within the tolerance (in either order of its ends)."""
        a, b = min(lo, hi), max(lo, hi)
        return (b / a - 1.0 <= self.tolerance) if self.scale == "log" else (b - a <= self.tolerance)

    def width(self, lo: float, hi: float) -> float:
        """The bracket's width in the tolerance's measure."""
        a, b = min(lo, hi), max(lo, hi)
        return b / a - 1.0 if self.scale == "log" else b - a


@dataclass(frozen=True)
class Point:
    """One point: its parameters (varied, free and derived keys) and its validated scene.

    Attributes
    ----------
    index : int
        Its place in the grid, from 0 (messages count from 1).
    params : dict
        Key -> value of every varied, searched, free and derived key.
    scene : Scene
        The base scene with the point's scene keys set, validated.
    """

    index: int
    params: dict
    scene: Scene

    @property
    def scene_dict(self) -> dict:
        """The canonical scene (granchain.scene.scene_to_dict of the validated scene)."""
        return scene_to_dict(self.scene)


@dataclass(frozen=True)
class Derived:
    """One [derive] key: its expression's text and parsed tree (granchain.campaigns.expr).

    Attributes
    ----------
    key : str
        The key it sets (a dotted scene key, or a free parameter later keys read).
    text : str
        The expression as the file writes it.
    tree : object
        Its parsed tree (expr.parse), evaluated for each point.
    """

    key: str
    text: str
    tree: object


@dataclass(frozen=True)
class Campaign:
    """A validated campaign file (granchain.campaigns.spec describes the file).

    Attributes
    ----------
    source : str
        What messages name as the file: its path, or ``<campaign dict>``.
    text : str
        The file's text ("" for a dict), copied into the workspace as campaign.toml.
    base : dict
        The base scene, canonical (granchain.scene.scene_to_dict of the validated scene).
    base_table : dict or None
        The base scene's tables as its file (or inline [scene]) writes them: what each point's keys
        are set on, so that a point is the scene file with those keys written in it (a tapered base
        keeps its taper rule and nominal radius, which the canonical form writes as per-bead radii);
        None: the canonical base.
    base_source : str
        Where the base scene came from: a bundled scene's name, a path, or the inline [scene].
    backend : str
        "reference" or "lammps".
    method : str or None
        "rk4" or "verlet"; None: the backend's default.
    rtol : float or None
        The tolerance every point is planned for; None: the scene's own values (the planner's
        default tolerance for those left "auto").
    error_estimate : bool
        Every observable gets its measured error (the 2 dt and 4 dt companions).
    kind : str
        "grid", "search" or "optimize".
    axes : tuple of Axis
        The grid's axes ([vary] keys, and [zip] as one); a search's outer points.
    derive : tuple of Derived
        The [derive] keys, in file order.
    search : Search or None
        The [search] table (kind "search").
    regime_contact : int or None
        The contact whose force history gives the table's pulses and regime; None: the last of the
        scene's [outputs] histories.
    title : str
        The campaign's title, or "".
    ranks : int or str
        MPI ranks per point, or "auto" (granchain.campaigns.execute.point_ranks).
    optimize : Optimize or None
        The [optimize] table (kind "optimize"; granchain.campaigns.optimize_spec.Optimize).
    cluster : dict or None
        The [cluster] table's values (granchain.campaigns.cluster_settings), or None.
    sections : tuple of Sections
        The [sections] table: per-bead keys each point builds from its parameters
        (granchain.campaigns.sections.Sections.build), after [derive].
    """

    source: str
    text: str
    base: dict  # the base scene, canonical (granchain.scene.scene_to_dict)
    base_source: str
    backend: str
    method: str | None
    rtol: float | None
    error_estimate: bool
    kind: str
    axes: tuple[Axis, ...]
    derive: tuple[Derived, ...]
    search: Search | None = None
    regime_contact: int | None = None
    title: str = ""
    ranks: int | str = 1  # MPI ranks per point, or "auto" (granchain.campaigns.execute.point_ranks)
    cluster: dict | None = None  # the [cluster] table's values (granchain.campaigns.cluster)
    base_table: dict | None = None  # the base scene as written: what the points' keys are set on
    optimize: Any = None  # the [optimize] table (optimize_spec.Optimize), for kind "optimize"
    sections: tuple = ()  # the [sections] table (sections.Sections): per-bead keys built from sections

    @property
    def varied_keys(self) -> tuple[str, ...]:
        """Every key of a point's parameters, in table order: the grid's, the searched one, the derived."""
        keys = [k for a in self.axes for k in a.keys]
        if self.search is not None:
            keys.append(self.search.key)
        if self.optimize is not None:
            keys.extend(self.optimize.keys)
        return (*keys, *(d.key for d in self.derive))

    @property
    def outer_keys(self) -> tuple[str, ...]:
        """The grid's keys, in table order: a search's outer keys (the searched and derived keys not among them)."""
        return tuple(k for a in self.axes for k in a.keys)

    def grid(self) -> list[dict]:
        """The grid's parameter sets (before [derive]), in order: the last axis varies fastest."""
        if not self.axes:
            return [{}]
        out = []
        for combo in itertools.product(*(a.values for a in self.axes)):
            params: dict = {}
            for axis, values in zip(self.axes, combo, strict=True):
                params.update(zip(axis.keys, values, strict=True))
            out.append(params)
        return out

    def point(self, params: dict, index: int = 0, count: int = 1) -> Point:
        """Make and validate one point from its grid parameters (the searched key among them for a
        search): apply [derive], set the scene keys on the base scene, read it as a scene."""
        full = dict(params)
        where = f"{self.source}: point {index + 1} of {count} ({params_text(params)})"
        values = self._values(full)
        for d in self.derive:
            try:
                v = expr.evaluate(d.tree, values, d.text)
            except expr.ExpressionError as e:
                raise CampaignError(f"{where}: [derive] {d.key!r}: {e}") from None
            full[d.key] = whole(d.key, v)
            values = self._values(full)
        data = _deep_copy(self.base if self.base_table is None else self.base_table)
        built = {s.key: s.build(full, where) for s in self.sections}  # on the scene, not among the params
        for key, value in [*full.items(), *built.items()]:
            if "." in key:  # the keys Scene.replace sets, set as it sets them (scene.set_key)
                try:
                    set_key(data, key, value, f"{where}: in the base scene")
                except SceneError as e:
                    raise CampaignError(str(e)) from None
        try:
            scene = scene_from_dict(data, source=f"campaign point ({params_text(full)})")
        except SceneError as e:
            msg = str(e).split(": ", 1)[-1] if str(e).startswith("campaign point (") else str(e)
            raise CampaignError(f"{where} is not a valid scene: {msg}") from None
        return Point(index=index, params=full, scene=scene)

    def _values(self, params: dict) -> dict:
        """Names an expression may read: the base scene's numbers, the parameters, their short names."""
        values = scene_numbers(self.base)
        values.update(scene_numbers(self.base_table or {}))  # a tapered chain's nominal radius and taper
        values.update(params)
        shorts: dict[str, list[str]] = {}
        for k in params:
            shorts.setdefault(k.rsplit(".", 1)[-1], []).append(k)
        for short, keys in shorts.items():
            if len(keys) == 1 and short not in params:
                values[short] = params[keys[0]]
        return values

    def points(self) -> list[Point]:
        """Every point of a grid campaign, each validated; a search's outer points with the searched
        key at both ends of its range are validated by :func:`check_search_points`."""
        grid = self.grid()
        return [self.point(p, i, len(grid)) for i, p in enumerate(grid)]


#: the scene keys that take a whole number (granchain.scene: an integer, not a float)
INTEGER_KEYS = ("chain.beads", "run.stop_after_contact")


def whole(key: str, value: Any) -> Any:
    """A computed value ([derive], a spaced [vary] list) for key: for an integer key, an integral
    float as that integer (2 * n = 20.0 is 20 beads); anything else as it is (20.5 beads is refused
    by the scene, naming the key)."""
    if key in INTEGER_KEYS and isinstance(value, float) and value.is_integer():
        return int(value)
    return value


def _deep_copy(d):
    if isinstance(d, dict):
        return {k: _deep_copy(v) for k, v in d.items()}
    if isinstance(d, list):
        return [_deep_copy(v) for v in d]
    return d


def scene_numbers(d: dict, prefix: str = "") -> dict[str, float]:
    """Every number of a scene's dict by its dotted name (``chain.radius``): what an expression may read."""
    out = {}
    for k, v in d.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(scene_numbers(v, name + "."))
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            out[name] = v
    return out


#: the most points a campaign may have (a typo in num can ask for millions); counted from the lists'
#: lengths and num before any value is made
MAX_POINTS = 100_000
#: the most beads a campaign point's chain may have when [vary] or [zip] sets chain.beads (one chain
#: longer than this is one run: granchain run, or granchain submit on a cluster)
MAX_POINT_BEADS = 10_000_000
#: the most MPI ranks a point may ask for
MAX_RANKS = 4096


#: the deepest a campaign's tables and lists nest (the file's tables, a [vary] list, a value that is a
#: list of contacts, an inline [scene]'s per-bead material tables: 6 levels)
MAX_NESTING = 32


def check_nesting(data: dict, source: str) -> None:
    """Refuse tables and lists nested deeper than MAX_NESTING (without recursing: a dict of the
    caller's may even contain itself), before any of them is read or shown in a message."""
    stack = [(data, 1)]
    while stack:
        value, depth = stack.pop()
        if depth > MAX_NESTING:
            raise CampaignError(
                f"{source}: nests arrays or tables more than {MAX_NESTING} levels deep; no campaign key takes more "
                "than a list of values, each a number, a string or a short list (e.g. [outputs] histories)"
            )
        if isinstance(value, dict):
            stack.extend((v, depth + 1) for v in value.values())
        elif isinstance(value, list):
            stack.extend((v, depth + 1) for v in value)


def _length(spec: Any) -> int | None:
    """How many values a [vary] / [zip] entry makes, read before any is made (None: not a valid entry;
    _values_of says why)."""
    if isinstance(spec, list):
        return len(spec)
    if isinstance(spec, dict):
        num = spec.get("num")
        if isinstance(num, int) and not isinstance(num, bool):
            return num
        if isinstance(num, float) and math.isfinite(num) and num >= 1:
            return math.floor(num)
    return None


def check_size(data: dict, source: str) -> None:
    """The grid's point count from the lists' lengths and num, before any value is made: a num of
    1e12 is refused here, naming the key and the limit (not after building a trillion values); so is
    a varied chain.beads above MAX_POINT_BEADS (its planning alone would not end)."""
    count = 1
    for name in ("vary", "zip"):
        table = data.get(name, {})
        lengths = []
        for key, spec in table.items():
            n = _length(spec)
            if n is None:
                continue
            if n > MAX_POINTS:
                raise CampaignError(
                    f"{source}: [{name}] {key!r} makes {n:g} values; a campaign has at most {MAX_POINTS} points "
                    "(granchain.campaigns.spec.MAX_POINTS): reduce num or the list"
                )
            if key == "chain.beads" and isinstance(spec, list):
                big = [v for v in spec if isinstance(v, int) and not isinstance(v, bool) and v > MAX_POINT_BEADS]
                if big:
                    raise CampaignError(
                        f"{source}: [{name}] 'chain.beads' = {big[0]}: a campaign point has at most "
                        f"{MAX_POINT_BEADS} beads (granchain.campaigns.spec.MAX_POINT_BEADS); one chain this long "
                        "is one run: granchain run, or granchain submit on a cluster"
                    )
            lengths.append(n)
        if not lengths:
            continue
        count *= max(lengths) if name == "zip" else math.prod(lengths)
        if count > MAX_POINTS:
            keys = ", ".join(repr(k) for k in data.get("vary", {})) + (
                ", [zip] " + ", ".join(repr(k) for k in data.get("zip", {})) if "zip" in data else ""
            )
            raise CampaignError(
                f"{source}: the grid of {keys} has {count:g} points or more; a campaign has at most {MAX_POINTS} "
                "(granchain.campaigns.spec.MAX_POINTS): reduce num or the lists"
            )
