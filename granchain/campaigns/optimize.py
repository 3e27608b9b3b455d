"""The optimize kind: an optimiser (optuna) proposes designs, each runs as an ordinary workspace point.

Why optuna (issue 45): its ask-and-tell interface lets granchain run each proposed design as a
campaign point on the Dask workers (cached, resumable) instead of inside the optimiser's own loop; one
search space mixes floats (linear or log), whole numbers and categorical choices (a material); its
samplers are seeded (TPESampler(seed=...): the same seed and the same results give the same
designs); and its TPE takes two objectives (a Pareto front: pareto_front). nevergrad and cma are continuous
first; deap is a toolkit for writing a genetic algorithm; scipy.optimize has no categorical variables.

The loop: ask `batch` trials of a study whose sampler is TPESampler(seed, n_startup_trials=startup),
make each trial's design a point (its [derive] keys computed, its scene validated), check the
constraints that read no observable (a violating design is not run), run the points not complete in the
workspace side by side, then tell the study every trial of the batch in trial order: COMPLETE with the
objective, FAIL where the run failed or its objective is unmeasured (never a value), PRUNED where a
constraint does not hold (TPE ranks pruned trials below the complete ones: it learns to avoid them).

Resumable without a journal: the study lives in memory, and a rerun asks and tells the same sequence
again. With the same seed the sampler proposes the same designs, whose points are complete in the
workspace: they are told their cached results without running, so the study reaches the state the
killed driver had, and goes on from there. A rerun with a larger ``trials`` continues the shorter
search exactly as an uninterrupted longer one would have. This relies on the sampler's determinism for
one optuna version (the record keeps the version).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from granchain.campaigns import expr
from granchain.campaigns import workspace as wsp
from granchain.campaigns.model import Campaign, CampaignError, params_text
from granchain.campaigns.optimize_spec import design_numbers
from granchain.exceptions import GranchainError
from granchain.postprocess.observables import table_columns

COMPLETE, FAILED, INFEASIBLE = "complete", "failed", "infeasible"
#: the tolerance a campaign without [campaign] rtol plans for (workflows.plan.plan_scene's default)
DEFAULT_RTOL = 1e-3
#: each backend's other, for the winner's check on it
OTHER_BACKEND = {"reference": "lammps", "lammps": "reference"}


def make_study(opt):
    """A fresh in-memory optuna study for the [optimize] table: TPE seeded with opt.seed."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    sampler = optuna.samplers.TPESampler(seed=opt.seed, n_startup_trials=opt.startup)
    if opt.objective2 is not None:  # two objectives: TPE's multi-objective form (a Pareto front)
        return optuna.create_study(directions=[opt.direction, opt.direction2], sampler=sampler)
    return optuna.create_study(direction=opt.direction, sampler=sampler)


def _reads_observable(constraint) -> bool:
    return bool(constraint.names & set(table_columns()))


def objective_of(job_dir, opt, values: dict, second: bool = False) -> tuple[float | None, float | None, str | None]:
    """(objective, its error bar or None, None) of a complete point, or (None, None, why not).

    values: the names the expression may read besides the observables (Campaign._values of the
    point's parameters). An expression's error bar is the first-order propagation of its observables'
    bars, summed in magnitude (they share the run's time step, so they are not independent):
    sum_i |f(o + e_i) - f(o - e_i)| / 2; none where an observable it reads has no bar. second: the
    second objective's."""
    tree, text = (opt.tree2, opt.objective2) if second else (opt.tree, opt.objective)
    run = Path(job_dir) / wsp.RUN_DIR
    summary = wsp.read_json(run / "summary.json") or {}
    obs = summary.get("observables") if isinstance(summary.get("observables"), dict) else {}
    errs = ((summary.get("errors") or {}).get("observables") or {}) if isinstance(summary.get("errors"), dict) else {}
    missing = summary.get("observables_missing") if isinstance(summary.get("observables_missing"), dict) else {}
    names = sorted(expr.names(tree) & set(table_columns()))
    vals = dict(values)
    bars = {}
    for name in names:
        v = obs.get(name)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            return None, None, f"{name} was not measured: {missing.get(name, 'no value in summary.json')}"
        vals[name] = float(v)
        e = (errs.get(name) or {}).get("error") if isinstance(errs.get(name), dict) else None
        bars[name] = float(e) if isinstance(e, (int, float)) and not isinstance(e, bool) and math.isfinite(e) else None
    try:
        f = expr.evaluate(tree, vals, text)
        if any(b is None for b in bars.values()):
            return f, None, None
        bar = 0.0
        for name, e in bars.items():
            hi = expr.evaluate(tree, {**vals, name: vals[name] + e}, text)
            lo = expr.evaluate(tree, {**vals, name: vals[name] - e}, text)
            bar += abs(hi - lo) / 2
    except expr.ExpressionError as e:
        return None, None, f"the objective cannot be computed: {e}"
    return f, bar, None


