"""The one exception class every error a user can cause derives from.

The command line turns a GranchainError into one line, ``granchain: error: <message>``, and exit
status 2; anything else is a bug and shows its traceback. A message names the field or argument,
the value, and the fix.
"""

from __future__ import annotations


class GranchainError(Exception):
    """An error the user can cause and fix: a bad scene, argument, run directory or request."""


class UsageError(GranchainError, ValueError):
    """A bad argument to a command or to the Python API (backend, method, --np, --rtol)."""
