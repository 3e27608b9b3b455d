"""granchain.integrators: every integrator declares its facts, and no module outside asks its name.

The planner, the error bars, the comparison table's peak definitions, the accuracy study and the
reference solver read an integrator's facts (integrator(method).order, .stability, ...). A module that
asks ``method == "rk4"`` or keeps a table keyed by "verlet" holds a fact the integrator should declare:
a new integrator would silently miss it. The scan below finds such questions in granchain/ (an AST
scan: comparisons with a method's name, dict literals keyed by one, subscripts by one).
"""

import ast
import dataclasses
import math
from pathlib import Path

import pytest

import granchain
from granchain.integrators import FACTS, INTEGRATORS, IntegratorFacts, integrator
from granchain.reference.solver import IMPLEMENTATIONS, METHODS

from . import name_scan

PACKAGE = Path(granchain.__file__).parent
#: the names the scan looks for: every registered integrator's
NAMES = frozenset(INTEGRATORS)
#: where a method's name may be asked, and why (module path relative to granchain/ -> reason)
EXCEPTIONS = {
    # the registry itself: the one place the names are declared
    "integrators.py": "the registry",
    # a summary.json's companion_method, read back as text for the terminal (a file's field, not a
    # run's integrator; cli/terminal.py is edited concurrently: to be read as integrator(...).label)
    "cli/terminal.py": "a summary's companion_method printed",
}


def questions(tree: ast.AST) -> list[tuple[int, str]]:
    """Where a module asks for a method by name (tests/name_scan.py)."""
    return name_scan.questions(tree, NAMES, "a method", any_call=True)


def test_the_scan_finds_each_kind_of_question():
    """The scan sees the questions the string-keyed tables asked (the cases main had)."""
    code = """
ORDER = {"rk4": 4, "verlet": 2}
if method == "verlet": pass
if method != "rk4" and dashpot: pass
x = "verlet" if m in ("lammps", "verlet") else "rk4"
if "rk4" in {plan.method}: pass
y = STABILITY["rk4"]
CALIBRATION = dict(rk4=(1.0, 4))
"""
    assert sorted(line for line, _ in questions(ast.parse(code))) == [2, 3, 4, 5, 6, 7, 8]
    assert questions(ast.parse('solve_chain(p, 1.0, 1e-3, "rk4")\nname = "verlet"\n')) == []


def test_no_module_outside_the_registry_asks_for_an_integrator_by_name():
    """Every module of granchain/ but the listed exceptions reads facts, not names."""
    bad = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        if rel in EXCEPTIONS:
            continue
        for line, what in questions(ast.parse(path.read_text(), filename=rel)):
            bad.append(f"granchain/{rel}:{line}: {what}")
    assert not bad, "declare the fact on the integrator (granchain.integrators) instead:\n" + "\n".join(bad)


def test_the_exceptions_are_still_needed():
    """An exception that no longer asks is removed from the list (it would hide a new question)."""
    for rel in EXCEPTIONS:
        if rel == "integrators.py":
            continue
        assert questions(ast.parse((PACKAGE / rel).read_text())), f"{rel} no longer asks: drop its exception"


@pytest.mark.parametrize("name", list(INTEGRATORS))
def test_every_integrator_declares_every_fact_in_its_own_class(name):
    """Each fact is given in the integrator's own class body (not inherited), of the declared kind."""
    facts = INTEGRATORS[name]
    cls = type(facts)
    assert cls is not IntegratorFacts
    assert dataclasses.is_dataclass(cls)
    assert cls.__dataclass_params__.frozen
    assert cls.__doc__
    assert cls.__doc__ != IntegratorFacts.__doc__
    for field in FACTS:
        assert field in vars(cls), f"{cls.__name__} does not declare {field}"
    assert facts.name == name
    assert facts.label
    assert isinstance(facts.order, int)
    assert facts.order >= 1
    assert isinstance(facts.damping_order, int)
    assert 1 <= facts.damping_order <= facts.order
    for value in (facts.stability, facts.calibration):
        assert isinstance(value, float)
        assert math.isfinite(value)
        assert value > 0
    assert isinstance(facts.damping_error, float)
    assert facts.damping_error >= 0
    for flag in (facts.peaks_by_overlap, facts.locates_kinks, facts.extrapolated_reference):
        assert isinstance(flag, bool)
    for why in (facts.unordered_with_damping, facts.mixes_orders):
        assert why is None or (isinstance(why, str) and why.strip())


def test_a_fact_left_out_fails_at_declaration():
    """The base class gives no value, so an integrator that forgets one cannot be made (its class, or
    the last fact left out alike)."""
    with pytest.raises(TypeError):

        @dataclasses.dataclass(frozen=True)
        class Forgetful(IntegratorFacts):
            name: str = "forgetful"

    declared = {f: getattr(INTEGRATORS["verlet"], f) for f in FACTS[:-1]}  # all but the last
    fields = [(f, object, dataclasses.field(default=v)) for f, v in declared.items()]
    with pytest.raises(TypeError):
        dataclasses.make_dataclass("Almost", fields, bases=(IntegratorFacts,), frozen=True)()


def test_every_integrator_runs_in_the_reference_and_is_looked_up_by_name():
    """The reference implements each registered integrator (same name), and runs exactly those."""
    assert set(IMPLEMENTATIONS) == set(INTEGRATORS)
    assert METHODS == tuple(INTEGRATORS)
    for name, cls in IMPLEMENTATIONS.items():
        assert cls.name == name
        assert integrator(name) is INTEGRATORS[name]
    with pytest.raises(ValueError, match="not known"):
        integrator("euler")


def test_facts_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        INTEGRATORS["rk4"].order = 3


def test_no_fact_is_named_after_a_damping_part():
    """The integrators' facts about damping are about a velocity-dependent force (the damping part's
    velocity_dependent, which callers read), not about one part: a fact named after a part
    (``dashpot_order``) would read as wrong for every other part that shares the property."""
    from granchain.physics.damping import DAMPING

    parts = {name for name in DAMPING if name != "none"} | {cls.key for cls in DAMPING.values() if cls.key}
    named = [(fact, part) for fact in FACTS for part in parts if part in fact]
    assert not named, f"integrator facts named after a damping part: {named}"
