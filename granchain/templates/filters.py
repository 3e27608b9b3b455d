"""The Jinja filters and tests of the deck templates, and the check every template value passes:
numbers written exactly, free text as an inert comment, nothing else that would break a deck line."""

from __future__ import annotations

import dataclasses
import re


def float_repr(x) -> str:
    """A number as the shortest text that reads back to the same double: ``repr(float(x))``."""
    return repr(float(x))


def comment(text) -> str:
    r"""Any text (a scene's title, a file name) as the payload of one inert comment line of a deck.

    LAMMPS reads a line up to '\n' only, joins the next line when the last non-blank character is
    '&', keeps reading while a line holds an odd number of triple quotes, loses the line end after a
    NUL, and only then drops the comment (input.cpp: Input::file, Input::parse). So: every character
    that is not printable (line and paragraph breaks of C and of str.splitlines, NUL, tabs, other
    controls, lone surrogates from undecodable file names) becomes a space (white space) or '?';
    '&' becomes '+' and '"' becomes "'", so the text holds no continuation and no triple quote
    wherever it sits on the line. '$' stays: LAMMPS drops a comment before it substitutes variables.
    """
    out = []
    for ch in str(text):
        if ch == "&":
            out.append("+")
        elif ch == '"':
            out.append("'")
        elif ch.isprintable():
            out.append(ch)
        else:
            out.append(" " if ch.isspace() else "?")
    return "".join(out)


def one_line(value):
    """Every {{ expression }} of the templates: text that would break a deck line is an error (free
    text goes through the comment filter; the rest is numbers and the templates' own words)."""
    if isinstance(value, str) and not value.isprintable():
        raise ValueError(f"deck template value {value!r} is not one line of printable text")
    return value


def law_parameters(law) -> dict:
    """The law's parameters, name -> value (the deck's comment on the nominal pair names them)."""
    return {f.name: float(getattr(law, f.name)) for f in dataclasses.fields(law)}


def is_atom_x(expr: str) -> bool:
    """A LAMMPS expression that is an atom's x by ID, x[ID] (fix chain/energy reads those itself)."""
    return re.fullmatch(r"x\[\d+\]", expr) is not None
