"""granchain run's (and collect's) line on the contacts whose peak was not complete when the run ended:
counted and named as contact runs, pointing to peaks.csv; before, only 'peaks without an estimate'
(unreliable error bars) was counted."""

import re
import warnings

import numpy as np

from granchain.cli.terminal import print_result
from granchain.postprocess.domains import contact_runs
from granchain.workflows.run import run_scene

from .conftest import make_scene


def _run(sc, out):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a fixed time step may draw an AccuracyWarning: not the point here
        return run_scene(sc, method="rk4", out=out)


def test_incomplete_peaks_counted_and_named(tmp_path, capsys):
    # the run ends while the leading wave is about two thirds down the chain: the far contacts are not
    # complete (reached or not)
    result = _run(make_scene(beads=24, end_time=1.2e-4, timestep=2e-8), tmp_path / "run")
    peaks = result.peaks
    open_ = peaks.index[~peaks["complete"].to_numpy(bool)].to_numpy()
    assert open_.size  # the setting of this test
    print_result(result, tmp_path / "run")
    lines = [x for x in capsys.readouterr().out.splitlines() if "not complete" in x and "peaks.csv" in x]
    assert len(lines) == 1, lines
    m = re.search(r"(\d+) of (\d+): ([\d, -]+?)\s{3}", lines[0])
    assert m, lines[0]
    assert int(m.group(1)) == open_.size
    assert int(m.group(2)) == len(peaks)
    assert m.group(3) == contact_runs(open_)
    never = peaks.index[~np.isfinite(peaks["time_of_peak"].to_numpy(float))].to_numpy()
    assert ("never reached: " + contact_runs(never) in lines[0]) == bool(never.size)


def test_no_line_without_incomplete_peaks(tmp_path, capsys):
    # run long past the wave's crossing of a short free chain: every contact's force has fallen back
    result = _run(make_scene(beads=12, end_time=4e-4, timestep=5e-8), tmp_path / "run")
    assert result.peaks["complete"].all()  # the setting of this test
    print_result(result, tmp_path / "run")
    assert "peaks not complete" not in capsys.readouterr().out
