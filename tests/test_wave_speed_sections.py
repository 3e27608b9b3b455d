"""A wave speed fitted over a window whose contacts differ is marked as an average over it, with the
speed of each uniform stretch of the window beside it; a uniform chain's is not; a periodic chain's (a
dimer, a trimer) is its cell-averaged speed, one number at the cell's scale, with no stretches. A
contact's kind does not depend on which of its two beads comes first."""

import io
from contextlib import redirect_stdout

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.physics import materials as mat
from granchain.postprocess.observables import FIT_CONTACTS, contact_kinds, front_arrivals, uniform_sections
from granchain.scene import parse_scene
from granchain.workflows.run import run_reference

from .test_varied_chains import _planned, chain_text, precompression_range, real_contact_positions

SETTINGS = settings(max_examples=15, deadline=None, suppress_health_check=list(HealthCheck))
#: two materials per section draw, told apart by their density (the mass a wave carries)
MATERIAL_NAMES = sorted(mat.MATERIALS)


def _window(n: int) -> tuple[int, int]:
    """The default window of a chain of n beads (Scene.window: its second and third quarters)."""
    c = n - 1
    a = max(1, c // 4)
    return a, min(max(a + 1, (3 * c) // 4), c)


@st.composite
def two_section_chains(draw):
    """A Hertz chain of 20-40 beads whose beads change once, inside the window with FIT_CONTACTS
    contacts of each section in it: two radii of one material or two materials of one radius.
    Returns (scene, the first bead of the second section)."""
    n = draw(st.integers(20, 40), label="beads")
    a, b = _window(n)
    # section 1: contacts a..s-2 of the window, the interface contact s-1, section 2: s..b
    s = draw(st.integers(a + FIT_CONTACTS + 1, b - FIT_CONTACTS + 1), label="first bead of section 2")
    if draw(st.booleans(), label="two radii"):
        r1 = draw(st.floats(1e-3, 6e-3), label="R1")
        r2 = r1 * draw(st.sampled_from([0.5, 0.7, 1.5, 2.0]), label="R2 / R1")
        radii = [r1] * (s - 1) + [r2] * (n - s + 1)
        chain = f'radius = {radii!r}\nmaterial = "stainless-steel-316"\n'
    else:
        m1 = draw(st.sampled_from(MATERIAL_NAMES), label="material 1")
        m2 = draw(
            st.sampled_from([m for m in MATERIAL_NAMES if mat.MATERIALS[m].density != mat.MATERIALS[m1].density]),
            label="material 2",
        )
        chain = f"radius = 4.76e-3\nmaterial = {[m1] * (s - 1) + [m2] * (n - s + 1)!r}\n"
    velocity = draw(st.floats(0.1, 2.0), label="velocity")
    return parse_scene(chain_text(chain, n, velocity), source="two-sections.toml"), s


@st.composite
def uniform_chains(draw):
    """A uniform Hertz chain of 20-40 beads: any built-in material and radius, precompressed or not."""
    n = draw(st.integers(20, 40), label="beads")
    chain = (
        f"radius = {draw(st.floats(1e-3, 6e-3), label='R')!r}\n"
        f"material = {draw(st.sampled_from(MATERIAL_NAMES), label='material')!r}\n"
    )
    velocity = draw(st.floats(0.1, 2.0), label="velocity")
    sc = parse_scene(chain_text(chain, n, velocity), source="uniform.toml")
    if not draw(st.booleans(), label="precompressed"):
        return sc
    f_kick, f_max = precompression_range(sc)
    f0 = min(10.0 ** draw(st.floats(-3.0, 3.0), label="log10 F0 / kick's force") * f_kick, f_max)
    return parse_scene(chain_text(chain, n, velocity, f0), source="uniform.toml")


def _own_fit(result, first: int, last: int) -> float:
    """The speed fitted here over contacts first..last's own arrivals against their real positions."""
    c = np.arange(first, last + 1)
    t = front_arrivals(result.solution, result.scene.effects.precompression)[c - 1]
    ok = np.isfinite(t)
    x = real_contact_positions(result.scene)[c - 1][ok]
    return 1.0 / np.polyfit(x, t[ok], 1)[0]


def _fitted(sc):
    """The planned scene run with Verlet, its wave speed fitted: (result, observables, notes)."""
    result = run_reference(_planned(sc), "verlet")
    obs, notes = result.observables(), result.observables_notes()
    assert obs["wave_speed"] is not None, result.observables_missing().get("wave_speed")
    return result, obs, notes


@SETTINGS
@given(drawn=two_section_chains())
def test_a_two_section_window_is_marked_and_fitted_per_section(drawn):
    sc, s = drawn
    result, obs, notes = _fitted(sc)
    a, b = result.scene.window
    note = notes["wave_speed"]
    assert note.startswith(f"an average over contacts {a}-{b}")
    assert f"beads in 2 stretches of one radius and material: {a}-{s - 1} of " in note
    assert f", {s}-{b + 1} of " in note
    sections = obs["wave_speed_sections"]
    # the interface contact s - 1 is a stretch of one: no speed of its own
    assert [sec["contacts"] for sec in sections] == [[a, s - 2], [s, b]]
    for sec in sections:
        assert sec["speed"] == pytest.approx(_own_fit(result, *sec["contacts"]), rel=1e-6)
        assert sec["stderr"] >= 0.0
    summary = result.summary()
    assert summary["observables_notes"] == notes
    printed = io.StringIO()
    with redirect_stdout(printed):
        from granchain.cli.terminal import print_result

        print_result(result, "out")
    text = printed.getvalue()
    assert "note: an average over contacts" in text
    assert f"wave_speed, contacts {s}-{b} (m/s)" in text


@SETTINGS
@given(sc=uniform_chains())
def test_a_uniform_window_has_no_note_and_no_sections(sc):
    result = run_reference(_planned(sc), "verlet")
    obs = result.observables()
    assert obs["wave_speed"] is not None, result.observables_missing().get("wave_speed")
    assert "wave_speed_sections" not in obs
    assert result.observables_notes() == {}
    assert "observables_notes" not in result.summary()


@st.composite
def periodic_chains(draw):
    """A Hertz chain of 20-40 beads that repeats a cell of 2 or 3 beads, each of a random radius and
    material (the last cell possibly cut short), possibly walled or precompressed. Returns (scene, the
    cell's length in beads: 1 where the drawn cell's beads are all alike, a uniform chain)."""
    p = draw(st.integers(2, 3), label="beads per cell")
    cell = [
        (draw(st.floats(2e-3, 6e-3), label=f"R{i + 1}"), draw(st.sampled_from(MATERIAL_NAMES), label=f"m{i + 1}"))
        for i in range(p)
    ]
    n = draw(st.integers(20, 40), label="beads")
    beads = [cell[i % p] for i in range(n)]
    chain = f"radius = {[r for r, _ in beads]!r}\nmaterial = {[m for _, m in beads]!r}\n"
    velocity = draw(st.floats(0.1, 2.0), label="velocity")
    wall = draw(st.booleans(), label="wall")
    sc = parse_scene(chain_text(chain, n, velocity, wall=wall), source="periodic.toml")
    if draw(st.booleans(), label="precompressed"):
        f_kick, f_max = precompression_range(sc)
        f0 = min(10.0 ** draw(st.floats(-3.0, 3.0), label="log10 F0 / kick's force") * f_kick, f_max)
        sc = parse_scene(chain_text(chain, n, velocity, f0, wall), source="periodic.toml")
    return sc, (1 if all(b == cell[0] for b in cell) else p)  # p is 2 or 3, a prime: the cell is primitive


@SETTINGS
@given(drawn=periodic_chains())
def test_a_periodic_window_has_one_cell_averaged_speed(drawn):
    sc, p = drawn
    result, obs, notes = _fitted(sc)
    a, b = result.scene.window
    if p == 1:  # the cell's beads all alike: a uniform chain
        assert notes == {}
    else:
        note = notes["wave_speed"]
        assert "not one number" not in note
        assert note.startswith(f"the cell-averaged speed of a periodic chain over contacts {a}-{b}")
        assert f"beads {a}-{b + 1} repeat a cell of {p} beads" in note
        assert "one number at the scale of the cell" in note
    # a periodic chain's speed is one number at the scale of its cell: no stretch per contact kind
    assert "wave_speed_sections" not in obs
    assert uniform_sections(result.scene) == [(a, b)]


#: three bead kinds (radius, material) a mirrored chain is drawn from, so that kinds recur
BEAD_POOL = st.tuples(st.sampled_from([2.38e-3, 3.5e-3, 4.76e-3]), st.sampled_from(MATERIAL_NAMES[:3]))


def _scene_of(beads: list, window: tuple[int, int]):
    """A Hertz chain of these (radius, material) beads measured over `window`, run nowhere."""
    chain = f"radius = {[r for r, _ in beads]!r}\nmaterial = {[m for _, m in beads]!r}\n"
    window_line = f"peak_force = true\nwindow = {list(window)!r}"
    text = chain_text(chain, len(beads), 1.0).replace("peak_force = true", window_line)
    return parse_scene(text, source="mirror.toml")


def _partition(kinds: list[int]) -> list[int]:
    """Kinds renumbered by first appearance: two lists of kinds that group the contacts alike compare equal."""
    first: dict[int, int] = {}
    return [first.setdefault(k, len(first)) for k in kinds]


@settings(max_examples=100, deadline=None)
@given(half=st.lists(BEAD_POOL, min_size=3, max_size=15))
def test_a_chain_and_its_mirror_image_have_the_same_kinds_and_sections(half):
    # the chain, then its mirror image: contact i and contact N - i join the same two beads, in the
    # opposite order; they are one law between one pair of masses, one kind
    beads = half + half[::-1]
    n_c = len(beads) - 1
    sc = _scene_of(beads, (1, n_c))
    kinds = contact_kinds(sc)
    assert kinds == kinds[::-1]
    mirrored = [(n_c + 1 - last, n_c + 1 - f) for f, last in uniform_sections(sc)][::-1]
    assert uniform_sections(sc) == mirrored
    # the chain alone and its mirror image, each over its whole length: the mirror's kinds and
    # stretches are the chain's, reversed
    n_h = len(half) - 1
    one, other = _scene_of(half, (1, n_h)), _scene_of(half[::-1], (1, n_h))
    assert _partition(contact_kinds(other)[::-1]) == _partition(contact_kinds(one))
    assert uniform_sections(other) == [(n_h + 1 - last, n_h + 1 - f) for f, last in uniform_sections(one)][::-1]


@settings(max_examples=8, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    big=st.sampled_from([3.5e-3, 4.76e-3, 6e-3]),
    ratio=st.sampled_from([0.4, 0.5, 0.7]),
    first=st.integers(2, 8),
    contacts=st.integers(FIT_CONTACTS, 2 * 3 - 2),  # fewer than 3 cells (6 beads): up to 4 contacts
)
def test_a_dimer_window_shorter_than_three_cells_is_still_marked(big, ratio, first, contacts):
    """A dimer window of fewer than PERIODIC_CELLS cells is no periodic chain to the note, and its
    contacts are all of one kind (large-small and small-large alike): its beads still alternate, so the
    speed fitted over it is an average and is marked so (before: no note at all)."""
    beads = [(big if i % 2 == 0 else big * ratio, "brass") for i in range(20)]
    window = (first, first + contacts - 1)
    sc = _scene_of(beads, window)
    result = run_reference(_planned(sc), "verlet")
    obs, notes = result.observables(), result.observables_notes()
    if obs["wave_speed"] is None:  # nothing fitted: nothing to mark
        return
    assert "not one number" in notes["wave_speed"], notes
    assert "wave_speed_sections" not in obs