def design_values(campaign: Campaign, point) -> dict:
    """The names a design's objective and constraints read before its run: the point's parameters
    and the base scene's numbers (Campaign._values) and its own chain's numbers (design_numbers)."""
    return {**campaign._values(point.params), **design_numbers(point.scene)}


def _violated(constraints, values: dict) -> str | None:
    """The first constraint that does not hold (or cannot be computed) for these values, as a message."""
    for c in constraints:
        try:
            if not c.holds(values):
                return f"infeasible: {c.text} does not hold"
        except expr.ExpressionError as e:
            return f"infeasible: {c.text} cannot be computed: {e}"
    return None


class _Trial:
    """One trial of a batch: its optuna trial, design, point, job and outcome."""

    def __init__(self, trial, params: dict):
        self.trial, self.params = trial, params
        self.point = self.job = self.future = None
        self.state, self.value, self.error, self.message = None, None, None, None
        self.value2 = self.error2 = None  # the second objective's (two objectives)


def _design(campaign: Campaign, runner, t: _Trial, evaluated: list) -> None:
    """Make the trial's point, check the constraints that read no observable, open its job."""
    opt = campaign.optimize
    try:
        t.point = campaign.point(t.params, t.trial.number, opt.trials)
    except CampaignError as e:
        t.state, t.message = FAILED, str(e)
        return
    values = design_values(campaign, t.point)
    why = _violated([c for c in opt.constraints if not _reads_observable(c)], values)
    if why is not None:
        t.state, t.message = INFEASIBLE, why
        return
    t.job = runner.job(t.point)
    evaluated.append((t.point, t.job.id, wsp.point_key(t.job.cached_statepoint)))


def _outcome(campaign: Campaign, t: _Trial, status: dict | None) -> None:
    """The trial's state, objective and message once its point is complete (or failed)."""
    opt = campaign.optimize
    state = wsp.job_state(t.job.path)
    if state == wsp.FAILED or (status is not None and status.get("status") != "done"):
        rec = wsp.read_json(Path(t.job.path) / wsp.FAILURE) or {}
        t.state = FAILED
        t.message = f"the run failed: {rec.get('message') or (status or {}).get('message', '?')}"
        return
    if state != wsp.DONE:
        t.state, t.message = FAILED, "the run did not complete"
        return
    values = design_values(campaign, t.point)
    t.value, t.error, why = objective_of(t.job.path, opt, values)
    if t.value is None:
        t.state, t.message = FAILED, f"objective {opt.objective!r} unmeasured: {why}"
        return
    if opt.objective2 is not None:
        t.value2, t.error2, why = objective_of(t.job.path, opt, values, second=True)
        if t.value2 is None:
            t.state, t.message = FAILED, f"objective {opt.objective2!r} unmeasured: {why}"
            return
    observed = dict(values)
    summary = wsp.read_json(Path(t.job.path) / wsp.RUN_DIR / "summary.json") or {}
    observed.update({k: v for k, v in (summary.get("observables") or {}).items() if isinstance(v, (int, float))})
    why = _violated([c for c in opt.constraints if _reads_observable(c)], observed)
    t.state, t.message = (INFEASIBLE, why) if why is not None else (COMPLETE, None)


