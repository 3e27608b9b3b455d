"""schedule.step_times against the per-step rule it states: after step k of a segment starting at
`start`, the time is start + k dt (k < its steps), and the segment's last step lands on its end."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

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
