"""History output through fix chain/history (histories.npy, issue 18 item 2) against the text dump it
replaces, on the same LAMMPS run: the same steps, the same doubles, serially and on 2 ranks, across a
deck's several runs, and after a run stopped by the run watch."""

from __future__ import annotations

import re

import numpy as np
import pytest

from granchain.lammps.runner import LammpsError, run_deck, step_times_of
from granchain.postprocess.dumps import read_dump
from granchain.postprocess.histories import HistoryFileError, read_histories, read_history_table
from granchain.scene import load_scene
from granchain.templates import DeckOptions, render_deck

from .conftest import make_scene

NPY = DeckOptions(history_file="npy")
FIX = re.compile(r"^fix\s+history history chain/history (\d+) histories.npy$", re.M)


def both(deck: str) -> str:
    """The npy deck writing the text dump as well, on the same steps of the same run."""
    m = FIX.search(deck)
    assert m, "the deck has no fix chain/history"
    dump = (
        f"dump            history history custom {m.group(1)} histories.dump id x y z vx vy vz d_fc v_vel v_ux\n"
        "dump_modify     history format float %.17g sort id\n"
    )
    return deck[: m.end() + 1] + dump + deck[m.end() + 1 :]


def _same(work, times=None):
    t, f, v = read_histories(work, times)
    dd = read_dump(work / "histories.dump", times)
    steps, ids, _, _ = read_history_table(work / "histories.npy")
    assert np.array_equal(steps, dd.step)
    assert np.array_equal(ids, dd.ids)
    assert np.array_equal(t, dd.time)
    assert np.array_equal(f, dd.columns["d_fc"])
    assert np.array_equal(v, dd.columns["v_vel"])
    assert f.shape == (len(dd.step), len(dd.ids))
    assert np.any(f > 0)
    return steps


@pytest.mark.parametrize("name", ["default", "effect-wall", "plastic-short-impulse", "effect-striker"])
def test_npy_equals_the_text_dump(tmp_path, name):
    """Bundled scenes (auto strides; several runs: load end, snapshots, a last shorter step)."""
    sc = load_scene(name)
    d = render_deck(sc, options=NPY)
    _, work = run_deck(both(d.deck), d.data, work_dir=tmp_path)
    steps = _same(work, step_times_of(sc))
    assert steps[0] == 0
    assert len(steps) > 10
    assert not list(work.glob("*.part"))


def test_every_step_on_two_ranks(tmp_path):
    sc = make_scene(beads=24, end_time=5e-5, timestep=2e-8, outputs="histories = [1, 12, 23]")
    d = render_deck(sc, options=NPY)
    assert FIX.search(d.deck).group(1) == "1"
    _, work = run_deck(both(d.deck), d.data, np_=2, work_dir=tmp_path)
    steps = _same(work)
    assert np.array_equal(steps, np.arange(len(steps)))


def test_a_halted_run_leaves_a_whole_file(tmp_path):
    """The run watch stops the deck in its second run (a low force bound): histories.npy is a whole file
    holding the text dump's first samples: those of the finished first run, or all up to the halt when
    the LAMMPS instance was closed after the error (the fix writes them when deleted); no .part is left.
    A run that did not finish writes no results dump, which is what marks a finished one."""
    sc = load_scene("default")
    d = render_deck(sc, options=NPY)
    low = re.sub(r"\(c_watch_max\[1\] > \S+\)", "(c_watch_max[1] > 2000.0)", both(d.deck))
    with pytest.raises(LammpsError, match="halt condition"):
        run_deck(low, d.data, work_dir=tmp_path)
    steps, ids, f, v = read_history_table(tmp_path / "histories.npy")
    dd = read_dump(tmp_path / "histories.dump")
    k = len(steps)
    assert 0 < k <= len(dd.step)
    assert np.array_equal(steps, dd.step[:k])
    assert np.array_equal(ids, dd.ids)
    assert np.array_equal(f, dd.columns["d_fc"][:k])
    assert np.array_equal(v, dd.columns["v_vel"][:k])
    assert not list(tmp_path.glob("*.part"))
    assert not (tmp_path / "peaks.dump").exists()


def test_the_text_dump_is_read_without_a_table(tmp_path):
    sc = make_scene(beads=10, end_time=2e-6, timestep=2e-8, outputs="histories = [1, 5]")
    d = render_deck(sc, options=DeckOptions(history_file="dump"))
    assert "chain/history" not in d.deck
    assert "histories.dump" in d.deck
    _, work = run_deck(d.deck, d.data, work_dir=tmp_path)
    t, f, v = read_histories(work)
    assert f.shape == v.shape == (101, 2)
    assert np.array_equal(t, np.arange(101.0))


def test_a_foreign_table_is_refused(tmp_path):
    np.save(tmp_path / "histories.npy", np.zeros((3, 4)))
    with pytest.raises(HistoryFileError):
        read_histories(tmp_path)