def _tell(study, t: _Trial) -> None:
    from optuna.trial import TrialState

    if t.state == COMPLETE:
        study.tell(t.trial, t.value if t.value2 is None else [t.value, t.value2])
    else:
        study.tell(t.trial, state=TrialState.FAIL if t.state == FAILED else TrialState.PRUNED)


def _run_batch(campaign: Campaign, runner, batch: list[_Trial], prog, started: list) -> None:
    """Run the batch's points that are not complete (each job once), collect them."""
    from distributed import as_completed

    futures: dict = {}  # job id -> future (a design asked twice in one batch runs once)
    for t in batch:
        if t.job is None or t.job.id in futures:
            continue
        if not runner.needs_run(t.job):
            continue
        if not started[0]:
            runner.prepare()
            started[0] = True
        futures[t.job.id] = runner.submit(t.job, t.point)
        runner.report.ran += 1
    prog.update(pending=len(futures))
    status = {}
    by_future = {f: jid for jid, f in futures.items()}
    for fut in as_completed(list(futures.values())) if futures else ():  # (no client until a first submission)
        jid = by_future[fut]
        params = next(t.point.params for t in batch if t.job is not None and t.job.id == jid)
        status[jid] = runner.collect(fut, params, prog)
    for t in batch:
        if t.job is not None:
            if t.job.id not in futures:
                prog.update(wsp.DONE)
            _outcome(campaign, t, status.get(t.job.id))
        else:
            prog.update(wsp.DONE if t.state == INFEASIBLE else wsp.FAILED)


def run_optimize(campaign: Campaign, runner, on_progress=None) -> tuple[list, list[dict]]:
    """Run an optimize campaign; returns (the evaluated points as (point, job id, point key), one row
    per trial: trial_row). on_progress(evaluated, rows) after each batch (the caller keeps the
    workspace's record current, so a killed driver leaves a readable table)."""
    from granchain.campaigns.campaign_progress import CampaignProgress

    opt = campaign.optimize
    study = make_study(opt)
    prog = CampaignProgress(opt.trials, "optimize", runner.stream, workers=runner.ex.nworkers)
    evaluated: list = []
    rows: list[dict] = []
    started = [False]
    try:
        while len(rows) < opt.trials:
            asked = [study.ask() for _ in range(min(opt.batch, opt.trials - len(rows)))]
            batch = [_Trial(tr, {v.key: v.suggest(tr) for v in opt.variables}) for tr in asked]
            for t in batch:
                _design(campaign, runner, t, evaluated)
            _run_batch(campaign, runner, batch, prog, started)
            for t in batch:  # in trial order: the study's state does not depend on which finished first
                _tell(study, t)
                rows.append(trial_row(t, opt, rows))
            runner.report.points = len({e[1] for e in evaluated})
            if on_progress is not None:
                on_progress(evaluated, rows)
    finally:
        prog.close()
    return evaluated, rows


def trial_row(t: _Trial, opt, before: list[dict]) -> dict:
    """A trial's row of the trials table: trial, the design (variables and derived keys), state,
    objective, objective_error, best_so_far (the best complete objective up to it), job, message."""
    row = {"trial": t.trial.number}
    row.update(t.point.params if t.point is not None else t.params)
    row.update(state=t.state, objective=t.value, objective_error=t.error)
    if opt.objective2 is not None:
        row.update(objective_2=t.value2, objective_2_error=t.error2)
    prev = before[-1]["best_so_far"] if before else None
    best = [x for x in (prev, t.value if t.state == COMPLETE else None) if x is not None]
    row["best_so_far"] = min(best, key=opt.sign) if best else None
    row["job"] = t.job.id if t.job is not None else None
    row["message"] = t.message
    return row


