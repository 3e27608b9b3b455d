"""The measurement window's contacts and beads: which are alike, periodic cells, uniform stretches,
and the words the wave speed's note names them in."""

from __future__ import annotations

import numpy as np

from granchain.physics.materials import MATERIALS

#: relative difference under which two contacts' constants or masses count as alike: the same kind
#: of bead computed twice (round-off), not a different bead
_ALIKE = 1e-9

#: the least number of times a cell of beads repeats over the window for the window to count as a
#: periodic chain (periodic_cell): fewer is a pattern, not a chain with a speed at the cell's scale
PERIODIC_CELLS = 3


def _alike(k: np.ndarray, ref: np.ndarray) -> bool:
    """Two keys (contact constants, masses, radii) agree to _ALIKE."""
    return k.shape == ref.shape and bool(np.allclose(k, ref, rtol=_ALIKE, atol=0.0))


def contact_kinds(scene) -> list[int]:
    """Each bead-bead contact's kind (0, 1, ...; in chain order): two contacts are of one kind where
    their laws' constants (ContactLaw.pair_coefficients: stiffness and any yield or plastic constants) and their
    two beads' masses agree to _ALIKE, whichever bead comes first: a large-small contact and a small-large
    one are one law between one pair of masses (the laws' mixing rules are symmetric), so a chain and its
    mirror image have the same kinds. A wave crosses contacts of one kind at one speed; where the kind
    changes, the speed does (stiffer contacts or lighter beads: faster)."""
    if not scene.per_bead:  # one bead kind: every contact alike (precompressed or not)
        return [0] * scene.n_contacts
    m = np.asarray(scene.bead_masses, dtype=float)
    keys = [
        np.array([*law.pair_coefficients(), *sorted((m[i], m[i + 1]))], dtype=float)
        for i, law in enumerate(scene.contact_laws)
    ]
    kinds: list[int] = []
    seen: list[np.ndarray] = []
    for k in keys:
        for j, ref in enumerate(seen):
            if _alike(k, ref):
                kinds.append(j)
                break
        else:
            seen.append(k)
            kinds.append(len(seen) - 1)
    return kinds


def periodic_cell(scene) -> int | None:
    """The number of beads p >= 2 of the cell that the measurement window's beads repeat (a dimer: 2,
    a trimer: 3), or None: bead i + p is bead i's radius and mass and contact i + p has contact i's law
    constants (to _ALIKE) all over the window's beads, which hold at least PERIODIC_CELLS cells; p is
    the shortest such cell. A window of one bead kind (p = 1) is uniform, not periodic (None).

    A periodic chain has one wave speed at the scale of its cell, the cell-averaged speed that dimer
    and trimer chains are measured by (Jayaprakash, Starosvetsky & Vakakis, "New family of solitary
    waves in granular dimer chains with no precompression", Phys. Rev. E 83, 036606, 2011; Porter, Daraio,
    Szelengowicz, Herbold & Kevrekidis, "Highly nonlinear solitary waves in heterogeneous periodic
    granular media", arXiv:0712.3552, dimer and trimer cells and the speed of their long-wavelength
    solitary wave; Potekin, Jayaprakash, McFarland, Remick, Bergman & Vakakis, "Experimental study of
    strongly nonlinear resonances and anti-resonances in granular dimer chains", Exp. Mech. 2013:
    reference not verified), though within a cell the front's hops from contact to contact (their
    lengths, the masses they move) differ."""
    if not scene.per_bead or not scene.n_contacts:
        return None
    a, b = scene.window  # the window's contacts a..b join beads a..b+1
    laws = scene.contact_laws
    contacts = [np.array(laws[c - 1].pair_coefficients(), dtype=float) for c in range(a, b + 1)]
    p = _shortest_cell(_window_bead_keys(scene), contacts)
    return p if p is not None and p >= 2 else None


