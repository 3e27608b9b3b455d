"""The [optimize] table of a campaign file: an objective, its direction, a trial budget, a seed, the
variables (scene keys) and constraints, read and validated before anything runs::

    [optimize]
    objective = "leading_peak_force"          # an observable, or an expression of observables ([derive] language)
    direction = "minimize"                    # or "maximize"
    trials = 20                               # the evaluation budget
    seed = 1                                  # the sampler's seed: the same seed, the same designs
    batch = 1                                 # designs asked for, and run side by side, at a time
    confirm = true                            # the winner re-run at rtol / 10 and on the other backend
    constraints = ["chain.radius * chain.taper ** 9 >= 2e-3"]   # must hold; a design violating one never runs

    [optimize.variables]
    "chain.taper" = { low = 0.8, high = 1.0 }                   # a float (log = true: a log scale)
    "chain.beads" = { low = 5, high = 12, integer = true }      # a whole number
    "chain.material" = { choices = ["brass", "chrome-steel-52100"] }   # one of a list

A constraint is ``LEFT op RIGHT``, op one of ``<= >= < >``, each side an expression of the [derive]
language (granchain.campaigns.expr: numbers, names, + - * / ** and parentheses, never eval). Its names,
like the objective's, are observables (granchain.postprocess.observables.table_columns), the variables
(full or unambiguous short names), the derived keys and the base scene's numbers. A constraint that
reads no observable is checked before its design runs (a violating design is not run); one that reads
an observable after. The optimiser runs in granchain.campaigns.optimize.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

from granchain.campaigns import expr
from granchain.campaigns.model import CampaignError

OPTIMIZE_KEYS = ("objective", "direction", "trials", "seed", "variables", "constraints", "batch", "startup", "confirm")
VARIABLE_KEYS = ("low", "high", "log", "integer", "choices")
DIRECTIONS = ("minimize", "maximize")
#: the most trials one [optimize] table may ask for (each is a run)
MAX_TRIALS = 10_000
#: a constraint's comparison: the first of these in its text splits it into its two sides
_COMPARISON = re.compile(r"<=|>=|<|>")


@dataclass(frozen=True)
class Variable:
    """One [optimize.variables] entry: a float or whole-number range, or a list of choices.

    Attributes
    ----------
    key : str
        The scene key (``chain.taper``), or a free parameter that [derive] reads.
    kind : str
        "float", "int" or "categorical".
    low, high : float or int or None
        The range's ends (both included), for "float" and "int".
    log : bool
        Sampled on a log scale (low > 0).
    choices : tuple
        The values of a "categorical" variable (strings, numbers or booleans).
    """

    key: str
    kind: str
    low: float | int | None = None
    high: float | int | None = None
    log: bool = False
    choices: tuple = ()

    def suggest(self, trial) -> Any:
        """The variable's value for an optuna trial (ask-and-tell: trial.suggest_*)."""
        if self.kind == "categorical":
            return trial.suggest_categorical(self.key, list(self.choices))
        if self.kind == "int":
            return trial.suggest_int(self.key, self.low, self.high, log=self.log)
        return trial.suggest_float(self.key, self.low, self.high, log=self.log)

    def ends(self) -> tuple:
        """The values validation tries before anything runs: the range's ends, or every choice."""
        return self.choices if self.kind == "categorical" else (self.low, self.high)

    @property
    def text(self) -> str:
        """The variable as the record and messages write it."""
        if self.kind == "categorical":
            return f"{self.key} in {list(self.choices)}"
        return f"{self.key} in [{self.low:g}, {self.high:g}]" + (" (log)" if self.log else "")


@dataclass(frozen=True)
class Constraint:
    """One constraint, ``left op right``: a design for which it does not hold is infeasible.

    Attributes
    ----------
    text : str
        As the file writes it.
    left, right : object
        The two sides' parsed trees (granchain.campaigns.expr.parse).
    op : str
        "<=", ">=", "<" or ">".
    """

    text: str
    left: object
    op: str
    right: object

    @property
    def names(self) -> set[str]:
        """The names both sides read."""
        return expr.names(self.left) | expr.names(self.right)

    def holds(self, values: dict) -> bool:
        """Whether it holds for these values (raises expr.ExpressionError where a side cannot be computed)."""
        a, b = expr.evaluate(self.left, values, self.text), expr.evaluate(self.right, values, self.text)
        return {"<=": a <= b, ">=": a >= b, "<": a < b, ">": a > b}[self.op]