def best_design(rows: list[dict], direction: str, keys: tuple[str, ...]) -> dict | None:
    """The best complete trial's design, objective and error bar, and whether the runner-up (the best
    other design: another job) is distinguished from it: their objectives differ by more than the sum
    of their error bars. None when no trial is complete."""
    sign = (lambda v: v) if direction == "minimize" else (lambda v: -v)
    done = sorted((r for r in rows if r.get("state") == COMPLETE), key=lambda r: (sign(r["objective"]), r["trial"]))
    if not done:
        return None
    done = [{**r, "objective_error": _bar(r.get("objective_error"))} for r in done]  # a table's NaN: no bar
    best = done[0]
    out = {"trial": best["trial"], **{k: best.get(k) for k in keys}}  # (confirm_best re-runs it)
    out.update(objective=best["objective"], objective_error=best.get("objective_error"), job=best["job"])
    other = next((r for r in done[1:] if r["job"] != best["job"]), None)
    out["runner_up_trial"] = None if other is None else other["trial"]
    out["runner_up_objective"] = None if other is None else other["objective"]
    out["runner_up_error"] = None if other is None else other.get("objective_error")
    out["verdict"] = _verdict(best, other, keys)
    out["trials"] = len(rows)
    out["designs_run"] = len({r["job"] for r in rows if isinstance(r.get("job"), str)})
    return out


def _bar(e) -> float | None:
    """An error bar as a number, or None where there is none (None, NaN as a DataFrame reads it back)."""
    return float(e) if isinstance(e, (int, float)) and not isinstance(e, bool) and math.isfinite(e) else None


def _verdict(best: dict, other: dict | None, keys) -> str:
    if other is None:
        return "the only design measured"
    eb, eo = best.get("objective_error"), other.get("objective_error")
    gap = abs(other["objective"] - best["objective"])
    design = params_text({k: other.get(k) for k in keys})
    if eb is None or eo is None:
        return f"no error bar on the best or the runner-up ({design}): their difference {gap:.4g} cannot be judged"
    if gap <= eb + eo:
        return f"not distinguished from the runner-up ({design}): they differ by {gap:.4g}, within their error bars"
    times = f"{gap / (eb + eo):.3g} times their error bars" if eb + eo > 0 else "their error bars both 0"
    return f"distinguished from the runner-up ({design}) by {gap:.4g}, {times}"


def best_text(best: dict | None, objective: str, keys, confirm: dict | None = None) -> str:
    """The best design as `campaign table --best` prints it: its objective from the re-run at rtol / 10
    where that ran (confirm: confirm_best's record), the search's and the other backend's values, whether
    they agree, and the verdict against the runner-up."""
    if best is None:
        return f"no trial has a measured objective {objective!r} yet (campaign table WS shows why)"
    bar = best["objective_error"]
    value = f"{best['objective']:.6g}" + (f" +- {bar:.2g}" if bar is not None else " (no error bar)")
    matched = confirm is not None and confirm.get("job") == best.get("job")
    if matched and confirm["tight"]["objective"] is not None:
        value = f"{_value_text(confirm['tight'])} ({_run_name(confirm['tight'])})"
    return "\n".join(
        [
            f"best design (trial {best['trial']}): {params_text({k: best[k] for k in keys})}",
            f"{objective} = {value}",
            *confirm_text(confirm, best),
            best["verdict"],
            f"{best['trials']} trials, {best['designs_run']} distinct designs run; job {best['job']}",
        ]
    )


def _variant(campaign: Campaign, backend: str, rtol: float) -> Campaign:
    """The campaign on another backend or at another rtol; a method the backend lacks is left to it."""
    from granchain.backends import backend_named

    method = campaign.method if campaign.method in backend_named(backend).methods else None
    return dataclasses.replace(campaign, backend=backend, rtol=rtol, method=method)


def _start_check(campaign: Campaign, runner, design: dict, index: int, entry: dict):
    """Open (and submit where not complete) the winner's point on entry's backend and rtol; returns
    (runner, job, point, future or None), or None with entry["message"] saying why it cannot run."""
    from granchain.campaigns.execute import Runner, preflight

    try:
        variant = _variant(campaign, entry["backend"], entry["rtol"])
        point = variant.point(design, index, campaign.optimize.trials)
        preflight(variant, [point])
        sub = Runner(variant, runner.ws, runner.ex, runner.rerun, runner.retry_failed, runner.stream)
        job = sub.job(point)
        entry["job"] = job.id
        future = None
        if sub.needs_run(job):
            sub.prepare()
            future = sub.submit(job, point)
            runner.report.ran += 1
        return sub, job, point, future
    except (GranchainError, ImportError, OSError) as e:  # no LAMMPS here, or the scene is not its
        entry["message"] = f"the {entry['backend']} backend cannot run the winner: {' '.join(str(e).split())}"
        return None


