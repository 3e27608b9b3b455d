"""The data file's positions: bodies meant to touch with zero force do not overlap in LAMMPS's arithmetic
(beads: exactly zero overlap, granchain.physics.positions.contact_quantum; a wall: touching_positions), so LAMMPS
leaves an at-rest chain ahead of the wave front exactly at rest, as the reference solver does."""

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.lammps.runner import run_lammps
from granchain.physics.positions import touching_positions
from granchain.scene import parse_scene
from granchain.templates import AtomLayout, render_deck
from granchain.workflows.run import run_reference

from .conftest import make_scene, make_scene_text


def data_atoms(data: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Type, diameter and x of every atom by ID, parsed from the data file's text as LAMMPS reads it."""
    rows = data.split("Atoms # sphere\n\n", 1)[1].split("\n\n", 1)[0].split("\n")  # (a Watch section may follow)
    cols = [r.split() for r in rows if r.strip()]
    assert [int(c[0]) for c in cols] == list(range(1, len(cols) + 1))
    return (
        np.array([int(c[1]) for c in cols]),
        np.array([float(c[2]) for c in cols]),
        np.array([float(c[4]) for c in cols]),
    )


def contact_distances(deck: str) -> dict[tuple[int, int], float]:
    """d0 of every type pair, parsed from the deck's pair_coeff lines (pair_coeff I J k d0 ...)."""
    out = {}
    for i, j, _k, d0 in re.findall(r"^pair_coeff\s+(\d+)\s+(\d+)\s+(\S+)\s+(\S+)", deck, re.M):
        out[int(i), int(j)] = out[int(j), int(i)] = float(d0)
    return out


def overlapping_pairs(scene) -> list[tuple[int, str]]:
    """Neighbouring atoms (by ID: striker, beads, wall) that overlap at t = 0 in LAMMPS's arithmetic, in
    our pair styles' test (fl(dx^2) < fl(d0^2), d0 from pair_coeff) or pair_style granular's (radsum =
    0.5 d_i + 0.5 d_j from the data file's diameters), or by any amount d0 - |dx| > 0 (Python floats are
    IEEE doubles: the same operations as LAMMPS's); and beads whose overlap d0 - |dx| is not exactly 0
    (a gap: the reference has none)."""
    deck, lay = render_deck(scene), AtomLayout.of(scene)
    types, diam, x = data_atoms(deck.data)
    d0 = contact_distances(deck.deck)
    bad = []
    for k in range(len(x) - 1):
        dx = x[k + 1] - x[k]
        tests = [("pair_coeff", d0[types[k], types[k + 1]])]
        beads = lay.first_id <= k + 1 < lay.last_id
        if beads:  # two beads (the yardstick takes no striker or wall)
            tests.append(("radsum", 0.5 * diam[k] + 0.5 * diam[k + 1]))
        bad += [(k + 1, name) for name, dist in tests if dx * dx < dist * dist or dist - abs(dx) > 0.0]
        if beads and not scene.effects.precompression and d0[types[k], types[k + 1]] - abs(dx) != 0.0:
            bad.append((k + 1, "gap"))
    return bad


def test_touching_positions_gap_at_most_an_ulp():
    d = np.full(99999, 2 * 4.76e-3)
    x = touching_positions(d, start=0.5)
    dx = np.diff(x)
    assert x[0] == 0.5
    assert np.all(dx >= d)
    assert np.all(dx * dx >= d * d)
    # the smallest such doubles: one ulp lower would overlap
    lower = np.nextafter(x[1:], -np.inf) - x[:-1]
    assert np.all(lower < d)


def test_a_long_chain_touches_exactly():
    sc = make_scene(beads=100000)
    x, d0 = sc.bead_positions, 2 * sc.contact_radius(sc.chain.radius)
    assert np.all(np.diff(x) == d0)
    assert 0.0 <= d0 - sc.diameter < 2 * sc.contact_quantum
    # (i-1) D, rounded, overlapped by round-off at 42% of these pairs
    old = np.diff(np.arange(100000) * sc.diameter)
    assert np.mean(old * old < sc.diameter**2) > 0.3


@settings(max_examples=60, deadline=None)
@given(
    beads=st.integers(2, 400),
    radius=st.floats(1e-4, 5e-2),
    far_end=st.sampled_from(["free", "wall"]),
)
def test_uniform_chain_no_round_off_overlap(beads, radius, far_end):
    text = make_scene_text(beads=beads, end_time=1e-5, timestep=1e-8)
    text = text.replace("radius = 4.76e-3", f"radius = {radius!r}")
    if far_end == "wall":
        text += '\n[boundary]\nfar_end = "wall"\n'
    assert overlapping_pairs(parse_scene(text, source="test.toml")) == []


@settings(max_examples=60, deadline=None)
@given(radii=st.lists(st.floats(1e-3, 1e-2), min_size=2, max_size=200))
def test_per_bead_chain_no_round_off_overlap(radii):
    text = make_scene_text(beads=len(radii), end_time=1e-5, timestep=1e-8)
    text = text.replace("radius = 4.76e-3", f"radius = [{', '.join(repr(r) for r in radii)}]")
    assert overlapping_pairs(parse_scene(text, source="test.toml")) == []


def test_striker_touches_bead_one_without_overlap():
    sc = make_scene(beads=50, loading='kind = "striker"\nvelocity = 2.0\nradius = 3.3e-3')
    assert overlapping_pairs(sc) == []


def test_precompressed_chain_keeps_its_real_overlaps():
    text = make_scene_text(beads=30, end_time=1e-5, timestep=1e-8) + "\n[precompression]\nforce = 10.0\n"
    sc = parse_scene(text, source="test.toml")
    _, _, x = data_atoms(render_deck(sc).data)
    d = sc.diameter
    assert np.all(np.diff(x) < d)  # every contact loaded
    assert overlapping_pairs(sc) == [(k, name) for k in range(1, 30) for name in ("pair_coeff", "radsum")]


@pytest.mark.parametrize("far_end", ["free", "wall"])
def test_lammps_leaves_the_chain_ahead_of_the_front_exactly_at_rest(far_end):
    """A 400-bead chain hit at 20 m/s, 40 Verlet steps: the disturbance moves at most one bead a step, so
    beads past 50 are exactly at rest in the reference; LAMMPS has them exactly at rest too (on (i-1) D
    rounded, round-off overlaps gave their contacts forces and the beads velocities of 1e-19 m/s)."""
    text = make_scene_text(beads=400, loading='kind = "velocity"\nvelocity = 20.0', end_time=4e-7, timestep=1e-8)
    if far_end == "wall":
        text += '\n[boundary]\nfar_end = "wall"\n'
    sc = parse_scene(text, source="test.toml")
    lam, _ = run_lammps(sc)
    ref = run_reference(sc, "verlet")
    a, b = lam.solution, ref.solution
    tail = slice(50, None)
    assert np.all(b.velocity[tail] == 0.0)
    assert np.all(b.displacement[tail] == 0.0)
    assert np.all(a.velocity[tail] == 0.0), np.count_nonzero(a.velocity[tail])
    assert np.all(a.displacement[tail] == 0.0)
    assert np.all(a.peak_force[tail] == 0.0), np.count_nonzero(a.peak_force[tail])
    # and the front itself as the reference has it
    assert np.max(np.abs(a.velocity - b.velocity)) / np.max(np.abs(b.velocity)) < 1e-9
