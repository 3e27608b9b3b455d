"""A harmonic drive whose amplitude exceeds the static force F0 pulls bead 1 at its troughs: the run says
so before it starts (guards.DriveBeyondLinearWarning), and a drive inside the linear domain says nothing."""

from __future__ import annotations

import warnings

import pytest

from granchain.scene import parse_scene
from granchain.workflows.guards import DriveBeyondLinearWarning, check_run


def driven(amplitude: float, f0: float | None) -> str:
    pre = f"[precompression]\nforce = {f0}\n" if f0 is not None else ""
    return (
        '[chain]\nbeads = 6\nradius = 4.76e-3\nmaterial = "brass"\n[contact]\nlaw = "hertz"\n'
        f'[loading]\nkind = "harmonic"\namplitude = {amplitude}\nfrequency = 5000.0\ncycles = 4\n{pre}'
        "[run]\nend_time = 1e-3\ntimestep = 1e-7\n"
    )


@pytest.mark.parametrize(("amplitude", "f0"), [(20.0, 10.0), (0.5, None), (10.5, 10.0)])
def test_a_drive_above_f0_is_said_before_the_run(amplitude, f0):
    with pytest.warns(DriveBeyondLinearWarning, match=r"pulls \(F0 - A < 0\)") as caught:
        check_run(parse_scene(driven(amplitude, f0), source="driven.toml"), machine=False)
    assert f"amplitude = {amplitude:g} N" in str(caught[0].message)
    assert f"F0 = {f0 or 0.0:g} N" in str(caught[0].message)


@pytest.mark.parametrize("amplitude", [0.01, 10.0])
def test_a_drive_at_or_below_f0_says_nothing(amplitude):
    with warnings.catch_warnings():
        warnings.simplefilter("error", DriveBeyondLinearWarning)
        check_run(parse_scene(driven(amplitude, 10.0), source="driven.toml"), machine=False)