def confirm_best(campaign: Campaign, runner, rows: list[dict]) -> dict | None:
    """The best design run again before it is reported (issue 45): at rtol / 10 on the search's backend
    ("tight") and at the search's rtol on the other backend ("other"), each a workspace point of its
    own (cached: a rerun finds them complete). Returns {"trial", "job", "design", "search", "tight",
    "other", "agreement"}, each run as {backend, rtol, job, objective, objective_error, message}; None
    when no trial is complete."""
    from granchain.campaigns.campaign_progress import CampaignProgress

    opt = campaign.optimize
    best = best_design(rows, opt.direction, opt.keys)
    if best is None:
        return None
    design = {k: best[k] for k in opt.keys}
    rtol = campaign.rtol if campaign.rtol is not None else DEFAULT_RTOL
    out = {"trial": best["trial"], "job": best["job"], "design": design}
    out["search"] = _entry(campaign.backend, rtol, best["job"], best["objective"], best["objective_error"])
    out["tight"] = _entry(campaign.backend, rtol / 10)
    out["other"] = _entry(OTHER_BACKEND[campaign.backend], rtol)
    started = {name: _start_check(campaign, runner, design, best["trial"], out[name]) for name in ("tight", "other")}
    started = {name: s for name, s in started.items() if s is not None}
    prog = CampaignProgress(len(started), "confirm", runner.stream, workers=runner.ex.nworkers)
    try:
        for name, (sub, job, point, future) in started.items():
            status = sub.collect(future, point.params, prog) if future is not None else None
            if future is None:
                prog.update(wsp.DONE)
            t = _Trial(None, design)
            t.point, t.job = point, job
            _outcome(sub.c, t, status)
            out[name].update(objective=t.value, objective_error=t.error, message=t.message)
            runner.report.done += sub.report.done
            runner.report.failed += sub.report.failed
            runner.report.messages += sub.report.messages
    finally:
        prog.close()
    out["agreement"] = [_agrees(out["search"], out["tight"]), _agrees(out["other"], out["tight"])]
    return out


def _entry(backend: str, rtol: float, job=None, objective=None, error=None) -> dict:
    return {
        "backend": backend,
        "rtol": rtol,
        "job": job,
        "objective": objective,
        "objective_error": error,
        "message": None,
    }


def _run_name(e: dict) -> str:
    return f"the {e['backend']} run at rtol {e['rtol']:.3g}"


def _agrees(a: dict, b: dict) -> str:
    """Whether two runs of one design agree within their error bars (|a - b| <= e_a + e_b), as a sentence."""
    if a["objective"] is None or b["objective"] is None:
        missing = a if a["objective"] is None else b
        return f"{_run_name(a)} against {_run_name(b)}: not compared ({_run_name(missing)} has no value)"
    gap = abs(a["objective"] - b["objective"])
    ea, eb = a["objective_error"], b["objective_error"]
    if ea is None or eb is None:
        return f"{_run_name(a)} and {_run_name(b)} differ by {gap:.4g}: no error bar to judge it by"
    verdict = "agree" if gap <= ea + eb else "disagree"
    times = f", {gap / (ea + eb):.3g} times" if ea + eb > 0 else ""
    return f"{_run_name(a)} and {_run_name(b)} {verdict}: they differ by {gap:.4g}{times} their error bars"


def _value_text(e: dict) -> str:
    if e["objective"] is None:
        return f"no value: {e['message'] or 'not run'}"
    bar = e["objective_error"]
    return f"{e['objective']:.6g}" + (f" +- {bar:.2g}" if bar is not None else " (no error bar)")


