"""A campaign from a file or a dict, run into a workspace, and its table (the API behind
``granchain.campaign`` / ``granchain.load_campaign`` and ``granchain campaign ...``)."""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
import sys
import time
from pathlib import Path

from granchain.campaigns import workspace as wsp
from granchain.campaigns.cluster_settings import SUBMIT, ClusterError, ClusterSettings, describe, merge
from granchain.campaigns.cluster_settings import check as check_cluster
from granchain.campaigns.execute import Executor, Runner, preflight, run_grid
from granchain.campaigns.model import CampaignInterrupted
from granchain.campaigns.optimize import confirm_best, run_optimize
from granchain.campaigns.search import run_search
from granchain.campaigns.spec import (
    Campaign,
    CampaignError,
    campaign_from_dict,
    check_ranks,
    load_campaign_file,
    params_text,
)
from granchain.campaigns.table import (
    build_best_table,
    build_search_table,
    build_table,
    build_trials_table,
    write_tables,
)
from granchain.results import CAMPAIGN_PACKAGES, RUN_PACKAGES, package_versions

#: a workspace's folder for the batch jobs' output (stdout and stderr of each worker job)
JOB_LOGS = "jobs"


def as_campaign(spec) -> Campaign:
    """A Campaign from a Campaign, a campaign file's path, or a dict of its tables."""
    if isinstance(spec, Campaign):
        return spec
    if isinstance(spec, dict):
        return campaign_from_dict(spec, source="<campaign dict>")
    if isinstance(spec, (str, Path)):
        return load_campaign_file(spec)
    raise CampaignError(f"campaign = {spec!r}: give a campaign file's path or a dict of its tables")


def validate(campaign: Campaign) -> list:
    """Every point made, validated as a scene, planned and its time step checked, before anything runs.
    A search's outer points are checked with the searched key at both ends of its range (and its
    predicate's contact among the scene's histories). Returns the grid's points (a search's: [])."""
    if campaign.kind == "grid":
        points = campaign.points()
        preflight(campaign, points)
        return points
    if campaign.kind == "optimize":
        preflight(campaign, optimize_ends(campaign))
        return []
    s = campaign.search
    grid = campaign.grid()
    ends = [campaign.point({**outer, s.key: v}, i, len(grid)) for i, outer in enumerate(grid) for v in (s.low, s.high)]
    preflight(campaign, ends)
    if s.predicate.quantity == "pulses":
        for p in ends:
            if s.predicate.contact not in p.scene.outputs.histories:
                raise CampaignError(
                    f"{campaign.source}: [search] predicate contact = {s.predicate.contact} is not among the "
                    f"scene's [outputs] histories {list(p.scene.outputs.histories)} at point "
                    f"({params_text(p.params)}); add it there (the pulse count needs its force history)"
                )
    return []


def optimize_ends(campaign: Campaign) -> list:
    """The designs checked before an optimize campaign runs: every combination of the variables' ends
    (each range's low and high, every choice) when there are at most 64, else each variable's ends with
    the others at their first; a design a constraint that reads no observable excludes is left out (it
    never runs)."""
    import itertools

    from granchain.campaigns.optimize import _reads_observable, _violated, design_values

    opt = campaign.optimize
    ends = [v.ends() for v in opt.variables]
    if math.prod(len(e) for e in ends) <= 64:
        combos = list(itertools.product(*ends))
    else:
        first = [e[0] for e in ends]
        combos = [tuple(x if j == i else first[j] for j in range(len(ends))) for i, e in enumerate(ends) for x in e]
    design = [c for c in opt.constraints if not _reads_observable(c)]
    points = []
    for i, combo in enumerate(combos):
        p = campaign.point(dict(zip(opt.keys, combo, strict=True)), i, len(combos))
        if _violated(design, design_values(campaign, p)) is None:
            points.append(p)
    return points


