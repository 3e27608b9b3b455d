"""granchain accuracy: options refused before any run, scenes with a striker, a wall or one bead."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.cli import main
from granchain.cli.terminal import resolve_scene
from granchain.exceptions import GranchainError, UsageError
from granchain.workflows.accuracy import METHODS, _dump_interval_errors, accuracy_study, check_study_options

from .conftest import make_scene

SMALL = dict(beads=12, end_time=6e-5, outputs="window = [3, 8]")


@pytest.mark.parametrize(
    ("argv", "word"),
    [
        (["--methods", "foo"], "--methods"),
        (["--methods", "rk4,"], "--methods"),
        (["--repeats", "0"], "--repeats"),
        (["--levels", "0"], "--levels"),
        (["--levels", "-2"], "--levels"),
    ],
)
def test_bad_options_refused_before_any_run(tmp_path, capsys, argv, word):
    out = tmp_path / "acc"
    code = main(["accuracy", "effect-wall", "--out", str(out), *argv])
    err = capsys.readouterr().err
    assert code != 0
    assert word in err
    assert "Traceback" not in err
    if word == "--methods":
        assert all(m in err for m in METHODS)
    assert not out.exists()


def test_help_lists_the_methods(capsys):
    with pytest.raises(SystemExit):
        main(["accuracy", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "lammps, rk4, verlet, dop853" in out


@settings(max_examples=60, deadline=None)
@given(st.text(alphabet=st.sampled_from(list("abcdklmnoprstv0123456789, ")), max_size=30))
def test_methods_strings_are_taken_or_refused_by_name(text):
    names = [m.strip() for m in text.split(",")]
    if all(n in METHODS for n in names):
        assert set(check_study_options(text, 1, 1)) == set(names)
    else:
        with pytest.raises(UsageError, match="--methods") as e:
            check_study_options(text, 1, 1)
        assert isinstance(e.value, GranchainError)


def test_one_bead_is_a_usage_error():
    with pytest.raises(UsageError, match="bead-bead contact"):
        accuracy_study(resolve_scene("classic-two-spheres"), methods=("rk4",), levels=1, repeats=1)


def test_reference_finer_than_every_level_and_plan():
    study = accuracy_study(make_scene(**SMALL), methods=("rk4", "verlet"), levels=1, repeats=1, dump_intervals=False)
    settings_ = [p.setting for p in study.points + study.plan_points]
    assert len(study.plan_points) == 2
    assert study.reference_timestep <= min(settings_) / 4


def test_dop853_ladder_leaks_no_scipy_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        study = accuracy_study(make_scene(**SMALL), methods=("dop853",), levels=6, repeats=1, dump_intervals=False)
    assert study.points
    assert min(p.setting for p in study.points) >= 100 * np.finfo(float).eps


@pytest.mark.parametrize(
    ("loading", "far"),
    [('kind = "striker"\nvelocity = 0.5', ""), ('kind = "impulse"\nimpulse = 0.1\nduration = 1e-6', "wall")],
)
def test_dump_interval_errors_with_a_striker_or_a_wall(loading, far):
    sc = make_scene(loading=loading, **SMALL)
    if far:
        from dataclasses import replace

        sc = replace(sc, effects=replace(sc.effects, far_end=far))
    errs = _dump_interval_errors(sc, 2e-8)
    assert errs
    assert errs[0][2] < 1e-12


def test_cheapest_follows_steps_not_timing_noise():
    # /tmp/explore4/acc-dimer: LAMMPS at 120 steps timed 0.0104 s, at 960 steps 0.0062 s; both met 1e-2
    from granchain.workflows.accuracy import AccuracyStudy, Point

    study = AccuracyStudy(scene=None, contacts=np.array([2]), reference_timestep=1e-9, reference_error=1e-9)
    study.points = [
        Point("lammps", 5.87e-6, 120, 0.0104, 5e-3, None),
        Point("lammps", 7.34e-7, 960, 0.0062, 1e-4, None),
        Point("rk4", 5.87e-6, 120, 0.05, 1e-5, None, 0.04),
    ]
    assert study.cheapest(1e-2).steps == 120
    assert study.cheapest(1e-2).method == "lammps"
    assert study.cheapest(1e-3).steps == 960  # only the finer LAMMPS run meets it, still under RK4
    assert study.cheapest(1e-6) is None
