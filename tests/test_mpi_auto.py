"""--np auto: MPI ranks only where they pay, by the measured crossover chain length."""

from __future__ import annotations

import argparse

import pytest

from granchain.cli import auto_np, np_arg
from granchain.scene import load_scene
from granchain.schedule import MPI_CROSSOVER_BEADS, auto_ranks


def test_one_rank_below_the_crossover():
    assert auto_ranks(MPI_CROSSOVER_BEADS - 1, cores=2) == 1
    assert auto_ranks(100, cores=64) == 1


def test_two_ranks_from_the_crossover_on_at_most_one_per_core():
    assert auto_ranks(MPI_CROSSOVER_BEADS, cores=2) == 2
    assert auto_ranks(10**6, cores=2) == 2
    assert auto_ranks(10**6, cores=1) == 1
    assert auto_ranks(10 * MPI_CROSSOVER_BEADS, cores=64) == 20


def test_auto_ranks_leave_enough_beads_per_rank():
    from granchain.workflows.run import MIN_BEADS_PER_RANK

    for beads in (MPI_CROSSOVER_BEADS, 3 * MPI_CROSSOVER_BEADS // 2, 10**6):
        assert beads // auto_ranks(beads, cores=1024) >= MIN_BEADS_PER_RANK


def test_np_argument():
    assert np_arg("auto") == "auto"
    assert np_arg("2") == 2
    with pytest.raises(argparse.ArgumentTypeError):
        np_arg("two")


def test_auto_np_of_a_bundled_scene_is_one_rank():
    scene = load_scene("default")  # 100 beads: far below the crossover
    assert auto_np(scene, "lammps") == 1
    assert auto_np(scene, "reference") == 1


def test_idle_cores_count_only_cores_without_other_work():
    from granchain.schedule import idle_cores

    assert idle_cores(2, load=0.1) == 2
    assert idle_cores(2, load=1.4) == 1
    assert idle_cores(2, load=6.0) == 1  # never below one
    assert idle_cores(16, load=3.6) == 12
    assert 1 <= idle_cores(2) <= 2  # the OS's own load average


def test_busy_cores_get_one_rank_even_for_a_long_chain():
    from granchain.schedule import idle_cores

    assert auto_ranks(10**6, cores=idle_cores(2, load=1.2)) == 1
    assert auto_ranks(10**6, cores=idle_cores(2, load=0.2)) == 2