def write_record(
    ws: Path, campaign: Campaign, runner: Runner, entries: list[dict], search_rows=None, trial_rows=None, confirm=None
) -> None:
    """Write campaign.json, the workspace's record of this campaign run: its settings, the code, the
    varied keys, the search, the points in order (entries: {"params", "job", "key"}) and a search's
    rows (an optimize campaign's trials, and its winner's re-runs: confirm). Written before the points
    run and kept current, so that the table can be read meanwhile and after a killed driver; kept as
    runner.record too (as campaign.json reads back), the record this run's table is made from: another
    campaign run into the same workspace rewrites the file."""
    record = {
        "schema": wsp.RECORD_SCHEMA,
        "kind": campaign.kind,
        "source": campaign.source,
        "title": campaign.title,
        "base_source": campaign.base_source,
        "backend": campaign.backend,
        "method": runner.record_method[0],
        "method_reason": runner.record_method[1],
        "rtol": campaign.rtol,
        "error_estimate": campaign.error_estimate,
        "regime_contact": campaign.regime_contact,
        "code": runner.code,
        # the libraries the campaign runs on (dask, distributed, signac) besides each run's own
        "provenance": {"packages": package_versions(RUN_PACKAGES + CAMPAIGN_PACKAGES)},
        "varied": list(campaign.varied_keys),
        "search": None
        if campaign.search is None
        else {
            "key": campaign.search.key,
            "range": [campaign.search.low, campaign.search.high],
            "scale": campaign.search.scale,
            "tolerance": campaign.search.tolerance,
            "predicate": campaign.search.predicate.text,
        },
        "optimize": _optimize_record(campaign),
        "points": entries,
        "search_results": search_rows,
        "optimize_results": trial_rows,
        "optimize_confirm": confirm,
    }
    runner.record = json.loads(json.dumps(record, default=wsp.plain))
    wsp.write_json(ws / wsp.RECORD, record)


def _optimize_record(campaign: Campaign) -> dict | None:
    """An [optimize] table as the record keeps it (with the optuna version its designs depend on)."""
    opt = campaign.optimize
    if opt is None:
        return None
    return {
        "objective": opt.objective,
        "direction": opt.direction,
        "trials": opt.trials,
        "seed": opt.seed,
        "batch": opt.batch,
        "startup": opt.startup,
        "variables": [v.text for v in opt.variables],
        "keys": list(opt.keys),
        "constraints": [c.text for c in opt.constraints],
        "confirm": opt.confirm,
        "objective_2": opt.objective2,
        "direction_2": opt.direction2,
        "sampler": f"optuna TPESampler(seed={opt.seed}, n_startup_trials={opt.startup})",
        "optuna": package_versions(("optuna",)).get("optuna"),
    }


def cluster_settings(campaign: Campaign, cluster=None, ranks: int = 1) -> ClusterSettings | None:
    """The campaign file's [cluster] table with `cluster` over it: a kind ("slurm"), a dict of
    settings (granchain.campaigns.cluster_settings.ClusterSettings' fields; None values are not given), or a
    ClusterSettings (used as it is). None: no batch cluster (local workers or --scheduler)."""
    if isinstance(cluster, ClusterSettings):
        settings = cluster
    else:
        flags = {"kind": cluster} if isinstance(cluster, str) else dict(cluster or {})
        try:
            settings = merge(campaign.cluster, flags)
        except ClusterError as e:
            raise CampaignError(str(e)) from None
    if settings is None:
        return None
    try:
        settings = check_cluster(settings, ranks=ranks)
    except ClusterError as e:
        raise CampaignError(str(e)) from None
    if settings.batch and shutil.which(SUBMIT[settings.kind]) is None:  # before the workspace is made
        raise CampaignError(
            f"--cluster {settings.kind}: {SUBMIT[settings.kind]} is not on PATH; run the campaign where jobs can be "
            f"submitted (a login node of the {settings.kind.upper()} cluster)"
        )
    return settings


