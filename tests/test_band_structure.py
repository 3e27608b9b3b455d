"""granchain.physics.bands against oracles built here: a long ring's eigenfrequencies (scipy.linalg.eigh
of its mass and stiffness matrices), the closed forms, and the decay along a finite driven chain
(tests/linear_chain.py); the springs from Hertz's law written out (Johnson, Contact Mechanics, sec. 4.2:
F = K alpha^(3/2), K = 4/3 E* sqrt(R*); linearised, k = dF/dalpha = (3/2) K^(2/3) F0^(1/3)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.linalg import eigh

from granchain.physics import bands
from granchain.physics.bands import BandError
from granchain.physics.predictions import predict
from granchain.scene import load_scene, parse_scene
from tests.linear_chain import matrices, steady_state
from tests.scenegen import AUTO_RUN

#: cells in the ring: odd, so q = 2 pi s / L holds q = 0 but not pi (the bound below covers pi's edge)
RING_CELLS = 41
CELLS_IN_SCENE = 3


def hertz_spring(ra, rb, ea, nua, eb, nub, f0):
    e_star = 1.0 / ((1 - nua**2) / ea + (1 - nub**2) / eb)
    r_star = ra * rb / (ra + rb)
    big_k = 4.0 / 3.0 * e_star * math.sqrt(r_star)
    return 1.5 * big_k ** (2.0 / 3.0) * f0 ** (1.0 / 3.0)


@st.composite
def cells(draw, min_beads=2, max_beads=4):
    """(masses, springs, the scene of CELLS_IN_SCENE cells of it): beads of distinct random densities,
    radii and moduli (one cell's beads), F0 in 1 .. 100 N."""
    p = draw(st.integers(min_beads, max_beads))
    dens = draw(st.lists(st.floats(1000.0, 20000.0), min_size=p, max_size=p, unique=True))
    radii = draw(st.lists(st.floats(2e-3, 10e-3), min_size=p, max_size=p))
    youngs = draw(st.lists(st.floats(5e9, 2.5e11), min_size=p, max_size=p))
    nu = draw(st.lists(st.floats(0.2, 0.45), min_size=p, max_size=p))
    f0 = draw(st.floats(1.0, 100.0))
    masses = np.array([d * 4 / 3 * math.pi * r**3 for d, r in zip(dens, radii, strict=True)])
    assume(all(abs(a / b - 1) > 1e-6 for i, a in enumerate(masses) for b in masses[i + 1 :]))
    springs = np.array(
        [
            hertz_spring(radii[j], radii[(j + 1) % p], youngs[j], nu[j], youngs[(j + 1) % p], nu[(j + 1) % p], f0)
            for j in range(p)
        ]
    )
    tables = [
        f"{{density = {d!r}, youngs_modulus = {e!r}, poisson_ratio = {v!r}}}"
        for d, e, v in zip(dens, youngs, nu, strict=True)
    ]
    text = (
        f"[chain]\nbeads = {p * CELLS_IN_SCENE}\nradius = {radii * CELLS_IN_SCENE!r}\n"
        f'material = [{", ".join(tables * CELLS_IN_SCENE)}]\n[contact]\nlaw = "hertz"\n'
        f'[loading]\nkind = "velocity"\nvelocity = 0.01\n[precompression]\nforce = {f0!r}\n{AUTO_RUN}'
    )
    return masses, springs, parse_scene(text, source="generated.toml")


def ring_eigenvalues(masses, springs, cells_in_ring):
    """omega^2 of a ring of `cells_in_ring` cells, ascending (scipy.linalg.eigh of K u = w^2 M u)."""
    m = np.tile(masses, cells_in_ring)
    k = np.tile(springs, cells_in_ring)
    mass, stiffness, _ = matrices(m, k, ring=True)
    return eigh(stiffness, mass, eigvals_only=True)


@settings(max_examples=25, deadline=None)
@given(cells())
def test_band_edges_are_a_long_rings_extreme_eigenfrequencies(cell):
    masses, springs, scene = cell
    p = masses.size
    got = bands.band_structure(scene)
    # the scene's cell is the one built here: its masses and Hertz springs linearised at F0
    np.testing.assert_allclose(got.cell.masses, masses, rtol=1e-12)
    np.testing.assert_allclose(got.cell.springs, springs, rtol=1e-10)
    lam = ring_eigenvalues(masses, springs, RING_CELLS)
    top = float(lam[-1])
    # the ring holds q = 0 but not pi: its nearest q is pi (1 - 1/L), and dD/dq (D = M^-1/2 K(q) M^-1/2)
    # has norm k_(p-1) / sqrt(m_(p-1) m_0) (only the edge's spring carries q), so an eigenvalue at pi
    # is within that times pi / L of the ring's; the rest is round-off
    slope = springs[-1] / math.sqrt(masses[-1] * masses[0])
    tol = slope * math.pi / RING_CELLS + 1e-10 * top
    for b, (lo, hi) in enumerate(got.bands):
        block = lam[b * RING_CELLS : (b + 1) * RING_CELLS]
        assert abs(block[0] - (2 * math.pi * lo) ** 2) <= tol
        assert abs(block[-1] - (2 * math.pi * hi) ** 2) <= tol
        # every ring mode lies in its band (within round-off)
        assert block[0] >= (2 * math.pi * lo) ** 2 - 1e-10 * top
        assert block[-1] <= (2 * math.pi * hi) ** 2 + 1e-10 * top
    assert len(got.bands) == p
    assert got.gaps[-1] == (got.bands[-1][1], math.inf)
    assert "small against F0" in got.domain


@settings(max_examples=40, deadline=None)
@given(st.floats(1e4, 1e8), st.floats(1e-5, 1e-2), st.floats(1e-5, 1e-2))
def test_the_closed_forms_are_the_general_solvers(k, m1, m2):
    ((lo, hi),) = bands.band_edges([m1], [k])
    assert lo == pytest.approx(0.0, abs=1e-6 * hi)
    assert hi / (2 * math.pi) == pytest.approx(bands.monoatomic_cutoff(k, m1), rel=1e-12)
    # w(q) = 2 sqrt(k/m) |sin(q/2)| on the monoatomic chain
    q = np.linspace(0, math.pi, 7)
    np.testing.assert_allclose(bands.dispersion([m1], [k], q)[:, 0], 2 * math.sqrt(k / m1) * np.sin(q / 2), rtol=1e-10)
    assume(abs(m1 / m2 - 1) > 1e-3)
    edges = bands.band_edges([m1, m2], [k, k])
    acoustic_top, optical_bottom, optical_top = bands.dimer_edges(k, m1, m2)
    assert edges[0, 1] == pytest.approx(acoustic_top, rel=1e-10)
    assert edges[1, 0] == pytest.approx(optical_bottom, rel=1e-10)
    assert edges[1, 1] == pytest.approx(optical_top, rel=1e-10)


def driven_decay(masses, springs, omega, mu):
    """The decay per cell of |U| on one bead per cell of a long chain driven at bead 0 (linear_chain's
    exact steady state): a straight-line fit of ln|U| over cells 1 .. c, stopping where |U| is 1e-11
    of the first and well before the far end (whose reflection grows as exp(-2 mu (L - c)))."""
    p = masses.size
    n_cells = max(40, math.ceil(40 / mu))
    m = np.tile(masses, n_cells)
    k = np.tile(springs, n_cells)[:-1]
    force = np.zeros(m.size, dtype=complex)
    force[0] = 1.0
    u = steady_state(m, k, omega, force)
    last = min(n_cells // 2, max(3, int(25 / mu)))
    cells_used = np.arange(1, last + 1)
    slope = np.polyfit(cells_used, np.log(np.abs(u[cells_used * p])), 1)[0]
    return -slope


@settings(max_examples=15, deadline=None)
@given(cells(min_beads=1), st.floats(0.2, 0.8), st.floats(1.05, 2.0))
def test_decay_per_cell_in_a_gap_matches_a_finite_driven_chain(cell, where, above):
    masses, springs, _ = cell
    bands_hz, gaps = bands.bands_and_gaps(masses, springs)
    frequencies = [above * gaps[-1][0]]  # above the top band
    if len(gaps) > 1:  # inside the first gap
        lo, hi = gaps[0]
        frequencies.append(lo + where * (hi - lo))
    for f in frequencies:
        omega = 2 * math.pi * f
        mu = float(bands.decay_per_cell(masses, springs, omega)[0])
        assert mu > 0
        if mu < 0.2:
            continue  # a gap's edge: the finite chain would need over 200 cells
        assert driven_decay(masses, springs, omega, mu) == pytest.approx(mu, rel=0.02)
    # in a pass band nothing decays
    middle = 0.5 * (bands_hz[0][0] + bands_hz[0][1])
    assert bands.decay_per_cell(masses, springs, 2 * math.pi * middle)[0] == 0.0


def test_the_dimer_scene_predicts_its_band_edges():
    scene = load_scene("classic-precompressed-dimer")
    rows = {p.name: p for p in predict(scene)}
    m = scene.bead_masses[:2]
    f0 = float(scene.effects.precompression)
    mats = scene.bead_materials[:2]
    r = scene.bead_radii[:2]
    k = hertz_spring(r[0], r[1], mats[0].youngs_modulus, mats[0].poisson_ratio, mats[1].youngs_modulus,
                     mats[1].poisson_ratio, f0)  # fmt: skip
    acoustic_top, optical_bottom, optical_top = (w / (2 * math.pi) for w in bands.dimer_edges(k, *m))
    assert rows["band_gap_lower"].value == pytest.approx(acoustic_top, rel=1e-10)
    assert rows["band_gap_upper"].value == pytest.approx(optical_bottom, rel=1e-10)
    assert rows["band_cutoff"].value == pytest.approx(optical_top, rel=1e-10)
    assert rows["band_cutoff"].unit == "Hz"
    # the bundled scene's pulse is not small against F0: outside the linear domain, said with the numbers
    assert not rows["band_cutoff"].applies
    assert "F0" in rows["band_cutoff"].applies_reason


def test_chains_without_a_band_structure_are_refused_naming_the_field():
    dimer = load_scene("classic-precompressed-dimer")
    with pytest.raises(BandError, match=r"\[precompression\] force"):
        bands.band_structure(load_scene("classic-dimer-wall"))
    odd = dimer.replace("chain.material", ["ptfe", "ptfe", *dimer.chain.materials[2:]])
    with pytest.raises(BandError, match=r"\[chain\]"):
        bands.band_structure(odd)
    assert not [p for p in predict(odd) if p.name.startswith("band_")]
    with pytest.raises(BandError, match="masses, springs"):
        bands.band_edges([1.0, 2.0], [1.0])
