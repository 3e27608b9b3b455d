"""What a new normal law, damping part, integrator, effect and backend touch: the files the docs list
for each exist for every registered one, the docs name them (docs/laws.md, docs/damping.md,
docs/effects.md, docs/architecture.md), and the registries are the only lists: no tuple, list or set
literal in granchain/ holds two names of registered laws or damping parts outside them."""

import ast
import inspect
from dataclasses import fields
from pathlib import Path

import pytest

import granchain
from granchain.backends import BACKENDS
from granchain.integrators import INTEGRATORS
from granchain.lammps.build import damping_header, law_header
from granchain.physics.damping import DAMPING
from granchain.physics.effects import EFFECTS
from granchain.physics.laws import LAWS
from granchain.reference.solver import IMPLEMENTATIONS
from granchain.scene.model import Effects

PACKAGE = Path(granchain.__file__).parent
ROOT = PACKAGE.parent
DOCS = ROOT / "docs"

#: what each kind of part touches, as the docs write it (<name>: the registered name), and the docs
#: that must list those files (the kind's own page, and architecture.md's "Where a new thing goes")
TOUCHES = {
    "law": (
        ("granchain/physics/laws/<name>.py", "granchain/physics/laws/__init__.py", "granchain/lammps/law_<name>.h"),
        ("laws.md", "architecture.md"),
    ),
    "damping": (
        (
            "granchain/physics/damping/<name>.py",
            "granchain/physics/damping/__init__.py",
            "granchain/lammps/damping_<name>.h",
            "granchain/scene/model.py",
        ),
        ("damping.md", "architecture.md"),
    ),
    "integrator": (
        ("granchain/integrators.py", "granchain/reference/<name>.py", "granchain/reference/solver.py"),
        ("architecture.md",),
    ),
    "effect": (
        ("granchain/physics/effects/<name>.py", "granchain/physics/effects/__init__.py"),
        ("effects.md", "architecture.md"),
    ),
    "backend": (("granchain/backends/builtin.py", "granchain/backends/__init__.py"), ("architecture.md",)),
}

#: every registered name of each kind
REGISTERED = {
    "law": tuple(LAWS),
    "damping": tuple(DAMPING),
    "integrator": tuple(INTEGRATORS),
    "effect": tuple(EFFECTS),
    "backend": tuple(BACKENDS),
}


@pytest.mark.parametrize("kind", sorted(TOUCHES))
def test_the_docs_name_what_a_new_part_touches(kind):
    """Each doc of the kind names every file a new one touches (the list pattern, <name> as written)."""
    files, docs = TOUCHES[kind]
    for doc in docs:
        text = (DOCS / doc).read_text()
        missing = [f for f in files if f"`{f}`" not in text]
        assert not missing, f"docs/{doc} does not name what a new {kind} touches: {missing}"


@pytest.mark.parametrize(("kind", "name"), [(k, n) for k, names in REGISTERED.items() for n in names])
def test_every_registered_part_has_the_files_the_docs_list(kind, name):
    """The listed files exist for every registered part: the docs' list is the one a new part follows."""
    for pattern in TOUCHES[kind][0]:
        path = ROOT / pattern.replace("<name>", name)
        assert path.is_file(), f"the {kind} {name!r} has no {path.relative_to(ROOT)} (docs list {pattern})"


def test_each_part_is_its_module_and_its_header():
    """A law's and a damping part's class live in their own module, named after them, and their C++
    header is the one the plugin build compiles (lammps.build: law_header, damping_header); a damping
    part's key is an attribute of scene.Effects; an integrator's reference implementation is
    registered under its name."""
    for name, cls in LAWS.items():
        assert Path(inspect.getfile(cls)) == PACKAGE / "physics" / "laws" / f"{name}.py"
        assert (PACKAGE / "lammps" / law_header(name)).is_file()
    effects = {f.name for f in fields(Effects)}
    for name, cls in DAMPING.items():
        assert Path(inspect.getfile(cls)) == PACKAGE / "physics" / "damping" / f"{name}.py"
        assert (PACKAGE / "lammps" / damping_header(name)).is_file()
        assert cls.key is None or cls.key in effects, f"{name}: scene.Effects has no {cls.key}"
    for name, cls in EFFECTS.items():
        assert Path(inspect.getfile(cls)) == PACKAGE / "physics" / "effects" / f"{name}.py"
    assert set(IMPLEMENTATIONS) == set(INTEGRATORS)


#: names of registered parts a list literal may not hold two of (laws; damping parts and their keys)
NAME_SETS = {
    "law": frozenset(LAWS),
    "damping": frozenset(DAMPING) | {cls.key for cls in DAMPING.values() if cls.key},
}
#: where a literal may list them, and why (module path relative to granchain/ -> reason)
EXCEPTIONS = {
    # the paper's figures compare its own two plastic laws (reproduce: the paper regenerated)
    "reproduce/laws.py": "the paper's two plastic laws, Figs. 5-7",
    # compare-laws maps the paper's two plastic laws' parameters onto each other (Thornton's yield
    # pressure <-> the bilinear law's plastic slope): a relation of the pair, not a fact of either law
    "workflows/law_comparison.py": "the parameter map between the paper's two plastic laws",
}


def _listed_names(node: ast.AST, names: frozenset[str]) -> set[str]:
    if not isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return set()
    return {e.value for e in node.elts if isinstance(e, ast.Constant) and e.value in names}


def test_the_registries_are_the_only_lists():
    """No list literal outside the registries holds two registered laws' or damping parts' names: a
    new law or part would be missing from it (tests/test_integrator_facts.py does this for integrators)."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        if rel in EXCEPTIONS or rel.startswith(("physics/laws/", "physics/damping/")):
            continue
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            for kind, names in NAME_SETS.items():
                listed = _listed_names(node, names)
                if len(listed) >= 2:
                    found.append(f"{rel}:{node.lineno}: {kind} names {sorted(listed)}")
    assert not found, "hard-coded lists of registered names (ask the registry): " + "; ".join(found)


def test_the_exceptions_are_still_needed():
    """Each exception still holds such a list (a fixed one leaves the list)."""
    for rel in EXCEPTIONS:
        tree = ast.parse((PACKAGE / rel).read_text())
        assert any(len(_listed_names(n, NAME_SETS["law"])) >= 2 for n in ast.walk(tree)), rel


def test_the_scan_finds_a_hard_coded_list():
    """The scan flags a tuple of two law names, or a damping part's name with another's key, and not
    one name alone or other strings."""
    laws, damping = sorted(NAME_SETS["law"])[:2], sorted(NAME_SETS["damping"])[:2]
    flagged = ast.parse(f"x = {tuple(laws)!r}\ny = [{damping[0]!r}, {damping[1]!r}]").body
    assert _listed_names(flagged[0].value, NAME_SETS["law"]) == set(laws)
    assert _listed_names(flagged[1].value, NAME_SETS["damping"]) == set(damping)
    single = ast.parse(f"z = ({laws[0]!r}, 'other')").body[0].value
    assert len(_listed_names(single, NAME_SETS["law"])) == 1