def confirm_text(confirm: dict | None, best: dict | None) -> list[str]:
    """The winner's re-runs as `campaign table --best` prints them (none where they are of another design)."""
    if confirm is None or best is None or confirm.get("job") != best.get("job"):
        return ["the winner has not been re-run at a tighter rtol yet (the search is incomplete, or confirm = false)"]
    lines = [
        f"{name}: {_value_text(confirm[key])} ({_run_name(confirm[key])})"
        for key, name in (
            ("tight", "re-run at rtol / 10"),
            ("search", "the search's run"),
            ("other", "the other backend"),
        )
    ]
    return lines + list(confirm.get("agreement") or [])


def pareto_front(rows: list[dict], directions: tuple[str, str]) -> list[dict]:
    """The complete trials no other complete trial dominates (at least as good in both objectives,
    better in one), each design (job) once, by the first objective; the rows as trial_row makes them
    (objective, objective_2)."""
    sign = [(1.0 if d == "minimize" else -1.0) for d in directions]
    done: dict = {}
    for r in rows:
        if r.get("state") == COMPLETE and r.get("job") not in done:
            done[r["job"]] = r
    pts = [(sign[0] * r["objective"], sign[1] * r["objective_2"], r) for r in done.values()]
    front = [r for a, b, r in pts if not any(x <= a and y <= b and (x < a or y < b) for x, y, _ in pts)]
    return sorted(front, key=lambda r: (sign[0] * r["objective"], r["trial"]))


def near_front(rows: list[dict], directions: tuple[str, str]) -> tuple[list[dict], list[dict]]:
    """The designs off the Pareto front (pareto_front) that its values alone rule out but its error
    bars do not: (not distinguished, cannot be judged), each by trial.

    A design r off the front is ruled out only where some front design q is better in both objectives
    by more than the two bars' sum (q_k + e_q,k + e_r,k <= r_k, signed so that less is better): within
    the bars, r's true values may lie on the front (the same rule best_design applies to one
    objective). A design without a bar, or whose every dominating front design lacks one, cannot be
    judged."""
    sign = [(1.0 if d == "minimize" else -1.0) for d in directions]
    front = pareto_front(rows, directions)
    on = {r["job"] for r in front}
    cols = (("objective", "objective_error"), ("objective_2", "objective_2_error"))
    undistinguished, unjudged = [], []
    seen = set(on)
    for r in sorted((r for r in rows if r.get("state") == COMPLETE), key=lambda r: r["trial"]):
        if r.get("job") in seen:
            continue
        seen.add(r["job"])
        bars_r = [_bar(r.get(e)) for _, e in cols]
        verdicts = []
        for q in front:
            bars_q = [_bar(q.get(e)) for _, e in cols]
            if None in bars_r or None in bars_q:
                verdicts.append(None)
                continue
            verdicts.append(
                all(
                    sign[k] * (r[c] - q[c]) >= bars_q[k] + bars_r[k]  # q better than r beyond both bars
                    for k, (c, _) in enumerate(cols)
                )
            )
        if True in verdicts:
            continue
        (unjudged if None in verdicts else undistinguished).append(r)
    return undistinguished, unjudged


def front_text(front: list[dict], objectives: tuple[str, str], keys, near: tuple = ((), ())) -> str:
    """The Pareto front as `campaign table --best` prints it: one design per line with both objectives."""
    if not front:
        return f"no trial has both objectives {list(objectives)} measured yet (campaign table WS shows why)"

    def value(v, e):
        return f"{v:.6g}" + (f" +- {e:.2g}" if e is not None and e == e else "")

    lines = [f"Pareto front of {objectives[0]} and {objectives[1]}: {len(front)} designs"]
    for r in front:
        lines.append(
            f"trial {r['trial']}: {params_text({k: r.get(k) for k in keys})}: {objectives[0]} = "
            f"{value(r['objective'], r.get('objective_error'))}, {objectives[1]} = "
            f"{value(r['objective_2'], r.get('objective_2_error'))}"
        )
    for rs, why in zip(
        near,
        (
            "not distinguished from the front within their error bars",
            "cannot be judged against the front (no error bar)",
        ),
        strict=True,
    ):
        if rs:
            lines.append(f"{why}: trial {', '.join(str(r['trial']) for r in rs)}")
    return "\n".join(lines)