def _shortest_cell(beads: list[np.ndarray], contacts: list[np.ndarray]) -> int | None:
    """The shortest p >= 1, up to len(beads) // PERIODIC_CELLS, for which each bead's key is alike
    (_alike) the key of the bead p before it and each contact's that of the contact p before it, or
    None (periodic_cell). Each p is one array comparison over all the keys (_rows_alike), not one
    per key: a window of 3000 beads takes milliseconds, not seconds."""
    bead_rows, bead_sizes = _key_rows(beads)
    contact_rows, contact_sizes = _key_rows(contacts)
    for p in range(1, len(beads) // PERIODIC_CELLS + 1):
        if _rows_alike(bead_rows, bead_sizes, p) and _rows_alike(contact_rows, contact_sizes, p):
            return p
    return None


def _key_rows(keys: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """1-D keys as the rows of one array, each padded with zeros to the longest, and each key's length:
    the padding of two keys of one length compares alike, and keys of two lengths never are (_alike)."""
    sizes = np.array([k.size for k in keys], dtype=int)
    rows = np.zeros((len(keys), int(sizes.max(initial=0))), dtype=float)
    for i, k in enumerate(keys):
        rows[i, : k.size] = k
    return rows, sizes


def _rows_alike(rows: np.ndarray, sizes: np.ndarray, p: int) -> bool:
    """Whether every key (a row of _key_rows) is alike (_alike) the key p rows before it: the same
    elementwise test as _alike(rows[i + p], rows[i]) for every i, in one array comparison."""
    return bool(np.all(sizes[p:] == sizes[:-p])) and bool(np.allclose(rows[p:], rows[:-p], rtol=_ALIKE, atol=0.0))


def _window_beads_alike(scene) -> bool:
    """Whether the measurement window's beads (a..b+1) all have one radius and mass (to _ALIKE)."""
    if not scene.per_bead or not scene.n_contacts:
        return True
    beads = _window_bead_keys(scene)
    return all(_alike(x, beads[0]) for x in beads)


def _window_bead_keys(scene) -> list[np.ndarray]:
    """The measurement window's beads a..b+1 as (radius, mass) keys to compare with _alike."""
    a, b = scene.window
    r, m = np.asarray(scene.bead_radii, dtype=float), np.asarray(scene.bead_masses, dtype=float)
    return [np.array([r[i], m[i]]) for i in range(a - 1, b + 1)]


def uniform_sections(scene) -> list[tuple[int, int]]:
    """The measurement window split into runs of consecutive contacts of one kind (contact_kinds):
    (first, last) 1-based contacts each; one run where the window's contacts are all alike, and one
    where the window is a periodic chain (periodic_cell), uniform at the scale of its cell: a single
    contact kind of it is no stretch the wave crosses at a speed of its own."""
    if not scene.n_contacts:
        return []
    a, b = scene.window
    if periodic_cell(scene):
        return [(int(a), int(b))]
    kind = contact_kinds(scene)
    runs = [[a, a]]
    for c in range(a + 1, b + 1):
        if kind[c - 1] == kind[runs[-1][1] - 1]:
            runs[-1][1] = c
        else:
            runs.append([c, c])
    return [(int(f), int(last)) for f, last in runs]


#: at most this many stretches of like beads are named one by one in the wave speed's note
_NAMED_STRETCHES = 6


def _bead_label(radius: float, material, named: bool) -> str:
    """A bead kind as the wave speed's note names it: its radius, and its material where the chain has several."""
    text = f"R = {radius * 1e3:.4g} mm"
    if named:
        name = next((k for k, v in MATERIALS.items() if v == material), None)
        text += f" {name}" if name else f" (rho {material.density:.4g} kg/m^3, E {material.youngs_modulus:.4g} Pa)"
    return text


def _stretches(runs) -> str:
    """1-based (first, last) stretches as a list: "4-9, 10, 11-19"."""
    return ", ".join(f"{f}-{last}" if f != last else f"{f}" for f, last in runs)


def _span(lo: str, hi: str, unit: str) -> str:
    """A range of formatted values ("2.1 to 2.4 mm"), or the one value where they agree ("2.38 mm")."""
    return f"{lo} {unit}" if lo == hi else f"{lo} to {hi} {unit}"


def _window_contacts(scene) -> str:
    """The window's contacts by stretches of one kind (uniform_sections), counted and, up to
    _NAMED_STRETCHES, listed ("contacts in 3 stretches of one kind: 4-9, 10, 11-19")."""
    sections = uniform_sections(scene)
    a, b = scene.window
    if len(sections) > _NAMED_STRETCHES:
        return f"contacts {a}-{b} in {len(sections)} stretches of one kind"
    return f"contacts in {len(sections)} stretches of one kind: {_stretches(sections)}"


def _window_beads(scene) -> str:
    """The window's beads by stretches of one radius and material ("beads in 2 stretches of one radius
    and material: 1-20 of R = 1 mm, 21-40 of R = 2 mm"; one stretch: "beads 1-40 of R = 1 mm"); a chain
    whose beads change every few beads (a taper) counted, with the range of its radii; a periodic window
    (periodic_cell) by its cell ("beads 7-22 repeat a cell of 2 beads (R = 4.76 mm, R = 2.38 mm): 8
    cells"). The count is that of the stretches listed."""
    a, b = scene.window
    r, mats = scene.bead_radii, scene.bead_materials
    named = any(m != mats[0] for m in mats)
    p = periodic_cell(scene)
    if p:
        cell = ", ".join(_bead_label(float(r[i]), mats[i], named) for i in range(a - 1, a - 1 + p))
        whole, rest = divmod(b - a + 2, p)
        more = f" and {rest} bead{'s' if rest > 1 else ''}" if rest else ""
        return f"beads {a}-{b + 1} repeat a cell of {p} beads ({cell}): {whole} cells{more}"
    runs: list[list] = []
    for i in range(a - 1, b + 1):  # the window's contacts a..b join beads a..b+1
        label = _bead_label(float(r[i]), mats[i], named)
        if runs and runs[-1][2] == label:
            runs[-1][1] = i + 1
        else:
            runs.append([i + 1, i + 1, label])
    if len(runs) > _NAMED_STRETCHES:
        w = r[a - 1 : b + 1] * 1e3
        radii = _span(f"{w.min():.4g}", f"{w.max():.4g}", "mm")
        return (
            f"beads {a}-{b + 1} in {len(runs)} stretches of one radius and material ("
            + ("radii " if radii.count(" to ") else "radius ")
            + radii
            + (", several materials" if named else "")
            + ")"
        )
    listed = ", ".join(f"{f}-{last} of {lab}" if f != last else f"{f} of {lab}" for f, last, lab in runs)
    if len(runs) == 1:
        return f"beads {listed}"
    return f"beads in {len(runs)} stretches of one radius and material: {listed}"
