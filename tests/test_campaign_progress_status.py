"""The campaign progress line counts each finished point under the word the table's status column
gives the same point: a point lost in flight is "missing" in both, not "failed" in one."""

from __future__ import annotations

import io

import pytest

from granchain.campaigns import model
from granchain.campaigns import workspace as wsp
from granchain.campaigns.campaign_progress import CampaignProgress
from granchain.campaigns.dask_executor import Executor
from granchain.campaigns.execute import Runner
from granchain.campaigns.point_task import run_point
from granchain.campaigns.spec import parse_campaign

from .test_campaigns import campaign_text

THREE = """
[vary]
"loading.amplitude" = [1.0, 2.0, 3.0]
"""


class _Finished:
    """A finished Dask future as Runner.collect sees one: its key and its result (or what it raises)."""

    def __init__(self, key: str, outcome):
        self.key, self._outcome = key, outcome

    def result(self):
        if isinstance(self._outcome, BaseException):
            raise self._outcome
        return self._outcome


def test_progress_words_are_the_table_status_of_the_same_points(tmp_path, monkeypatch):
    """One point done (run_point in this process), one failed (run_point refuses a payload of another
    granchain: failure.json), one lost (its future raised, as a KilledWorker does): the progress line
    says done 1, failed 1, missing 1, which is what workspace.job_state (the table's status) says of
    each job directory."""
    from granchain import progress

    monkeypatch.setattr(progress, "DELAY", 0.0)
    monkeypatch.setattr(progress, "is_quiet", lambda: False)
    c = parse_campaign(
        campaign_text(THREE, campaign='backend = "reference"\nmethod = "verlet"\nerror_estimate = false')
    )
    runner = Runner(c, tmp_path / "ws", Executor(workers=1), stream=io.StringIO())
    stream = io.StringIO()
    prog = CampaignProgress(3, stream=stream)
    points = c.points()
    jobs = [runner.job(p) for p in points]
    done_payload = runner.payload(jobs[0], points[0])
    failed_payload = {**runner.payload(jobs[1], points[1]), "code": {"granchain": "0.0.0-another"}}
    outcomes = [run_point(done_payload), run_point(failed_payload), RuntimeError("worker lost three times")]
    for i, (job, outcome) in enumerate(zip(jobs, outcomes, strict=True)):
        runner.in_flight[f"k{i}"] = job.path
        runner.collect(_Finished(f"k{i}", outcome), points[i].params, prog)
    prog.close()
    line = stream.getvalue().strip().splitlines()[-1]
    table_words = [wsp.job_state(job.path) for job in jobs]
    assert table_words == [model.DONE, model.FAILED, model.MISSING]
    for word in set(table_words):
        assert f"{word} {table_words.count(word)}" in line, line
    assert (runner.report.done, runner.report.failed, runner.report.lost) == (1, 1, 1)


@pytest.mark.parametrize("outcome", ["done", "failed", "lost"])
def test_every_outcome_has_a_table_word(outcome):
    """Every task outcome the driver collects is counted under one of the table's status words."""
    prog = CampaignProgress(1, stream=io.StringIO())
    prog.update(outcome)
    (word,) = [w for w, n in prog.finished.items() if n]
    assert word in (model.DONE, model.FAILED, model.MISSING, model.STALE)
