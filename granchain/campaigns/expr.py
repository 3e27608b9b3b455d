"""A tiny arithmetic language for a campaign's [derive] table, evaluated without eval or exec.

Campaign and scene files are shared between people and machines: reading one must never execute
anything. An expression is numbers, names, ``+ - * / **`` and parentheses, nothing else::

    "impulse / amplitude"        "0.5 * (loading.amplitude + 2) ** -1.5"

Grammar (``**`` binds tighter than a unary sign and groups to the right, as in Python)::

    expr   := term (("+" | "-") term)*
    term   := unary (("*" | "/") unary)*
    unary  := ("+" | "-") unary | power
    power  := atom ("**" unary)?
    atom   := NUMBER | NAME | "(" expr ")"

A NAME is letters, digits, ``_`` and dots (``loading.amplitude``). :func:`parse` turns the text into
a small tree (checked once, before any point is made); :func:`evaluate` computes it for one point's
values. Every problem is an :class:`ExpressionError` naming the expression and the place.

An expression is at most MAX_LENGTH characters and its tree at most MAX_DEPTH operations deep
(parentheses, signs and chained operators all count): the parser and the evaluator recurse, and a
file someone else wrote must not reach Python's recursion limit (a RecursionError, not a message).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from granchain.exceptions import GranchainError


class ExpressionError(GranchainError, ValueError):
    """An expression that cannot be read or computed; the message names it and the fix."""


#: the longest expression read (characters)
MAX_LENGTH = 10_000
#: the deepest expression tree read: nested parentheses or signs, or operators chained (a + b + ...)
MAX_DEPTH = 100


_TOKEN = re.compile(
    r"\s*(?:(?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)|(?P<name>[A-Za-z_][A-Za-z0-9_.]*)|(?P<op>\*\*|[-+*/()]))"
)


@dataclass(frozen=True)
class Num:
    """A number of the expression, as a float."""

    value: float


@dataclass(frozen=True)
class Name:
    """A name the expression reads (``loading.amplitude``, ``impulse``): looked up for each point."""

    name: str


@dataclass(frozen=True)
class Unary:
    """A sign, "+" or "-", applied to its operand (a tree)."""

    op: str
    operand: object


@dataclass(frozen=True)
class Binary:
    """An operation "+", "-", "*", "/" or "**" on two trees."""

    op: str
    left: object
    right: object


def _tokens(text: str) -> list[tuple[str, str, int]]:
    out, pos = [], 0
    text = text.rstrip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m:
            bad = text[pos:].lstrip()[:1]
            raise ExpressionError(
                f"expression {text!r}: {bad!r} at position {len(text) - len(text[pos:].lstrip()) + 1} is not "
                "allowed; an expression has numbers, names, + - * / ** and parentheses only"
            )
        kind = m.lastgroup
        out.append((kind, m.group(kind), m.start(kind)))
        pos = m.end()
    return out


class _Parser:
    def __init__(self, text: str):
        self.text = text
        self.toks = _tokens(text)
        self.i = 0
        self.depth = 0  # parentheses and signs open now

    def nest(self, at: int) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise ExpressionError(
                f"expression {_short(self.text)}: nested more than {MAX_DEPTH} deep (parentheses, signs or powers) at "
                f"position {at + 1}; split it into several [derive] keys"
            )

    def peek(self) -> tuple[str, str, int] | None:
        return self.toks[self.i] if self.i < len(self.toks) else None

    def take(self) -> tuple[str, str, int]:
        tok = self.peek()
        if tok is None:
            raise ExpressionError(f"expression {self.text!r} ends too early: a number, a name or '(' is missing")
        self.i += 1
        return tok

    def is_op(self, *ops: str) -> bool:
        tok = self.peek()
        return tok is not None and tok[0] == "op" and tok[1] in ops

    def expr(self):
        node = self.term()
        while self.is_op("+", "-"):
            op = self.take()[1]
            node = Binary(op, node, self.term())
        return node

    def term(self):
        node = self.unary()
        while self.is_op("*", "/"):
            op = self.take()[1]
            node = Binary(op, node, self.unary())
        return node

    def unary(self):
        if self.is_op("+", "-"):
            _, op, at = self.take()
            self.nest(at)
            node = Unary(op, self.unary())
            self.depth -= 1
            return node
        return self.power()

    def power(self):
        node = self.atom()
        if self.is_op("**"):
            at = self.take()[2]
            self.nest(at)
            node = Binary("**", node, self.unary())
            self.depth -= 1
        return node

    def atom(self):
        kind, value, at = self.take()
        if kind == "num":
            return Num(float(value))
        if kind == "name":
            if self.is_op("("):
                raise ExpressionError(
                    f"expression {self.text!r}: {value}(...) at position {at + 1} is a call; calls are not allowed, "
                    "only numbers, names, + - * / ** and parentheses"
                )
            return Name(value)
        if value == "(":
            self.nest(at)
            node = self.expr()
            self.depth -= 1
            if not self.is_op(")"):
                raise ExpressionError(f"expression {self.text!r}: '(' at position {at + 1} is never closed")
            self.take()
            return node
        raise ExpressionError(
            f"expression {self.text!r}: {value!r} at position {at + 1} where a number, a name or '(' should be"
        )


def parse(text: str):
    """The expression's tree; raises ExpressionError for anything but the grammar above."""
    if not isinstance(text, str) or not text.strip():
        raise ExpressionError(f'expression {_short(text)}: give a non-empty string such as "impulse / amplitude"')
    if len(text) > MAX_LENGTH:
        raise ExpressionError(
            f"expression {_short(text)}: {len(text)} characters, more than {MAX_LENGTH}; split it into several "
            "[derive] keys"
        )
    p = _Parser(text)
    node = p.expr()
    if p.peek() is not None:
        kind, value, at = p.peek()
        raise ExpressionError(f"expression {text!r}: unexpected {value!r} at position {at + 1}")
    depth = _depth(node)
    if depth > MAX_DEPTH:
        raise ExpressionError(
            f"expression {_short(text)}: {depth} operations deep (a chain such as a + b + c + ... counts one "
            f"each), more than {MAX_DEPTH}; split it into several [derive] keys"
        )
    return node


