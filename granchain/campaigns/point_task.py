"""One campaign point's task, run in a Dask worker: the point's run directory written into its job
directory, or failure.json with a one-line message, and a small status record returned (and kept in
task.json). A point already complete is not run again."""

from __future__ import annotations

import os
import socket
import time
import traceback
import warnings
from pathlib import Path

from granchain import progress
from granchain.campaigns import workspace as wsp
from granchain.campaigns.model import CampaignError
from granchain.exceptions import GranchainError


def run_point(payload: dict) -> dict:
    """Run one point in a worker: write its run directory into its job directory, or failure.json.

    payload: job_dir, scene (canonical dict), source, backend, method, rtol, error_estimate, code.
    Returns {"job", "status": "done" | "failed", "message", "wall_time", "run_time", "warnings", "host", "pid"}
    (also written to the job directory's task.json).
    """
    t0 = time.perf_counter()
    job = Path(payload["job_dir"])
    before = finished_before(job, payload)
    if before is not None:
        return before
    caught: list[str] = []
    status, message, detail, run_time = "done", None, None, None
    try:
        mine = wsp.code_version(payload["backend"])
        if mine != payload["code"]:
            raise CampaignError(
                f"this worker ({socket.gethostname()}) runs {wsp.code_text(mine)}, the campaign "
                f"{wsp.code_text(payload['code'])}: install the same granchain on every worker"
            )
        from granchain.scene import scene_from_dict
        from granchain.workflows.run import run_scene

        run_dir = job / wsp.RUN_DIR
        if os.path.islink(run_dir):  # planted after the driver set such links aside (set_aside_run_links)
            raise CampaignError(
                f"{run_dir}: this point's run directory is a symbolic link; granchain writes a point's run only "
                "in its own job directory, never through a link: the next 'granchain campaign run "
                f"--retry-failed' moves the link to {job.parent.parent / wsp.DAMAGED} (what it points to is not "
                "touched) and runs the point again"
            )

        with progress.quiet(), warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            scene = scene_from_dict(payload["scene"], source=payload["source"])
            t_run = time.perf_counter()
            run_scene(
                scene,
                backend=payload["backend"],
                method=payload["method"],
                rtol=payload["rtol"],
                error_estimate=payload["error_estimate"],
                out=job / wsp.RUN_DIR,
                overwrite=True,
                np_=payload.get("ranks", 1),
            )
        run_time = time.perf_counter() - t_run
        caught = [str(x.message).splitlines()[0] for x in w]
        (job / wsp.FAILURE).unlink(missing_ok=True)
        write_job_document(job)
    except Exception as e:  # noqa: BLE001 - recorded with its message; the campaign goes on
        status, message = "failed", one_line(e)
        if not isinstance(e, GranchainError):  # a bug: keep where it happened
            detail = traceback.format_exc()
        try:
            wsp.write_json(
                job / wsp.FAILURE,
                {"message": message, "type": type(e).__name__, "traceback": detail, "host": socket.gethostname()},
            )
        except OSError as refused:  # a link at its name, a full or read-only disk: the record says so
            message += f"; and its {wsp.FAILURE} could not be written: {one_line(refused)}"
    wall = time.perf_counter() - t0
    record = {
        "job": job.name,
        "status": status,
        "message": message,
        "wall_time": wall,
        "run_time": run_time,  # run_scene alone (the run and its run directory); the rest is the machinery's
        "warnings": caught,
        "host": socket.gethostname(),
        "pid": os.getpid(),
        "ranks": payload.get("ranks", 1),
        "token": payload.get("token"),
    }
    try:
        wsp.write_json(job / wsp.TASK, record)
    except OSError:  # the record is a courtesy; the run directory is what counts
        pass
    return record


def finished_before(job: Path, payload: dict) -> dict | None:
    """The status of a point that is complete already, without running it again; None: run it.

    A task Dask runs a second time (its worker, or the worker's batch job, ended before the scheduler
    heard the result) finds its own run directory complete, with its own token in task.json: that
    run stands. A point another campaign completed meanwhile stands too, unless this run reruns
    everything (``rerun``)."""
    if wsp.job_state(job) != "done":
        return None
    rec = wsp.read_json(job / wsp.TASK)
    token = payload.get("token")
    mine = isinstance(rec, dict) and token is not None and rec.get("token") == token
    if not mine and payload.get("rerun"):
        return None
    out = {
        "job": job.name,
        "status": "done",
        "message": None,
        "wall_time": 0.0,
        "run_time": None,
        "warnings": [],
        "host": socket.gethostname(),
        "pid": os.getpid(),
        "repeated": True,
    }
    if mine:
        out.update({k: rec[k] for k in ("wall_time", "run_time", "warnings") if k in rec})
    return out


def one_line(e: BaseException) -> str:
    """An exception as one line: a GranchainError's message; anything else with its type."""
    text = " ".join(str(e).split()) or type(e).__name__
    return text if isinstance(e, GranchainError) else f"{type(e).__name__}: {text}"


def write_job_document(job: Path) -> None:
    """The point's results as its signac job document (signac_job_document.json), so that signac's own
    tools (``project.to_dataframe()``, ``find_jobs(doc_filter=...)``) show them beside the state point:
    each measured observable of summary.json, and ``unmeasured`` (which could not be, and why). The
    run directory stays the truth the campaign table is read from; a document that cannot be written
    (a link at its name, a full disk) leaves the point done."""
    summary = wsp.read_json(job / wsp.RUN_DIR / "summary.json")
    if not isinstance(summary, dict):
        return
    obs = summary.get("observables") if isinstance(summary.get("observables"), dict) else {}
    missing = wsp.measurable_missing(summary)
    doc = {k: v for k, v in obs.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
    doc["unmeasured"] = "; ".join(f"{k}: {v}" for k, v in missing.items()) or None
    try:
        wsp.write_json(job / JOB_DOCUMENT, doc)
    except OSError:
        pass


#: signac's job document file in a job directory (signac.job.Job.FN_DOCUMENT)
JOB_DOCUMENT = "signac_job_document.json"
