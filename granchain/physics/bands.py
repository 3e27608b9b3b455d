"""The linear band structure of a precompressed periodic chain: Bloch dispersion, pass bands, gaps and
the evanescent decay per cell in a gap.

Domain of every result here: a motion small against the static force F0 (the dynamic force a few
per cent of F0 or less), about which each contact is a linear spring of stiffness k_j = dF/dalpha
of its law's virgin curve at F0 (``ContactLaw.loading_stiffness``: Hertz F = K alpha^(3/2) gives
k = (3/2) K^(2/3) F0^(1/3), a power law F = K alpha^n gives n K^(1/n) F0^((n-1)/n)); no dissipation;
an infinite chain (a finite one's modes fall inside the bands; its ends add their own). A force
comparable to F0 changes the stiffness over a cycle (Nesterenko's weakly nonlinear waves) and a
contact that opens leaves the linear chain altogether.

The chain: a cell of p beads (masses m_0 .. m_(p-1)) and p springs, spring j joining bead j and bead
j+1 (spring p-1 joins bead p-1 to the next cell's bead 0), repeated. A Bloch wave u_j^(n) =
U_j exp(i (q n - w t)) (q: the wavenumber per cell, rad) solves K(q) U = w^2 M U, K(q) the cell's
stiffness matrix with the spring across the cell's edge carrying the phase exp(+-i q) (Brillouin,
*Wave Propagation in Periodic Structures*, 1946, ch. IV); p bands, each between its frequencies at q
= 0 and q = pi (in one dimension with nearest-neighbour springs each band is monotone in q: Kohn,
Phys. Rev. 115, 809, 1959). In a gap q is complex: the transfer matrix T of one cell, (u, F) of bead 0
to (u, F) of the next cell's bead 0 (F the tension of the spring on the bead's left), has det T = 1
and eigenvalues exp(+-i q) with cos q = tr T / 2; where |tr T / 2| > 1 the wave decays by
mu = arccosh(|tr T| / 2) nepers per cell (Im q), Re q = 0 or pi (Mead, J. Sound Vib. 27, 235, 1973).

Closed forms (angular frequencies): a monoatomic chain (spring k, mass m) has w(q) = 2 sqrt(k/m)
|sin(q/2)|, cutoff f_c = (1/pi) sqrt(k/m) Hz; a dimer (masses m1, m2, both springs k) has its
acoustic band up to sqrt(2k/m_heavy), its optical band from sqrt(2k/m_light) to sqrt(2k (1/m1 + 1/m2))
(Herbold, Kim, Nesterenko, Wang & Daraio, Acta Mech. 205, 85, 2009; Boechler et al., PRL 104,
244302, 2010).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from granchain.exceptions import GranchainError

__all__ = [
    "DOMAIN",
    "BandError",
    "BandStructure",
    "Cell",
    "band_edges",
    "band_structure",
    "bloch_wavenumber",
    "decay_per_cell",
    "dimer_edges",
    "dispersion",
    "linearised_cell",
    "monoatomic_cutoff",
    "periodic_cell",
    "transfer_matrix",
]

#: what every result of this module holds for, in words
DOMAIN = (
    "the chain linearised about its static force F0: a motion small against F0 (a dynamic force a few "
    "per cent of F0 or less), no dissipation, an infinite periodic chain"
)
#: beads and springs equal to this relative tolerance count as one (a cell's period)
PERIOD_RTOL = 1e-12
#: a gap narrower than this fraction of its upper edge is closed (equal masses in a cell of two)
CLOSED_GAP_RTOL = 1e-9


class BandError(GranchainError, ValueError):
    """A chain whose band structure is not defined (no precompression, not periodic, gravity) or a bad
    cell: the message names the field and the fix."""


@dataclass(frozen=True)
class Cell:
    """A periodic cell of a linearised chain.

    Attributes
    ----------
    masses : numpy.ndarray
        m_0 .. m_(p-1), kg.
    springs : numpy.ndarray
        k_0 .. k_(p-1), N/m: spring j joins bead j and bead j+1 (the last, bead p-1 and the next
        cell's bead 0).
    static_force : float
        F0, N, the force the springs are linearised about (NaN where the cell was given as springs).
    """

    masses: np.ndarray
    springs: np.ndarray
    static_force: float = math.nan


def _cell(masses, springs) -> tuple[np.ndarray, np.ndarray]:
    m = np.atleast_1d(np.asarray(masses, dtype=float))
    k = np.atleast_1d(np.asarray(springs, dtype=float))
    if m.ndim != 1 or m.shape != k.shape or m.size == 0:
        raise BandError(
            f"masses, springs: a cell needs as many springs as beads (spring j joins bead j and j+1), got "
            f"{m.size} and {k.size}; pass one spring per bead"
        )
    if not (np.all(np.isfinite(m)) and np.all(m > 0) and np.all(np.isfinite(k)) and np.all(k > 0)):
        raise BandError("masses, springs: every mass and stiffness must be finite and > 0; pass the cell's values")
    return m, k


def _stiffness(k: np.ndarray, q: float) -> np.ndarray:
    """K(q) of the cell: spring j between beads j and j+1, the last across the edge with phase exp(i q)."""
    p = k.size
    out = np.zeros((p, p), dtype=complex)
    for j in range(p):
        a, b = j, (j + 1) % p
        phase = np.exp(1j * q) if j == p - 1 else 1.0
        out[a, a] += k[j]
        out[b, b] += k[j]
        out[a, b] -= k[j] * phase
        out[b, a] -= k[j] * np.conj(phase)
    return out


def dispersion(masses, springs, q) -> np.ndarray:
    """The Bloch dispersion w(q), rad/s: every band's angular frequency at each wavenumber per cell.

    Parameters
    ----------
    masses, springs : array_like
        The cell (Cell says which spring joins which beads).
    q : array_like
        Wavenumbers per cell, rad.

    Returns
    -------
    numpy.ndarray
        Shape (len(q), p): the p bands' frequencies at each q, ascending (the eigenvalues of
        M^(-1/2) K(q) M^(-1/2), K(q) Hermitian).
    """
    m, k = _cell(masses, springs)
    scale = 1.0 / np.sqrt(m)
    rows = []
    for qi in np.atleast_1d(np.asarray(q, dtype=float)):
        dyn = scale[:, None] * _stiffness(k, float(qi)) * scale[None, :]
        rows.append(np.sqrt(np.maximum(np.linalg.eigvalsh(dyn), 0.0)))
    return np.array(rows)


def band_edges(masses, springs) -> np.ndarray:
    """Each band's lowest and highest angular frequency, rad/s: shape (p, 2), from q = 0 and q = pi
    (each band is monotone in between: the module docstring)."""
    ends = dispersion(masses, springs, [0.0, math.pi])
    return np.sort(ends.T, axis=1)


def transfer_matrix(masses, springs, omega: float) -> np.ndarray:
    """The 2x2 transfer matrix of one cell at angular frequency omega: (u, F) of bead 0 to (u, F) of the
    next cell's bead 0, F the tension of the spring on a bead's left.

    A bead: F_(j+1) = F_j - m_j omega^2 u_j (its equation of motion); a spring: u_(j+1) = u_j + F_(j+1) / k_j.
    """
    m, k = _cell(masses, springs)
    out = np.eye(2)
    w2 = float(omega) ** 2
    for mj, kj in zip(m, k, strict=True):
        out = np.array([[1.0, 1.0 / kj], [0.0, 1.0]]) @ np.array([[1.0, 0.0], [-mj * w2, 1.0]]) @ out
    return out


def bloch_wavenumber(masses, springs, omega) -> np.ndarray:
    """The complex Bloch wavenumber per cell q(omega) of the decaying (or right-going) wave, rad.

    cos q = tr T / 2 (transfer_matrix): in a pass band q is real in [0, pi]; in a gap q = i mu
    (tr T / 2 > 1) or pi + i mu (tr T / 2 < -1), mu = arccosh(|tr T| / 2) > 0 the decay per cell.
    """
    out = []
    for w in np.atleast_1d(np.asarray(omega, dtype=float)):
        half = 0.5 * float(np.trace(transfer_matrix(masses, springs, w)))
        if abs(half) <= 1.0:
            out.append(complex(math.acos(half), 0.0))
        else:
            mu = math.acosh(abs(half))
            out.append(complex(0.0 if half > 0 else math.pi, mu))
    return np.array(out)


def decay_per_cell(masses, springs, omega) -> np.ndarray:
    """Im q(omega): the evanescent decay per cell in nepers (the amplitude falls by exp(-mu) a cell), 0
    in a pass band; 20 mu / ln 10 is the same in dB per cell."""
    return bloch_wavenumber(masses, springs, omega).imag


def monoatomic_cutoff(k: float, m: float) -> float:
    """f_c = (1/pi) sqrt(k/m), Hz: the top of a monoatomic chain's only band (w = 2 sqrt(k/m) at q = pi);
    above it every wave is evanescent."""
    return math.sqrt(k / m) / math.pi


def dimer_edges(k: float, m1: float, m2: float) -> tuple[float, float, float]:
    """A dimer's band edges, rad/s (both springs k): (acoustic top sqrt(2k/m_heavy), optical bottom
    sqrt(2k/m_light), optical top sqrt(2k (1/m1 + 1/m2))); the gap lies between the first two."""
    heavy, light = max(m1, m2), min(m1, m2)
    return math.sqrt(2 * k / heavy), math.sqrt(2 * k / light), math.sqrt(2 * k * (1 / m1 + 1 / m2))


# ------------------------------------------------------------------------- a scene's chain


@dataclass(frozen=True)
class BandStructure:
    """A periodic chain's pass bands and gaps, in Hz, with the domain they hold in.

    Attributes
    ----------
    cell : Cell
        The cell (masses, linearised springs, F0).
    bands : tuple of (float, float)
        Each pass band's (lowest, highest) frequency, Hz, ascending; the first starts at 0.
    gaps : tuple of (float, float)
        Each gap's (lowest, highest) frequency, Hz, between the bands, the last (top band's top, inf).
    domain : str
        What the numbers hold for (DOMAIN, and the law's caveat where it has one).
    """

    cell: Cell
    bands: tuple[tuple[float, float], ...]
    gaps: tuple[tuple[float, float], ...]
    domain: str

    @property
    def cutoff(self) -> float:
        """The top of the highest pass band, Hz: above it every wave is evanescent."""
        return self.bands[-1][1]

    def decay_per_cell(self, frequency) -> np.ndarray:
        """Im q at `frequency` (Hz): the decay per cell in nepers, 0 in a pass band."""
        omega = 2 * math.pi * np.asarray(frequency, dtype=float)
        return decay_per_cell(self.cell.masses, self.cell.springs, omega)


def bands_and_gaps(masses, springs) -> tuple[tuple, tuple]:
    """(bands, gaps) in Hz of a cell (BandStructure's fields); gaps narrower than CLOSED_GAP_RTOL of
    their upper edge are closed (the two bands touch)."""
    edges = band_edges(masses, springs) / (2 * math.pi)
    bands = tuple((float(lo), float(hi)) for lo, hi in edges)
    gaps = [
        (bands[b][1], bands[b + 1][0])
        for b in range(len(bands) - 1)
        if bands[b + 1][0] - bands[b][1] > CLOSED_GAP_RTOL * bands[b + 1][0]
    ]
    return bands, (*gaps, (bands[-1][1], math.inf))


def periodic_cell(masses, springs) -> int:
    """The smallest period p (in beads) of a finite chain of masses m_0 .. m_(N-1) and contacts k_0 ..
    k_(N-2) (contact i between beads i and i+1) that holds at least two whole cells, or 0 if none does."""
    m = np.asarray(masses, dtype=float)
    k = np.asarray(springs, dtype=float)
    for p in range(1, m.size // 2 + 1):
        same_m = np.allclose(m[p:], m[:-p], rtol=PERIOD_RTOL, atol=0)
        same_k = k.size <= p or np.allclose(k[p:], k[:-p], rtol=PERIOD_RTOL, atol=0)
        if same_m and same_k and k.size >= p:
            return p
    return 0


def linearised_cell(scene) -> Cell:
    """The periodic cell of a scene's precompressed chain, each contact's spring the slope of its law's
    virgin curve at F0 (``loading_stiffness``).

    Raises
    ------
    BandError
        No precompression, gravity (each contact then carries its own static force), or a chain with
        no period holding two whole cells.
    """
    f0 = float(scene.effects.precompression)
    if not f0 > 0:
        raise BandError(
            "[precompression] force: the scene has none, and an uncompressed chain has no linear band "
            "structure (its contacts have no stiffness at zero force); give [precompression] force = F0"
        )
    if scene.effects.gravity:
        raise BandError(
            "[gravity] g: each contact carries its own static force (the weight above it), so the chain "
            "linearised about it is not periodic; drop [gravity] for a band structure"
        )
    if not scene.per_bead:  # a uniform chain of any length, "auto" included: a cell of one bead
        return Cell(np.array([scene.mass]), np.atleast_1d(np.asarray(scene.law.loading_stiffness(f0), float)), f0)
    masses = np.asarray(scene.bead_masses, dtype=float)
    springs = np.array([float(law.loading_stiffness(f0)) for law in scene.contact_laws])
    p = periodic_cell(masses, springs)
    if not p:
        raise BandError(
            f"[chain]: its {masses.size} beads repeat no cell at least twice (radii, materials and contact "
            "values), so it has no band structure; give a periodic chain (a dimer, a trimer ...)"
        )
    return Cell(masses[:p], springs[:p], f0)


def band_structure(scene) -> BandStructure:
    """The pass bands and gaps (Hz) of a scene's precompressed periodic chain, with their domain.

    Parameters
    ----------
    scene : granchain.scene.Scene
        A chain with [precompression] whose beads repeat a cell (a uniform chain: a cell of one bead).

    Returns
    -------
    BandStructure
        The cell, its bands and gaps and the domain they hold in.

    Raises
    ------
    BandError
        As linearised_cell.
    """
    cell = linearised_cell(scene)
    bands, gaps = bands_and_gaps(cell.masses, cell.springs)
    domain = DOMAIN
    if scene.contact.law_class.history:
        domain += (
            f"; a {scene.contact.law} contact's springs are its virgin curve's slope at F0: one that has "
            "unloaded oscillates on its stiffer unloading branch, and the bands move up"
        )
    return BandStructure(cell, bands, gaps, domain)
