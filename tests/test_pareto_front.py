"""The Pareto front of a two-objective search (issue 45) on generated trials, not only fronts known by
construction: no design on it is dominated, every design off it is dominated by one on it, each design
once; and the error bars' verdict: with no bars every design off the front is ruled out, larger bars
never rule out more, and a design is ruled out exactly where a front design's worst corner beats its
best corner in both objectives (the two boxes value +- bar do not overlap in the sense of dominance)."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.campaigns.optimize import front_text, near_front, pareto_front

values = st.integers(-6, 6).map(float)  # small integers: ties and repeated values are common
bars = st.sampled_from([0.0, 0.25, 0.5, 1.0, 2.5])


@st.composite
def trials(draw, with_bars: bool = True):
    n = draw(st.integers(1, 12))
    rows = []
    for k in range(n):
        state = draw(st.sampled_from(["complete"] * 4 + ["failed", "infeasible"]))
        job = draw(st.sampled_from([None, f"{draw(st.integers(0, 9)):032x}"]))  # repeats: the same design again
        job = job or f"{k + 100:032x}"
        rows.append(
            {
                "trial": k,
                "state": state,
                "job": job,
                "objective": draw(values),
                "objective_2": draw(values),
                "objective_error": draw(bars) if with_bars else 0.0,
                "objective_2_error": draw(bars) if with_bars else 0.0,
            }
        )
    # one design has one result: a repeated job repeats its first trial's values
    first = {}
    for r in rows:
        if r["job"] in first:
            r.update(
                {
                    c: first[r["job"]][c]
                    for c in ("state", "objective", "objective_2", "objective_error", "objective_2_error")
                }
            )
        else:
            first[r["job"]] = r
    return rows


directions = st.tuples(st.sampled_from(["minimize", "maximize"]), st.sampled_from(["minimize", "maximize"]))


def _signed(r, d):
    s = [1.0 if x == "minimize" else -1.0 for x in d]
    return s[0] * r["objective"], s[1] * r["objective_2"]


def _dominates(q, r, d) -> bool:
    (a, b), (x, y) = _signed(q, d), _signed(r, d)
    return a <= x and b <= y and (a < x or b < y)


@settings(max_examples=200, deadline=None)
@given(rows=trials(), d=directions)
def test_the_front_is_the_undominated_designs_each_once(rows, d):
    done = [r for r in rows if r["state"] == "complete"]
    front = pareto_front(rows, d)
    jobs = [r["job"] for r in front]
    assert len(jobs) == len(set(jobs))
    for r in front:
        assert r["state"] == "complete"
        assert not any(_dominates(q, r, d) for q in done)
    for r in done:
        if r["job"] not in jobs:
            assert any(_dominates(q, r, d) for q in front)
    assert [_signed(r, d)[0] for r in front] == sorted(_signed(r, d)[0] for r in front)


@settings(max_examples=200, deadline=None)
@given(rows=trials(with_bars=False), d=directions)
def test_without_error_bars_every_design_off_the_front_is_ruled_out(rows, d):
    assert near_front(rows, d) == ([], [])


@settings(max_examples=200, deadline=None)
@given(rows=trials(), d=directions, k=st.floats(1.0, 4.0))
def test_a_design_is_ruled_out_exactly_where_a_front_designs_box_beats_its_box(rows, d, k):
    front = pareto_front(rows, d)
    undistinguished, unjudged = near_front(rows, d)
    assert unjudged == []  # every bar is given here
    off = {r["job"]: r for r in rows if r["state"] == "complete" and r["job"] not in {q["job"] for q in front}}

    def beaten(q, r):  # q's worst corner at least as good as r's best corner in both objectives
        (a, b), (x, y) = _signed(q, d), _signed(r, d)
        return (
            a + q["objective_error"] <= x - r["objective_error"]
            and b + q["objective_2_error"] <= y - r["objective_2_error"]
        )

    expected = sorted(j for j, r in off.items() if not any(beaten(q, r) for q in front))
    assert sorted(r["job"] for r in undistinguished) == expected
    wider = [
        {**r, "objective_error": k * r["objective_error"], "objective_2_error": k * r["objective_2_error"]}
        for r in rows
    ]
    assert {r["job"] for r in near_front(wider, d)[0]} >= set(expected)  # larger bars never rule out more


def test_a_design_without_a_bar_cannot_be_judged_and_is_said_so():
    rows = [
        {
            "trial": 0,
            "state": "complete",
            "job": "a",
            "objective": 1.0,
            "objective_2": 1.0,
            "objective_error": 0.1,
            "objective_2_error": 0.1,
        },
        {
            "trial": 1,
            "state": "complete",
            "job": "b",
            "objective": 2.0,
            "objective_2": 2.0,
            "objective_error": None,
            "objective_2_error": 0.1,
        },
        {
            "trial": 2,
            "state": "complete",
            "job": "c",
            "objective": 1.1,
            "objective_2": 1.1,
            "objective_error": 0.1,
            "objective_2_error": 0.1,
        },
    ]
    d = ("minimize", "minimize")
    near = near_front(rows, d)
    assert [r["job"] for r in near[0]] == ["c"]
    assert [r["job"] for r in near[1]] == ["b"]
    text = front_text(pareto_front(rows, d), ("f", "g"), (), near)
    assert "not distinguished from the front within their error bars: trial 2" in text
    assert "cannot be judged against the front (no error bar): trial 1" in text
