"""periodic_cell tests each cell length p with one array comparison over all the window's keys
(_shortest_cell), not np.allclose per pair of beads: before, a 3000-bead interface chain took 3.05 s a call
and a run calls it about 35 times. The answer is unchanged: here the old pairwise loop, copied as the oracle,
and the new function agree on key sequences drawn around every edge of the test (cells of 1-4 keys with
noise below, at and above _ALIKE, zeros, nan and inf, contact keys of several lengths) and on generated
and hand-written scenes."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.postprocess.observables import (
    _ALIKE,
    PERIODIC_CELLS,
    _shortest_cell,
    _window_bead_keys,
    periodic_cell,
)
from granchain.scene import parse_scene

from .scenegen import scene_texts


def old_alike(k: np.ndarray, ref: np.ndarray) -> bool:
    """observables._alike as it was."""
    return k.shape == ref.shape and bool(np.allclose(k, ref, rtol=_ALIKE, atol=0.0))


def old_shortest_cell(beads: list[np.ndarray], contacts: list[np.ndarray]) -> int | None:
    """The loop of periodic_cell before it was vectorised: np.allclose per pair of keys."""
    n = len(beads)
    for p in range(1, n // PERIODIC_CELLS + 1):
        if all(old_alike(beads[i + p], beads[i]) for i in range(n - p)) and all(
            old_alike(contacts[j + p], contacts[j]) for j in range(len(contacts) - p)
        ):
            return p
    return None


def old_periodic_cell(scene) -> int | None:
    """periodic_cell before it was vectorised, whole."""
    if not scene.per_bead or not scene.n_contacts:
        return None
    a, b = scene.window
    laws = scene.contact_laws
    contacts = [np.array(laws[c - 1].pair_coefficients(), dtype=float) for c in range(a, b + 1)]
    p = old_shortest_cell(_window_bead_keys(scene), contacts)
    return p if p is not None and p >= 2 else None


#: relative changes around the _ALIKE threshold (and far from it) that a repeated key may get
NUDGES = [0.0, 0.0, 0.0, 0.5 * _ALIKE, 0.999 * _ALIKE, _ALIKE, 1.001 * _ALIKE, 2 * _ALIKE, 1e-6]

#: values a key may hold: ordinary, zero, tiny, huge, negative, and not finite
VALUES = st.one_of(
    st.floats(1e-4, 1e4),
    st.sampled_from([0.0, -0.0, 1e-300, 5e-324, 1e300, -2.5, np.nan, np.inf, -np.inf]),
)


@st.composite
def key_sequences(draw, width: st.SearchStrategy[int], n: int) -> list[np.ndarray]:
    """A cell of 1-4 keys repeated over n keys, some entries nudged by a relative amount near
    _ALIKE (either sign), some keys replaced by another, of another length or not."""
    cell = draw(st.integers(1, 4))
    base = []
    for _ in range(cell):
        w = draw(width)
        base.append(np.array(draw(st.lists(VALUES, min_size=w, max_size=w)), dtype=float))
    keys = [base[i % cell].copy() for i in range(n)]
    for _ in range(draw(st.integers(0, 4))):
        i = draw(st.integers(0, n - 1))
        if keys[i].size and draw(st.booleans()):
            j = draw(st.integers(0, keys[i].size - 1))
            keys[i][j] *= 1.0 + draw(st.sampled_from([-1.0, 1.0])) * draw(st.sampled_from(NUDGES))
        else:
            w = draw(width)
            keys[i] = np.array(draw(st.lists(VALUES, min_size=w, max_size=w)), dtype=float)
    return keys


@settings(max_examples=600, deadline=None)
@given(data=st.data())
def test_same_cell_as_the_pairwise_loop(data):
    n = data.draw(st.integers(2, 40), label="beads in the window")
    beads = data.draw(key_sequences(st.just(2), n), label="beads")  # (radius, mass), as periodic_cell's
    # the n - 1 contacts' law constants, of any length
    contacts = data.draw(key_sequences(st.integers(0, 3), n - 1), label="contacts")
    assert _shortest_cell(beads, contacts) == old_shortest_cell(beads, contacts)


@settings(max_examples=300, deadline=None)
@given(data=st.data())
def test_same_cell_on_clean_cells(data):
    """Exactly periodic keys (no noise) over every length: the new loop finds the same (shortest) cell."""
    cell = data.draw(st.integers(1, 4))
    base = [np.array(data.draw(st.lists(st.floats(1e-3, 1e3), min_size=2, max_size=2))) for _ in range(cell)]
    n = data.draw(st.integers(2, 30))
    beads = [base[i % cell] for i in range(n)]
    contacts = [np.array([beads[i][0] + beads[i + 1][0]]) for i in range(n - 1)]
    assert _shortest_cell(beads, contacts) == old_shortest_cell(beads, contacts)


def chain(radius: str, beads: int, window: str = "") -> str:
    return (
        f'[chain]\nbeads = {beads}\nradius = {radius}\nmaterial = "stainless-steel-316"\n[contact]\nlaw = "hertz"\n'
        '[loading]\nkind = "velocity"\nvelocity = 0.5\n[run]\nend_time = "auto"\ntimestep = "auto"\n'
        f"[outputs]\npeak_force = true\n{window}"
    )


def radii(pattern: list[float], beads: int) -> str:
    return "[" + ", ".join(repr(pattern[i % len(pattern)]) for i in range(beads)) + "]"


def test_same_cell_on_scenes():
    texts = [
        chain(radii([4.76e-3, 2.38e-3], 16), 16),  # a dimer
        chain(radii([4.76e-3, 2.38e-3], 16), 16, "window = [5, 8]\n"),  # a dimer window of 2 cells
        chain(radii([4e-3, 3e-3, 2e-3], 30), 30),  # a trimer
        chain(radii([3e-3, 3e-3, 2e-3], 30), 30),  # a cell of two like beads and one other
        chain(radii([2e-3] * 20 + [3e-3] * 20, 40), 40),  # an interface
        chain(radii([2e-3] * 19 + [3e-3] + [2e-3] * 20, 40), 40),  # an impurity
        chain(radii([2e-3, 2e-3 * (1 + 0.5 * _ALIKE)], 30), 30),  # two radii that are alike
        chain(radii([2e-3, 2e-3 * (1 + 5 * _ALIKE)], 30), 30),  # two radii that are not
    ]
    got = [periodic_cell(parse_scene(t, source="t.toml")) for t in texts]
    assert got == [old_periodic_cell(parse_scene(t, source="t.toml")) for t in texts]
    assert (got[0], got[2], got[4]) == (2, 3, None)  # a dimer, a trimer, an interface: as they say


@settings(max_examples=100, deadline=None)
@given(text=scene_texts(max_beads=60))
def test_same_cell_on_generated_scenes(text):
    scene = parse_scene(text, source="generated.toml")
    assert periodic_cell(scene) == old_periodic_cell(scene)
