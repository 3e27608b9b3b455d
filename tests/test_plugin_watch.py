"""The plugin's run-watch computes and fix chain/nve (issue 18) against what the decks use today:
the same numbers, serial and on 2 ranks, so the template may switch to them (benchmarks/RESULTS.md)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

from granchain.lammps.runner import LammpsError, read_results, run_deck
from granchain.scene import load_scene
from granchain.templates import render_deck

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from bench_pair import chain_nve, proposed, watch_computes  # noqa: E402


def _run(deck: str, data: str, tmp: Path, np_: int = 1) -> dict[str, np.ndarray]:
    _, work = run_deck(deck, data, np_=np_, work_dir=tmp)
    res = read_results(work)
    res["energy"] = np.loadtxt(work / "energy.txt", comments="#", ndmin=2)
    return res


@pytest.mark.parametrize("name", ["default", "plastic-short-impulse"])
def test_proposed_deck_gives_the_same_numbers(tmp_path, name):
    d = render_deck(load_scene(name))
    a = _run(d.deck, d.data, tmp_path / "a")
    b = _run(proposed(d.deck), d.data, tmp_path / "b")
    for key in a:
        assert np.array_equal(a[key], b[key]), key  # the same expressions: the same doubles


def test_proposed_deck_on_two_ranks(tmp_path):
    d = render_deck(load_scene("default"))
    a = _run(d.deck, d.data, tmp_path / "a")
    b = _run(proposed(d.deck), d.data, tmp_path / "b", np_=2)
    for key in ("x", "vx", "fpeak", "tpeak"):
        np.testing.assert_allclose(b[key], a[key], rtol=1e-12, atol=1e-15 * np.max(np.abs(a[key])))


def _halt(deck: str, data: str, tmp: Path, np_: int = 1) -> str:
    with pytest.raises(LammpsError) as e:
        run_deck(deck, data, np_=np_, work_dir=tmp)
    m = re.search(r"halt condition for fix-id (\w+) met on step (\d+) with value (\S+)", str(e.value))
    assert m, str(e.value)
    return m.groups()


@pytest.mark.parametrize("np_", [1, 2])
def test_watch_computes_stop_on_the_same_step_and_atom(tmp_path, np_):
    """A force bound the default scene's pulse crosses: both watches halt on the same step and name the
    same atom (compute chain/fmax is compute reduce max ... replace)."""
    d = render_deck(load_scene("default"))
    low = re.sub(r"\(c_watch_max\[1\] > \S+\)", "(c_watch_max[1] > 2000.0)", d.deck)
    assert low != d.deck
    old = _halt(low, d.data, tmp_path / "a", np_)
    new = _halt(watch_computes(low), d.data, tmp_path / "b", np_)
    assert old == new


def test_chain_nve_refuses_motion_off_the_axis(tmp_path):
    d = render_deck(load_scene("default"))
    deck = chain_nve(d.deck).replace(
        "read_data       chain.data", "read_data       chain.data\nvelocity        all set NULL 1.0 NULL"
    )
    with pytest.raises(LammpsError, match="chain/nve integrates along x only"):
        run_deck(deck, d.data, work_dir=tmp_path)