def run_campaign(
    spec,
    out,
    workers: int | None = None,
    scheduler: str | None = None,
    rerun: bool = False,
    retry_failed: bool = False,
    stream=None,
    cluster=None,
    ranks: int | str | None = None,
):
    """Run a campaign into the workspace `out`; returns (its table as a DataFrame, the RunReport).

    Nothing runs unless every point is valid. Points complete in the workspace are not run again
    (``rerun`` forces them; ``retry_failed`` runs the failed ones again). Ctrl-C stops the workers
    (on a batch cluster: cancels the jobs this run submitted, only those), writes the table of what
    is complete, says so, and raises KeyboardInterrupt (CampaignInterrupted).

    cluster: worker jobs on a batch queue: "slurm" or "pbs", or a dict of settings ({"kind": "slurm",
    "queue": ..., "jobs": 4, ...}; granchain.campaigns.cluster_settings.ClusterSettings), over the file's
    [cluster] table. ranks: MPI ranks per point (or "auto"), over [campaign] ranks.
    """
    campaign = as_campaign(spec)
    if ranks is not None:
        campaign = dataclasses.replace(campaign, ranks=check_ranks(ranks, campaign.backend, "--ranks"))
    stream = sys.stderr if stream is None else stream
    settings = cluster_settings(campaign, cluster, ranks=1 if campaign.ranks == "auto" else campaign.ranks)
    points = validate(campaign)
    ws = Path(out)
    ex = Executor(
        workers=workers,
        scheduler=scheduler,
        cluster=settings,
        ranks=_job_ranks(campaign, settings, points),
        log_directory=ws / JOB_LOGS,
    )
    runner = Runner(campaign, ws, ex, rerun=rerun, retry_failed=retry_failed, stream=stream)
    if settings is not None and settings.batch:
        runner.say(f"campaign: worker jobs: {describe(settings, ex.ranks)}")
    _write_inputs(ws, campaign)
    try:
        _run_points(campaign, runner, ws, points)
        ex.check_failure()  # every batch job ended, none may be replaced: the points not run are missing
    except CampaignError:
        ex.close()
        write_tables(ws, runner.record)
        raise
    except KeyboardInterrupt:
        raise CampaignInterrupted(_stop_interrupted(campaign, runner, ex, ws)) from None
    finally:
        ex.close()
    tables = write_tables(ws, runner.record)
    _say_failures(runner)
    return tables, runner.report


def _write_inputs(ws: Path, campaign: Campaign) -> None:
    """The campaign file's text and its base scene as TOML, beside the points."""
    if campaign.text:
        wsp.write_text(ws / "campaign.toml", campaign.text)  # never through a link planted there
    from granchain.scene import scene_from_dict

    wsp.write_text(ws / "base.toml", scene_from_dict(campaign.base, source=campaign.base_source).to_toml())


def _run_points(campaign: Campaign, runner: Runner, ws: Path, points: list) -> None:
    """Run a grid's points, or a search, keeping the workspace's record of them current."""
    if campaign.kind == "grid":
        jobs = [runner.job(p) for p in points]
        entries = [
            {"params": p.params, "job": j.id, "key": wsp.point_key(j.cached_statepoint)}
            for p, j in zip(points, jobs, strict=True)
        ]
        write_record(ws, campaign, runner, entries)  # the table can be read while the points run
        run_grid(campaign, runner, points)
        return
    write_record(ws, campaign, runner, [])
    last = [time.monotonic()]
    if campaign.kind == "optimize":
        _run_optimize(campaign, runner, ws, last)
        return

    def search_entries(evaluated):
        ordered = sorted(evaluated, key=lambda e: (e[2], e[0].params[campaign.search.key]))
        return [{"params": p.params, "job": job, "key": key} for p, job, _, key in ordered]

    def save(evaluated, rows):  # at most every 2 s: the record of a search in progress
        if time.monotonic() - last[0] >= 2.0:
            write_record(ws, campaign, runner, search_entries(evaluated), rows)
            last[0] = time.monotonic()

    evaluated, search_rows = run_search(campaign, runner, on_progress=save)
    write_record(ws, campaign, runner, search_entries(evaluated), search_rows)


