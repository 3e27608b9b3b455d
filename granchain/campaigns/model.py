"""A validated campaign: its grid's axes, its search, its derived keys, and the points it makes,
each a validated scene (granchain.campaigns.spec reads a campaign file into one)."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

from granchain.campaigns import expr
from granchain.errors import GranchainError
from granchain.scene import Scene, SceneError, scene_from_dict, scene_to_dict


class CampaignError(GranchainError, ValueError):
    """A campaign file or one of its points is invalid; the message names the key and the fix."""


def _num_text(v: Any) -> str:
    return f"{v:.6g}" if isinstance(v, float) else repr(v) if isinstance(v, str) else str(v)


def params_text(params: dict) -> str:
    """'loading.amplitude = 100, loading.duration = 1e-05': a point's parameters, for messages."""
    return ", ".join(f"{k} = {_num_text(v)}" for k, v in params.items())


@dataclass(frozen=True)
class Axis:
    """One axis of the grid: a single [vary] key, or the keys of [zip] (values: one tuple per step)."""

    keys: tuple[str, ...]
    values: tuple[tuple, ...]


@dataclass(frozen=True)
class Predicate:
    """quantity op value, on one run: ``pulses at contact 20 > 1``."""

    quantity: str
    op: str
    value: float
    contact: int | None = None

    @property
    def text(self) -> str:
        where = f" at contact {self.contact}" if self.contact is not None else ""
        return f"{self.quantity}{where} {self.op} {_num_text(self.value)}"

    def holds(self, x: float) -> bool:
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
    until ``predicate`` flips."""

    key: str
    low: float
    high: float
    scale: str  # "log" | "linear"
    tolerance: float
    predicate: Predicate

    def midpoint(self, lo: float, hi: float) -> float:
        return math.sqrt(lo * hi) if self.scale == "log" else 0.5 * (lo + hi)

    def converged(self, lo: float, hi: float) -> bool:
        a, b = min(lo, hi), max(lo, hi)
        return (b / a - 1.0 <= self.tolerance) if self.scale == "log" else (b - a <= self.tolerance)

    def width(self, lo: float, hi: float) -> float:
        """The bracket's width in the tolerance's measure."""
        a, b = min(lo, hi), max(lo, hi)
        return b / a - 1.0 if self.scale == "log" else b - a


@dataclass(frozen=True)
class Point:
    """One point: its parameters (varied, free and derived keys) and its validated scene."""

    index: int
    params: dict
    scene: Scene

    @property
    def scene_dict(self) -> dict:
        """The canonical scene (granchain.scene.scene_to_dict of the validated scene)."""
        return scene_to_dict(self.scene)


@dataclass(frozen=True)
class Derived:
    """One [derive] key: its expression's text and parsed tree (granchain.campaigns.expr)."""

    key: str
    text: str
    tree: object


@dataclass(frozen=True)
class Campaign:
    """A validated campaign file (granchain.campaigns.spec describes the file)."""

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

    @property
    def varied_keys(self) -> tuple[str, ...]:
        """Every key of a point's parameters, in table order: the grid's, the searched one, the derived."""
        keys = [k for a in self.axes for k in a.keys]
        if self.search is not None:
            keys.append(self.search.key)
        return (*keys, *(d.key for d in self.derive))

    @property
    def outer_keys(self) -> tuple[str, ...]:
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
            full[d.key] = v
            values = self._values(full)
        data = _deep_copy(self.base)
        for key, value in full.items():
            if "." in key:
                _set_key(data, key, value, where)
        try:
            scene = scene_from_dict(data, source=f"campaign point ({params_text(full)})")
        except SceneError as e:
            msg = str(e).split(": ", 1)[-1] if str(e).startswith("campaign point (") else str(e)
            raise CampaignError(f"{where} is not a valid scene: {msg}") from None
        return Point(index=index, params=full, scene=scene)

    def _values(self, params: dict) -> dict:
        """Names an expression may read: the base scene's numbers, the parameters, their short names."""
        values = scene_numbers(self.base)
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


def _set_key(data: dict, key: str, value: Any, where: str) -> None:
    parts = key.split(".")
    node = data
    for i, part in enumerate(parts[:-1]):
        nxt = node.get(part)
        if nxt is None:
            nxt = node[part] = {}
        if not isinstance(nxt, dict):
            head = ".".join(parts[: i + 1])
            raise CampaignError(
                f"{where}: cannot set {key!r}: {head} is {nxt!r} in the base scene, not a table (set {head!r} itself)"
            )
        node = nxt
    node[parts[-1]] = value
