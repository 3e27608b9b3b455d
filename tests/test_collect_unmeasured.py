"""granchain collect says what the plain-LAMMPS run ended before measuring, as granchain run does
("granchain: not measured: ..." on stderr, postprocess.observables.unmeasured_outputs), with what to do
(granchain run would run a planned scene longer), and exits as run does: 1 where the end time was the
planner's. Before, collect printed the numbers only ("largest force so far, not a peak") and exited 0."""

import warnings

from granchain.cli import main
from granchain.postprocess.observables import unmeasured_outputs
from granchain.workflows.collect import collect

from .conftest import make_scene_text
from .scenegen import stainless_on_wall_text
from .test_collect import lmp, render

#: a 20-bead chain whose fixed end time stops the wave before the window's end
SHORT = make_scene_text(beads=20, end_time=3e-5, timestep=2e-8)

#: a planned scene (end "auto") whose wall's peak plain LAMMPS, run once, may not see
PLANNED_WALL = stainless_on_wall_text("velocity", 0.5, 10, contact='law = "thornton"\nyield_pressure = 3e8\n')


def collected(tmp_path, text, capsys):
    d = render(tmp_path, text)
    assert lmp(d).returncode == 0
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # NotRefinedWarning: not the point here
        rc = main(["collect", str(d), "--out", str(tmp_path / "run")])
        err = capsys.readouterr().err
        expected = unmeasured_outputs(*(lambda r: (r.scene, r.solution))(collect(d, out=tmp_path / "again")))
    lines = [x.removeprefix("granchain: not measured: ") for x in err.splitlines() if "not measured: " in x]
    return rc, err, lines, expected


def test_collect_says_not_measured(tmp_path, capsys):
    rc, err, lines, expected = collected(tmp_path, SHORT, capsys)
    assert expected  # the setting of this test: the run ended before the window's end
    assert lines == expected
    assert "a longer [run] end_time" in err
    assert rc == 0  # a fixed end time the user chose: told, as granchain run tells it


def test_collect_exits_as_run_on_a_planned_end(tmp_path, capsys):
    rc, err, lines, expected = collected(tmp_path, PLANNED_WALL, capsys)
    assert lines == expected
    assert rc == (1 if expected else 0)
    assert ("granchain run would have run this planned scene again, longer" in err) == bool(expected)