def _run_optimize(campaign: Campaign, runner: Runner, ws: Path, last: list) -> None:
    """Run an optimize campaign, keeping the record current (every batch, at most every 2 s)."""

    def entries(evaluated):  # each point once, in the order first asked
        seen: dict = {}
        for p, job, key in evaluated:
            seen.setdefault(job, {"params": p.params, "job": job, "key": key})
        return list(seen.values())

    def save(evaluated, rows):
        if time.monotonic() - last[0] >= 2.0:
            write_record(ws, campaign, runner, entries(evaluated), trial_rows=rows)
            last[0] = time.monotonic()

    evaluated, rows = run_optimize(campaign, runner, on_progress=save)
    write_record(ws, campaign, runner, entries(evaluated), trial_rows=rows)
    if campaign.optimize.confirm:  # the winner re-run before it is reported (its runs: points of their own)
        confirm = confirm_best(campaign, runner, rows)
        write_record(ws, campaign, runner, entries(evaluated), trial_rows=rows, confirm=confirm)


def _stop_interrupted(campaign: Campaign, runner: Runner, ex: Executor, ws: Path) -> bool:
    """After Ctrl-C: stop the workers (cancel this run's batch jobs), keep what is complete, say so
    (unless quiet; returns whether it was said)."""
    interrupted = time.time()
    ex.close()
    runner.forget_interrupted(interrupted)
    if campaign.kind == "grid":
        write_tables(ws, runner.record)
    if ex.jobs is not None and ex.jobs.jobs:
        runner.say(f"campaign interrupted: cancelled its worker jobs {', '.join(ex.jobs.jobs)} (only those)")
    return runner.say(
        f"campaign interrupted: the points in flight are lost, the complete ones are kept in {ws}; run the "
        "same command again to complete only the missing ones"
    )


def _say_failures(runner: Runner) -> None:
    """The first 20 failed points with their messages, and how many more."""
    r = runner.report
    for params, message in r.messages[:20]:
        runner.say(f"campaign: point ({params_text(params)}) failed: {message}")
    if len(r.messages) > 20:
        runner.say(f"campaign: ... {len(r.messages) - 20} more failures (table.csv, column message)")


def _job_ranks(campaign: Campaign, settings: ClusterSettings | None, points: list) -> int:
    """The cores a worker is given for its points: [campaign] ranks, or for "auto" the batch job's
    cores per job (one worker per job), or locally the most ranks the --np auto rule gives any point
    on this machine's cores (a search's points are not known before: 1)."""
    if campaign.ranks != "auto":
        return campaign.ranks
    if settings is not None and settings.batch:
        if settings.cores_per_job is None:
            raise CampaignError(
                'ranks = "auto" on a batch cluster needs the cores a point may use: give --cores-per-job '
                "(or [cluster] cores_per_job); each point then runs on as many of them as pay for its chain"
            )
        return settings.cores_per_job
    from granchain.campaigns.execute import planned_beads
    from granchain.schedule import auto_ranks
    from granchain.workflows.run import available_cores

    return max((auto_ranks(planned_beads(campaign, p.scene), available_cores()) for p in points), default=1)


def load_campaign(ws, table: str | None = None):
    """A workspace's table as a pandas DataFrame: table="points" (one row per point), "search" (one
    row per outer point of a search, its transition), "trials" (one row per trial of an optimize
    campaign), "best" (its best design, one row: objective, error bar, runner-up, verdict), or None: a
    search's transitions, an optimize campaign's trials, a grid's points."""
    from granchain.campaigns.table import read_record

    kind = read_record(Path(ws)).get("kind")
    if table is None:
        table = {"search": "search", "optimize": "trials"}.get(kind, "points")
    if table == "points":
        return build_table(ws)
    if table == "search":
        return build_search_table(ws)
    if table in ("trials", "best"):
        return build_trials_table(ws) if table == "trials" else build_best_table(ws)
    raise CampaignError(f"table = {table!r}: 'points', 'search', 'trials' or 'best' (an optimize campaign's)")
