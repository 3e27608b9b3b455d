r"""The campaign table: one row per point, read from the workspace (its run directories are the truth).

Columns, in order:

* the point's parameters: every [vary], [zip], searched and [derive] key (dotted scene keys as written);
  a key "auto" at some points and a number at others as the number (NaN for "auto") and ``<key>_auto``,
  one of other mixed values (``peak_force = [true, [5, 10]]``) as JSON text (storable);
* ``status``: done, failed (the message is in ``message``), missing (not run yet, or lost), stale
  (not computed by this code; a result of another granchain or plugin version exists);
* ``pulses`` and ``regime``: distinct pulses in the dynamic force (F - F0 on a precompressed chain)
  history of the regime contact (``regime_contact``, default the last of the scene's [outputs]
  histories) and 'single solitary wave' / 'wave train' / 'no wave', or on a precompressed chain whose
  pulse stays small against F0 'weakly nonlinear wave' (granchain.postprocess.response_regimes);
  blank without histories;
* every observable of summary.json with its estimated error (``<name>_error``, from the run's companions,
  an estimate or a bound as ``granchain run`` gives it; blank where no estimate could be stood behind:
  summary.json ``errors`` says why),
  then ``unmeasured``, the observables a done point could not measure, each with summary.json's reason
  (observables_missing: "leading_peak_force: contact 14 was not reached by the wave ..."), blank when it
  measured every one, and ``error_estimate``, the largest relative peak-force error over the measured contacts;
* each sensor bead's quantities (``sensor_peak_force_bead_<i>``, ``sensor_time_of_peak_bead_<i>``:
  granchain.postprocess.sensors) with their errors (``<name>_error``), where the scene has sensors;
* ``beads``, ``timestep``, ``steps`` (as run, after planning), ``bead_steps`` (summary.json price),
  ``wall_time`` (the run plus its error-estimate companions, s), ``warnings``, ``message``, ``job``
  (the signac job id: the directory WS/workspace/<job>).

``attrs["units"]`` gives every column's unit (column_units), ``attrs["provenance"]`` the campaign's
record of the libraries it ran on (campaign.json's provenance: dask, distributed and signac too).

Written as table.csv (floats round-trip) and table.parquet; a search adds search.csv / search.parquet.
The terminal view (format_table) prints control characters of any value escaped (``\x1b``): a
string parameter of a campaign file someone else wrote cannot move the cursor or retitle the terminal.
A workspace's record (campaign.json) is checked before it is used: a job id that is not signac's
(32 hex digits) never becomes a path.
"""

from __future__ import annotations

import json
import math
import re
import unicodedata
from pathlib import Path

from granchain import safe_files
from granchain.campaigns import model
from granchain.campaigns import workspace as wsp
from granchain.campaigns.search import read_history, static_force
from granchain.campaigns.spec import CampaignError
from granchain.postprocess.observables import SENSOR_OBSERVABLES, table_columns, units, with_error_bars
from granchain.scene import KEY_UNITS

TIMING_COLUMNS = ("wall_time",)  # differ between two runs of the same point; everything else is reproducible


#: the whole numbers a table column stores as integers (Parquet's int64); a larger one is a float
INT64 = range(-(2**63), 2**63)


