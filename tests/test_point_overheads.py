"""The work around a campaign point made cheap (issue 44 item 2), with the same results:
schedule.step_times against the per-step rule it states (after step k of a segment starting at
`start`, the time is start + k dt, k < its steps; its last step lands on its end), and the LAMMPS
runs' sweep of stale work directories done at a process's first run, then once a minute."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.lammps import runner
from granchain.schedule import step_plan, step_times


def times_by_rule(plan, dt: float) -> list[float]:
    """The oracle: one Python float per step, start + k dt, then the segment's end."""
    out = [0.0]
    for g in plan:
        out += [g.start + float(k) * dt for k in range(1, g.steps)]
        out.append(g.end)
    return out


@settings(max_examples=60, deadline=None)
@given(
    dt=st.floats(1e-9, 1e-5),
    n=st.floats(1.0, 3000.0),
    load=st.floats(0.0, 1.0),
    snaps=st.lists(st.floats(0.0, 1.0), max_size=3),
)
def test_step_times_are_the_rule_bit_for_bit(dt, n, load, snaps):
    end = dt * n
    plan = step_plan(end, dt, load * end, [s * end for s in snaps])
    got = step_times(plan, dt)
    want = np.asarray(times_by_rule(plan, dt))
    assert got.shape == want.shape == (1 + sum(g.steps for g in plan),)
    assert np.array_equal(got.view(np.int64), want.view(np.int64))
    assert all(math.isfinite(t) for t in got)


def test_stale_work_directories_are_swept_at_the_first_run_then_once_a_minute(tmp_path, monkeypatch):
    clock, sweeps = [1000.0], []
    monkeypatch.setattr(runner.time, "monotonic", lambda: clock[0])
    monkeypatch.setattr(runner, "sweep_stale_work_dirs", lambda: sweeps.append(runner.tempfile.gettempdir()))
    monkeypatch.setattr(runner, "_swept", {})
    monkeypatch.setattr(runner.tempfile, "tempdir", str(tmp_path / "a"))
    runner.sweep_if_due()
    assert sweeps == [str(tmp_path / "a")]  # a process's first run sweeps
    clock[0] += runner.SWEEP_EVERY / 2
    runner.sweep_if_due()
    assert len(sweeps) == 1  # not again within the minute
    monkeypatch.setattr(runner.tempfile, "tempdir", str(tmp_path / "b"))
    runner.sweep_if_due()
    assert sweeps[-1] == str(tmp_path / "b")  # another temporary directory is its own first
    clock[0] += runner.SWEEP_EVERY
    monkeypatch.setattr(runner.tempfile, "tempdir", str(tmp_path / "a"))
    runner.sweep_if_due()
    assert sweeps == [str(tmp_path / "a"), str(tmp_path / "b"), str(tmp_path / "a")]