def _short(text) -> str:
    r = repr(text)
    return r if len(r) <= 80 else r[:60] + "..." + r[-15:]


def _depth(node) -> int:
    """The depth of an expression tree, without recursion (it is checked before anything recurses)."""
    deepest, stack = 0, [(node, 1)]
    while stack:
        n, d = stack.pop()
        deepest = max(deepest, d)
        if isinstance(n, Unary):
            stack.append((n.operand, d + 1))
        elif isinstance(n, Binary):
            stack += [(n.left, d + 1), (n.right, d + 1)]
    return deepest


def names(node) -> set[str]:
    """The names an expression reads."""
    if isinstance(node, Name):
        return {node.name}
    if isinstance(node, Unary):
        return names(node.operand)
    if isinstance(node, Binary):
        return names(node.left) | names(node.right)
    return set()


def evaluate(node, values: dict[str, float], text: str = "") -> float:
    """The expression's value with names looked up in values (every name must be there)."""
    if isinstance(node, Num):
        return node.value
    if isinstance(node, Name):
        v = values[node.name]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ExpressionError(f"expression {text!r}: {node.name} = {v!r} is not a number")
        return float(v)
    if isinstance(node, Unary):
        v = evaluate(node.operand, values, text)
        return -v if node.op == "-" else v
    a, b = evaluate(node.left, values, text), evaluate(node.right, values, text)
    try:
        if node.op == "+":
            r = a + b
        elif node.op == "-":
            r = a - b
        elif node.op == "*":
            r = a * b
        elif node.op == "/":
            r = a / b
        else:
            r = a**b
    except ZeroDivisionError:
        raise ExpressionError(f"expression {text!r}: division by zero") from None
    except OverflowError:
        raise ExpressionError(f"expression {text!r}: the result overflows") from None
    if isinstance(r, complex) or not math.isfinite(r):
        raise ExpressionError(f"expression {text!r}: {a!r} {node.op} {b!r} is not a finite real number")
    return float(r)
