"""Reading one TOML table of a scene: each key checked as it is read, and every problem a
:class:`SceneError` that names the file, the section, the key, the value and what is allowed."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from granchain.exceptions import GranchainError

if TYPE_CHECKING:
    from granchain.physics.materials import PlausibleRange


class SceneError(GranchainError, ValueError):
    """A scene file is invalid. The message names the file, the key, the value and the fix."""


def _shown(value: Any) -> str:
    """A value as a message shows it: its repr, shortened (a long string, a big list, deep nesting
    would make a message of megabytes, or recurse without end)."""
    import reprlib

    r = reprlib.Repr()
    r.maxstring, r.maxother, r.maxlong, r.maxlevel = 80, 80, 60, 3
    r.maxlist = r.maxtuple = r.maxdict = r.maxset = 12
    try:
        return r.repr(value)
    except RecursionError:  # pragma: no cover - reprlib bounds the depth
        return "<nested too deeply to show>"


class _Section:
    """Reads keys from one TOML table, remembering which were used, and raises clear errors."""

    def __init__(self, file: str, name: str, table: Any):
        self.file, self.name = file, name
        if not isinstance(table, dict):
            raise SceneError(f"{file}: [{name}] must be a table, got {_shown(table)}; write it as a [{name}] section")
        self.table = dict(table)
        self.used: set[str] = set()

    def error(self, message: str) -> SceneError:
        """A SceneError about this file (message names the section, key and fix)."""
        return SceneError(f"{self.file}: {message}")

    def fail(self, key: str, value: Any, allowed: str) -> SceneError:
        return SceneError(f"{self.file}: [{self.name}] {key} = {_shown(value)} is invalid: {allowed}")

    def has(self, key: str) -> bool:
        return key in self.table

    def raw(self, key: str, default: Any = None) -> Any:
        self.used.add(key)
        return self.table.get(key, default)

    def missing(self, key: str, allowed: str) -> SceneError:
        """A required key is absent: name it, and the present key that looks like a typo of it."""
        typo = [k for k in self.table if k not in self.used and _did_you_mean(k, (key,))]
        hint = f" ({_shown(typo[0])} looks like a typo of {key!r})" if typo else ""
        return SceneError(f"{self.file}: [{self.name}] is missing {key!r}{hint}: {allowed}")

    def required(self, key: str, allowed: str) -> Any:
        if key not in self.table:
            raise self.missing(key, allowed)
        return self.raw(key)

    def number(
        self,
        key: str,
        *,
        required: bool = True,
        default: float | None = None,
        low: float | None = None,
        low_open: bool = True,
        high: float | None = None,
        high_open: bool = True,
        what: str = "",
    ) -> float | None:
        allowed = _range_text(low, low_open, high, high_open, what)
        if key not in self.table:
            if required:
                raise self.missing(key, allowed)
            return default
        v = self.raw(key)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise self.fail(key, v, allowed)
        v = float(v)
        if low is not None and (v <= low if low_open else v < low):
            raise self.fail(key, v, allowed)
        if high is not None and (v >= high if high_open else v > high):
            raise self.fail(key, v, allowed)
        return v

    def quantity(self, key: str, plausible: PlausibleRange, *, required: bool = True, what: str = "") -> float | None:
        """A material property in SI: a finite number inside ``plausible``; outside it, a message that
        names the value, the range of real solids and the unit slip that would explain it."""
        v = self.number(key, required=required, what=what)
        if v is None:
            return None
        why = plausible.refusal(v)
        if why:
            raise SceneError(f"{self.file}: [{self.name}] {key} = {why}")
        return v

    def integer(self, key: str, *, low: int, high: int | None = None, what: str = "") -> int:
        allowed = (
            f"an integer >= {low}" + (f" and <= {high:,}" if high is not None else "") + (f" ({what})" if what else "")
        )
        v = self.required(key, allowed)
        if isinstance(v, bool) or not isinstance(v, int) or v < low or (high is not None and v > high):
            raise self.fail(key, v, allowed)
        return v

    def choice(self, key: str, choices: tuple[str, ...]) -> str:
        allowed = "one of " + ", ".join(repr(c) for c in choices)
        v = self.required(key, allowed)
        if v not in choices:
            raise self.fail(key, v, allowed)
        return v

    def forbid(self, keys: tuple[str, ...], reason: str) -> None:
        for key in keys:
            if key in self.table:
                raise SceneError(
                    f"{self.file}: [{self.name}] {key} = {_shown(self.table[key])} is not allowed here: {reason}"
                )

    def finish(self, known: tuple[str, ...]) -> None:
        for key in self.table:
            if key not in self.used:
                raise SceneError(
                    f"{self.file}: [{self.name}] has unknown key {_shown(key)} = {_shown(self.table[key])}; "
                    f"{_did_you_mean(key, known)}allowed keys: {', '.join(known)}"
                )


def _did_you_mean(key: str, known) -> str:
    """'did you mean "beads"? ' for a key one typo away from a known one, else ''."""
    import difflib

    close = difflib.get_close_matches(str(key), list(known), n=1, cutoff=0.6)
    return f"did you mean {close[0]!r}? " if close else ""


def _range_text(low, low_open, high, high_open, what) -> str:
    parts = []
    if low is not None:
        parts.append(f"{'>' if low_open else '>='} {low:g}")
    if high is not None:
        parts.append(f"{'<' if high_open else '<='} {high:g}")
    text = "a finite number" + (" " + " and ".join(parts) if parts else "")
    return text + (f" ({what})" if what else "")