@dataclass(frozen=True)
class Optimize:
    """The [optimize] table, validated.

    Attributes
    ----------
    objective : str
        The objective's text: an observable's name or an expression of observables.
    tree : object
        Its parsed tree.
    direction : str
        "minimize" or "maximize".
    trials : int
        The evaluation budget (trials asked of the optimiser).
    seed : int
        The sampler's seed.
    variables : tuple of Variable
        What varies, in file order.
    constraints : tuple of Constraint
        What must hold.
    batch : int
        Designs asked for at a time and run side by side (told in trial order: the result does not
        depend on which finishes first).
    startup : int
        Trials sampled at random before TPE models the results (optuna's n_startup_trials).
    confirm : bool
        The best design is run again at rtol / 10 and on the other backend before it is reported
        (optimize.confirm_best; not with two objectives).
    objective2, tree2, direction2 : str, object, str or None
        A second objective (``objective = ["a", "b"]``), its tree and direction: the search then
        finds a Pareto front (optuna's multi-objective TPE).
    """

    objective: str
    tree: object
    direction: str
    trials: int
    seed: int
    variables: tuple[Variable, ...]
    constraints: tuple[Constraint, ...] = ()
    batch: int = 1
    startup: int = 5
    confirm: bool = True
    objective2: str | None = None
    tree2: object = None
    direction2: str | None = None

    @property
    def keys(self) -> tuple[str, ...]:
        """The variables' keys, in file order."""
        return tuple(v.key for v in self.variables)

    def sign(self, value: float) -> float:
        """value as minimised: -value for "maximize"."""
        return value if self.direction == "minimize" else -value


