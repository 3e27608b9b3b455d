"""Contact laws declare their facts, and no module outside granchain/physics/laws/ asks a law's name.

The planner, the error bars, the loading regime, the fronts and the deck read what a law declares
(ContactLaw.onset_order, closing_limits_order, constant_tangent, loading_time_scale,
builtin_granular_normal, model_domains: rule 9 of granchain.physics.laws.base). A module that asks
``law == "bilinear"`` holds a fact the law should declare: a new law would silently get the wrong
answer. The scan is tests/test_integrator_facts.py's, with the laws' names.
"""

import ast
import math

import pytest

from granchain.physics.laws import LAWS
from granchain.physics.laws.base import TimeScale
from granchain.physics.loading_regime import loading_regime

from . import name_scan
from .conftest import LAW_NAMES, make_scene
from .test_integrator_facts import PACKAGE

#: the names the scan looks for: every registered law's
NAMES = frozenset(LAWS)
#: where a law's name may be asked, and why (module path relative to granchain/ -> reason)
EXCEPTIONS = {
    # the laws' own conversions into one another by equal plastic slopes (Thornton's p_y and the bilinear
    # k, Sec. III): a fact of the pair of laws `granchain compare --laws` converts between, by name
    "workflows/law_comparison.py": "converts a scene between two named laws",
    # the paper's own comparison of the Thornton and bilinear chains (Sec. III C): the laws are its subject
    "reproduce/laws.py": "reproduces the paper's comparison of two named laws",
}


def questions(tree: ast.AST) -> list[tuple[int, str]]:
    """Where a module asks for a law by name (tests/name_scan.py)."""
    return name_scan.questions(tree, NAMES, "a law", any_call=False)


def test_the_scan_finds_each_kind_of_question():
    """The scan sees the questions the modules asked before the laws declared their facts."""
    code = """
if scene.contact.law != "bilinear" or not step: pass
why = {"the law": scene.contact.law != "hertz"}
if law in ("thornton", "bilinear"): pass
T = {"hertz": 0.5, "power": 0.1}
y = LAWS["thornton"]
Z = dict(hertz=1)
"""
    assert sorted(line for line, _ in questions(ast.parse(code))) == [2, 3, 4, 5, 6, 7]
    assert questions(ast.parse('DecayFit(power=1.0)\nname = "hertz"\nf(law="bilinear")\n')) == []


def test_no_module_outside_the_laws_asks_for_a_law_by_name():
    """Every module of granchain/ but the laws' package and the listed exceptions reads facts, not names."""
    bad = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        if rel.startswith("physics/laws/") or rel in EXCEPTIONS:
            continue
        for line, what in questions(ast.parse(path.read_text(), filename=rel)):
            bad.append(f"granchain/{rel}:{line}: {what}")
    assert not bad, "declare the fact on the law (granchain.physics.laws.base, rule 9) instead:\n" + "\n".join(bad)


def test_the_exceptions_are_still_needed():
    """An exception that no longer asks is removed from the list (it would hide a new question)."""
    for rel in EXCEPTIONS:
        assert questions(ast.parse((PACKAGE / rel).read_text())), f"{rel} no longer asks: drop its exception"


def test_the_yes_no_stand_ins_for_the_exponent_are_gone():
    """loading_is_linear and hertz_onset stood in for the exponent and the time scale: no law has them."""
    for cls in LAWS.values():
        assert not hasattr(cls, "loading_is_linear")
        assert not hasattr(cls, "hertz_onset")


@pytest.mark.parametrize("law", LAW_NAMES)
def test_every_law_declares_its_facts(law):
    """Each fact is of its kind, and onset_order is 1 + n of the declared exponent where the law does not
    say it measured otherwise (only the bilinear loading line's closing is a located kink)."""
    cls = LAWS[law]
    sc = make_scene(law=law)
    for flag in (cls.constant_tangent, cls.closing_limits_order):
        assert isinstance(flag, bool)
    assert cls.builtin_granular_normal is None or isinstance(cls.builtin_granular_normal, str)
    order = sc.law.onset_order()
    assert isinstance(order, float)
    assert 2.0 <= order <= 4.0
    if cls.closing_limits_order:
        assert order == 1.0 + float(min(sc.law.loading_exponent().flat))
    if cls.constant_tangent:  # the same tangent at any force
        forces = [1.0, 1e3]
        assert float(sc.law.tangent_stiffness(forces[0])) == float(sc.law.tangent_stiffness(forces[1]))


@pytest.mark.parametrize("law", LAW_NAMES)
def test_every_law_gives_its_loading_time_scale(law):
    """Every law tells a step load's regime from its own time scale, and a longer load is as long or
    longer against it (the ratio grows with T; the regime passes short -> transition -> long in order)."""
    step = 'kind = "step"\namplitude = 20.0\nduration = {T!r}'
    regimes, ratios = [], []
    for duration in (1e-9, 1e-7, 1e-5, 1e-3):
        sc = make_scene(law=law, loading=step.format(T=duration))
        scale = LAWS[law].loading_time_scale(sc, 20.0, duration)
        assert isinstance(scale, TimeScale)
        assert 0.0 < scale.short_below < scale.long_above
        got = loading_regime(sc)
        assert math.isclose(got.ratio, scale.ratio, rel_tol=1e-12)
        assert scale.unit in got.text
        regimes.append(got.regime)
        ratios.append(got.ratio)
    assert ratios == sorted(ratios)
    order = ["short", "transition", "long"]
    assert [order.index(r) for r in regimes] == sorted(order.index(r) for r in regimes)
    assert regimes[0] == "short"
    assert regimes[-1] == "long"
