"""The scan behind tests/test_integrator_facts.py and tests/test_law_facts.py: where a module asks for a
registered part (an integrator, a law) by its name instead of reading a fact the part declares."""

import ast


def literal_names(node: ast.AST, names: frozenset[str]) -> set[str]:
    """The names of `names` a node is, or holds as the elements of a tuple, list or set literal."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
        return {node.value}
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return set().union(*(literal_names(e, names) for e in node.elts)) if node.elts else set()
    return set()


def questions(tree: ast.AST, names: frozenset[str], part: str, any_call: bool) -> list[tuple[int, str]]:
    """(line, what) for each place a module asks for a `part` ("a law", "a method") by name: a comparison
    with a name (==, !=, in, not in, against a name or a literal collection of names), a dict literal
    keyed by one, a subscript by one, and a call keyed by one (any call's keyword where `any_call`: an
    integrator's name is never a keyword argument's; else only dict(...)'s: power= is a law's name and a
    fit's keyword)."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            if any(literal_names(n, names) for n in (node.left, *node.comparators)):
                found.append((node.lineno, f"compares {part} with a name"))
        elif isinstance(node, ast.Dict):
            if any(k is not None and literal_names(k, names) for k in node.keys):
                found.append((node.lineno, f"a table keyed by {part}'s name"))
        elif isinstance(node, ast.Subscript) and literal_names(node.slice, names):
            found.append((node.lineno, f"indexes a table by {part}'s name"))
        elif isinstance(node, ast.Call) and (any_call or getattr(node.func, "id", None) == "dict"):
            if any(k.arg in names for k in node.keywords):
                found.append((node.lineno, f"a table keyed by {part}'s name (a keyword)"))
    return found