def _number(v):
    """A number of summary.json as it is; anything else (a damaged file's) as blank, a whole number
    too large for int64 as a float (or blank past the floats)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    if isinstance(v, int) and v not in INT64:
        return float(v) if abs(v) < 2**1023 else None
    return v


def _scalar(v):
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    return json.dumps(v)


def regime_contact(record: dict, sp_scene: dict) -> int | None:
    """The contact whose force history gives a row's pulses and regime: the record's
    regime_contact, else the last of the point's scene's [outputs] histories, else None."""
    rc = record.get("regime_contact")
    if rc is not None:
        return rc
    hist = _dict(_dict(sp_scene).get("outputs")).get("histories") or []
    return int(hist[-1]) if hist else None


#: the most read from a run directory's histories.csv for the regime columns (bytes)
HISTORY_LIMIT = 512 * 1024 * 1024


def _history(run: Path, contact: int):
    """The regime contact's force history, or None when histories.csv is absent, a link, too large or
    damaged (the row then has no pulses or regime)."""
    path = run / "histories.csv"
    try:
        if safe_files.file_size(path) > HISTORY_LIMIT:
            return None
        force = read_history(run, contact)
    except (OSError, ValueError, IndexError, TypeError):
        return None
    if force is None or getattr(force, "ndim", 0) != 1 or not len(force):
        return None
    return force


def point_row(ws: Path, record: dict, entry: dict, stale: dict) -> dict:
    """One table row for one point of the record."""
    from granchain.postprocess.response_regimes import classify_wave, count_pulses

    row = {k: _scalar(v) for k, v in entry["params"].items()}
    job_dir = ws / "workspace" / entry["job"]
    sp = wsp.read_statepoint(job_dir) or {}  # (a damaged one: the point is missing)
    state = wsp.job_state(job_dir, sp) if sp else "missing"
    key = entry.get("key") or (wsp.point_key(sp) if sp else None)
    if state == model.MISSING and key in stale:
        state = model.STALE
    row["status"] = state
    summary = wsp.read_json(job_dir / wsp.RUN_DIR / "summary.json") if state == "done" else None
    try:  # the scene's histories, when the job is there
        contact = regime_contact(record, sp.get("scene"))
    except (TypeError, ValueError, IndexError):
        contact = None
    row["pulses"], row["regime"] = None, None
    if summary is not None and isinstance(contact, int) and not isinstance(contact, bool):
        force = _history(job_dir / wsp.RUN_DIR, contact)
        if force is not None:  # counted on the dynamic force F - F0 (F0: summary.json's static_force)
            f0 = static_force(summary)
            row["pulses"], row["regime"] = count_pulses(force, static_force=f0), classify_wave(force, static_force=f0)
    summary = _dict(summary)
    obs = _dict(summary.get("observables"))
    errs = _dict(_dict(summary.get("errors")).get("observables"))
    barred = with_error_bars()  # each registered observable's column, and its error bar's beside it
    for name in table_columns():
        row[name] = _number(obs.get(name))
        if name in barred:
            row[f"{name}_error"] = _number(_dict(errs.get(name)).get("error"))
    missing = wsp.measurable_missing(summary)
    row["unmeasured"] = "; ".join(f"{k}: {v}" for k, v in missing.items()) or None
    row.update(_sensor_columns(summary))
    row["error_estimate"] = _number(summary.get("error_estimate"))
    price = _dict(summary.get("price"))
    row["beads"] = _number(summary.get("beads"))
    row["timestep"] = _number(summary.get("timestep"))
    row["steps"] = _number(summary.get("steps"))
    row["bead_steps"] = _number(price.get("bead_steps"))
    wall = _number(price.get("wall_time"))
    row["wall_time"] = None if wall is None else wall + (_number(price.get("error_estimate")) or 0.0)
    task = _dict(wsp.read_json(job_dir / wsp.TASK))
    warned = task.get("warnings") or []
    warned = [str(w) for w in warned] if isinstance(warned, list) else [str(warned)]
    row["warnings"] = (" | ".join(warned) or None) if state == "done" else None
    message = None
    if state == "failed":
        message = _dict(wsp.read_json(job_dir / wsp.FAILURE)).get("message")
        message = None if message is None else str(message)
    elif state == "stale":
        message = "computed by other code: " + wsp.code_text(stale[key])
    row["message"] = message
    row["job"] = entry["job"]
    return row


def _sensor_columns(summary: dict) -> dict:
    """A row's sensor bead columns (postprocess.sensors): each sensor's quantities, named by sensor_key,
    with their error bars beside them (summary.json's ``sensors`` and errors.end_peaks); a damaged
    file's values blank."""
    sensors = _dict(summary.get("sensors"))
    errs = _dict(_dict(summary.get("errors")).get("end_peaks"))
    beads = sensors.get("beads") if isinstance(sensors.get("beads"), list) else []
    out: dict = {}
    for k, bead in enumerate(beads):
        if isinstance(bead, bool) or not isinstance(bead, int):
            continue
        for quantity, obs in SENSOR_OBSERVABLES.items():
            values = sensors.get(quantity) if isinstance(sensors.get(quantity), list) else []
            key = obs.key(bead)
            out[key] = _number(values[k]) if k < len(values) else None
            out[f"{key}_error"] = _number(_dict(errs.get(key)).get("error"))
    return out


def _dict(x) -> dict:
    return x if isinstance(x, dict) else {}


def build_table(ws: str | Path, record: dict | None = None):
    """The campaign table of a workspace as a pandas DataFrame (one row per point of its record).

    record: the points of one campaign run (what its campaign.json was when it wrote it); None, the
    workspace's campaign.json now. Another campaign run into the same workspace meanwhile rewrites
    that file: a run's own table is made from its own record."""
    import pandas as pd

    ws = Path(ws)
    record = read_record(ws) if record is None else record
    project = wsp.open_workspace(ws)
    stale = wsp.stale_versions(project, record["code"])
    rows = [point_row(ws, record, e, stale) for e in record["points"]]
    keys = {k for e in record["points"] for k in e["params"]}
    df = storable(pd.DataFrame(rows), keys)
    df.attrs["units"] = column_units(df.columns)
    df.attrs["provenance"] = _dict(record.get("provenance"))
    return df


#: units of the table's own columns ("1": dimensionless; "text" and "bool": not numbers)
TABLE_UNITS = {
    "status": "text",
    "pulses": "1",
    "regime": "text",
    "unmeasured": "text",
    "error_estimate": "1",
    "beads": "1",
    "timestep": "s",
    "steps": "1",
    "bead_steps": "1",
    "wall_time": "s",
    "warnings": "text",
    "message": "text",
    "job": "text",
}


def column_units(columns) -> dict[str, str]:
    """The unit of every column of a campaign table (its attrs["units"]): a parameter's the scene
    key's (granchain.scene.KEY_UNITS; "" where the key's unit is its law's, a [contact] key), an
    observable's and its error's the registry's (observables.units()), ``<key>_auto`` "bool"."""
    obs = units()
    out = {}
    for col in columns:
        base = col.removesuffix("_error")
        if col in TABLE_UNITS:
            out[col] = TABLE_UNITS[col]
        elif base in obs:
            out[col] = obs[base]
        elif col.endswith("_auto"):
            out[col] = "bool"
        else:
            out[col] = KEY_UNITS.get(col, "")
    return out


def build_search_table(ws: str | Path, record: dict | None = None):
    """The search table of a workspace as a pandas DataFrame: one row per outer point (its bracket,
    transition, runs and status: Bisection.row), as the record (build_table) keeps it; a CampaignError
    for a grid."""
    import pandas as pd

    record = read_record(Path(ws)) if record is None else record
    if record.get("kind") != "search":
        raise CampaignError(f"{ws}: is a {record.get('kind')} campaign; only a search has transitions")
    rows = [r for r in record.get("search_results") or [] if isinstance(r, dict)]
    return storable(pd.DataFrame([{str(k): _scalar(v) for k, v in r.items()} for r in rows]), set())


def _trial_rows(ws, record: dict | None) -> tuple[dict, list[dict]]:
    record = read_record(Path(ws)) if record is None else record
    if record.get("kind") != "optimize":
        raise CampaignError(f"{ws}: is a {record.get('kind')} campaign; only an optimize campaign has trials")
    return record, [r for r in record.get("optimize_results") or [] if isinstance(r, dict)]


def build_trials_table(ws: str | Path, record: dict | None = None):
    """The trials table of an optimize campaign as a pandas DataFrame: one row per trial (its design,
    state, objective, objective_error, best_so_far, job, message: optimize.trial_row), as the record
    keeps it; a CampaignError for another kind."""
    import pandas as pd

    record, rows = _trial_rows(ws, record)
    df = storable(pd.DataFrame([{str(k): _scalar(v) for k, v in r.items()} for r in rows]), set())
    objective = _dict(record.get("optimize")).get("objective")
    df.attrs["units"] = {**column_units(df.columns), **_objective_units(objective)}
    return df


def _objective_units(objective) -> dict:
    """The objective's unit where it is one observable's, for its columns."""
    unit = units().get(objective) if isinstance(objective, str) else None
    return {} if unit is None else {c: unit for c in ("objective", "objective_error", "best_so_far")}


def build_best_table(ws: str | Path, record: dict | None = None):
    """An optimize campaign's best design as a one-row DataFrame (optimize.best_design: the design,
    objective, objective_error, the runner-up's and the verdict; the winner's re-runs, tight_* at rtol /
    10 and other_* on the other backend, and their agreement); empty when no trial is complete. With two
    objectives: the Pareto front (optimize.pareto_front), one row per design on it."""
    import pandas as pd

    from granchain.campaigns.optimize import best_design, pareto_front

    record, rows = _trial_rows(ws, record)
    opt = _dict(record.get("optimize"))
    keys = tuple(k for k in opt.get("keys") or [] if isinstance(k, str))
    if opt.get("objective_2"):  # two objectives: the Pareto front, one row per design on it
        return pd.DataFrame(pareto_front(rows, (opt.get("direction", "minimize"), opt.get("direction_2"))))
    best = best_design(rows, opt.get("direction", "minimize"), keys)
    if best is None:
        return pd.DataFrame([])
    confirm = _dict(record.get("optimize_confirm"))
    if confirm.get("job") == best["job"]:  # the winner's re-runs: tight (rtol / 10) and other (backend)
        for name in ("tight", "other"):
            run = _dict(confirm.get(name))
            for k in ("backend", "rtol", "objective", "objective_error", "job", "message"):
                best[f"{name}_{k}"] = run.get(k)
        best["agreement"] = "; ".join(str(a) for a in confirm.get("agreement") or [])
    return pd.DataFrame([best])


def _kind(v) -> str | None:
    """What a table cell holds, for its column's type: None (blank), bool, number, auto or text."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return None
    if isinstance(v, bool):
        return "bool"
    if isinstance(v, float) or (isinstance(v, int) and v in INT64):
        return "number"
    return "auto" if v == "auto" else "text"


def _text(v):
    """A cell of a column of mixed values as text: a string as it is (a character UTF-8 cannot
    write, a lone surrogate of a damaged file's JSON, escaped), anything else as JSON writes it
    (true, 0.0005, [5, 10]); blank stays blank."""
    if _kind(v) is None:
        return None
    text = v if isinstance(v, str) else json.dumps(v)
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


def storable(df, keys: set):
    """df with every column of one type, as CSV and Parquet store it: an all-blank column as float
    NaN; a parameter (keys) that is "auto" at some points and a number at others as the number
    (NaN where "auto") and beside it ``<key>_auto`` (True where the point left it "auto"); any other
    column of mixed values (``peak_force = [true, [5, 10]]``, a damaged file's) as text, each value
    as JSON writes it."""
    for col in list(df.columns):
        kinds = {_kind(v) for v in df[col]} - {None}
        if not kinds:
            df[col] = df[col].astype(float)
        elif kinds == {"number", "auto"} and col in keys and f"{col}_auto" not in df.columns:
            auto = df[col].map(lambda v: v == "auto")
            df[col] = df[col].map(lambda v: math.nan if _kind(v) in (None, "auto") else float(v)).astype(float)
            df.insert(df.columns.get_loc(col) + 1, f"{col}_auto", auto)
        elif len(kinds) > 1 or kinds == {"text"} or kinds == {"auto"}:
            df[col] = df[col].map(_text).astype(object)
    return df


_JOB_ID = re.compile(r"[0-9a-f]{32}")


def read_record(ws: Path) -> dict:
    """The workspace's campaign.json, checked: its points each a job id of signac's (32 hex digits)
    and a table of parameters; a CampaignError naming what is wrong otherwise."""
    wsp.check_links(ws)
    path = Path(ws) / wsp.RECORD
    rec = wsp.read_json(path)
    if rec is None:
        raise CampaignError(
            f"{ws}: is not a campaign workspace (no readable {wsp.RECORD}); give the --out directory of "
            "'granchain campaign run'"
        )
    damaged = f"{path}: is damaged ({{}}); run 'granchain campaign run FILE --out {ws}' again to write it"
    if not isinstance(rec, dict):
        raise CampaignError(damaged.format("not a JSON object"))
    points = rec.get("points")
    if not isinstance(points, list):
        raise CampaignError(damaged.format("no list of points"))
    for k, e in enumerate(points):
        if not isinstance(e, dict) or not isinstance(e.get("params"), dict):
            raise CampaignError(damaged.format(f"point {k + 1} is not a job and its parameters"))
        if not isinstance(e.get("job"), str) or not _JOB_ID.fullmatch(e["job"]):
            raise CampaignError(
                damaged.format(f"point {k + 1}'s job {str(e.get('job'))[:40]!r} is not a signac job id")
            )
        if e.get("key") is not None and not isinstance(e["key"], str):
            raise CampaignError(damaged.format(f"point {k + 1}'s key is not a string"))
    if not isinstance(rec.get("code"), dict):
        raise CampaignError(damaged.format("no code record"))
    for key in ("varied", "search_results", "optimize_results"):
        if rec.get(key) is not None and not isinstance(rec[key], list):
            raise CampaignError(damaged.format(f"{key} is not a list"))
    if rec.get("title") is not None and not isinstance(rec["title"], str):
        raise CampaignError(damaged.format("its title is not a string"))
    return rec


def campaign_tables(ws: str | Path, record: dict | None = None) -> dict:
    """The tables of a workspace, written nowhere: {"table": ...} and for a search {"search": ...}.
    record: one campaign run's own (build_table); None, the workspace's campaign.json."""
    ws = Path(ws)
    record = read_record(ws) if record is None else record
    tables = {"table": build_table(ws, record)}
    if record.get("kind") == "search":
        tables["search"] = build_search_table(ws, record)
    if record.get("kind") == "optimize":
        tables["trials"] = build_trials_table(ws, record)
    return tables


def save_tables(ws: str | Path, tables: dict) -> None:
    """Write the tables (campaign_tables) as table.csv and table.parquet (search.csv / search.parquet,
    trials.csv / trials.parquet)."""
    for name, df in tables.items():
        _write_atomic(df, Path(ws) / f"{name}.csv", "csv")
        _write_atomic(df, Path(ws) / f"{name}.parquet", "parquet")


def write_tables(ws: str | Path, record: dict | None = None) -> dict:
    """Write table.csv and table.parquet (and search.csv / search.parquet) of one campaign run's
    record (build_table; None: the workspace's campaign.json); returns the tables."""
    tables = campaign_tables(ws, record)
    save_tables(ws, tables)
    return tables


def _write_atomic(df, path: Path, fmt: str) -> None:
    """Write aside and rename, refusing a link at path; a failure (read-only, disk full) leaves no
    temporary file and is a WorkspaceWriteError naming the file."""
    try:
        with safe_files.open_for_write(path, "w" if fmt == "csv" else "wb") as fh:
            if fmt == "csv":
                df.to_csv(fh, index=False)
            else:
                df.to_parquet(fh, index=False)
    except OSError as e:
        raise wsp.WorkspaceWriteError(
            e.errno,
            f"{path}: cannot be written ({e.strerror or e}); make the workspace writable, or free some space "
            "('granchain campaign table WS --csv' prints the table without writing it)",
        ) from None


def printable(text: str) -> str:
    r"""text with control and format characters escaped (ESC as \x1b, a newline as \n, U+202E as
    \u202e): safe to print on a terminal, one line."""
    out = []
    for ch in text:
        if ch == "\\":
            out.append(ch)
        elif unicodedata.category(ch) in ("Cc", "Cf", "Zl", "Zp"):
            out.append(ch.encode("unicode_escape").decode("ascii"))
        else:
            out.append(ch)
    return "".join(out)


def format_table(df, columns: list[str] | None = None, max_rows: int = 60) -> str:
    """A short text view for the terminal: the parameters, status, regime and the observables that
    have values (with their errors)."""
    autos = [c for c in df.columns if c.endswith("_auto") and c[: -len("_auto")] in df.columns]
    if columns is None:  # (a key's <key>_auto shows as "auto" in the key's own column)
        columns = [c for c in df.columns if c not in ("job", "warnings", "message", *autos)]
        columns = [c for c in columns if not df[c].isna().all() or f"{c}_auto" in autos]
    view = df[columns].head(max_rows).astype(object)
    for c in autos:
        if c[: -len("_auto")] in columns:
            view[c[: -len("_auto")]] = view[c[: -len("_auto")]].where(~df[c].head(max_rows).astype(bool), "auto")

    def fmt(v):
        if v is None or (isinstance(v, float) and math.isnan(v)):
            return "-"
        if isinstance(v, float):
            return f"{v:.6g}"
        return printable(str(v))

    cells = [[printable(str(c)) for c in columns]] + [[fmt(v) for v in row] for row in view.itertuples(index=False)]
    widths = [max(len(r[i]) for r in cells) for i in range(len(columns))]
    lines = ["  ".join(x.rjust(w) for x, w in zip(r, widths, strict=True)) for r in cells]
    if len(df) > max_rows:
        lines.append(f"... {len(df) - max_rows} more rows (table.csv has them all)")
    return "\n".join(lines)
