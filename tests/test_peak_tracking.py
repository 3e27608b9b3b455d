"""The pair styles' peak bookkeeping (running peak, its time, the smallest force since, the leading pulse)
runs only over the contacts the pair loop wrote a force for at this sample or the previous one
(pair_chain.cpp track_active: every other contact has nothing to update), and over every contact on a
step whose neighbour list was built (local indices may have changed). `pair_style ... peaks all` runs it
over every contact every step. Both must write the same bits, on any scene: every law, loading and
effect, and atoms whose local order LAMMPS changes in the middle of a run (exchanged between ranks)."""

import random
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from granchain.lammps.runner import read_results, run_deck
from granchain.scene import parse_scene
from granchain.templates import render_deck

from .conftest import LAW_NAMES, RANDOM_LOADINGS, make_scene_text, random_scene_text

#: what the deck writes from the peak bookkeeping and the dynamics (not log.lammps: it has timings)
OUTPUTS = ("peaks.dump", "histories.npy", "energy.txt", "run_end.txt", "load_end.txt")


def peaks_all(deck: str) -> str:
    out, n = re.subn(r"^(pair_style\s+chain/.*)$", r"\1 peaks all", deck, count=1, flags=re.M)
    assert n == 1
    return out


def outputs_of(deck: str, data: str, work, np_: int = 1) -> dict[str, bytes]:
    _, work = run_deck(deck, data, np_=np_, work_dir=work)
    got = {f: (work / f).read_bytes() for f in OUTPUTS if (work / f).exists()}
    assert "peaks.dump" in got
    return got


def assert_same_bits(deck: str, data: str, tmp_path, np_: int = 1) -> None:
    a = outputs_of(deck, data, tmp_path / "active", np_)
    b = outputs_of(peaks_all(deck), data, tmp_path / "all", np_)
    assert a.keys() == b.keys()
    for name in a:
        assert a[name] == b[name], name


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    law=st.sampled_from(LAW_NAMES),
    beads=st.integers(8, 300),
    loading=st.sampled_from(sorted(RANDOM_LOADINGS)),
    size=st.floats(0.2, 5.0),
    wall=st.booleans(),
    precompression=st.sampled_from([0.0, 0.0, 20.0]),
    dashpot=st.sampled_from([0.0, 0.0, 3.0]),
)
# (a long chain with a solitary pulse: few contacts carry a force at a time, the lists' case; on a
# short or loaded chain most do and the plugin takes the full pass)
@example(law="hertz", beads=250, loading="impulse", size=1.0, wall=False, precompression=0.0, dashpot=0.0)
@example(law="bilinear", beads=200, loading="velocity", size=2.0, wall=False, precompression=0.0, dashpot=3.0)
def test_active_contacts_give_every_contacts_bits(
    tmp_path_factory, law, beads, loading, size, wall, precompression, dashpot
):
    """Random scenes: the shortcut writes what tracking every contact every step writes, bit for bit.
    The runs are long enough for the wave to reach the far end and come back from a wall."""
    text = random_scene_text(
        law=law,
        beads=beads,
        loading=loading,
        size=size,
        wall=wall,
        precompression=precompression,
        dashpot=dashpot,
        end_time=2.5e-4,
        step_duration=1e-4,
        outputs="peak_force = true\nhistories = [1, 3]",
    )
    d = render_deck(parse_scene(text, source="test.toml"))
    assert_same_bits(d.deck, d.data, tmp_path_factory.mktemp("run"))


def shuffled_atoms(data: str, seed: int) -> str:
    """The data file with its Atoms lines in a random order: LAMMPS numbers local atoms in file order."""
    head, rest = data.split("Atoms # sphere\n\n", 1)
    rows, sep, tail = rest.partition("\n\n")
    lines = rows.strip("\n").split("\n")
    shuffled = random.Random(seed).sample(lines, len(lines))
    assert shuffled != lines
    assert sorted(shuffled) == sorted(lines)
    return head + "Atoms # sphere\n\n" + "\n".join(shuffled) + "\n" + sep + tail


@pytest.mark.parametrize("law", LAW_NAMES)
def test_atoms_exchanged_between_ranks_mid_run(tmp_path, law):
    """Two ranks, atoms unsorted and in random local order, a free chain of 41 beads pushed for 2 ms:
    bead 21 starts on the middle of the shrink-wrapped box, where the ranks' subdomains meet, and as the
    chain compresses it crosses to the other rank; each exchange moves other atoms' local indices while
    contacts carry forces. The pair loop and the bookkeeping must follow the new indices (a pair array
    kept from the first build fails here). (What this cannot pin down: the full pass on a build
    step itself matters only for a contact whose force falls to exactly 0 on that step while an
    exchange moves it, too rare to provoke; removing that guard passes here.)"""
    text = make_scene_text(
        beads=41,
        law=law,
        loading='kind = "step"\namplitude = 500.0\nduration = 1.0',
        end_time=2e-3,
        timestep=5e-8,
        outputs="peak_force = true\nhistories = [1, 20]",
    )
    d = render_deck(parse_scene(text, source="test.toml"))
    deck, n = re.subn(r"^atom_modify\s+sort .*$", "atom_modify     sort 0 0.0", d.deck, flags=re.M)
    assert n == 1
    data = shuffled_atoms(d.data, seed=len(law))
    assert_same_bits(deck, data, tmp_path, np_=2)
    # and the two ranks' numbers are one rank's (pair_chain.cpp's flat pair array follows the list's
    # builds: a stale one would pair the wrong local atoms after an exchange)
    run_deck(deck, data, work_dir=tmp_path / "one")
    one, two = read_results(tmp_path / "one"), read_results(tmp_path / "active")
    for key in ("x", "vx", "fpeak", "tpeak", "fmin"):
        np.testing.assert_allclose(two[key], one[key], rtol=1e-12, atol=1e-15 * np.max(np.abs(one[key])), err_msg=key)
    # the runs did rebuild their neighbour lists (the case the test is about)
    log = (tmp_path / "active" / "log.lammps").read_text()
    builds = [int(b) for b in re.findall(r"^Neighbor list builds = (\d+)", log, re.M)]
    assert max(builds) > 5, builds
