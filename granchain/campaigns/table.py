"""The campaign table: one row per point, read from the workspace (its run directories are the truth).

Columns, in order:

* the point's parameters: every [vary], [zip], searched and [derive] key (dotted scene keys as written);
* ``status``: done, failed (the message is in ``message``), missing (not run yet, or lost), stale
  (not computed by this code; a result of another granchain or plugin version exists);
* ``pulses`` and ``regime``: distinct pulses in the force history of the regime contact
  (``regime_contact``, default the last of the scene's [outputs] histories) and 'single solitary wave'
  / 'wave train' / 'no wave' (granchain.postprocess.regimes); blank without histories;
* every observable of summary.json with its estimated error (``<name>_error``, from the run's 2 dt and
  4 dt companions; blank where no estimate could be stood behind: summary.json ``errors`` says why),
  and ``error_estimate``, the largest relative peak-force error over the measured contacts;
* ``beads``, ``timestep``, ``steps`` (as run, after planning), ``bead_steps`` (summary.json price),
  ``wall_time`` (the run plus its error-estimate companions, s), ``warnings``, ``message``, ``job``
  (the signac job id: the directory WS/workspace/<job>).

Written as table.csv (floats round-trip) and table.parquet; a search adds search.csv / search.parquet.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from granchain.campaigns import workspace as wsp
from granchain.campaigns.search import read_history
from granchain.campaigns.spec import OBSERVABLES, CampaignError

TIMING_COLUMNS = ("wall_time",)  # differ between two runs of the same point; everything else is reproducible


def _scalar(v):
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    return json.dumps(v)


def regime_contact(record: dict, sp_scene: dict) -> int | None:
    rc = record.get("regime_contact")
    if rc is not None:
        return rc
    hist = (sp_scene.get("outputs") or {}).get("histories") or []
    return int(hist[-1]) if hist else None


def point_row(ws: Path, record: dict, entry: dict, stale: dict) -> dict:
    """One table row for one point of the record."""
    from granchain.postprocess.regimes import classify_wave, count_pulses

    row = {k: _scalar(v) for k, v in entry["params"].items()}
    job_dir = ws / "workspace" / entry["job"]
    state = wsp.job_state(job_dir)
    sp = wsp.read_json(job_dir / "signac_statepoint.json") or {}
    key = entry.get("key") or (wsp.point_key(sp) if sp else None)
    if state == "missing" and key in stale:
        state = "stale"
    row["status"] = state
    summary = wsp.read_json(job_dir / wsp.RUN_DIR / "summary.json") if state == "done" else None
    contact = regime_contact(record, sp.get("scene", {}))  # the scene's histories, when the job is there
    row["pulses"], row["regime"] = None, None
    if summary is not None and contact is not None:
        force = read_history(job_dir / wsp.RUN_DIR, contact)
        if force is not None:
            row["pulses"], row["regime"] = count_pulses(force), classify_wave(force)
    obs = (summary or {}).get("observables", {})
    errs = ((summary or {}).get("errors") or {}).get("observables", {})
    for name in OBSERVABLES:
        row[name] = obs.get(name)
        if name in ("leading_peak_force", "leading_peak_force_nondim", "wave_speed", "max_peak_force"):
            row[f"{name}_error"] = (errs.get(name) or {}).get("error")
    row["error_estimate"] = (summary or {}).get("error_estimate")
    price = (summary or {}).get("price") or {}
    row["beads"] = (summary or {}).get("beads")
    row["timestep"] = (summary or {}).get("timestep")
    row["steps"] = (summary or {}).get("steps")
    row["bead_steps"] = price.get("bead_steps")
    wall = price.get("wall_time")
    row["wall_time"] = None if wall is None else wall + (price.get("error_estimate") or 0.0)
    task = wsp.read_json(job_dir / wsp.TASK) or {}
    row["warnings"] = (" | ".join(task.get("warnings") or []) or None) if state == "done" else None
    message = None
    if state == "failed":
        message = (wsp.read_json(job_dir / wsp.FAILURE) or {}).get("message")
    elif state == "stale":
        message = "computed by other code: " + wsp.code_text(stale[key])
    row["message"] = message
    row["job"] = entry["job"]
    return row


def build_table(ws: str | Path):
    """The campaign table of a workspace as a pandas DataFrame (one row per point of its record)."""
    import pandas as pd

    ws = Path(ws)
    record = read_record(ws)
    project = wsp.open_workspace(ws)
    stale = wsp.stale_versions(project, record["code"])
    rows = [point_row(ws, record, e, stale) for e in record["points"]]
    df = pd.DataFrame(rows)
    for col in df.columns:  # all-blank columns as float NaN, numbers as numbers (CSV/Parquet types)
        if df[col].isna().all():
            df[col] = df[col].astype(float)
    return df


def build_search_table(ws: str | Path):
    import pandas as pd

    record = read_record(Path(ws))
    if record.get("kind") != "search":
        raise CampaignError(f"{ws}: is a {record.get('kind')} campaign; only a search has transitions")
    rows = record.get("search_results") or []
    df = pd.DataFrame([{k: _scalar(v) for k, v in r.items()} for r in rows])
    for col in df.columns:
        if df[col].isna().all():
            df[col] = df[col].astype(float)
    return df


def read_record(ws: Path) -> dict:
    rec = wsp.read_json(Path(ws) / wsp.RECORD)
    if rec is None:
        raise CampaignError(
            f"{ws}: is not a campaign workspace (no readable {wsp.RECORD}); give the --out directory of "
            "'granchain campaign run'"
        )
    return rec


def write_tables(ws: str | Path) -> dict:
    """Write table.csv and table.parquet (and search.csv / search.parquet); returns the tables."""
    ws = Path(ws)
    tables = {"table": build_table(ws)}
    if read_record(ws).get("kind") == "search":
        tables["search"] = build_search_table(ws)
    for name, df in tables.items():
        _write_atomic(df, ws / f"{name}.csv", "csv")
        _write_atomic(df, ws / f"{name}.parquet", "parquet")
    return tables


def _write_atomic(df, path: Path, fmt: str) -> None:
    import os

    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    if fmt == "csv":
        df.to_csv(tmp, index=False)
    else:
        df.to_parquet(tmp, index=False)
    os.replace(tmp, path)


def format_table(df, columns: list[str] | None = None, max_rows: int = 60) -> str:
    """A short text view for the terminal: the parameters, status, regime and the observables that
    have values (with their errors)."""
    if columns is None:
        columns = [c for c in df.columns if c not in ("job", "warnings", "message")]
        columns = [c for c in columns if not df[c].isna().all()]
    view = df[columns].head(max_rows)

    def fmt(v):
        if v is None or (isinstance(v, float) and math.isnan(v)):
            return "-"
        if isinstance(v, float):
            return f"{v:.6g}"
        return str(v)

    cells = [[str(c) for c in columns]] + [[fmt(v) for v in row] for row in view.itertuples(index=False)]
    widths = [max(len(r[i]) for r in cells) for i in range(len(columns))]
    lines = ["  ".join(x.rjust(w) for x, w in zip(r, widths, strict=True)) for r in cells]
    if len(df) > max_rows:
        lines.append(f"... {len(df) - max_rows} more rows (table.csv has them all)")
    return "\n".join(lines)
