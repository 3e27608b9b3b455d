"""The backends: every solver granchain runs a scene on, behind one interface (backends.protocol).

``BACKENDS`` is the one list: ``--backend``'s choices, a campaign's ``backend`` and a run
directory's ``backend`` are its keys. A new backend is a :class:`Backend` subclass (a
:class:`FileIOBackend` for a program run through files) and its line here.
"""

from __future__ import annotations

from granchain.backends.builtin import LammpsBackend, ReferenceBackend
from granchain.backends.protocol import PROPERTIES, Backend, Calculation, FileIOBackend, WorkFiles
from granchain.exceptions import UsageError

#: the reference solver, in this process: the yardstick of every error estimate
REFERENCE = ReferenceBackend()
#: LAMMPS with granchain's pair styles, through files in a work directory
LAMMPS = LammpsBackend()

#: every backend by name, the reference first (the default)
BACKENDS: dict[str, Backend] = {b.name: b for b in (REFERENCE, LAMMPS)}

#: every integrator some backend runs, in the order the backends name them
METHODS: tuple[str, ...] = tuple(dict.fromkeys(m for b in BACKENDS.values() for m in b.methods))


def backend_named(backend: str | Backend) -> Backend:
    """The backend of this name (a Backend is returned as it is).

    Raises
    ------
    UsageError
        No backend has this name.
    """
    if isinstance(backend, Backend):
        return backend
    try:
        return BACKENDS[backend]
    except (KeyError, TypeError):
        raise UsageError(f"backend = {backend!r} is not known; choose one of {', '.join(BACKENDS)}") from None


__all__ = [
    "BACKENDS",
    "LAMMPS",
    "METHODS",
    "PROPERTIES",
    "REFERENCE",
    "Backend",
    "Calculation",
    "FileIOBackend",
    "WorkFiles",
    "backend_named",
]