def _whole(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def read_kind(c: dict, data: dict, source: str, axes: list, kinds: tuple) -> str:
    """[campaign] kind, or the kind its tables make: "search" with [search], "optimize" with [optimize]."""
    kind = c.get("kind", "search" if "search" in data else "optimize" if "optimize" in data else "grid")
    if kind not in kinds:
        raise CampaignError(f"{source}: [campaign] kind = {kind!r} is invalid: 'grid', 'search' or 'optimize'")
    need = {
        "search": "a [search] table (key, range, predicate)",
        "optimize": "an [optimize] table (objective, variables)",
    }
    if kind in need and kind not in data:
        raise CampaignError(f"{source}: [campaign] kind = {kind!r} needs {need[kind]}")
    for other in ("search", "optimize"):
        if other in data and kind != other:
            raise CampaignError(
                f"{source}: a [{other}] table with kind = {kind!r}: drop kind (or set kind = {other!r})"
            )
    if kind == "optimize" and axes:
        raise CampaignError(
            f"{source}: an [optimize] campaign has no [vary] or [zip] grid yet; drop them (give the varied keys "
            "as [optimize.variables])"
        )
    return kind


def read_optimize(t: Any, source: str, did_you_mean) -> Optimize:
    """The [optimize] table validated (did_you_mean: scene.section._did_you_mean, for spelling hints);
    a CampaignError naming the field and the fix otherwise."""
    where = f"{source}: [optimize]"
    if not isinstance(t, dict):
        raise CampaignError(f"{where} must be a table: write it as an [optimize] section")
    for key in t:
        if key not in OPTIMIZE_KEYS:
            raise CampaignError(
                f"{where} has unknown key {key!r}; {did_you_mean(key, OPTIMIZE_KEYS)}allowed keys: "
                f"{', '.join(OPTIMIZE_KEYS)}"
            )
    for key in ("objective", "variables"):
        if key not in t:
            raise CampaignError(
                f"{where} is missing {key!r} (objective, variables; docs/campaigns.md 'The optimize kind')"
            )
    objectives = t["objective"] if isinstance(t["objective"], list) else [t["objective"]]
    if not 1 <= len(objectives) <= 2:
        raise CampaignError(f"{where} objective = {t['objective']!r} is invalid: one objective, or a list of two")
    directions = t.get("direction", "minimize")
    directions = directions if isinstance(directions, list) else [directions] * len(objectives)
    if len(directions) != len(objectives) or any(d not in DIRECTIONS for d in directions):
        raise CampaignError(
            f"{where} direction = {t.get('direction')!r} is invalid: 'minimize' or 'maximize' (a list of one per "
            "objective for two)"
        )
    direction = directions[0]
    trials = t.get("trials", 20)
    if not _whole(trials) or not 1 <= trials <= MAX_TRIALS:
        raise CampaignError(
            f"{where} trials = {trials!r} is invalid: a whole number from 1 to {MAX_TRIALS} (the evaluation budget)"
        )
    seed = t.get("seed", 0)
    if not _whole(seed) or not 0 <= seed < 2**32:
        raise CampaignError(f"{where} seed = {seed!r} is invalid: a whole number from 0 to 2**32 - 1")
    batch = t.get("batch", 1)
    if not _whole(batch) or not 1 <= batch <= trials:
        raise CampaignError(f"{where} batch = {batch!r} is invalid: a whole number from 1 to trials ({trials})")
    startup = t.get("startup", min(10, max(2, trials // 3)))
    if not _whole(startup) or startup < 1:
        raise CampaignError(f"{where} startup = {startup!r} is invalid: a whole number >= 1 (random trials first)")
    trees = [_read_objective(o, where) for o in objectives]
    second = (objectives[1], trees[1], directions[1]) if len(objectives) == 2 else (None, None, None)
    variables = _read_variables(t["variables"], f"{where}.variables", did_you_mean)
    constraints = _read_constraints(t.get("constraints", []), where)
    confirm = t.get("confirm", True)
    if not isinstance(confirm, bool):
        raise CampaignError(
            f"{where} confirm = {confirm!r} is invalid: true (the winner re-run at rtol / 10 and on the other "
            "backend) or false"
        )
    confirm = confirm and second[0] is None  # a front has no one winner to re-run
    return Optimize(
        objectives[0], trees[0], direction, trials, seed, variables, constraints, batch, startup, confirm, *second
    )


def _read_objective(objective: Any, where: str):
    if not isinstance(objective, str):
        raise CampaignError(
            f"{where} objective = {objective!r} is invalid: an observable or an expression as a string, "
            'e.g. "wall_max_force"'
        )
    try:
        return expr.parse(objective)
    except expr.ExpressionError as e:
        raise CampaignError(f"{where} objective: {e}") from None


def _read_variables(table: Any, where: str, did_you_mean) -> tuple[Variable, ...]:
    if not isinstance(table, dict) or not table:
        raise CampaignError(
            f'{where} is empty or not a table: give each varied key a range or choices, e.g. "chain.taper" = '
            "{ low = 0.8, high = 1.0 }"
        )
    return tuple(_read_variable(key, spec, f"{where} {key!r}", did_you_mean) for key, spec in table.items())


def _read_variable(key: str, spec: Any, where: str, did_you_mean) -> Variable:
    form = "{ low = a, high = b } (log = true for a log scale, integer = true for whole numbers) or { choices = [...] }"
    if not isinstance(spec, dict):
        raise CampaignError(f"{where} = {spec!r} is invalid: {form}")
    for k in spec:
        if k not in VARIABLE_KEYS:
            raise CampaignError(f"{where} has unknown key {k!r}; {did_you_mean(k, VARIABLE_KEYS)}allowed: {form}")
    if "choices" in spec:
        choices = spec["choices"]
        if set(spec) != {"choices"}:
            raise CampaignError(f"{where}: choices is a list alone; drop low, high, log and integer")
        if not isinstance(choices, list) or not choices:
            raise CampaignError(
                f'{where} choices = {choices!r} is invalid: a non-empty list of values, e.g. ["brass", "steel"]'
            )
        if any(not isinstance(c, (str, int, float, bool)) for c in choices) or len(set(map(repr, choices))) != len(
            choices
        ):
            raise CampaignError(f"{where} choices = {choices!r} is invalid: distinct strings, numbers or booleans")
        return Variable(key, "categorical", choices=tuple(choices))
    if "low" not in spec or "high" not in spec:
        raise CampaignError(f"{where} = {spec!r} needs both low and high: {form}")
    low, high, log, integer = spec["low"], spec["high"], spec.get("log", False), spec.get("integer", False)
    if not isinstance(log, bool) or not isinstance(integer, bool):
        raise CampaignError(f"{where}: log and integer are true or false")
    check = _whole if integer else _number
    what = "whole numbers" if integer else "finite numbers"
    if not check(low) or not check(high):
        raise CampaignError(f"{where}: low = {low!r}, high = {high!r} are invalid: two {what}")
    if not low < high:
        raise CampaignError(
            f"{where}: low = {low!r} >= high = {high!r}; give low < high (a fixed value belongs in the base scene)"
        )
    if log and low <= 0:
        raise CampaignError(
            f"{where}: log = true needs low > 0 (got low = {low!r}); use a linear range for zero or negatives"
        )
    if integer:
        return Variable(key, "int", int(low), int(high), log)
    return Variable(key, "float", float(low), float(high), log)


def _read_constraints(items: Any, where: str) -> tuple[Constraint, ...]:
    if isinstance(items, str):
        items = [items]
    if not isinstance(items, list) or any(not isinstance(c, str) for c in items):
        raise CampaignError(
            f"{where} constraints = {items!r} is invalid: a list of strings such as "
            '"chain.beads * chain.radius <= 0.05"'
        )
    out = []
    for text in items:
        m = _COMPARISON.search(text)
        if m is None or _COMPARISON.search(text, m.end()) is not None:
            raise CampaignError(
                f"{where} constraint {text!r} is invalid: one comparison LEFT op RIGHT, op one of <= >= < >, e.g. "
                '"chain.radius * chain.taper ** 9 >= 2e-3"'
            )
        try:
            left, right = expr.parse(text[: m.start()]), expr.parse(text[m.end() :])
        except expr.ExpressionError as e:
            raise CampaignError(f"{where} constraint {text!r}: {e}") from None
        out.append(Constraint(text, left, m.group(), right))
    return tuple(out)


#: numbers of a design's own chain that the objective and the constraints may read (issue 45: a total
#: mass or length as a bound), with their units; computed from the point's scene (design_numbers)
DESIGN_NUMBERS = {"chain_mass": "kg", "chain_length": "m"}


def design_numbers(scene) -> dict:
    """The design's DESIGN_NUMBERS: chain_mass, the beads' total mass (the striker not counted), kg;
    chain_length, the chain's length at rest, the sum of its beads' diameters, m."""
    return {"chain_mass": float(scene.bead_masses.sum()), "chain_length": float(2.0 * scene.bead_radii.sum())}


def check_names(opt: Optimize, readable: set[str], observables: tuple[str, ...], source: str, did_you_mean) -> None:
    """Every name the objective and the constraints read is an observable or one of `readable` (the
    variables, derived keys, base scene numbers); the objective reads at least one observable."""
    known = set(readable) | set(observables)
    objectives = [(opt.objective, opt.tree)] + ([(opt.objective2, opt.tree2)] if opt.objective2 else [])
    parts = [("objective", text, expr.names(tree)) for text, tree in objectives] + [
        ("constraint", c.text, c.names) for c in opt.constraints
    ]
    for what, text, names in parts:
        for name in sorted(names):
            if name not in known:
                raise CampaignError(
                    f"{source}: [optimize] {what} {text!r} reads {name!r}: {did_you_mean(name, sorted(known))}it is "
                    "not an observable (docs/observables.md), a variable, a derived key or a number of the base scene"
                )
    for text, tree in objectives:
        if not expr.names(tree) & set(observables):
            raise CampaignError(
                f"{source}: [optimize] objective {text!r} reads no observable: give an observable of the run "
                f"({', '.join(observables[:6])}, ...) or an expression of them"
            )
